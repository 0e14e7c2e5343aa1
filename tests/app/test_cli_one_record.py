"""``hammerbound identify --record``: one ordinary record from the command line (issue 26).

The record is simulated here (our own play operator and scipy's ``lfilter``); the linear
block has unit steady-state gain, so the truth is directly comparable with the intervals of
the unit-gain normalisation (22.8).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from oracles import play as own_play
from scipy.signal import lfilter

from hammerbound.app.cli import main

GAMMA = (0.25, 0.06, 0.26, 0.05)
A, B = [1.0, -0.5], [0.0, 0.5]  # unit gain: theta = (a1, b1) = (-0.5, 0.5)


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    rng = np.random.default_rng(11)
    u = []
    while len(u) < 60:
        u += [rng.uniform(-2, 2)] * int(rng.integers(3, 9))
    u = np.array(u[:60])
    y = lfilter(B, A, own_play(u, *GAMMA)) + 0.02 * rng.choice([-1.0, 1.0], u.size)
    path = tmp_path_factory.mktemp("one_record") / "plant.csv"
    path.write_text("t,u,y\n" + "".join(f"{0.1 * i!r},{float(a)!r},{float(b)!r}\n"
                                        for i, (a, b) in enumerate(zip(u, y, strict=True))))
    return path


def _run(capsys, *argv):
    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


ARGS = ("--output-bound", 0.02, "--na", 1, "--nb", 1, "--nk", 1, "--method", "lp")


def test_json_intervals_hold_the_truth(capsys, record):
    rc, out, _ = _run(capsys, "identify", "--record", record, *ARGS, "--json")
    assert rc == 0
    res = json.loads(out)
    assert res["procedure"] == "one-record"
    assert res["parameters"] == ["ml", "cl", "mr", "cr", "a1", "b1"]
    truth = [*GAMMA, -0.5, 0.5]
    for name, lo, hi, v in zip(res["parameters"], res["lower"], res["upper"], truth,
                               strict=True):
        assert (lo is None or lo <= v) and (hi is None or v <= hi), name
    assert res["data"]["N"] == 60 and res["data"]["dt"] == pytest.approx(0.1)
    assert any("backlash box assumed" in a for a in res["assumptions"])


def test_text_output_names_the_record_the_bound_and_the_assumptions(capsys, record):
    rc, out, _ = _run(capsys, "identify", "--record", record, *ARGS)
    assert rc == 0
    assert out.startswith(f"record {record}: N = 60, dt = 0.1")
    assert "output error bound 0.02 (--output-bound)" in out
    assert "one record" in out and "assumptions:" in out


def test_the_a_priori_box_can_be_given(capsys, record):
    box = [0.2, 0.3, 0.0, 0.1, 0.2, 0.3, 0.0, 0.1]
    rc, out, _ = _run(capsys, "identify", "--record", record, *ARGS, "--json",
                      "--gamma-box", *box)
    assert rc == 0
    res = json.loads(out)
    lo, hi = np.array(res["lower"][:4]), np.array(res["upper"][:4])
    assert np.all(lo >= np.array(box[0::2])) and np.all(hi <= np.array(box[1::2]))


@pytest.mark.parametrize("extra, message", [
    (("--prbs", "p.csv"), "not both"),
    (("--steady-output-bound", 0.1), "--steady-output-bound belongs"),
])
def test_conflicting_options_are_refused(capsys, record, extra, message):
    rc, out, err = _run(capsys, "identify", "--record", record, *ARGS, *extra)
    assert rc == 2 and out == ""
    assert message in err


def test_gamma_box_without_record_is_refused(capsys):
    rc, out, err = _run(capsys, "identify", "--steady", "s.csv", "--prbs", "p.csv",
                        "--output-bound", 0.05, "--gamma-box", *range(8))
    assert rc == 2 and "--gamma-box is the a priori backlash box of --record" in err


def test_missing_output_bound_is_refused(capsys, record):
    rc, out, err = _run(capsys, "identify", "--record", record, "--na", 1, "--nb", 1)
    assert rc == 2 and "--output-bound" in err


def test_no_record_at_all_says_both_ways(capsys):
    rc, out, err = _run(capsys, "identify", "--output-bound", 0.05)
    assert rc == 2 and "--record DATA.csv" in err and "--steady STEADY.csv" in err


def _strict(text):
    """Parse as RFC 8259 JSON: Infinity and NaN are not JSON."""
    def refuse(name):
        raise ValueError(f"not JSON: {name}")
    return json.loads(text, parse_constant=refuse)


def test_json_of_a_record_that_bounds_nothing_is_strict_json(capsys, tmp_path):
    """A monotone ramp identifies no dead band: the infinite ends are null everywhere,
    in the interval records too (they were printed as Infinity)."""
    u = np.linspace(-2, 2, 60)
    y = lfilter(B, A, own_play(u, *GAMMA)) + 0.02 * np.sin(np.arange(60))
    path = tmp_path / "ramp.csv"
    path.write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n"
                                      for a, b in zip(u, y, strict=True)))
    rc, out, err = _run(capsys, "identify", "--record", path, *ARGS, "--json")
    assert rc == 0 and "never reverses" in err
    res = _strict(out)
    assert None in res["upper"]  # not identified: null, not a number
    ends = [iv.get(k) for iv in res["intervals"] for k in ("upper", "centre", "half_width")]
    assert None in ends and all(e is None or np.isfinite(e) for e in ends)


def test_text_speaks_command_line_and_gives_the_linear_model(capsys, tmp_path):
    """The ramp bounds no dead band but the linear block: its central model is printed, and
    the assumptions name the command-line option, not the Python parameter."""
    u = np.linspace(-2, 2, 60)
    y = lfilter(B, A, own_play(u, *GAMMA)) + 0.02 * np.sin(np.arange(60))
    path = tmp_path / "ramp.csv"
    path.write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n"
                                      for a, b in zip(u, y, strict=True)))
    rc, out, err = _run(capsys, "identify", "--record", path, *ARGS)
    assert rc == 0
    assert "pass --gamma-box to change" in out and "pass gamma_box" not in out
    assert "central model: G(z) = " in out
    rc, out, _ = _run(capsys, "identify", "--record", path, *ARGS, "--json")
    assert _strict(out)["transfer_function"]["den"][0] == 1.0


def test_report_of_one_record_holds_the_truth_and_its_figures(capsys, record, tmp_path):
    """Issue 26: the report works on a one-record fit (it was refused, "--report needs the
    chapter's two experiments"): report.md with the record, the assumptions, both blocks'
    intervals and the envelope, and its three figures; stdout keeps the text result."""
    out_dir = tmp_path / "rep"
    rc, out, err = _run(capsys, "identify", "--record", record, *ARGS, "--report", out_dir)
    assert rc == 0 and "report written to" in err and "report written" not in out
    assert "ml" in out and "assumptions" in out
    files = sorted(p.name for p in out_dir.iterdir())
    assert files == ["backlash_characteristic.png", "envelope.png", "intervals.png",
                     "report.md"]
    text = (out_dir / "report.md").read_text()
    for section in ("## Record", "## Assumptions", "## Backlash", "## Linear block",
                    "### Output envelope"):
        assert section in text
    assert "N = 60 samples, sampling time 0.1" in text
    rows = {line.split("|")[1].strip(): [c.strip() for c in line.split("|")[2:5]]
            for line in text.splitlines()
            if line.startswith("| ") and line.split("|")[1].strip() in
            ("ml", "cl", "mr", "cr", "a1", "b1")}
    truth = dict(zip(("ml", "cl", "mr", "cr", "a1", "b1"), (*GAMMA, -0.5, 0.5), strict=True))
    for name, (lo, _, hi) in rows.items():
        assert float(lo) - 1e-4 <= truth[name] <= float(hi) + 1e-4, name  # 4 digits shown
    assert len(rows) == 6
    # an existing report is kept without --force, before any fit
    rc, out, err = _run(capsys, "identify", "--record", record, *ARGS, "--report", out_dir)
    assert rc != 0 and "--force" in err and out == ""
