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


def test_an_end_just_inside_an_assumed_limit_is_not_identified():
    """An end within ASSUMED_LIMIT_RTOL of a default limit is the limit's, not the
    record's; with a box the user gave (rtol 1e-6) it keeps its value."""
    from hammerbound.joint.prior import ASSUMED_LIMIT_RTOL

    u = np.array([-1.5, 1.5, -1.5, 1.5])
    bounds = np.array([[0.2, 0.3], [0.01, 2.0 - 1e-4], [0.2, 0.3], [0.01, 0.1]])
    near = dict(unidentified(u, NAMES, bounds, PRIOR, ASSUMED, rtol=ASSUMED_LIMIT_RTOL))
    assert list(near) == ["c_l"]
    assert not unidentified(u, NAMES, bounds, PRIOR, ASSUMED)


def test_a_b_end_the_default_box_sets_through_the_gain_is_not_identified():
    """New-user trial 11: b1 >= -9999.975 (b2 <= 1e4 through the gain equality) was
    reported as a finite bound of the relaxation while the warning said b1 was not
    bounded; it is infinite now, like b1's upper end at the box."""
    from types import SimpleNamespace

    import hammerbound as hb
    from hammerbound.exceptions import NotIdentifiedWarning
    from hammerbound.hammerstein.one_record import _unbounded_b

    box = np.array([[-2.0, 2.0], [-1.0, 1.0], [-1e4, 1e4], [-1e4, 1e4]])
    problem = SimpleNamespace(na=2, nb=2, nk=1, p=4, names=("a1", "a2", "b1", "b2"),
                              box=box)
    tb = np.array([[-1.79, -0.69], [-0.04, 0.83], [-9999.975, 1e4], [-9999.976, 1e4]])
    lin = hb.LinearEIVSetEstimator(output_bound=0.05, na=2, nb=2)
    with pytest.warns(NotIdentifiedWarning, match="b1, b2"):
        out, hit = _unbounded_b(problem, tb, lin)
    assert hit == ("b1", "b2")
    assert np.all(np.isinf(out[2:])) and np.array_equal(out[:2], tb[:2])
    inside = tb.copy()
    inside[2:, 0] = -9900.0  # 1 % inside: the relaxation's bound, kept
    with pytest.warns(NotIdentifiedWarning):
        out, _ = _unbounded_b(problem, inside, lin)
    assert np.array_equal(out[2:, 0], [-9900.0, -9900.0])


def test_a_default_limit_reached_is_widened_and_a_given_box_is_kept():
    """The fit is run again with the default limits an end reached WIDEN_FACTOR times
    wider (a default limit can hold up other ends); a box the user gave is theirs."""
    from hammerbound.joint.prior import WIDEN_FACTOR, GammaPrior

    default = GammaPrior(PRIOR, user_given=False)
    wide = default.widened([1])
    assert wide.box[1, 1] == pytest.approx(WIDEN_FACTOR * 2.0)
    np.testing.assert_array_equal(np.delete(wide.box, 1, axis=0), np.delete(PRIOR, 1, axis=0))
    assert not wide.user_given
    given = GammaPrior(PRIOR, user_given=True)
    np.testing.assert_array_equal(given.widened([0, 1]).box, PRIOR)


def test_the_box_shown_is_never_wider_than_the_box_used():
    """Review: a default limit of 102.4967 was shown as m_l in [0, 102.5] -- an assumption
    weaker than the one the intervals rest on."""
    from hammerbound.joint.prior import GammaPrior

    box = np.array([[0.0, 102.4967], [0.0123456, 3.3394], [0.5, 1.99999], [0.0, 0.25]])
    text = GammaPrior(box, user_given=False).describe()
    assert "m_l in [0, 102.4]" in text and "c_l in [0.01235, 3.339]" in text
    assert "m_r in [0.5, 1.999]" in text and "c_r in [0, 0.25]" in text
