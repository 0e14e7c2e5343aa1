"""Branch-and-bound per interval end of the one-record set (after :mod:`.tighten`).

For every parameter of ``[theta, m_l, c_l, m_r, c_r]`` and both senses the exact extreme
over the one-record set (:mod:`.problem`) is bracketed by

* a **certified outer bound**: the smallest certified LP bound (:mod:`.relaxation`) over the
  open leaves of a branch-and-bound tree on the box of ``[theta, gamma, z0]``; the tree
  starts from the leaves of :func:`~.tighten.outer_leaves` (the a priori box cut into
  parts and shrunk by optimality-based bound tightening, OBBT);
* an **inner value**: the parameter at the best point that :func:`~.problem.verify_point`
  accepts (a simulation of the backlash and the fixed-theta LP of stage 2), found by the
  local search of :mod:`.local` from relaxation points.

The search of an end stops when the gap is below ``tol * max(1, |value|)`` (status
``"optimal"``) or at a node/time limit (status ``"limit"``: the outer bound still holds).
"""

from __future__ import annotations

import heapq
import time
from dataclasses import dataclass

import numpy as np

from .local import restore, walk
from .modes import DOWN, HOLD, UP
from .problem import RecordProblem, Witness
from .relaxation import build_relaxation, solve_lp
from .warm import keyed_basis, start_from

__all__ = ["EndResult", "search_end"]

_SPLIT_CLIP = 0.1
# a node with ambiguous samples is split on one of them (decided branches) before its box
SAMPLE = "sample"  # origin of a child split on a sample (no pseudocost)
# steps of the walk of an end's starting point towards the end (measured at N = 300 on the
# chapter's record: 4 steps 124 s, 2 steps 97 s, same nodes and widths; none: slower, the
# branch-and-bound then lacks a good cutoff)
WALK_STEPS = 2
# the local search of an end backs off to at most one search per this many nodes
MAX_SEARCH_SPACING = 64
# ... and takes at most this share of the end's time: a search (restore from a node's LP
# point, up to 8 SLP steps of two LPs) costs several node LPs, and under a time limit the
# nodes are what tighten the certified bound (chapter's record, N = 300, Delta eta = 0.3,
# 4 s per end, one job: 10-69 nodes per end with the searches unlimited, 62-129 without
# them, every outer bound as tight or tighter without; median distance of an outer bound
# to the exact end 0.72 of the interval's width with them, 0.49 without, 0.50 with this
# share)
MAX_SEARCH_SHARE = 0.2
# a child whose LP differs from its parent's (split on a sample's branch) starts from the
# parent's basis carried over by keys (:mod:`.warm`); False: it starts cold
CARRY_BASIS = True


@dataclass
class EndResult:
    """One interval end: certified ``bound`` (an outer bound of ``min sense * v_k``), the
    best verified ``value`` (inf if none) and its witness, nodes, time and status."""

    bound: float
    value: float
    witness: Witness | None
    nodes: int
    seconds: float
    status: str


def _solve(problem, box, col, sense, basis=None, cutoff=None, decisions=None, deadline=None):
    """Certified bound of ``min sense * v_col`` over ``box``, LP point (or None), basis
    (an in-process HiGHS snapshot with the LP's column and row keys: a child whose decided
    samples changed the LP starts from it carried over by :func:`.warm.carry_basis`); the
    LP stops at ``deadline`` (keeping the bound it certifies).

    ``cutoff``: the dual simplex may stop once its certified bound exceeds it (status
    "cutoff", no point): a node that cannot beat the incumbent, or is infeasible, is then
    dropped without solving it to the end or certifying its infeasibility by a ray."""
    rel = build_relaxation(problem, box, decisions=decisions, deadline=deadline)
    lp = rel.lp
    c = np.zeros(lp.c.size)
    c[rel.box_cols[col]] = sense
    lp.set_cost(c)
    lp.set_cutoff(cutoff)  # None or not finite: no cutoff
    if basis is not None:
        start_from(rel, basis, carry=CARRY_BASIS)
    res = solve_lp(lp)
    x = None if res.x is None else res.x[rel.box_cols]
    return res, x, (keyed_basis(rel) if res.status == "optimal" else None), rel


def _children(box, j, x):
    lo, hi = box[j]
    w = hi - lo
    at = 0.5 * (lo + hi) if x is None else float(np.clip(x[j], lo + _SPLIT_CLIP * w,
                                                          hi - _SPLIT_CLIP * w))
    a, b = box.copy(), box.copy()
    a[j, 1] = at
    b[j, 0] = at
    return a, b


def _sample_children(structure, decisions):
    """The decisions of the children of a node split on the branch of its ambiguous sample
    with the widest envelope: it holds, and (where still possible) it moves up or down.
    Every parameter point of the node takes one of them (:class:`~.modes.Decided`)."""
    a = max(structure.ambiguous, key=lambda amb: amb.hi - amb.lo)
    branches = [HOLD] + ([UP] if a.up else []) + ([DOWN] if a.down else [])
    return [{**decisions, a.t: b} for b in branches]


def _cap(box, k, sense, value):
    """``box`` restricted to ``sense * v_k <= value`` (None if empty)."""
    box = box.copy()
    if sense > 0:
        box[k, 1] = min(box[k, 1], value)
    else:
        box[k, 0] = max(box[k, 0], -value)
    return None if box[k, 0] > box[k, 1] else box


class _Incumbent:
    """The best verified point of one end."""

    def __init__(self, problem, k, sense, witness, deadline=None):
        self.problem, self.k, self.sense = problem, k, sense
        self.deadline = deadline  # the walks stop there
        self.witness = None
        self.value = np.inf
        if witness is not None:
            self.offer(witness, walk_it=True)

    def offer(self, w, walk_it=False):
        if w is None:
            return False
        if walk_it:
            w = walk(self.problem, w, self.k, self.sense, max_iter=WALK_STEPS,
                     deadline=self.deadline)
        val = self.sense * float(w.vector[self.k])
        if val < self.value:
            self.value, self.witness = val, w
            return True
        return False


class _Pseudocosts:
    """Average bound gain per split of every variable (both sides), seeded by strong
    branching at the root: the spatial tree splits where splitting has paid (on the
    chapter's record, splitting the backlash never moves the bound of ``b_1``, splitting
    ``a_i`` does)."""

    def __init__(self, n):
        self.sum = np.zeros((n, 2))
        self.cnt = np.zeros((n, 2))

    def add(self, j, side, gain):
        self.sum[j, side] += max(gain, 0.0)
        self.cnt[j, side] += 1

    def choose(self, box, root_w):
        mean = np.where(self.cnt > 0, self.sum / np.maximum(self.cnt, 1), np.nan)
        known = np.nanmean(mean) if np.any(self.cnt > 0) else 1.0
        mean = np.where(np.isnan(mean), known if np.isfinite(known) else 1.0, mean)
        rel = (box[:, 1] - box[:, 0]) / np.maximum(root_w, 1e-300)
        score = np.maximum(mean[:, 0], 1e-12) * np.maximum(mean[:, 1], 1e-12) * rel
        score[rel <= 1e-9] = -1.0
        return int(np.argmax(score))


def _rc_tighten(box, cols_r, bound, target):
    """Reduced-cost bound tightening: the LP bound ``bound`` holds with the term
    ``min(r_j l_j, r_j u_j)`` updated for any sub-box (and the sub-box's McCormick rows are
    tighter still), so the part of ``v_j`` where it exceeds ``target`` is cut. Widened by a
    relative 1e-9 for rounding."""
    slack = target - bound
    if cols_r is None or not (np.isfinite(slack) and slack > 0):
        return box
    box = box.copy()
    with np.errstate(divide="ignore"):
        d = slack / np.abs(cols_r) * (1.0 + 1e-9)
    d = d + 1e-12 * np.maximum(1.0, np.abs(box).max(axis=1))
    up = cols_r > 0
    box[up, 1] = np.minimum(box[up, 1], box[up, 0] + d[up])
    dn = cols_r < 0
    box[dn, 0] = np.maximum(box[dn, 0], box[dn, 1] - d[dn])
    return box


class _EndSearch:
    """Branch-and-bound state of one interval end (``min sense * v_k``)."""

    def __init__(self, problem, leaves, k, sense, start, tol, max_nodes, stop):
        self.pr, self.k, self.sense, self.tol = problem, k, sense, tol
        self.max_nodes, self.stop = max_nodes, stop
        self.deadline = stop if np.isfinite(stop) else None  # for the node LPs
        self.inc = _Incumbent(problem, k, sense, start, self.deadline)
        hull = np.column_stack([np.min([b[:, 0] for b in leaves], axis=0),
                                np.max([b[:, 1] for b in leaves], axis=0)])
        self.root_w = hull[:, 1] - hull[:, 0]
        self.end0 = hull[k, 0] if sense > 0 else -hull[k, 1]
        self.pc = _Pseudocosts(hull.shape[0])
        self.heap, self.count, self.nodes, self.searches = [], 0, 0, 1
        self.spacing, self.next_search = 1, 0
        self.t0, self.search_seconds = time.perf_counter(), 0.0
        self.pruned = np.inf  # smallest certified bound of a node dropped for its bound
        for b in leaves:
            self.push(b[k, 0] if sense > 0 else -b[k, 1], b, None, None, {})

    def gap_tol(self):
        v = self.inc.value
        return self.tol * max(1.0, abs(v)) if np.isfinite(v) else 0.0

    def push(self, bound, box, basis, origin, decisions):
        heapq.heappush(self.heap, (bound, self.count, box, basis, origin, decisions))
        self.count += 1

    def solve(self, box, bound, basis, decisions):
        """Solve a node: (bound, LP point, basis, tightened box) or None if it is dropped."""
        if np.isfinite(self.inc.value):
            box = _cap(box, self.k, self.sense, self.inc.value)
            if box is None:
                return None
        res, x, nb, rel = _solve(self.pr, box, self.k, self.sense, basis,
                                 cutoff=self.inc.value - self.gap_tol(), decisions=decisions,
                                 deadline=self.deadline)
        self.nodes += 1
        if res.status == "infeasible":
            return None
        node_bound = max(bound, res.bound)
        self.local_search(x)
        if node_bound >= self.inc.value - self.gap_tol():
            self.pruned = min(self.pruned, node_bound)
            return None
        r = None if res.reduced is None else res.reduced[rel.box_cols]
        target = self.inc.value - self.gap_tol()
        kept = _rc_tighten(box, r, res.bound, target)
        if not np.array_equal(kept, box):
            # the parts cut off are certified >= target only (not >= the incumbent): the
            # minimum may lie there, below the incumbent (review; as stage 2's closed_lb)
            self.pruned = min(self.pruned, target)
        return node_bound, x, nb, kept, decisions, rel.structure

    def local_search(self, x):
        """A verified point from a node LP point. The searches back off geometrically
        while they find nothing better (the spacing doubles after each miss and returns to
        one node after a hit), and wait while they have taken more than MAX_SEARCH_SHARE of
        the end's time: on the chapter's record at N = 300 the incumbent of an end rarely
        moves after the root, and a search costs several node LPs."""
        if x is None or self.sense * x[self.k] >= self.inc.value - self.gap_tol():
            return
        if self.nodes < self.next_search:
            return
        if self.search_seconds > MAX_SEARCH_SHARE * (time.perf_counter() - self.t0):
            return
        self.searches += 1
        t = time.perf_counter()
        found = self.inc.offer(restore(self.pr, x, self.pr.box, max_iter=8,
                                       deadline=self.deadline))
        self.search_seconds += time.perf_counter() - t
        self.spacing = 1 if found else min(2 * self.spacing, MAX_SEARCH_SPACING)
        self.next_search = self.nodes + self.spacing

    def branch(self, node_bound, x, nb, box, decisions, structure, strong=False):
        """Split the node: on the branch of its most ambiguous sample while it has one
        (:func:`_sample_children`), else on a variable (pseudocosts; at the root, both
        children of every variable are solved first)."""
        if structure.ambiguous:
            for child in _sample_children(structure, decisions):
                self.push(node_bound, box, nb, SAMPLE, child)
            return
        if strong:
            self.strong_branching(node_bound, x, nb, box)
        j = self.pc.choose(box, self.root_w)
        for side, child in enumerate(_children(box, j, x)):
            self.push(node_bound, child, nb, (j, side, node_bound), decisions)

    def strong_branching(self, node_bound, x, nb, box):
        for j in range(box.shape[0]):
            if box[j, 1] - box[j, 0] <= 1e-9 * self.root_w[j]:
                continue
            for side, child in enumerate(_children(box, j, x)):
                res, *_ = _solve(self.pr, child, self.k, self.sense, nb,
                                 deadline=self.deadline)
                gain = np.inf if res.status == "infeasible" else res.bound - node_bound
                self.pc.add(j, side, min(gain, 10 * abs(node_bound) + 1.0))

    def run(self) -> str:
        while self.heap:
            bound, _, box, basis, origin, decisions = self.heap[0]
            if bound >= self.inc.value - self.gap_tol():
                return "optimal"
            if self.nodes >= self.max_nodes or time.time() > self.stop:
                return "limit"
            heapq.heappop(self.heap)
            out = self.solve(box, bound, basis, decisions)
            if isinstance(origin, tuple) and out is not None:
                self.pc.add(origin[0], origin[1], out[0] - origin[2])
            if out is not None:
                self.branch(*out, strong=origin is None)
        return "optimal"

    def outer(self) -> float:
        """Certified bound: the minimum lies in an open node, in a node dropped for its
        bound, or is the incumbent (never below the starting box's end)."""
        heap_min = min((h[0] for h in self.heap), default=np.inf)
        return max(min(heap_min, self.pruned, self.inc.value), self.end0)


def search_end(problem: RecordProblem, leaves, k, sense, start=None, *, tol=1e-4,
               max_nodes=2000, time_limit=None, deadline=None) -> EndResult:
    """Branch-and-bound for ``min sense * v_k`` over the one-record set inside the union of
    ``leaves`` (certified boxes, e.g. from :func:`outer_leaves`, or one box); ``start`` is a
    verified point."""
    t0 = time.time()
    stop = min(t0 + time_limit if time_limit else np.inf, deadline or np.inf)
    if isinstance(leaves, np.ndarray) and leaves.ndim == 2:
        leaves = [leaves]
    srch = _EndSearch(problem, [np.asarray(b, dtype=float) for b in leaves], k, sense,
                      start, tol, max_nodes, stop)
    status = srch.run()
    return EndResult(srch.outer(), srch.inc.value, srch.inc.witness, srch.nodes,
                     time.time() - t0, status)
