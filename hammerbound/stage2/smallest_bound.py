"""The smallest output error bound an empty stage 2 leaves open: a certified lower figure.

A smaller output bound can only shrink the set (22.34), so a bound at which the set is
certified empty proves it empty for every smaller one. When stage 2 is empty at the bound
given, the polytopic LP is solved at larger multiples of it (doubling, then bisection), and
the largest multiple it certifies empty is stated: "the data allow no output bound below X"
(new-user trial 17 and recheck 49: stage 1 said how close its data came to the bound,
stage 2 did not). It is a lower figure: the LP set is an outer set, so the smallest bound
at which a model explains the data can be larger; never smaller.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..exceptions import EmptyFeasibleSetError, SolverError

__all__ = ["LazyText", "largest_empty_factor", "lower_bound_words", "smallest_output_factor",
           "smallest_output_text"]

#: at most this many doublings of the bound (2**10 times the bound given)
MAX_DOUBLINGS = 10
#: bisection steps after the doubling: the factor to 2**-7 of its bracket
BISECTIONS = 7
#: seconds the search may take in all (on the error path of a fit)
TIME_BUDGET = 10.0


def _empty(problem, factor) -> bool | None:
    """Whether the LP certifies the set empty at ``factor`` times the output bounds (None:
    the solver gave no decision)."""
    from ..relaxations.lp import lp_bounds

    scaled = dataclasses.replace(problem, output_bound=problem.deta * factor)
    try:
        lp_bounds(scaled, check_box=False)
    except EmptyFeasibleSetError:
        return True
    except SolverError:
        return None
    return False


class LazyText:
    """A message part computed when the message is first shown (``str``), then kept; it
    pickles as its text. An empty verdict caught and dropped (order selection, a
    cross-validation fold) then never pays for the smallest-bound search (it had made
    ``OrderSelectionCV`` on a falsified grid 6x slower: 1.7 -> 10.1 s)."""

    def __init__(self, make):
        self._make, self._text = make, None

    def __str__(self) -> str:
        if self._text is None:
            self._text, self._make = str(self._make()), None
        return self._text

    def __repr__(self) -> str:
        return repr(str(self))

    def __reduce__(self):
        return (str, (str(self),))


def smallest_output_factor(problem, time_budget: float = TIME_BUDGET) -> float:
    """The largest factor ``s >= 1`` found at which the LP certifies the set empty with the
    output bounds multiplied by ``s`` (1.0 when the LP does not certify it above 1, or the
    time is up at once): no output bound below ``s`` times the given ones lets a model of
    these orders, input bounds and a priori box explain the data."""
    return largest_empty_factor(lambda f: _empty(problem, f), time_budget)


def largest_empty_factor(empty_at, time_budget: float = TIME_BUDGET) -> float:
    """The largest factor ``s >= 1`` at which ``empty_at(s)`` certified the set empty
    (True; False: not certified; None: no decision, the search stops), by doubling from 1
    and then bisection, within ``time_budget`` seconds. Only certified factors are
    returned, so the result is a lower figure of the smallest bound that explains the
    data (emptiness at ``s`` proves it at every smaller bound)."""
    stop = time.monotonic() + float(time_budget)
    last = [0.0]  # seconds of the last decision: one that would end past the budget is not
                  # started (review 51: N = 3000 took 17.6 s against a budget of 10 s)

    def decide(factor):
        if time.monotonic() + last[0] > stop:
            return None
        t0 = time.monotonic()
        out = empty_at(factor)
        last[0] = time.monotonic() - t0
        return out

    lo, hi = 1.0, None
    for _ in range(MAX_DOUBLINGS):
        decision = decide(2.0 * lo)
        if decision is None:
            return lo
        if not decision:
            hi = 2.0 * lo
            break
        lo *= 2.0
    if hi is None:
        return lo
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        decision = decide(mid)
        if decision is None:
            break
        lo, hi = (mid, hi) if decision else (lo, mid)
    return lo


def lower_bound_words(deta, factor) -> str:
    """``X`` of "no output error bound below X": ``factor`` times a scalar bound, rounded
    down, or "f x these bounds" for per-sample bounds ("" when ``factor`` is not above 1)."""
    from ..tables import rounded_text

    if not factor > 1.0:
        return ""
    deta = np.asarray(deta, dtype=float)
    if np.all(deta == deta.flat[0]):
        return rounded_text(factor * float(deta.flat[0]), down=True, digits=3)
    return f"{rounded_text(factor, down=True, digits=3)} x these bounds"


def smallest_output_text(problem, factor) -> str:
    """The sentence of an empty stage 2's message (empty when ``factor`` says nothing
    beyond the bound given)."""
    low = lower_bound_words(problem.deta, factor)
    if not low:
        return ""
    gain = "" if problem.gain is None else ", the steady-state gain constraint"
    return (f"Within the a priori box (with the input error bound{gain} and the orders as "
            f"they are) the data allow no output error bound below {low}: the LP set is "
            "still empty there. A system outside the box, or of another gain, may need "
            "less.")
