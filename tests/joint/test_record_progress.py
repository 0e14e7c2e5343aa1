"""Progress of a one-record fit (``progress=True``, ``identify --record --progress``): what
is shown is what happened (partition generations, leaves counted to their number, every
interval end of the exact method), on stderr only."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from oracles import one_record

import hammerbound as hb
from hammerbound.app.cli import main


def _fit(u, y, method, progress, **kw):
    lin = hb.LinearEIVSetEstimator(output_bound=0.02, na=2, nb=2, nk=1, method=method,
                                   progress=progress, **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return hb.HammersteinBacklashIdentifier(linear=lin, procedure="one-record").fit(u, y)


def test_lp_fit_shows_partition_and_leaves_on_stderr_only(capsys):
    u, y, _ = one_record(40, 0.02, "uniform", 2)
    _fit(u, y, "lp", True)
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.splitlines()
    assert lines and all(ln.startswith("one-record: ") for ln in lines)
    gens = [ln for ln in lines if "partition generation" in ln]
    assert gens and gens[0].startswith("one-record: partition generation 1: 1 part(s)")
    leaves = [ln for ln in lines if re.match(r"one-record: leaf \d+/\d+", ln)]
    n = int(re.match(r"one-record: leaf \d+/(\d+)", leaves[0]).group(1))
    # a line at most every few seconds, the last leaf always, then what they came to
    assert 1 <= len(leaves) <= n and leaves[-1].startswith(f"one-record: leaf {n}/{n}")
    said = [ln for ln in lines if ln.startswith("one-record: leaves: ")]
    counts = re.match(r"one-record: leaves: (\d+) tightened, (\d+) certified empty, (\d+) "
                      r"cut short by the time limit", said[0]).groups()
    assert len(said) == 1 and sum(map(int, counts)) == n
    _fit(u, y, "lp", False)
    assert capsys.readouterr() == ("", "")  # default: silent


@pytest.mark.deep  # 19 s (quick tier budget)
def test_exact_fit_counts_every_interval_end(capsys):
    u, y, _ = one_record(40, 0.02, "uniform", 2)
    idf = _fit(u, y, "exact", True, total_time_limit=30)
    out, err = capsys.readouterr()
    assert out == ""
    ends = [ln for ln in err.splitlines() if ln.startswith("one-record: interval end ")]
    searched = int(re.match(r"one-record: interval end \d+/(\d+)", ends[0]).group(1))
    assert len(ends) == searched <= 16  # 8 parameters x 2 ends, minus those not searched
    statuses = [re.search(r": (\w+) (min|max), status (\w+)", ln).group(3) for ln in ends]
    assert set(statuses) <= {"optimal", "limit"}
    assert np.all(np.isfinite(idf.theta_bounds_))


def test_cli_progress_goes_to_stderr_and_json_stays_clean(capsys, tmp_path):
    import json

    u, y, _ = one_record(40, 0.02, "uniform", 2)
    path = tmp_path / "r.csv"
    path.write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n"
                                      for a, b in zip(u, y, strict=True)))
    rc = main(["identify", "--record", str(path), "--output-bound", "0.02", "--na", "2",
               "--nb", "2", "--nk", "1", "--method", "lp", "--progress", "--json"])
    out, err = capsys.readouterr()
    assert rc == 0 and json.loads(out)["procedure"] == "one-record"
    assert "one-record: partition generation 1" in err and "one-record: leaves: " in err


def test_lines_after_the_deadline_do_not_claim_work():
    """New-user trial 11: after the deadline every remaining leaf was reported
    "tightened" and every end "status limit, 0 nodes", in the same instant."""
    import time
    from types import SimpleNamespace

    from hammerbound.joint.bounds import _end_outcome
    from hammerbound.joint.tighten import _leaf_outcome

    gone, ahead = time.time() - 1.0, time.time() + 600.0
    box = np.zeros((9, 2))
    # the last item: the deadline had passed when the leaf returned (in its worker)
    assert _leaf_outcome((box, [], 0, False, 1.0)) == "tightened"
    assert _leaf_outcome((None, [], 0, True, 1.0)) == "certified empty"
    assert _leaf_outcome((box, [], 0, True, 1.0)).startswith("time limit reached")
    idle = SimpleNamespace(status="limit", nodes=0)
    assert _end_outcome("a1 min", idle, gone) == (
        "a1 min: not searched, time limit reached (the tightened box's bound)")
    assert _end_outcome("a1 min", idle, ahead) == "a1 min, status limit, 0 nodes"
    assert _end_outcome("a1 min", SimpleNamespace(status="limit", nodes=5), gone) == (
        "a1 min, status limit, 5 nodes")


def test_item_lines_come_every_few_seconds_and_the_last_always(monkeypatch):
    """New-user trial 20: a generation of the partition ran 91 s without a line, and 71
    leaves cut by the deadline took 71 lines in the same instant."""
    import io

    from hammerbound.joint import progress as P

    now = [0.0]
    monkeypatch.setattr(P.time, "perf_counter", lambda: now[0])
    out = io.StringIO()
    bar = P.RecordProgress(True, file=out)  # not a terminal: plain lines
    bar.start("leaf", 4, every=5.0)
    for t in (1.0, 2.0, 7.0, 8.0):  # only the one due (5 s after the start) and the last
        now[0] = t
        bar.done("tightened")
    assert out.getvalue().splitlines() == ["one-record: leaf 3/4: tightened [7.0 s]",
                                           "one-record: leaf 4/4: tightened [8.0 s]"]
    out.truncate(0), out.seek(0)
    bar.start("partition generation 2, part", 3, every=5.0, last=False)
    for t in (9.0, 14.0, 30.0):  # the last has its summary line instead
        now[0] = t
        bar.done()
    assert out.getvalue() == "one-record: partition generation 2, part 2/3 [14.0 s]\n"
