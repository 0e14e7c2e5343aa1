"""The symbolic play operator of the one-record method against our own play operator.

:func:`hammerbound.joint.modes.inner_structure` says, for a whole box of backlash
parameters and first values, which line every sample is on (or that it is ambiguous, with
an envelope and one-sided rows). Every claim must hold at every point of the box: checked at
random points with our own play operator (tests/oracles.py, not the package's).
"""

import numpy as np
import pytest
from oracles import play as own_play
from oracles import points, record_and_box, short_steps

from hammerbound.joint.modes import (
    AMBIG,
    INIT,
    LEFT,
    RIGHT,
    inner_envelope,
    inner_structure,
)

GAMMA = np.array([0.25, 0.0628, 0.26, 0.0489])








def assert_claims(st, u, g, z0, x, scale):
    """Every claim of the structure ``st`` holds at the point: line forms, envelopes of the
    ambiguous samples and their one-sided rows."""
    for t in range(u.size):
        k, s = int(st.kind[t]), int(st.src[t])
        if k != AMBIG:
            assert abs(x[t] - form_value(u, g, z0, k, s)) <= scale, (t, k, s)
            continue
        a = st.ambiguous[s]
        assert a.lo - scale <= x[t] <= a.hi + scale
        prev = (z0 if a.src_kind == INIT else
                form_value(u, g, z0, a.src_kind, a.src) if a.src_kind in (RIGHT, LEFT)
                else x[st.ambiguous[a.src].t])
        if not a.up:
            assert x[t] <= prev + scale
        if not a.down:
            assert x[t] >= prev - scale






def form_value(u, g, z0, kind, src):
    ml, cl, mr, cr = g
    if kind == RIGHT:
        return mr * (u[src] - cr)
    if kind == LEFT:
        return ml * (u[src] + cl)
    return z0


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("rel", [0.0, 0.02, 0.15])
def test_every_claim_holds_at_random_points_of_the_box(seed, rel):
    rng, u, gbox, zbox = record_and_box(seed, rel)
    st = inner_structure(u, np.vstack([gbox, zbox]))
    lo_env, hi_env = inner_envelope(u, gbox, zbox)
    checked = 0
    for g, z0, x, scale in points(rng, gbox, zbox, u, 40, 1000):
        assert np.all(x >= lo_env - scale) and np.all(x <= hi_env + scale)
        assert_claims(st, u, g, z0, x, scale)
        checked += 1
    assert checked >= 10


def test_a_point_box_has_no_ambiguity_and_reproduces_the_play_operator():
    rng = np.random.default_rng(3)
    u = short_steps(rng, 200)
    ml, cl, mr, cr = GAMMA
    z0 = mr * (u[0] - cr)
    st = inner_structure(u, np.vstack([np.column_stack([GAMMA, GAMMA]), [z0, z0]]))
    assert st.n_ambiguous == 0
    x = own_play(u, *GAMMA, z0)
    vals = [form_value(u, GAMMA, z0, int(k), int(s)) for k, s in zip(st.kind, st.src, strict=True)]
    np.testing.assert_allclose(vals, x, rtol=0, atol=1e-14)


def test_unknown_first_value_collapses_after_a_reversal_wider_than_the_gap():
    """The envelope is the whole band at the start and a point once the input has gone
    past both lines (the issue's "it collapses after the input reverses")."""
    u = np.r_[np.zeros(5), np.full(5, 1.5), np.full(5, -1.5), np.full(5, 0.3)]
    gbox = np.column_stack([GAMMA, GAMMA])
    lo, hi = inner_envelope(u, gbox)
    assert hi[0] - lo[0] > 0.02
    np.testing.assert_allclose(hi[5:], lo[5:], atol=1e-12)
    x = own_play(u, *GAMMA, 0.0)
    np.testing.assert_allclose(lo[5:], x[5:], atol=1e-12)


def own_branch(x, t):
    """The branch our own play operator took at sample ``t`` (ties count as holding)."""
    if x[t] > x[t - 1]:
        return "up"
    if x[t] < x[t - 1]:
        return "down"
    return "hold"


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("rel", [0.02, 0.15])
def test_decided_samples_hold_at_points_that_take_those_branches(seed, rel):
    """A branch-and-bound node fixes the branch of ambiguous samples: for a point that
    takes those branches, every claim of the decided structure holds (forms, envelopes,
    one-sided rows) and so do the decision's own inequalities; the point's branch is
    always among the children a node is split into (up / down only where still
    possible)."""
    from hammerbound.joint.modes import DOWN, HOLD, UP

    rng, u, gbox, zbox = record_and_box(seed, rel)
    box = np.vstack([gbox, zbox])
    base = inner_structure(u, box)
    checked = decided = 0
    for g, z0, x, scale in points(rng, gbox, zbox, u, 30, 2000):
        # the point's own branches at (a random half of) the ambiguous samples
        dec = {}
        for a in base.ambiguous:
            br = own_branch(x, a.t)
            assert (br != "up" or a.up) and (br != "down" or a.down), (a, br)
            if rng.uniform() < 0.5 or not dec:
                dec[a.t] = {"up": UP, "down": DOWN, "hold": HOLD}[br]
        st = inner_structure(u, box, dec)
        ml, cl, mr, cr = g
        for d in st.decided:
            prev = x[d.t - 1]
            R, L = mr * (u[d.t] - cr), ml * (u[d.t] + cl)
            if d.branch == UP:
                assert R >= prev - scale
            elif d.branch == DOWN:
                assert L <= prev + scale
            else:
                assert R <= prev + scale and prev <= L + scale
            decided += 1
        assert_claims(st, u, g, z0, x, scale)
        checked += 1
    assert checked >= 10
    if base.ambiguous:
        assert decided > 0


@pytest.mark.parametrize("seed", range(3))
def test_relaxation_of_the_truths_branches_brackets_the_truth(seed):
    """The node relaxation with the decided branches of the true system (our own
    simulation, noise exactly at +-bound) bounds every parameter around the truth."""
    from oracles import A_TRUE, B_TRUE
    from scipy.signal import lfilter

    from hammerbound.joint import RecordProblem
    from hammerbound.joint.modes import DOWN, HOLD, UP
    from hammerbound.joint.relaxation import build_relaxation

    rng = np.random.default_rng(seed)
    theta = np.r_[A_TRUE[1:], B_TRUE[1:]]
    for _ in range(20):  # a record with ambiguous samples over the box
        u = short_steps(rng, 120)
        x = own_play(u, *GAMMA, 0.0)
        truth = np.r_[theta, GAMMA, x[0]]
        box = np.column_stack([truth - 0.05 * np.abs(truth) - 1e-3,
                               truth + 0.05 * np.abs(truth) + 1e-3])
        st = inner_structure(u, box[4:9])
        if st.ambiguous:
            break
    assert st.ambiguous, "the test wants ambiguous samples"
    deta = 0.05
    y = lfilter(B_TRUE, A_TRUE, x) + deta * rng.choice([-1.0, 1.0], u.size)
    pb = RecordProblem(u, y, np.full(u.size, deta), 2, 2, 1, box)
    names = {"up": UP, "down": DOWN, "hold": HOLD}
    dec = {a.t: names[own_branch(x, a.t)] for a in st.ambiguous}
    rel = build_relaxation(pb, box, decisions=dec)
    for k in range(9):
        for sense in (1.0, -1.0):
            c = np.zeros(rel.lp.c.size)
            c[rel.box_cols[k]] = sense
            rel.lp.set_cost(c)
            res = rel.lp.solve()
            assert res.status == "optimal", (k, sense, res.status)
            assert res.bound <= sense * truth[k] + 1e-9, (k, sense, res.bound, truth[k])
