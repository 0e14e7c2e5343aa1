"""``--model-set FILE.json`` of ``eiv`` and ``identify``: the guaranteed model set of the
linear block (Bode envelope, certified uncertainty weights) for a robust-control design,
from the command line (it had no route to it)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from oracles import one_record
from scipy.signal import freqz, lfilter

from hammerbound.app.cli import main

A, B = [1.0, -0.6], [0.0, 0.5]  # y_t = 0.6 y_{t-1} + 0.5 u_{t-1}, static gain 1.25


def _eiv_csv(tmp_path, bound=0.02, seed=0):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1, 1, 40), 4)
    y = lfilter(B, A, u) + bound * rng.choice([-1.0, 1.0], u.size)  # exactly at the bound
    path = tmp_path / "rec.csv"
    path.write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(u, y,
                                                                                   strict=True)))
    return path


def _z_response(num, den, omega):
    """The response of ``num(z) / den(z)`` (python-control's coefficients, in powers of
    ``z``) at ``z = e^{j omega}``."""
    z = np.exp(1j * np.asarray(omega))
    return np.polyval(num, z) / np.polyval(den, z)


def _run(*argv):
    try:
        return main(list(argv))
    except SystemExit as stop:  # argparse's own errors
        return stop.code


def test_eiv_writes_a_model_set_that_holds_the_true_plant(tmp_path, capsys):
    out = tmp_path / "set.json"
    rc = _run("eiv", str(_eiv_csv(tmp_path)), "--na", "1", "--nb", "1", "--output-bound",
              "0.02", "--method", "lp", "--steady-state-gain", "1.25", "--model-set",
              str(out), "--json")
    doc = json.loads(capsys.readouterr().out)
    assert rc == 0 and doc["model_set"] == str(out)
    ms = json.loads(out.read_text())
    lo, hi = np.array(ms["lower"]), np.array(ms["upper"])
    assert np.all(lo <= [-0.6, 0.5]) and np.all([-0.6, 0.5] <= hi)
    for part in ("box", "gain_plane"):
        env = ms[part]["frequency_envelope"]
        w = np.array(env["omega"])
        _, g = freqz(B, A, worN=w)  # dt = 1 sample (no time column)
        mag = np.abs(g)
        assert np.all(np.array(env["mag_lower"]) <= mag * (1 + 1e-12))
        upper = np.array([np.inf if v is None else v for v in env["mag_upper"]])
        assert np.all(mag <= upper * (1 + 1e-12))
        for kind in ("multiplicative", "additive"):
            wt = ms[part]["uncertainty_weights"][kind]
            assert wt["kind"] == kind and len(wt["num"]) == len(wt["den"])
    assert ms["gain_plane"]["steady_state_gain"] == 1.25


def test_an_existing_file_is_refused_before_any_work(tmp_path, capsys):
    out = tmp_path / "set.json"
    out.write_text("mine")
    rc = _run("eiv", str(_eiv_csv(tmp_path)), "--na", "1", "--nb", "1", "--output-bound",
              "0.02", "--method", "lp", "--model-set", str(out))
    cap = capsys.readouterr()
    assert rc == 2 and out.read_text() == "mine" and cap.out == ""
    assert "--model-set" in cap.err and "--force" in cap.err


def test_no_model_set_from_an_infinite_interval(tmp_path, capsys):
    """One record stopped before it bounded the b_j: no file, exit status 1, and the
    reason among the JSON warnings."""
    u, y, _ = one_record(60, 0.02, "uniform", 2)
    rec = tmp_path / "r.csv"
    rec.write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n"
                                     for a, b in zip(u, y, strict=True)))
    out = tmp_path / "set.json"
    rc = _run("identify", "--record", str(rec), "--output-bound", "0.02", "--method", "lp",
              "--total-time-limit", "0", "--model-set", str(out), "--json")
    doc = json.loads(capsys.readouterr().out)
    assert rc == 1 and not out.exists() and doc["model_set"] is None
    assert any("no model set written" in w["message"] for w in doc["warnings"])


def test_identify_two_experiments_writes_the_model_set(tmp_path, capsys):
    from hammerbound import chapter_example

    ex = chapter_example(0.02, N=80)
    ss, pr = tmp_path / "steady.csv", tmp_path / "prbs.csv"
    for path, (u, y) in ((ss, (ex.steady.u, ex.steady.y)), (pr, (ex.prbs.u, ex.prbs.y))):
        path.write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n"
                                          for a, b in zip(u, y, strict=True)))
    out = tmp_path / "set.json"
    rc = _run("identify", "--steady", str(ss), "--prbs", str(pr), "--steady-output-bound",
              "0.02", "--output-bound", "0.02", "--method", "lp", "--model-set", str(out))
    capsys.readouterr()
    assert rc == 0
    ms = json.loads(out.read_text())
    a1, a2, b1, b2 = ex.theta_true
    env = ms["gain_plane"]["frequency_envelope"]  # unit gain (22.8)
    _, g = freqz([0.0, b1, b2], [1.0, a1, a2], worN=np.array(env["omega"]))
    assert np.all(np.array(env["mag_lower"]) <= np.abs(g) * (1 + 1e-12))
    assert np.all(np.abs(g) <= np.array(env["mag_upper"]) * (1 + 1e-12))
    # each weight names the G0 it bounds around (on the gain plane not the box centre;
    # the file had none, trial 13): |G/G0 - 1| <= |W| for the true G
    for kind in ("multiplicative", "additive"):
        wt = ms["gain_plane"]["uncertainty_weights"][kind]
        omega = np.linspace(0.0, np.pi, 2001)
        _, g = freqz([0.0, b1, b2], [1.0, a1, a2], worN=omega)
        g0 = _z_response(wt["central"]["num"], wt["central"]["den"], omega)
        w = _z_response(wt["num"], wt["den"], omega)
        dev = np.abs(g / g0 - 1) if kind == "multiplicative" else np.abs(g - g0)
        assert np.all(dev <= np.abs(w) * (1 + 1e-9)), kind


def _wide_csv(tmp_path):
    """A short noisy record whose a1 interval reaches the stability limit -1: every
    interval finite, but some A of the box vanishes on the unit circle (no finite
    weight)."""
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1, 1, 10), 3)
    y = lfilter([0, 0.5], [1, -0.9], u) + 0.3 * rng.uniform(-1, 1, u.size)
    path = tmp_path / "wide.csv"
    path.write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(u, y,
                                                                                   strict=True)))
    return path


def test_finite_intervals_without_a_finite_weight_still_give_the_set(tmp_path, capsys):
    """The intervals and the envelope are written, the weights are null with the reason
    (the whole file was dropped, exit status 1, review)."""
    out = tmp_path / "set.json"
    rc = _run("eiv", str(_wide_csv(tmp_path)), "--na", "1", "--nb", "1", "--output-bound",
              "0.3", "--method", "lp", "--model-set", str(out))
    err = " ".join(capsys.readouterr().err.split())
    assert rc == 0
    # said on stderr too (new-user trial 20: only the file's no_weight said it)
    assert "the model set's multiplicative weight is null: the multiplicative" in err
    assert "the model set's additive weight is null" in err
    ms = json.loads(out.read_text())
    assert ms["lower"][0] == pytest.approx(-1.0)
    assert ms["box"]["uncertainty_weights"] == {"multiplicative": None, "additive": None}
    why = ms["box"]["no_weight"]  # each kind with its own reason
    assert set(why) == {"multiplicative", "additive"}
    assert all("unit circle" in text for text in why.values())
    assert any("output error bound" in a for a in ms["assumptions"])


def test_a_failure_while_writing_keeps_the_results(tmp_path, capsys, monkeypatch):
    """Any error of the model set (here a solver error of the weight) leaves the
    identification's results printed, with a warning and exit status 1 (it ended the
    command with exit status 2 and nothing on stdout, review)."""
    from hammerbound.exceptions import SolverError
    from hammerbound.stage2.estimator import LinearEIVSetEstimator

    def broken(self, *a, **kw):
        raise SolverError("the weight's LP failed")

    monkeypatch.setattr(LinearEIVSetEstimator, "uncertainty_weight", broken)
    out = tmp_path / "set.json"
    rc = _run("eiv", str(_eiv_csv(tmp_path)), "--na", "1", "--nb", "1", "--output-bound",
              "0.02", "--method", "lp", "--model-set", str(out), "--json")
    cap = capsys.readouterr()
    doc = json.loads(cap.out)
    assert rc == 1 and not out.exists() and doc["model_set"] is None
    assert doc["intervals"] and any("SolverError: the weight's LP failed" in w["message"]
                                    for w in doc["warnings"])


def test_a_file_made_while_the_fit_ran_is_kept(tmp_path, capsys, monkeypatch):
    from hammerbound.stage2.estimator import LinearEIVSetEstimator

    out = tmp_path / "set.json"
    fit = LinearEIVSetEstimator.fit

    def fit_then_someone_writes(self, *a, **kw):
        res = fit(self, *a, **kw)
        out.write_text("theirs")
        return res

    monkeypatch.setattr(LinearEIVSetEstimator, "fit", fit_then_someone_writes)
    rc = _run("eiv", str(_eiv_csv(tmp_path)), "--na", "1", "--nb", "1", "--output-bound",
              "0.02", "--method", "lp", "--model-set", str(out))
    err = capsys.readouterr().err
    assert rc == 1 and out.read_text() == "theirs"
    assert "appeared while the fit ran; pass --force" in err


def test_force_writes_through_a_link_and_leaves_no_temporary_file(tmp_path, capsys):
    """--force replaces the content where the path points (a replacing rename swapped a
    link for a plain file and could leave a ".part" file behind, review)."""
    real = tmp_path / "real.json"
    real.write_text("{}")
    link = tmp_path / "set.json"
    link.symlink_to(real)
    rc = _run("eiv", str(_eiv_csv(tmp_path)), "--na", "1", "--nb", "1", "--output-bound",
              "0.02", "--method", "lp", "--model-set", str(link), "--force")
    capsys.readouterr()
    assert rc == 0 and link.is_symlink()
    assert "frequency_envelope" in json.loads(real.read_text())["box"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["real.json", "rec.csv", "set.json"]
