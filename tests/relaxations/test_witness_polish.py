"""The exact method's witnesses lie inside the set (issue 29, item 9).

A witness accepted by ``check_theta`` holds (22.34) to 1e-9 of the equations' terms, which an
independent check reads as error bounds widened by up to ~1e-6 of Delta eta (small noise,
large outputs). ``local.polish`` moves each witness a little into the set; here an
independent LP (``oracles.error_scale``: written out equation by equation, rows divided by
the magnitudes of their terms, HiGHS tolerances 1e-10) confirms that the witnesses need no
widening beyond rounding: strictly inside where the set has an interior, the point itself
(to ~1e-13) where it is a single point (noise exactly at the bound on every sample of a
two-level record).
"""

from __future__ import annotations

import numpy as np
import pytest
from oracles import chapter_eiv_data, error_scale, two_level_data

from hammerbound.relaxations.exact.bnb import exact_bounds
from hammerbound.relaxations.exact.local import POLISH_RADIUS, polish
from hammerbound.relaxations.exact.points import _Point
from hammerbound.relaxations.problem import EIVProblem, check_theta

#: what the independent LP may read as widening for a point exactly on the set's edge
#: (its own rounding; the witnesses before polishing needed up to ~1e-6)
LP_ROUNDING = 1e-10


CASES = {
    "independent, small noise": lambda: chapter_eiv_data(N=40, deta=0.005, seed=1,
                                                         at_bound=True),
    "independent": lambda: chapter_eiv_data(N=40, deta=0.05, seed=2, at_bound=True),
    "two-level, small noise": lambda: two_level_data(3, N=40, deta=0.005),
    "two-level": lambda: two_level_data(4, N=40, deta=0.05),
}


@pytest.mark.parametrize("name", list(CASES))
def test_exact_witnesses_need_no_widening(name):
    data, theta = CASES[name]()
    pr = EIVProblem(**data)
    res = exact_bounds(pr, tol=1e-3)
    assert np.all(res.bounds[:, 0] <= theta) and np.all(theta <= res.bounds[:, 1])
    for info in res.infos:
        assert info.witness is not None
        assert error_scale(pr, info.witness) <= 1.0 + LP_ROUNDING, (name, info.param)
        assert check_theta(pr, info.witness, witness=(info.point.eta, info.point.dx)).feasible


def test_polish_moves_an_edge_witness_inside():
    """A point accepted only within the acceptance tolerance (the truth of two-level data
    with the noise exactly at the bound -- the set is that point -- nudged off it) comes
    back to the set, within POLISH_RADIUS of where it was."""
    data, theta = two_level_data(5, N=40, deta=0.005)
    pr = EIVProblem(**data)
    rng = np.random.default_rng(0)
    g = pr.gain_row()[0]
    edge = None
    for step in (1e-9, 3e-10, 1e-10, 3e-11):
        for _ in range(5):
            d = rng.normal(size=theta.size)
            d -= (g @ d) / (g @ g) * g  # stay on the gain plane
            th = theta + step * d / np.linalg.norm(d)
            if error_scale(pr, th) > 1 + 1e-8 and check_theta(pr, th).feasible:
                edge = th
                break
        if edge is not None:
            break
    assert edge is not None, "no nudged truth is accepted within the tolerance only"
    chk = check_theta(pr, edge)
    (out,) = polish(pr, [_Point(edge, chk.eta, chk.dx)])
    assert error_scale(pr, out.theta) <= 1.0 + LP_ROUNDING
    assert np.all(np.abs(out.theta - edge) <= POLISH_RADIUS * np.maximum(1.0, np.abs(edge)))
    assert check_theta(pr, out.theta, witness=(out.eta, out.dx)).feasible
