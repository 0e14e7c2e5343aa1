"""Windows of a long record (hammerbound.joint.windows): every window is a relaxation.

Truths are simulated by the oracles (``one_record``: own play operator, scipy's lfilter);
noise is exactly at +-bound (random signs) or uniform. A window's OBBT box must hold the truth's
parameters and, for a window that starts later, the truth's inner value where it starts.
"""

from __future__ import annotations

import numpy as np
import pytest
from oracles import GAMMA_TRUE, THETA_TRUE, one_record

from hammerbound.exceptions import EmptyFeasibleSetError
from hammerbound.joint import RecordProblem, default_gamma_box, record_box
from hammerbound.joint.tighten import _window_obbt, obbt
from hammerbound.joint.windows import window_problem, windows

GAMMA = np.asarray(GAMMA_TRUE)


def _problem(u, y, deta, gamma_box=None):
    g = default_gamma_box(u, y, deta) if gamma_box is None else gamma_box
    return RecordProblem(u, y, deta, 2, 2, 1, record_box(2, 2, u, g))


def test_windows_cover_every_equation_and_short_records_are_not_split():
    u, y, _ = one_record(1000, 0.05, "uniform", 0)
    pr = _problem(u, y, 0.05)
    assert windows(_problem(u[:200], y[:200], 0.05)) == []
    for length in (100, 300, 333):
        ws = windows(pr, length)
        assert len(ws) >= 2 and ws[0][0] == 0 and ws[-1][1] == pr.N
        covered = np.zeros(pr.N, dtype=bool)
        for s, e in ws:
            assert e - s >= pr.n0 + 1
            covered[s + pr.n0: e] = True  # the equations of the window
        assert covered[pr.n0:].all()


@pytest.mark.parametrize("noise", ["bound", "uniform"])
def test_every_window_holds_the_truth(noise):
    u, y, x = one_record(240, 0.05, noise, 1)
    # a narrow backlash box: the band at u_0 then misses the later windows' inner values
    pr = _problem(u, y, 0.05, np.column_stack([0.8 * GAMMA, 1.2 * GAMMA]))
    truth = np.concatenate([THETA_TRUE, GAMMA])
    for s, e in windows(pr, 80):
        wp = window_problem(pr, pr.box, s, e)
        assert wp.box[-1, 0] <= x[s] <= wp.box[-1, 1]  # the band at u_s holds x_s
        box = obbt(wp, wp.box, max_rounds=2)
        assert np.all(box[:-1, 0] <= truth) and np.all(truth <= box[:-1, 1]), (s, e)
        assert box[-1, 0] <= x[s] <= box[-1, 1]
        # a window's box is never wider than the record's a priori box
        assert np.all(box[:-1, 0] >= pr.box[:-1, 0]) and np.all(box[:-1, 1] <= pr.box[:-1, 1])


def test_window_obbt_of_a_long_record_holds_the_truth_and_tightens():
    u, y, x = one_record(480, 0.05, "bound", 2)
    pr = _problem(u, y, 0.05)
    assert len(windows(pr)) >= 2
    box = _window_obbt(pr, pr.box, None, None, 2, 0.01)
    truth = np.concatenate([THETA_TRUE, GAMMA, [x[0]]])
    assert np.all(box[:, 0] <= truth) and np.all(truth <= box[:, 1])
    w0, w1 = pr.box[:, 1] - pr.box[:, 0], box[:, 1] - box[:, 0]
    assert np.all(w1[:2] < 0.1 * w0[:2])  # the poles are bounded by the windows


def test_a_window_that_no_parameters_explain_certifies_the_box_empty():
    u, y, _ = one_record(480, 0.05, "uniform", 3)
    y = y.copy()
    y[300:] += np.linspace(0.0, 40.0, 180) ** 2  # the second window explodes
    pr = _problem(u, y, 0.05)
    box = pr.box.copy()
    box[2:4] = [[-50.0, 50.0], [-50.0, 50.0]]  # b bounded: no linear block follows it
    pr = RecordProblem(u, y, 0.05, 2, 2, 1, box)
    assert _window_obbt(pr, pr.box, None, None, 1, 0.01) is None
    with pytest.raises(EmptyFeasibleSetError):
        obbt(pr, pr.box, max_rounds=1)
