"""Warm starts of the branch-and-bound's node LPs across changes of the LP's shape.

A child split on a sample's branch (:func:`~.search._sample_children`) has another
relaxation than its parent: the sample's value variable, its products and their envelope
rows go away, rows of the decided branch come in, and later samples may change form. Its
parent's simplex basis then does not fit, and the child used to start cold: 88 ms per LP
against 17 ms warm on an end of a random-step record (N = 300, Delta eta = 0.3), where most
of an end's first LPs are such children. :func:`carry_basis` maps the parent's basis onto
the child's LP by the keys of their columns and rows (:func:`.relaxation.key`): a column or
row in both keeps its status, a new column starts at its lower bound, a new row basic,
and the number of basic variables is then made equal to the number of rows (the result is
a basis for :meth:`~hammerbound.solvers.highs.HighsLP.set_basis`). It is only a starting
point for the dual simplex: every bound is still certified from the duals
of the child's own solve (:class:`~hammerbound.solvers.highs.HighsLP`).
"""

from __future__ import annotations

import highspy
import numpy as np

from ..solvers.highs import basis_arrays

__all__ = ["carry_basis", "keyed_basis", "start_from"]

_ST = highspy.HighsBasisStatus
LOWER, BASIC, UPPER, ZERO = (int(_ST.kLower), int(_ST.kBasic), int(_ST.kUpper),
                             int(_ST.kZero))


def _carry(old_keys, old_status, new_keys, default):
    """Statuses of ``new_keys``: those of equal ``old_keys``, else ``default``; and which
    were found."""
    order = np.argsort(old_keys, kind="stable")
    ks = old_keys[order]
    pos = np.clip(np.searchsorted(ks, new_keys), 0, max(ks.size - 1, 0))
    found = (ks.size > 0) & (ks[pos] == new_keys) & (new_keys >= 0)
    out = np.full(new_keys.size, default, dtype=np.int64)
    out[found] = old_status[order[pos[found]]]
    return out, found


def _nonbasic_row(lo, hi):
    """The nonbasic status of rows with bounds ``lo, hi``: at a finite bound, else zero."""
    return np.where(np.isfinite(lo), LOWER, np.where(np.isfinite(hi), UPPER, ZERO))


def carry_basis(snap, old_cols, old_rows, new_cols, new_rows, row_lo, row_hi):
    """``(col_status, row_status)`` for the LP with column and row keys ``new_cols``,
    ``new_rows`` (row bounds ``row_lo``, ``row_hi``; :meth:`HighsLP.set_basis` takes them)
    from ``snap``, a basis of the LP keyed ``old_cols``, ``old_rows``; None if nothing
    fits."""
    old_cs, old_rs = basis_arrays(snap)
    cs, cfound = _carry(old_cols, old_cs, new_cols, LOWER)
    rs, rfound = _carry(old_rows, old_rs, new_rows, BASIC)
    if not cfound.any():
        return None
    excess = int(np.sum(cs == BASIC) + np.sum(rs == BASIC)) - new_rows.size
    if excess > 0:  # too many basic: new rows first, then any row, leave the basis
        cand = np.flatnonzero((rs == BASIC) & ~rfound)
        cand = np.concatenate([cand, np.flatnonzero((rs == BASIC) & rfound)])[:excess]
        rs[cand] = _nonbasic_row(row_lo[cand], row_hi[cand])
        excess -= cand.size
        if excess > 0:
            cand = np.flatnonzero(cs == BASIC)[:excess]
            cs[cand] = LOWER
    elif excess < 0:  # too few: the slacks of nonbasic rows enter (the last rows first)
        cand = np.flatnonzero(rs != BASIC)[::-1][: -excess]
        rs[cand] = BASIC
    return cs, rs


def keyed_basis(rel):
    """The basis of the relaxation ``rel``'s last solve with the keys of its columns and
    rows (what :func:`start_from` takes)."""
    return rel.lp.snapshot(), rel.col_keys, rel.row_keys


def start_from(rel, basis, carry: bool = True) -> bool:
    """Start the relaxation ``rel``'s LP from ``basis`` (:func:`keyed_basis` of another LP
    of the same record): restored when the two LPs have the same columns and rows, else,
    with ``carry``, carried over by their keys (:func:`carry_basis`); whether it was set."""
    snap, ck, rk = basis
    if np.array_equal(ck, rel.col_keys) and np.array_equal(rk, rel.row_keys):
        return bool(rel.lp.restore(snap))
    if not carry:
        return False
    carried = carry_basis(snap, ck, rk, rel.col_keys, rel.row_keys, rel.lp.rl, rel.lp.ru)
    return bool(rel.lp.set_basis(carried))
