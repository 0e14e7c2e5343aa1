"""The exact method's stopping rules are checked in the lower layer too (new-user trial 8:
``exact_bounds(tol=-1)`` was accepted and searched every end to its limits), and a wrong
group array names the estimator's parameter and the shapes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.exceptions import DataValidationError, ParameterValidationError
from hammerbound.relaxations import EIVProblem, exact_bounds


@pytest.fixture(scope="module")
def problem():
    rng = np.random.default_rng(0)
    x = np.repeat(rng.uniform(-1, 1, 10), 4)
    y = lfilter([0.0, 0.5], [1.0, -0.5], x) + rng.uniform(-0.01, 0.01, x.size)
    return EIVProblem(y, x, input_bound=0.0, output_bound=0.01, na=1, nb=1)


@pytest.mark.parametrize("kw, match", [
    ({"tol": -1}, "tol must be a finite number > 0"),
    ({"tol": 0.0}, "tol must be"),
    ({"tol": float("nan")}, "tol must be"),
    ({"tol": True}, "tol must be"),
    ({"max_nodes": -1}, "max_nodes"),
    ({"max_nodes": 2.5}, "max_nodes"),
    ({"time_limit": -1.0}, "time_limit"),
    ({"total_time_limit": float("nan")}, "total_time_limit"),
])
def test_exact_bounds_refuses_bad_stopping_rules_before_any_work(problem, kw, match):
    with pytest.raises(ParameterValidationError, match=match):
        exact_bounds(problem, **kw)


def test_the_estimator_refuses_them_the_same_way(problem):
    est = hb.LinearEIVSetEstimator(1, 1, output_bound=0.01, method="exact", tol=-1)
    with pytest.raises(ParameterValidationError, match="tol must be a finite number > 0"):
        est.fit(problem.x, problem.y)


def test_a_group_array_of_the_wrong_length_names_the_parameter(problem):
    est = hb.LinearEIVSetEstimator(1, 1, output_bound=0.01, method="lp")
    with pytest.raises(DataValidationError, match=r"input_groups=.*\(40,\).*got shape \(39,\)"):
        est.fit(problem.x, problem.y, input_bound=0.01, input_groups=np.zeros(39, int))
