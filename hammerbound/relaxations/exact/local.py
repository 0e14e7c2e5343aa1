"""Local search for the inner values of the exact method: sequential linear programming
(SLP) on the bilinear EIV set (22.34), a primal heuristic of the branch-and-bound
(:mod:`.bnb`).

The only non-linear terms of (22.34) are the products ``a_i eta_{t-i}`` and
``b_j dx_var[g]``. Around a verified point ``(theta0, eta0, dx0)`` they are linearised
(``a eta ~ a0 eta + a eta0 - a0 eta0``), which leaves an LP in ``(theta, eta, dx_var)``:
minimise ``sense * theta_k`` inside a trust region ``|theta - theta0| <= rho`` (and the
search box). Its solution is close to the set, not in it (the dropped terms are
``(a - a0)(eta - eta0)``), so it only gives a *direction*: the pool's line search
(:meth:`.points._Pool.line_search`) walks from ``theta0`` towards it and returns the last
point that :func:`.problem.check_theta` accepts. The trust region grows when a step goes
most of the way and shrinks when it does not.

On the chapter's two-level data (N = 300, Delta eta = 0.3) the walk takes 4-12 LPs
(0.06-0.4 s) per interval end, after which no search of the tree finds a point better by
more than the tolerance. Before, 644 line searches towards node LP points, spread over the
whole tree, did that work (17 of 48 s); now the tree only has to prove the bound (8 ends:
39-42 -> 24-25 s on one core, ``python -m benchmarks.exact_ablation``; notes in
``docs/benchmarks.md``).

Nothing here bounds anything: a point is an incumbent only after ``check_theta`` accepts it.
"""

from __future__ import annotations

import time

import numpy as np

from ...solvers.highs_process import limit_run, new_highs, wall_stamp
from ..problem import EIVProblem


def colwise_structure(rows, cols, ncol: int) -> dict:
    """A fixed column-major sparsity pattern for entries ``(rows, cols)`` (duplicates are
    summed): values given in the order of ``rows``/``cols`` are gathered into HiGHS's
    ``value_`` array by :func:`colwise_values` with one ``bincount``."""
    rows = np.asarray(rows)
    cols = np.asarray(cols)
    order = np.lexsort((rows, cols))
    r_s, c_s = rows[order], cols[order]
    new = np.ones(order.size, dtype=bool)
    new[1:] = (r_s[1:] != r_s[:-1]) | (c_s[1:] != c_s[:-1])
    pos = np.cumsum(new) - 1
    return {"pos": pos, "order": order, "nnz": int(pos[-1]) + 1 if pos.size else 0,
            "index": r_s[new].astype(np.int32),
            "start": np.searchsorted(c_s[new], np.arange(ncol + 1)).astype(np.int32)}


def colwise_values(st: dict, vals) -> np.ndarray:
    """The ``value_`` array of :func:`colwise_structure` for entry values ``vals``."""
    return np.bincount(st["pos"], weights=np.asarray(vals)[st["order"]], minlength=st["nnz"])


def solve_colwise(h, st: dict, vals, cost, col_lo, col_hi, row_lo, row_hi, basis=None, *,
                  deadline=None):
    """Pass the LP ``min cost'z, row_lo <= A z <= row_hi, col_lo <= z <= col_hi`` with ``A``
    of the pattern ``st`` (:func:`colwise_structure`) and entry values ``vals`` to the HiGHS
    instance ``h``, warm-start it from ``basis`` (same pattern) and solve, stopping at
    ``deadline`` (:func:`time.time` stamp) or after
    :data:`~hammerbound.solvers.highs_process.RUN_TIME_LIMIT` s. Returns the new basis, or None
    when the LP is not solved to optimality (stopped ones included)."""
    import highspy as hs

    lp = hs.HighsLp()
    lp.num_col_, lp.num_row_ = len(cost), len(row_lo)
    lp.col_cost_ = cost
    lp.col_lower_, lp.col_upper_ = col_lo, col_hi
    lp.row_lower_, lp.row_upper_ = row_lo, row_hi
    lp.a_matrix_.format_ = hs.MatrixFormat.kColwise
    lp.a_matrix_.start_ = st["start"]
    lp.a_matrix_.index_ = st["index"]
    lp.a_matrix_.value_ = colwise_values(st, vals)
    h.passModel(lp)
    if basis is not None:
        h.setBasis(basis)
    limit_run(h, deadline=deadline)
    h.run()
    if h.getModelStatus() != hs.HighsModelStatus.kOptimal:
        return None
    return h.getBasis()


class LinearisedSet:
    """The LP of one SLP step (see the module docstring), kept on one HiGHS instance and
    warm-started from the previous step's basis (the sparsity never changes).

    Columns ``[theta (p), eta (N), dx_var (K)]``; rows: the linearised equations of (22.34),
    then the gain equality (if any). ``elastic=True`` (restoration, :func:`restore`) adds a
    column ``s >= 0`` and asks only ``|linearised residual_t| <= s``, minimising ``s``.
    """

    def __init__(self, problem: EIVProblem, elastic: bool = False):
        import highspy

        pr = problem
        self.problem = pr
        self._hs = highspy
        p, n, k, na = pr.p, pr.N, pr.n_groups, pr.na
        t = pr.equation_times
        m = t.size
        self.m = m
        self.eta_idx = pr.eta_index()  # (m, na + 1): t, t-1, ..
        self.dx_idx = pr.dx_index()  # (m, nbp)
        self.y_lag = pr.y[self.eta_idx[:, 1:]]  # (m, na)
        self.x_lag = pr.x[t[:, None] - pr.b_lags[None, :]]  # (m, nbp)
        self.yt = pr.y[t]
        nbp = self.dx_idx.shape[1]
        loc = np.arange(m)
        rows = np.concatenate([np.repeat(loc, na), np.repeat(loc, nbp),  # a, b
                               np.repeat(loc, na + 1),  # eta_t, eta_{t-i}
                               np.repeat(loc, nbp)])  # dx_var
        cols = np.concatenate([np.tile(np.arange(na), m), na + np.tile(np.arange(nbp), m),
                               p + self.eta_idx.ravel(), p + n + self.dx_idx.ravel()])
        self.elastic = bool(elastic)
        self.ncol = p + n + k + self.elastic
        self.neq = m * (1 + self.elastic)
        if self.elastic:
            # rows lin_t - s <= rhs_t (first m) and lin_t + s >= rhs_t (next m)
            s_col = np.full(2 * m, p + n + k)
            rows = np.concatenate([rows, rows + m, loc, loc + m])
            cols = np.concatenate([cols, cols, s_col])
        self.gain = pr.gain_row()
        if self.gain is not None:
            rows = np.concatenate([rows, np.full(p, self.neq)])
            cols = np.concatenate([cols, np.arange(p)])
        self.st = colwise_structure(rows, cols, self.ncol)
        self.nrow = self.neq + (self.gain is not None)
        self.err_lo = np.concatenate([-pr.deta, -pr.dx_group, [0.0] * self.elastic])
        self.err_hi = np.concatenate([pr.deta, pr.dx_group, [highspy.kHighsInf] * self.elastic])
        self.h = new_highs({"primal_feasibility_tolerance": 1e-10} if self.elastic else None)
        self.basis = None
        self.solves = 0
        #: :func:`time.time` stamp at which a solve stops (None: only the run limit)
        self.deadline = None

    def solve(self, theta0, eta0, dx0, k: int, sense: float, lo, hi):
        """``argmin sense * theta_k`` over the set linearised at ``(theta0, eta0, dx0)``
        with ``lo <= theta <= hi`` (elastic: ``argmin s``, ``k`` and ``sense`` unused);
        returns ``(theta (p,), eta (N,), dx_var (K,))`` or None."""
        hs = self._hs
        pr = self.problem
        na, n, p = pr.na, pr.N, pr.p
        a0, b0 = theta0[:na], theta0[na:]
        m = self.m
        vals = np.concatenate([(self.y_lag - eta0[self.eta_idx[:, 1:]]).ravel(),
                               (dx0[self.dx_idx] - self.x_lag).ravel(),
                               np.tile(np.concatenate([[-1.0], -a0]), m),
                               np.tile(b0, m)])
        rhs = -self.yt - eta0[self.eta_idx[:, 1:]] @ a0 + dx0[self.dx_idx] @ b0
        cost = np.zeros(self.ncol)
        inf = hs.kHighsInf
        if self.elastic:
            vals = np.concatenate([vals, vals, -np.ones(m), np.ones(m)])
            row_lo = np.concatenate([np.full(m, -inf), rhs])
            row_hi = np.concatenate([rhs, np.full(m, inf)])
            cost[-1] = 1.0
        else:
            row_lo = row_hi = rhs
            cost[k] = sense
        if self.gain is not None:
            vals = np.concatenate([vals, self.gain[0]])
            row_lo = np.concatenate([row_lo, [self.gain[1]]])
            row_hi = np.concatenate([row_hi, [self.gain[1]]])
        self.basis = solve_colwise(self.h, self.st, vals, cost,
                                   np.concatenate([lo, self.err_lo]),
                                   np.concatenate([hi, self.err_hi]), row_lo, row_hi,
                                   self.basis, deadline=self.deadline)
        self.solves += 1
        if self.basis is None:
            return None
        z = np.asarray(self.h.getSolution().col_value)
        return z[:p].copy(), z[p : p + n].copy(), z[p + n : p + n + pr.n_groups].copy()


def improve(pool, start, k: int, sense: float, box, resolution: float, *,
            max_lps: int = 40, stop_at: float | None = None, rho0: float = 0.2):
    """Walk a verified point ``start`` (a :class:`.points._Point`) towards the minimum of
    ``sense * theta_k`` over the EIV set by SLP steps inside ``box`` (p, 2).

    Stops when a step promises less than ``resolution``, after ``max_lps`` LPs, or at
    ``stop_at`` (:func:`time.perf_counter`). Returns the best verified point (``start`` if
    nothing better was found); every point returned has passed ``check_theta``.
    """
    if pool.local is None:
        pool.local = LinearisedSet(pool.problem)
    lin = pool.local
    box = np.asarray(box, dtype=float)[: pool.problem.p]
    width = box[:, 1] - box[:, 0]
    rho = rho0 * width
    floor = 1e-6 * width
    best = start
    lin.deadline = wall_stamp(stop_at)
    for _ in range(max_lps):
        if stop_at is not None and time.perf_counter() > stop_at:
            break
        th0 = best.theta
        out = lin.solve(th0, best.eta, best.dx, k, sense, np.maximum(th0 - rho, box[:, 0]),
                        np.minimum(th0 + rho, box[:, 1]))
        if out is None:
            rho = 0.5 * rho
            if np.all(rho < floor):
                break
            continue
        cand = out[0]
        promised = sense * (th0[k] - cand[k])
        if promised < resolution:
            break
        new = pool.add(cand)
        if new is None:
            new = pool.line_search(th0, cand, k=k, resolution=0.25 * resolution)
        moved = -np.inf if new is None else sense * (th0[k] - new.theta[k])
        if moved > 0:
            best = new
        if moved > 0.5 * promised:
            rho = np.minimum(2.0 * rho, width)
        elif moved < 0.1 * promised:
            rho = 0.5 * rho
            if np.all(rho < floor):
                break
    return best


def restore(pool, starts, box, *, max_lps: int = 12, stop_at: float | None = None):
    """Gauss-Newton on (22.34) from unverified points (e.g. a relaxation's LP points):
    from each start ``(theta0, eta0, dx0)`` in turn, each step minimises the largest
    linearised residual ``s`` (elastic LP) inside ``box`` and re-linearises at the
    solution, until :func:`.problem.check_theta` accepts a step's theta (at most
    ``max_lps`` steps per start). Returns the verified point or None.

    For sets too thin for any relaxation point to be feasible -- noise exactly at its bound
    on every sample makes the set a single point, as in stage 1 -- the steps converge
    quadratically to it, where the tree's points never get within the acceptance
    tolerance (1e-9 of the equation terms).
    """
    pr = pool.problem
    lin = LinearisedSet(pr, elastic=True)
    box = np.asarray(box, dtype=float)[: pr.p]
    for theta0, eta0, dx0 in starts:
        th = np.clip(np.asarray(theta0, dtype=float), box[:, 0], box[:, 1])
        eta = np.clip(np.asarray(eta0, dtype=float), -pr.deta, pr.deta)
        dxv = np.clip(np.asarray(dx0, dtype=float), -pr.dx_group, pr.dx_group)
        for _ in range(max_lps):
            if stop_at is not None:
                if time.perf_counter() >= stop_at:
                    return None
                # a degenerate elastic LP can otherwise take minutes past stop_at
                lin.deadline = wall_stamp(stop_at)
            out = lin.solve(th, eta, dxv, 0, 1.0, box[:, 0], box[:, 1])
            if out is None:
                break
            th, eta, dxv = out
            pt = pool.add(th)
            if pt is not None:
                return pt
    return None


def restore_near(pool, start, box, radius: float, *, max_lps: int = 4,
                 stop_at: float | None = None):
    """:func:`restore` from one unverified point ``start = (theta0, eta0, dx0)`` inside
    ``box`` (p, 2) narrowed to ``|theta - theta0| <= radius * max(1, |theta0|)``.

    For a node LP point at which the McCormick relaxation is exact (every product holds to
    rounding) but that :func:`.problem.check_theta` rejects: the set is thin there, and the
    point misses it by the LP solver's feasibility tolerance. The chapter's two-level data
    at N = 30 (``b1`` lower end) had such a point ``2e-4`` below the best verified value
    that line searches never improved: 20000 nodes without closing the gap, against 18
    nodes with this step. Restricting the steps to a small box keeps them near the point
    (unrestricted, they converged to the incumbent). Returns the verified point or None.
    """
    theta0 = np.asarray(start[0], dtype=float)
    near = radius * np.maximum(1.0, np.abs(theta0))
    box = np.asarray(box, dtype=float)
    rbox = np.column_stack([np.maximum(box[:, 0], theta0 - near),
                            np.minimum(box[:, 1], theta0 + near)])
    if np.any(rbox[:, 0] > rbox[:, 1]):
        return None
    return restore(pool, [start], rbox, max_lps=max_lps, stop_at=stop_at)


#: Relative margin by which :func:`polish` keeps witnesses inside the error bounds, and the
#: (relative) box around a witness it may move it in.
POLISH_MARGIN = 2e-8
POLISH_RADIUS = 1e-7


def polish(problem: EIVProblem, points, *, margin: float = POLISH_MARGIN,
           radius: float = POLISH_RADIUS, keep=None):
    """Move verified points (:class:`.points._Point`, or None) slightly into the set.

    A witness accepted by :func:`.problem.check_theta` satisfies (22.34) only to the
    acceptance tolerance (``1e-9`` of the equations' terms), which an independent check
    reads as error bounds widened by up to ``1e-9 * terms / error terms`` (``5e-7`` of
    ``Delta eta`` measured at ``Delta eta = 0.005``). One Gauss-Newton step from the witness
    (:class:`LinearisedSet`, elastic) on the error bounds shrunk by ``margin``, inside
    ``|theta - theta0| <= radius * max(1, |theta0|)``, gives a point whose errors keep that
    margin; it replaces the witness if ``check_theta`` accepts it. Where the set has no
    such point nearby (a single point: noise exactly at the bound on every sample of a
    two-level record), the step is taken on the bounds as given instead and kept only if
    its residuals are smaller than the witness's. Returns the list of (possibly) polished
    points; ``theta`` moves by at most ``radius`` (relative).

    ``keep``, optional, one ``(k, sense, slack)`` per point: ``sense * theta_k`` may grow by
    at most ``slack`` (an interval end's witness value stays within its tolerance).
    """
    import dataclasses

    from ..problem import check_theta
    from .points import _Point

    points = list(points)
    if not any(pt is not None for pt in points):
        return points
    shrunk = dataclasses.replace(problem, output_bound=problem.deta * (1.0 - margin),
                                 input_bound=problem.dx * (1.0 - margin))
    lins = [LinearisedSet(shrunk, elastic=True), None]
    inside = 0.1 * margin * float(np.min(problem.deta))  # residual of a point inside
    out = []
    for j, pt in enumerate(points):
        if pt is None:
            out.append(None)
            continue
        th0 = np.asarray(pt.theta, dtype=float)
        near = radius * np.maximum(1.0, np.abs(th0))
        lo = np.maximum(problem.theta_box[:, 0], th0 - near)
        hi = np.minimum(problem.theta_box[:, 1], th0 + near)
        if keep is not None:
            k, sense, slack = keep[j]
            if sense > 0:
                hi[k] = min(hi[k], th0[k] + max(slack, 0.0))
            else:
                lo[k] = max(lo[k], th0[k] - max(slack, 0.0))
        best = pt
        for i in range(2):
            if lins[i] is None:
                lins[i] = LinearisedSet(problem, elastic=True)
            step = lins[i].solve(th0, pt.eta, pt.dx, 0, 1.0, lo, hi)
            if step is None:
                continue
            if i == 0 and lins[0].h.getInfo().objective_function_value > inside:
                continue  # no point of the shrunk set next to the witness
            chk = check_theta(problem, step[0], witness=step[1:])
            if i == 1:
                ref = check_theta(problem, th0, witness=(pt.eta, pt.dx))
                if not (chk.feasible and chk.max_rel_violation < ref.max_rel_violation):
                    break
            if chk.feasible:
                best = _Point(step[0], chk.eta, chk.dx)
            break
        out.append(best)
    return out
