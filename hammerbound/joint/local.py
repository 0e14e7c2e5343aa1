"""Verified points of the one-record set by sequential linear programming (SLP).

At a point ``v = [theta, m_l, c_l, m_r, c_r, z0]`` the play operator fixes every sample's
branch (:func:`~.modes.branch_forms`). With the branches fixed, the inner signal is a
smooth (bilinear) function of ``gamma, z0`` and each equation of :mod:`.problem` a smooth
function of ``(v, eta)``; the branches stay valid while a few smooth inequalities hold
(the sample that moved up is above its previous state, ...). Linearising all of them at
the point gives an LP in ``(dv, eta)``:

* :func:`restore` minimises the largest scaled equation violation inside a trust region
  (Gauss-Newton in the max norm): from a relaxation point near the set it reaches a point
  that :func:`~.problem.verify_point` accepts, also when the set is (nearly) one point;
* :func:`walk` minimises ``sense * v_k`` with the linearised equations held, then restores:
  it moves a verified point towards the end of its interval.

Nothing here bounds anything: a point counts only once :func:`~.problem.verify_point` has
accepted it (an independent simulation and the fixed-theta LP of stage 2).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

from ..solvers.highs_process import past, seconds_left
from ..tolerances import FEASIBILITY_RTOL
from .modes import INIT, LEFT, RIGHT, branch_forms
from .problem import RecordProblem, Witness, verify_point

__all__ = ["restore", "walk"]

# a step's LP that HiGHS has not solved by then counts as a failed step (the trust region
# shrinks): seen at N = 300, one step's LP ran for minutes inside the starting pool
STEP_LP_LIMIT = 5.0


def _lp_options(deadline):
    """scipy/HiGHS options of a step's LP: at most STEP_LP_LIMIT s, and no later than
    ``deadline`` (a :func:`time.time` stamp)."""
    return {"time_limit": seconds_left(STEP_LP_LIMIT, deadline)}


class _Linearised:
    """Residuals, Jacobian and branch inequalities at a point, branches fixed."""

    def __init__(self, problem: RecordProblem, v, eta):
        self.pr = problem
        self.v = np.asarray(v, dtype=float)
        self.eta = np.asarray(eta, dtype=float)
        p = problem.p
        ml, cl, mr, cr, z0 = self.v[p:]
        u = problem.u
        kind, src = branch_forms(u, ml, cl, mr, cr, z0)
        self.kind, self.src = kind, src
        # value of every inner sample and its gradient w.r.t. (ml, cl, mr, cr, z0)
        us = np.where(src >= 0, u[np.maximum(src, 0)], 0.0)
        X = np.where(kind == RIGHT, mr * (us - cr), np.where(kind == LEFT, ml * (us + cl), z0))
        G = np.zeros((u.size, 5))
        left, right, ini = kind == LEFT, kind == RIGHT, kind == INIT
        G[left, 0], G[left, 1] = us[left] + cl, ml
        G[right, 2], G[right, 3] = us[right] - cr, -mr
        G[ini, 4] = 1.0
        self.X, self.G = X, G

    def equations(self):
        """Residuals F (n_eq,), Jacobians w.r.t. v (n_eq, p+5) and eta (sparse n_eq x N),
        and the scale of every equation."""
        pr, v, eta = self.pr, self.v, self.eta
        na, p = pr.na, pr.p
        t = np.arange(pr.n0, pr.N)
        a, b = v[:na], v[na:p]
        y = pr.y
        F = y[t] - eta[t]
        Jv = np.zeros((t.size, p + 5))
        rows, cols, vals = [np.arange(t.size)], [t], [-np.ones(t.size)]
        scale = np.abs(y[t]) + pr.deta[t]
        for i in range(1, na + 1):
            F = F + a[i - 1] * (y[t - i] - eta[t - i])
            Jv[:, i - 1] = y[t - i] - eta[t - i]
            rows.append(np.arange(t.size))
            cols.append(t - i)
            vals.append(-a[i - 1] * np.ones(t.size))
            scale = scale + abs(a[i - 1]) * (np.abs(y[t - i]) + pr.deta[t - i])
        for jpos, lag in enumerate(pr.b_lags):
            s = t - lag
            F = F - b[jpos] * self.X[s]
            Jv[:, na + jpos] = -self.X[s]
            Jv[:, p:] -= b[jpos] * self.G[s]
            scale = scale + abs(b[jpos]) * np.abs(self.X[s])
        Je = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                           shape=(t.size, pr.N))
        return F, Jv, Je, scale

    def branch_rows(self):
        """Inequalities ``h + H dv >= 0`` (rows over v) that keep the branches valid."""
        pr, v = self.pr, self.v
        p, u = pr.p, pr.u
        ml, cl, mr, cr, z0 = v[p:]
        hs, Hs = [], []

        def line(kind, s):  # value and gradient of a line at input u_s
            g = np.zeros(p + 5)
            if kind == RIGHT:
                g[p + 2], g[p + 3] = u[s] - cr, -mr
                return mr * (u[s] - cr), g
            g[p], g[p + 1] = u[s] + cl, ml
            return ml * (u[s] + cl), g

        def state(t):
            if self.kind[t] == INIT:
                g = np.zeros(p + 5)
                g[p + 4] = 1.0
                return z0, g
            return line(self.kind[t], self.src[t])

        def geq(a, b):  # a - b >= 0
            hs.append(a[0] - b[0])
            Hs.append(a[1] - b[1])

        geq(state(0), line(RIGHT, 0))
        geq(line(LEFT, 0), state(0))
        for t in np.flatnonzero(np.diff(u) != 0) + 1:
            prev, cur = state(t - 1), state(t)
            if self.kind[t] == RIGHT and self.src[t] == t:
                geq(cur, prev)
            elif self.kind[t] == LEFT and self.src[t] == t:
                geq(prev, cur)
            else:
                geq(prev, line(RIGHT, t))
                geq(line(LEFT, t), prev)
        for s in (int(np.argmin(u)), int(np.argmax(u))):
            geq(line(LEFT, s), line(RIGHT, s))
        return np.array(hs), np.array(Hs)


def _step(lin: _Linearised, box, rho, objective=None, rho_eta=None, deadline=None):
    """One SLP step. Without ``objective``: the smallest step (scaled L1 norm) among those
    that minimise the largest scaled linearised violation (two LPs: a minimum-norm
    Gauss-Newton step in the max norm, which converges fast where the first LP alone jumps
    between vertices of its optimal face). With ``objective = (k, sense)``: minimise
    ``sense * v_k`` with the violations held at the current level. ``rho`` (and
    ``rho_eta``) bound the step of ``v`` (and of ``eta``: the products ``a_i eta`` make a
    large noise step as wrong as a large parameter step). Returns ``(v, eta)`` or None."""
    pr = lin.pr
    F, Jv, Je, scale = lin.equations()
    hb, Hb = lin.branch_rows()
    nv, N, m = Jv.shape[1], pr.N, F.size
    # rows in units of the current largest violation, so that HiGHS's absolute feasibility
    # tolerance (1e-7) acts relative to it and the steps go on below it -- down to the
    # relative feasibility tolerance of the package: below it, rows scaled by 1/cur reached
    # 1e13 and HiGHS ran each such LP into its time limit (N = 300, Delta eta = 0.05: 11
    # LPs of the starting pool took 5 s each, 55 of its 59 s)
    cur = float(np.max(np.abs(F) / scale)) if m else 0.0
    s = 1.0 / (scale * max(cur, FEASIBILITY_RTOL))
    # variables [dv (nv), eta (N), tau, |dv| (nv), |eta - eta0| (N)]
    Jn = sp.hstack([sp.csr_matrix(Jv * s[:, None]), sp.diags(s) @ Je]).tocsr()
    # linearised residual: F + Jv dv + Je (eta - eta0) = F - Je eta0 + [Jv Je] [dv; eta]
    r0 = (F - Je @ lin.eta) * s
    tau_col = -np.ones((m, 1))
    zero_abs = sp.csr_matrix((m, nv + N))
    eye_v, eye_e = sp.eye(nv, format="csr"), sp.eye(N, format="csr")
    z = sp.csr_matrix
    A_ub = sp.vstack([
        sp.hstack([Jn, tau_col, zero_abs]),
        sp.hstack([-Jn, tau_col, zero_abs]),
        sp.hstack([z(-Hb), z((hb.size, N + 1 + nv + N))]),
        sp.hstack([eye_v, z((nv, N + 1)), -eye_v, z((nv, N))]),
        sp.hstack([-eye_v, z((nv, N + 1)), -eye_v, z((nv, N))]),
        sp.hstack([z((N, nv)), eye_e, z((N, 1 + nv)), -eye_e]),
        sp.hstack([z((N, nv)), -eye_e, z((N, 1 + nv)), -eye_e]),
    ]).tocsr()
    b_ub = np.concatenate([-r0, r0, hb, np.zeros(nv), np.zeros(nv), lin.eta, -lin.eta])
    lo_v = np.maximum(box[:, 0] - lin.v, -rho)
    hi_v = np.minimum(box[:, 1] - lin.v, rho)
    e_lo, e_hi = -pr.deta, pr.deta
    if rho_eta is not None:
        e_lo = np.maximum(e_lo, lin.eta - rho_eta)
        e_hi = np.minimum(e_hi, lin.eta + rho_eta)
    bounds = np.vstack([np.column_stack([lo_v, hi_v]), np.column_stack([e_lo, e_hi]),
                        [[0.0, np.inf]], np.column_stack([np.zeros(nv + N),
                                                          np.full(nv + N, np.inf)])])
    # the gain equality (22.8), linear in v: sum b_j - g sum a_i = g
    g = float(pr.gain)
    grow = np.zeros(2 * (nv + N) + 1)
    grow[: pr.na] = -g
    grow[pr.na: pr.p] = 1.0
    A_eq = grow[None, :]
    b_eq = np.array([g - float(grow[: pr.p] @ lin.v[: pr.p])])
    c = np.zeros(2 * (nv + N) + 1)
    if objective is None:
        c[nv + N] = 1.0
        res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=bounds,
                      method="highs", options=_lp_options(deadline))
        if res.status != 0:
            return None
        tau = float(res.x[nv + N])
        bounds[nv + N] = [0.0, tau * (1 + 1e-9) + 1e-16]
        c[:] = 0.0
        ref = np.maximum(np.abs(lin.v), 1e-3 * np.maximum(box[:, 1] - box[:, 0], 1e-300))
        c[nv + N + 1: 2 * nv + N + 1] = 1.0 / ref
        c[2 * nv + N + 1:] = 1.0 / pr.deta
    else:
        k, sense = objective
        c[k] = sense
        bounds[nv + N] = [0.0, 1.0]  # violations held at the current level
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=bounds,
                  method="highs", options=_lp_options(deadline))
    if res.status != 0:
        return None
    return lin.v + res.x[:nv], np.clip(res.x[nv: nv + N], -pr.deta, pr.deta)


def _initial_eta(problem, v):
    """A noise sequence to linearise around: the stage-2 fixed-theta LP's witness (or 0)."""
    from ..exceptions import SolverError
    from ..relaxations.problem import check_theta

    p = problem.p
    x = _clamped_play(problem, v)
    try:
        chk = check_theta(problem.eiv_problem(x), v[:p])
    except SolverError:  # HiGHS could not decide that LP (e.g. far-off values): start at 0
        return np.zeros(problem.N)
    return chk.eta


def _clamped_play(problem, v):
    from .modes import play

    p = problem.p
    ml, cl, mr, cr, z0 = v[p:]
    u0 = problem.u[0]
    z0 = min(max(z0, mr * (u0 - cr)), ml * (u0 + cl))
    return play(problem.u, ml, cl, mr, cr, z0)


def _violation(problem, v, eta):
    """Largest scaled equation violation at ``(v, eta)`` (branches of ``v``)."""
    F, _, _, scale = _Linearised(problem, v, eta).equations()
    return float(np.max(np.abs(F) / scale)) if F.size else 0.0


def restore(problem: RecordProblem, v, box=None, *, max_iter=20, rho=None,
            deadline=None) -> Witness | None:
    """A verified point near ``v`` (Gauss-Newton steps in the max norm with an adaptive
    trust region), or None."""
    box = problem.box if box is None else np.asarray(box, dtype=float)
    v = np.clip(np.asarray(v, dtype=float), box[:, 0], box[:, 1])
    w = verify_point(problem, v)
    if w is not None:
        return w
    width = np.maximum(box[:, 1] - box[:, 0], 1e-300)
    ref = np.maximum(np.abs(v), 1e-3 * width)
    f = 1e-2 if rho is None else float(np.max(rho / ref))
    eta = _initial_eta(problem, v)
    viol = _violation(problem, v, eta)
    for _ in range(max_iter):
        if past(deadline):
            return None
        rho = f * ref
        try:
            step = _step(_Linearised(problem, v, eta), box, rho, rho_eta=f * problem.deta,
                         deadline=deadline)
        except (ValueError, FloatingPointError):
            return None
        if step is None:
            f = 0.25 * f
            continue
        v_new = np.clip(step[0], box[:, 0], box[:, 1])
        viol_new = _violation(problem, v_new, step[1])
        if viol_new < viol:
            v, eta, viol = v_new, step[1], viol_new
            w = verify_point(problem, v)
            if w is not None:
                return w
            f = min(2.0 * f, 1.0)
        else:
            f = 0.25 * f
        if f < 1e-12:
            return None
    return None


def walk(problem: RecordProblem, witness: Witness, k: int, sense: float, box=None, *,
         max_iter=4, deadline=None) -> Witness:
    """Move a verified point towards ``min sense * v_k``; returns the best verified point."""
    box = problem.box if box is None else np.asarray(box, dtype=float)
    best = witness
    rho = 0.1 * np.maximum(box[:, 1] - box[:, 0], 1e-12)
    for _ in range(max_iter):
        if past(deadline):
            break
        v0 = best.vector
        try:
            step = _step(_Linearised(problem, v0, best.eta), box, rho, objective=(k, sense),
                         deadline=deadline)
        except (ValueError, FloatingPointError):
            break
        if step is None:
            break
        v_new, _ = step
        cand = restore(problem, np.clip(v_new, box[:, 0], box[:, 1]), box, max_iter=6,
                       deadline=deadline)
        if cand is not None and sense * cand.vector[k] < sense * v0[k] - 1e-15 * (1 + abs(v0[k])):
            best = cand
            rho = rho * 2.0
        else:
            rho = rho * 0.25
            if np.all(rho < 1e-10 * np.maximum(1.0, np.abs(v0))):
                break
    return best
