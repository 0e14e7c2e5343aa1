"""The causes named for a backlash end the record does not bound (joint.prior.unidentified)."""

import numpy as np
import pytest

from hammerbound.joint.prior import unidentified

NAMES = ("m_l", "c_l", "m_r", "c_r")
PRIOR = np.array([[1e-3, 10.0], [0.0, 2.0], [1e-3, 10.0], [0.0, 2.0]])
ASSUMED = np.array([[False, True]] * 4)


def _causes(method):
    """A record that reverses by 3, so the input is not the cause: c_l's upper end sits at
    its assumed limit, the others well inside."""
    u = np.array([-1.5, 1.5, -1.5, 1.5])
    bounds = np.array([[0.2, 0.3], [0.01, 2.0], [0.2, 0.3], [0.01, 0.1]])
    return dict(unidentified(u, NAMES, bounds, PRIOR, ASSUMED, method=method))


@pytest.mark.parametrize("method", ["exact", "lp"])
def test_only_the_end_at_its_assumed_limit_is_named(method):
    assert list(_causes(method)) == ["c_l"]


def test_the_exact_method_is_suggested_only_after_the_lp_method():
    lp, exact = _causes("lp")["c_l"], _causes("exact")["c_l"]
    assert "method='exact'" in lp
    assert "method='exact'" not in exact  # the exact method ran already
    assert "gamma_box" in exact and "reversals: 3 down, 3 up" in exact
