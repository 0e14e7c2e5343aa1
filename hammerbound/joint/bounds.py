"""Guaranteed intervals of every parameter from one ordinary record (the public entry).

:func:`record_bounds` runs the whole method on a :class:`~.problem.RecordProblem`:

1. OBBT over parts of the a priori box (:func:`.tighten.outer_leaves`): certified bounds
   on every parameter from the LP relaxation alone (``method="lp"`` stops here);
2. verified points from the last OBBT round's LP points (:func:`.local.restore`);
3. branch-and-bound per interval end (:func:`.search.search_end`), the ends in parallel
   with joblib (``n_jobs``).

The result is an :class:`~hammerbound.relaxations.IntervalResult` over
``[theta, m_l, c_l, m_r, c_r]`` whose every :class:`~hammerbound.relaxations.BoundInfo`
carries the end's status, its verified witness (``point``: the
:class:`~.problem.Witness`) and the gap between them; the result's ``root_box`` is the OBBT
box of every variable and ``pool`` the verified points found on the way.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from ..relaxations.exact.limits import end_share
from ..relaxations.result import BoundInfo, IntervalResult
from ..solvers.highs_process import past
from ..status import BOX, INACCURATE, LIMIT, RELAXATION
from .local import restore
from .problem import RecordProblem
from .progress import RecordProgress
from .search import search_end
from .tighten import map_jobs, outer_leaves, pool_size
from .units import RecordUnits

__all__ = ["RecordDetails", "record_bounds"]


@dataclass(frozen=True)
class RecordDetails:
    """What the one-record search did: the number of leaf boxes after OBBT, whether the
    time limit stopped it, and how many relaxation LPs ended before optimality (their own
    time limit); with either, ends may sit at the a priori box for that reason."""

    leaves: int
    stopped_by_time: bool
    lps_stopped: int = 0
    #: leaves the deadline cut short, and the mean seconds of those tightened in time
    leaves_cut: int = 0
    leaf_seconds: float = 0.0


def _pool(problem, points, limit=8, deadline=None):
    """Verified points from the last ``limit`` LP points of OBBT (restored to the set;
    at N = 300 on the chapter's record 24 points cost 11 s; 8 gave the same nodes and widths)."""
    out = []
    for x in points[-limit:]:
        if past(deadline):
            break
        w = restore(problem, x, max_iter=12, deadline=deadline)
        if w is not None:
            out.append(w)
    return out


def _best_start(pool, k, sense):
    return min(pool, key=lambda w: sense * w.vector[k]) if pool else None


def _end_job(problem, box, k, sense, start, kw, order=None):
    """One end's search; ``order = (i, ends, workers)`` gives it its share of the time
    left before ``kw["deadline"]`` (:func:`end_share`)."""
    if order is not None and kw.get("deadline") is not None:
        share = end_share(kw["deadline"], *order)
        limit = kw.get("time_limit")
        kw = {**kw, "time_limit": share if limit is None else min(limit, share)}
    return search_end(problem, box, k, sense, start, **kw)


def _not_searched(box, k, sense):
    """The result of an end left at its OBBT bound (see ``skip``)."""
    from .search import EndResult

    return EndResult(sense * (box[k, 0] if sense > 0 else box[k, 1]), np.inf, None, 0, 0.0,
                     "limit")


def _info(name, sense, res, bound):
    w = res.witness
    value = sense * res.value if w is not None else float("nan")
    return BoundInfo(name, "min" if sense > 0 else "max", float(bound),
                     solver_value=value, status=res.status, certified=True,
                     time=res.seconds, gap=None if w is None else abs(value - bound),
                     witness=None if w is None else w.vector, nodes=res.nodes, point=w)


def _lp_infos(names, box, stopped, lps_stopped=0):
    """The relaxation's ends: status LIMIT when the fit's deadline stopped the tightening,
    INACCURATE when only some of its LPs ended before optimality (their own time limit, or
    HiGHS could not solve them; their bounds come from their duals), RELAXATION
    otherwise. (Failed LPs were reported as "at time/node limit" in a fit that ended long
    before its limit, review.)"""
    st = LIMIT if stopped else INACCURATE if lps_stopped else RELAXATION
    return tuple(BoundInfo(n, s, float(box[i, j]), status=st, certified=True)
                 for i, n in enumerate(names) for j, s in ((0, "min"), (1, "max")))


def _at_prior(infos, prior):
    """Ends that sit at the a priori box get status BOX (guaranteed under that box, not by
    the record), unless a time limit stopped them (LIMIT says more)."""
    out = []
    for i, info in enumerate(infos):
        k, e = divmod(i, 2)
        at = info.bound == prior[k, e]
        out.append(replace(info, status=BOX) if at and info.status != LIMIT else info)
    return tuple(out)


def _end_outcome(label, result, deadline) -> str:
    """What an interval end's progress line says (an end the deadline left without a node
    was not searched: trial 11 read "status limit, 0 nodes" after the deadline as work)."""
    if result.nodes == 0 and result.status == "limit" and past(deadline):
        return f"{label}: not searched, time limit reached (the tightened box's bound)"
    return f"{label}, status {result.status}, {result.nodes} nodes"


def record_bounds(problem: RecordProblem, *, method="exact", tol=1e-4, max_nodes=2000,
                  time_limit=None, deadline=None, n_jobs=1, skip=None,
                  progress=False) -> IntervalResult:
    """Certified intervals of ``[theta, m_l, c_l, m_r, c_r]`` over the one-record set.

    Parameters
    ----------
    problem : RecordProblem
    method : {"exact", "lp"}
        ``"lp"``: the OBBT box of the relaxation (certified, not tight); ``"exact"``:
        branch-and-bound to ``tol``.
    tol : float
        An end stops when ``value - bound <= tol * max(1, |value|)`` in the units the search
        runs in (:mod:`.units`: input and output scaled to order one by powers of two, so
        the units of the record do not matter; ``m_l, m_r`` in units of the record's
        ``max |y| / max |u|`` scale as powers of two, ``c_l, c_r`` of its ``max |u|``).
    max_nodes, time_limit : per interval end; ``deadline``: absolute :func:`time.time`.
    n_jobs : int
        Interval ends searched in parallel (joblib).
    skip : callable or None
        ``skip(k, sense, bound) -> bool``: an end whose OBBT bound makes the search
        pointless (e.g. it is at an assumed a priori limit, so it will be reported as not
        identified) keeps that certified bound, status "limit", without a search.
    progress : bool
        Lines (or bars on a terminal) on stderr: the partition, the leaves, the interval
        ends (:mod:`.progress`).

    Raises
    ------
    EmptyFeasibleSetError
        The relaxation is certified infeasible: nothing explains the record.
    """
    units = RecordUnits.of(problem)
    if skip is not None and not units.identity:
        skip = _skip_in(skip, units.factors(problem.p))
    res = _record_bounds(units.problem(problem), method=method, tol=tol, max_nodes=max_nodes,
                         time_limit=time_limit, deadline=deadline, n_jobs=n_jobs, skip=skip,
                         progress=progress)
    return res if units.identity else _result_back(res, units, problem.p)


def _skip_in(skip, factors):
    """``skip`` (of bounds in the data's units) for bounds in the search's units."""
    return lambda k, sense, bound: skip(k, sense, bound / factors[k])


def _result_back(res: IntervalResult, units: RecordUnits, p: int) -> IntervalResult:
    """A result of the search (in ``units``) in the data's units: every bound, value,
    gap, witness and pool point divided by its row's factor (exact powers of two)."""
    f = units.factors(p)
    infos = []
    for i, info in enumerate(res.infos):
        k = i // 2
        infos.append(replace(
            info, bound=info.bound / f[k], solver_value=info.solver_value / f[k],
            gap=None if info.gap is None else info.gap / f[k],
            witness=None if info.witness is None else units.back(info.witness, p),
            point=units.witness_back(info.point, p)))
    pool = None if res.pool is None else tuple(units.witness_back(w, p) for w in res.pool)
    return replace(res, bounds=units.back(res.bounds, p), infos=tuple(infos),
                   root_box=units.back(res.root_box, p), pool=pool)


def _record_bounds(problem: RecordProblem, *, method, tol, max_nodes, time_limit, deadline,
                   n_jobs, skip, progress) -> IntervalResult:
    """:func:`record_bounds` on a problem in the units it is searched in."""
    t0 = time.perf_counter()
    points = []
    stops = []
    bar = RecordProgress(progress)
    pace = [0, 0.0]  # leaves cut by the deadline, mean seconds of the others

    def on_pace(cut, seconds):
        pace[:] = [cut, seconds]

    leaves = outer_leaves(problem, deadline=deadline, on_point=points.append, n_jobs=n_jobs,
                          on_stop=stops.append, progress=bar, on_pace=on_pace)
    lps_stopped = sum(stops)
    if lps_stopped:
        skip = None  # an OBBT bound at a limit may be the stopped LPs', not the record's
    box = np.column_stack([np.min([b[:, 0] for b in leaves], axis=0),
                           np.max([b[:, 1] for b in leaves], axis=0)])
    names = problem.names[: problem.p + 4]
    if method == "lp":
        infos = _lp_infos(names, box, past(deadline), lps_stopped)
        return IntervalResult(tuple(names), box[: problem.p + 4].copy(),
                              infos=_at_prior(infos, problem.box),
                              method="lp",
                              time=time.perf_counter() - t0, root_box=box,
                              details=RecordDetails(len(leaves), past(deadline),
                                                    lps_stopped, *pace))
    pool = _pool(problem, points, deadline=deadline)
    jobs = [(k, s) for k in range(problem.p + 4) for s in (1.0, -1.0)]
    kw = {"tol": tol, "max_nodes": max_nodes, "time_limit": time_limit, "deadline": deadline}
    skipped = {(k, s) for k, s in jobs
               if skip is not None and skip(k, s, box[k, 0] if s > 0 else box[k, 1])}
    todo = [(k, s) for k, s in jobs if (k, s) not in skipped]
    procs = pool_size(n_jobs, len(todo), deadline)  # as map_jobs will run them
    args = [(problem, leaves, k, s, _best_start(pool, k, s), kw, (i, len(todo), procs))
            for i, (k, s) in enumerate(todo)]
    bar.start("interval end", len(args))
    labels = iter(f"{names[k]} {'min' if s > 0 else 'max'}" for k, s in todo)
    found = iter(map_jobs(_end_job, args, n_jobs, deadline=deadline, each=lambda r: bar.done(
        _end_outcome(next(labels), r, deadline))))
    bar.close()
    results = [_not_searched(box, k, s) if (k, s) in skipped else next(found)
               for k, s in jobs]
    bounds = box[: problem.p + 4].copy()
    infos = []
    for (k, s), res in zip(jobs, results, strict=True):
        b = s * res.bound
        if s > 0:
            bounds[k, 0] = max(bounds[k, 0], b)
        else:
            bounds[k, 1] = min(bounds[k, 1], b)
        infos.append(_info(names[k], s, res, bounds[k, 0 if s > 0 else 1]))
    return IntervalResult(tuple(names), bounds, infos=_at_prior(infos, problem.box),
                          method="exact",
                          time=time.perf_counter() - t0, root_box=box, pool=tuple(pool),
                          details=RecordDetails(len(leaves), past(deadline), lps_stopped,
                                                *pace))

