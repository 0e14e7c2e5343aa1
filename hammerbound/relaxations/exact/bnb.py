"""Tight parameter uncertainty intervals (22.36)-(22.37) by spatial branch-and-bound.

For every parameter ``theta_k`` and both senses the exact extreme value over the EIV set
(22.34) is bracketed by

* a **guaranteed outer bound**: the minimum, over the open leaves of a branch-and-bound
  tree on the theta box, of the McCormick LP relaxation (:mod:`.mccormick`), each made
  rigorous by a dual bound (:mod:`._highs`); the tree starts from the polytopic LP box
  (:func:`.lp.lp_bounds`) shrunk by optimality-based bound tightening (OBBT);
* an **inner value**: ``theta_k`` at the best point verified feasible by
  :func:`.problem.check_theta` (with its witness ``eta``, ``dx``).

The difference is the certified gap. The search stops when the gap is below
``tol * max(1, |value|)`` in the units it searches in (:mod:`..units`: for a ``b_j``,
``tol * max(G, |value|)`` with ``G`` the power of two nearest the largest ``|b_j|`` of the
LP bounds, 1 when that lies in ``[1/8, 8]``, from the input's magnitude when such a
bound sits at the a priori box); node and time limits return the
still-valid outer bound with status ``"limit"``.

This module runs the LP, OBBT (:mod:`.obbt`) and the first verified points, then one
search per interval end (:mod:`.search`, serially or on joblib workers), and assembles the
result. Every part of the search listed below that can be switched off (to measure what
it buys) is a :class:`.search.SearchOptions` field, passed as ``options``.

What keeps the tree small and the nodes cheap (N = 300, Delta eta = 0.3, two-level inner
signal: 2297 -> 1768 nodes and 60 s -> 14 s for the 8 bounds on 2 cores; independent
errors 15 s -> 8 s; ``python -m benchmarks.exact_idle``, notes in ``docs/benchmarks.md``):

* every end starts from a **near-optimal incumbent**: an SLP local search
  (:func:`.local.improve`) walks the best verified point down ``sense * theta_k`` before
  the tree starts, so the tree only has to prove the bound; the tree's own searches
  (screening node LP points, line searches towards them) then start backed off and back
  off further (without a cap) while they do not improve the incumbent by more than their
  resolution; one that does find a better point (another basin) walks it down as well
  (not on a working set of equations: there one SLP LP over all equations costs more
  than the walk saves);
* when no relaxation point is feasible -- noise exactly at its bound on every sample can
  leave a single point -- Gauss-Newton steps from the OBBT points (:func:`.local.restore`)
  find the verified point the tree's points never get close enough to;
* every node box is **capped at the incumbent** (``sense * theta_k <= value``): nothing
  above it can hold the minimum, and the cap tightens every envelope involving theta_k;
* **reduced-cost bound tightening** removes the part of a node box whose rigorous LP bound
  already exceeds the incumbent (:func:`.node_box._reduced_cost_tightening`);
* every child node starts from its parent's simplex basis (a snapshot kept with the
  node; one bound away), not from whatever node was solved last: 3.5x fewer simplex
  iterations on the chapter's two-level data (``python -m benchmarks.exact_ablation``);
* in a serial run the ends share one node LP model (:class:`.search.Workspace`; each end
  resets box, cost, cut-off and basis) and the OBBT bases stay in-process snapshots (no
  element-by-element conversion): 7 % less CPU time at Delta eta = 0.005, N = 300;
* node LPs stop at a cut-off half the tolerance below the incumbent; a cut-off node whose
  certified bound still does not close it is solved to the end (a point to branch at)
  rather than split blindly;
* on the two-level inner signal (few input-error variables shared by many samples,
  :func:`.mccormick.shared_groups`) the searches for the ends of the ``b_j`` also branch on
  those shared variables: the ``b`` interval is set by the unknown levels (``b`` scales with
  one over their difference), and a narrower level box tightens every ``b_j dx`` envelope
  at once. The ``a_i`` ends, insensitive to the levels, branch on theta only. Measured a
  wash (``python -m benchmarks.exact_ablation``: fewer nodes at Delta eta = 0.15 and 0.2,
  3 % more at 0.3);
* node LPs use devex dual pricing and, for well-scaled data, no scaling
  (:func:`.mccormick._node_options`);
* when no relaxation point is feasible (thin sets), a Nelder-Mead search on the screening
  violation supplies the first verified point (:meth:`.points._Pool.seek`);
* on long records (from :data:`.working_set.AUTO_MIN_EQUATIONS` equations, independent
  input errors), the OBBT and node LPs hold a growing **working set** of equations
  (:mod:`.working_set`): a relaxation of the full LP, so every bound stays certified over
  all equations (N = 3000: 5.3x faster in ``python -m benchmarks.exact_scaling``).
"""

from __future__ import annotations

import time
import warnings
from functools import partial

import numpy as np
from joblib.externals.loky.process_executor import BrokenProcessPool

from ...exceptions import EmptyFeasibleSetError, SearchLimitWarning
from ...solvers.highs_process import past
from ..lp import end_statuses, lp_bounds, raise_if_box_limited
from ..problem import EIVProblem
from ..result import BoundInfo, ExactDetails, IntervalResult, VerifiedPoint
from ..units import Units
from .isolation import SolverCrashError, crash_prone, run_isolated, why
from .limits import check_limits
from .local import polish, restore
from .mccormick import shared_groups
from .obbt import _obbt
from .points import _on_gain_plane, _Pool, seek_a
from .search import EndResult, SearchOptions, Workspace, _not_searched, search_end
from .working_set import AUTO_MIN_EQUATIONS, initial_equations

__all__ = ["SearchOptions", "exact_bounds"]


def _perf_deadline(deadline):
    """A :func:`time.time` deadline (or None) as a :func:`time.perf_counter` one."""
    return None if deadline is None else time.perf_counter() + (deadline - time.time())


#: the part of the time left that :func:`.points.seek_a` may take (each of its LPs is one
#: of the full record: 0.2 s at N = 2000, so a search that finds nothing could otherwise
#: take the ends' time)
SEEK_A_SHARE = 0.25


def _share(deadline, part):
    """A :func:`time.time` deadline ``part`` of the way from now to ``deadline`` (None:
    None)."""
    if deadline is None:
        return None
    now = time.time()
    return now + part * max(0.0, deadline - now)


def verified_points(problem, box, roots, thetas, ws=None, deadline=None) -> list:
    """The first verified-feasible points of (22.34) inside the OBBT ``box``: the OBBT LP
    points ``thetas`` (and their mean and the box centre, on the gain plane) that pass
    :func:`.problem.check_theta`; when none does (a thin set), Gauss-Newton steps from the
    OBBT points (a single-point set, e.g. noise exactly at its bound), then (without
    input errors) a Nelder-Mead search over ``a`` alone with ``b`` chosen by an LP
    (:func:`.points.seek_a`), then one on the screening violation. Stops at ``deadline``
    (:func:`time.time`)."""
    p = problem.p

    def time_left():
        return deadline is None or time.time() < deadline

    pool = _Pool(problem, working_set=ws is not None)
    starts = ([np.mean(thetas, axis=0)] if thetas else []) + [box.mean(axis=1)]
    for th in list(thetas) + [_on_gain_plane(problem, th) for th in starts]:
        if not time_left():
            break
        pool.add(th)
    if not pool.points and time_left():
        n, kg = problem.N, problem.n_groups
        xs = [r[1] for r in roots.values() if r[1] is not None][:2]
        restore(pool, [(x[:p], x[p : p + n], x[p + n : p + n + kg]) for x in xs], box,
                stop_at=_perf_deadline(deadline))
    if not pool.points and time_left() and not problem.has_input_errors:
        seek_a(problem, starts[-1], box, pool.verify, deadline=_share(deadline, SEEK_A_SHARE))
    if not pool.points and time_left():
        pool.seek(starts, box, deadline=deadline)
    return pool.points


def exact_bounds(
    problem: EIVProblem,
    tol: float = 1e-4,
    max_nodes: int = 20000,
    time_limit: float = 600.0,
    n_jobs: int = 1,
    progress: bool = False,
    theta_box=None,
    *,
    check_box: bool = True,
    total_time_limit: float | None = None,
    deadline: float | None = None,
    working_set: bool | None = None,
    options: SearchOptions | None = None,
) -> IntervalResult:
    """Tight parameter uncertainty intervals (22.35)-(22.37) with a certificate.

    Every end starts from, and never reports wider than, the polytopic LP bound
    (:func:`.lp.lp_bounds`) shrunk by OBBT: a node or time limit returns the best certified
    outer bound found so far (status ``"limit"``), never a wider or infinite one.

    The search runs on data brought to order one by powers of two (:mod:`..units`: outputs
    and inputs; exact, the set in theta is the same up to a factor of the ``b_j``, mapped
    back exactly), so the answer does not depend on the units of the data. A node LP that
    HiGHS refuses on every attempt (:meth:`._highs.HighsLP.solve`) keeps its parent's certified
    bound, and the end's message says so. Each end's witness is polished a little into the
    set (:func:`.local.polish`).

    Parameters
    ----------
    problem : EIVProblem
        The EIV problem (22.34).
    tol : float, default 1e-4
        Stop an interval end when ``value - bound <= tol * max(1, |value|)`` (absolute for
        small parameters, relative for large ones); for a ``b_j``, ``tol * max(G, |value|)``
        with ``G`` the power of two nearest the largest ``|b_j|`` of the LP bounds (1 when
        that lies in ``[1/8, 8]``; from the input's magnitude when such a bound sits at the
        a priori box), so that the units of the data do not matter.
    max_nodes : int, default 20000
        Node limit per interval end.
    time_limit : float, default 600
        Wall-time limit (s) per interval end.
    n_jobs : int, default 1
        The ``2 p`` interval ends are searched in parallel with joblib. With 1, a long
        output-error record's search still runs in a worker process
        (:mod:`.isolation`: HiGHS can crash the process there). If a joblib worker dies,
        the search runs again as with 1, every step in a worker process.
    progress : bool, default False
        Show a tqdm progress bar per interval end.
    theta_box : array_like, shape (p, 2), optional
        A priori box replacing ``problem.theta_box``.
    check_box : bool, default True
        Raise :class:`UnboundedSetError` when a bound coincides with the a priori box.
    total_time_limit : float or None, default None
        Wall-time budget (s) of the whole call, shared by the ``2 p`` ends and the joblib
        workers: each end searches for at most ``time_limit`` and for its share of the
        time left (:func:`.limits.end_share`: the time left divided by the rounds of ends
        still to run, so that the first ends cannot use up the budget of the others, and
        time an end does not use goes to the ends after it); the LP always runs, OBBT's
        LPs, the search for a first feasible point and the witnesses' polish only while
        time is left (a budget the set-up uses up gives the LP bounds); an end that has no
        time left when it starts reports its LP/OBBT bound with status ``"limit"``.
    deadline : float or None, default None
        The same budget as an absolute :func:`time.time` timestamp (e.g. shared with other
        steps of a fit); with both, the earlier one counts.
    working_set : bool or None, default None
        Solve the OBBT and node LPs on a growing working set of equations
        (:mod:`.working_set`; the bounds stay certified over all equations, the working-set
        LPs relax the full ones). ``None``: from
        :data:`.working_set.AUTO_MIN_EQUATIONS` equations on (long records), unless the
        input errors are shared by groups of samples (the two-level inner signal), where
        the full LPs with the SLP walk are faster.
    options : SearchOptions or None, default None
        Parts of the search to switch off (:class:`.search.SearchOptions`; all on by
        default), e.g. for an ablation study; no option changes a bound beyond ``tol``.

    Returns
    -------
    IntervalResult
        ``method="exact"``; ``bounds`` (p, 2) are guaranteed outer bounds of (22.36) and
        (22.37). Every :class:`BoundInfo` carries ``gap`` (bound to best verified value),
        ``witness`` (verified-feasible theta, shape (p,)), ``point`` (a
        :class:`~hammerbound.relaxations.result.VerifiedPoint`: the witness with its ``eta``
        (N,) and ``dx`` (K,)), ``inner`` (theta_k at the witness), ``nodes``, ``time``. The
        result holds the ``lp`` result, the OBBT ``root_box`` (p, 2), ``inner`` (p, 2), the
        hull of the witnesses, and ``details.working_set``; an end that coincides with
        ``problem.theta_box`` has status ``BOX``.

    Raises
    ------
    ParameterValidationError
        ``tol``, ``max_nodes``, ``time_limit`` or ``total_time_limit`` out of range.
    EmptyFeasibleSetError
        The data are inconsistent (from the LP or from the relaxation at the root).
    UnboundedSetError
        An exact bound coincides with the a priori box.

    Warns
    -----
    SearchLimitWarning
        A worker process of the search died (HiGHS crashed in it): the steps it did not
        finish report their LP or OBBT outer bounds with status ``"limit"``.
    RuntimeWarning
        A joblib worker died (``n_jobs > 1``): the search ran again one step at a time.
    """
    check_limits(tol, max_nodes, time_limit, total_time_limit)
    t0 = time.perf_counter()
    options = SearchOptions() if options is None else options
    if total_time_limit is not None:
        end = time.time() + float(total_time_limit)
        deadline = end if deadline is None else min(deadline, end)
    if theta_box is not None:
        problem = problem.with_theta_box(theta_box)
    # the LP bound of the data as given (what method="lp" reports: never wider), then the
    # same set in theta on data of order one (exact power-of-two scaling): HiGHS's
    # absolute tolerances then act relatively; the witnesses' errors are scaled back below
    lp = lp_bounds(problem, check_box=False)
    given, units = problem, Units.of_lp(problem, lp.bounds)
    problem = units.problem(problem)
    lp_box = units.to_search(lp.bounds)
    if working_set is None:
        # not with shared input errors (two-level): their products couple every
        # equation, and full LPs with the SLP walk were 3-6x faster at N = 900
        working_set = (problem.equation_times.size >= AUTO_MIN_EQUATIONS
                       and not shared_groups(problem))
    ws = initial_equations(problem, lp_box) if working_set else None
    jobs = [(k, s) for k in range(problem.p) for s in (1.0, -1.0)]
    isolate = crash_prone(problem)
    args = dict(tol=tol, max_nodes=max_nodes, time_limit=time_limit, progress=progress,
                to_data=1.0 / units.factors(problem.p))
    try:
        box, ws, outs, crashes, retried = _search_all(
            problem, lp_box, jobs, ws, n_jobs, deadline, options, args, isolate=isolate,
            t0=t0)
    except BrokenProcessPool as err:  # a joblib worker died in OBBT (n_jobs > 1)
        retried = [why(err)]
        box, ws, outs, crashes, _ = _search_all(problem, lp_box, jobs, ws, 1, deadline,
                                                options, args, isolate=True, t0=t0)
    if retried:
        # the steps not finished ran again one at a time, each in a worker process: a step
        # that dies again keeps what was certified before it (the LP bounds were a 100x
        # wider fallback on a long output-error record, new-user trial 9)
        isolate = True
        warnings.warn(f"a worker process of the parallel exact search died ({retried[0]}): "
                      "HiGHS can crash on long output-error records (see hammerbound."
                      "relaxations.exact.isolation), or the system ended it (e.g. out of "
                      "memory). The steps it had not finished ran again one at a time, each "
                      "in a worker process of its own (as with n_jobs=1).", RuntimeWarning,
                      stacklevel=2)
    polished = _polished(problem, jobs, outs, tol, options, deadline, isolate, crashes)
    if crashes:
        warnings.warn(f"the exact search stopped on {len(crashes)} step(s): {crashes[0]}. "
                      "The bounds of the steps that did not finish are the LP or OBBT outer "
                      "bounds (still guaranteed; status 'limit'); a witness that could not be "
                      "polished is the verified point the search found.", SearchLimitWarning,
                      stacklevel=2)
    if any(o.bound == np.inf for o in outs):
        # every leaf of a search was certified infeasible and no point was verified: the
        # set is empty (reporting +inf/-inf bounds with status "limit" would hide that)
        raise EmptyFeasibleSetError(
            "the branch-and-bound certified every node of the McCormick relaxation of "
            "(22.34) infeasible: no theta explains the data within the error bounds (the "
            "polytopic LP set is a strict outer approximation).", first_index=None,
            relaxation="exact")
    bounds, inner, infos = _end_infos(problem, jobs, outs, polished, lp.bounds, units)
    names = problem.param_names
    if check_box:
        raise_if_box_limited(bounds, given.theta_box, names,
                             [f"{i.param} {i.end}" for i in infos if i.status == "limit"])
    return IntervalResult(
        param_names=tuple(names), bounds=bounds, infos=tuple(infos), method="exact",
        time=time.perf_counter() - t0,
        status=end_statuses(names, infos, bounds, given.theta_box), lp=lp,
        root_box=units.back(box),
        inner=inner, details=ExactDetails(None if ws is None else int(ws.size)),
    )


def _search_all(problem, lp_box, jobs, ws, n_jobs, deadline, options, args, *, isolate, t0):
    """OBBT from the LP box, the first verified points, then one search per end in
    ``jobs`` (serially, sharing one :class:`.search.Workspace`, or on joblib workers).

    With ``isolate`` (problems on which HiGHS may crash, :func:`.isolation.crash_prone`)
    every step that does not already run on joblib workers runs in a worker process of
    :mod:`.isolation`; a step whose process dies keeps what the steps before it certified
    (the LP box for OBBT, the OBBT box for an end). With ``n_jobs != 1`` the ends go to
    the joblib workers one at a time (``batch_size=1``: each takes its share of the time
    left, :func:`.limits.end_share`, and no end waits behind another on one worker); if a
    worker dies there, the ends whose results had not come back run again one at a time,
    each isolated, from the OBBT box and points already found (a worker that dies in OBBT
    raises ``BrokenProcessPool``).

    Returns the OBBT box, the working set, the ends' results, the messages of the steps
    that died, and the reasons the parallel ends were run again (empty: they were not)."""
    crashes, retried = [], []
    parallel = None
    if n_jobs != 1:
        from joblib import Parallel

        parallel = Parallel(n_jobs=n_jobs, batch_size=1)
        parallel.__enter__()
    try:
        step = partial(_step, isolate, crashes)
        obbt_kw = dict(n_jobs=n_jobs, parallel=parallel, deadline=deadline, ws=ws,
                       picklable=isolate)
        if parallel is None:
            box, roots, thetas, ws = step(
                _obbt, problem, lp_box, **obbt_kw,
                fallback=lambda why: (np.array(lp_box), {}, [], ws))
        else:  # its LPs run on the joblib workers
            box, roots, thetas, ws = _obbt(problem, lp_box, **obbt_kw)
        pts = step(verified_points, problem, box, roots, thetas, ws, deadline,
                   fallback=lambda why: [])
        args = dict(args, deadline=deadline, ws=ws, options=options)
        ends = (problem, box, jobs, pts, roots, args)
        outs = None
        if parallel is not None:
            outs, died = _parallel_ends(n_jobs, *ends)
            if died is not None:
                retried.append(died)
                # only the ends whose result did not come back run again
                rest = [i for i, o in enumerate(outs) if o is None]
                again = _serial_ends(True, crashes, problem, box, [jobs[i] for i in rest],
                                     pts, roots, args, positions=rest)
                for i, o in zip(rest, again, strict=True):
                    outs[i] = o
        if outs is None:
            outs = _serial_ends(isolate, crashes, *ends)
    finally:
        if parallel is not None:
            parallel.__exit__(None, None, None)
    return box, ws, outs, crashes, retried


def _step(isolate, crashes, fn, *a, fallback, **kw):
    """``fn(*a, **kw)``; with ``isolate`` in the worker process of :mod:`.isolation`,
    where a crash appends its message to ``crashes`` and returns ``fallback(message)``."""
    if not isolate:
        return fn(*a, **kw)
    try:
        return run_isolated(fn, *a, **kw)
    except SolverCrashError as err:
        crashes.append(str(err))
        return fallback(str(err))


def _serial_ends(isolate, crashes, problem, box, jobs, pts, roots, args, positions=None):
    """The ends one after the other: in this process, sharing one
    :class:`.search.Workspace`, or with ``isolate`` each in the isolated worker
    (:func:`_step`). ``positions``: the ends' places in the progress display (default
    0, 1, ...)."""
    step = partial(_step, isolate, crashes)
    wsp = None if isolate else Workspace()
    positions = range(len(jobs)) if positions is None else positions
    outs = []
    for i, ((k, s), pos) in enumerate(zip(jobs, positions, strict=True)):
        t_end = time.perf_counter()
        outs.append(step(
            search_end, problem, box, k, s, pts, roots.get((k, s)), position=pos,
            workspace=wsp, order=(i, len(jobs), 1), **args,
            fallback=lambda why, k=k, s=s, t=t_end: _crashed_end(problem, box, k, s, pts,
                                                                 t, why)))
    return outs


def _parallel_ends(n_jobs, problem, box, jobs, pts, roots, args):
    """The ends on the joblib workers, one end per dispatch. Returns the ends' results
    in the order of ``jobs`` and None, or, if a worker died, the results that came back
    (None for the others) and the reason (:func:`.isolation.why`)."""
    from joblib import Parallel, delayed, effective_n_jobs

    workers = effective_n_jobs(n_jobs)
    outs = [None] * len(jobs)
    # the loky executor of the OBBT's Parallel is reused; results come back as each end
    # finishes, so those are kept if a worker dies later
    run = Parallel(n_jobs=n_jobs, batch_size=1, return_as="generator_unordered")
    try:
        for i, out in run(delayed(_numbered)(i, problem, box, k, s, pts, roots.get((k, s)),
                                             position=i, order=(i, len(jobs), workers),
                                             **args)
                          for i, (k, s) in enumerate(jobs)):
            outs[i] = out
    except BrokenProcessPool as err:
        return outs, why(err)
    return outs, None


def _numbered(i, *a, **kw):
    """``(i, search_end(*a, **kw))``: an end's result with its place (unordered results)."""
    return i, search_end(*a, **kw)


def _crashed_end(problem, box, k, s, points, t0, why) -> EndResult:
    """An end whose search died with its process: the box end (or a verified point's
    value, if better) with status "limit" and ``why`` as its message."""
    out = _not_searched(problem, box, k, s, points, t0)
    out.message = f"not searched to the end: {why}; the LP/OBBT outer bound is reported"
    return out


def _polished(problem, jobs, outs, tol, options, deadline, isolate, crashes):
    """The ends' witnesses a little inside the set (an independent check accepts them at
    the error bounds as given, not only within the acceptance tolerance): see
    :func:`.local.polish`; each end's value may worsen only by what is left of its
    tolerance. With ``isolate`` the polish runs in the search's worker process (its elastic
    LPs are HiGHS runs on the full record); if that dies, the verified witnesses are kept
    as they are and the crash is appended to ``crashes``."""
    witnesses = [o.witness for o in outs]
    if not options.polish or past(deadline):
        return witnesses
    keep = [(k, s, tol * max(1.0, abs(o.value)) - (o.value - o.bound)
             if o.status == "optimal" else np.inf) for (k, s), o in zip(jobs, outs, strict=True)]
    return _step(isolate, crashes, polish, problem, witnesses, keep=keep,
                 fallback=lambda why: witnesses)


def _end_infos(problem, jobs, outs, polished, lp_box, units):
    """``(bounds (p, 2), inner (p, 2), infos)`` of the ends' results, in the data's units
    (``problem`` is in the search's :class:`..units.Units`; ``lp_box`` in the data's)."""
    p = problem.p
    bounds = np.zeros((p, 2))
    inner = np.full((p, 2), np.nan)
    infos = []
    to_data = 1.0 / units.factors(p)  # per parameter: search units -> the data's
    for (k, s), o, wit in zip(jobs, outs, polished, strict=True):
        e = 0 if s > 0 else 1
        f = to_data[k]
        value = s * float(wit.theta[k]) if wit is not None else o.value
        theta = None if wit is None else units.back(wit.theta)
        # never wider than the LP bound (the OBBT box lies inside it; kept explicit)
        bounds[k, e] = max(f * s * o.bound, lp_box[k, 0]) if e == 0 else \
            min(f * s * o.bound, lp_box[k, 1])
        if wit is not None:
            inner[k, e] = theta[k]
        infos.append(BoundInfo(
            param=problem.param_names[k], sense="min" if s > 0 else "max",
            bound=float(bounds[k, e]), solver_value=float(f * s * o.solver_value),
            status=o.status, certified=True, time=o.time, iterations=o.iterations,
            gap=max(f * float(value - o.bound), 0.0) if np.isfinite(value) else None,
            witness=theta, nodes=o.nodes, message=o.message,
            point=None if wit is None else VerifiedPoint(
                theta.copy(), *units.errors_back(wit.eta, wit.dx)),
            inner=None if wit is None else float(theta[k]),
        ))
    return bounds, inner, infos
