"""``hammerbound diagnose`` with an identified backlash model (new-user trial 17: the
command line took only ``--num/--den``, so the model an identification gave could not be
diagnosed): ``--model FIT.json`` (the JSON of ``identify --json``) and ``--backlash``."""

from __future__ import annotations

import json

import numpy as np
import pytest
from oracles import GAMMA_TRUE, hammerstein
from scipy.signal import lfilter

from hammerbound.app.cli import main

A, B = [1.0, -0.76, 0.82], [0.0, 2.15, -1.09]


def _write(path, u, y):
    path.write_text("u,y\n" + "".join(f"{a!r},{b!r}\n" for a, b in
                                      zip(map(float, u), map(float, y), strict=True)))
    return path


def _steps(rng, n=240):
    return np.repeat(rng.uniform(-2.0, 2.0, n // 8), 8)


@pytest.fixture(scope="module")
def fit_json(tmp_path_factory):
    """A two-stage fit of the chapter's plant (own simulation), saved as identify's JSON."""
    tmp = tmp_path_factory.mktemp("fit")
    rng = np.random.default_rng(5)
    levels = np.r_[np.linspace(0.3, 2.5, 12), -np.linspace(0.3, 2.5, 12)]
    ys = [hammerstein(np.r_[0.0, np.full(400, v)], GAMMA_TRUE, B, A)[-1] for v in levels]
    ss = _write(tmp / "steady.csv", levels, np.array(ys) + rng.uniform(-0.02, 0.02, 24))
    u = rng.choice([-1.0, 1.0], 100)
    pr = _write(tmp / "prbs.csv", u, hammerstein(u, GAMMA_TRUE, B, A)
                + rng.uniform(-0.02, 0.02, u.size))
    out = tmp / "fit.json"
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["identify", "--steady", str(ss), "--prbs", str(pr), "--output-bound",
                     "0.02", "--method", "lp", "--json"]) == 0
    out.write_text(buf.getvalue())
    return out


def _centres(path):
    fit = json.loads(path.read_text())
    return {n: 0.5 * (a + b) for n, a, b in zip(fit["parameters"], fit["lower"],
                                                fit["upper"], strict=True)}


def test_the_model_of_a_fit_explains_its_own_simulation(fit_json, tmp_path, capsys):
    """A record simulated (own code) from the fit's centres is consistent with the model
    ``--model`` builds, taken as exact (``--refit none``): A, B, the backlash and its
    start are built as the JSON says."""
    c = _centres(fit_json)
    u = _steps(np.random.default_rng(1))
    x = np.empty(u.size)
    state = 0.0
    for t, v in enumerate(u):  # the play operator from x0 = 0, clamped into the band
        state = min(max(state, c["mr"] * (v - c["cr"])), c["ml"] * (v + c["cl"]))
        x[t] = state
    y = lfilter([0.0, c["b1"], c["b2"]], [1.0, c["a1"], c["a2"]], x)
    rec = _write(tmp_path / "new.csv", u, y + 0.01 * np.random.default_rng(2).uniform(-1, 1,
                                                                                      u.size))
    rc = main(["diagnose", str(rec), "--model", str(fit_json), "--output-bound", "0.011",
               "--refit", "none", "--json"])
    rep = json.loads(capsys.readouterr().out)
    assert rc == 0 and rep["consistent_before"] is True


def _worn(fit_json, tmp_path):
    """A record of the fit's central model with its dead band 8 times wider (own code)."""
    c = _centres(fit_json)
    u = _steps(np.random.default_rng(3))
    y = hammerstein(u, (c["ml"], 8 * c["cl"], c["mr"], 8 * c["cr"]), [0.0, c["b1"], c["b2"]],
                    [1.0, c["a1"], c["a2"]])
    return _write(tmp_path / "new.csv", u, y)


def test_a_wider_dead_band_in_the_record_is_found_inconsistent(fit_json, tmp_path, capsys):
    rec = _worn(fit_json, tmp_path)
    main(["diagnose", str(rec), "--model", str(fit_json), "--output-bound", "0.01",
          "--refit", "none", "--json", "--candidates", "backlash", "--max-effects", "1"])
    rep = json.loads(capsys.readouterr().out)
    assert rep["consistent_before"] is False


def test_a_verdict_against_the_fit_says_it_tested_the_centre(fit_json, tmp_path, capsys):
    rec = _worn(fit_json, tmp_path)
    main(["diagnose", str(rec), "--model", str(fit_json), "--output-bound", "0.01",
          "--candidates", "offset", "--max-effects", "1"])
    out = capsys.readouterr().out
    assert "tests the fitted set's central model" in " ".join(out.split())


def test_backlash_with_num_den_is_a_hammerstein_model(tmp_path, capsys):
    u = _steps(np.random.default_rng(4))
    y = hammerstein(u, GAMMA_TRUE, B, A) + np.random.default_rng(5).uniform(-0.01, 0.01,
                                                                             u.size)
    rec = _write(tmp_path / "d.csv", u, y)
    args = ["diagnose", str(rec), "--num", "0 2.15 -1.09", "--den", "1 -0.76 0.82",
            "--output-bound", "0.011", "--refit", "none", "--json"]
    main([*args, "--backlash", " ".join(map(str, GAMMA_TRUE))])
    with_backlash = json.loads(capsys.readouterr().out)
    main([*args, "--candidates", "offset", "--max-effects", "1"])
    without = json.loads(capsys.readouterr().out)
    assert with_backlash["consistent_before"] is True
    assert without["consistent_before"] is False


@pytest.mark.parametrize(("extra", "said"), [
    (["--model", "{fit}", "--num", "0 1"], "--model FIT.json gives the whole model"),
    ([], "the model is required: --num and --den"),
    (["--num", "0 1"], "the model is required"),
    (["--num", "0 1", "--den", "1 -0.5", "--backlash", "1 0.1 1"], "--backlash takes four"),
    (["--model", "{bad}"], "is not JSON"),
    (["--model", "{unbounded}"], "did not bound cl"),
])
def test_model_options_are_checked(fit_json, tmp_path, capsys, extra, said):
    rec = _write(tmp_path / "d.csv", np.arange(20.0), np.arange(20.0))
    (tmp_path / "bad.json").write_text("{not json")
    fit = json.loads(fit_json.read_text())
    fit["upper"][fit["parameters"].index("cl")] = None
    (tmp_path / "unbounded.json").write_text(json.dumps(fit))
    extra = [e.format(fit=fit_json, bad=tmp_path / "bad.json",
                      unbounded=tmp_path / "unbounded.json") for e in extra]
    rc = main(["diagnose", str(rec), "--output-bound", "0.1", *extra])
    assert rc == 2
    assert said in " ".join(capsys.readouterr().err.split())


def test_an_unknown_initial_backlash_state_is_not_scored(fit_json, tmp_path, capsys):
    """Re-check 51: a fit's own record was "certified" inconsistent with its central model,
    which started the backlash at 0 where the record's state started elsewhere. The
    samples any start can reach are not scored by default (the report says so)."""
    c = _centres(fit_json)
    u = _steps(np.random.default_rng(6))
    state = c["ml"] * (u[0] + c["cl"])  # the top of the first band, not 0
    x = np.empty(u.size)
    for t, v in enumerate(u):
        state = max(c["mr"] * (v - c["cr"]), min(c["ml"] * (v + c["cl"]), state))
        x[t] = state
    y = lfilter([0.0, c["b1"], c["b2"]], [1.0, c["a1"], c["a2"]], x)
    rec = _write(tmp_path / "new.csv", u, y)
    args = ["diagnose", str(rec), "--model", str(fit_json), "--output-bound", "0.005",
            "--refit", "none", "--json", "--candidates", "offset", "--max-effects", "1"]
    main(args)
    rep = json.loads(capsys.readouterr().out)
    assert rep["consistent_before"] is True
    assert rep["skip"] > 0
    assert f"the first {rep['skip']} samples are not scored" in rep["skip_note"]
    main([*args, "--skip", "0"])
    assert json.loads(capsys.readouterr().out)["consistent_before"] is False


def test_a_denominator_not_starting_with_one_is_said(tmp_path, capsys):
    """New-user trial 21: continuous-time coefficients "4.5 1" were read as 4.5 + q^-1
    without a word."""
    u = _steps(np.random.default_rng(8))
    rec = _write(tmp_path / "d.csv", u, lfilter([0.0, 0.5], [1.0, -0.5], u))
    main(["diagnose", str(rec), "--num", "0 1", "--den", "4.5 1", "--output-bound", "0.1",
          "--candidates", "offset", "--max-effects", "1"])
    err = " ".join(capsys.readouterr().err.split())
    assert "--den starts with 4.5, not 1: the model is read in powers of q^-1 and divided " \
        "by it (A = [1.0, 0.222222])" in err
    main(["diagnose", str(rec), "--num", "0 0.5", "--den", "1 -0.5", "--output-bound", "0.1",
          "--candidates", "offset", "--max-effects", "1"])
    assert "--den starts" not in capsys.readouterr().err


def test_the_record_read_is_said_first(tmp_path, capsys):
    """New-user trial 21: diagnose did not echo which file, N, dt or columns it read (the
    identify and eiv commands do)."""
    u = _steps(np.random.default_rng(9))
    rec = _write(tmp_path / "d.csv", u, lfilter([0.0, 0.5], [1.0, -0.5], u))
    args = ["diagnose", str(rec), "--num", "0 0.5", "--den", "1 -0.5", "--output-bound",
            "0.1", "--candidates", "offset", "--max-effects", "1"]
    main(args)
    first = capsys.readouterr().out.splitlines()[0]
    assert first == f"record {rec}: N = {u.size}, dt = not given, input 'u', output 'y'"
    main([*args, "--json"])
    assert json.loads(capsys.readouterr().out)["record"]["N"] == u.size
