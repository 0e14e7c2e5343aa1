"""HiGHS keeps one thread scheduler per process, sized by the first ``run()``; a later run
whose ``threads`` option is non-zero and different fails without solving. Our LPs leave
that option at its default, so a user's (or another library's) earlier highspy solve must
not break a fit. Run in a fresh process: the scheduler cannot be reset inside this one.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = textwrap.dedent('''
    import numpy as np, highspy
    from scipy.signal import lfilter

    # someone else's HiGHS solve first, with its own thread count
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("threads", 2)
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = 1, 0
    lp.col_cost_, lp.col_lower_, lp.col_upper_ = np.array([1.0]), np.array([-1.0]), np.array([1.0])
    h.passModel(lp)
    assert h.run() == highspy.HighsStatus.kOk

    from hammerbound import LinearEIVSetEstimator
    rng = np.random.default_rng(3)
    x = np.where(rng.random(60) < 0.5, -1.0, 1.0)
    theta = np.array([-0.5, 0.8])            # y_t = 0.5 y_(t-1) + 0.8 x_(t-1)
    y = lfilter([0.0, 0.8], [1.0, -0.5], x) + rng.uniform(-0.05, 0.05, x.size)
    for method in ("lp", "exact"):
        est = LinearEIVSetEstimator(1, 1, output_bound=0.05, method=method).fit(x, y)
        assert est.contains(theta), (method, est.bounds_)
        print(method, "ok")
''')


def test_fit_after_another_highs_user_in_the_process():
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    res = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                         env=env, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    # (the other user's first Highs() printed HiGHS's banner: not ours to silence)
    assert [ln for ln in res.stdout.splitlines() if ln.endswith(" ok")] == ["lp ok", "exact ok"]
