"""The exact method's progress lines end with the gap each end reports (new-user trial:
"finished, 0% of gap closed, gap 0.000697" for an end reported optimal with gap 1e-6)."""

from __future__ import annotations

import re

import numpy as np
from scipy.signal import lfilter

import hammerbound as hb


def test_finished_lines_show_the_reported_gap(capsys):
    # own simulation: 0.5 q^-1 / (1 - 0.8 q^-1), steps of 4 samples, uniform errors (the
    # trial's record: the a1 upper end closed with nodes left on the heap)
    rng = np.random.default_rng(1)
    x0 = np.repeat(rng.uniform(-1, 1, 11), 4)[:40]
    w = lfilter([0.0, 0.5], [1.0, -0.8], x0)
    y = w + rng.uniform(-0.05, 0.05, 40)
    u = x0 - rng.uniform(-0.02, 0.02, 40)
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.05, method="exact",
                                   progress=True).fit(u, y, input_bound=0.02)
    err = capsys.readouterr().err
    lines = re.findall(r"exact (\w+) (min|max): finished, (\d+)% of gap closed, gap (\S+),",
                       err)
    assert len(lines) == 4
    for (name, sense, pct, gap), info in zip(lines, est.bound_info_, strict=True):
        assert (name, sense) == (info.param, info.sense)
        assert info.status == "optimal" and pct == "100"
        tol = 1e-4 * max(1.0, abs(info.bound))
        assert float(gap) <= tol
