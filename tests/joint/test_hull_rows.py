"""The play operator's envelope rows at ambiguous samples (:mod:`hammerbound.joint.hull_rows`)
hold at every point of the box: checked with our own play operator (tests/oracles.py) at
random points, and the planes against max/min at random points of their rectangles."""

import numpy as np
import pytest
from oracles import play as own_play
from oracles import points, record_and_box

from hammerbound.joint.hull_rows import envelope_planes, hull_rows
from hammerbound.joint.modes import inner_structure
from hammerbound.joint.relaxation import _Rows


@pytest.mark.parametrize("seed", range(5))
def test_planes_bound_max_from_above_and_min_from_below(seed):
    rng = np.random.default_rng(seed)
    for _ in range(300):
        pr, sr = np.sort(rng.uniform(-2, 2, 2)), np.sort(rng.uniform(-2, 2, 2))
        if rng.uniform() < 0.2:  # touching ranges
            sr = np.array([pr[1], pr[1] + rng.uniform(0, 1)])
        corners_p, corners_s = np.repeat(pr, 2), np.tile(sr, 2)
        P = np.r_[corners_p, rng.uniform(pr[0], pr[1], 200)]
        S = np.r_[corners_s, rng.uniform(sr[0], sr[1], 200)]
        overlap = pr[0] < sr[1] and sr[0] < pr[1]
        for upper in (True, False):
            alpha, beta, gamma, ok = envelope_planes(pr, sr, upper)
            assert ok.sum() == (2 if overlap else 0)
            f = np.maximum(P, S) if upper else np.minimum(P, S)
            for a, b, c in zip(alpha[0][ok[0]], beta[0][ok[0]], gamma[0][ok[0]], strict=True):
                h = a * P + b * S + c
                assert np.all(h >= f) if upper else np.all(h <= f)


def test_planes_are_the_envelope_at_the_corners():
    """Not just valid: each plane passes (within its margin) through three corners."""
    pr, sr = (-1.0, 1.0), (-0.5, 2.0)
    corners = [(p, s) for p in pr for s in sr]
    for upper in (True, False):
        f = max if upper else min
        alpha, beta, gamma, ok = envelope_planes(pr, sr, upper)
        for a, b, c in zip(alpha[0][ok[0]], beta[0][ok[0]], gamma[0][ok[0]], strict=True):
            tight = sum(abs(a * p + b * s + c - f(p, s)) < 1e-9 for p, s in corners)
            assert tight == 3


def _row_values(rows, beta):
    A_rows = np.concatenate(rows.r)
    cols = np.concatenate(rows.c)
    vals = np.concatenate(rows.v)
    out = np.zeros(rows.m)
    np.add.at(out, A_rows, vals * beta[cols])
    return out, np.concatenate(rows.lo), np.concatenate(rows.hi)


class _Problem:  # what hull_rows reads of a RecordProblem
    def __init__(self, u):
        self.u, self.p = u, 0


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("rel", [0.15, 0.3])
def test_every_row_holds_at_random_points_of_the_box(seed, rel):
    rng, u, gbox, zbox = record_and_box(seed, rel)
    box = np.vstack([gbox, zbox])
    st = inner_structure(u, box)
    rows = _Rows()
    bc = np.arange(5 + len(st.ambiguous))
    hull_rows(rows, _Problem(u), box, st, bc, lambda t, j: np.zeros(np.size(t), np.int64))
    if not st.ambiguous:
        pytest.skip("no ambiguous sample in this box")
    assert rows.m > 0
    checked = 0
    for g, z0, x, scale in points(rng, gbox, zbox, u, 40, 1000):
        ml, cl, mr, cr = g
        beta = np.r_[ml, ml * cl, mr, mr * cr, z0, [x[a.t] for a in st.ambiguous]]
        assert np.allclose(x, own_play(u, *g, z0))
        val, lo, hi = _row_values(rows, beta)
        assert np.all(val >= lo - scale) and np.all(val <= hi + scale)
        checked += 1
    assert checked >= 10
