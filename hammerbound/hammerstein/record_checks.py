"""What the one-record path tells about the record itself, before and after its search:
a reverse-acting plant (negative least-squares gain), inputs far from the dead band's
u = 0, and a dead band left over all the inputs (warnings and the text added to an empty
verdict). Split from :mod:`.one_record`."""

from __future__ import annotations

import warnings

import numpy as np

from ..data.gain_sign import negative_gain_hint, record_a1, record_gain
from ..exceptions import DataWarning, EmptyFeasibleSetError
from ..joint.tighten import before_checklist
from ..relaxations.problem import b_lags_of
from ..tables import rounded_text

__all__ = ["record_a1_of", "record_gain_of", "warn_dead_band_covers_record", "warn_gain_sign",
           "warn_inputs_off_zero", "with_gain_sign"]


def _lags(problem):
    """The output and input lags of the model's orders (``1..na``, the ``b_j``'s)."""
    return np.arange(1, problem.na + 1), b_lags_of(problem.nb, problem.nk)


def record_gain_of(problem) -> float:
    """The record's least-squares gain (input -> output, the model's orders)."""
    return record_gain(problem.u, problem.y, *_lags(problem))


def record_a1_of(problem) -> float:
    """The record's least-squares ``A(1)`` (the model's orders)."""
    return record_a1(problem.u, problem.y, *_lags(problem))


def with_gain_sign(exc, problem):
    """``exc`` again, with the hint of a reverse-acting plant when the record's
    least-squares gain (input -> output, the model's orders) is negative."""
    hint = negative_gain_hint(record_gain_of(problem))
    if not hint:
        return exc
    # the likeliest cause first, before the general checklist (recheck 49: it came last
    # in a message of about 1300 characters)
    return EmptyFeasibleSetError(before_checklist(str(exc), hint), side=exc.side,
                                 first_index=exc.first_index, relaxation=exc.relaxation)


def warn_gain_sign(problem, res):
    """A DataWarning when the time limit stopped a fit before it could certify the set
    empty, no point of the set was verified, and the record's least-squares gain is
    negative: the plant *may* be reverse-acting, which the model cannot explain (trial 11:
    ``fit(u, -y)`` under a 30 s limit returned intervals without a word). A fit that ran to
    the end, or verified a point, found the set non-empty: no warning then (a noisy record
    of a plant with a small A(1) can have a negative least-squares gain, review)."""
    d = res.details
    if d is None or not d.stopped_by_time or any(i.witness is not None for i in res.infos):
        return
    gain = record_gain_of(problem)
    if gain < 0:
        warnings.warn(
            f"the time limit stopped the search before it found a point of the set or "
            f"certified it empty, and the record's least-squares gain is negative "
            f"({gain:.3g}): the plant may be reverse-acting (its output falls as its input "
            "rises), which no parameters of the model explain (positive backlash slopes, "
            "unit-gain linear block (22.8)). If it is, fit the negated output (-y); else "
            "give the search more time (total_time_limit).", DataWarning,
            # warn -> here -> fit_one_record -> _fit_one_record -> fit -> the caller
            stacklevel=5)


def warn_inputs_off_zero(u, name="u"):
    """A DataWarning before the search when every input lies on one side of 0, farther
    from it than the inputs' spread: the model's dead band holds u = 0, so a backlash
    working about an operating point (a valve at 50 %) is either no model of the record or
    one the search bounds very slowly. New-user trial 18: a flow loop's OP in 43-57 %
    bounded no backlash parameter in 600 s; shifted by 50 %, tight intervals in 23 s."""
    lo, hi = float(np.min(u)), float(np.max(u))
    gap = lo if lo > 0 else -hi
    if not gap > hi - lo:
        return
    side = "above" if lo > 0 else "below"
    warnings.warn(
        f"the record's inputs lie in [{lo:.4g}, {hi:.4g}], all {side} 0 and farther from it "
        f"than their spread ({hi - lo:.3g}), while the model's dead band [-c_l, c_r] holds "
        f"u = 0. If the actuator works about an operating point (e.g. a valve at 50 %), "
        f"shift {name} by it and the output by its value there (e.g. both by their means, "
        "or by a rest value) and fit again: the search is then much faster, and a dead band "
        "at the operating point becomes one about u = 0. Unshifted, the fit may end at its "
        "time limit with nothing bounded.", DataWarning,
        # warn -> here -> fit_one_record -> _fit_one_record -> fit -> the caller
        stacklevel=5)


def warn_dead_band_covers_record(u, gamma_bounds):
    """A DataWarning when every backlash left has its dead band over all the inputs
    (``c_l > -min u`` and ``c_r > max u``): its lines then stay on both sides of 0 over
    the record, so the inner signal can move only one way (down from a start above 0, up
    from one below). New-user trial 16: an output bound 5x too small left c_l >= 1.21 and
    c_r >= 0.97 over inputs in [-0.98, 0.97] (the time limit stopped the search), with
    only time-limit warnings. Not a verdict of "empty": a record whose output moves one
    way is explained so."""
    lo, hi = float(np.min(u)), float(np.max(u))
    cl, cr = float(gamma_bounds[1, 0]), float(gamma_bounds[3, 0])
    if not (cl > -lo and cr > hi):
        return
    warnings.warn(
        f"every backlash left has its dead band [-c_l, c_r] over all the record's inputs "
        f"[{rounded_text(lo, down=True, digits=6)}, {rounded_text(hi, down=False, digits=6)}] "
        f"(c_l >= {rounded_text(cl, down=True, digits=6)}, c_r >= "
        f"{rounded_text(cr, down=True, digits=6)}): its inner signal can then move only "
        "one way over the whole record. If the output moves both ways, no "
        "parameters explain it -- the output bound is probably too small for the noise, or "
        "the orders too low -- and more time may certify the set empty.", DataWarning,
        # warn -> here -> fit_one_record -> _fit_one_record -> fit -> the caller
        stacklevel=5)
