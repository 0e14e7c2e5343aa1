"""The two-level inner signal with the LP method (new-user trial 7): the LP method bounds
every equation's errors by their worst case, so shared errors cannot tighten it; the
summary said "inner signal two-level" as if they did."""

from __future__ import annotations

import numpy as np
import pytest

import hammerbound as hb


@pytest.fixture(scope="module")
def fits():
    ex = hb.chapter_example(0.05, N=120, random_state=2)
    out = {}
    for inner in ("independent", "two-level"):
        out[inner] = hb.HammersteinBacklashIdentifier(
            hb.BacklashSetEstimator(0.05), hb.LinearEIVSetEstimator(output_bound=0.05, method="lp"),
            inner_signal=inner).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    return out


def test_the_lp_method_gives_the_same_intervals_for_both_inner_signals(fits):
    np.testing.assert_array_equal(fits["two-level"].linear_.bounds_,
                                  fits["independent"].linear_.bounds_)


def test_the_summary_says_the_lp_method_does_not_use_the_two_levels(fits):
    assert "not used by method 'lp'" in fits["two-level"].summary()
    assert "not used" not in fits["independent"].summary()
