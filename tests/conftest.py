"""Shared fixtures: chapter-like stage-2 data generated without the stage-1 code."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from hammerbound.relaxations.problem import EIVProblem

THETA_TRUE = np.array([-0.76, 0.82, 2.15, -1.09])
A_TRUE = np.array([1.0, -0.76, 0.82])
B_TRUE = np.array([0.0, 2.15, -1.09])
GAIN_TRUE = B_TRUE.sum() / A_TRUE.sum()


def play(u, ml, cl, mr, cr):
    """Backlash (22.1) at rest, the tests' own implementation (not the package's):
    ``x_t = min(max(x_{t-1}, mr (u_t - cr)), ml (u_t + cl))`` from ``x = 0``."""
    x, out = 0.0, np.empty(np.shape(u))
    for t, v in enumerate(u):
        x = min(max(x, mr * (v - cr)), ml * (v + cl))
        out[t] = x
    return out


def make_eiv_problem(N=60, deta=0.05, dx=0.003, two_level=False, seed=0, normalise=True):
    """Chapter example (section 22.5) seen by stage 2, with u* = 2.

    The backlash output levels are x_hi = m_r (u* - c_r), x_lo = m_l (-u* + c_l); the
    linear block is normalised to unit gain (22.8) by moving the gain into x. The central
    inner values are the true ones shifted by a random amount inside +-dx, as stage 1
    would deliver. Returns (problem, theta_true).
    """
    rng = np.random.default_rng(seed)
    ml, cl, mr, cr, us = 0.25, 0.0628, 0.26, 0.0489, 2.0
    u = np.where(rng.random(N) < 0.5, us, -us)
    x_hi, x_lo = mr * (us - cr), ml * (-us + cl)
    g = GAIN_TRUE if normalise else 1.0
    x = np.where(u > 0, x_hi, x_lo) * g
    w = lfilter(B_TRUE / g, A_TRUE, x)
    y = w + rng.uniform(-deta, deta, N)
    shift = rng.uniform(-dx, dx, 2)
    xc = np.where(u > 0, x_hi * g + shift[0], x_lo * g + shift[1])
    theta = np.concatenate([A_TRUE[1:], B_TRUE[1:] / g])
    groups = (u < 0).astype(int) if two_level else None
    prob = EIVProblem(y, xc, dx, deta, na=2, nb=2, b0=False,
                      gain=1.0 if normalise else None, groups=groups)
    return prob, theta


@pytest.fixture
def chapter_problem():
    return make_eiv_problem()
