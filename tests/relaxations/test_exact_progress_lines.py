"""Progress lines (new-user trial): the exact method's end with the gap each end reports
("finished, 0% of gap closed, gap 0.000697" was shown for an end reported optimal with gap
1e-6); the moment method has lines too (a cvxopt fit ran 3 minutes without one)."""

from __future__ import annotations

import re

import numpy as np
import pytest
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
    # the time on a line is the end's, as in bound_info_ (its first points and walk were
    # left out: 0.0 s on the line, 0.16 s in the report, trial 13)
    secs = [float(t) for t in re.findall(r"exact \w+ (?:min|max): finished.*, ([\d.]+) s$",
                                         err, flags=re.M)]
    assert len(secs) == 4
    for t, info in zip(secs, est.bound_info_, strict=True):
        assert abs(t - info.time) <= max(0.2, 0.2 * info.time), (t, info.time)


def _record():
    rng = np.random.default_rng(1)
    x0 = np.repeat(rng.uniform(-1, 1, 8), 4)
    y = lfilter([0.0, 0.5], [1.0, -0.8], x0) + rng.uniform(-0.05, 0.05, x0.size)
    return x0 - rng.uniform(-0.02, 0.02, x0.size), y


@pytest.mark.parametrize("n_jobs", [1, 2])
def test_moment_lines(capsys, n_jobs):
    u, y = _record()
    hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.05, method="moment",
                             progress=True, n_jobs=n_jobs).fit(u, y, input_bound=0.02)
    cap = capsys.readouterr()
    assert cap.out == ""
    assert re.search(r"moment: order-1 sparse relaxation built in [\d.]+ s \(\d+ moments",
                     cap.err)
    solved = re.findall(r"moment: (a1|b1) (min|max) solved \((\d) of 4\)", cap.err)
    assert sorted((n, s) for n, s, _ in solved) == [("a1", "max"), ("a1", "min"),
                                                    ("b1", "max"), ("b1", "min")]
    assert [c for *_, c in solved] == ["1", "2", "3", "4"]
    hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.05, method="moment").fit(
        u, y, input_bound=0.02)
    assert capsys.readouterr().err == ""
