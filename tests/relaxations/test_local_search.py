"""The SLP local search for inner values (relaxations/local.py) and its place in the
branch-and-bound: every point it returns is verified, it gets near the exact interval ends
on its own, and the exact intervals do not depend on it (a search that finds nothing, or
no search at all, gives the same certified bounds).

Data from the tests' own generators (oracles.py: plain numpy/scipy, noise exactly at
+-Delta eta); membership is re-checked by an independent scipy LP (oracles.error_scale).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from oracles import chapter_eiv_data, error_scale, two_level_data

import hammerbound.relaxations.exact.search as search
from hammerbound.relaxations.exact.bnb import SearchOptions, exact_bounds
from hammerbound.relaxations.exact.local import LinearisedSet, improve, restore
from hammerbound.relaxations.exact.points import _Pool
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.problem import EIVProblem

TOL = 1e-4


@functools.cache
def _problem(kind, seed):
    if kind == "two-level":
        return EIVProblem(**two_level_data(seed, N=80, deta=0.1)[0])
    return EIVProblem(**chapter_eiv_data(N=60, deta=0.05, dx=0.003, seed=seed, at_bound=True)[0])


@functools.cache
def _exact(kind, seed, local=True):
    pr = _problem(kind, seed)
    return exact_bounds(pr, tol=TOL, options=SearchOptions(local_search=local))


def _start(kind, seed):
    """A fresh pool and a verified point to start from (the centre of the witnesses'
    hull, or a witness), with the exact result."""
    pr = _problem(kind, seed)
    res = _exact(kind, seed)
    pool = _Pool(pr)
    for th in [res.inner.mean(axis=1), *[i.witness for i in res.infos]]:
        if np.all(np.isfinite(th)) and pool.add(th) is not None:
            return pr, pool, pool.points[-1], res
    raise AssertionError("no verified start")


def _inside(pr, theta):
    """Independent membership: error scaling <= 1 (+ LP tolerance) and the gain row."""
    g = pr.gain_row()
    return (error_scale(pr, theta) <= 1 + 1e-6
            and abs(g[0] @ theta - g[1]) <= 1e-9 * (np.abs(g[0]) @ np.abs(theta) + abs(g[1])))


def test_linearised_set_holds_the_verified_point():
    """With a zero trust region the only candidate is the point itself: the linearised
    equations hold exactly at a verified point (the LP is feasible there)."""
    pr, pool, pt, _ = _start("two-level", 1)
    lin = LinearisedSet(pr)
    for k in range(pr.p):
        out = lin.solve(pt.theta, pt.eta, pt.dx, k, 1.0, pt.theta, pt.theta)
        assert out is not None
        assert np.allclose(out[0], pt.theta, atol=1e-9)


@pytest.mark.parametrize("kind,seed", [("two-level", 0), ("two-level", 1), ("independent", 2)])
def test_improve_walks_to_the_exact_ends_with_verified_points(kind, seed):
    pr, pool, start, res = _start(kind, seed)
    box = res.root_box
    for k in range(pr.p):
        for sense in (1.0, -1.0):
            pt = improve(pool, start, k, sense, box, 0.05 * TOL)
            # never worse than the start, and verified independently
            assert sense * pt.theta[k] <= sense * start.theta[k]
            assert _inside(pr, pt.theta)
            # the certified exact end bounds it, and it gets close on its own
            end = res.bounds[k, 0 if sense > 0 else 1]
            assert sense * pt.theta[k] >= sense * end - 1e-9
            assert abs(pt.theta[k] - end) <= 20 * TOL * max(1.0, abs(end)), (k, sense)


def test_improve_respects_the_box_and_the_time_limit():
    pr, pool, start, res = _start("two-level", 1)
    box = res.root_box.copy()
    # a box that ends just below the start in b1: nothing better inside it
    box[2, 0] = start.theta[2]
    pt = improve(pool, start, 2, 1.0, box, 0.05 * TOL)
    assert pt.theta[2] >= box[2, 0] - 1e-12
    # stop_at in the past: no step at all
    assert improve(pool, start, 2, -1.0, res.root_box, 0.0, stop_at=0.0) is start


@pytest.mark.parametrize("kind,seed", [("two-level", 0), ("independent", 2)])
def test_exact_bounds_do_not_depend_on_the_local_search(kind, seed):
    with_local = _exact(kind, seed)
    without = _exact(kind, seed, local=False)
    for res in (with_local, without):
        assert all(i.status == "optimal" for i in res.infos)
    tol = TOL * np.maximum(1.0, np.abs(with_local.bounds))
    assert np.all(np.abs(with_local.bounds - without.bounds) <= tol * (1 + 1e-9))


def test_a_local_search_that_finds_nothing_still_closes_every_end(monkeypatch):
    """The tree's own searches take over (they start backed off after a walk): a stuck
    local search costs time, never a bound or the status."""
    pr = _problem("two-level", 0)
    ref = _exact("two-level", 0)
    calls = []

    def stuck(pool, start, *args, **kwargs):
        calls.append(1)
        return start

    monkeypatch.setattr(search, "improve", stuck)
    res = exact_bounds(pr, tol=TOL)
    assert calls
    assert all(i.status == "optimal" for i in res.infos)
    tol = TOL * np.maximum(1.0, np.abs(ref.bounds))
    assert np.all(np.abs(res.bounds - ref.bounds) <= tol * (1 + 1e-9))
    for info in res.infos:
        assert _inside(pr, info.witness)
    lp = lp_bounds(pr).bounds
    assert np.all(res.bounds[:, 0] >= lp[:, 0]) and np.all(res.bounds[:, 1] <= lp[:, 1])


@pytest.mark.parametrize("seed", [0, 3])
def test_restore_finds_the_single_point_of_a_set_at_the_noise_bound(seed):
    """Noise exactly at +-Delta eta with random signs on every sample leaves one point
    (the truth; as in stage 1): no relaxation point is ever accepted, Gauss-Newton steps
    from an OBBT point reach it, and every end closes at once with the truth as witness."""
    data, truth = two_level_data(seed, N=80, deta=0.05)
    pr = EIVProblem(**data)
    res = exact_bounds(pr, tol=TOL, max_nodes=200)
    assert all(i.status == "optimal" for i in res.infos)
    assert sum(i.nodes for i in res.infos) < 100
    for info in res.infos:
        assert _inside(pr, info.witness)
        assert np.allclose(info.witness, truth, atol=1e-6)
    assert np.all(truth >= res.bounds[:, 0] - 1e-12) and np.all(truth <= res.bounds[:, 1] + 1e-12)
    # restore on its own, from the root box centre with zero errors (not a feasible point)
    box = res.root_box
    pool = _Pool(pr)
    pt = restore(pool, [(box.mean(axis=1), np.zeros(pr.N), np.zeros(pr.n_groups))], box)
    assert pt is not None and _inside(pr, pt.theta)


def test_restore_gives_up_on_an_empty_linearisation():
    """Data that no theta explains (output shifted far beyond the bounds): restore returns
    None instead of a point (nothing unverified ever comes out)."""
    data, _ = two_level_data(0, N=60, deta=0.05)
    pr = EIVProblem(**data)
    bad = EIVProblem(pr.y + 10.0 * np.sign(np.sin(np.arange(pr.N))), pr.x, pr.dx, pr.deta,
                     2, 2, steady_state_gain=1.0, groups=pr.groups)
    box = np.array([[-2.0, 2.0], [-1.0, 1.0], [-10.0, 10.0], [-10.0, 10.0]])
    assert restore(_Pool(bad), [(box.mean(axis=1), np.zeros(bad.N), np.zeros(bad.n_groups))],
                   box) is None
