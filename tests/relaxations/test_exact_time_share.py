"""A total time budget is shared by the exact method's interval ends (new-user trial 9:
with ``total_time_limit=240`` the first end used 180 s and the 7 others were not searched),
and the progress lines say how each end ended (the trial saw "finished, 61% of gap closed,
gap 0.000501" for an end stopped by the budget without a verified point)."""

from __future__ import annotations

import re
import time

import numpy as np
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.relaxations import exact_bounds
from hammerbound.relaxations.exact import search
from hammerbound.relaxations.exact.progress import _GapBar

THETA = np.array([-0.5, 0.06, 1.0, 0.5])


def _problem(n=60, seed=2, d=0.1):
    rng = np.random.default_rng(seed)
    x = np.where(rng.random(n) < 0.5, 1.0, -1.0) + 0.3 * rng.uniform(-1, 1, n)
    y = lfilter([0, 0, 1.0, 0.5], [1.0, -0.5, 0.06], x) + rng.uniform(-d, d, n)
    return hb.EIVProblem(y, x, input_bound=0.0, output_bound=d, na=2, nb=2, nk=2)


def _never_closes(monkeypatch):
    """Every end's search runs until it is stopped (a search that would need more time
    than any budget), then reports "limit"."""
    def run(self):
        while time.perf_counter() < self.stop_at:
            time.sleep(0.005)
        self.status = "limit"

    monkeypatch.setattr(search.EndSearch, "run", run)


def test_the_budget_is_shared_by_the_ends(monkeypatch):
    _never_closes(monkeypatch)
    pr = _problem()
    budget = 2.0
    t = time.perf_counter()
    res = exact_bounds(pr, total_time_limit=budget, time_limit=600.0)
    assert time.perf_counter() - t < budget + 3.0
    assert all(i.status == "limit" for i in res.infos)
    # every end was searched, for about its share: none was left "not searched"
    assert not any("not searched" in i.message for i in res.infos), \
        [i.message for i in res.infos]
    assert all("its share of the total time budget" in i.message for i in res.infos)
    assert max(i.time for i in res.infos) < budget / 2
    # still guaranteed
    assert np.all(res.bounds[:, 0] <= THETA) and np.all(THETA <= res.bounds[:, 1])


def test_time_an_end_does_not_use_goes_to_the_ends_after_it(monkeypatch):
    """The first 4 ends (a1, a2) need no search time; the last 4 share what they left."""
    def run(self):
        if self.k < 2:
            return  # closes at once (its bound stays the certified root bound)
        while time.perf_counter() < self.stop_at:
            time.sleep(0.005)
        self.status = "limit"

    monkeypatch.setattr(search.EndSearch, "run", run)
    pr = _problem()
    budget = 3.0
    res = exact_bounds(pr, total_time_limit=budget, time_limit=600.0)
    first, last = res.infos[:4], res.infos[4:]
    spent = sum(i.time for i in first)
    # each of the last 4 got about a quarter of what the first 4 left (not an eighth of
    # the budget, and not all of it for the first of them)
    left = budget - spent - 0.3  # the LP, OBBT and first points before the ends
    assert min(i.time for i in last) > 0.8 * left / 4 - 0.05, [i.time for i in res.infos]
    assert all("its share" in i.message for i in last)
    assert np.all(res.bounds[:, 0] <= THETA) and np.all(THETA <= res.bounds[:, 1])


def test_progress_lines_say_how_an_end_stopped(monkeypatch, capsys):
    _never_closes(monkeypatch)
    est = hb.LinearEIVSetEstimator(na=2, nb=2, nk=2, output_bound=0.1, method="exact",
                                   total_time_limit=2.0, progress=True)
    pr = _problem()
    est.fit(pr.x, pr.y, input_bound=0.0)
    err = capsys.readouterr().err
    last = [ln for ln in err.splitlines() if ln.startswith("exact ")
            and "searching" not in ln]
    assert len(last) == 8, err
    assert all("stopped by its share of the total time budget (total_time_limit)" in ln
               and "finished" not in ln for ln in last), last


def test_without_a_verified_point_the_line_does_not_call_the_box_width_a_gap(capsys):
    bar = _GapBar("a1 min", 0, 1.0, np.inf)
    bar.update(0.4, 1e-4, 12, verified=False)
    bar.close("stopped by the time limit (time_limit)")
    line = capsys.readouterr().err.strip()
    assert re.fullmatch(r"exact a1 min: stopped by the time limit \(time_limit\), 60% of gap "
                        r"closed, no verified point yet \(box width 0\.4 above the bound\), "
                        r"12 nodes, [\d.]+ s", line), line


def test_a_fit_has_a_total_budget_by_default(monkeypatch):
    """Without one, a long record's exact fit could run 8 x 600 s without a word (trial 9):
    the estimator's default budget reaches the search as a deadline, and the command line
    has the same default (``inf`` lifts it)."""
    from hammerbound.app.cli.main import build_parser
    from hammerbound.app.cli.options import stage2_kwargs
    from hammerbound.relaxations.exact import bnb

    seen = []
    real = bnb.exact_bounds

    def spy(*a, deadline=None, **kw):
        seen.append(deadline)
        return real(*a, deadline=deadline, **kw)

    monkeypatch.setattr(bnb, "exact_bounds", spy)
    pr = _problem()
    t = time.time()
    hb.LinearEIVSetEstimator(na=2, nb=2, nk=2, output_bound=0.1, method="exact").fit(
        pr.x, pr.y, input_bound=0.0)
    assert len(seen) == 1 and seen[0] is not None and 590 < seen[0] - t < 610
    parser = build_parser()
    eiv = ["eiv", "data.csv", "--na", "2", "--nb", "2", "--output-bound", "0.1"]
    args = parser.parse_args(eiv)
    assert stage2_kwargs(args)["total_time_limit"] == 600.0
    args = parser.parse_args(eiv + ["--total-time-limit", "inf"])
    assert stage2_kwargs(args)["total_time_limit"] is None


def test_parallel_ends_each_get_their_share(monkeypatch):
    """n_jobs > 1: every end gets its share of the time left for the rounds of ends the
    workers run (review of trial 9: joblib batched two ends on one worker and the second
    waited behind the first, "not searched"; n_jobs=-1 counted as one worker, so the first
    ends got an eighth, not a quarter). Threads stand for the workers here, so that the
    searches that never close reach them."""
    from joblib import effective_n_jobs, parallel_config

    _never_closes(monkeypatch)
    with parallel_config(backend="threading"):
        res = exact_bounds(_problem(), total_time_limit=5.0, n_jobs=-1)
    assert not any("not searched" in i.message for i in res.infos), \
        [(i.param, i.sense, round(i.time, 2), i.message[:40]) for i in res.infos]
    rounds = -(-8 // effective_n_jobs(-1))
    assert min(i.time for i in res.infos) > 0.75 * 4.0 / rounds, [i.time for i in res.infos]
    assert np.all(res.bounds[:, 0] <= THETA) and np.all(THETA <= res.bounds[:, 1])


def test_crash_prone_steps_run_isolated_with_parallel_jobs_too(monkeypatch):
    """With n_jobs=2 on a crash-prone record the first verified points and the polish (HiGHS
    on the full record, in this process before) run in the isolated worker."""
    from hammerbound.relaxations.exact import bnb

    calls = []

    def recording(fn, *a, **kw):
        calls.append(fn.__name__)
        return fn(*a, **kw)

    monkeypatch.setattr(bnb, "crash_prone", lambda problem: True)
    monkeypatch.setattr(bnb, "run_isolated", recording)
    exact_bounds(_problem(), n_jobs=2)
    assert calls == ["verified_points", "polish"]
