"""The tests' independent oracles: what the package is checked against.

Nothing here imports hammerbound. Every function is written from the chapter's equations
with numpy and scipy only, so a test that compares the package with these compares two
independent implementations:

* the chapter's example system (section 22.5): :data:`GAMMA_TRUE`, :data:`A_TRUE`,
  :data:`B_TRUE`;
* :func:`play`: the backlash (22.1)-(22.2) as a play operator; :func:`hammerstein`: the
  backlash followed by ``B/A`` (22.3)-(22.4);
* simulated stage-2 records (the EIV data of (22.34)): :func:`chapter_eiv_data`,
  :func:`two_level_data`, :func:`boundary_case`; each returns the keyword arguments of
  ``EIVProblem`` (plain arrays, so a test builds the problem with ``EIVProblem(**data)``)
  and the true ``theta``;
* :func:`error_scale` / :func:`explains`: our own feasibility LP at fixed ``theta``
  (scipy's ``linprog``): does ``theta`` explain the data within the error bounds?
* :func:`side_widening`: our own LP for one side of stage 1 (22.9)-(22.10);
* :func:`frequency_response`: ``B(e^{-j w dt}) / A(e^{-j w dt})`` of parameter vectors.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog
from scipy.signal import lfilter

# ----------------------------------------------------------------------- the chapter's example
#: the backlash of the chapter's example ``(m_l, c_l, m_r, c_r)`` (section 22.5)
GAMMA_TRUE = (0.25, 0.0628, 0.26, 0.0489)
#: its linear block ``A(q^-1) = 1 - 0.76 q^-1 + 0.82 q^-2``, ``B = 2.15 q^-1 - 1.09 q^-2``
A_TRUE = np.array([1.0, -0.76, 0.82])
B_TRUE = np.array([0.0, 2.15, -1.09])
THETA_TRUE = np.array([-0.76, 0.82, 2.15, -1.09])
GAIN_TRUE = B_TRUE.sum() / A_TRUE.sum()
#: a linear block of unit static gain close to the chapter's (``B(1) = A(1) = 1.06``)
B_UNIT_GAIN = np.array([0.0, 2.18, -1.12])


# ----------------------------------------------------------------------------- simulators
def play(u, ml, cl, mr, cr, x0=0.0):
    """Backlash (22.1)-(22.2) as a play operator, from ``x_{-1} = x0``:
    ``x_t = min(max(x_{t-1}, m_r (u_t - c_r)), m_l (u_t + c_l))``."""
    x, out = x0, np.empty(np.shape(u), dtype=float)
    for t, v in enumerate(u):
        x = min(max(x, mr * (v - cr)), ml * (v + cl))
        out[t] = x
    return out


def random_steps(N, rng, hold=(3, 20)):
    """Random-step input: levels uniform in [-2, 2], each held ``hold`` samples."""
    u = []
    while len(u) < N:
        u += [rng.uniform(-2, 2)] * int(rng.integers(hold[0], hold[1] + 1))
    return np.array(u[:N])


def one_record(N, deta, noise, seed):
    """A random-step record of the chapter's system (backlash ``GAMMA_TRUE``, then
    ``B/A`` at rest from ``x = 0``): ``(u, y, x)``; noise ``"uniform"`` in the bound or
    ``"bound"`` (exactly at +-deta, random signs)."""
    rng = np.random.default_rng(seed)
    u = random_steps(N, rng)
    x = play(u, *GAMMA_TRUE)
    eta = (rng.uniform(-deta, deta, N) if noise == "uniform"
           else deta * rng.choice([-1.0, 1.0], N))
    return u, lfilter(B_TRUE, A_TRUE, x) + eta, x


def hammerstein(u, gamma, b, a, x0=0.0):
    """Noise-free output of the backlash ``gamma = (m_l, c_l, m_r, c_r)`` followed by
    ``B/A`` (coefficients in ``scipy.signal.lfilter`` order), at rest."""
    return lfilter(b, a, play(u, *gamma, x0=x0))


def eiv_data(y, x, input_bound, output_bound, na, nb, nk=1, steady_state_gain=None,
             groups=None) -> dict:
    """A record of (22.34) as the keyword arguments of ``EIVProblem`` (plain arrays): what
    :func:`error_scale` and :func:`explains` read, and ``EIVProblem(**data)`` builds."""
    return dict(y=y, x=x, input_bound=input_bound, output_bound=output_bound, na=na, nb=nb,
                nk=nk, steady_state_gain=steady_state_gain, groups=groups)


def chapter_eiv_data(N=60, deta=0.05, dx=0.003, two_level=False, seed=0, normalise=True,
                     at_bound=False):
    """The chapter example (section 22.5) as stage 2 sees it, with ``u* = 2``.

    The backlash output levels are ``x_hi = m_r (u* - c_r)``, ``x_lo = m_l (-u* + c_l)``;
    the linear block is normalised to unit gain (22.8) by moving the gain into ``x``. The
    central inner values are the true ones shifted by a random amount inside ``+-dx``, as
    stage 1 would deliver. ``at_bound``: output errors exactly at ``+-deta`` (random
    signs) instead of uniform inside. Returns ``(data, theta)``: ``data`` holds the
    keyword arguments of ``EIVProblem``.
    """
    rng = np.random.default_rng(seed)
    ml, cl, mr, cr = GAMMA_TRUE
    us = 2.0
    u = np.where(rng.random(N) < 0.5, us, -us)
    x_hi, x_lo = mr * (us - cr), ml * (-us + cl)
    g = GAIN_TRUE if normalise else 1.0
    x = np.where(u > 0, x_hi, x_lo) * g
    w = lfilter(B_TRUE / g, A_TRUE, x)
    y = w + (deta * rng.choice([-1.0, 1.0], N) if at_bound else rng.uniform(-deta, deta, N))
    shift = rng.uniform(-dx, dx, 2)
    xc = np.where(u > 0, x_hi * g + shift[0], x_lo * g + shift[1])
    theta = np.concatenate([A_TRUE[1:], B_TRUE[1:] / g])
    data = eiv_data(y, xc, dx, deta, 2, 2, steady_state_gain=1.0 if normalise else None,
                    groups=(u < 0).astype(int) if two_level else None)
    return data, theta


def two_level_data(seed, N=80, deta=0.05, dx=(0.01, 0.03), levels=(0.25, -0.23),
                   at_bound=True):
    """Data of (22.34) with a two-level inner signal whose true levels are off their
    nominal values by up to ``dx`` (one shared error per level) and output errors exactly
    at ``+-deta`` (random signs: the set is then a single point, the truth) or,
    ``at_bound=False``, uniform inside. Returns ``(data, theta)`` as
    :func:`chapter_eiv_data`."""
    rng = np.random.default_rng(seed)
    s = rng.random(N) < 0.5
    nominal = np.where(s, levels[0], levels[1])
    off = rng.uniform(-1, 1, 2) * np.asarray(dx)
    true_x = nominal + np.where(s, off[0], off[1])
    noise = rng.choice([-1.0, 1.0], N) if at_bound else rng.uniform(-1.0, 1.0, N)
    y = lfilter(B_UNIT_GAIN, A_TRUE, true_x) + deta * noise
    data = eiv_data(y, nominal, np.where(s, dx[0], dx[1]), deta, 2, 2, steady_state_gain=1.0,
                    groups=(~s).astype(int))
    return data, np.concatenate([A_TRUE[1:], B_UNIT_GAIN[1:]])


#: error patterns of :func:`extremal_noise`
PATTERNS = ("alternating", "random", "constant", "inside")
#: signal scales of :func:`boundary_case`
SCALES = (1e-4, 1e-2, 1.0, 1e2, 1e4)
#: samples per model order in :func:`boundary_case` (small: the moment and exact runs)
N_OF_ORDER = {1: 6, 2: 8, 3: 10}


def extremal_noise(kind, n, bound, rng):
    """Errors of magnitude exactly ``bound`` in a pattern of :data:`PATTERNS`
    (``"inside"``: random signs at ``(1 - 1e-12) bound``)."""
    if kind == "alternating":
        s = np.where(np.arange(n) % 2 == 0, 1.0, -1.0) * rng.choice([-1.0, 1.0])
    elif kind == "constant":
        s = np.full(n, rng.choice([-1.0, 1.0]))
    else:
        s = rng.choice([-1.0, 1.0], n)
    mag = (1.0 - 1e-12) * bound if kind == "inside" else bound
    return s * mag


def boundary_case(i):
    """Case ``i`` of the extremal-noise design: a stable system of order 1-3, a PRBS
    record and errors at their bound; deterministic in ``i``.

    Returns ``(kw, theta, via_estimator)``: ``kw`` holds ``y, x, dx, deta, na, nb, gain``
    (the chapter's names), ``via_estimator`` says which interface case ``i`` uses.
    """
    rng = np.random.default_rng(1000 + i)
    order = (1, 1, 1, 1, 1, 1, 1, 2, 2, 3)[i % 10]
    pattern = PATTERNS[i % 4]
    scale = SCALES[(i // 4) % 5]
    with_input_noise = (i // 20) % 2 == 1
    with_gain = (i // 40) % 2 == 1
    n = N_OF_ORDER[order]
    poles = rng.uniform(0.1, 0.8, order) * rng.choice([-1.0, 1.0], order)
    A = np.real(np.poly(poles))
    b = rng.uniform(0.5, 1.5, order) * rng.choice([-1.0, 1.0], order)
    if abs(b.sum()) < 0.3:  # keep the gain away from zero
        b[0] += np.sign(b[0]) * 0.5
    B = np.concatenate([[0.0], b])
    x_true = np.where(rng.random(n) < 0.5, 1.0, -1.0) * scale
    w = lfilter(B, A, x_true)
    d_eta = 0.05 * scale * rng.uniform(0.2, 2.0)
    y = w + extremal_noise(pattern, n, d_eta, rng)
    d_x = 0.02 * scale if with_input_noise else 0.0
    x_c = x_true + (extremal_noise(pattern, n, d_x, rng) if with_input_noise else 0.0)
    gain = float(B.sum() / A.sum()) if with_gain else None
    theta = np.concatenate([A[1:], B[1:]])
    kw = dict(y=y, x=x_c, dx=d_x, deta=d_eta, na=order, nb=order, gain=gain)
    return kw, theta, i % 2 == 0


# ------------------------------------------------------------------- feasibility LPs
def b_lags(nb, nk=1):
    """Lags of ``b_j``: ``nk .. nk + nb - 1``; ``nk = 0``: ``0 .. nb`` (the direct term
    ``b_0`` plus the chapter's ``b_1 .. b_nb``)."""
    return np.arange(nk, nb + 1 if nk == 0 else nk + nb)


def _field(data, name, default=None):
    if isinstance(data, Mapping):
        return data.get(name, default)
    return getattr(data, name, default)


def error_scale(data, theta) -> float:
    """Smallest ``s >= 0`` such that ``theta = (a_1..a_na, b_..)`` explains the record
    with ``|eta_t| <= s output_bound_t`` and ``|e_g| <= s input_bound`` (22.34):

        (y_t - eta_t) + sum_i a_i (y_{t-i} - eta_{t-i}) = sum_j b_j (x_{t-j} - e_{g(t-j)})

    for every ``t >= max(na, last lag)``; samples with the same ``groups`` label share one
    input error ``e_g``. ``theta`` is in the set iff ``s <= 1`` (up to the LP's rounding,
    ~1e-10 here: rows are divided by the magnitudes of their terms, HiGHS tolerances
    1e-10). The gain equality is not part of it (see :func:`explains`).

    ``data``: a mapping or an object with ``y, x, input_bound, output_bound, na, nb`` and
    optionally ``nk`` (default 1) and ``groups`` -- e.g. the ``data`` of
    :func:`chapter_eiv_data` or an ``EIVProblem`` (only its data fields are read).
    """
    theta = np.asarray(theta, dtype=float)
    y = np.asarray(_field(data, "y"), dtype=float)
    x = np.asarray(_field(data, "x"), dtype=float)
    n, na = y.size, int(_field(data, "na"))
    nk = _field(data, "nk")
    lags = b_lags(int(_field(data, "nb")), 1 if nk is None else int(nk))
    deta = np.broadcast_to(np.asarray(_field(data, "output_bound"), dtype=float), (n,))
    dx = np.broadcast_to(np.asarray(_field(data, "input_bound", 0.0), dtype=float), (n,))
    labels = _field(data, "groups")
    _, g = np.unique(np.arange(n) if labels is None else np.asarray(labels),
                     return_inverse=True)
    k = int(g.max()) + 1
    dx_group = np.full(k, np.inf)
    np.minimum.at(dx_group, g, dx)  # a shared error obeys every bound of its samples
    a, b = theta[:na], theta[na:]
    T = np.arange(max(na, int(lags[-1])), n)
    rows, cols, vals = [], [], []
    r, scale = np.empty(T.size), np.empty(T.size)
    for row, t in enumerate(T):
        ylag, xlag = y[t - np.arange(1, na + 1)], x[t - lags]
        rows += [row] * (1 + na + lags.size)
        cols += [t, *(t - np.arange(1, na + 1)), *(n + g[t - lags])]
        vals += [-1.0, *(-a), *b]
        r[row] = -(y[t] + a @ ylag - b @ xlag)
        scale[row] = abs(y[t]) + np.abs(a) @ np.abs(ylag) + np.abs(b) @ np.abs(xlag) or 1.0
    M = sp.csr_matrix((vals, (rows, cols)), shape=(T.size, n + k))  # (repeated entries add)
    Ms = sp.diags(1 / scale) @ M @ sp.diags(np.concatenate([deta, dx_group]))
    nz = n + k
    eye = sp.identity(nz, format="csr")
    ones = sp.csr_matrix(-np.ones((nz, 1)))
    res = linprog(np.r_[np.zeros(nz), 1.0],
                  A_ub=sp.vstack([sp.hstack([eye, ones]), sp.hstack([-eye, ones])]),
                  b_ub=np.zeros(2 * nz), A_eq=sp.hstack([Ms, sp.csr_matrix((T.size, 1))]),
                  b_eq=r / scale, bounds=[(None, None)] * nz + [(0, None)], method="highs",
                  options={"primal_feasibility_tolerance": 1e-10,
                           "dual_feasibility_tolerance": 1e-10})
    assert res.status == 0, res.message
    return float(res.fun)


def explains(data, theta, rtol=1e-6) -> bool:
    """``theta`` explains the record within its error bounds widened by ``rtol``
    (:func:`error_scale` ``<= 1 + rtol``) and, when ``data`` has a
    ``steady_state_gain``, meets ``B(1) = steady_state_gain A(1)`` (22.8) to 1e-8."""
    theta = np.asarray(theta, dtype=float)
    gain = _field(data, "steady_state_gain")
    if gain is not None:
        na = int(_field(data, "na"))
        a, b = theta[:na], theta[na:]
        if abs(b.sum() - gain * (1 + a.sum())) > 1e-8 * (1 + abs(gain)):
            return False
    return error_scale(data, theta) <= 1.0 + rtol


def side_widening(u, y, bound, side) -> float:
    """Stage 1, one side (22.9)-(22.10): the smallest ``s`` (any sign) such that some
    ``m >= 0``, ``beta >= 0`` give ``|m u -+ beta - y| <= (1 + s) bound`` on every point
    (right: ``y = m u - beta``, left: ``y = m u + beta``); rows divided by ``bound``. The
    points are consistent with a line of the side iff ``s <= 0``."""
    u, y = np.asarray(u, dtype=float), np.asarray(y, dtype=float)
    sigma = -1.0 if side == "right" else 1.0
    A = np.column_stack([u, np.full_like(u, sigma)]) / bound
    rows = np.vstack([np.column_stack([A, -np.ones(u.size)]),
                      np.column_stack([-A, -np.ones(u.size)])])
    rhs = np.concatenate([y / bound + 1.0, -y / bound + 1.0])
    res = linprog([0, 0, 1], A_ub=rows, b_ub=rhs, bounds=[(0, None), (0, None), (None, None)],
                  method="highs")
    assert res.status == 0, res.message
    return float(res.fun)


# ------------------------------------------------------------------- frequency responses
def frequency_response(thetas, omega, na, lags, dt=1.0):
    """``G(e^{j w dt}) = B / A`` of every row of ``thetas`` (``a_1..a_na`` then the ``b_j``
    of ``lags``) at the frequencies ``omega``: shape ``(len(thetas), len(omega))``."""
    th = np.atleast_2d(thetas)
    za = np.exp(-1j * np.outer(omega * dt, np.arange(1, na + 1)))
    zb = np.exp(-1j * np.outer(omega * dt, lags))
    return (th[:, na:] @ zb.T) / (1 + th[:, :na] @ za.T)


# ------------------------------------------------------------------ random boxes
# (the symbolic play operator's tests: records, backlash boxes about the chapter's backlash
# and random well-posed points in them)

def short_steps(rng, n, lo=-2.0, hi=2.0):
    u = []
    while len(u) < n:
        u += [rng.uniform(lo, hi)] * int(rng.integers(1, 8))
    return np.array(u[:n])


def box_around(rng, rel):
    g = np.asarray(GAMMA_TRUE) * (1 + rel * rng.uniform(-1, 1, 4))
    w = rel * np.asarray(GAMMA_TRUE) * rng.uniform(0.0, 1.0, 4)
    return np.column_stack([g - w, g + w])


def random_point(rng, gbox, zbox, u):
    """A point of the box where the backlash is well-posed on the record (``L_t >= R_t``,
    the region the method works in) with ``x_0`` in the band at ``u_0``."""
    g = gbox[:, 0] + rng.uniform(0, 1, 4) * (gbox[:, 1] - gbox[:, 0])
    ml, cl, mr, cr = g
    if np.any(ml * (u + cl) < mr * (u - cr)):
        return None
    lo, hi = max(zbox[0], mr * (u[0] - cr)), min(zbox[1], ml * (u[0] + cl))
    if lo > hi:
        return None
    return g, lo + rng.uniform() * (hi - lo)


def record_and_box(seed, rel):
    """A random-step record (mostly well-posed for the wide boxes too) and a backlash box
    of relative width ``rel`` around the chapter's, with a first-value box in the band."""
    rng = np.random.default_rng(seed)
    u = short_steps(rng, 80, -1.5, 1.5)
    gbox = box_around(rng, rel)
    band = (gbox[2, 0] * (u[0] - gbox[3, 1]), gbox[0, 1] * (u[0] + gbox[1, 1]))
    mid = 0.5 * (band[0] + band[1])
    zbox = np.array([mid - rel * abs(band[1] - band[0]), mid + rel * abs(band[1] - band[0])])
    return rng, u, gbox, zbox


def points(rng, gbox, zbox, u, want, tries):
    """Up to ``want`` random well-posed points ``(g, z0, x, scale)`` of the box, with our
    own play operator's inner signal ``x`` and a rounding scale."""
    found = 0
    for _ in range(tries):
        if found == want:
            return
        pt = random_point(rng, gbox, zbox, u)
        if pt is None:
            continue
        g, z0 = pt
        x = play(u, *g, z0)
        found += 1
        yield g, z0, x, 1e-12 * (1 + np.abs(x).max())
