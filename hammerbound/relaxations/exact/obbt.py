"""Node LPs and optimality-based bound tightening (OBBT) for the branch-and-bound
(:mod:`.bnb`).

A node LP is the McCormick relaxation (:mod:`.mccormick`) of (22.34) on a theta box, or on
long records the same relaxation over a growing working set of equations
(:mod:`.working_set`); every bound it gives is certified over all equations. OBBT shrinks
the starting box (the polytopic LP box) by minimising and maximising every ``theta_k`` over
that relaxation for a few rounds.
"""

from __future__ import annotations

import time

import numpy as np

from ...exceptions import EmptyFeasibleSetError
from ...solvers.highs_process import past
from .mccormick import McCormickRelaxation
from .points import _Screen
from .working_set import GROW_AFTER, WorkingSetRelaxation


def warm_start(lp, basis) -> bool:
    """Warm start ``lp`` from ``basis``: a picklable :meth:`._highs.HighsLP.get_basis`
    (from a worker) or an in-process :meth:`._highs.HighsLP.snapshot` (cheaper: no
    conversion element by element), or None (nothing to do)."""
    if basis is None:
        return False
    if isinstance(basis, tuple):
        return lp.set_basis(basis)
    return lp.restore(basis)


def _relaxation(problem, box, ws):
    """The full McCormick relaxation (``ws`` None) or one on the working set ``ws``."""
    if ws is None:
        return McCormickRelaxation(problem, box)
    return WorkingSetRelaxation(problem, box, ws)


def _solve(relax, screen=None):
    """Solve the node LP of ``relax``; on a working set, add the equations found violated
    at its point and re-solve until none is (every bound on the way is certified: the
    working-set LP relaxes the full one; after :data:`.working_set.GROW_AFTER` re-solves
    the set doubles per round). The result's ``iterations`` sum all re-solves."""
    iters = rounds = 0
    while True:
        res = relax.lp.solve()
        iters += res.iterations
        rounds += 1
        if not isinstance(relax, WorkingSetRelaxation) or res.status != "optimal":
            break
        add = relax.separate(res.x, screen, grow=rounds > GROW_AFTER)
        if add.size == 0:
            break
        relax.add_equations(add)
    res.iterations = iters
    return res


def _obbt_task(problem, box, tasks, bases, deadline=None, ws=None, picklable=True):
    """Solve the OBBT LPs ``tasks`` (list of (k, sense)) on one McCormick model.

    The bases returned are picklable (for joblib workers) or, with ``picklable=False``
    (serial runs), in-process snapshots. Returns a list of ``(bound, theta (p,) or None,
    x or None, basis)`` where ``bound`` is a rigorous lower bound of ``min sense * theta_k``
    over the relaxation (``-inf`` for a task skipped or cut short at ``deadline``, a
    :func:`time.time` timestamp), and the working set at the end (None without one).
    """
    relax = _relaxation(problem, box, ws)
    screen = None if ws is None else _Screen(problem, working_set=True)
    out = []
    for (k, s), basis in zip(tasks, bases, strict=True):
        if deadline is not None:
            left = deadline - time.time()
            if left <= 0:
                out.append((-np.inf, None, basis, 0))
                continue
            relax.lp.deadline = deadline  # HighsLP: a stopped solve keeps its dual bound
        c = np.zeros(relax.ncol)
        c[k] = s
        relax.lp.set_cost(c)
        if ws is None:
            warm_start(relax.lp, basis)
        r = _solve(relax, screen)
        if r.status == "infeasible":
            out.append((np.inf, None, None, r.iterations))
            continue
        out.append((r.bound, None if r.x is None else r.x.copy(),
                    _basis(relax.lp, picklable) if ws is None else None, r.iterations))
    return out, (None if ws is None else relax.equations)


def _basis(lp, picklable):
    return lp.get_basis() if picklable else lp.snapshot()


def _obbt(problem, box, n_jobs=1, rounds=4, rel_improve=0.02, parallel=None, deadline=None,
          ws=None, picklable=None):
    """Optimality-based bound tightening of the theta box on the McCormick relaxation.

    Each round solves ``min/max theta_k`` (k = 1..p) over the relaxation on the current
    box (in parallel when ``n_jobs > 1``) and shrinks the box with the rigorous bounds.
    Every LP stops at ``deadline`` (a :func:`time.time` timestamp, if given) with the
    rigorous bound of its current duals; no further round starts after it. Every round's
    box is a valid outer box. The bases returned are picklable with workers (``parallel``)
    or ``picklable=True`` (the result crosses processes), else in-process snapshots.

    Returns
    -------
    box : ndarray, shape (p, 2)
    roots : dict
        ``(k, sense) -> (bound, x, basis)`` of the last round (the root nodes of the
        searches; the bound stays valid on the final, smaller box).
    thetas : list of ndarray (p,)
        LP points met on the way (feasibility candidates).
    ws : ndarray or None
        With a working set ``ws`` (equation indices) on input: the union of the working
        sets grown by the OBBT LPs (else None).
    """
    p = problem.p
    box = np.array(box, dtype=float)
    tasks = [(k, s) for k in range(p) for s in (1.0, -1.0)]
    bases = {t: None for t in tasks}
    thetas = []
    roots = {}
    nj = max(1, min(n_jobs, len(tasks)))
    chunks = [tasks[i::nj] for i in range(nj)]
    for _ in range(rounds):
        old = box.copy()
        if nj == 1:
            res, ws_new = _obbt_task(problem, box, tasks, [bases[t] for t in tasks], deadline,
                                     ws, picklable=parallel is not None or bool(picklable))
            res = dict(zip(tasks, res, strict=True))
            ws_all = [ws_new]
        else:
            from joblib import delayed

            outs = parallel(delayed(_obbt_task)(problem, box, ch, [bases[t] for t in ch],
                                                deadline, ws)
                            for ch in chunks)
            res = {t: o for ch, (oc, _) in zip(chunks, outs, strict=True)
                   for t, o in zip(ch, oc, strict=True)}
            ws_all = [w for _, w in outs]
        if ws is not None:
            ws = np.unique(np.concatenate([ws, *ws_all]))
        for (k, s), (bnd, x, basis, _) in res.items():
            if not np.isfinite(bnd) and bnd > 0:
                raise EmptyFeasibleSetError(
                    "the McCormick relaxation of (22.34) is certified infeasible inside "
                    "the LP outer box: no theta explains the data within the error "
                    "bounds (the polytopic LP set is a strict outer approximation).",
                    first_index=None, relaxation="exact")
            bases[(k, s)] = basis
            roots[(k, s)] = (bnd, x, basis)
            if x is not None:
                thetas.append(x[:p].copy())
            if s > 0:
                box[k, 0] = min(max(box[k, 0], bnd), box[k, 1])
            else:
                box[k, 1] = max(min(box[k, 1], -bnd), box[k, 0])
        w_old = old[:, 1] - old[:, 0]
        w_new = box[:, 1] - box[:, 0]
        if np.all(w_new >= (1 - rel_improve) * w_old):
            break
        if past(deadline):
            break
    return box, roots, thetas, ws
