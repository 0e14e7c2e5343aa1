"""McCormick LPs of output-error records (no input errors).

* A product ``b_j dx`` whose error bound is zero is exactly zero: the relaxation drops its
  column and rows. Its bounds are checked against the tests' own McCormick LP (scipy).
* A working set that must grow to most equations doubles after ``GROW_AFTER`` re-solves;
  on a long record one OBBT LP took 220 rounds of about ten equations (120 s).
* Unscaled node LPs crashed the process in HiGHS 1.15-1.16 (segmentation fault) on the
  later OBBT rounds of a long output-error record; the deep test runs that case in a child
  process.
* HiGHS still crashes on some long output-error records (scaled or not): their searches run
  in a worker process, and a step whose worker dies keeps the bound certified before it.
"""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import linprog
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.relaxations.exact import obbt
from hammerbound.relaxations.exact.mccormick import McCormickRelaxation
from hammerbound.relaxations.exact.working_set import (
    GROW_AFTER,
    WorkingSetRelaxation,
    initial_equations,
)
from hammerbound.relaxations.lp import lp_bounds

THETA = np.array([-0.5, 0.06, 1.0, 0.5])  # A = 1 - 0.5 q^-1 + 0.06 q^-2, B = q^-2 (1 + 0.5 q^-1)
D = 0.1


def _record(n, seed):
    rng = np.random.default_rng(seed)
    x = np.where(rng.random(n) < 0.5, 1.0, -1.0) + 0.3 * rng.uniform(-1, 1, n)
    y = lfilter([0, 0, 1.0, 0.5], [1.0, -0.5, 0.06], x) + rng.uniform(-D, D, n)
    return hb.EIVProblem(y, x, input_bound=0.0, output_bound=D, na=2, nb=2, nk=2)


def _own_mccormick_bounds(pr, box):
    """min and max of every theta_k over the tests' own McCormick LP of the output-error
    equations ``(y_t - e_t) + a1 (y_t-1 - e_t-1) + a2 (y_t-2 - e_t-2) = b1 x_t-2 + b2 x_t-3``,
    with ``w_it = a_i e_t-i`` relaxed over ``box`` x ``[-D, D]``. Variables
    ``[a1, a2, b1, b2, e (N), w (2 m)]``."""
    y, x, n = pr.y, pr.x, pr.N
    t = np.arange(3, n)
    m = t.size
    nv = 4 + n + 2 * m
    rows, cols, vals = [], [], []
    r = np.arange(m)
    for k, col in enumerate([y[t - 1], y[t - 2], -x[t - 2], -x[t - 3]]):
        rows += [r]
        cols += [np.full(m, k)]
        vals += [col]
    rows += [r]
    cols += [4 + t]
    vals += [-np.ones(m)]
    for i in (1, 2):
        rows += [r]
        cols += [4 + n + (i - 1) * m + r]
        vals += [-np.ones(m)]
    A_eq = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(m, nv))
    b_eq = -y[t]
    ub_rows, b_ub = [], []
    for i in (1, 2):
        lo, hi = box[i - 1]
        for q in range(m):
            w, a, e = 4 + n + (i - 1) * m + q, i - 1, 4 + t[q] - i
            # w >= lo e - D a + lo D ; w >= hi e + D a - hi D ; w <= hi e - D a + hi D ;
            # w <= lo e + D a - lo D   (as A_ub z <= b_ub)
            for cw, ce, ca, rhs in ((-1, lo, -D, -lo * D), (-1, hi, D, hi * D),
                                    (1, -hi, D, hi * D), (1, -lo, -D, -lo * D)):
                row = np.zeros(nv)
                row[w], row[e], row[a] = cw, ce, ca
                ub_rows.append(row)
                b_ub.append(rhs)
    bounds = [tuple(b) for b in box] + [(-D, D)] * n + [(None, None)] * (2 * m)
    out = np.zeros((4, 2))
    for k in range(4):
        for s, col in ((1.0, 0), (-1.0, 1)):
            c = np.zeros(nv)
            c[k] = s
            res = linprog(c, A_ub=np.array(ub_rows), b_ub=np.array(b_ub), A_eq=A_eq,
                          b_eq=b_eq, bounds=bounds, method="highs")
            assert res.status == 0
            out[k, col] = s * res.fun
    return out


def _package_bounds(relax, p=4):
    out = np.zeros((p, 2))
    for k in range(p):
        for s, col in ((1.0, 0), (-1.0, 1)):
            c = np.zeros(relax.ncol)
            c[k] = s
            relax.lp.set_cost(c)
            res = obbt._solve(relax)
            assert res.status == "optimal"
            out[k, col] = s * res.bound
    return out


def test_zero_products_dropped_and_bounds_match_own_lp():
    pr = _record(40, 1)
    box = np.column_stack([THETA - [0.1, 0.08, 0.2, 0.2], THETA + [0.1, 0.08, 0.2, 0.2]])
    relax = McCormickRelaxation(pr, box)
    m = pr.equation_times.size
    assert np.all(relax.px < pr.na)  # only the a_i eta products
    assert relax.ncol == pr.p + pr.N + pr.n_groups + pr.na * m
    got = _package_bounds(relax)
    ref = _own_mccormick_bounds(pr, box)
    # certified bounds: never inside the tests' LP bounds beyond the rounding, and equal
    # up to the relaxation's outward tolerance
    assert np.all(got[:, 0] <= ref[:, 0] + 1e-9) and np.all(got[:, 1] >= ref[:, 1] - 1e-9)
    np.testing.assert_allclose(got, ref, atol=1e-6)


def test_working_set_doubles_when_most_equations_are_needed():
    pr = _record(900, 0)
    box = lp_bounds(pr).bounds
    relax = WorkingSetRelaxation(pr, box, initial_equations(pr, box))
    solves = []
    orig = relax.lp.solve

    def counted(*a, **k):
        solves.append(1)
        return orig(*a, **k)

    relax.lp.solve = counted
    c = np.zeros(relax.ncol)
    c[0] = 1.0
    relax.lp.set_cost(c)
    res = obbt._solve(relax)
    assert res.status == "optimal"
    m = pr.equation_times.size
    assert relax.equations.size > m / 2  # this LP needs most equations
    assert len(solves) <= GROW_AFTER + int(np.ceil(np.log2(m))) + 1
    assert res.bound <= THETA[0]  # certified over all equations: the truth is above it


# a record of _record(n, seed) in a child process (a crash there does not end the tests)
_RECORD = r"""
import time, warnings, numpy as np
from scipy.signal import lfilter
import hammerbound as hb
rng = np.random.default_rng({seed})
n = {n}
x = np.where(rng.random(n) < 0.5, 1.0, -1.0) + 0.3 * rng.uniform(-1, 1, n)
y = lfilter([0, 0, 1.0, 0.5], [1.0, -0.5, 0.06], x) + rng.uniform(-0.1, 0.1, n)
pr = hb.EIVProblem(y, x, input_bound=0.0, output_bound=0.1, na=2, nb=2, nk=2)
"""

_CRASH_CASE = _RECORD.format(n=3000, seed=0) + r"""
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.units import Units
from hammerbound.relaxations.exact.obbt import _obbt
lp = lp_bounds(pr, check_box=False)
units = Units.of_lp(pr, lp.bounds)
box, *_ = _obbt(units.problem(pr), units.to_search(lp.bounds), rounds=4, ws=None,
                deadline=time.time() + 600)
print("widths", (box[:, 1] - box[:, 0]).tolist())
"""


@pytest.mark.deep
def test_long_output_error_obbt_does_not_crash():
    proc = subprocess.run([sys.executable, "-c", _CRASH_CASE], capture_output=True, text=True,
                          timeout=900)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "widths" in proc.stdout


# ---- the search in a worker process (hammerbound.relaxations.exact.isolation) ------------


def _die():
    import os
    import signal

    os.kill(os.getpid(), signal.SIGSEGV)


def test_run_isolated_reports_a_dead_worker():
    from hammerbound.relaxations.exact.isolation import SolverCrashError, run_isolated

    assert run_isolated(np.add, 2, 3) == 5
    with pytest.raises(SolverCrashError, match="SIGSEGV"):
        run_isolated(_die)
    assert run_isolated(np.add, 1, 1) == 2  # a new worker after the crash


_DIE_QUIETLY = r"""
import os, signal
from hammerbound.relaxations.exact.isolation import SolverCrashError, run_isolated
def die():
    os.kill(os.getpid(), signal.SIGSEGV)
try:
    run_isolated(die)
except SolverCrashError as err:
    print("crash reported:", err)
"""


def test_a_crashed_worker_writes_no_fault_dump():
    """The worker's death is reported by the warning, not by Python's fault handler dump
    (a traceback and 166 module names on the user's stderr, new-user trial 9)."""
    proc = subprocess.run([sys.executable, "-c", _DIE_QUIETLY], capture_output=True,
                          text=True, timeout=120)
    assert "crash reported: the worker process of the exact search died" in proc.stdout
    assert "Fatal Python error" not in proc.stderr, proc.stderr[-1500:]


def test_crash_prone_only_long_output_error_records():
    from hammerbound.relaxations.exact.isolation import crash_prone

    assert crash_prone(_record(400, 0))
    assert not crash_prone(_record(200, 0))
    rng = np.random.default_rng(0)
    x = rng.uniform(-1, 1, 400)
    eiv = hb.EIVProblem(lfilter([0, 0, 1.0, 0.5], [1.0, -0.5, 0.06], x), x, input_bound=0.01,
                        output_bound=D, na=2, nb=2, nk=2)
    assert not crash_prone(eiv)


def test_a_crashed_end_keeps_the_obbt_bound(monkeypatch):
    """A search step whose worker dies: that end reports its OBBT box end with status
    "limit" and a SearchLimitWarning; the other ends are searched as usual."""
    from hammerbound.exceptions import SearchLimitWarning
    from hammerbound.relaxations import exact_bounds
    from hammerbound.relaxations.exact import bnb
    from hammerbound.relaxations.exact.isolation import SolverCrashError

    calls = []

    def fake_isolated(fn, *a, **kw):  # in this process; the search of end 3 "dies"
        calls.append(fn.__name__)
        if fn.__name__ == "search_end" and calls.count("search_end") == 3:
            raise SolverCrashError("the worker process of the exact search died (test)")
        return fn(*a, **kw)

    monkeypatch.setattr(bnb, "crash_prone", lambda problem: True)
    monkeypatch.setattr(bnb, "run_isolated", fake_isolated)
    pr = _record(60, 2)
    with pytest.warns(SearchLimitWarning, match="died"):
        res = exact_bounds(pr)
    assert calls[:2] == ["_obbt", "verified_points"] and calls.count("search_end") == 8
    statuses = [i.status for i in res.infos]
    assert statuses[2] == "limit" and "died" in res.infos[2].message
    assert statuses.count("optimal") == 7
    assert res.bounds[1, 0] == pytest.approx(res.root_box[1, 0], rel=1e-12, abs=1e-12)
    assert np.all(res.bounds[:, 0] <= THETA) and np.all(THETA <= res.bounds[:, 1])



def test_the_polish_runs_isolated_and_a_crash_there_keeps_the_witnesses(monkeypatch):
    """On a crash-prone record the witnesses' polish (HiGHS LPs on the full record) runs in
    the worker too; if it dies, the bounds are those of the search, every witness is the
    verified point the search found (it still explains the data: the tests' own residuals),
    and the warning says so."""
    from hammerbound.exceptions import SearchLimitWarning
    from hammerbound.relaxations import exact_bounds
    from hammerbound.relaxations.exact import bnb
    from hammerbound.relaxations.exact.isolation import SolverCrashError

    calls = []

    def fake_isolated(fn, *a, **kw):
        calls.append(fn.__name__)
        if fn.__name__ == "polish":
            raise SolverCrashError("the worker process of the exact search died (test)")
        return fn(*a, **kw)

    pr = _record(60, 2)
    monkeypatch.setattr(bnb, "crash_prone", lambda problem: True)
    monkeypatch.setattr(bnb, "run_isolated", fake_isolated)
    with pytest.warns(SearchLimitWarning, match="could not be polished"):
        res = exact_bounds(pr)
    assert calls[-1] == "polish"
    assert [i.status for i in res.infos] == ["optimal"] * 8
    assert np.all(res.bounds[:, 0] <= THETA) and np.all(THETA <= res.bounds[:, 1])
    y, x = pr.y, pr.x
    t = np.arange(3, pr.N)
    for info in res.infos:
        th, eta = info.point.theta, info.point.eta
        assert np.max(np.abs(eta)) <= D
        ybar = y - eta
        r = ybar[t] + th[0] * ybar[t - 1] + th[1] * ybar[t - 2] - th[2] * x[t - 2] - th[3] * x[t - 3]
        assert np.max(np.abs(r)) <= 1e-7

_ISOLATED_CASE = _RECORD.format(n=1000, seed=1) + r"""
from hammerbound.relaxations import exact_bounds
with warnings.catch_warnings(record=True) as w:
    warnings.simplefilter("always")
    r = exact_bounds(pr, total_time_limit=240, time_limit=60)
truth = np.array([-0.5, 0.06, 1.0, 0.5])
print("inside", bool(np.all(r.bounds[:, 0] <= truth) and np.all(truth <= r.bounds[:, 1])))
print("statuses", [i.status for i in r.infos], [str(m.message)[:80] for m in w])
"""


@pytest.mark.deep
def test_long_output_error_record_survives_a_solver_crash():
    """The record on which HiGHS crashed the process (N = 1000, seed 1 of the benchmark's
    records): the fit returns, and the truth is inside every interval."""
    proc = subprocess.run([sys.executable, "-c", _ISOLATED_CASE], capture_output=True,
                          text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "inside True" in proc.stdout, proc.stdout


def test_a_dead_joblib_worker_runs_the_search_again_one_step_at_a_time(monkeypatch):
    """With n_jobs > 1 the ends run on joblib workers; if one dies (new-user trial 9: HiGHS
    crashed a worker on a long output-error record, and every end fell back to the LP
    bound, about 100x wider), the search runs again one step at a time in an isolated
    worker: every end searched to the end, a RuntimeWarning, never an exception."""
    from joblib.externals.loky.process_executor import TerminatedWorkerError

    from hammerbound.relaxations import exact_bounds
    from hammerbound.relaxations.exact import bnb

    real = bnb._search_all
    isolated = []

    def dies_in_parallel(*a, isolate, **kw):
        if a[4] != 1:  # n_jobs
            raise TerminatedWorkerError("A worker process managed by the executor was "
                                        "unexpectedly terminated. The exit codes of the "
                                        "workers are {SIGSEGV(-11)}")
        isolated.append(isolate)
        return real(*a, isolate=isolate, **kw)

    pr = _record(60, 2)
    monkeypatch.setattr(bnb, "_search_all", dies_in_parallel)
    with pytest.warns(RuntimeWarning, match=r"parallel exact search died \(exit code "
                                            r"SIGSEGV\(-11\)\).*ran again one at a time"):
        res = exact_bounds(pr, n_jobs=2)
    assert isolated == [True]
    assert [i.status for i in res.infos] == ["optimal"] * 8  # not the LP bounds
    assert np.all(res.bounds[:, 0] <= THETA) and np.all(THETA <= res.bounds[:, 1])


def test_a_worker_dying_in_the_ends_keeps_the_bound_tightening(monkeypatch):
    """A joblib worker that dies while the ends are searched: the ends run again one at a
    time, isolated, from the OBBT box already found (OBBT is not run again)."""
    import threading

    from joblib import parallel_config
    from joblib.externals.loky.process_executor import TerminatedWorkerError

    from hammerbound.relaxations import exact_bounds
    from hammerbound.relaxations.exact import bnb

    real_search, real_obbt = bnb.search_end, bnb._obbt
    obbt_runs = []

    def search_end(*a, **kw):  # a "worker" (thread) dies; the retry runs in this thread
        if threading.current_thread() is not threading.main_thread():
            raise TerminatedWorkerError("The exit codes of the workers are {SIGSEGV(-11)}")
        return real_search(*a, **kw)

    def obbt(*a, **kw):
        obbt_runs.append(1)
        return real_obbt(*a, **kw)

    monkeypatch.setattr(bnb, "search_end", search_end)
    monkeypatch.setattr(bnb, "_obbt", obbt)
    monkeypatch.setattr(bnb, "run_isolated", lambda fn, *a, **kw: fn(*a, **kw))
    with parallel_config(backend="threading"), \
            pytest.warns(RuntimeWarning, match="ran again one at a time"):
        res = exact_bounds(_record(60, 2), n_jobs=2)
    assert len(obbt_runs) == 1
    assert [i.status for i in res.infos] == ["optimal"] * 8
    assert np.all(res.bounds[:, 0] <= THETA) and np.all(THETA <= res.bounds[:, 1])


def test_an_interrupt_kills_the_running_step():
    """A KeyboardInterrupt in this process (a notebook's "interrupt kernel") ends the step
    running in the worker: the next call and the exit do not wait for it."""
    import signal
    import time

    from hammerbound.relaxations.exact.isolation import run_isolated

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGALRM, interrupt)
    try:
        run_isolated(np.add, 0, 0)  # the worker is up
        signal.alarm(1)
        with pytest.raises(KeyboardInterrupt):
            run_isolated(time.sleep, 30)
        t = time.perf_counter()
        assert run_isolated(np.add, 1, 2) == 3
        assert time.perf_counter() - t < 20  # not behind the 30 s sleep
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def test_the_estimator_says_which_ends_a_crash_stopped(monkeypatch):
    """The estimator's limit warning names the ends whose worker died: more time does not
    help those."""
    from hammerbound.relaxations.exact import bnb
    from hammerbound.relaxations.exact.isolation import SolverCrashError

    def fake_isolated(fn, *a, **kw):
        if fn.__name__ == "search_end" and a[2] == 0 and a[3] < 0:  # a1 max
            raise SolverCrashError("the worker process of the exact search died (test)")
        return fn(*a, **kw)

    monkeypatch.setattr(bnb, "crash_prone", lambda problem: True)
    monkeypatch.setattr(bnb, "run_isolated", fake_isolated)
    pr = _record(60, 2)
    est = hb.LinearEIVSetEstimator(na=2, nb=2, nk=2, output_bound=D)
    with pytest.warns(hb.exceptions.SearchLimitWarning) as caught:
        est.fit(pr.x, pr.y, input_bound=0.0)
    texts = [str(w.message) for w in caught]
    assert any("a1 upper: the worker process of the search died" in t
               and "more time does not help" in t for t in texts), texts


def test_a_dead_worker_reruns_only_the_ends_not_finished(monkeypatch):
    """The ends that came back before a joblib worker died are kept: only the others run
    again (all 8 ran again before, which could double the fit's time)."""
    import threading
    from collections import Counter

    from joblib import parallel_config
    from joblib.externals.loky.process_executor import TerminatedWorkerError

    from hammerbound.relaxations import exact_bounds
    from hammerbound.relaxations.exact import bnb

    real_search = bnb.search_end
    calls = Counter()

    def search_end(problem, box, k, s, *a, **kw):
        calls[k, s] += 1
        if threading.current_thread() is not threading.main_thread() and (k, s) == (3, -1.0):
            time.sleep(1.0)  # the last end dies after the others came back
            raise TerminatedWorkerError("The exit codes of the workers are {SIGSEGV(-11)}")
        return real_search(problem, box, k, s, *a, **kw)

    monkeypatch.setattr(bnb, "search_end", search_end)
    monkeypatch.setattr(bnb, "run_isolated", lambda fn, *a, **kw: fn(*a, **kw))
    with parallel_config(backend="threading"), \
            pytest.warns(RuntimeWarning, match="ran again one at a time"):
        res = exact_bounds(_record(60, 2), n_jobs=2)
    assert calls.pop((3, -1.0)) == 2
    assert sorted(calls.values()) == [1] * 7
    assert [i.status for i in res.infos] == ["optimal"] * 8
    assert np.all(res.bounds[:, 0] <= THETA) and np.all(THETA <= res.bounds[:, 1])
