"""What a branch-and-bound node's theta box may lose without losing the minimum of
``sense * theta_k`` (:mod:`.search`): everything above the incumbent (:func:`_cap`) and the
part whose rigorous LP bound already exceeds it (:func:`_reduced_cost_tightening`)."""

from __future__ import annotations

import numpy as np


def _cap(box, k, sense, ub):
    """``box`` restricted to ``sense * theta_k <= ub`` (None if that leaves nothing)."""
    if sense > 0:
        if box[k, 0] > ub:
            return None
        if box[k, 1] > ub:
            box = box.copy()
            box[k, 1] = ub
    else:
        if box[k, 1] < -ub:
            return None
        if box[k, 0] < -ub:
            box = box.copy()
            box[k, 0] = -ub
    return box


def _reduced_cost_tightening(box, r, bound, target):
    """Shrink a node's theta box by reduced-cost bound tightening.

    ``bound`` is the rigorous LP bound of the node and ``r`` (p,) the reduced costs of the
    theta columns behind it (:func:`._highs.row_dual_bound`). That bound holds, with the
    term ``min(r_j l_j, r_j u_j)`` updated, for any sub-box; the McCormick relaxation of
    a sub-box is tighter still. So the part ``theta_j > l_j + (target - bound) / r_j``
    (``r_j > 0``; mirrored for ``r_j < 0``) has relaxed value ``>= target`` and is cut off.
    The cut is widened by a relative 1e-9 to stay on the safe side of rounding.

    Returns ``(new_box, cut)`` where ``cut`` says whether anything was removed.
    """
    slack = target - bound
    if not (np.isfinite(slack) and slack > 0):
        return box, False
    box = box.copy()
    cut = False
    with np.errstate(divide="ignore"):
        d = slack / np.abs(r) * (1.0 + 1e-9)
    d = d + 1e-12 * np.maximum(1.0, np.abs(box).max(axis=1))
    for j in np.flatnonzero(r > 0):
        hi = box[j, 0] + d[j]
        if hi < box[j, 1]:
            box[j, 1], cut = hi, True
    for j in np.flatnonzero(r < 0):
        lo = box[j, 1] - d[j]
        if lo > box[j, 0]:
            box[j, 0], cut = lo, True
    return box, cut


def _box_end(box, k, sense):
    """The end of ``box`` that bounds ``min sense * theta_k`` from below."""
    return float(box[k, 0]) if sense > 0 else -float(box[k, 1])
