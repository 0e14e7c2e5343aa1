"""New-user trial 6 (discrepancy workflow and the command line on one's own CSVs): what it
found, fixed and kept fixed.

* a single-level input with steady-state data crashed with an IndexError;
* the two-stage JSON had no ``procedure`` / ``assumptions`` and its central model no time
  unit;
* an empty stage 2 named ``--input-bound`` and ``--steady-state-gain`` (flags ``identify``
  lacks) and never the steady-state points its input bound comes from;
* ``--prbs`` with an ordinary record silently became a one-record fit under the header
  "PRBS record", with advice in Python syntax;
* a one-record fit whose ``b_j`` sat at the default box ``|b_j| <= 1e4`` printed those ends
  as finite and a zero central model ``G(z) = (0) / (1)``.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from oracles import GAMMA_TRUE, hammerstein, one_record
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.app.cli import main
from hammerbound.exceptions import (
    DataValidationError,
    EmptyFeasibleSetError,
    IllPosedBacklashError,
    NotIdentifiedWarning,
    UnboundedSetError,
)

A, B = [1.0, -0.76, 0.82], [0.0, 2.15, -1.09]


def _write(path, u, y, header="u,y"):
    path.write_text(header + "\n" + "".join(
        f"{a!r},{b!r}\n" for a, b in zip(map(float, u), map(float, y), strict=True)))
    return path


def _steady(rng, bound, settle=400, at_bound=False):
    """Steady-state points of the chapter's plant (own simulation: each level held until
    the transient is far below the bound) and their noise."""
    levels = np.r_[np.linspace(0.3, 2.5, 12), -np.linspace(0.3, 2.5, 12)]
    ys = []
    for lev in levels:
        u = np.r_[0.0, np.full(settle, lev)]
        ys.append(hammerstein(u, GAMMA_TRUE, B, A)[-1])
    noise = (bound * rng.choice([-1.0, 1.0], levels.size) if at_bound
             else rng.uniform(-bound, bound, levels.size))
    return levels, np.array(ys) + noise


def _prbs(rng, n, bound, ustar=1.0):
    u = ustar * rng.choice([-1.0, 1.0], n)
    return u, hammerstein(u, GAMMA_TRUE, B, A) + rng.uniform(-bound, bound, n)


@pytest.fixture
def two_experiments(tmp_path):
    rng = np.random.default_rng(3)
    us, ys = _steady(rng, 0.02)
    u, y = _prbs(rng, 80, 0.02)
    ss = _write(tmp_path / "steady.csv", us, ys)
    t = 20.0 * np.arange(u.size)
    pr = tmp_path / "prbs.csv"
    pr.write_text("time (ms),u,y\n" + "".join(
        f"{a!r},{b!r},{c!r}\n" for a, b, c in zip(*(map(float, v) for v in (t, u, y)),
                                                   strict=True)))
    return ss, pr, (u, y), (us, ys)


@pytest.mark.parametrize("u", [np.ones(60), np.zeros(60), -np.ones(60)])
def test_a_single_level_input_is_a_typed_error(two_experiments, u):
    _, _, (_, y), steady = two_experiments
    idf = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.02), hb.LinearEIVSetEstimator(output_bound=0.02,
                                                                method="lp"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(DataValidationError, match="the input is constant"):
            idf.fit(u, y[:60], steady_state=steady)


def test_the_two_stage_json_says_its_procedure_and_assumptions(two_experiments, capsys):
    ss, pr, _, _ = two_experiments
    assert main(["identify", "--steady", str(ss), "--prbs", str(pr), "--output-bound",
                 "0.02", "--method", "lp", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["procedure"] == "two-stage"
    text = " ".join(out["assumptions"])
    assert "settled: a transient left" in text and "stage-1 bounds |dx_t|" in text
    assert "(22.8)" in text and "|b_j| <= 1e4" in text
    assert out["data"]["time_unit"] == "ms"
    assert out["transfer_function"]["time_unit"] == "ms"
    assert out["transfer_function"]["dt"] == 20


def test_prbs_flag_with_an_ordinary_record_is_refused_in_cli_terms(two_experiments, tmp_path,
                                                                    capsys):
    ss, _, _, _ = two_experiments
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-2, 2, 12), 6)
    rec = _write(tmp_path / "rec.csv", u, hammerstein(u, GAMMA_TRUE, B, A))
    rc = main(["identify", "--steady", str(ss), "--prbs", str(rec), "--output-bound", "0.02",
               "--method", "lp"])
    cap = capsys.readouterr()
    assert rc == 2 and cap.out == ""
    assert "DataValidationError" in cap.err and "exactly two values" in cap.err
    assert "--record DATA.csv (not --prbs)" in cap.err
    assert "procedure=" not in cap.err


def test_an_empty_stage_two_names_the_steady_points_not_absent_flags(tmp_path, capsys):
    """Steady-state points with noise exactly at their bound and a transient left (held
    for 60 samples of a 0.9 pole plant: ~1e-3 of the step left): stage 1's inner bound is
    then far too tight, and the PRBS record (noise inside its bound) is blamed."""
    rng = np.random.default_rng(5)
    us, ys = _steady(rng, 0.02, settle=12, at_bound=True)
    u, y = _prbs(rng, 80, 0.02)
    ss = _write(tmp_path / "steady.csv", us, ys)
    pr = _write(tmp_path / "prbs.csv", u, y)
    rc = main(["identify", "--steady", str(ss), "--prbs", str(pr), "--output-bound", "0.02",
               "--method", "lp"])
    err = capsys.readouterr().err
    if rc == 0:
        pytest.skip("this draw is consistent: nothing to say")  # pragma: no cover
    assert rc == 2 and "EmptyFeasibleSetError" in err
    assert "--input-bound" not in err and "--steady-state-gain" not in err
    assert "computed from the steady-state points" in err and "not settled" in err


def test_the_library_message_of_an_empty_stage_two():
    """The same through Python: the re-framed error keeps its type and attributes."""
    rng = np.random.default_rng(5)
    us, ys = _steady(rng, 0.02, settle=12, at_bound=True)
    u, y = _prbs(rng, 80, 0.02)
    idf = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.02), hb.LinearEIVSetEstimator(output_bound=0.02,
                                                                method="lp"))
    try:
        idf.fit(u, y, steady_state=(us, ys))
    except EmptyFeasibleSetError as exc:
        assert "input_bound" not in str(exc) and "steady_state_gain=None" not in str(exc)
        assert "stage 1's inner-signal bound |dx_t| <=" in str(exc)
        assert exc.relaxation == "lp" and isinstance(exc.__cause__, EmptyFeasibleSetError)
    else:  # pragma: no cover - the draw above is empty (checked when written)
        pytest.fail("expected an empty stage 2 from unsettled steady-state points")


def _b_at_box_fit():
    """A one-record fit stopped before any work: every end stays at the a priori box."""
    u, y, _ = one_record(80, 0.05, "uniform", 0)
    lin = hb.LinearEIVSetEstimator(output_bound=0.05, na=2, nb=2, method="lp",
                                   total_time_limit=1e-3)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        idf = hb.HammersteinBacklashIdentifier(linear=lin, procedure="one-record").fit(u, y)
    return idf, caught


def test_b_at_the_default_box_is_not_identified():
    idf, caught = _b_at_box_fit()
    msgs = [str(w.message) for w in caught if issubclass(w.category, NotIdentifiedWarning)]
    # stopped by the time limit: the warning leads with that, not with the record
    # (new-user trial 9: "the record does not bound ..." when only time was short)
    assert any(m.startswith("within the time limit the search did not bound b1, b2")
               and "|b_j| <= 1e4" in m and "give more time (total_time_limit)" in m
               # trial 16: an over-parameterised model (na = nb = 2 on a first-order
               # plant) was advised only "a record that moves the input more often"
               and "lower na, nb if the plant may be of lower order" in m
               for m in msgs), msgs
    assert np.all(np.isinf(idf.theta_bounds_[2:]))
    # bound_info_ agrees with bounds_ (it said "limit" at +-1e4)
    for info in idf.bound_info_:
        k = list(idf.param_names_).index(info.param)
        end = idf.bounds_[k, 0 if info.sense == "min" else 1]
        assert info.bound == end or (np.isfinite(end) and info.bound == pytest.approx(end))
        assert (info.status == "not identified") == bool(np.isinf(end))
    assert np.all(np.isfinite(idf.theta_bounds_[:2]))  # the stable-A box stays (A1)
    assert idf.system_ is None
    with pytest.raises(UnboundedSetError, match="does not bound b1, b2.*lower na, nb"):
        idf.linear_.to_transfer_function()
    with pytest.raises(UnboundedSetError):
        idf.predict(np.ones(10))
    assert not any(issubclass(w.category, RuntimeWarning) for w in caught)
    frame = idf.intervals_.records()
    assert frame[6]["lower"] == -np.inf and np.isnan(frame[6]["centre"])


def test_a_theta_box_given_keeps_its_ends():
    u, y, _ = one_record(80, 0.05, "uniform", 0)
    lin = hb.LinearEIVSetEstimator(output_bound=0.05, na=2, nb=2, method="lp",
                                   total_time_limit=1e-3,
                                   theta_box={"b1": (-5.0, 5.0), "b2": (-5.0, 5.0)})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idf = hb.HammersteinBacklashIdentifier(linear=lin, procedure="one-record").fit(u, y)
    assert np.all(np.isfinite(idf.theta_bounds_))
    assert idf.theta_bounds_[2, 0] == -5.0 and idf.theta_bounds_[3, 1] == 5.0


def test_cli_prints_no_zero_model(tmp_path, capsys):
    u, y, _ = one_record(80, 0.05, "uniform", 0)
    rec = _write(tmp_path / "rec.csv", u, y)
    assert main(["identify", "--record", str(rec), "--output-bound", "0.05", "--method",
                 "lp", "--total-time-limit", "0.001", "--json"]) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert out["transfer_function"] is None
    assert out["intervals"][6]["lower"] is None and out["intervals"][6]["centre"] is None
    assert "RuntimeWarning" not in cap.err
    assert "see assumptions_" not in cap.err and "bound_info_" not in cap.err



# ------------------------------------------------ review of the above (helper, same day)
def test_no_frequency_envelope_or_weight_when_b_is_unbounded():
    """An infinite b_j gave a NaN magnitude envelope that excluded every model: refused."""
    idf, _ = _b_at_box_fit()
    with pytest.raises(UnboundedSetError, match="no frequency envelope"):
        idf.linear_.frequency_response_bounds()
    with pytest.raises(UnboundedSetError, match="no uncertainty weight"):
        idf.linear_.uncertainty_weight()
    assert idf.linear_.to_transfer_function(theta=[-0.5, 0.1, 0.3, 0.3]) is not None


def test_one_step_band_with_an_unbounded_b_at_a_zero_input():
    """0 * [-inf, inf] is 0 in the band (it was NaN), and the band holds the data."""
    idf, _ = _b_at_box_fit()
    x = np.r_[np.zeros(6), np.ones(4)]
    y = np.zeros(10)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = idf.linear_.one_step_envelope(x, y, input_bound=0.0)
    lo, hi = env.lower[2:], env.upper[2:]
    assert not np.any(np.isnan(lo)) and not np.any(np.isnan(hi))
    assert np.all(np.isfinite(lo[:4])) and np.all(lo <= 0.0) and np.all(hi >= 0.0)


def test_the_one_record_linear_view_has_a_summary():
    idf, _ = _b_at_box_fit()
    text = idf.linear_.summary()
    assert text.startswith("linear block of a one-record fit: method lp, na=2 nb=2 nk=1")
    assert "|b_j| <= 1e4 (default theta box" in text and "not identified" in text
    b1 = next(line for line in text.splitlines() if line.startswith("b1 "))
    assert b1.split()[1:5] == ["-inf", "-", "inf", "inf"]


def _settled_two_stage(theta_box=None, n=80, bound=0.02):
    rng = np.random.default_rng(1)
    us, ys = _steady(rng, bound)
    u, y = _prbs(rng, n, bound)
    idf = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(bound),
        hb.LinearEIVSetEstimator(output_bound=bound, method="lp", theta_box=theta_box))
    return idf, u, y, (us, ys)


def test_a_box_that_misses_the_gain_is_not_blamed_on_the_data():
    idf, u, y, steady = _settled_two_stage(
        {"a1": (0.5, 0.6), "a2": (0.5, 0.6), "b1": (0.0, 0.1), "b2": (0.0, 0.1)})
    with pytest.raises(EmptyFeasibleSetError) as info:
        idf.fit(u, y, steady_state=steady)
    text = str(info.value)
    assert "theta_box and the gain equality" in text
    assert "fixes the gain at 1" in text and "check the gain" not in text
    assert "steady-state points" not in text


def test_an_unbounded_stage_two_names_no_absent_flag(tmp_path, capsys):
    """Ten PRBS samples cannot bound a third-order block: UnboundedSetError, whose
    assumptions said 'pass steady_state_gain=None' (``--steady-state-gain`` on the CLI)."""
    rng = np.random.default_rng(1)
    us, ys = _steady(rng, 0.02)
    u = np.r_[1.0, -np.ones(9)]
    y = hammerstein(u, GAMMA_TRUE, B, A) + rng.uniform(-0.02, 0.02, u.size)
    ss = _write(tmp_path / "steady.csv", us, ys)
    pr = _write(tmp_path / "prbs.csv", u, y)
    rc = main(["identify", "--steady", str(ss), "--prbs", str(pr), "--output-bound", "3",
               "--steady-output-bound", "0.02", "--na", "3", "--nb", "3", "--method", "lp"])
    err = capsys.readouterr().err
    assert rc == 2 and "UnboundedSetError" in err
    assert "--steady-state-gain" not in err and "steady_state_gain" not in err


def test_an_offset_prbs_gets_cli_advice(tmp_path, capsys):
    rng = np.random.default_rng(1)
    us, ys = _steady(rng, 0.02)
    u, y = _prbs(rng, 60, 0.02)
    u = np.where(u > 0, 1.01, -1.0)
    ss = _write(tmp_path / "steady.csv", us, ys)
    pr = _write(tmp_path / "prbs.csv", u, y)
    rc = main(["identify", "--steady", str(ss), "--prbs", str(pr), "--output-bound", "0.02",
               "--method", "lp"])
    err = capsys.readouterr().err
    assert rc == 2 and "prbs_level" not in err
    assert "+-u* in the file" in err and "--record DATA.csv" in err


def test_diagnose_cli_takes_candidates_all_and_speaks_cli(tmp_path, capsys):
    rng = np.random.default_rng(2)
    u = np.repeat(rng.uniform(-2.0, 2.0, 8), 8)
    y = lfilter(B, A, u) + 0.3  # a linear plant and an offset: every candidate is tried
    path = _write(tmp_path / "d.csv", u, y + rng.uniform(-0.01, 0.01, u.size))
    rc = main(["diagnose", str(path), "--num", "0 2.15 -1.09", "--den", "1 -0.76 0.82",
               "--output-bound", "0.01", "--candidates", "all", "--max-effects", "1"])
    out = capsys.readouterr().out
    assert rc == 0 and "Missing effect: offset" in out
    assert "candidates='all'" not in out and "refit='linear'" not in out


def test_no_output_envelope_when_the_backlash_is_not_bounded():
    """It said "X contains NaN or infinity (first at sample 0)" about a finite input."""
    idf, _ = _b_at_box_fit()
    assert not np.all(np.isfinite(idf.gamma_bounds_))
    with pytest.raises(UnboundedSetError, match="no output envelope: the record does not"):
        idf.output_envelope(np.ones(20), np.zeros(20))


def test_no_inverse_from_a_set_too_wide_says_why():
    """A given gamma_box left as it is (the fit stopped at once): the default command
    range shrank to (0, 0) and the error named v_range, which the user never passed."""
    u, y, _ = one_record(80, 0.05, "uniform", 0)
    lin = hb.LinearEIVSetEstimator(output_bound=0.05, na=2, nb=2, method="lp",
                                   total_time_limit=1e-3)
    box = [[0.5, 2.0], [0.0, 0.5], [0.5, 2.0], [0.0, 0.5]]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idf = hb.HammersteinBacklashIdentifier(linear=lin, procedure="one-record",
                                               gamma_box=box).fit(u, y)
    assert np.all(idf.gamma_bounds_ == np.array(box))
    with pytest.raises(IllPosedBacklashError, match="too wide for a guaranteed inverse"):
        idf.inverse()
