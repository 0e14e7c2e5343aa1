"""``hammerbound eiv``: the general EIV problem from one CSV record (issue 14)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import lfilter

from hammerbound.app.cli import main

ROOT = Path(__file__).resolve().parents[2]
LRIC_EXACT = np.array([[-0.9217, -0.8830], [0.7195, 0.7935], [-0.3227, -0.2428]])
LRIC_ARGS = ["--na", "1", "--nb", "1", "--nk", "0", "--input-bound", "0.05",
             "--output-bound", "0.05", "--dt", "0.1"]
EIV_TRUTH = np.array([-0.8, 0.7, 0.2])   # a1, b0, b1 of _eiv_csv


def _eiv_csv(tmp_path, N=40, seed=5):
    """Own simulation: y = (0.7 + 0.2 q^-1) / (1 - 0.8 q^-1) x, dt = 0.1 (column t in
    seconds), input and output errors exactly at +-0.05 (random signs)."""
    rng = np.random.default_rng(seed)
    x0 = rng.uniform(-2, 2, N)
    w = lfilter([0.7, 0.2], [1.0, -0.8], x0)
    u = x0 + 0.05 * np.where(rng.random(N) < 0.5, 1.0, -1.0)
    y = w + 0.05 * np.where(rng.random(N) < 0.5, 1.0, -1.0)
    path = tmp_path / "eiv.csv"
    path.write_text("t,u,y\n" + "".join(f"{0.1 * k:.1f},{float(u[k])!r},{float(y[k])!r}\n" for k in range(N)))
    return path


def _record(tmp_path, t=None, names=("u", "y"), N=40, seed=1):
    """Own simulation: y = 0.5 x(t-1) / (1 - 0.6 q^-1) with output errors at +-0.01."""
    rng = np.random.default_rng(seed)
    u = np.where(rng.random(N) < 0.5, 1.0, -1.0)
    y = lfilter([0, 0.5], [1, -0.6], u) + 0.01 * np.where(rng.random(N) < 0.5, 1.0, -1.0)
    path = tmp_path / "rec.csv"
    cols = ([] if t is None else ["t"]) + list(names)
    rows = [[*([] if t is None else [t[k]]), u[k], y[k]] for k in range(N)]
    path.write_text(",".join(cols) + "\n" + "\n".join(",".join(repr(float(v)) for v in r)
                                                      for r in rows) + "\n")
    return path


def test_eiv_json_lric_exact(capsys, shared_data):
    """The third-party LRIC record (../shared/data/lric/), exact method."""
    lric = shared_data("lric", "eiv_first_order_2017.csv")
    rc = main(["eiv", str(lric), *LRIC_ARGS, "--method", "exact", "--json"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["parameters"] == ["a1", "b0", "b1"]
    bounds = np.column_stack([out["lower"], out["upper"]])
    np.testing.assert_allclose(bounds, LRIC_EXACT, atol=2e-4)
    assert [r["parameter"] for r in out["intervals"]] == ["a1", "b0", "b1"]
    assert out["data"]["dt"] == 0.1 and out["data"]["N"] == 30
    assert out["transfer_function"]["dt"] == 0.1
    np.testing.assert_allclose(out["transfer_function"]["den"][1], bounds[0].mean())


def test_eiv_json_subprocess_stdout_is_only_json(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(
        [sys.executable, "-m", "hammerbound", "eiv", str(_eiv_csv(tmp_path)),
         *LRIC_ARGS, "--method", "lp", "--json"],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)  # nothing but the JSON document on stdout
    assert out["parameters"] == ["a1", "b0", "b1"]
    lo, hi = np.array(out["lower"]), np.array(out["upper"])
    assert np.all((lo <= EIV_TRUTH) & (EIV_TRUTH <= hi))


def test_eiv_text_output_names_and_model(tmp_path, capsys):
    rc = main(["eiv", str(_eiv_csv(tmp_path)), *LRIC_ARGS, "--method", "lp"])
    assert rc == 0
    out = capsys.readouterr().out
    assert "dt = 0.1" in out and "no gain constraint" in out
    for name in ("a1", "b0", "b1"):
        assert any(line.startswith(name + " ") for line in out.splitlines())
    import re

    pole = re.search(r"G\(z\) = \(.*\) / \(z - (0\.\d+)\)", out)
    assert pole and abs(float(pole.group(1)) - 0.8) < 0.05   # the true pole is 0.8


def test_eiv_time_column_gives_dt_and_columns_by_name(tmp_path, capsys):
    path = _record(tmp_path, t=0.25 * np.arange(40) + 3.0, names=("volt", "speed"))
    rc = main(["eiv", str(path), "--na", "1", "--nb", "1", "--output-bound", "0.01",
               "--u-col", "volt", "--y-col", "speed", "--method", "lp", "--json"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["data"]["dt"] == 0.25
    assert out["data"]["input"] == "volt" and out["data"]["output"] == "speed"
    lo, hi = np.array(out["lower"]), np.array(out["upper"])
    assert np.all((lo <= [-0.6, 0.5]) & ([-0.6, 0.5] <= hi))


def test_eiv_sample_counter_time_column_with_dt(tmp_path, capsys):
    path = _record(tmp_path, t=np.arange(40))
    rc = main(["eiv", str(path), "--na", "1", "--nb", "1", "--output-bound", "0.01",
               "--dt", "0.1", "--method", "lp", "--json"])
    assert rc == 0
    assert json.loads(capsys.readouterr().out)["data"]["dt"] == 0.1


@pytest.mark.parametrize("t, extra, match", [
    (np.r_[0.0, 0.1, 0.2, 0.35, 0.4 + 0.1 * np.arange(36)], [], "not uniformly sampled"),
    (0.5 * np.arange(40), ["--dt", "0.1"], "step 0.5 but dt=0.1"),
])
def test_eiv_bad_time_column(tmp_path, capsys, t, extra, match):
    path = _record(tmp_path, t=t)
    rc = main(["eiv", str(path), "--na", "1", "--nb", "1", "--output-bound", "0.01",
               "--method", "lp", "--json", *extra])
    cap = capsys.readouterr()
    assert rc == 2 and cap.out == ""
    assert match in cap.err


def test_eiv_missing_column_and_gain_error(tmp_path, capsys):
    path = _record(tmp_path)
    rc = main(["eiv", str(path), "--na", "1", "--nb", "1", "--output-bound", "0.01",
               "--u-col", "volt", "--json"])
    cap = capsys.readouterr()
    assert rc == 2 and cap.out == "" and "volt" in cap.err
    # a wrong gain constraint: the error names it
    rc = main(["eiv", str(path), "--na", "1", "--nb", "1", "--output-bound", "0.01",
               "--steady-state-gain", "3", "--method", "lp", "--json"])
    cap = capsys.readouterr()
    assert rc == 2 and cap.out == ""
    assert "EmptyFeasibleSetError" in cap.err and "B(1)/A(1) = 3" in cap.err


def test_eiv_total_time_limit_zero_reports_lp_bounds_with_status_limit(tmp_path, capsys):
    """A spent total budget: every end keeps its certified LP bound, status 'limit'."""
    args = ["eiv", str(_eiv_csv(tmp_path)), *LRIC_ARGS, "--json"]
    assert main([*args, "--method", "lp"]) == 0
    lp = json.loads(capsys.readouterr().out)
    rc = main([*args, "--method", "exact", "--total-time-limit", "0"])
    assert rc == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    # the warning: one stderr line in command-line terms (no source path, no keywords)
    lines = [ln for ln in cap.err.splitlines() if "stopped early" in ln]
    assert len(lines) == 1 and lines[0].startswith("hammerbound eiv: warning: SearchLimitWarning")
    assert "--total-time-limit" in lines[0] and "time_limit" not in lines[0]
    assert ".py" not in cap.err and "warnings.warn" not in cap.err
    lo, hi = np.array(out["lower"]), np.array(out["upper"])
    assert np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))
    # never wider than the LP bound, and still around the true system
    assert np.all(lo >= np.array(lp["lower"]) - 1e-12) and np.all(hi <= np.array(lp["upper"]) + 1e-12)
    assert np.all((lo <= EIV_TRUTH) & (EIV_TRUTH <= hi))
    assert all("limit" in r["status"] for r in out["intervals"])


def test_eiv_moment_names_its_order_in_text_and_json(tmp_path, capsys):
    """A moment fit says which relaxation ran (order, basis, solver): order 1 and order 2
    results otherwise look alike (found by a new-user trial)."""
    path = str(_eiv_csv(tmp_path, N=12))
    rc = main(["eiv", path, *LRIC_ARGS, "--method", "moment", "--order", "2"])
    out = capsys.readouterr().out
    assert rc == 0 and "method moment (order 2, sparse basis, clarabel), na=1" in out
    rc = main(["eiv", path, *LRIC_ARGS, "--method", "moment", "--order", "1", "--json"])
    model = json.loads(capsys.readouterr().out)["model"]
    assert rc == 0 and model["method"] == "moment"
    assert model["method_label"] == "moment (order 1, clarabel)"
    rc = main(["eiv", path, *LRIC_ARGS, "--method", "lp", "--json"])
    assert json.loads(capsys.readouterr().out)["model"]["method_label"] == "lp"
