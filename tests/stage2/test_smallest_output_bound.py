"""An empty stage 2 says the smallest output bound its data leave open (recheck 49: stage 1
said how close its data came to the bound, stage 2 did not): a certified lower figure, so
never above a bound at which the truth explains the data."""

from __future__ import annotations

import re

import numpy as np
import pytest
from oracles import chapter_eiv_data, explains

from hammerbound import EmptyFeasibleSetError, LinearEIVSetEstimator

PHRASE = (r"Within the a priori box \(with the input error bound, the steady-state gain "
          r"constraint and the orders as they are\) the data allow no output error bound "
          r"below ([0-9.e+-]+): the LP set is still empty there")


@pytest.mark.parametrize("seed", [0, 1, pytest.param(2, marks=pytest.mark.deep),
                                  pytest.param(3, marks=pytest.mark.deep)])
def test_the_figure_never_exceeds_a_bound_the_truth_meets(seed):
    """Output errors exactly at +-0.05 (own simulation): the truth explains the data at
    0.05 (checked by our own LP), so no certified figure may exceed 0.05; fitted at 0.02
    the set is empty, and the figure says more than the bound given."""
    data, theta = chapter_eiv_data(N=150, deta=0.05, dx=0.003, seed=seed, at_bound=True)
    assert explains(data, theta)
    est = LinearEIVSetEstimator(output_bound=0.02, method="lp", steady_state_gain=1.0)
    with pytest.raises(EmptyFeasibleSetError) as info:
        est.fit(data["x"], data["y"], input_bound=0.003)
    found = re.search(PHRASE, str(info.value))
    assert found, str(info.value)
    low = float(found[1])
    assert 0.02 < low <= 0.05
    # (the truth itself does not fit at 0.02: the set is empty for a reason)
    assert not explains({**data, "output_bound": 0.02}, theta)


def test_nothing_is_said_when_the_lp_does_not_empty_above_the_bound():
    from hammerbound.relaxations.problem import EIVProblem
    from hammerbound.stage2.smallest_bound import smallest_output_factor, smallest_output_text

    data, _ = chapter_eiv_data(N=60, deta=0.05, dx=0.003, seed=0)
    problem = EIVProblem(**data)  # not empty at its own bound: no factor above 1
    assert smallest_output_factor(problem) == 1.0
    assert smallest_output_text(problem, 1.0) == ""


def test_per_sample_bounds_are_stated_as_a_factor():
    from hammerbound.relaxations.problem import EIVProblem
    from hammerbound.stage2.smallest_bound import smallest_output_text

    data, _ = chapter_eiv_data(N=40, deta=0.05, dx=0.003, seed=0)
    problem = EIVProblem(**{**data, "output_bound": np.linspace(0.01, 0.02, 40)})
    assert "below 1.73 x these bounds" in smallest_output_text(problem, 1.7349)


def test_the_figure_is_sought_only_when_the_message_is_shown(monkeypatch):
    """Order selection drops the empty verdicts of its candidates: the search for the
    figure (up to 10 s each) made a falsified grid 6x slower until it became lazy."""
    import pickle

    import hammerbound.stage2.smallest_bound as sb

    calls = []
    real = sb.smallest_output_factor
    monkeypatch.setattr(sb, "smallest_output_factor",
                        lambda problem: calls.append(1) or real(problem))
    data, _ = chapter_eiv_data(N=80, deta=0.05, dx=0.003, seed=0, at_bound=True)
    est = LinearEIVSetEstimator(output_bound=0.02, method="lp", steady_state_gain=1.0)
    with pytest.raises(EmptyFeasibleSetError) as info:
        est.fit(data["x"], data["y"], input_bound=0.003)
    assert calls == []
    assert re.search(PHRASE, str(info.value)) and calls == [1]
    assert str(info.value) == str(pickle.loads(pickle.dumps(info.value))) and calls == [1]
