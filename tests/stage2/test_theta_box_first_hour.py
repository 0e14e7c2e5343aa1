"""The a priori box of the linear block in a new user's first hour (new-user trial):
an "empty" verdict that only the default box causes says so; some rows of the box can be
given by name (Python ``theta_box={"a1": (-3, 3)}``, CLI ``--theta-box a1=-3:3``)."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.app.cli import main
from hammerbound.exceptions import (
    EmptyFeasibleSetError,
    ParameterValidationError,
    UnboundedSetError,
)

A1, B1 = -1.05, 0.5  # unstable: a1 outside the default box |a1| <= 1


def _unstable(N=40, seed=10, deta=0.05, dx=0.02):
    """Own simulation of y = 0.5 q^-1 / (1 - 1.05 q^-1) x with input and output errors
    exactly at their bounds (random signs)."""
    rng = np.random.default_rng(seed)
    x0 = rng.uniform(-1, 1, N)
    w = lfilter([0.0, B1], [1.0, A1], x0)
    u = x0 + dx * rng.choice([-1.0, 1.0], N)
    y = w + deta * rng.choice([-1.0, 1.0], N)
    return u, y


def test_empty_only_by_the_default_box_says_so():
    u, y = _unstable()
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.05, method="lp")
    with pytest.raises(EmptyFeasibleSetError) as exc:
        est.fit(u, y, input_bound=0.02)
    msg = str(exc.value)
    assert "the a priori box may be what excludes the system" in msg
    # the row the wider LP set leaves the box by, where it lies, and an example box
    m = re.search(r"There the LP set has a1 in \[([-\d.e]+), ([-\d.e]+)\], beyond the a "
                  r"priori box \(a1 in \[-1, 1\]\)", msg)
    assert m and float(m[1]) <= A1 <= float(m[2])
    assert "theta_box={'a1': (-10, 10)}" in msg and "'b1'" not in msg


def _milli_kilo():
    """Own simulation, x in thousandths and y in thousands: b_j of about 1e6."""
    rng = np.random.default_rng(3)
    x = rng.choice([-1.0, 1.0], 120)
    w = lfilter([0.0, 2.0, -1.0], [1.0, -0.7, 0.3], x)
    return 1e-3 * x, 1e3 * (w + rng.uniform(-0.05, 0.05, x.size))


TRUTH_MILLI_KILO = np.array([-0.7, 0.3, 2e6, -1e6])


def test_empty_by_a_b_box_too_small_for_the_units_names_the_b_rows():
    """The b_j of about 1e6 lie beyond the default |b_j| <= 1e4: the hint names b1, b2."""
    x, y = _milli_kilo()
    est = hb.LinearEIVSetEstimator(na=2, nb=2, output_bound=50.0, method="lp")
    with pytest.raises(EmptyFeasibleSetError) as exc:
        est.fit(x, y)
    msg = str(exc.value)
    assert "There the LP set has b1 in [" in msg and "b2 in [" in msg
    assert "(keeping any rows you gave for the others), e.g. theta_box={'b1': (-1e+07, " \
        "1e+07), 'b2': (-1e+07, 1e+07)}" in msg
    assert "'a1'" not in msg  # a is not what the box excludes
    fit = hb.LinearEIVSetEstimator(na=2, nb=2, output_bound=50.0, method="lp", theta_box={
        "b1": (-1e7, 1e7), "b2": (-1e7, 1e7)}).fit(x, y)  # the example box works
    assert fit.contains(TRUTH_MILLI_KILO)


def test_cli_names_every_row_of_the_example_box(tmp_path, capsys):
    x, y = _milli_kilo()
    path = tmp_path / "milli_kilo.csv"
    path.write_text("u,y\n" + "".join(f"{a:.17g},{b:.17g}\n" for a, b in zip(x, y, strict=True)))
    args = ["eiv", str(path), "--na", "2", "--nb", "2", "--output-bound", "50", "--method",
            "lp"]
    assert main(args) == 2
    err = capsys.readouterr().err
    flags = "--theta-box b1=-1e+07:1e+07 --theta-box b2=-1e+07:1e+07"
    assert f"e.g. {flags}." in err
    assert main([*args, *flags.split(), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["model"]["theta_box"]["b1"] == [-1e7, 1e7]


def test_empty_by_the_data_says_the_box_is_not_the_cause():
    u, y = _unstable()
    # the errors are at +-0.05: a bound of 0.01 leaves nothing, whatever the box
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.01, method="lp",
                                   theta_box={"a1": (-3, 3)})
    with pytest.raises(EmptyFeasibleSetError, match="the box is not what empties it"):
        est.fit(u, y, input_bound=0.02)


@pytest.mark.parametrize("method", ["lp", "exact"])
def test_named_rows_replace_the_default_box(method):
    u, y = _unstable()
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.05, method=method,
                                   theta_box={"a1": (-3, 3)}).fit(u, y, input_bound=0.02)
    assert est.contains(np.array([A1, B1]))
    assert np.allclose(est.problem_.theta_box, [[-3, 3], [-1e4, 1e4]])
    text = est.summary()
    assert "a priori box a1 in [-3, 3] (theta_box); default box for b1 (|b_j| <= 1e4)" \
        in text
    assert "stable A" not in text


def test_default_b_rows_still_refuse_an_unbounded_b():
    """Rows given for a only: a b bound at the (arbitrary) default box is an error; with
    the b row given it is the user's prior (status 'box')."""
    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 1, 30)  # measured within 1 of the input: it may have been 0
    y = lfilter([0.0, 0.5], [1.0, -0.5], x) + 0.3 * rng.uniform(-1, 1, 30)
    with pytest.raises(UnboundedSetError, match="default box"):
        hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.3, method="lp",
                                 theta_box={"a1": (-0.99, 0.99)}).fit(x, y, input_bound=1.0)
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.3, method="lp",
                                   theta_box={"a1": (-0.99, 0.99), "b1": (-5, 5)})
    est.fit(x, y, input_bound=1.0)
    assert est.contains(np.array([-0.5, 0.5]))
    assert "box" in est.result_.status[1]


@pytest.mark.parametrize("box, match", [
    ({"a3": (-3, 3)}, r"unknown parameter\(s\) \['a3'\]; the parameters are a1, b1"),
    ({"a1": 3}, r"got a1: 3 \(give a pair"),
    ({"a1": (3, -3)}, "lower <= upper"),
    ({"b1": (-np.inf, 1)}, "finite"),
])
def test_bad_named_rows(box, match):
    u, y = _unstable()
    with pytest.raises(ParameterValidationError, match=match):
        hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.05, theta_box=box).fit(
            u, y, input_bound=0.02)


def _csv(tmp_path):
    u, y = _unstable()
    path = tmp_path / "unstable.csv"
    path.write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(u, y, strict=True)))
    return path


def test_cli_theta_box(tmp_path, capsys):
    path = _csv(tmp_path)
    args = ["eiv", str(path), "--na", "1", "--nb", "1", "--output-bound", "0.05",
            "--input-bound", "0.02", "--method", "lp"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "Pass a --theta-box" in err and "e.g. --theta-box a1=-10:10." in err
    assert "theta_box" not in err
    assert main([*args, "--theta-box", "a1=-3:3", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    lo, hi = out["lower"], out["upper"]
    assert lo[0] <= A1 <= hi[0] and lo[1] <= B1 <= hi[1]


@pytest.mark.parametrize("extra, match", [
    (["--theta-box", "a1=3"], "expected NAME=LOWER:UPPER"),
    (["--theta-box", "a1=-3:3", "--theta-box", "a1=-2:2"], "names a parameter twice"),
    (["--theta-box", "a7=-3:3"], r"unknown parameter\(s\) \['a7'\]"),
])
def test_cli_bad_theta_box(tmp_path, capsys, extra, match):
    path = _csv(tmp_path)
    try:
        rc = main(["eiv", str(path), "--na", "1", "--nb", "1", "--output-bound", "0.05",
                   "--method", "lp", *extra])
    except SystemExit as stop:  # argparse's own errors
        rc = stop.code
    cap = capsys.readouterr()
    assert rc == 2 and cap.out == ""
    assert re.search(match, cap.err)


def test_no_box_hint_when_the_lp_set_itself_is_not_empty():
    """An empty verdict of a tighter relaxation (exact method) while the LP set is not
    empty: the LP cannot tell whether the box is the cause, so no hint."""
    from hammerbound.relaxations.problem import EIVProblem
    from hammerbound.stage2.fitting import widened_box_hint

    u, y = _unstable()
    pr = EIVProblem(y=y, x=u, input_bound=0.02, output_bound=0.05, na=1, nb=1,
                    theta_box=[[-3, 3], [-10, 10]])
    assert widened_box_hint(pr) == ""


@pytest.mark.parametrize("extra, said", [
    (["--na", "-1", "--nb", "1"], "--na must be an integer >= 0"),
    (["--na", "1", "--nb", "1", "--total-time-limit", "-5"],
     "argument --total-time-limit: must be a number of seconds >= 0, or inf (or none) for "
     "no limit; got '-5'"),
    (["--na", "1", "--nb", "1", "--total-time-limit", "nan"],
     "argument --total-time-limit: must be a number of seconds >= 0"),
    (["--na", "1", "--nb", "1", "--time-limit", "-1"],
     "argument --time-limit: must be a number of seconds >= 0, or inf (or none) for no "
     "limit; got '-1'"),
])
def test_cli_names_its_flags(tmp_path, capsys, extra, said):
    path = _csv(tmp_path)
    try:
        rc = main(["eiv", str(path), "--output-bound", "0.05", *extra])
    except SystemExit as stop:  # argparse's own errors
        rc = stop.code
    err = capsys.readouterr().err
    assert rc == 2 and said in err


def test_a_narrow_user_box_far_from_the_system_is_suspected():
    """A box the user gave that misses the system: the hint widens the default box as
    well, so it does not say the box is innocent (review finding)."""
    rng = np.random.default_rng(0)
    x = np.repeat(rng.uniform(-1, 1, 20), 4)
    y = lfilter([0.0, 0.5], [1.0, -0.6], x) + rng.uniform(-0.02, 0.02, 80)
    for box in ({"a1": (0.5, 0.6)}, [[0.5, 0.6], [-1e4, 1e4]]):
        with pytest.raises(EmptyFeasibleSetError,
                           match="the a priori box may be what excludes the system"):
            hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="lp",
                                     theta_box=box).fit(x, y)


@pytest.mark.parametrize("box, match", [({"a1": "12"}, "give a pair"),
                                        ({"a1": (np.nan, 1)}, "needs finite ends")])
def test_bad_row_values(box, match):
    u, y = _unstable()
    with pytest.raises(ParameterValidationError, match=match):
        hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.05, theta_box=box).fit(
            u, y, input_bound=0.02)


def test_an_empty_dict_is_the_default_box():
    from hammerbound.stage2.fitting import box_text

    assert box_text({}, 1, 1, 1) == box_text(None, 1, 1, 1)


def test_cli_records_the_box(tmp_path, capsys):
    path = _csv(tmp_path)
    args = ["eiv", str(path), "--na", "1", "--nb", "1", "--output-bound", "0.05",
            "--input-bound", "0.02", "--method", "lp", "--theta-box", "a1=-3:3"]
    assert main([*args, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["model"]["theta_box"] == {"a1": [-3.0, 3.0]}
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "given:" in text and "a priori box a1 in [-3, 3] (--theta-box)" in text
    assert "(theta_box)" not in text
    try:
        rc = main([*args[:-1], "a1=3:-3"])
    except SystemExit as stop:
        rc = stop.code
    assert rc == 2 and "LOWER and UPPER must be finite with LOWER <= UPPER" in \
        capsys.readouterr().err


def test_the_verdict_says_which_relaxation_found_the_set_empty(monkeypatch):
    """The LP's own "empty" says relaxation="lp", the exact method's "exact": the hint then
    solves only the LP in the wider box (or nothing), not the LP in the box again."""
    from hammerbound.relaxations import lp as lp_module
    from hammerbound.stage2.fitting import widened_box_hint

    u, y = _unstable()
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.05, method="lp")
    with pytest.raises(EmptyFeasibleSetError) as exc:
        est.fit(u, y, input_bound=0.02)
    assert exc.value.relaxation == "lp"
    problem = est._build_problem(u, y, 0.02, None)
    boxes = []
    real = lp_module.lp_bounds

    def counted(pr, *args, **kwargs):
        boxes.append(pr.theta_box.copy())
        return real(pr, *args, **kwargs)

    monkeypatch.setattr(lp_module, "lp_bounds", counted)
    for relaxation, n_lps in ((None, 2), ("lp", 1), ("exact", 0)):
        boxes.clear()
        hint = widened_box_hint(problem, relaxation)
        assert len(boxes) == n_lps
        assert ("may be what excludes the system" in hint) == (relaxation != "exact")


def test_crossed_ends_name_the_method_that_certified_them():
    """Certified ends that cross are an empty verdict of the method that produced them:
    the error records it (``relaxation``), so the hint does not solve the LP again."""
    from types import SimpleNamespace

    from hammerbound.stage2.fitting import check_not_crossed

    u, y = _unstable()
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.05, method="lp",
                                   theta_box={"a1": (-3, 3)})
    est.fit(u, y, input_bound=0.02)
    crossed = np.array(est.bounds_)
    crossed[1] = [crossed[1, 1] + 0.1, crossed[1, 1]]
    for method in ("lp", "exact"):
        with pytest.raises(EmptyFeasibleSetError, match="the certified bounds on b1 cross") \
                as exc:
            check_not_crossed(SimpleNamespace(**{**est.get_params(), "method": method}),
                              est.problem_, crossed)
        assert exc.value.relaxation == method


def test_a_b_end_a_limit_left_at_the_box_is_not_blamed_on_the_data():
    """An exact fit whose budget is used up keeps the LP bound, here at the default box of
    b1: the error says the search stopped and whether the data bound b1 is not known (it
    said "the data do not bound b1", review of trial 9); the LP method, which is not
    stopped, still says the data do not bound it."""
    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 1, 30)
    y = lfilter([0.0, 0.5], [1.0, -0.5], x) + 0.3 * rng.uniform(-1, 1, 30)
    kw = dict(na=1, nb=1, output_bound=0.3, theta_box={"a1": (-0.99, 0.99)})
    with pytest.raises(UnboundedSetError, match=r"b1 lower, b1 upper below the default box"
                                                r".*the search stopped there"
                                                r".*whether the data bound it is not known"):
        hb.LinearEIVSetEstimator(method="exact", total_time_limit=0.0, **kw).fit(
            x, y, input_bound=1.0)
    with pytest.raises(UnboundedSetError, match="the data do not bound b1"):
        hb.LinearEIVSetEstimator(method="lp", **kw).fit(x, y, input_bound=1.0)


def test_exact_bounds_check_box_does_not_blame_the_data_for_a_stopped_end():
    """``exact_bounds(check_box=True)`` itself (not only the estimator) says that an end a
    limit left at the box is not known to be unbounded (it said "the data do not bound")."""
    from hammerbound.relaxations import EIVProblem, exact_bounds

    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 1, 30)
    y = lfilter([0.0, 0.5], [1.0, -0.5], x) + 0.3 * rng.uniform(-1, 1, 30)
    box = np.array([[-0.99, 0.99], [-1e4, 1e4]])
    pr = EIVProblem(y, x, np.full(30, 1.0), np.full(30, 0.3), 1, 1, theta_box=box)
    with pytest.raises(UnboundedSetError, match=r"no bound on .*b1 upper.*the search stopped"
                                                r".*whether the data bound it is not known"):
        exact_bounds(pr, total_time_limit=0.0)


def test_the_default_b_box_check_blames_the_data_only_for_ends_not_stopped():
    """Of two b ends at the default box, one stopped by a limit and one that the search
    finished, only the finished one is said to be unbounded by the data (the estimator's
    check said "the data do not bound" both as soon as one end was not stopped)."""
    from types import SimpleNamespace

    from hammerbound.stage2.fitting import check_box

    box = np.array([[-0.99, 0.99], [-1e4, 1e4]])
    problem = SimpleNamespace(theta_box=box, param_names=["a1", "b1"], na=1, nb=1, nk=1)
    infos = [SimpleNamespace(param="b1", end="lower", status="limit"),
             SimpleNamespace(param="b1", end="upper", status="optimal")]
    res = SimpleNamespace(bounds=np.array([[-0.5, 0.5], [-1e4, 1e4]]), infos=infos)
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.3)
    with pytest.raises(UnboundedSetError) as exc:
        check_box(est, problem, res)
    text = str(exc.value)
    assert re.search(r"the data do not bound b1 upper below the default box", text)
    assert re.search(r"no bound on b1 lower below the default box.*the search stopped",
                     text)
    assert "b1 lower, b1 upper" not in text
