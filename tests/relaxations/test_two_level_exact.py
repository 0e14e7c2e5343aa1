"""Exact method on the two-level inner signal: branching on the shared input errors,
warm starts from the parent node and the cut-off re-solve (relaxations/exact/search.py,
relaxations/mccormick.py).

The data are simulated here with plain numpy/scipy (a two-level input through the true
G(q), noise exactly at +-Delta eta with random signs), not with the package.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from oracles import error_scale, two_level_data

import hammerbound.relaxations.exact.search as search
from hammerbound.relaxations.exact.bnb import SearchOptions, exact_bounds
from hammerbound.relaxations.exact.mccormick import McCormickRelaxation, shared_groups
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.problem import EIVProblem
from hammerbound.solvers.highs import LPSolve

TOL = 1e-4


@functools.cache
def _fit(seed, deta, branch_shared=True, at_bound=True):
    data, theta = two_level_data(seed, deta=deta, at_bound=at_bound)
    pr = EIVProblem(**data)
    return pr, theta, exact_bounds(pr, tol=TOL,
                                   options=SearchOptions(shared_branching=branch_shared))


def test_shared_groups_only_for_few_shared_errors():
    data, _ = two_level_data(0)
    pr = EIVProblem(**data)
    assert shared_groups(pr) == 2
    indep = EIVProblem(pr.y, pr.x, pr.dx, pr.deta, 2, 2, steady_state_gain=1.0)
    assert shared_groups(indep) == 0


@pytest.mark.parametrize("seed", [0, 1])
def test_narrowed_dx_box_equals_recentred_problem(seed):
    """set_box with a narrowed [lo, hi] box of the shared input errors gives the same LP
    bounds as a relaxation built on a problem whose nominal levels are moved to the box
    centre with radius (hi - lo) / 2 (McCormick envelopes are shift-invariant)."""
    data, _ = two_level_data(seed)
    pr = EIVProblem(**data)
    box = lp_bounds(pr).bounds
    rng = np.random.default_rng(seed)
    r = pr.dx_group
    lo = -r + rng.uniform(0.1, 0.4, 2) * r
    hi = r - rng.uniform(0.1, 0.4, 2) * r
    relax = McCormickRelaxation(pr, box)
    relax.set_box(np.vstack([box, np.column_stack([lo, hi])]))
    centre = 0.5 * (lo + hi)
    # x - dxv with dxv in [lo, hi]  ==  (x - centre) - dxv' with dxv' in [-rad, rad]
    g = pr.groups
    moved = EIVProblem(pr.y, pr.x - centre[g], (0.5 * (hi - lo))[g], pr.deta, 2, 2,
                       steady_state_gain=1.0, groups=g)
    ref = McCormickRelaxation(moved, box)
    full = McCormickRelaxation(pr, box)
    moved_by = 0.0
    for q in range(pr.p):
        for s in (1.0, -1.0):
            vals = []
            for rel in (relax, ref, full):
                c = np.zeros(rel.ncol)
                c[q] = s
                rel.lp.set_cost(c)
                out = rel.lp.solve()
                assert out.status == "optimal"
                vals.append(out.value)
            # equal up to the outward equation tolerance (1e-9 of the terms, which differ
            # slightly between the two data sets; thin sets amplify it)
            assert vals[0] == pytest.approx(vals[1], abs=1e-5, rel=1e-5)
            # narrowing never loosens the relaxation (up to HiGHS's own optimality tolerance)
            assert vals[0] >= vals[2] - 1e-7 * max(1.0, abs(vals[2]))
            moved_by = max(moved_by, vals[0] - vals[2])
    assert moved_by > 1e-3  # the narrowed box is not a no-op
    # and back to the full box: the original relaxation again
    relax.set_box(np.vstack([box, np.column_stack([-r, r])]))
    fresh = McCormickRelaxation(pr, box)
    for rel in (relax, fresh):
        c = np.zeros(rel.ncol)
        c[pr.na] = 1.0
        rel.lp.set_cost(c)
    assert relax.lp.solve().value == pytest.approx(fresh.lp.solve().value, abs=1e-6)


@pytest.mark.parametrize("seed,deta,at_bound", [(0, 0.05, True), (1, 0.1, True),
                                                (1, 0.1, False), (2, 0.1, False)])
def test_two_level_exact_sound_and_tight(seed, deta, at_bound):
    """Noise exactly at the bound (a single-point set) and uniform inside (a set with
    volume, where the tree has to work)."""
    pr, theta, res = _fit(seed, deta, at_bound=at_bound)
    # the truth is inside
    assert np.all(theta >= res.bounds[:, 0] - 1e-9), (theta, res.bounds)
    assert np.all(theta <= res.bounds[:, 1] + 1e-9), (theta, res.bounds)
    # every witness passes an independent LP and its end is within the gap
    for info in res.infos:
        assert info.status == "optimal"
        assert error_scale(pr, info.witness) <= 1 + 1e-6
        # the stopping rule: gap <= tol * max(1, |value|), value = theta_k at the witness
        assert info.gap <= TOL * max(1.0, abs(info.inner)) * (1 + 1e-9)
    # never wider than the polytopic LP bound
    lp = lp_bounds(pr).bounds
    assert np.all(res.bounds[:, 0] >= lp[:, 0]) and np.all(res.bounds[:, 1] <= lp[:, 1])


@pytest.mark.parametrize("seed,deta", [(1, 0.1), (2, 0.1)])
def test_branching_on_shared_errors_agrees_with_theta_only(seed, deta):
    """Both searches certify their ends within the tolerance of the same exact value (on
    sets with volume, where both trees branch)."""
    _, _, with_dx = _fit(seed, deta, at_bound=False)
    _, _, theta_only = _fit(seed, deta, branch_shared=False, at_bound=False)
    assert sum(i.nodes for i in with_dx.infos) > 8  # the tree did branch
    tol = TOL * np.maximum(1.0, np.abs(with_dx.bounds))
    assert np.all(np.abs(with_dx.bounds - theta_only.bounds) <= tol * (1 + 1e-9))


def test_cut_off_node_with_weak_certificate_is_resolved(monkeypatch):
    """A node LP stopped by the cut-off whose certified bound does not close the node
    (here: no certificate at all) is solved to the end, not split blindly: the search
    still ends with status "optimal" and the same bounds."""
    pr, _, ref = _fit(0, 0.05)
    real = search._solve
    hits = []

    def weak_cutoff(relax, screen=None):
        if relax.lp._cutoff is not None and np.isfinite(relax.lp._cutoff) \
                and relax.lp._cutoff < 1e29:
            hits.append(1)
            return LPSolve("cutoff", -np.inf, np.nan, None, 0)
        return real(relax, screen)

    monkeypatch.setattr(search, "_solve", weak_cutoff)
    res = exact_bounds(pr, tol=TOL, max_nodes=3000)
    assert hits, "the cut-off path was not exercised"
    assert all(i.status == "optimal" for i in res.infos)
    tol = TOL * np.maximum(1.0, np.abs(ref.bounds))
    assert np.all(np.abs(res.bounds - ref.bounds) <= tol * (1 + 1e-9))
