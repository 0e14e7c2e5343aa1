"""The one-record fit under the *default* backlash box, which is a guess (:mod:`hammerbound.joint.prior`).

A default limit can hold up other ends, or exclude the truth altogether. So when an end
reaches a default limit, the fit is run again with that limit
:data:`~hammerbound.joint.prior.WIDEN_FACTOR` times wider -- when the time left allows it
(twice what the first fit took: the wider box is slower) -- and that fit is reported,
unless the time limit stopped it where the first one had finished: then the first stays,
resting on its box (in the assumptions), and a warning says so. The wider fit's
intervals rest on a weaker assumption and may be wider (an end no record of that input can
bound, e.g. the far dead band of an input that never reverses, still widens the box): so
a fit given the time for the second run may report wider intervals than one without it,
each guaranteed under the box its assumptions list. An empty verdict of the
default box names that box (a backlash beyond it is not excluded). A box the user gave is
used as given.
"""

from __future__ import annotations

import sys
import time
import warnings

from ..exceptions import EmptyFeasibleSetError, SearchLimitWarning
from ..joint import ASSUMED_LIMIT_RTOL, GAMMA_NAMES, WIDEN_FACTOR, at_prior_limit

__all__ = ["search_default_box"]


def search_default_box(search, prior, deadline, progress=False):
    """``(prior, problem, result)`` of ``search(prior) -> (problem, result)``, run again
    with a wider default box where the first run needs it (see the module)."""
    t0 = time.time()
    try:
        problem, res = search(prior)
    except EmptyFeasibleSetError as exc:
        # not searched again wider: over a wider box the relaxation could not certify the
        # common empty verdicts (a reverse-acting plant, a bound below the noise; tried),
        # and those come with their hints. The verdict names the box it rests on instead.
        if prior.user_given:
            raise
        raise _in_default_box(exc, prior) from exc
    rows = limits_reached(res.bounds, problem.p, prior)
    if not rows or not _time_for(deadline, time.time() - t0):
        return prior, problem, res
    wider = prior.widened(rows)
    names = ", ".join(GAMMA_NAMES[i] for i in rows)
    _say(progress, f"{names} reached the default backlash box; fitting again with it "
                   f"{WIDEN_FACTOR:g}x wider")
    try:
        wproblem, wres = search(wider)
    except EmptyFeasibleSetError as exc:  # then the default box is empty too
        raise _in_default_box(exc, wider) from exc
    if _stopped(wres) and not _stopped(res):
        warnings.warn(
            f"{names} reached the default backlash box, and the fit with it "
            f"{WIDEN_FACTOR:g}x wider did not finish within the time limit: the intervals "
            "are those of the default box, and they rest on it (assumptions_); a slope or "
            "dead band beyond it could lie outside them. Give more time "
            "(total_time_limit) or a gamma_box from what you know of the actuator.",
            # warn -> here -> fit_one_record -> _fit_one_record -> fit -> the caller
            SearchLimitWarning, stacklevel=5)
        return prior, problem, res
    return wider, wproblem, wres


def limits_reached(bounds, p, prior) -> list:
    """Rows of the backlash whose upper end is at a default (assumed) limit."""
    if prior.user_given:
        return []
    return [i for i in range(4)
            if at_prior_limit(bounds[p + i, 1], prior.box, i, 1, ASSUMED_LIMIT_RTOL)]


def _time_for(deadline, first) -> bool:
    """Whether the time left allows a second fit: twice what the first took."""
    return deadline is None or deadline - time.time() >= 2.0 * first


def _stopped(res) -> bool:
    return res.details is not None and bool(res.details.stopped_by_time)


def _say(progress, text) -> None:
    if progress:
        print(f"one-record: {text}", file=sys.stderr, flush=True)


def _in_default_box(exc, prior):
    """``exc`` with what its verdict rests on: the default box (a guess), named."""
    return EmptyFeasibleSetError(
        f"{exc} This holds within the default backlash box, an assumption ("
        f"{prior.limits()}): a backlash beyond it (e.g. a state that starts on a line far "
        "from the record's inputs) is not excluded; give a gamma_box from what you know "
        "of the actuator.", side=exc.side, first_index=exc.first_index,
        relaxation=exc.relaxation)
