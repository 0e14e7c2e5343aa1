"""A thin set without input errors (new-user trial 8): the set of a second-order
output-error record is a needle in ``(a1, a2)`` that the search's witnesses did not follow,
so two ends stayed at their time limit with gaps of a quarter of the interval. With no
input errors the equations at fixed ``a`` are linear in ``b`` and the errors: the search
now completes the node LP's ``a`` with the best ``b`` (one LP), and bisects on ``a`` alone.

The record is simulated here; every witness is checked by the tests' own LP-free residual
computation."""

from __future__ import annotations

import numpy as np
import pytest
from oracles import eiv_data, explains
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.relaxations import exact_bounds
from hammerbound.relaxations.exact.points import _Pool, a_margin, b_for_a, seek_a
from hammerbound.relaxations.problem import check_theta

THETA = np.array([-0.5, 0.06, 1.0, 0.5])  # A = 1 - 0.5 q^-1 + 0.06 q^-2, B = q^-2 (1 + 0.5 q^-1)
D = 0.1


@pytest.fixture(scope="module")
def problem():
    rng = np.random.default_rng(0)
    n = 90
    x = np.where(rng.random(n) < 0.5, 1.0, -1.0) + 0.3 * rng.uniform(-1, 1, n)
    y = lfilter([0, 0, 1.0, 0.5], [1.0, -0.5, 0.06], x) + rng.uniform(-D, D, n)
    return hb.EIVProblem(y, x, input_bound=0.0, output_bound=D, na=2, nb=2, nk=2)


def _residuals(pr, theta, eta):
    """(y_t - eta_t) + a1 (y_t-1 - eta_t-1) + a2 (y_t-2 - eta_t-2) - b2 x_t-2 - b3 x_t-3."""
    y, x = pr.y - eta, pr.x
    t = np.arange(3, pr.N)
    return (y[t] + theta[0] * y[t - 1] + theta[1] * y[t - 2]
            - theta[2] * x[t - 2] - theta[3] * x[t - 3])


@pytest.fixture(scope="module")
def res(problem):
    return exact_bounds(problem, time_limit=10)


@pytest.mark.deep
def test_every_end_of_the_needle_closes_with_verified_witnesses(problem, res):
    assert [i.status for i in res.infos] == ["optimal"] * 8
    assert np.all((res.bounds[:, 0] <= THETA) & (THETA <= res.bounds[:, 1]))
    for info in res.infos:
        w, eta = info.witness, info.point.eta
        assert np.all(np.abs(eta) <= D * (1 + 1e-7))
        scale = np.abs(problem.y).max() * 3 + np.abs(problem.x).max() * 3
        assert np.max(np.abs(_residuals(problem, w, eta))) <= 1e-7 * scale


def test_b_for_a_completes_a_feasible_a_and_refuses_an_infeasible_one(problem):
    # the truth's a is feasible (errors within the bound): b_for_a finds a b for it
    b = b_for_a(problem, THETA, 0, 1.0)
    assert b is not None and check_theta(problem, np.r_[THETA[:2], b]).feasible
    # the lowest b2 for that a is at most the truth's, and still verified
    low = b_for_a(problem, THETA, 2, 1.0)
    assert low[0] <= THETA[2] + 1e-9 and check_theta(problem, np.r_[THETA[:2], low]).feasible
    # an a far outside the set has no b at all
    assert b_for_a(problem, np.r_[THETA[0] - 0.05, THETA[1:]], 0, 1.0) is None
    # with input errors the equations at fixed a are not linear in b: not used
    noisy = hb.EIVProblem(problem.y, problem.x, input_bound=0.01, output_bound=D, na=2, nb=2,
                          nk=2)
    assert _Pool(noisy).complete(THETA, 0, 1.0) is None


def _long_record(seed=1, n=1200, d=0.02):
    """A long, lightly noisy output-error record of a resonant plant (the kind of new-user
    trial 9, N = 2000, on which no search found a first verified point in 240 s)."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1, 1, n // 8 + 1), 8)[:n]
    y = lfilter([0, 0, 0.2, 0.1], [1.0, -1.2, 0.5], u) + rng.uniform(-d, d, n)
    data = eiv_data(y, u, 0.0, d, 2, 2, nk=2)
    return hb.EIVProblem(**data), data


def test_a_margin_is_nonnegative_exactly_on_the_set():
    """s(a) >= 0 with its b explaining the record (the tests' own LP says so) at the true
    a; s < 0 at an a off the set."""
    pr, data = _long_record()
    s, b = a_margin(pr, [-1.2, 0.5])
    assert s >= 0 and explains(data, np.r_[-1.2, 0.5, b])
    s_off, _ = a_margin(pr, [-1.15, 0.5])
    assert s_off < 0


def test_a_margin_stops_at_its_deadline():
    """seek_a checks its deadline between LPs; each LP also stops at it (a record's LP
    could overrun the fit's time by its own length): a passed deadline gives no margin
    (-inf, never a wrong one) where the same LP without it finds the true a's."""
    import time

    pr, _ = _long_record()
    assert a_margin(pr, [-1.2, 0.5])[0] >= 0
    s, b = a_margin(pr, [-1.2, 0.5], deadline=time.time() - 1.0)
    assert s == -np.inf and b is None


def test_seek_a_finds_a_first_point_of_a_long_output_error_record():
    """From the centre of the LP box (not in the set), the search over a alone finds a
    point that check_theta verifies and the tests' own LP confirms."""
    from hammerbound.relaxations import lp_bounds

    pr, data = _long_record()
    box = lp_bounds(pr).bounds
    centre = box.mean(axis=1)
    assert not check_theta(pr, centre).feasible

    def verify(theta):
        return theta if check_theta(pr, theta).feasible else None

    theta = seek_a(pr, centre, box, verify)
    assert theta is not None and explains(data, theta)
    assert np.all((box[:, 0] <= theta) & (theta <= box[:, 1]))


@pytest.mark.parametrize("seed", range(4))
def test_a_margin_of_first_order_plants_is_not_lost_to_presolve(seed):
    """HiGHS's presolve ended "not set" on most of these LPs (s = -inf at the true a, so
    the search had no signal, review); the LP is solved again without it."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1, 1, 51), 4)[:200]
    y = lfilter([0, 1.0], [1, -0.7], u) + rng.uniform(-0.02, 0.02, 200)
    data = eiv_data(y, u, 0.0, 0.02, 1, 1)
    s, b = a_margin(hb.EIVProblem(**data), [-0.7])
    assert s >= 0 and explains(data, np.r_[-0.7, b])


def test_seek_a_gets_a_share_of_the_time_left():
    """seek_a's LPs are of the full record; a search that finds nothing may take only a
    part of the time left (SEEK_A_SHARE), not the ends' time."""
    import time

    from hammerbound.relaxations.exact.bnb import SEEK_A_SHARE, _share

    now = time.time()
    got = _share(now + 100.0, SEEK_A_SHARE)
    assert now + 100.0 * SEEK_A_SHARE - 1.0 <= got <= now + 100.0 * SEEK_A_SHARE + 1.0
    assert _share(None, SEEK_A_SHARE) is None
    assert _share(now - 5.0, SEEK_A_SHARE) <= time.time()
