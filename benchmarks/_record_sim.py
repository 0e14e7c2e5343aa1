"""The one-record benchmarks' own simulator and witness check (independent of the package).

Nothing here imports hammerbound: the truths are simulated by this file's play operator and
linear recursion, and a witness is accepted only if this file's simulation of its backlash
and an independent LP (scipy's HiGHS) find a noise sequence that explains the record.

The chapter's system (section 22.5): backlash ``m_l = 0.25, c_l = 0.0628, m_r = 0.26,
c_r = 0.0489``; ``A = 1 - 0.76 q^-1 + 0.82 q^-2``, ``B = 2.15 q^-1 - 1.09 q^-2`` (unit
steady-state gain (22.8): ``B(1) = A(1) = 1.06``).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog
from scipy.sparse import coo_matrix, vstack

GAMMA = np.array([0.25, 0.0628, 0.26, 0.0489])
A = np.array([1.0, -0.76, 0.82])
B = np.array([0.0, 2.15, -1.09])
THETA = np.array([-0.76, 0.82, 2.15, -1.09])  # a1, a2, b1, b2 (nk = 1)
#: a witness's noise may exceed the bound by at most this (absolute; outputs are O(1))
WITNESS_TOL = 1e-7


def play(u, ml, cl, mr, cr, x0=0.0):
    """x_t = min(max(x_{t-1}, m_r (u_t - c_r)), m_l (u_t + c_l)) from x_{-1} = x0."""
    x, out = float(x0), np.empty(len(u))
    for t, v in enumerate(np.asarray(u, dtype=float)):
        x = min(max(x, mr * (v - cr)), ml * (v + cl))
        out[t] = x
    return out


def linear(x, a=A, b=B):
    """w_t = -sum_i a_i w_{t-i} + sum_j b_j x_{t-j}, from rest (own recursion)."""
    w = np.zeros(len(x))
    for t in range(len(x)):
        s = sum(b[j] * x[t - j] for j in range(len(b)) if t - j >= 0)
        s -= sum(a[i] * w[t - i] for i in range(1, len(a)) if t - i >= 0)
        w[t] = s
    return w


# ------------------------------------------------------------------ inputs
def random_steps(N, rng, lo=-2.0, hi=2.0, hold=(3, 20)):
    u = []
    while len(u) < N:
        u += [rng.uniform(lo, hi)] * int(rng.integers(hold[0], hold[1] + 1))
    return np.array(u[:N])


def sine_sweep(N, rng, amp=2.0):
    """A chirp from 0.005 to 0.055 cycles per sample, random phase."""
    t = np.arange(N)
    return amp * np.sin(2 * np.pi * t * (0.005 + 0.025 * t / N) + rng.uniform(0, 2 * np.pi))


def multilevel_prbs(N, rng, levels=(-2.0, -1.0, -0.3, 0.3, 1.0, 2.0), p_switch=0.25):
    """A new random level (of ``levels``) with probability ``p_switch`` each sample."""
    u = np.empty(N)
    cur = rng.choice(levels)
    for t in range(N):
        if t > 0 and rng.random() < p_switch:
            cur = rng.choice(levels)
        u[t] = cur
    return u


SIGNALS = {"steps": random_steps, "sine": sine_sweep, "prbs": multilevel_prbs}


def record(signal, N, deta, noise, seed):
    """(u, y) of the chapter system: noise "uniform" in +-deta or "bound" (+-deta, random
    signs); the backlash starts at x = 0."""
    rng = np.random.default_rng(seed)
    u = SIGNALS[signal](N, rng)
    w = linear(play(u, *GAMMA))
    if noise == "uniform":
        eta = rng.uniform(-deta, deta, N)
    elif noise == "bound":
        eta = deta * rng.choice([-1.0, 1.0], N)
    else:
        raise ValueError(noise)
    return u, w + eta


# ------------------------------------------------------------------ witnesses
def noise_excess(u, y, deta, theta, gamma, z0, na=2, lags=(1, 2)):
    """Smallest ``s`` such that some noise ``|eta_t| <= deta + s`` makes every equation
    ``(y_t - eta_t) + sum a_i (y_{t-i} - eta_{t-i}) = sum b_j x_{t-j}`` (t >= n0) exact,
    with ``x`` this file's play operator from ``x_0 = z0`` (the first sample's state).
    ``inf`` when the backlash point is not admissible (m <= 0, ``z0`` outside ``[R_0,
    L_0]``, lines crossing on the record) or the LP fails."""
    ml, cl, mr, cr = (float(v) for v in gamma)
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    if ml <= 0 or mr <= 0 or not (mr * (u[0] - cr) - 1e-12 <= z0 <= ml * (u[0] + cl) + 1e-12):
        return np.inf
    if np.any(ml * (u + cl) < mr * (u - cr)):
        return np.inf
    x = np.empty(u.size)
    x[0] = z0
    x[1:] = play(u[1:], ml, cl, mr, cr, x0=z0)
    a, b = np.asarray(theta[:na], float), np.asarray(theta[na:], float)
    N = u.size
    n0 = max(na, max(lags))
    rows, cols, vals, rhs = [], [], [], []
    for r, t in enumerate(range(n0, N)):
        rows.append(r), cols.append(t), vals.append(1.0)
        val = y[t]
        for i in range(1, na + 1):
            rows.append(r), cols.append(t - i), vals.append(a[i - 1])
            val += a[i - 1] * y[t - i]
        for j, lag in enumerate(lags):
            val -= b[j] * x[t - lag]
        rhs.append(val)
    m = N - n0
    E = coo_matrix((vals, (rows, cols)), shape=(m, N + 1)).tocsr()
    # |eta_t| <= deta + s  <=>  eta_t - s <= deta, -eta_t - s <= deta
    eye = coo_matrix((np.ones(N), (np.arange(N), np.arange(N))), shape=(N, N + 1))
    s_col = coo_matrix((-np.ones(N), (np.arange(N), np.full(N, N))), shape=(N, N + 1))
    A_ub = vstack([eye + s_col, -eye + s_col]).tocsr()
    b_ub = np.full(2 * N, float(deta))
    c = np.zeros(N + 1)
    c[N] = 1.0
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=E, b_eq=np.asarray(rhs),
                  bounds=[(None, None)] * N + [(None, None)], method="highs")
    return float(res.x[N]) if res.status == 0 else np.inf


def gain_error(theta, na=2):
    """|B(1) / A(1) - 1| (the unit-gain normalisation (22.8))."""
    a1 = 1.0 + float(np.sum(theta[:na]))
    return abs(float(np.sum(theta[na:])) / a1 - 1.0)
