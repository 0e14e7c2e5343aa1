"""The command line as users run it: a separate process, its stdout, stderr and exit code.

Runs ``python -m hammerbound`` with PYTHONPATH set to this checkout, so the subprocess runs
the code under test. Checks that
- stdout carries only the program's output (no third-party banner: HiGHS prints one from
  C on the first ``Highs()`` of every process, workers included) and parses as JSON with
  ``--json``;
- every output path is checked before the work, a bad one gives exit code 2 and a one-line
  message, and no existing user file changes unless ``--force`` is given.
"""

from __future__ import annotations

import importlib.metadata
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import tomllib

from hammerbound.app.report import REPORT_FILES

ROOT = Path(__file__).resolve().parents[2]


def run_cli(*args, cwd=None, timeout=600):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return subprocess.run([sys.executable, "-m", "hammerbound", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, env=env, timeout=timeout)


def _simulate(N, deta, seed):
    """Backlash-Hammerstein data from our own few lines of numpy (the chapter's system)."""
    rng = np.random.default_rng(seed)
    ml, cl, mr, cr = 0.25, 0.0628, 0.26, 0.0489
    a1, a2, b1, b2 = -0.76, 0.82, 2.15, -1.09
    g = (b1 + b2) / (1 + a1 + a2)
    b1, b2 = b1 / g, b2 / g  # unit gain (22.8)
    amps = np.linspace(0.25, 2.5, 25)
    u_ss = np.r_[amps, -amps]
    x_ss = np.where(u_ss > 0, mr * (u_ss - cr), ml * (u_ss + cl))  # steady state: x after a
    y_ss = x_ss + rng.uniform(-deta, deta, u_ss.size)              # monotone approach
    u = np.where(rng.random(N) < 0.5, -1.0, 1.0)
    x = np.empty(N)
    prev = 0.0
    for t in range(N):  # backlash (22.1), the play operator between the two lines
        up, down = mr * (u[t] - cr), ml * (u[t] + cl)
        if prev < up:
            prev = up
        elif prev > down:
            prev = down
        x[t] = prev
    w = np.zeros(N)
    for t in range(N):
        w[t] = (-a1 * (w[t - 1] if t >= 1 else 0) - a2 * (w[t - 2] if t >= 2 else 0)
                + b1 * (x[t - 1] if t >= 1 else 0) + b2 * (x[t - 2] if t >= 2 else 0))
    y = w + rng.uniform(-deta, deta, N)
    return (u_ss, y_ss), (u, y), np.array([ml, cl, mr, cr, a1, a2, b1, b2])


def _write_csv(path, u, y):
    path.write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(u, y,
                                                                                    strict=True)))


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli-data")
    (u_ss, y_ss), (u, y), true = _simulate(60, 0.02, 3)
    _write_csv(d / "steady.csv", u_ss, y_ss)
    _write_csv(d / "prbs.csv", u, y)
    return d / "steady.csv", d / "prbs.csv", true


def _identify_args(data, *extra):
    ss, pr, _ = data
    return ("identify", "--steady", ss, "--prbs", pr, "--steady-output-bound", "0.02",
            "--output-bound", "0.02", "--method", "lp", *extra)


def _state(path: Path):
    """Bytes and modification time of a file, or of every file below a directory."""
    if path.is_dir():
        return {p.name: _state(p) for p in sorted(path.iterdir())}
    st = path.stat()
    return (path.read_bytes(), st.st_mtime_ns)


def _previous_report(rep: Path) -> Path:
    """A directory holding an earlier report and a file of the user's, with old mtimes."""
    rep.mkdir()
    for name in REPORT_FILES:
        (rep / name).write_bytes(b"an earlier report: " + name.encode())
    (rep / "mine.txt").write_text("not the program's\n")
    for f in rep.iterdir():  # any rewrite shows in the modification times
        os.utime(f, ns=(1_000_000_000, 1_000_000_000))
    return rep


def _assert_refused(res, command, *fragments):
    assert res.returncode == 2, (res.returncode, res.stderr)
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr  # one line, no traceback
    assert lines[0].startswith(f"hammerbound {command}: error: "), lines[0]
    for f in fragments:
        assert f in lines[0], lines[0]
    assert res.stdout == ""  # refused before any work: no table was printed


# ------------------------------------------------------------------ clean stdout
def test_version_is_the_distribution_version():
    res = run_cli("--version")
    assert res.returncode == 0 and res.stderr == ""
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert importlib.metadata.version("hammerbound") == pyproject
    assert res.stdout.strip() == f"hammerbound {pyproject}"
    import hammerbound

    assert hammerbound.__version__ == pyproject


def test_identify_json_stdout_is_only_json(data, tmp_path):
    """Two worker processes: each would print HiGHS's banner on its first Highs()."""
    rep = tmp_path / "new" / "rep"
    rep.parent.mkdir()
    res = run_cli(*_identify_args(data, "--json", "--n-jobs", 2, "--report", rep))
    assert res.returncode == 0, res.stderr
    assert "HiGHS" not in res.stdout + res.stderr
    out = json.loads(res.stdout)  # the whole of stdout: nothing before or after the JSON
    lo, hi, true = np.array(out["lower"]), np.array(out["upper"]), data[2]
    assert out["parameters"] == ["ml", "cl", "mr", "cr", "a1", "a2", "b1", "b2"]
    assert np.all((lo <= true) & (true <= hi)), (lo, hi)
    assert sorted(p.name for p in rep.iterdir()) == sorted(REPORT_FILES)


@pytest.mark.deep
def test_identify_json_exact_two_jobs_stdout_is_only_json(data):
    """The exact method builds its own highspy.Highs() objects in worker processes."""
    res = run_cli(*_identify_args(data, "--json", "--n-jobs", 2)[:-2], "--method", "exact",
                  "--json", "--n-jobs", 2)
    assert res.returncode == 0, res.stderr
    assert "HiGHS" not in res.stdout
    out = json.loads(res.stdout)
    assert np.all((np.array(out["lower"]) <= data[2]) & (data[2] <= np.array(out["upper"])))


def test_demo_json_stdout_is_only_json_and_progress_on_stderr(tmp_path):
    res = run_cli("demo", "--N", 30, 40, "--output-bounds", 0.02, 0.05, "--method", "lp",
                  "--n-jobs", 2, "--seeds", 0, 1, "--json", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert "HiGHS" not in res.stdout
    recs = json.loads(res.stdout)  # one record per table row, nothing else on stdout
    assert sorted({r["N"] for r in recs if r["N"]}) == [30, 40]
    assert sorted({r["delta_eta"] for r in recs}) == [0.02, 0.05]
    assert {r["table"] for r in recs} == {"22.1", "N=30", "N=40"}
    assert len(recs) == 2 * (6 + 4 + 4)
    for r in recs:
        assert r["seeds"] == [0, 1] and len(r["widths"]) == 2
        assert all(r["inside"]) and r["lower"] <= r["true"] <= r["upper"]
    # the default report directory was created (it did not exist)
    assert Path(tmp_path, "demo-report", "report.md").is_file()
    # progress: one line per fit (2 levels x 2 seeds x 2 N) as it finishes, on stderr; the
    # fits run side by side, so in the order they finish, each exactly once
    err = res.stderr.splitlines()
    ends = [s for s in err if s.startswith("hammerbound demo: [")]
    assert [s.split("]")[0] for s in ends] == [f"hammerbound demo: [{k}/8" for k in range(1, 9)]
    fits = sorted(s.split("] ")[1].split(" lp ")[0] for s in ends)
    assert fits == sorted(f"delta_eta={d} N={n} seed={k}" for d in ("0.02", "0.05")
                          for n in (30, 40) for k in (0, 1))


def test_demo_text_tables_on_stdout_quiet(tmp_path):
    res = run_cli("demo", "--N", 30, "--output-bounds", 0.05, "--method", "lp", "--report", "",
                  "--quiet", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert "Table 22.1" in res.stdout and "Table (N=30)" in res.stdout
    assert "[1/1]" not in res.stdout and res.stderr == ""
    assert list(tmp_path.iterdir()) == []  # --report '' writes nothing


# ------------------------------------------------------------------ output paths
def test_identify_report_onto_existing_file_is_refused(data, tmp_path):
    target = tmp_path / "notes.txt"
    target.write_text("my notes\n")
    before = _state(target)
    res = run_cli(*_identify_args(data, "--report", target))
    _assert_refused(res, "identify", str(target), "not a directory")
    assert _state(target) == before


@pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs Linux /proc")
def test_identify_report_in_unwritable_place(data):
    res = run_cli(*_identify_args(data, "--report", "/proc/x"))
    _assert_refused(res, "identify", "/proc", "cannot create files")


def test_identify_report_over_previous_report(data, tmp_path):
    rep = _previous_report(tmp_path / "rep")
    before = _state(rep)
    res = run_cli(*_identify_args(data, "--report", rep))
    _assert_refused(res, "identify", "already holds a report", "--force")
    assert _state(rep) == before
    res = run_cli(*_identify_args(data, "--report", rep, "--force"))
    assert res.returncode == 0, res.stderr
    after = _state(rep)
    assert after["mine.txt"] == before["mine.txt"]  # files that are not the report: untouched
    assert set(after) == set(before)
    for name in REPORT_FILES:
        assert after[name][1] != before[name][1], name  # rewritten
    assert "Stage 2" in (rep / "report.md").read_text()


def test_benchmark_output_checked_before_the_run(tmp_path):
    res = run_cli("benchmark", "--N", 30, "--output", "/no/dir/out.json")
    _assert_refused(res, "benchmark", "/no/dir", "does not exist")
    target = tmp_path / "out.json"
    target.write_text('{"previous": "results"}')
    before = _state(target)
    res = run_cli("benchmark", "--N", 30, "--output", target)
    _assert_refused(res, "benchmark", "already exists", "--force")
    assert _state(target) == before


@pytest.mark.deep
def test_benchmark_output_force_overwrites(tmp_path):
    target = tmp_path / "out.json"
    target.write_text('{"previous": "results"}')
    res = run_cli("benchmark", "--N", 30, "--output-bound", 0.02, "--output", target, "--force")
    assert res.returncode == 0, res.stderr
    rows = json.loads(target.read_text())
    assert [r["method"] for r in rows] == ["lp", "moment", "exact", "exact"]
    assert "lp (independent)" in res.stdout
    assert "[4/4] exact (two-level): done in" in res.stderr  # progress on stderr only
    assert "[1/4]" not in res.stdout


def test_demo_never_overwrites_a_previous_report(tmp_path):
    args = ("demo", "--N", 30, "--output-bounds", 0.05, "--method", "lp", "--quiet")
    rep = _previous_report(tmp_path / "demo-report")  # the default ./demo-report
    before = _state(rep)
    res = run_cli(*args, cwd=tmp_path)
    _assert_refused(res, "demo", "demo-report", "already holds a report", "--force")
    assert _state(rep) == before
    res = run_cli(*args, "--force", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    after = _state(rep)
    assert set(after) == set(before) and after["mine.txt"] == before["mine.txt"]
    assert all(after[k][1] != before[k][1] for k in REPORT_FILES)
    assert "Chapter example" in (rep / "report.md").read_text()


def test_diagnose_plot_checked_and_force(data, tmp_path):
    _, pr, _ = data
    target = tmp_path / "fig.png"
    target.write_bytes(b"my figure")
    before = _state(target)
    args = ("diagnose", pr, "--num", "0 1", "--den", "1 -0.5", "--output-bound", "0.5",
            "--candidates", "offset", "--plot", target)
    res = run_cli(*args)
    _assert_refused(res, "diagnose", "already exists", "--force")
    assert _state(target) == before
    res = run_cli(*args, "--force")
    assert res.returncode in (0, 1), res.stderr  # 1: model inconsistent with these data
    assert target.read_bytes()[:4] == b"\x89PNG"


def _has_subcommand(name):
    from hammerbound.app.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return name in sub.choices


@pytest.mark.skipif(not _has_subcommand("eiv"), reason="no 'eiv' subcommand in this checkout")
def test_eiv_json_stdout_is_only_json(tmp_path):
    """First-order EIV record (our own simulation), two worker processes."""
    rng = np.random.default_rng(5)
    N, a1, b0, b1 = 30, -0.9, 0.75, -0.28
    u0 = rng.uniform(-1, 1, N)
    y0 = np.zeros(N)
    for t in range(N):
        y0[t] = (-a1 * (y0[t - 1] if t else 0.0) + b0 * u0[t] + b1 * (u0[t - 1] if t else 0.0))
    u = u0 + rng.uniform(-0.05, 0.05, N)
    y = y0 + rng.uniform(-0.05, 0.05, N)
    _write_csv(tmp_path / "eiv.csv", u, y)
    res = run_cli("eiv", tmp_path / "eiv.csv", "--na", 1, "--nb", 1, "--nk", 0,
                  "--input-bound", 0.05, "--output-bound", 0.05, "--method", "lp",
                  "--n-jobs", 2, "--json")
    assert res.returncode == 0, res.stderr
    assert "HiGHS" not in res.stdout
    out = json.loads(res.stdout)
    assert len(out["lower"]) == len(out["upper"]) == 3
