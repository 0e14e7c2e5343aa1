"""First-hour findings of new-user trial 11 (one ordinary record from the command line and
from Python): time limits that are not seconds, an option that one record ignored, JSON
without the warnings, advice naming limits the LP method does not have, and a
reverse-acting record fitted under a time limit without a word."""

from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pytest
from oracles import one_record
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.app.cli import main
from hammerbound.exceptions import DataWarning, ParameterValidationError, SearchLimitWarning


def _csv(tmp_path, y_sign=1.0):
    u, y, _ = one_record(40, 0.02, "uniform", 2)
    path = tmp_path / "r.csv"
    path.write_text("u,y\n" + "".join(f"{float(a)!r},{float(y_sign * b)!r}\n"
                                      for a, b in zip(u, y, strict=True)))
    return path


def _identify(path, *extra):
    try:
        return main(["identify", "--record", str(path), "--output-bound", "0.02", "--na",
                     "2", "--nb", "2", "--method", "lp", *extra])
    except SystemExit as stop:  # argparse's own errors
        return stop.code


@pytest.mark.parametrize("value", ["-5", "nan", "soon"])
def test_a_total_time_limit_that_is_not_seconds_is_refused(tmp_path, capsys, value):
    rc = _identify(_csv(tmp_path), "--total-time-limit", value)
    err = capsys.readouterr().err
    assert rc == 2
    assert ("argument --total-time-limit: must be a number of seconds >= 0, or inf (or "
            f"none) for no limit; got '{value}'") in err


def test_none_lifts_the_budget_like_inf():
    from hammerbound.app.cli.options import budget, total_budget

    for word in ("none", "None", "inf"):
        assert total_budget(type("A", (), {"total_time_limit": budget(word)})) is None
    assert budget("12.5") == 12.5


def test_a_negative_budget_is_refused_in_python_too():
    u, y, _ = one_record(40, 0.02, "uniform", 2)
    lin = hb.LinearEIVSetEstimator(output_bound=0.02, na=2, nb=2, method="lp",
                                   total_time_limit=-5)
    with pytest.raises(ParameterValidationError, match="total_time_limit must be None or a "
                                                       "number of seconds >= 0; got -5"):
        hb.HammersteinBacklashIdentifier(linear=lin).fit(u, y)


def test_inner_signal_is_refused_with_one_record(tmp_path, capsys):
    rc = _identify(_csv(tmp_path), "--inner-signal", "two-level")
    err = capsys.readouterr().err
    assert rc == 2 and "--inner-signal belongs to the PRBS experiment (--prbs)" in err


def test_json_carries_the_warnings(tmp_path, capsys):
    """Those of the fit and those of reading the data (an index column that is not a time
    column warns; it was on stderr only, review)."""
    path = _csv(tmp_path)
    rows = path.read_text().splitlines()
    path.write_text("\n".join(["n," + rows[0]]
                              + [f"{i},{r}" for i, r in enumerate(rows[1:])]) + "\n")
    rc = _identify(path, "--total-time-limit", "0.5", "--json")
    out, err = capsys.readouterr()
    assert rc == 0
    got = json.loads(out)["warnings"]
    assert got and all(set(w) == {"category", "message"} for w in got)
    # the same warnings as on stderr, in command-line terms, and no other
    for w in got:
        assert f"warning: {w['category']}: {w['message']}" in err
    assert len(got) == err.count(": warning: ")
    assert any(w["category"] == "NotIdentifiedWarning" for w in got)
    assert any(w["category"] == "DataWarning" and "no time column" in w["message"]
               for w in got)
    assert not any("total_time_limit" in w["message"] for w in got)


def _fit_warnings(n, budget, sign=1.0):
    """The warnings of an lp one-record fit of a record of ``n`` samples (output times
    ``sign``) with ``total_time_limit=budget``."""
    u, y, _ = one_record(n, 0.02, "uniform", 2)
    lin = hb.LinearEIVSetEstimator(output_bound=0.02, na=2, nb=2, method="lp",
                                   total_time_limit=budget)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hb.HammersteinBacklashIdentifier(linear=lin).fit(u, sign * y)
    return caught


def test_the_lp_method_is_not_told_to_raise_per_end_limits():
    caught = _fit_warnings(40, 0.5)
    limit = [str(w.message) for w in caught if w.category is SearchLimitWarning]
    assert limit and all("raise total_time_limit for tighter" in m for m in limit)
    assert not any("max_nodes" in m for m in limit)


def test_a_reverse_acting_record_stopped_by_time_is_told_so():
    """fit(u, -y) under a short budget returns (nothing certified it empty): a DataWarning
    names the negative least-squares gain; the record as recorded gets none."""
    for sign, expect in ((-1.0, True), (1.0, False)):
        # no time at all: nothing is certified (0.5 s certify this -y empty, with the hint)
        caught = _fit_warnings(60, 0.0, sign)
        said = [str(w.message) for w in caught if w.category is DataWarning
                and "least-squares gain is negative" in str(w.message)]
        assert bool(said) == expect, said
        if expect:
            assert "fit the negated output (-y)" in said[0]


def test_json_intervals_carry_each_end_status_as_a_code(tmp_path, capsys):
    """Besides the table's words ("lower relaxation; upper not identified"), each interval
    record gives both ends' status codes (trial 11: a program had to parse the words)."""
    from hammerbound.status import STATUSES

    rc = _identify(_csv(tmp_path), "--total-time-limit", "0.5", "--json")
    doc = json.loads(capsys.readouterr().out)
    assert rc == 0
    for rec, lo, hi in zip(doc["intervals"], doc["lower"], doc["upper"], strict=True):
        assert rec["lower_status"] in STATUSES and rec["upper_status"] in STATUSES
        assert (lo is None) == (rec["lower_status"] == "not identified")
        assert (hi is None) == (rec["upper_status"] == "not identified")


def test_unbounded_slopes_name_a_free_scale_when_a1_can_reach_zero():
    """Slopes not identified while the a_i intervals *found* let A(1) = 1 + sum a_i reach
    0: the warning names the free scale of the unit-gain normalisation (trial 11); not
    when the a_i keep A(1) > 0, are still at their a priori box, or the time limit stopped
    the search (those intervals say nothing of the plant; review)."""
    from types import SimpleNamespace

    from hammerbound.hammerstein.one_record import _scale_hint

    box = np.vstack([[[-2.0, 2.0], [-1.0, 1.0]], [[-1e4, 1e4]] * 2, [[0, 30], [0, 4]] * 2,
                     [[-1, 1]]])
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1, 1, 30), 10)
    fast = lfilter([0, 0.5, 0.2], [1, -0.3, 0.0], u)  # A(1) = 0.7: no slow-plant hint
    problem = SimpleNamespace(na=2, nb=2, nk=1, box=box, u=u, y=fast)
    found = np.vstack([[[-1.79, -0.69], [-0.04, 0.83]], box[2:]])  # trial 11's a_i
    hint = _scale_hint(problem, found, {"ml", "mr"})
    assert "let A(1) = 1 + a_1 + ... + a_na reach 0 (down to -0.83)" in hint
    assert _scale_hint(problem, found, {"ml"}, stopped_by_time=True) == ""
    assert _scale_hint(problem, found, {"cl", "cr"}) == ""  # slopes bounded
    tight = found.copy()
    tight[:2] = [[-1.35, -1.25], [0.40, 0.50]]  # A(1) >= 0.05
    assert _scale_hint(problem, tight, {"ml", "mr"}) == ""
    assert _scale_hint(problem, box, {"ml", "mr"}) == ""  # the a_i at their box


def test_a_slow_record_is_named_when_the_search_says_nothing_of_the_a_i():
    """Trial 18: second-order plants with A(1) = 0.06 and 0.2 bounded nothing in 300 s,
    and the warning named only the time limit: the record's least-squares A(1) is named
    as a possible reason then (stopped, or the a_i at their box)."""
    from types import SimpleNamespace

    from hammerbound.hammerstein.one_record import _scale_hint

    box = np.vstack([[[-2.0, 2.0], [-1.0, 1.0]], [[-1e4, 1e4]] * 2, [[0, 30], [0, 4]] * 2,
                     [[-1, 1]]])
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1, 1, 30), 10)
    slow = lfilter([0, 0.04, 0.02], [1, -1.5, 0.56], u)  # A(1) = 0.06
    problem = SimpleNamespace(na=2, nb=2, nk=1, box=box, u=u, y=slow)
    hint = _scale_hint(problem, box, {"ml", "mr"}, stopped_by_time=True)
    assert "least-squares fit has A(1) = 1 + a_1 + ... + a_na = 0.06" in hint
    assert _scale_hint(problem, box, {"cl"}, stopped_by_time=True) == ""  # slopes bounded


def test_a_fit_stopped_by_time_does_not_blame_the_plant_scale():
    from hammerbound.exceptions import NotIdentifiedWarning

    caught = _fit_warnings(60, 0.0)
    said = [str(w.message) for w in caught if w.category is NotIdentifiedWarning]
    assert any("ml" in m for m in said) and not any("A(1)" in m for m in said)


def test_progress_is_on_by_default_on_a_terminal_only(monkeypatch):
    """A long fit was silent for minutes without --progress (trial 11): on a terminal the
    progress is on unless --no-progress; into a pipe or file it stays off unless asked."""
    import hammerbound.terminal as terminal
    from hammerbound.app.cli.main import build_parser
    from hammerbound.app.cli.options import progress_wanted

    parser = build_parser()
    base = ["identify", "--record", "r.csv", "--output-bound", "0.05"]
    for tty in (True, False):
        monkeypatch.setattr(terminal, "is_terminal", lambda file=None, tty=tty: tty)
        assert progress_wanted(parser.parse_args(base)) is tty
        assert progress_wanted(parser.parse_args([*base, "--progress"])) is True
        assert progress_wanted(parser.parse_args([*base, "--no-progress"])) is False


def test_the_reverse_acting_warning_needs_a_fit_that_found_nothing():
    """A negative least-squares gain alone does not warn: a fit that ran to the end or
    verified a point found the set non-empty (a noisy record of a plant with a small A(1)
    can have a negative least-squares gain, review)."""
    from types import SimpleNamespace

    from hammerbound.hammerstein.record_checks import warn_gain_sign

    u, y, _ = one_record(60, 0.02, "uniform", 2)
    problem = SimpleNamespace(u=u, y=-y, na=2, nb=2, nk=1)

    def said(stopped, witness):
        res = SimpleNamespace(details=SimpleNamespace(stopped_by_time=stopped),
                              infos=[SimpleNamespace(witness=witness)])
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            warn_gain_sign(problem, res)
        return [w for w in caught if w.category is DataWarning]

    assert len(said(True, None)) == 1
    assert not said(False, None)
    assert not said(True, np.zeros(4))


def test_a_stage_one_empty_set_names_the_steady_output_bound(tmp_path, capsys):
    """New-user trial 13: the message said "--output-bound (too small?)" for the
    steady-state record, whose bound is --steady-output-bound."""
    ex = hb.chapter_example(0.02, N=80)
    ss, pr = tmp_path / "steady.csv", tmp_path / "prbs.csv"
    for path, (u, y) in ((ss, (ex.steady.u, ex.steady.y)), (pr, (ex.prbs.u, ex.prbs.y))):
        path.write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n"
                                          for a, b in zip(u, y, strict=True)))
    rc = main(["identify", "--steady", str(ss), "--prbs", str(pr), "--output-bound", "0.02",
               "--steady-output-bound", "1e-5", "--method", "lp"])
    err = capsys.readouterr().err
    assert rc == 2 and "EmptyFeasibleSetError" in err
    assert "--steady-output-bound (too small?)" in err and "--output-bound (too" not in err


def test_the_prbs_levels_are_shown_with_the_digits_that_tell_them_apart():
    """Trial 13: a level 2 + 1e-9 showed as "[-2. 2. 2.]"."""
    from hammerbound.exceptions import DataValidationError
    from hammerbound.stage1.inner_signal import read_prbs_level

    u = np.r_[np.tile([2.0, -2.0], 20), 2.0 + 1e-9]
    with pytest.raises(DataValidationError, match=r"3 distinct value\(s\) \[-2 2 2\.000000001\]"):
        read_prbs_level(u)


def test_the_two_level_assumption_names_the_levels_not_samples():
    """Trial 13: the two-level fit's assumptions said "(per sample)" of its inner-signal
    bound, which is one unknown value per PRBS level."""
    ex = hb.chapter_example(0.02, N=80)
    said = {}
    for inner, method in (("independent", "exact"), ("two-level", "exact"),
                          ("two-level", "lp")):
        idf = hb.HammersteinBacklashIdentifier(
            hb.BacklashSetEstimator(0.02),
            hb.LinearEIVSetEstimator(output_bound=0.02, method=method),
            inner_signal=inner).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
        said[inner, method] = next(a for a in idf.assumptions_
                                   if a.startswith("inner signal"))
        assert said[inner, method] in idf.summary()  # the summary says the same
        up, down = (float(np.max(idf.dx_ * (sign * ex.prbs.u > 0))) for sign in (1, -1))
    two = said["two-level", "exact"]
    assert "two unknown levels" in two and "per sample" not in two
    shown = re.search(r"\|dx\| <= (\S+) \(u = \+u\*\) and (\S+) \(u = -u\*\)", two)
    for text, used in zip(shown.groups(), (up, down), strict=True):  # which is which
        # never weaker than the bound used (".4g" showed 0.001821 for 0.00182079: the
        # README's example), and no more than the 4th digit below it
        assert used * (1 - 1e-3) <= float(text) <= used
    per_sample = "inner signal within the stage-1 bounds |dx_t|"
    assert said["independent", "exact"].startswith(per_sample)
    # the LP method bounds each equation's errors on their own: its bounds rest on the
    # per-sample bounds only
    assert said["two-level", "lp"].startswith(per_sample)
