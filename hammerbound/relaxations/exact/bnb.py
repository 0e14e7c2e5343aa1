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
``tol * max(1, |value|)``; node and time limits return the still-valid outer bound with
status ``"limit"``.

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
  already exceeds the incumbent (:func:`_reduced_cost_tightening`);
* every child node starts from its parent's simplex basis (a snapshot kept with the
  node; one bound away), not from whatever node was solved last: 3.5x fewer simplex
  iterations on the chapter's two-level data (``python -m benchmarks.exact_ablation``);
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

import heapq
import time
from dataclasses import dataclass

import numpy as np

from ...exceptions import EmptyFeasibleSetError
from ..lp import end_statuses, lp_bounds, raise_if_box_limited
from ..problem import EIVProblem, unit_scale
from ..result import BoundInfo, ExactDetails, IntervalResult, VerifiedPoint
from .local import improve, polish, restore, restore_near
from .mccormick import shared_groups
from .obbt import _limit_lp, _obbt, _relaxation, _solve
from .points import _on_gain_plane, _Point, _Pool
from .working_set import AUTO_MIN_EQUATIONS, initial_equations

__all__ = ["exact_bounds"]
# branch at the LP point, kept this fraction of the width away from the box edges
_SPLIT_CLIP = 0.05
# after a line search that does not improve the incumbent, wait up to this many nodes
_MAX_SEARCH_GAP = 16
_MAX_SEARCH_GAP_WALKED = 1024
# Gauss-Newton restoration next to an LP point at which the relaxation is exact (every
# product violation below this, relative to max(1, |incumbent|)): once per this many nodes
_EXACT_VIOLATION = 1e-9
_RESTORE_GAP = 64
# the SLP walk to a near-optimal incumbent (.local.improve), and its resolution (a fraction
# of the tolerance)
_LOCAL = True
_LOCAL_RES = 0.05


def _cap(box, k, sense, ub):
    """``box`` restricted to ``sense * theta_k <= ub`` (None if that leaves nothing)."""
    if sense > 0:
        if box[k, 0] > ub:
            return None
        if box[k, 1] > ub:
            box = box.copy()
            box[k, 1] = ub
    else:
        if box[k, 1] < -ub:
            return None
        if box[k, 0] < -ub:
            box = box.copy()
            box[k, 0] = -ub
    return box


def _reduced_cost_tightening(box, r, bound, target):
    """Shrink a node's theta box by reduced-cost bound tightening.

    ``bound`` is the rigorous LP bound of the node and ``r`` (p,) the reduced costs of the
    theta columns behind it (:func:`._highs.row_dual_bound`). That bound holds, with the
    term ``min(r_j l_j, r_j u_j)`` updated, for any sub-box; the McCormick relaxation of
    a sub-box is tighter still. So the part ``theta_j > l_j + (target - bound) / r_j``
    (``r_j > 0``; mirrored for ``r_j < 0``) has relaxed value ``>= target`` and is cut off.
    The cut is widened by a relative 1e-9 to stay on the safe side of rounding.

    Returns ``(new_box, cut)`` where ``cut`` says whether anything was removed.
    """
    slack = target - bound
    if not (np.isfinite(slack) and slack > 0):
        return box, False
    box = box.copy()
    cut = False
    with np.errstate(divide="ignore"):
        d = slack / np.abs(r) * (1.0 + 1e-9)
    d = d + 1e-12 * np.maximum(1.0, np.abs(box).max(axis=1))
    for j in np.flatnonzero(r > 0):
        hi = box[j, 0] + d[j]
        if hi < box[j, 1]:
            box[j, 1], cut = hi, True
    for j in np.flatnonzero(r < 0):
        lo = box[j, 1] - d[j]
        if lo > box[j, 0]:
            box[j, 0], cut = lo, True
    return box, cut


@dataclass
class _Search:
    bound: float
    value: float
    witness: _Point | None
    nodes: int
    time: float
    status: str
    message: str
    iterations: int
    solver_value: float


def _box_end(box, k, sense):
    """The end of ``box`` that bounds ``min sense * theta_k`` from below."""
    return float(box[k, 0]) if sense > 0 else -float(box[k, 1])


class _GapBar:
    """Progress of one interval end: the fraction of its initial certified gap closed.

    The gap is "best verified value minus certified outer bound" (before a verified point
    exists, the width of the root box in ``theta_k`` stands for the value); the search is
    done when the gap is below ``tol``, so 100 % means done. On a terminal a tqdm bar whose
    postfix shows the gap, the nodes and the time left before the time limit stops the
    search; otherwise (a pipe, a file) plain lines without cursor codes: one every
    :data:`_LINE_EVERY` seconds and one when the end is done.
    """

    def __init__(self, label, position, gap0, stop_at):
        import sys

        self.gap0 = max(float(gap0), 1e-300)
        self.stop_at = stop_at
        self.shown = 0.0
        self.label = label
        self.t0 = self.last = time.perf_counter()
        self.state = (0.0, float(gap0), 0)
        self.bar = None
        isatty = getattr(sys.stderr, "isatty", None)
        if callable(isatty) and isatty():
            from tqdm.auto import tqdm

            self.bar = tqdm(total=100.0, position=position, leave=False, desc=label,
                            bar_format="{desc}: {percentage:3.0f}% of gap closed |{bar}| "
                                       "{elapsed} {postfix}")

    def update(self, gap, target, nodes):
        gap = max(float(gap), 0.0)
        done = 1.0 - max(gap - target, 0.0) / max(self.gap0 - target, 1e-300)
        pct = 100.0 * min(max(done, 0.0), 1.0)
        self.state = (pct, gap, nodes)
        if self.bar is None:
            if time.perf_counter() - self.last >= _LINE_EVERY:
                self._line("searching")
            return
        left = self.stop_at - time.perf_counter()
        self.bar.set_postfix_str(f"gap {gap:.3g}, {nodes} nodes, stops within {max(left, 0):.0f} s"
                                 if np.isfinite(left) else f"gap {gap:.3g}, {nodes} nodes",
                                 refresh=False)
        if pct > self.shown:
            self.bar.update(pct - self.shown)
            self.shown = pct
        else:
            self.bar.update(0)

    def _line(self, what):
        import sys

        pct, gap, nodes = self.state
        self.last = time.perf_counter()
        print(f"exact {self.label}: {what}, {pct:.0f}% of gap closed, gap {gap:.3g}, "
              f"{nodes} nodes, {self.last - self.t0:.1f} s", file=sys.stderr, flush=True)

    def close(self):
        if self.bar is None:
            self._line("finished")
        else:
            self.bar.close()


#: seconds between progress lines of an interval end when stderr is not a terminal
_LINE_EVERY = 10.0


def _search(problem, box0, k, sense, points, root, tol, max_nodes, time_limit, progress,
            position, deadline=None, ws=None):
    """Minimise ``sense * theta_k`` over the EIV set by branch-and-bound (one interval end).

    ``root`` is ``(bound, x, basis)`` from the last OBBT round (or None). ``box0`` is the
    OBBT box, a certified outer box: the returned bound is never below its end (monotone
    knowledge), also when a limit stops the search. The search runs for at most
    ``time_limit`` seconds and stops at ``deadline`` (a :func:`time.time` timestamp, the
    total budget of the fit); an end whose budget is used up before it starts reports the
    box end with status ``"limit"``.
    """
    t0 = time.perf_counter()
    p = problem.p
    box0 = np.array(box0, dtype=float)
    end0 = _box_end(box0, k, sense)

    def val(theta):
        return sense * float(theta[k])

    limit = float(time_limit)
    by_budget = False
    if deadline is not None and deadline - time.time() < limit:
        limit, by_budget = deadline - time.time(), True
    if limit <= 0 and by_budget:
        inc = min(points, key=lambda q: val(q.theta), default=None)
        ub = val(inc.theta) if inc is not None else np.inf
        bound = min(end0, ub)
        return _Search(bound, ub, inc, 0, time.perf_counter() - t0, "limit",
                       "not searched: the total time budget (total_time_limit) was used up "
                       "before this end started; the LP/OBBT outer bound is reported",
                       0, np.nan)
    stop_at = t0 + limit
    relax = _relaxation(problem, box0, ws)
    c = np.zeros(relax.ncol)
    c[k] = sense
    relax.lp.set_cost(c)
    # branching variables: theta, then -- for the end of a B coefficient -- the shared
    # input-error variables (two-level inner signal; see the module docstring)
    ks = shared_groups(problem) if k >= problem.na else 0
    bcols = np.concatenate([np.arange(p), relax.dx_columns()[:ks]]).astype(np.int64)
    if ks:
        box0 = np.vstack([box0, np.column_stack([-problem.dx_group, problem.dx_group])])
    pool = _Pool(problem, list(points), stop_at=stop_at, working_set=ws is not None)
    if ws is not None:
        pool._ensure_screen()

    inc = min(pool.points, key=lambda q: val(q.theta), default=None)
    # the SLP walk (.local) works on all equations: on long records (working set) one of
    # its LPs costs more than it saves (N = 10000: 1.8 s per LP, 97 s against 55 s in all)
    local = _LOCAL and ws is None
    if inc is not None and local:
        # a near-optimal incumbent first: the tree then only has to prove the bound
        inc = improve(pool, inc, k, sense, box0,
                      _LOCAL_RES * tol * max(1.0, abs(val(inc.theta))), stop_at=stop_at)
    ub = val(inc.theta) if inc is not None else np.inf
    interior = np.mean([q.theta for q in pool.points], axis=0) if pool.points else None
    if interior is not None and (pool._out_of_time() or pool.verify(interior) is None):
        interior = inc.theta
    width0 = box0[:, 1] - box0[:, 0]
    min_w = 1e-12 * np.maximum(1.0, np.abs(box0).max(axis=1))
    heap = []
    counter = 0
    pending = None  # (lb, box, precomputed LPSolve-like (bound, x))
    if root is not None and root[1] is not None and ws is None:
        relax.lp.set_basis(root[2])
        pending = (max(end0, root[0]), box0, root[1])
    elif root is not None and ws is not None:
        # the OBBT basis belongs to another working set: solve the root again, from its bound
        heap.append((max(end0, root[0]), counter, box0, None))
        counter += 1
    else:
        heap.append((end0, counter, box0, None))
        counter += 1
    closed_lb = np.inf  # min bound over leaves closed by bound (not by infeasibility)
    # after the SLP walk the incumbent is near-optimal: the tree's searches start backed off
    walked = inc is not None and local
    max_gap = _MAX_SEARCH_GAP_WALKED if walked else _MAX_SEARCH_GAP
    last_try, try_gap = -1, (_MAX_SEARCH_GAP if walked else 1)
    last_restore = -_RESTORE_GAP
    nodes = 0
    iters = 0
    refusals = []  # notes of the node LPs HiGHS refused (they kept their parent's bound)
    status = "optimal"
    root_value = np.nan
    bar = None
    top = end0 + float(width0[k])  # sup of sense * theta_k over the root box
    if progress:
        bar = _GapBar(f"{problem.param_names[k]} {'min' if sense > 0 else 'max'}", position,
                      min(ub, top) - end0, stop_at)
    while heap or pending is not None:
        tol_eff = tol * max(1.0, abs(ub)) if np.isfinite(ub) else 0.0
        rc = None
        if pending is not None:
            lb, box, x = pending
            pending = None
            nodes += 1
            root_value = sense * float(x[k])
        else:
            if heap[0][0] >= ub - tol_eff:
                break
            if nodes >= max_nodes or time.perf_counter() > stop_at:
                status = "limit"
                break
            lb_parent, _, box, basis = heapq.heappop(heap)
            if np.isfinite(ub):
                # only sense * theta_k <= ub can hold the minimum: cap the box there,
                # which also tightens every McCormick envelope that involves theta_k
                box = _cap(box, k, sense, ub)
                if box is None:
                    continue
            relax.set_box(box)
            if basis is not None:
                relax.lp.restore(basis)  # the parent's basis: one bound away
            # HiGHS stops once its objective passes the cutoff; half the tolerance below the
            # incumbent leaves room for the certified bound to trail HiGHS's own value
            relax.lp.set_cutoff(ub - 0.5 * tol_eff if np.isfinite(ub) else None)
            _limit_lp(relax.lp, stop_at - time.perf_counter())
            res = _solve(relax, pool.screen)
            nodes += 1
            iters += res.iterations
            if res.status == "cutoff" and not res.bound >= ub - tol_eff:
                # cut off, but the certified bound does not close the node: solve it to the
                # end (a point to branch at) instead of splitting it blindly
                relax.lp.set_cutoff(None)
                res = _solve(relax, pool.screen)
                iters += res.iterations
            if res.refused:
                # HiGHS refused the node LP on every attempt: the node keeps its parent's
                # certified bound (lb_parent below) and is split without an LP point
                refusals.append(res.note)
            if res.status == "infeasible":
                continue
            lb = max(lb_parent, res.bound)
            x = res.x if res.status == "optimal" else None
            if x is not None:
                rc_bound, rc = res.bound, res.reduced[bcols]
            if nodes == 1 and x is not None:
                root_value = res.value
        if bar is not None:
            lb_now = max(end0, min(closed_lb, lb, heap[0][0] if heap else np.inf))
            bar.update(min(ub, top) - lb_now, tol_eff, nodes)
        if lb >= ub - tol_eff:
            closed_lb = min(closed_lb, lb)
            continue
        width = box[:, 1] - box[:, 0]
        if x is not None:
            th = np.clip(x[:p], box[:p, 0], box[:p, 1])
            if val(th) < ub - tol_eff:
                # the primal heuristic (screening the LP point, then line searches of ~10
                # LPs each) runs while it pays off, then backs off geometrically: the
                # lower-bound proof needs no incumbent updates
                due = nodes - last_try >= try_gap
                pt = pool.add(th) if due else None
                searching = pt is None and due
                if due:
                    last_try = nodes
                if searching and inc is not None:
                    # short segment from the incumbent: fine resolution near the optimum
                    pt = pool.line_search(inc.theta, th, k=k, resolution=0.25 * tol_eff)
                    if pt is not None and val(pt.theta) >= ub:
                        pt = None
                if searching and pt is None and interior is not None:
                    pt = pool.line_search(interior, th, k=k, resolution=0.25 * tol_eff)
                if pt is not None and local and val(pt.theta) < ub - tol_eff:
                    # another basin (or the first point): walk it down by SLP as well
                    pt = improve(pool, pt, k, sense, box0, _LOCAL_RES * tol_eff,
                                 stop_at=stop_at)
                if pt is None and local and nodes - last_restore >= _RESTORE_GAP \
                        and relax.violations(x, ks).max() <= _EXACT_VIOLATION * max(1.0, abs(ub)):
                    # the relaxation is exact at the LP point, yet the point is not verified:
                    # the set is thin there (see restore_near)
                    last_restore = nodes
                    pt = restore_near(pool, (th, *relax.split_eta_dx(x)), box[:p],
                                      0.25 * tol_eff, stop_at=stop_at)
                    if pt is not None and val(pt.theta) < ub - tol_eff:
                        pt = improve(pool, pt, k, sense, box0, _LOCAL_RES * tol_eff,
                                     stop_at=stop_at)
                if due:
                    # useful: better by more than the searches' resolution
                    useful = pt is not None and val(pt.theta) < ub - 0.25 * tol_eff
                    try_gap = 1 if useful else min(2 * try_gap, max_gap)
                if pt is not None and val(pt.theta) < ub:
                    inc, ub = pt, val(pt.theta)
                    if interior is None:
                        interior = pt.theta
                    tol_eff = tol * max(1.0, abs(ub))
                    if lb >= ub - tol_eff:
                        closed_lb = min(closed_lb, lb)
                        continue
            if rc is not None and np.isfinite(ub):
                box, cut = _reduced_cost_tightening(box, rc, rc_bound, ub - tol_eff)
                if cut:
                    closed_lb = min(closed_lb, ub - tol_eff)
                    width = box[:, 1] - box[:, 0]
            score = relax.violations(x, ks) * width / np.maximum(width0, 1e-300)
            if score.max() > 0:
                i = int(np.argmax(score))
            else:
                i = int(np.argmax(width[:p] / np.maximum(width0[:p], 1e-300)))
            margin = _SPLIT_CLIP * width[i]
            split = float(np.clip(x[bcols[i]], box[i, 0] + margin, box[i, 1] - margin))
        else:
            # no LP point: the widest theta (a shared input error may be in no equation)
            i = int(np.argmax(width[:p] / np.maximum(width0[:p], 1e-300)))
            split = 0.5 * (box[i, 0] + box[i, 1])
        if width[i] <= min_w[i]:
            closed_lb = min(closed_lb, lb)  # cannot split further: keep its bound
            continue
        # children start from this node's basis (a working-set model grows between nodes)
        basis = relax.lp.snapshot() if ws is None else None
        for side in (0, 1):
            child = box.copy()
            child[i, 1 - side] = split
            heapq.heappush(heap, (lb, counter, child, basis))
            counter += 1
    if bar is not None:
        bar.close()
    open_lb = min((h[0] for h in heap), default=np.inf)
    bound = min(closed_lb, open_lb, ub)
    # monotone knowledge: the OBBT box end is a certified bound as well (a leaf LP that
    # failed, or the root of a search stopped at once, may carry -inf); +inf (every leaf
    # certified infeasible, no verified point) is kept: exact_bounds reports the empty set
    bound = max(bound, min(end0, ub))
    gap = max(ub - bound, 0.0)
    elapsed = time.perf_counter() - t0
    if status == "limit":
        if nodes >= max_nodes:
            why = "node limit (max_nodes)"
        elif by_budget:
            why = "total time budget (total_time_limit)"
        else:
            why = "time limit (time_limit)"
        msg = (f"stopped by the {why} ({nodes} nodes, {elapsed:.1f} s): the bound is a valid "
               f"outer bound, certified gap {gap:.3g}")
    elif not np.isfinite(ub):
        status = "limit"
        msg = "no verified-feasible point found: only the outer bound is certified"
    else:
        msg = f"gap {gap:.3g} <= tol after {nodes} nodes ({pool.checks} check_theta calls)"
    if refusals:
        msg += (f"; {len(refusals)} node LP(s) could not be solved and kept their parent's "
                f"certified bound ({refusals[0]})")
    return _Search(bound, ub, inc, nodes, elapsed, status, msg, iters, root_value)


def _perf_deadline(deadline):
    """A :func:`time.time` deadline (or None) as a :func:`time.perf_counter` one."""
    return None if deadline is None else time.perf_counter() + (deadline - time.time())


def verified_points(problem, box, roots, thetas, ws=None, deadline=None) -> list:
    """The first verified-feasible points of (22.34) inside the OBBT ``box``: the OBBT LP
    points ``thetas`` (and their mean and the box centre, on the gain plane) that pass
    :func:`.problem.check_theta`; when none does (a thin set), Gauss-Newton steps from the
    OBBT points (a single-point set, e.g. noise exactly at its bound), then a Nelder-Mead
    search on the screening violation. Stops at ``deadline`` (:func:`time.time`)."""
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
) -> IntervalResult:
    """Tight parameter uncertainty intervals (22.35)-(22.37) with a certificate.

    Every end starts from, and never reports wider than, the polytopic LP bound
    (:func:`.lp.lp_bounds`) shrunk by OBBT: a node or time limit returns the best certified
    outer bound found so far (status ``"limit"``), never a wider or infinite one.

    The search runs on the data multiplied by a power of two that brings them to order one
    (:func:`.problem.unit_scale`; exact, the set in theta is the same). A node LP that HiGHS
    refuses on every attempt (:meth:`._highs.HighsLP.solve`) keeps its parent's certified
    bound, and the end's message says so. Each end's witness is polished a little into the
    set (:func:`.local.polish`).

    Parameters
    ----------
    problem : EIVProblem
        The EIV problem (22.34).
    tol : float, default 1e-4
        Stop an interval end when ``value - bound <= tol * max(1, |value|)`` (absolute for
        small parameters, relative for large ones).
    max_nodes : int, default 20000
        Node limit per interval end.
    time_limit : float, default 600
        Wall-time limit (s) per interval end.
    n_jobs : int, default 1
        The ``2 p`` interval ends are searched in parallel with joblib.
    progress : bool, default False
        Show a tqdm progress bar per interval end.
    theta_box : array_like, shape (p, 2), optional
        A priori box replacing ``problem.theta_box``.
    check_box : bool, default True
        Raise :class:`UnboundedSetError` when a bound coincides with the a priori box.
    total_time_limit : float or None, default None
        Wall-time budget (s) of the whole call, shared by the ``2 p`` ends and the joblib
        workers: each end searches for at most ``min(time_limit, time left)``; the LP and
        the first OBBT round always run (set-up), further OBBT rounds and the search for a
        first feasible point only while time is left; an end that has no time left when it
        starts reports its LP/OBBT bound with status ``"limit"``.
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
    EmptyFeasibleSetError
        The data are inconsistent (from the LP or from the relaxation at the root).
    UnboundedSetError
        An exact bound coincides with the a priori box.
    """
    t0 = time.perf_counter()
    if total_time_limit is not None:
        end = time.time() + float(total_time_limit)
        deadline = end if deadline is None else min(deadline, end)

    def time_left():
        return deadline is None or time.time() < deadline

    if theta_box is not None:
        problem = problem.with_theta_box(theta_box)
    # the LP bound of the data as given (what method="lp" reports: never wider), then the
    # same set in theta on data of order one (exact power-of-two scaling): HiGHS's
    # absolute tolerances then act relatively; the witnesses' errors are scaled back below
    lp = lp_bounds(problem, check_box=False)
    scale = unit_scale(problem)
    if scale != 1.0:
        problem = problem.scaled(scale)
    p = problem.p
    jobs = [(k, s) for k in range(p) for s in (1.0, -1.0)]
    parallel = None
    if n_jobs != 1:
        from joblib import Parallel

        parallel = Parallel(n_jobs=n_jobs)
        parallel.__enter__()
    try:
        if working_set is None:
            # not with shared input errors (two-level): their products couple every
            # equation, and full LPs with the SLP walk were 3-6x faster at N = 900
            working_set = (problem.equation_times.size >= AUTO_MIN_EQUATIONS
                           and not shared_groups(problem))
        ws = initial_equations(problem, lp.bounds) if working_set else None
        box, roots, thetas, ws = _obbt(problem, lp.bounds, n_jobs=n_jobs, parallel=parallel,
                                       deadline=deadline, ws=ws)
        pts = verified_points(problem, box, roots, thetas, ws, deadline)
        args = dict(tol=tol, max_nodes=max_nodes, time_limit=time_limit, progress=progress,
                    deadline=deadline, ws=ws)
        if parallel is None:
            outs = [_search(problem, box, k, s, pts, roots.get((k, s)), position=i, **args)
                    for i, (k, s) in enumerate(jobs)]
        else:
            from joblib import delayed

            outs = parallel(
                delayed(_search)(problem, box, k, s, pts, roots.get((k, s)), position=i, **args)
                for i, (k, s) in enumerate(jobs))
    finally:
        if parallel is not None:
            parallel.__exit__(None, None, None)
    # witnesses a little inside the set (an independent check accepts them at the error
    # bounds as given, not only within the acceptance tolerance): see local.polish
    # (each end's value may worsen only by what is left of its tolerance)
    keep = [(k, s, tol * max(1.0, abs(o.value)) - (o.value - o.bound)
             if o.status == "optimal" else np.inf) for (k, s), o in zip(jobs, outs, strict=True)]
    polished = polish(problem, [o.witness for o in outs], keep=keep) if time_left() else \
        [o.witness for o in outs]
    if any(o.bound == np.inf for o in outs):
        # every leaf of a search was certified infeasible and no point was verified: the
        # set is empty (reporting +inf/-inf bounds with status "limit" would hide that)
        raise EmptyFeasibleSetError(
            "the branch-and-bound certified every node of the McCormick relaxation of "
            "(22.34) infeasible: no theta explains the data within the error bounds (the "
            "polytopic LP set is a strict outer approximation).", first_index=None)
    names = problem.param_names
    bounds = np.zeros((p, 2))
    inner = np.full((p, 2), np.nan)
    infos = []
    for (k, s), o, wit in zip(jobs, outs, polished, strict=True):
        e = 0 if s > 0 else 1
        value = s * float(wit.theta[k]) if wit is not None else o.value
        bounds[k, e] = s * o.bound
        # never wider than the LP bound (the OBBT box lies inside it; kept explicit)
        bounds[k, e] = max(bounds[k, e], lp.bounds[k, 0]) if e == 0 else \
            min(bounds[k, e], lp.bounds[k, 1])
        if wit is not None:
            inner[k, e] = wit.theta[k]
        infos.append(BoundInfo(
            param=names[k], sense="min" if s > 0 else "max", bound=float(bounds[k, e]),
            solver_value=float(s * o.solver_value), status=o.status, certified=True,
            time=o.time, iterations=o.iterations,
            gap=max(float(value - o.bound), 0.0) if np.isfinite(value) else None,
            witness=None if wit is None else wit.theta.copy(), nodes=o.nodes, message=o.message,
            point=None if wit is None else VerifiedPoint(wit.theta.copy(), wit.eta / scale,
                                                         wit.dx / scale),
            inner=None if wit is None else float(wit.theta[k]),
        ))
    if check_box:
        raise_if_box_limited(bounds, problem.theta_box, names)
    return IntervalResult(
        param_names=tuple(names), bounds=bounds, infos=tuple(infos), method="exact",
        time=time.perf_counter() - t0,
        status=end_statuses(names, infos, bounds, problem.theta_box), lp=lp, root_box=box,
        inner=inner, details=ExactDetails(None if ws is None else int(ws.size)),
    )
