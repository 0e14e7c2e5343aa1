"""A thin set: every input and output error exactly at its bound (new-user trial: three of
six ends of this N = 60 record ran into the node limit, 94 s, status "limit"). Restoration
next to node LP points that hold their products to the LP's own tolerance closes them."""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from hammerbound.relaxations import exact_bounds
from hammerbound.relaxations.problem import EIVProblem, check_theta

TRUTH = np.array([-0.7, 0.4, 0.3])  # a1, b0, b1


def _record():
    """Own simulation of (0.4 + 0.3 q^-1) / (1 - 0.7 q^-1), steps of 4 samples, input and
    output errors at +-0.03 with random signs."""
    rng = np.random.default_rng(0)
    x = np.repeat(rng.uniform(-1, 1, 16), 4)[:60]
    w = lfilter([0.4, 0.3], [1.0, -0.7], x)
    eta = 0.03 * rng.choice([-1.0, 1.0], 60)
    d = 0.03 * rng.choice([-1.0, 1.0], 60)
    return x - d, w + eta


def test_every_end_closes_on_a_thin_set():
    u, y = _record()
    pr = EIVProblem(y=y, x=u, input_bound=0.03, output_bound=0.03, na=1, nb=1, nk=0)
    res = exact_bounds(pr, tol=1e-4, max_nodes=500, check_box=False)
    assert all(i.status == "optimal" for i in res.infos)
    assert np.all(res.bounds[:, 0] <= TRUTH) and np.all(TRUTH <= res.bounds[:, 1])
    for info in res.infos:
        assert check_theta(pr, info.witness).feasible
        assert info.gap <= 1e-4 * max(1.0, abs(info.bound))
