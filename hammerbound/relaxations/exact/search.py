"""One interval end of the exact method: ``min sense * theta_k`` over the EIV set (22.34)
by spatial branch-and-bound (:class:`EndSearch`); :mod:`.bnb` runs the ``2 p`` ends.

A node is a box of theta (followed, for the ``b_j`` ends of the two-level inner signal, by
the boxes of the shared input errors). Its certified lower bound comes from the McCormick
LP (:func:`.obbt._solve`); the incumbent (upper bound) is a point verified by
:func:`.problem.check_theta`. The loop pops the node with the lowest bound, solves its LP
(:meth:`EndSearch._next`), tries to improve the incumbent at the LP point
(:meth:`EndSearch._try_incumbent`), and splits the node (:meth:`EndSearch._branch`). Every
choice here only changes how fast the gap closes, never a bound: see the module docstring
of :mod:`.bnb` for what each part buys.
"""

from __future__ import annotations

import heapq
import time
from dataclasses import dataclass

import numpy as np

from ...solvers.highs_process import wall_stamp
from .incumbent import (
    _FIRST_COMPLETE,
    _LOCAL_RES,
    _MAX_SEARCH_GAP,
    _MAX_SEARCH_GAP_WALKED,
    _RESTORE_GAP,
    IncumbentSearch,
)
from .limits import end_share
from .local import improve
from .mccormick import shared_groups
from .node_box import _box_end, _cap, _reduced_cost_tightening
from .obbt import _relaxation, _solve, warm_start
from .points import _Point, _Pool
from .progress import _GapBar

# branch at the LP point, kept this fraction of the width away from the box edges
_SPLIT_CLIP = 0.05
_STOP = object()  # _next: the search is over


@dataclass(frozen=True)
class SearchOptions:
    """Parts of the exact method's search that can be switched off, e.g. to measure what
    each one buys (``python -m benchmarks.exact_ablation``) or in tests. None of them
    changes a bound beyond the tolerance: they only change how fast the gap closes.
    Picklable, so they reach joblib workers (``n_jobs > 1``).

    Attributes
    ----------
    local_search : bool, default True
        Walk the incumbent down by SLP (:func:`.local.improve`) before the tree and after a
        point of another basin; restoration next to exact LP points.
    shared_branching : bool, default True
        On the two-level inner signal, the ``b_j`` ends also branch on the shared input
        errors (:func:`.mccormick.shared_groups`).
    parent_basis : bool, default True
        Children start from their parent's simplex basis (else from the last node's).
    polish : bool, default True
        Move every end's witness a little into the set (:func:`.local.polish`).
    """

    local_search: bool = True
    shared_branching: bool = True
    parent_basis: bool = True
    polish: bool = True


@dataclass
class EndResult:
    """What one interval end's search returns to :func:`.bnb.exact_bounds`."""

    bound: float
    value: float
    witness: _Point | None
    nodes: int
    time: float
    status: str
    message: str
    iterations: int
    solver_value: float


class Workspace:
    """What the next interval end of the same process can reuse instead of building it
    again (serial runs, ``n_jobs=1``): the McCormick node model (full LPs only; every end
    resets its box, cost, cut-off and basis). It holds no result. The screening and SLP
    LPs are not shared: warm-started from another end's basis they changed the search's
    path (two-level signal, Delta eta = 0.3: 10 % slower)."""

    def __init__(self):
        self.relax = None


def _stop_time(t0, time_limit, deadline):
    """``(stop_at, by_budget)``: the :func:`time.perf_counter` time the search stops at
    (``time_limit`` from ``t0``, or the :func:`time.time` ``deadline`` if earlier)."""
    limit = float(time_limit)
    if deadline is not None and deadline - time.time() < limit:
        return t0 + deadline - time.time(), True
    return t0 + limit, False


def search_end(problem, box0, k, sense, points, root, tol, max_nodes, time_limit, progress,
               position, deadline=None, ws=None, options=None, workspace=None, to_data=None,
               order=None) -> EndResult:
    """Minimise ``sense * theta_k`` over the EIV set by branch-and-bound (one interval end).

    ``root`` is ``(bound, x, basis)`` from the last OBBT round (or None). ``box0`` is the
    OBBT box, a certified outer box: the returned bound is never below its end (monotone
    knowledge), also when a limit stops the search. The search runs for at most
    ``time_limit`` seconds and stops at ``deadline`` (a :func:`time.time` timestamp, the
    total budget of the fit); an end whose budget is used up before it starts reports the
    box end with status ``"limit"``. ``options``: :class:`SearchOptions`; ``workspace``: a
    :class:`Workspace` shared with the other ends of this process, or None; ``to_data``:
    per parameter, the factor from the search's units to the data's (the progress shows
    the gap in the data's units), or None (the same units). ``order = (i, ends, workers)``:
    this end is the ``i``-th of ``ends`` started in order on ``workers`` processes, and
    may use only its share of the time left before ``deadline`` (:func:`.limits.end_share`:
    time an end leaves unused goes to the ends after it).
    """
    t0 = time.perf_counter()
    if deadline is not None and order is not None:
        deadline = min(deadline, time.time() + end_share(deadline, *order))
    stop_at, by_budget = _stop_time(t0, time_limit, deadline)
    if stop_at <= t0 and by_budget:
        return _not_searched(problem, box0, k, sense, points, t0)
    s = EndSearch(problem, box0, k, sense, tol, max_nodes, stop_at, ws,
                  options or SearchOptions(), workspace)
    s.start(points, root)
    if progress:
        s.bar = _GapBar(f"{problem.param_names[k]} {'min' if sense > 0 else 'max'}",
                        position, min(s.ub, s.top) - s.end0, stop_at,
                        1.0 if to_data is None else float(to_data[k]), t0=t0)
    s.run()
    return s.result(t0, by_budget)


def _not_searched(problem, box0, k, sense, points, t0) -> EndResult:
    """The result of an end whose time budget was used up before it started."""
    inc = min(points, key=lambda q: sense * float(q.theta[k]), default=None)
    ub = sense * float(inc.theta[k]) if inc is not None else np.inf
    bound = min(_box_end(np.asarray(box0, dtype=float), k, sense), ub)
    return EndResult(bound, ub, inc, 0, time.perf_counter() - t0, "limit",
                     "not searched: the total time budget (total_time_limit) was used up "
                     "before this end started; the LP/OBBT outer bound is reported", 0, np.nan)


class EndSearch(IncumbentSearch):
    """The state of one interval end's branch-and-bound (see :func:`search_end`)."""

    def __init__(self, problem, box0, k, sense, tol, max_nodes, stop_at, ws, options,
                 workspace=None):
        self.problem, self.k, self.sense, self.tol = problem, k, float(sense), tol
        self.max_nodes, self.stop_at, self.ws, self.options = max_nodes, stop_at, ws, options
        self.workspace = workspace
        p = problem.p
        box0 = np.array(box0, dtype=float)
        self.end0 = _box_end(box0, k, sense)
        self.top = self.end0 + float(box0[k, 1] - box0[k, 0])  # sup of sense * theta_k
        self.relax = self._relaxation(box0)
        c = np.zeros(self.relax.ncol)
        c[k] = sense
        self.relax.lp.set_cost(c)
        # branching variables: theta, then -- for the end of a B coefficient -- the shared
        # input-error variables (two-level inner signal; see the docstring of .bnb)
        self.ks = shared_groups(problem) if (k >= problem.na and options.shared_branching) \
            else 0
        self.bcols = np.concatenate([np.arange(p), self.relax.dx_columns()[:self.ks]]) \
            .astype(np.int64)
        if self.ks:
            box0 = np.vstack([box0, np.column_stack([-problem.dx_group, problem.dx_group])])
        self.box0 = box0
        self.width0 = box0[:, 1] - box0[:, 0]
        self.min_w = 1e-12 * np.maximum(1.0, np.abs(box0).max(axis=1))
        # the SLP walk (.local) works on all equations: on long records (working set) one
        # of its LPs costs more than it saves (N = 10000: 1.8 s per LP, 97 s against 55 s)
        self.local = options.local_search and ws is None
        self.heap, self.counter, self.pending = [], 0, None
        self.closed_lb = np.inf  # min bound over leaves closed by bound (not infeasibility)
        self.nodes = self.iters = 0
        self.refusals = []  # notes of the node LPs HiGHS refused (they kept their parent's)
        self.status, self.root_value, self.bar = "optimal", np.nan, None
        self.last_restore = -_RESTORE_GAP

    # ---- set-up ---------------------------------------------------------------------
    def _relaxation(self, box0):
        """The node LP model: the workspace's (full LPs, reset to ``box0``) or a new one."""
        wsp, pr = self.workspace, self.problem
        if self.ws is not None or wsp is None:
            return _relaxation(pr, box0, self.ws)
        if wsp.relax is None:
            wsp.relax = _relaxation(pr, box0, None)
        elif shared_groups(pr):  # a b_j end before may have narrowed the shared errors
            wsp.relax.set_box(np.vstack([box0, np.column_stack([-pr.dx_group, pr.dx_group])]))
        else:
            wsp.relax.set_box(box0)
        return wsp.relax

    def val(self, theta) -> float:
        return self.sense * float(theta[self.k])

    @property
    def tol_eff(self) -> float:
        """The tolerance on the gap at the current incumbent (absolute for small values)."""
        return self.tol * max(1.0, abs(self.ub)) if np.isfinite(self.ub) else 0.0

    def start(self, points, root):
        """The pool of verified points, a (walked) incumbent and the root node."""
        self.pool = _Pool(self.problem, list(points), stop_at=self.stop_at,
                          working_set=self.ws is not None)
        if self.ws is not None:
            self.pool._ensure_screen()
        inc = min(self.pool.points, key=lambda q: self.val(q.theta), default=None)
        if inc is not None and self.local:
            # a near-optimal incumbent first: the tree then only has to prove the bound
            inc = improve(self.pool, inc, self.k, self.sense, self.box0,
                          _LOCAL_RES * self.tol * max(1.0, abs(self.val(inc.theta))),
                          stop_at=self.stop_at)
        self.inc = inc
        self.ub = self.val(inc.theta) if inc is not None else np.inf
        self.interior = self._interior()
        # after the SLP walk the incumbent is near-optimal: the searches start backed off
        walked = inc is not None and self.local
        self.max_gap = _MAX_SEARCH_GAP_WALKED if walked else _MAX_SEARCH_GAP
        self.last_try, self.try_gap = -1, (_MAX_SEARCH_GAP if walked else 1)
        self.last_complete, self.complete_gap = -1, _FIRST_COMPLETE
        self._seed(root)

    def _interior(self):
        """A verified point inside the set to line-search from: the mean of the pool's
        points if verified, else the incumbent's theta (None without points)."""
        pool = self.pool
        if not pool.points:
            return None
        interior = np.mean([q.theta for q in pool.points], axis=0)
        if pool._out_of_time() or pool.verify(interior) is None:
            interior = self.inc.theta
        return interior

    def _seed(self, root):
        """The root node: OBBT's LP point and basis (full LPs), or a node to solve."""
        if root is not None and root[1] is not None and self.ws is None:
            warm_start(self.relax.lp, root[2])
            self.pending = (max(self.end0, root[0]), self.box0, root[1])
        elif root is not None and self.ws is not None:
            # the OBBT basis belongs to another working set: solve the root from its bound
            self._push(max(self.end0, root[0]), self.box0, None)
        else:
            self._push(self.end0, self.box0, None)

    def _push(self, lb, box, basis):
        heapq.heappush(self.heap, (lb, self.counter, box, basis))
        self.counter += 1

    # ---- the loop -------------------------------------------------------------------
    def run(self):
        """Process nodes until the gap closes or a limit stops the search."""
        while self.heap or self.pending is not None:
            node = self._next()
            if node is _STOP:
                break
            if node is None:
                continue
            lb, box, x, rc = node
            self._show(lb)
            if self._closes(lb):
                continue
            if x is not None and self._try_incumbent(x, box, lb):
                continue
            self._branch(lb, box, x, rc)
        if self.bar is not None:  # the last line shows the gap the end reports
            self.bar.update(min(self.ub, self.top) - self._bound(), self.tol_eff, self.nodes,
                            verified=np.isfinite(self.ub))

    def _closes(self, lb) -> bool:
        """Close a node whose bound is within the tolerance of the incumbent."""
        if lb >= self.ub - self.tol_eff:
            self.closed_lb = min(self.closed_lb, lb)
            return True
        return False

    def _show(self, lb):
        if self.bar is not None:
            lb_now = max(self.end0, min(self.closed_lb, lb,
                                        self.heap[0][0] if self.heap else np.inf))
            self.bar.update(min(self.ub, self.top) - lb_now, self.tol_eff, self.nodes,
                            verified=np.isfinite(self.ub))

    def _next(self):
        """The next node as ``(lb, box, x or None, (bound, reduced costs) or None)``; None
        for a node closed on the way (empty under the cap, LP infeasible); ``_STOP``."""
        if self.pending is not None:
            lb, box, x = self.pending
            self.pending = None
            self.nodes += 1
            self.root_value = self.val(x)
            return lb, box, x, None
        if self.heap[0][0] >= self.ub - self.tol_eff:
            return _STOP
        if self.nodes >= self.max_nodes or time.perf_counter() > self.stop_at:
            self.status = "limit"
            return _STOP
        lb_parent, _, box, basis = heapq.heappop(self.heap)
        if np.isfinite(self.ub):
            # only sense * theta_k <= ub can hold the minimum: cap the box there, which
            # also tightens every McCormick envelope that involves theta_k
            box = _cap(box, self.k, self.sense, self.ub)
            if box is None:
                return None
        return self._solve_node(lb_parent, box, basis)

    def _solve_node(self, lb_parent, box, basis):
        """Solve a node LP (see :meth:`_next`)."""
        relax, ub, tol_eff = self.relax, self.ub, self.tol_eff
        relax.set_box(box)
        if basis is not None:
            relax.lp.restore(basis)  # the parent's basis: one bound away
        # HiGHS stops once its objective passes the cutoff; half the tolerance below the
        # incumbent leaves room for the certified bound to trail HiGHS's own value
        relax.lp.set_cutoff(ub - 0.5 * tol_eff if np.isfinite(ub) else None)
        # every solve of the node (and its working-set re-solves) stops at the search's end
        relax.lp.deadline = wall_stamp(self.stop_at)
        res = _solve(relax, self.pool.screen)
        self.nodes += 1
        self.iters += res.iterations
        if res.status == "cutoff" and not res.bound >= ub - tol_eff:
            # cut off, but the certified bound does not close the node: solve it to the
            # end (a point to branch at) instead of splitting it blindly; a re-solve
            # stopped early keeps the cut-off solve's certified bound
            first = res.bound
            relax.lp.set_cutoff(None)
            res = _solve(relax, self.pool.screen)
            self.iters += res.iterations
            if res.status not in ("optimal", "infeasible") and not res.bound >= first:
                res.bound = first
        if res.refused:
            # HiGHS refused the node LP on every attempt: the node keeps its parent's
            # certified bound and is split without an LP point
            self.refusals.append(res.note)
        if res.status == "infeasible":
            return None
        x = res.x if res.status == "optimal" else None
        if self.nodes == 1 and x is not None:
            self.root_value = res.value
        rc = (res.bound, res.reduced[self.bcols]) if x is not None else None
        return max(lb_parent, res.bound), box, x, rc

    # ---- the incumbent --------------------------------------------------------------
    # ---- branching ------------------------------------------------------------------
    def _branch(self, lb, box, x, rc):
        """Split an open node in two (after reduced-cost tightening of its box)."""
        width = box[:, 1] - box[:, 0]
        if x is not None:
            if rc is not None and np.isfinite(self.ub):
                target = self.ub - self.tol_eff
                box, cut = _reduced_cost_tightening(box, rc[1], rc[0], target)
                if cut:
                    self.closed_lb = min(self.closed_lb, target)
                    width = box[:, 1] - box[:, 0]
            i, split = self._split_at(x, box, width)
        else:
            # no LP point: the widest theta (a shared input error may be in no equation)
            i = self._widest(width)
            split = 0.5 * (box[i, 0] + box[i, 1])
        if width[i] <= self.min_w[i]:
            self.closed_lb = min(self.closed_lb, lb)  # cannot split further: keep its bound
            return
        # children start from this node's basis (a working-set model grows between nodes)
        basis = self.relax.lp.snapshot() \
            if self.ws is None and self.options.parent_basis else None
        for side in (0, 1):
            child = box.copy()
            child[i, 1 - side] = split
            self._push(lb, child, basis)

    def _widest(self, width) -> int:
        p = self.problem.p
        return int(np.argmax(width[:p] / np.maximum(self.width0[:p], 1e-300)))

    def _split_at(self, x, box, width):
        """The branching variable (largest product violation times relative width) and
        the LP point's value, clipped away from the box edges."""
        score = self.relax.violations(x, self.ks) * width / np.maximum(self.width0, 1e-300)
        i = int(np.argmax(score)) if score.max() > 0 else self._widest(width)
        margin = _SPLIT_CLIP * width[i]
        return i, float(np.clip(x[self.bcols[i]], box[i, 0] + margin, box[i, 1] - margin))

    # ---- the result -----------------------------------------------------------------
    def result(self, t0, by_budget) -> EndResult:
        """The certified bound (never below the OBBT box end), the incumbent, a message;
        the progress display, if any, closes saying how the search ended."""
        ub = self.ub
        bound = self._bound()
        elapsed = time.perf_counter() - t0
        status, msg, outcome = self._message(max(ub - bound, 0.0), elapsed, by_budget)
        if self.bar is not None:
            self.bar.close(outcome)
        return EndResult(bound, ub, self.inc, self.nodes, elapsed, status, msg, self.iters,
                         self.root_value)

    def _bound(self) -> float:
        """The certified bound of the end so far (of the closed and open nodes)."""
        open_lb = min((h[0] for h in self.heap), default=np.inf)
        bound = min(self.closed_lb, open_lb, self.ub)
        # monotone knowledge: the OBBT box end is a certified bound as well (a leaf LP
        # that failed, or the root of a search stopped at once, may carry -inf); +inf
        # (every leaf certified infeasible, no verified point) is kept: exact_bounds
        # reports the empty set
        return max(bound, min(self.end0, self.ub))

    def _message(self, gap, elapsed, by_budget):
        """``(status, message, outcome)`` of the end; ``outcome``: how the search ended,
        in a few words for the progress display ("finished", "stopped by the ...")."""
        status, nodes = self.status, self.nodes
        outcome = "finished"
        if status == "limit":
            if nodes >= self.max_nodes:
                why = "the node limit (max_nodes)"
            elif by_budget:
                why = "its share of the total time budget (total_time_limit)"
            else:
                why = "the time limit (time_limit)"
            outcome = f"stopped by {why}"
            msg = (f"stopped by {why} ({nodes} nodes, {elapsed:.1f} s): the bound is a "
                   f"valid outer bound, certified gap {gap:.3g}")
        elif not np.isfinite(self.ub):
            status = "limit"
            outcome = "stopped without a verified-feasible point"
            msg = "no verified-feasible point found: only the outer bound is certified"
        else:
            msg = f"gap {gap:.3g} <= tol after {nodes} nodes ({self.pool.checks} check_theta calls)"
        if self.refusals:
            msg += (f"; {len(self.refusals)} node LP(s) could not be solved and kept their "
                    f"parent's certified bound ({self.refusals[0]})")
        return status, msg, outcome
