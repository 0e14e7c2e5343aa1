"""Warm starts across the LP shapes of the one-record branch-and-bound (joint/warm.py)."""

from __future__ import annotations

import numpy as np
import pytest
from oracles import GAMMA_TRUE, THETA_TRUE, one_record

from hammerbound.joint import RecordProblem, default_gamma_box, record_box, search, tighten
from hammerbound.joint.modes import DOWN, HOLD, UP
from hammerbound.joint.relaxation import build_relaxation, solve_lp
from hammerbound.joint.warm import BASIC, carry_basis


@pytest.fixture(scope="module")
def node():
    """A random-step record at a large output bound, its OBBT box, and the relaxation over
    it: several samples are ambiguous there (the branch-and-bound splits on them)."""
    u, y, _ = one_record(120, 0.3, "uniform", 5)
    pr = RecordProblem(u, y, 0.3, 2, 2, 1, record_box(2, 2, u, default_gamma_box(u, y, 0.3)))
    box = tighten.obbt(pr, max_rounds=2)
    rel = build_relaxation(pr, box)
    assert rel.structure.n_ambiguous >= 2
    return pr, box, rel


def _solve(rel, k, sense, basis=None):
    c = np.zeros(rel.lp.c.size)
    c[rel.box_cols[k]] = sense
    rel.lp.set_cost(c)
    if basis is not None:
        assert rel.lp.set_basis(basis)
    return solve_lp(rel.lp)


def test_every_row_and_column_has_its_own_key(node):
    pr, box, rel = node
    for keys, n in ((rel.col_keys, rel.lp.A.shape[1]), (rel.row_keys, rel.lp.A.shape[0])):
        assert keys.size == n and np.unique(keys).size == n and np.all(keys > 0)


def test_a_carried_basis_fits_the_child_and_changes_no_bound(node):
    """A child split on an ambiguous sample's branch has other columns and rows than its
    parent. The parent's basis carried over by keys has one basic variable per row, HiGHS
    accepts it, the status is the cold solve's (infeasible children are certified
    infeasible either way), the optimum is the same, and both certified bounds lie below
    it. The start basis can change how tight a certificate from an LP's duals is (a review
    found a cold solve certifying -0.548 for an LP of value 6e-6, warm 4e-6; here, with the
    envelope rows, a cold -0.140 and warm -3.8e-6 for a value of 6.4e-6), never its
    validity."""
    pr, box, rel = node
    k, sense = pr.p + 2, 1.0  # m_r min
    assert _solve(rel, k, sense).status == "optimal"
    snap = rel.lp.snapshot()
    seen = set()
    for a in rel.structure.ambiguous:
        for branch in [HOLD] + ([UP] if a.up else []) + ([DOWN] if a.down else []):
            child = build_relaxation(pr, box, decisions={a.t: branch})
            assert not np.array_equal(child.row_keys, rel.row_keys)
            cold = _solve(child, k, sense)
            child = build_relaxation(pr, box, decisions={a.t: branch})
            carried = carry_basis(snap, rel.col_keys, rel.row_keys, child.col_keys,
                                  child.row_keys, child.lp.rl, child.lp.ru)
            basic = sum(int(np.sum(st == BASIC)) for st in carried)
            assert basic == child.lp.A.shape[0]
            warm = _solve(child, k, sense, basis=carried)
            assert warm.status == cold.status, (a.t, branch)
            seen.add(cold.status)
            if cold.status == "optimal":
                for res in (warm, cold):
                    assert res.bound <= res.value + 1e-9 * max(1.0, abs(res.value))
                # the same LP: the same optimum (its certificates may differ, see above)
                assert warm.value == pytest.approx(cold.value, rel=1e-6, abs=1e-6)
    assert "optimal" in seen


def test_the_search_ends_where_it_ends_without_carrying(monkeypatch):
    """The carried bases change only where the dual simplex starts (and so which optimal
    vertex a node LP returns): one end (c_l max) searched to its tolerance with and without
    them gives the same interval end within the tolerance, and the truth is not cut off."""
    u, y, _ = one_record(120, 0.005, "uniform", 5)
    pr = RecordProblem(u, y, 0.005, 2, 2, 1,
                       record_box(2, 2, u, default_gamma_box(u, y, 0.005)))
    box = tighten.obbt(pr, max_rounds=2)
    k, sense, tol = pr.p + 1, -1.0, 1e-3
    ends = {}
    for carry in (True, False):
        monkeypatch.setattr(search, "CARRY_BASIS", carry)
        r = search.search_end(pr, box, k, sense, tol=tol, max_nodes=3000)
        assert r.status == "optimal"
        ends[carry] = r.bound
    assert abs(ends[True] - ends[False]) <= 2 * tol
    truth = np.concatenate([THETA_TRUE, GAMMA_TRUE])[k]
    assert max(ends.values()) <= sense * truth + 1e-9


def test_obbt_from_the_previous_rows_basis_keeps_every_bound(monkeypatch):
    """OBBT rows start from the previous row's basis (tighten.CARRY_BASIS): the truth is
    inside both boxes, the carried start is really used, and no width grows by more than
    1 % (the rows' LP points differ, and so the later rows' relaxations: the boxes are
    not equal, each is certified)."""
    from oracles import GAMMA_TRUE, THETA_TRUE, one_record

    from hammerbound.joint import RecordProblem, default_gamma_box, record_box, tighten

    u, y, _ = one_record(80, 0.05, "bound", 2)
    pr = RecordProblem(u, y, 0.05, 2, 2, 1, record_box(2, 2, u, default_gamma_box(u, y, 0.05)))
    used = []
    start = tighten.start_from
    monkeypatch.setattr(tighten, "start_from", lambda rel, b: used.append(1) or start(rel, b))
    boxes = {}
    for carry in (False, True):
        monkeypatch.setattr(tighten, "CARRY_BASIS", carry)
        boxes[carry] = tighten.obbt(pr, max_rounds=2)
    assert len(used) > 10  # every row after the first (only with CARRY_BASIS)
    truth = np.concatenate([THETA_TRUE, GAMMA_TRUE])
    for b in boxes.values():
        assert np.all(b[: truth.size, 0] <= truth) and np.all(truth <= b[: truth.size, 1])
    w_cold = boxes[False][:, 1] - boxes[False][:, 0]
    w_carry = boxes[True][:, 1] - boxes[True][:, 0]
    assert np.all(w_carry <= 1.01 * w_cold + 1e-9)


def test_a_solve_past_the_iteration_cap_is_solved_again_from_scratch(node, monkeypatch):
    """A stalled simplex (seen from warm starts) is cut at ITERATION_CAP iterations per row
    and column and solved again cold: the same certified bound, a note that says so, and
    HiGHS's iteration limit as it was before."""
    from hammerbound.joint import relaxation

    pr, box, _ = node
    k = pr.p + 2
    ref = _solve(build_relaxation(pr, box), k, 1.0)
    monkeypatch.setattr(relaxation, "ITERATION_CAP", 0.001)
    rel = build_relaxation(pr, box)
    capped = _solve(rel, k, 1.0)
    assert capped.status == ref.status == "optimal"
    assert capped.bound == pytest.approx(ref.bound, rel=1e-9, abs=1e-12)
    assert "solved again from scratch" in capped.note
    limit = rel.lp.h.getOptionValue("simplex_iteration_limit")
    assert (limit[1] if isinstance(limit, tuple) else limit) == 2**31 - 1


def test_the_re_solve_after_the_cap_stops_when_the_first_solve_would_have(node, monkeypatch):
    """The cold re-solve is part of the same LP's task: it gets the first solve's stop as
    its deadline (not a fresh run limit, which gave up to twice an LP's time limit), and
    the LP's own deadline is given back afterwards."""
    from hammerbound.joint import relaxation

    pr, box, _ = node
    monkeypatch.setattr(relaxation, "ITERATION_CAP", 0.001)
    rel = build_relaxation(pr, box)
    own = rel.lp.deadline
    cls = type(rel.lp)
    solve, seen = cls.solve, []

    def spy(self, **kw):
        seen.append(("deadline", self.deadline))
        out = solve(self, **kw)
        seen.append(("stop", self.stop))
        return out

    monkeypatch.setattr(cls, "solve", spy)
    capped = _solve(rel, pr.p + 2, 1.0)
    assert "solved again from scratch" in capped.note
    assert [k for k, _ in seen] == ["deadline", "stop", "deadline", "stop"]
    first_stop = seen[1][1]
    assert seen[2][1] == (first_stop if own is None else min(own, first_stop))
    assert seen[3][1] <= first_stop
    assert rel.lp.deadline == own
