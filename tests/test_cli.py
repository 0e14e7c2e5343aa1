"""The hammerbound command line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hammerbound.cli import main
from hammerbound.experiments import chapter_example


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
    rc = main(["demo", "--noise-levels", "0.005", "0.05", "--method", "lp", "--report", ""])
    out = capsys.readouterr().out
    assert rc == 0
    assert "Table 22.1" in out and "Table 22.2" in out and "Table 22.3" in out
    # our row and the chapter's row for m_l at delta_eta = 0.005
    line = next(s for s in out.splitlines() if s.strip().startswith("ml") and "[0.2500" in s)
    assert "*" in line
    assert "true parameters inside every interval: yes" in out


def test_identify_json_and_report(csv_files, tmp_path, capsys):
    ex, ss, pr = csv_files
    rc = main(["identify", "--steady", str(ss), "--prbs", str(pr), "--steady-noise", "0.02",
               "--prbs-noise", "0.02", "--method", "lp", "--json",
               "--report", str(tmp_path / "rep")])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    lo, hi = np.array(out["lower"]), np.array(out["upper"])
    true = np.r_[ex.gamma_true, ex.theta_true]
    assert out["parameters"] == ["ml", "cl", "mr", "cr", "a1", "a2", "b1", "b2"]
    assert np.all((lo <= true) & (true <= hi))
    rep = (tmp_path / "rep" / "report.md").read_text()
    assert "Stage 1" in rep and "Stage 2" in rep
    for fig in ("backlash_sets.png", "intervals.png", "envelope.png"):
        assert (tmp_path / "rep" / fig).stat().st_size > 1000


def test_identify_missing_column(csv_files, tmp_path, capsys):
    _, ss, _ = csv_files
    bad = tmp_path / "bad.csv"
    _write(bad, [1.0, -1.0], [0.1, -0.1], header="input,output")
    rc = main(["identify", "--steady", str(ss), "--prbs", str(bad), "--steady-noise", "0.02",
               "--prbs-noise", "0.02"])
    err = capsys.readouterr().err
    assert rc == 2 and "missing column" in err and "input" in err


def test_identify_bad_row(csv_files, tmp_path, capsys):
    _, ss, _ = csv_files
    bad = tmp_path / "bad.csv"
    bad.write_text("u,y\n1.0,0.2\n-1.0,abc\n")
    rc = main(["identify", "--steady", str(ss), "--prbs", str(bad), "--steady-noise", "0.02",
               "--prbs-noise", "0.02"])
    err = capsys.readouterr().err
    assert rc == 2 and "line 3" in err and "not a number" in err


def test_identify_missing_file(tmp_path, capsys):
    rc = main(["identify", "--steady", str(tmp_path / "nope.csv"), "--prbs", "x.csv",
               "--steady-noise", "0.02", "--prbs-noise", "0.02"])
    assert rc == 2 and "no such file" in capsys.readouterr().err


def test_help_everywhere(capsys):
    for cmd in (["--help"], ["demo", "--help"], ["identify", "--help"], ["benchmark", "--help"]):
        with pytest.raises(SystemExit) as e:
            main(cmd)
        assert e.value.code == 0
    assert main(["diagnose", "--help"]) == 0
    assert "usage" in capsys.readouterr().out.lower()


def test_benchmark_quick(tmp_path, capsys):
    out = tmp_path / "b.json"
    rc = main(["benchmark", "--N", "40", "--noise-bound", "0.005", "--output", str(out)])
    assert rc == 0
    rows = json.loads(out.read_text())
    assert [r["method"] for r in rows] == ["lp", "moment", "exact", "exact"]
    assert all(r["true_inside"] for r in rows)


def test_benchmark_suite_forwarding(monkeypatch, tmp_path, capsys):
    import sys
    from pathlib import Path

    with monkeypatch.context() as m:  # suite not importable (e.g. installed without the repo)
        m.chdir(tmp_path)
        m.setitem(sys.modules, "benchmarks.__main__", None)
        assert main(["benchmark", "suite", "list"]) == 2
        assert "repository root" in capsys.readouterr().err
    monkeypatch.chdir(Path(__file__).resolve().parents[1])
    assert main(["benchmark", "suite", "list"]) == 0
    assert "python -m benchmarks stage1" in capsys.readouterr().out
