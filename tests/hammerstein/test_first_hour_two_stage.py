"""What a new user of the two-stage path, the model set and the discrepancy workflow met
first (a new-user trial with its own simulator): a silent change of procedure, a flag
misnamed, an assumption missing, a sampler hint that did not apply, verdicts that did
not say what to try next."""

from __future__ import annotations

import warnings

import control
import numpy as np
import pytest
from oracles import play as _play  # the tests' own play operator
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.exceptions import DataWarning, ParameterValidationError, SolverError
from hammerbound.hammerstein.setup import choose_procedure


def _identifier(**kw):
    return hb.HammersteinBacklashIdentifier(hb.BacklashSetEstimator(0.05),
                                            hb.LinearEIVSetEstimator(output_bound=0.05,
                                                                     method="lp"), **kw)


def test_steady_state_data_with_a_record_that_is_no_prbs_says_which_procedure_runs():
    u = np.where(np.sin(0.7 * np.arange(40)) >= 0, 1.0, -1.0)
    u[5] = 0.0  # one sample off the PRBS levels
    steady = (np.array([1.0, 2.0, -1.0, -2.0]), np.array([0.2, 0.4, -0.2, -0.4]))
    with pytest.warns(DataWarning, match=r"u\[5\] = 0.*one ordinary record") as caught:
        assert choose_procedure(_identifier(), u, steady) == "one-record"
    assert "procedure='one-record'" in str(caught[0].message)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # said explicitly: no warning; a PRBS: none either
        assert choose_procedure(_identifier(procedure="one-record"), u, steady) == "one-record"
        assert choose_procedure(_identifier(), np.sign(u + 0.5), steady) == "two-stage"


def test_a_negative_steady_output_bound_names_its_own_flag(capsys):
    from hammerbound.app.cli.main import main

    rc = main(["identify", "--steady", "s.csv", "--prbs", "p.csv", "--output-bound", "0.02",
               "--steady-output-bound", "-1"])
    err = capsys.readouterr().err
    assert rc == 2 and "--steady-output-bound must be a number > 0" in err


@pytest.fixture(scope="module")
def two_stage():
    ex = hb.chapter_example(0.05, N=60, random_state=0)
    idf = _identifier().fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    return ex, idf


def test_the_two_stage_summary_names_the_a_priori_box_of_the_linear_block(two_stage):
    _, idf = two_stage
    assert "|a_i| <= binom(na, i)" in idf.summary()
    assert any("|b_j| <= 1e4" in a for a in idf.assumptions_)


def test_identifier_samples_take_seeds(two_stage):
    ex, idf = two_stage
    _, lin = idf.sample(3, random_state=0, seeds=[ex.theta_true])
    assert lin.theta.shape == (3, 4)


def test_the_sampler_hint_says_what_was_searched(monkeypatch, two_stage):
    from hammerbound.modelset import sampling

    _, idf = two_stage
    monkeypatch.setattr(sampling, "_seek", lambda *a, **k: [])
    monkeypatch.setattr(sampling._Verifier, "__call__", lambda self, theta: None)
    with pytest.raises(SolverError, match="the centre of the intervals, the fit's witnesses")\
            as err:
        idf.linear_.sample(2, random_state=0)
    assert "seeds are all outside" not in str(err.value)
    assert "sample(n, seeds=[theta])" in str(err.value)


def test_one_record_samples_refuse_seeds():
    u = np.repeat([0.5, -1.5, 1.0, -1.0, 1.5, -0.5], 5)
    y = lfilter([0.0, 0.5], [1.0, -0.5], _play(u, 0.25, 0.06, 0.26, 0.05))
    lin = hb.LinearEIVSetEstimator(output_bound=0.01, na=1, nb=1, nk=1, method="lp")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idf = hb.HammersteinBacklashIdentifier(linear=lin).fit(
            u, y + 0.01 * np.sign(np.sin(np.arange(u.size))))
    with pytest.raises(ParameterValidationError, match="two-stage"):
        idf.sample(2, seeds=[[-0.5, 0.5]])


def test_a_verdict_without_an_explanation_names_the_candidates_not_tried():
    """An asymmetric backlash against a linear model: the default candidates do not explain
    it, and the verdict says which registered ones were not tried (found: it only said
    the effect may not be in the library, though asym_backlash is)."""
    from hammerbound.discrepancy import diagnose

    rng = np.random.default_rng(5)
    u = np.repeat(rng.uniform(-1.1, 1.1, 50), 8)
    y = lfilter([0.0, 0.1, 0.1], [1.0, -1.1, 0.3], _play(u, 0.3, 0.05, 0.32, 0.04))
    y = y + rng.uniform(-0.02, 0.02, u.size)
    G = control.tf([0.0, 0.1, 0.1], [1.0, -1.1, 0.3], True)
    rep = diagnose(G, u, y, output_bound=0.02)
    assert rep.effect is None  # the default candidates do not explain it
    assert "Not tried:" in rep.message and "asym_backlash" in rep.message
    assert "candidates='all'" in rep.message
    found = diagnose(G, u, y, output_bound=0.02, candidates=["backlash", "asym_backlash"])
    assert found.effect is not None and "asym_backlash" in str(found.effect)
