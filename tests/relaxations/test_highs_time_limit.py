"""Every HiGHS solve of the package stops at its run limit or its caller's deadline
(``hammerbound.solvers.highs_process.limit_run``), and a stopped solve never yields a bound or a
witness it cannot stand behind.

Seen before the fix: a stage-2 screening LP (the witness search of ``consistency``, 3 s
budget) ran for 14 min, because HiGHS's ``time_limit`` was never set on that instance.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
import scipy.sparse as sp
from oracles import chapter_eiv_data

from hammerbound.relaxations.problem import EIVProblem
from hammerbound.relaxations.witness import WitnessLP, seek_feasible
from hammerbound.solvers.highs import HighsLP
from hammerbound.solvers.highs_process import RUN_TIME_LIMIT, limit_run, new_highs


def _lp(n=1500, seed=0):
    """A random feasible, bounded LP min c'z, A z <= b, 0 <= z <= 1 (own data)."""
    rng = np.random.default_rng(seed)
    A = sp.random(n, n, density=8.0 / n, random_state=rng, format="csc") + sp.eye(n)
    z0 = rng.uniform(0.2, 0.8, n)
    b = A @ z0 + rng.uniform(0.0, 0.1, n)
    c = -rng.uniform(0.5, 1.5, n)
    return A, np.full(n, -np.inf), b, np.zeros(n), np.ones(n), c


def test_limit_is_per_run_not_the_sum_of_all_runs():
    """HiGHS's time_limit counts all runs of an instance: a plain limit would stop every
    run once the sum passed it. limit_run sets it per run."""
    A, rl, ru, lb, ub, c = _lp(300)  # ~0.02 s a run; 10x that on a loaded machine
    lp = HighsLP(A, rl, ru, lb, ub, c, run_limit=1.0)
    first = lp.solve()
    assert first.status == "optimal"
    runs = 0
    while lp.h.getRunTime() < 2.5 or runs < 3:  # the sum well past one run's limit
        lp.h.clearSolver()  # from scratch: every run does the full work again
        res = lp.solve()
        assert res.status == "optimal", f"run {runs} stopped at {lp.h.getRunTime():.2f} s"
        assert res.bound == pytest.approx(first.bound, rel=1e-9, abs=1e-9)
        runs += 1
        assert runs < 2000, "the LP is too small to accumulate run time"


def test_a_solve_past_its_deadline_stops_with_an_outer_bound():
    A, rl, ru, lb, ub, c = _lp()
    full = HighsLP(A, rl, ru, lb, ub, c).solve()
    assert full.status == "optimal"
    cut = HighsLP(A, rl, ru, lb, ub, c, deadline=time.time() - 1.0).solve()
    assert cut.status == "failed" and cut.x is None
    assert cut.bound <= full.bound + 1e-9 * max(1.0, abs(full.bound))
    lp = HighsLP(A, rl, ru, lb, ub, c, deadline=time.time() - 1.0)
    assert lp.solve().status == "failed"
    lp.deadline = None  # an attribute: the next solve runs to the end
    assert lp.solve().bound == pytest.approx(full.bound, rel=1e-9, abs=1e-9)


def test_limit_run_caps_and_never_disables_the_limit():
    h = new_highs()
    assert limit_run(h) == RUN_TIME_LIMIT
    assert limit_run(h, seconds=10 * RUN_TIME_LIMIT) == RUN_TIME_LIMIT
    assert 0.0 < limit_run(h, seconds=2.0, deadline=time.time() + 1.0) <= 1.0
    assert limit_run(h, deadline=time.time() - 5.0) > 0.0  # never 0 or negative
    assert h.getOptionValue("time_limit")[1] < 1e3  # never "no limit"


def test_highs_lp_refuses_a_bare_time_limit_option():
    A, rl, ru, lb, ub, c = _lp(20)
    with pytest.raises(ValueError, match="run_limit"):
        HighsLP(A, rl, ru, lb, ub, c, options={"time_limit": 5.0})


def _long_problem():
    data, theta = chapter_eiv_data(N=4000, deta=0.05, seed=3)
    return EIVProblem(**data), theta


def test_a_screening_lp_past_its_deadline_screens_nothing():
    pr, theta = _long_problem()
    assert WitnessLP(pr).screens(theta)  # the truth, solved to the end
    lp = WitnessLP(pr)
    lp.deadline = time.time() - 1.0
    assert lp.violation(theta) == np.inf and not lp.screens(theta)
    lp.deadline = None  # the stopped solve was not remembered as an answer
    assert lp.screens(theta)


def test_seek_feasible_gives_its_deadline_to_the_screen_and_restores_it():
    pr, theta = _long_problem()
    lp = WitnessLP(pr)
    seen = []
    real = WitnessLP.violation

    def spy(self, th):
        seen.append(self.deadline)
        return real(self, th)

    WitnessLP.violation = spy
    try:
        stop = time.time() + 30.0
        hit = seek_feasible(pr, lp, lambda th: th, [theta], pr.theta_box, deadline=stop)
    finally:
        WitnessLP.violation = real
    assert hit is not None and seen and all(d == stop for d in seen)
    assert lp.deadline is None


def _stop_every_run(h, seconds=None, deadline=None):
    """A limit_run that stops every HiGHS run at once (a stand-in for a slow LP)."""
    h.setOptionValue("time_limit", h.getRunTime() + 1e-12)
    return 0.0


def test_lp_bounds_with_stopped_lps_say_limit_never_unbounded(monkeypatch):
    from hammerbound.exceptions import SolverError, UnboundedSetError
    from hammerbound.relaxations.lp import lp_bounds
    from hammerbound.solvers import highs

    data, theta = chapter_eiv_data(N=300, deta=0.05, seed=3)
    pr = EIVProblem(**data)
    full = lp_bounds(pr, check_box=False)
    monkeypatch.setattr(highs, "limit_run", _stop_every_run)
    cut = lp_bounds(pr, check_box=False)
    assert np.all(cut.bounds[:, 0] <= full.bounds[:, 0] + 1e-12)  # outer, never tighter
    assert np.all(cut.bounds[:, 1] >= full.bounds[:, 1] - 1e-12)
    assert {s for pair in cut.status for s in pair} == {"limit"}
    assert all(i.status == "limit" and "before optimality" in i.message for i in cut.infos)
    with pytest.raises(SolverError, match="before optimality") as err:
        lp_bounds(pr, check_box=True)  # the data are not blamed for the box
    assert not isinstance(err.value, UnboundedSetError)


def test_one_record_names_stopped_lps_not_the_record(monkeypatch):
    """A record that bounds the backlash, with every relaxation LP stopped: the warning
    names the stopped LPs, and the bounds stay outer."""
    import warnings

    from oracles import one_record

    import hammerbound as hb
    from hammerbound.exceptions import NotIdentifiedWarning
    from hammerbound.solvers import highs

    u, y, _ = one_record(60, 0.02, "uniform", 4)
    lin = hb.LinearEIVSetEstimator(output_bound=0.02, na=2, nb=2, nk=1, method="lp")
    monkeypatch.setattr(highs, "limit_run", _stop_every_run)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        idf = hb.HammersteinBacklashIdentifier(linear=lin, procedure="one-record").fit(u, y)
    text = " ".join(str(w.message) for w in caught if w.category is NotIdentifiedWarning)
    assert "ended before optimality" in text and "never move back" not in text
    assert np.all(np.isinf(idf.gamma_bounds_[:, 1]))  # nothing certified: not identified
