"""How close a record came to explaining itself, for an empty one-record verdict.

A smaller output bound can only shrink the one-record set, so a bound at which its
relaxation is certified infeasible proves it empty for every smaller one: the verdict
states the largest such multiple of the bound given that a short search finds (new-user
trial 18: stage 1 and stage 2 said how close their data came to the bound, one record did
not). Split from :mod:`.one_record`.
"""

from __future__ import annotations

import sys
import time
import warnings

from ..exceptions import EmptyFeasibleSetError
from ..joint import record_bounds
from ..joint.tighten import before_checklist
from ..stage2.smallest_bound import LazyText, largest_empty_factor, lower_bound_words

__all__ = ["SMALLEST_BUDGET", "with_smallest_bound"]


#: seconds the smallest-bound search of an empty verdict may take: twice the verdict's
#: time, within these limits
SMALLEST_BUDGET = (2.0, 30.0)


def with_smallest_bound(exc, problem_at, ob, prior, lin, spent):
    """``exc`` whose message gains the sentence of :func:`_smallest_bound_text` when it is
    first shown (a verdict caught and dropped, e.g. in order selection, costs nothing)."""
    text = str(exc)
    return EmptyFeasibleSetError(
        LazyText(lambda: _smallest_bound_text(text, problem_at, ob, prior, lin, spent)),
        side=exc.side, first_index=exc.first_index, relaxation=exc.relaxation)


def _smallest_bound_text(text, problem_at, ob, prior, lin, spent):
    """``text`` with "the record allows no output bound below X": the relaxation
    (``method="lp"``) on ``problem_at(factor)`` (the record's problem with its output bound
    ``ob`` times ``factor``) at doubled, then bisected factors, each certified empty or not
    within the time left; only certified factors count, so X can only err low
    (:func:`~hammerbound.stage2.smallest_bound.largest_empty_factor`). ``spent``: the
    seconds the verdict took (the search may take twice that, within
    :data:`SMALLEST_BUDGET`, and each factor's relaxation twice that, at least 0.5 s: an
    emptiness the relaxation certifies comes about as fast as the verdict did)."""
    budget = min(SMALLEST_BUDGET[1], max(SMALLEST_BUDGET[0], 2.0 * spent))
    stop = time.time() + budget
    if lin.progress:
        print(f"one-record: the set is empty; seeking the smallest output bound the record "
              f"allows (at most {budget:.0f} s)", file=sys.stderr, flush=True)

    def empty_at(factor):
        if stop - time.time() < 0.5:
            return None
        with warnings.catch_warnings():  # a search at a larger bound: its own words
            warnings.simplefilter("ignore")  # (time limits ...) are not the user's
            try:
                record_bounds(problem_at(factor), method="lp", n_jobs=lin.n_jobs,
                              deadline=min(stop, time.time() + max(0.5, 2.0 * spent)))
            except EmptyFeasibleSetError:
                return True
        return False  # not certified (a set, or the time ran out)

    low = lower_bound_words(ob, largest_empty_factor(empty_at, budget))
    if not low:
        return text
    box = ("the gamma_box you gave" if prior.user_given else
           f"the backlash in {prior.limits()}")
    sentence = (f"The record allows no output error bound below {low} (the relaxation is "
                f"still certified infeasible there, with {box} and the orders as they are).")
    return before_checklist(text, sentence)  # whose first cause is the output bound
