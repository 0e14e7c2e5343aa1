"""An LP of the one-record search stopped by a deadline keeps a certified bound, never a
wrong one (hammerbound.joint.tighten._tighten_one with a deadline)."""

from __future__ import annotations

import time

import numpy as np
import pytest
from oracles import one_record

from hammerbound.joint import RecordProblem, default_gamma_box, record_box
from hammerbound.joint.relaxation import LP_TIME_LIMIT, build_relaxation
from hammerbound.joint.tighten import _tighten_one


def _problem(N=400, deta=0.05, seed=0):
    u, y, _ = one_record(N, deta, "bound", seed)
    return RecordProblem(u, y, deta, 2, 2, 1, record_box(2, 2, u, default_gamma_box(u, y, deta)))


def test_every_relaxation_lp_carries_the_cap_and_the_deadline():
    pr = _problem(N=60)
    stop = time.time() + 100.0
    lp = build_relaxation(pr, pr.box, deadline=stop).lp
    assert lp.run_limit == LP_TIME_LIMIT and lp.deadline == stop
    assert build_relaxation(pr, pr.box).lp.deadline is None


def test_an_lp_stopped_by_the_deadline_keeps_an_outer_bound():
    pr = _problem()
    box = pr.box.copy()
    stopped = 0
    for k in (0, 1, pr.p + 1, pr.p + 3):
        full = _tighten_one(pr, box, k)[0]
        cut = _tighten_one(pr, box, k, deadline=time.time() + 1e-4)[0]
        assert cut is not None and full is not None
        # stopped early: never tighter than the LP solved to the end (rounding aside)
        tol = 1e-9 * max(1.0, float(np.max(np.abs(full))))
        assert cut[0] <= full[0] + tol and cut[1] >= full[1] - tol
        assert box[k, 0] <= cut[0] and cut[1] <= box[k, 1]
        stopped += bool(cut[1] - cut[0] > full[1] - full[0] + tol)
    assert stopped  # the deadline did stop LPs


def _fit(u, y, **kw):
    import warnings

    import hammerbound as hb

    lin = hb.LinearEIVSetEstimator(output_bound=0.02, na=2, nb=2, nk=1, method="lp", **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return hb.HammersteinBacklashIdentifier(linear=lin, procedure="one-record").fit(u, y)


def test_a_fit_stopped_by_its_time_limit_says_limit_not_relaxation():
    u, y, _ = one_record(60, 0.02, "uniform", 4)
    idf = _fit(u, y, total_time_limit=0.3)
    statuses = {s for pair in idf.intervals_.status for s in pair}
    assert statuses <= {"limit", "not identified"} and "limit" in statuses


@pytest.mark.deep
def test_ends_at_the_a_priori_box_say_box():
    """An end the relaxation leaves at the a priori box is the box's, not the record's.
    Deep: 36-43 s, the slowest test of the quick tier (which ran 369 s, over its 5 min)."""
    from hammerbound.joint.bounds import record_bounds

    u, y, _ = one_record(60, 0.02, "uniform", 4)
    pr = RecordProblem(u, y, 0.02, 2, 2, 1, record_box(2, 2, u, default_gamma_box(u, y, 0.02)))
    res = record_bounds(pr, method="lp")
    prior = pr.box[: pr.p + 4]
    at = res.bounds == prior
    assert at.any()  # c_l, c_r >= 0 or an assumed upper limit: some end stays there
    for i, info in enumerate(res.infos):
        k, e = divmod(i, 2)
        assert (info.status == "box") == bool(at[k, e]), (info.param, info.sense)


def test_restore_and_walk_stop_at_the_deadline(monkeypatch):
    """The starting pool's and the incumbents' local steps honour the deadline: past it
    they solve no LP (they overran total_time_limit by minutes before)."""
    from oracles import GAMMA_TRUE, THETA_TRUE

    from hammerbound.joint import local
    from hammerbound.joint.problem import verify_point

    u, y, x = one_record(60, 0.05, "bound", 0)
    pr = RecordProblem(u, y, 0.05, 2, 2, 1, record_box(2, 2, u, default_gamma_box(u, y, 0.05)))
    truth = verify_point(pr, np.concatenate([THETA_TRUE, GAMMA_TRUE, [x[0]]]))
    assert truth is not None  # the truth explains its own record
    calls = []
    real = local.linprog

    def counting(*a, **kw):
        calls.append(kw.get("options"))
        return real(*a, **kw)

    monkeypatch.setattr(local, "linprog", counting)
    v = pr.box.mean(axis=1)
    assert local.restore(pr, v, deadline=time.time() - 1.0) is None
    assert local.walk(pr, truth, 0, 1.0, deadline=time.time() - 1.0) is truth
    assert calls == []
    local.walk(pr, truth, 0, 1.0, max_iter=2, deadline=time.time() + 1e3)
    assert calls and all(0 < o["time_limit"] <= local.STEP_LP_LIMIT for o in calls)


def test_end_share_gives_what_is_left_to_the_rounds_still_to_run():
    from hammerbound.relaxations.exact.limits import end_share

    assert end_share(100.0, 0, 16, 2, now=40.0) == 60.0 / 8  # 8 rounds of 2 ends
    assert end_share(100.0, 15, 16, 2, now=40.0) == 60.0  # the last end: all that is left
    assert end_share(100.0, 14, 16, 2, now=40.0) == 60.0  # the last round has two ends
    assert end_share(100.0, 0, 16, 1, now=40.0) == 60.0 / 16
    assert end_share(100.0, 3, 16, 2, now=120.0) == 0.0  # past the deadline


def test_workers_are_the_processes_map_jobs_runs_on():
    from joblib import effective_n_jobs

    from hammerbound.joint.tighten import workers

    assert workers(1, 16) == 1 and workers(4, 1) == 1
    assert workers(4, 3) == min(effective_n_jobs(4), 3)
    assert workers(-1, 16) == min(effective_n_jobs(-1), 16)
    assert workers(2, 16) == 2


@pytest.mark.deep  # 11 s (quick tier budget)
def test_every_end_gets_a_share_of_the_deadline(monkeypatch):
    """With a fit deadline, each interval end's search is limited to its share of the
    time left (before, the first ends took it all and the rest were never searched)."""
    from hammerbound.joint import bounds

    u, y, _ = one_record(60, 0.05, "uniform", 1)
    pr = RecordProblem(u, y, 0.05, 2, 2, 1, record_box(2, 2, u, default_gamma_box(u, y, 0.05)))
    seen = []
    real = bounds.search_end

    def recording(problem, leaves, k, sense, start=None, **kw):
        seen.append((time.time(), kw["time_limit"]))
        return real(problem, leaves, k, sense, start, **{**kw, "max_nodes": 1})

    monkeypatch.setattr(bounds, "search_end", recording)
    deadline = time.time() + 600.0
    bounds.record_bounds(pr, method="exact", deadline=deadline, n_jobs=1)
    assert len(seen) == 2 * (pr.p + 4)  # no skip: every end is searched
    for i, (t, limit) in enumerate(seen):
        share = (deadline - t) / (len(seen) - i)
        assert 0.0 < limit <= share + 1.0, (i, limit, share)


def test_lp_ends_whose_lps_failed_are_not_said_to_be_at_a_time_limit():
    """Review: some relaxation LPs ended "unknown" in a fit that finished in 30 s of its
    120 s, and every end read "at time/node limit". Only the fit's deadline gives LIMIT;
    LPs that ended before optimality on their own give INACCURATE (bounds from duals)."""
    from hammerbound.joint.bounds import _lp_infos
    from hammerbound.status import INACCURATE, LIMIT, RELAXATION, describe

    box = np.array([[0.0, 1.0], [2.0, 3.0]])
    for stopped, failed, want in ((False, 3, INACCURATE), (True, 3, LIMIT),
                                  (True, 0, LIMIT), (False, 0, RELAXATION)):
        infos = _lp_infos(["a1", "b1"], box, stopped, failed)
        assert {i.status for i in infos} == {want}
    assert "limit" not in describe(INACCURATE)


def test_finite_ends_of_failed_lps_are_named_in_a_warning():
    """Review: ends of status INACCURATE (LPs that ended before optimality on their own)
    had no warning, where status LIMIT had one."""
    import warnings
    from types import SimpleNamespace

    from hammerbound.exceptions import SearchLimitWarning
    from hammerbound.hammerstein.one_record import _warn_inaccurate
    from hammerbound.status import INACCURATE, RELAXATION

    infos = [SimpleNamespace(param="a1", end="lower", status=INACCURATE, bound=-0.6),
             SimpleNamespace(param="ml", end="upper", status=INACCURATE, bound=np.inf),
             SimpleNamespace(param="b1", end="lower", status=RELAXATION, bound=0.3)]
    with pytest.warns(SearchLimitWarning, match=r"3 relaxation LP\(s\) .*bounds of a1 lower "
                                                r"are certified"):
        _warn_inaccurate(infos, 3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _warn_inaccurate(infos[1:], 3)
