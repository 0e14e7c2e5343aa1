"""The hammerbound command line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hammerbound.app.cli import main
from hammerbound.systems.experiments import chapter_example


def _write(path, u, y, header="u,y"):
    with open(path, "w") as fh:
        fh.write(header + "\n")
        for a, b in zip(u, y, strict=True):
            fh.write(f"{float(a)!r},{float(b)!r}\n")


@pytest.fixture
def csv_files(tmp_path):
    ex = chapter_example(0.02, N=80)
    ss, pr = tmp_path / "steady.csv", tmp_path / "prbs.csv"
    _write(ss, ex.steady.u, ex.steady.y)
    _write(pr, ex.prbs.u, ex.prbs.y)
    return ex, ss, pr


def test_demo_prints_tables_beside_chapter(capsys):
    rc = main(["demo", "--output-bounds", "0.005", "0.05", "--method", "lp", "--report", ""])
    out = capsys.readouterr().out
    assert rc == 0
    assert "Table 22.1" in out and "Table 22.2" in out and "Table 22.3" in out
    # our row and the chapter's row for m_l at delta_eta = 0.005
    line = next(s for s in out.splitlines() if s.strip().startswith("ml") and "[0.2500" in s)
    assert "*" in line
    assert "true parameters inside every interval: yes" in out


def test_identify_json_and_report(csv_files, tmp_path, capsys):
    ex, ss, pr = csv_files
    rc = main(["identify", "--steady", str(ss), "--prbs", str(pr), "--steady-output-bound", "0.02",
               "--output-bound", "0.02", "--method", "lp", "--json",
               "--report", str(tmp_path / "rep")])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    lo, hi = np.array(out["lower"]), np.array(out["upper"])
    true = np.r_[ex.gamma_true, ex.theta_true]
    assert out["parameters"] == ["ml", "cl", "mr", "cr", "a1", "a2", "b1", "b2"]
    assert np.all((lo <= true) & (true <= hi))
    rep = (tmp_path / "rep" / "report.md").read_text()
    assert "Stage 1" in rep and "Stage 2" in rep
    # what the intervals rest on, and the central model with its sampling time (trial 13)
    assert "## Assumptions" in rep and "- PRBS output errors" in rep.split("## Assumptions")[1]
    assert "Central model (the centre of the intervals): G(z) = (" in rep
    for fig in ("backlash_sets.png", "intervals.png", "envelope.png"):
        assert (tmp_path / "rep" / fig).stat().st_size > 1000


def test_identify_missing_column(csv_files, tmp_path, capsys):
    _, ss, _ = csv_files
    bad = tmp_path / "bad.csv"
    _write(bad, [1.0, -1.0], [0.1, -0.1], header="input,output")
    rc = main(["identify", "--steady", str(ss), "--prbs", str(bad), "--steady-output-bound", "0.02",
               "--output-bound", "0.02"])
    err = capsys.readouterr().err
    assert rc == 2 and "missing column" in err and "input" in err


def test_identify_bad_row(csv_files, tmp_path, capsys):
    _, ss, _ = csv_files
    bad = tmp_path / "bad.csv"
    bad.write_text("u,y\n1.0,0.2\n-1.0,abc\n")
    rc = main(["identify", "--steady", str(ss), "--prbs", str(bad), "--steady-output-bound", "0.02",
               "--output-bound", "0.02"])
    err = capsys.readouterr().err
    assert rc == 2 and "line 3" in err and "not a number" in err


def test_identify_missing_file(tmp_path, capsys):
    rc = main(["identify", "--steady", str(tmp_path / "nope.csv"), "--prbs", "x.csv",
               "--steady-output-bound", "0.02", "--output-bound", "0.02"])
    assert rc == 2 and "no such file" in capsys.readouterr().err


def test_help_everywhere(capsys):
    for cmd in (["--help"], ["demo", "--help"], ["identify", "--help"], ["benchmark", "--help"],
                ["eiv", "--help"], ["diagnose", "--help"]):
        with pytest.raises(SystemExit) as e:
            main(cmd)
        assert e.value.code == 0
        assert "usage" in capsys.readouterr().out.lower()
    from hammerbound.app.cli import diagnose_cli_main

    assert diagnose_cli_main(["--help"]) == 0
    assert "--force" in capsys.readouterr().out


def test_benchmark_quick(tmp_path, capsys):
    out = tmp_path / "b.json"
    rc = main(["benchmark", "--N", "40", "--output-bound", "0.005", "--output", str(out)])
    assert rc == 0
    rows = json.loads(out.read_text())
    assert [r["method"] for r in rows] == ["lp", "moment", "exact", "exact"]
    assert all(r["true_inside"] for r in rows)


def test_benchmark_suite_points_at_the_repository(monkeypatch, tmp_path, capsys):
    """The suite is not installed: the command says how to run it, and imports nothing
    from the working directory (no sys.path change)."""
    import sys

    before = list(sys.path)
    monkeypatch.chdir(tmp_path)
    assert main(["benchmark", "suite", "list"]) == 2
    err = capsys.readouterr().err
    assert "python -m benchmarks list" in err and "repository root" in err
    assert sys.path == before and "benchmarks.__main__" not in sys.modules


# ------------------------------------------------------------------ output paths (in-process)
def test_check_output_file_cases(tmp_path):
    import os

    from hammerbound.app.paths import check_output_file, write_output_text
    from hammerbound.exceptions import OutputExistsError, OutputPathError

    new = tmp_path / "new.json"
    assert check_output_file(new) == new and not new.exists()  # the check writes nothing
    assert [p.name for p in tmp_path.iterdir()] == []           # (its probe file is removed)
    with pytest.raises(OutputPathError, match="does not exist; create it first"):
        check_output_file(tmp_path / "no" / "x.json", option="--output")
    with pytest.raises(OutputPathError, match="is a directory"):
        check_output_file(tmp_path, force=True)
    with pytest.raises(OutputPathError, match="empty output path"):
        check_output_file("  ")
    old = tmp_path / "old.json"
    old.write_text("keep")
    with pytest.raises(OutputExistsError, match="--output: .*old.json already exists; pass --force"):
        check_output_file(old, option="--output")
    assert check_output_file(old, force=True) == old and old.read_text() == "keep"
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(OutputPathError, match="not a regular file"):
        check_output_file(fifo, force=True)
    link = tmp_path / "dangling"
    link.symlink_to(tmp_path / "missing")
    with pytest.raises(OutputPathError, match="symbolic link to a missing file"):
        check_output_file(link, force=True)
    a_file = tmp_path / "plain"
    a_file.write_text("")
    with pytest.raises(OutputPathError, match="is not a directory"):
        check_output_file(a_file / "x.json")
    # a file that appears between the check and the write is not clobbered without force
    late = check_output_file(tmp_path / "late.json")
    late.write_text("someone else's")
    with pytest.raises(OutputExistsError, match="left unchanged"):
        write_output_text(late, "ours")
    assert late.read_text() == "someone else's"
    write_output_text(late, "ours", force=True)
    assert late.read_text() == "ours"


def test_check_output_dir_cases(tmp_path):
    from hammerbound.app.paths import check_output_dir
    from hammerbound.exceptions import OutputExistsError, OutputPathError

    files = ("report.md", "fig.png")
    assert check_output_dir(tmp_path / "rep", files) == tmp_path / "rep"
    assert not (tmp_path / "rep").exists()
    with pytest.raises(OutputPathError, match="does not exist"):
        check_output_dir(tmp_path / "a" / "b", files)
    (tmp_path / "f").write_text("")
    with pytest.raises(OutputPathError, match="not a directory"):
        check_output_dir(tmp_path / "f", files, force=True)
    d = tmp_path / "d"
    d.mkdir()
    (d / "other.txt").write_text("")
    assert check_output_dir(d, files) == d  # unrelated files do not block a report
    (d / "fig.png").write_text("")
    with pytest.raises(OutputExistsError, match="already holds a report \\(fig.png\\); pass --force"):
        check_output_dir(d, files, option="--report")
    assert check_output_dir(d, files, force=True) == d
    (d / "report.md").mkdir()
    with pytest.raises(OutputPathError, match="is a directory"):
        check_output_dir(d, files, force=True)


@pytest.mark.parametrize("argv, fragment", [
    (["benchmark", "--output", "{tmp}"], "is a directory"),
    (["benchmark", "--output", "/dev/null"], "not a regular file"),
    (["identify", "--steady", "s.csv", "--prbs", "p.csv", "--steady-output-bound", "0.02",
      "--output-bound", "0.02", "--report", "{tmp}/no/rep"], "does not exist"),
    (["diagnose", "d.csv", "--num", "0 1", "--den", "1 -0.5", "--output-bound", "0.1",
      "--plot", "{tmp}/no/fig.png"], "does not exist"),
    (["demo", "--report", "{tmp}/no/rep"], "does not exist"),
])
def test_bad_output_paths_fail_first(argv, fragment, tmp_path, capsys):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(argv) == 2
    cap = capsys.readouterr()
    assert cap.out == ""  # nothing ran (the inputs s.csv, p.csv, d.csv do not even exist)
    assert cap.err.count("\n") == 1 and fragment in cap.err and "error: Output" in cap.err


def test_report_overwrite_is_explicit(csv_files, tmp_path):
    from hammerbound import BacklashSetEstimator, HammersteinBacklashIdentifier, LinearEIVSetEstimator
    from hammerbound.app.report import REPORT_FILES, write_report
    from hammerbound.exceptions import OutputExistsError

    ex, _, _ = csv_files
    ident = HammersteinBacklashIdentifier(
        BacklashSetEstimator(0.02), LinearEIVSetEstimator(output_bound=0.02, method="lp"))
    ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    rep = tmp_path / "rep"
    args = (ident, ex.steady.u, ex.steady.y, ex.prbs.u, ex.prbs.y, rep)
    assert write_report(*args) == rep / "report.md"
    assert sorted(p.name for p in rep.iterdir()) == sorted(REPORT_FILES)
    (rep / "report.md").write_text("edited by hand")
    with pytest.raises(OutputExistsError, match="already holds a report .*overwrite=True"):
        write_report(*args)
    assert (rep / "report.md").read_text() == "edited by hand"
    write_report(*args, overwrite=True)
    assert "Stage 2" in (rep / "report.md").read_text()
