"""The LP and exact methods give the same answer whatever the units of the data.

A record in other units -- the input times ``sx``, the output times ``sy`` -- has the same
EIV set (22.34) with every ``b_j`` times ``g = sy / sx`` (and the gain of (22.8) times
``g``). Both methods solve in units where the data are of order one (exact powers of two,
:mod:`hammerbound.relaxations.units`): the LP method's intervals in other units are the
same, the exact method's the same up to its tolerance, its witnesses explain the record
*as given* (our own LP, :func:`oracles.error_scale`), and data of unusual units take as
long as any other: the case ``x * 1e-4``, ``y * 1e4`` (``b_j ~ 1e8``) ran for over 40
minutes before.
"""

from __future__ import annotations

import functools
import time

import numpy as np
import pytest
from oracles import chapter_eiv_data, explains

from hammerbound.relaxations.exact.bnb import exact_bounds
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.problem import EIVProblem
from hammerbound.relaxations.units import Units

TOL = 1e-4
SCALES = [(1e3, 1e-3), (1e-3, 1.0), (1e-4, 1e4), (3.0, 7e5)]


def _scaled(data, sx, sy, box=None):
    d = dict(data)
    d.update(x=data["x"] * sx, input_bound=data["input_bound"] * sx, y=data["y"] * sy,
             output_bound=data["output_bound"] * sy,
             steady_state_gain=data["steady_state_gain"] * sy / sx)
    return d


@functools.cache
def _reference():
    data, theta = chapter_eiv_data(N=60, deta=0.02, seed=3, at_bound=True)
    return data, theta, exact_bounds(EIVProblem(**data, theta_box=_box(1.0)), tol=TOL)


def _box(g):
    """The a priori box in the units of ``g`` (the same box for every unit)."""
    return np.array([[-2.0, 2.0], [-1.0, 1.0], [-1e3 * g, 1e3 * g], [-1e3 * g, 1e3 * g]])


@pytest.mark.parametrize("sx, sy", SCALES)
def test_lp_intervals_and_polytopes_in_other_units(sx, sy):
    data, theta, _ = _reference()
    g = sy / sx
    ref = lp_bounds(EIVProblem(**data, theta_box=_box(1.0)))
    res = lp_bounds(EIVProblem(**_scaled(data, sx, sy), theta_box=_box(g)))
    back = res.bounds.copy()
    back[2:] /= g
    # the data in other units differ from the reference's by their rounding only
    np.testing.assert_allclose(back, ref.bounds, rtol=1e-7, atol=1e-9)
    truth = theta.copy()
    truth[2:] *= g
    assert np.all((res.bounds[:, 0] <= truth) & (truth <= res.bounds[:, 1]))
    slack = [np.max((q.A @ truth - q.b) / (np.abs(q.A) @ np.abs(truth) + np.abs(q.b)))
             for q in res.polytopes]
    assert min(slack) <= 1e-9, "the truth is in none of the orthant polytopes"
    for i in res.infos:
        assert np.isfinite(i.solver_value)


@pytest.mark.parametrize("sx, sy", SCALES)
def test_exact_intervals_in_other_units_are_the_same(sx, sy):
    data, theta, ref = _reference()
    g = sy / sx
    scaled = _scaled(data, sx, sy)
    box = _box(g)
    t0 = time.perf_counter()
    res = exact_bounds(EIVProblem(**scaled, theta_box=box), tol=TOL)
    seconds = time.perf_counter() - t0
    back = res.bounds.copy()
    back[2:] /= g
    assert all(i.status == "optimal" for i in res.infos), [i.message for i in res.infos]
    # each end is within its tolerance of the exact extreme in both runs
    slack = 2 * TOL * np.maximum(1.0, np.abs(ref.bounds)) + 1e-9
    np.testing.assert_array_less(np.abs(back - ref.bounds), slack)
    truth = theta.copy()
    truth[2:] *= g
    assert np.all((res.bounds[:, 0] <= truth) & (truth <= res.bounds[:, 1]))
    # the b_j close to a tolerance relative to the largest |b_j| (as a power of two), not
    # to 1e-4 absolute whatever the units
    b_scale = np.sqrt(2.0) * abs(g) * np.max(np.abs(ref.bounds[2:]))
    for info in res.infos:
        unit = b_scale if info.param.startswith("b") else 1.0
        assert info.gap <= TOL * max(unit, abs(info.inner)), info
        # the witness explains the record in the units it was given in
        assert explains(scaled, info.witness, rtol=1e-6), info
        assert np.max(np.abs(info.point.eta) / scaled["output_bound"]) <= 1 + 1e-6
    # no hang: the unscaled reference takes about a second here
    assert seconds < 120, seconds


def test_search_units_map_back_exactly():
    data, _, _ = _reference()
    pr = EIVProblem(**_scaled(data, 1e-4, 1e4))
    u = Units.of(pr)
    # powers of two, data of order one in the search's units
    assert np.log2(u.output).is_integer() and np.log2(u.input).is_integer()
    sp = u.problem(pr)
    assert 0.1 < np.max(np.abs(sp.y)) < 10 and 0.1 < np.max(np.abs(sp.x)) < 10
    theta = np.array([-0.7, 0.3, 1.234e8, -5.6e7])
    assert np.array_equal(u.back(u.to_search(theta)), theta)
    # the same equations hold: residuals scale by the output factor only
    np.testing.assert_allclose(sp.simulate_noise_free(u.to_search(theta)),
                               u.output * pr.simulate_noise_free(theta), rtol=1e-12,
                               atol=1e-12 * np.max(np.abs(pr.y)) * u.output)
    # the gain equality too
    row, rhs = sp.gain_row()
    row0, rhs0 = pr.gain_row()
    assert np.isclose(row @ u.to_search(theta) - rhs, (row0 @ theta - rhs0) / u.input)


def test_lp_bounds_at_the_a_priori_box_do_not_set_the_b_scale():
    """b_j ~ 1e-8 with the default box |b_j| <= 1e4: the LP's b bounds sit at the box and
    say nothing of the b_j's scale; the input's magnitude sets it (from the box the exact
    fit of the tests' badly scaled case took 300 s instead of 1 s). With a box that the
    LP bounds leave, their largest |b_j| does."""
    data, _ = chapter_eiv_data(N=80, deta=0.02, dx=0.0, seed=7)
    g = 1e-8
    pr = EIVProblem(**_scaled(data, 1e4, 1e-4))
    lp = lp_bounds(pr, check_box=False)
    assert np.any(np.isclose(np.abs(lp.bounds[2:]), 1e4)), lp.bounds  # at the box
    assert Units.of_lp(pr, lp.bounds) == Units.of(pr)
    pr = EIVProblem(**_scaled(data, 1e4, 1e-4), theta_box=_box(g))
    lp = lp_bounds(pr)
    mag = np.max(np.abs(lp.bounds[2:]))
    assert Units.of_lp(pr, lp.bounds).input == 2.0 ** np.round(np.log2(mag))
