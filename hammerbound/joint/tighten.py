"""Certified boxes of the one-record set by optimality-based bound tightening (OBBT).

:func:`obbt` shrinks a box row by row with the LP relaxation (:mod:`.relaxation`): each
bound is the certified bound of an LP, and the relaxation is rebuilt after each row, so
what one row decides (e.g. the branch of a sample) helps the next. :func:`outer_leaves`
cuts the a priori box into parts by dead band and slope, drops the parts certified empty
and tightens the rest: the leaves whose union holds the whole set, where the per-end
branch-and-bound of :mod:`.search` starts (``method="lp"`` reports their hull). A long
record is tightened over its windows first (:mod:`.windows`).
"""

from __future__ import annotations

import time
from functools import partial

import numpy as np

from ..exceptions import EmptyFeasibleSetError
from ..solvers.highs_process import past
from .prior import reversal_summary
from .problem import RecordProblem
from .progress import PROGRESS_EVERY
from .relaxation import build_relaxation, solve_lp
from .warm import keyed_basis, start_from
from .windows import window_problem, windows

__all__ = ["before_checklist", "obbt", "outer_leaves"]

# OBBT of the leaves: at most this many rounds, and stop when a round shrinks no width by
# more than this fraction (measured on the chapter's record at N = 120: to the 1 % fixed
# point took 1745 LPs, most of them shrinking boxes by a few per cent per round)
LEAF_ROUNDS = 6
LEAF_SHRINK = 0.05
# on a long record, the partition tightens its boxes over the windows only (one round) and
# the leaves get LEAF_ROUNDS rounds over the windows before those over the whole record
# (:mod:`.windows`; measured on the chapter's random-step record, N = 1000, Delta eta =
# 0.05, method "lp", one core: 230 s without windows, 138 s with, the same widths to 1e-5)

#: What an EmptyFeasibleSetError of the one-record search suggests.
EMPTY_HINT = ("Likely causes, commonest first: (1) an output bound too small for the noise "
              "(values rounded in the file add up to half their last digit: noise within "
              "0.01 written with 6 decimals needs 0.0100005); (2) orders na, nb or a delay "
              "nk that do not fit the plant; (3) input and output columns swapped; (4) a "
              "gamma_box you gave that misses the backlash; (5) backlash lines that cross "
              "inside the record's input range (the model needs m_l (u + c_l) >= "
              "m_r (u - c_r) at every input; unequal slopes cross at u = (m_l c_l + m_r c_r) / "
              "(m_r - m_l)); (6) a dead band [-c_l, c_r] that does not "
              "hold u = 0 (an offset, e.g. a valve's input in percent: shift u first, e.g. "
              "by the input at which the output rests, and y by that rest value; the model "
              "has no output offset either); (7) samples that are not consecutive (a "
              "cross-validation split such as KFold joins pieces of the record: use "
              "TimeSeriesSplit).")

def before_checklist(text: str, sentence: str) -> str:
    """``text`` (an empty verdict's message) with ``sentence`` put before its checklist
    :data:`EMPTY_HINT` (the likelier or more telling statement first, recheck 49), or at
    its end when it has none."""
    if EMPTY_HINT in text:
        return text.replace(EMPTY_HINT, f"{sentence} {EMPTY_HINT}", 1)
    return f"{text} {sentence}"


#: The first LP of a row's relaxation starts from the previous row's basis (carried over by
#: keys where the relaxation changed, :mod:`.warm`), by the primal simplex; False: cold.
#: Measured on the benchmark's random-step record (N = 300, method "lp", one core, CPU
#: time): 15.7 s against 18.5 s at Delta eta = 0.05 (two runs each, alternating), 20.6 s
#: against 23.0 s at 0.3; the dual simplex from the carried basis gained nothing (19.1 s,
#: 23.1 s). The final bounds moved by at most 4e-6 of their widths (every one certified
#: from its own LP's duals; the rows' LP points differ, and so later relaxations).
CARRY_BASIS = True

# the partition of the backlash box stops splitting at this many boxes (a record that
# cannot tell the slopes or gaps apart would otherwise give parts**4 of them)
MAX_PARTS = 48


def _obbt_order(problem):
    """OBBT order: the linear block's poles (set by the output's own dynamics), the first
    inner value and the dead band (which decide the samples' branches), then the slopes
    and the ``b_j`` (which the first ones make tight)."""
    p, na = problem.p, problem.na
    return [*range(na), p + 4, p + 1, p + 3, p, p + 2, *range(na, p)]


def _tighten_one(problem, box, k, deadline=None, on_stop=None, basis=None, hull=None):
    """Certified bounds of row ``k`` from one relaxation (None: certified empty), the LP
    points and the basis of the last LP (``(snapshot, column keys, row keys)``, or None);
    the LPs stop at ``deadline`` or their time limit (keeping the bounds they certify;
    ``on_stop()`` is called for each LP that ended before optimality). ``basis``, from the
    previous row (:func:`obbt`), is where the first LP starts (see :data:`CARRY_BASIS`);
    ``hull``: :func:`~.relaxation.build_relaxation`'s."""
    rel = build_relaxation(problem, box, deadline=deadline, hull=hull)
    warm = CARRY_BASIS and basis is not None and start_from(rel, basis)
    out = box[k].copy()
    points = []
    for sense in (1.0, -1.0):
        c = np.zeros(rel.lp.c.size)
        c[rel.box_cols[k]] = sense
        rel.lp.set_cost(c)
        # the primal simplex after a change of the cost only (the second solve), or from
        # the previous row's basis, which is near primal feasible for this row's LP
        res = solve_lp(rel.lp, primal=sense < 0 or warm)
        if res.status == "infeasible":
            return None, points, None
        if res.status != "optimal" and on_stop is not None:
            on_stop()
        if sense > 0:
            out[0] = max(out[0], res.bound)
        else:
            out[1] = min(out[1], -res.bound)
        if res.x is not None:
            points.append(res.x[rel.box_cols])
    last = keyed_basis(rel) if res.status == "optimal" else None
    return (None if out[0] > out[1] else out), points, last


def obbt(problem: RecordProblem, box=None, *, max_rounds=30, shrink=0.01, deadline=None,
         on_point=None, rows=None, on_stop=None, hull=None):
    """Shrink the box by OBBT rounds until a round shrinks no width by more than
    ``shrink`` (relative). Sequential: the relaxation is rebuilt after each row, so what one
    row's bounds decide (e.g. the branch of a sample) helps the next. Every bound is
    certified; ``on_point(x)`` sees each LP point, ``on_stop()`` each LP that ended before
    optimality (its time limit).

    Raises
    ------
    EmptyFeasibleSetError
        An LP of the relaxation is certified infeasible: no parameters explain the record.
    """
    box = problem.box.copy() if box is None else np.array(box, dtype=float)
    order = _obbt_order(problem) if rows is None else list(rows)
    basis = None
    for _ in range(max_rounds):
        old = box.copy()
        for k in order:
            if past(deadline):  # every row so far is certified: stop here
                return box
            row, points, basis = _tighten_one(problem, box, k, deadline, on_stop, basis,
                                              hull)
            if row is None:
                raise EmptyFeasibleSetError(
                    "no backlash and linear block explain the record within the bounds "
                    "(the relaxation of the one-record set is certified infeasible). "
                    + EMPTY_HINT)
            box[k] = row
            if on_point is not None:
                for x in points:
                    on_point(x)
        w_old = old[:, 1] - old[:, 0]
        w_new = box[:, 1] - box[:, 0]
        if np.all(w_old - w_new <= shrink * np.maximum(w_old, 1e-300)):
            break
        if past(deadline):
            break
    return box


def workers(n_jobs, n) -> int:
    """Processes that :func:`map_jobs` runs ``n`` jobs on with ``n_jobs`` (1: in this
    process)."""
    if n_jobs == 1 or n < 2:
        return 1
    from joblib import effective_n_jobs

    return max(1, min(effective_n_jobs(n_jobs), n))


#: the least time left before the deadline for which :func:`map_jobs` starts worker
#: processes (loky's took 1-3 s to start on a loaded 2-core machine)
POOL_MIN_SECONDS = 5.0


def pool_size(n_jobs, n, deadline=None) -> int:
    """The processes :func:`map_jobs` uses for ``n`` items: :func:`workers`, or 1 with less
    than :data:`POOL_MIN_SECONDS` left before ``deadline``."""
    short = deadline is not None and deadline - time.time() < POOL_MIN_SECONDS
    return 1 if short else workers(n_jobs, n)


def map_jobs(fn, items, n_jobs, each=None, deadline=None):
    """``[fn(*a) for a in items]``, over :func:`workers` processes (joblib) when that
    pays; ``each(result)`` is called in this process as each result arrives (in order).
    With less than :data:`POOL_MIN_SECONDS` left before ``deadline`` the items run here
    (each stops at the deadline), where starting the workers can take longer than that
    (a fit with ``total_time_limit=0.5`` and ``n_jobs=2`` took 5 s, review)."""
    procs = pool_size(n_jobs, len(items), deadline)
    if procs == 1:
        results = (fn(*a) for a in items)
    else:
        from joblib import Parallel, delayed

        results = Parallel(n_jobs=procs, return_as="generator")(
            delayed(fn)(*a) for a in items)
    out = []
    for r in results:
        out.append(r)
        if each is not None:
            each(r)
    return out


def _window_obbt(problem, box, rows, deadline, max_rounds, shrink, on_stop=None,
                 hull=None):
    """``box`` tightened by OBBT over the record's windows (:mod:`.windows`), or None
    when a window certifies it empty."""
    p = problem.p
    for s, e in windows(problem):
        wp = window_problem(problem, box, s, e)
        try:
            wb = obbt(wp, wp.box, max_rounds=max_rounds, shrink=shrink, rows=rows,
                      deadline=deadline, on_stop=on_stop, hull=hull)
        except EmptyFeasibleSetError:
            return None
        box = box.copy()
        box[: p + 4] = wb[: p + 4]
        if s == 0:
            box[p + 4] = wb[p + 4]
    return box


def _part_obbt(problem, box, rows, deadline, max_rounds=1, shrink=0.01, window_rounds=0,
               full=True, hull=None):
    """OBBT of one part in a worker: ``(box or None if certified empty, LP points, number
    of LPs that ended before optimality)``; first ``window_rounds`` rounds over the windows
    of a long record, then (``full``, and always for a record too short for windows) over
    the whole record."""
    points, stops = [], []
    on_stop = partial(stops.append, 1)
    if window_rounds and windows(problem):
        box = _window_obbt(problem, box, rows, deadline, window_rounds, shrink, on_stop,
                           hull)
        if box is None or not full:
            return box, points, len(stops)
    try:
        box = obbt(problem, box, max_rounds=max_rounds, shrink=shrink, rows=rows,
                   deadline=deadline, on_point=points.append, on_stop=on_stop, hull=hull)
    except EmptyFeasibleSetError:
        return None, points, len(stops)
    return box, points, len(stops)


def _partition(problem, prior, parts, deadline, n_jobs=1, on_stop=None, progress=None):
    """Boxes covering the set whose backlash widths are at most ``1/parts`` of the prior's
    (each tightened in ``a``, ``z0``, ``m`` and ``c`` by the relaxation; boxes certified
    empty are dropped; past ``MAX_PARTS`` boxes the rest are kept as they are). The boxes
    of one generation are tightened in parallel (``n_jobs``); ``progress`` (a
    :class:`.progress.RecordProgress`) gets a line per generation."""
    p = problem.p
    cols = (p, p + 1, p + 2, p + 3)
    rows = [*range(problem.na), p + 4, p, p + 2, *cols]
    res = np.array([max(prior[k, 1] - prior[k, 0], 1e-300) / parts for k in cols])
    # one round per generation, over the windows only on a long record
    # without the envelope rows (relaxation.HULL_ROWS: they cost, not helped, here)
    part = partial(_part_obbt, max_rounds=1, shrink=0.01, window_rounds=1, full=False,
                   hull=False)
    queue, out = [prior.copy()], []
    generation = 0
    while queue:
        if past(deadline):
            if progress is not None:
                progress.line(f"partition stopped by the time limit, {len(out + queue)} "
                              "part(s) kept as they are")
            return out + queue
        generation += 1
        if progress is not None:  # its summary line follows
            progress.start(f"partition generation {generation}, part", len(queue),
                           every=PROGRESS_EVERY, last=False)
        done = map_jobs(part, [(problem, b, rows, deadline) for b in queue], n_jobs,
                        deadline=deadline, each=None if progress is None
                        else lambda _r: progress.done())
        n_tightened, n_done = len(done), len(out)
        queue = []
        for b, _points, n_stopped in done:
            if n_stopped and on_stop is not None:
                on_stop(n_stopped)
            if b is None:
                continue
            w = np.array([b[k, 1] - b[k, 0] for k in cols])
            if np.any(w > res) and len(out) + len(queue) + 2 <= MAX_PARTS:
                j = cols[int(np.argmax(w / res))]
                lo, hi = b.copy(), b.copy()
                lo[j, 1] = hi[j, 0] = 0.5 * (b[j, 0] + b[j, 1])
                queue.extend([lo, hi])
            else:
                out.append(b)
        if progress is not None:
            progress.close()
            empty = sum(b is None for b, _, _ in done)
            progress.line(f"partition generation {generation}: {n_tightened} part(s) "
                          f"tightened, {empty} certified empty, {len(out) - n_done} kept, "
                          f"{len(queue)} to tighten next")
    return out


def _leaf_obbt(problem, box, deadline):
    """A leaf's OBBT (:func:`_part_obbt`, the search of each end does the rest: its rounds
    stop once they pay little) and whether the deadline had passed when it returned,
    judged in the worker (a leaf delivered late, behind a slower one, was still tightened
    in time)."""
    t0 = time.perf_counter()
    out = _part_obbt(problem, box, None, deadline, max_rounds=LEAF_ROUNDS,
                     shrink=LEAF_SHRINK, window_rounds=LEAF_ROUNDS)
    return (*out, past(deadline), time.perf_counter() - t0)


def _leaf_outcome(result) -> str:
    """What a leaf's progress line says: a leaf that returned after the deadline was cut
    short by it (trial 11: leaves skipped at the deadline were said to be "tightened")."""
    if result[0] is None:
        return "certified empty"
    if result[3]:
        return "time limit reached (kept as far as it was tightened)"
    return "tightened"


def outer_leaves(problem: RecordProblem, box=None, *, parts=8, deadline=None,
                 on_point=None, n_jobs=1, on_stop=None, progress=None, on_pace=None):
    """Certified boxes whose union holds the whole set.

    The dead band decides which samples are ambiguous, and a wide dead-band range leaves
    the relaxation too weak to bound anything. So the widths of ``c_l`` and ``c_r`` are
    first brought below ``1/parts`` of their a priori range: each box's ``c`` bounds are
    tightened by the relaxation (empty boxes are dropped, certified) and the wider ``c``
    is bisected while still too wide; OBBT rounds then drop the boxes that are empty and
    shrink the rest (the leaves). On the chapter's
    records, boxes of the wrong dead band are certified empty by their first LPs. The
    parts are tightened over ``n_jobs`` processes. On a long record the parts are
    tightened over its windows only, and the leaves over its windows before the whole
    record (:mod:`.windows`: every window is a relaxation, at a fraction of the cost).

    ``on_stop(n)`` is told of the ``n`` LPs of a part that ended before optimality (their
    time limit, :data:`~.relaxation.LP_TIME_LIMIT`): their bounds are certified but weaker.
    ``progress`` (a :class:`.progress.RecordProgress`) shows the partition and the leaves.
    ``on_pace(cut, seconds)`` is told how many leaves the deadline cut short and the mean
    seconds of those tightened in time (new-user trial 18: "raise the time limit" said
    not by how much; 22 of 78 leaves had taken about 2 s each).

    Raises EmptyFeasibleSetError when every box is empty.
    """
    prior = problem.box if box is None else np.asarray(box, dtype=float)
    if reversal_summary(problem.u)["monotone"]:
        parts = 1  # one line only is ever active: nothing can tell the dead bands apart
    todo = _partition(problem, prior, parts, deadline, n_jobs, on_stop, progress)
    if progress is not None:
        progress.start("leaf", len(todo), every=PROGRESS_EVERY)
    done = map_jobs(_leaf_obbt, [(problem, b, deadline) for b in todo], n_jobs,
                    deadline=deadline,
                    each=None if progress is None
                    else lambda r: progress.done(_leaf_outcome(r)))
    in_time = [sec for *_, late, sec in done if not late]
    said = [_leaf_outcome(r) for r in done]
    # a leaf certified empty after the deadline was not cut short (review 52)
    cut = len(said) - said.count("tightened") - said.count("certified empty")
    if progress is not None:
        progress.close()
        progress.line(f"leaves: {said.count('tightened')} tightened, "
                      f"{said.count('certified empty')} certified empty, {cut} cut short by "
                      "the time limit")
    if on_pace is not None and cut and in_time:
        on_pace(cut, float(np.mean(in_time)))
    out = []
    for b, points, n_stopped, _late, _sec in done:
        if n_stopped and on_stop is not None:
            on_stop(n_stopped)
        if on_point is not None:
            for x in points:
                on_point(x)
        if b is not None:
            out.append(b)
    if not out:
        raise EmptyFeasibleSetError(
            "no backlash and linear block explain the record within the bounds (the "
            "relaxation is certified infeasible on every part of the a priori box). "
            + EMPTY_HINT)
    return out
