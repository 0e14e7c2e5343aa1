"""Shared fixtures: chapter-like stage-2 data generated without the stage-1 code."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.signal import lfilter

from hammerbound.relaxations.problem import EIVProblem

#: test and benchmark data that are not the project's (read in place, never copied into it)
SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def shared_data(*parts) -> Path:
    """Path of a file under ``../shared/data/`` (relative to the repository root); the
    calling test is skipped, with the path in the reason, when the file is not there."""
    path = SHARED_DATA.joinpath(*parts)
    if not path.is_file():
        pytest.skip(f"third-party data not found at {path} (tests read it from "
                    "../shared/data/ beside the repository; it is not part of the package)")
    return path


def lric_data():
    """``(u, y)`` of the LRIC exam record (P0li22/LRIC, 22 February 2017: 30 samples,
    dt = 0.1, input and output errors bounded by 0.05), or skip."""
    d = np.genfromtxt(shared_data("lric", "eiv_first_order_2017.csv"), delimiter=",",
                      names=True)
    return d["u"], d["y"]


THETA_TRUE = np.array([-0.76, 0.82, 2.15, -1.09])
A_TRUE = np.array([1.0, -0.76, 0.82])
B_TRUE = np.array([0.0, 2.15, -1.09])
GAIN_TRUE = B_TRUE.sum() / A_TRUE.sum()
CH_A = np.array([1.0, -0.76, 0.82])  # the chapter's A(q^-1) (B(1) = A(1) = 1.06)
CH_B = np.array([0.0, 2.18, -1.12])


def play(u, ml, cl, mr, cr):
    """Backlash (22.1) at rest, the tests' own implementation (not the package's):
    ``x_t = min(max(x_{t-1}, mr (u_t - cr)), ml (u_t + cl))`` from ``x = 0``."""
    x, out = 0.0, np.empty(np.shape(u))
    for t, v in enumerate(u):
        x = min(max(x, mr * (v - cr)), ml * (v + cl))
        out[t] = x
    return out


def make_eiv_problem(N=60, deta=0.05, dx=0.003, two_level=False, seed=0, normalise=True,
                     at_bound=False):
    """Chapter example (section 22.5) seen by stage 2, with u* = 2.

    The backlash output levels are x_hi = m_r (u* - c_r), x_lo = m_l (-u* + c_l); the
    linear block is normalised to unit gain (22.8) by moving the gain into x. The central
    inner values are the true ones shifted by a random amount inside +-dx, as stage 1
    would deliver. ``at_bound``: output noise exactly at +-deta (random signs) instead of
    uniform inside. Returns (problem, theta_true).
    """
    rng = np.random.default_rng(seed)
    ml, cl, mr, cr, us = 0.25, 0.0628, 0.26, 0.0489, 2.0
    u = np.where(rng.random(N) < 0.5, us, -us)
    x_hi, x_lo = mr * (us - cr), ml * (-us + cl)
    g = GAIN_TRUE if normalise else 1.0
    x = np.where(u > 0, x_hi, x_lo) * g
    w = lfilter(B_TRUE / g, A_TRUE, x)
    y = w + (deta * rng.choice([-1.0, 1.0], N) if at_bound else rng.uniform(-deta, deta, N))
    shift = rng.uniform(-dx, dx, 2)
    xc = np.where(u > 0, x_hi * g + shift[0], x_lo * g + shift[1])
    theta = np.concatenate([A_TRUE[1:], B_TRUE[1:] / g])
    groups = (u < 0).astype(int) if two_level else None
    prob = EIVProblem(y, xc, dx, deta, na=2, nb=2, b0=False,
                      gain=1.0 if normalise else None, groups=groups)
    return prob, theta


def make_two_level(seed, N=80, deta=0.05, dx=(0.01, 0.03), levels=(0.25, -0.23),
                   at_bound=True):
    """Data of (22.34) with a two-level inner signal whose true levels are off their
    nominal values by up to ``dx`` and output noise exactly at +-deta (random signs: the
    set is then a single point, the truth) or, ``at_bound=False``, uniform inside."""
    rng = np.random.default_rng(seed)
    s = rng.random(N) < 0.5
    nominal = np.where(s, levels[0], levels[1])
    off = rng.uniform(-1, 1, 2) * np.asarray(dx)
    true_x = nominal + np.where(s, off[0], off[1])
    noise = rng.choice([-1.0, 1.0], N) if at_bound else rng.uniform(-1.0, 1.0, N)
    y = lfilter(CH_B, CH_A, true_x) + deta * noise
    dxs = np.where(s, dx[0], dx[1])
    pr = EIVProblem(y, nominal, dxs, deta, 2, 2, gain=1.0, groups=(~s).astype(int))
    return pr, np.concatenate([CH_A[1:], CH_B[1:]])


def min_error_scale(pr, theta):
    """Independent LP: is ``theta`` in the EIV set (22.34)? Returns the smallest uniform
    scaling of the error bounds that explains the data (<= 1 + 1e-7: inside)."""
    a, b = theta[: pr.na], theta[pr.na :]
    lags = pr.b_lags
    T = np.arange(pr.n0, pr.N)
    n, k = pr.N, pr.n_groups
    # variables: eta (n), dxv (k), s; rows: equation residuals linear in (eta, dxv)
    M = np.zeros((T.size, n + k + 1))
    r = np.zeros(T.size)
    for row, t in enumerate(T):
        M[row, t] = -1.0
        for i in range(1, pr.na + 1):
            M[row, t - i] = -a[i - 1]
        for bj, j in zip(b, lags, strict=True):
            M[row, n + pr.groups[t - j]] += bj
        r[row] = -(pr.y[t] + a @ pr.y[t - np.arange(1, pr.na + 1)]
                   - b @ pr.x[t - lags])
    # |eta| <= s deta, |dxv| <= s dx: scale the variables by s via bounds on ratio form
    bound = np.concatenate([pr.deta, pr.dx_group])
    Aub = np.vstack([np.hstack([np.eye(n + k), -bound[:, None]]),
                     np.hstack([-np.eye(n + k), -bound[:, None]])])
    M[:, -1] = 0.0
    c = np.zeros(n + k + 1)
    c[-1] = 1.0
    res = linprog(c, A_ub=Aub, b_ub=np.zeros(2 * (n + k)), A_eq=M, b_eq=r,
                  bounds=[(None, None)] * (n + k) + [(0, None)], method="highs")
    assert res.status == 0
    return res.fun


@pytest.fixture
def chapter_problem():
    return make_eiv_problem()
