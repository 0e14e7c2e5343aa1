"""hammerbound.app.chapter: the Table 22.1 -> inner-signal mapping, the records, the demo."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from hammerbound import LinearEIVSetEstimator
from hammerbound.app.chapter import (
    chapter_inner_bounds,
    reproduce_chapter,
    reproduction_misses,
)
from hammerbound.app.chapter_output import stdout_to_stderr
from hammerbound.app.cli import main
from hammerbound.exceptions import ParameterValidationError
from hammerbound.systems.experiments import CHAPTER_NOISE_LEVELS, CHAPTER_U_STAR, chapter_example

CSV = Path(__file__).resolve().parents[2] / "hammerbound" / "data" / "chapter22_tables.csv"
TRUE = {"ml": 0.25, "cl": 0.0628, "mr": 0.26, "cr": 0.0489}


def _table_22_1():
    """{delta_eta: {param: (lower_text, upper_text)}} read with the csv module."""
    out = {}
    with open(CSV, newline="") as fh:
        for r in csv.DictReader(fh):
            if r["table"] == "22.1":
                out.setdefault(float(r["delta_eta"]), {})[r["param"]] = (r["lower"], r["upper"])
    return out


def test_mapping_by_hand_at_0_3():
    # Table 22.1, delta_eta = 0.3: m_r in [0.2590, 0.2618], c_r in [0.0223, 0.0749],
    # m_l in [0.2490, 0.2518], c_l in [0.0352, 0.0898]; u* = 1.
    ib = chapter_inner_bounds(0.3, 1.0, rounding="as-printed")
    assert ib.x_hi == pytest.approx((0.2590 * (1 - 0.0749), 0.2618 * (1 - 0.0223)), abs=1e-12)
    assert ib.x_lo == pytest.approx((-0.2518 * (1 - 0.0352), -0.2490 * (1 - 0.0898)), abs=1e-12)
    # radius (22.29): (0.25596 - 0.23960) / 2
    assert ib.radius[0] == pytest.approx((0.2618 * 0.9777 - 0.2590 * 0.9251) / 2, abs=1e-12)
    # outward: every printed end moves by half a unit of its 4th decimal
    ob = chapter_inner_bounds(0.3, 1.0)
    h = 0.5e-4
    assert ob.x_hi == pytest.approx(((0.2590 - h) * (1 - 0.0749 - h),
                                     (0.2618 + h) * (1 - 0.0223 + h)), abs=1e-12)
    assert ob.radius[0] > ib.radius[0] and ob.radius[1] > ib.radius[1]


def test_mapping_uses_printed_precision():
    # delta_eta = 0.02 prints m_l as 0.2496 / 0.2503 but the true value as 0.25000: the
    # half-unit is taken from each printed end (4 decimals -> 0.5e-4)
    tab = _table_22_1()[0.02]
    lo_ml, hi_ml = (float(v) for v in tab["ml"])
    lo_cl, hi_cl = (float(v) for v in tab["cl"])
    ob = chapter_inner_bounds(0.02, 1.0)
    h = 0.5e-4
    assert ob.x_lo == pytest.approx((-(hi_ml + h) * (1 - (lo_cl - h)),
                                     -(lo_ml - h) * (1 - (hi_cl + h))), abs=1e-12)


@pytest.mark.parametrize("deta", CHAPTER_NOISE_LEVELS)
def test_mapping_contains_the_box_and_the_truth(deta):
    tab = _table_22_1()[deta]
    ib = chapter_inner_bounds(deta, CHAPTER_U_STAR, rounding="as-printed")
    rng = np.random.default_rng(1)
    for (m, c), rng_x, sign in ((("mr", "cr"), ib.x_hi, 1.0), (("ml", "cl"), ib.x_lo, -1.0)):
        mm = rng.uniform(float(tab[m][0]), float(tab[m][1]), 2000)
        cc = rng.uniform(float(tab[c][0]), float(tab[c][1]), 2000)
        x = sign * mm * (CHAPTER_U_STAR - cc)
        assert np.all((x >= rng_x[0] - 1e-15) & (x <= rng_x[1] + 1e-15))
        # the corners attain the ends
        corners = [sign * float(tab[m][i]) * (CHAPTER_U_STAR - float(tab[c][k]))
                   for i in (0, 1) for k in (0, 1)]
        assert min(corners) == pytest.approx(rng_x[0]) and max(corners) == pytest.approx(rng_x[1])
        x_true = sign * TRUE[m] * (CHAPTER_U_STAR - TRUE[c])
        assert rng_x[0] <= x_true <= rng_x[1]


def test_mapping_errors():
    with pytest.raises(ParameterValidationError, match="stage1='experiment'"):
        chapter_inner_bounds(0.1)
    with pytest.raises(ParameterValidationError, match="Result 1"):
        chapter_inner_bounds(0.3, 0.08)
    with pytest.raises(ParameterValidationError, match="outward"):
        chapter_inner_bounds(0.3, rounding="nearest")
    with pytest.raises(ParameterValidationError, match="stage1 must be one of"):
        reproduce_chapter("table", N=30, noise_levels=(0.05,), seeds=[0], method="lp")
    with pytest.raises(ParameterValidationError, match="at least one"):
        reproduce_chapter("chapter", N=30, noise_levels=(0.05,), seeds=[], method="lp")


KEYS = {"table", "N", "delta_eta", "param", "true", "lower", "upper", "chapter_lower",
        "chapter_upper", "method", "stage1", "seeds", "widths", "median_width", "spread",
        "ratio", "inside", "lowers", "uppers", "median_half_width"}


def test_records_chapter_stage1_against_direct_fit():
    seeds = [0, 3]
    recs = reproduce_chapter("chapter", N=(100, 40), noise_levels=(0.05,), seeds=seeds,
                             method="lp")
    assert len(recs) == 6 + 4 + 4
    for r in recs:
        assert KEYS <= set(r), KEYS - set(r)
        assert r["stage1"] == "chapter" and r["seeds"] == seeds
        lo, hi = np.array(r["lowers"]), np.array(r["uppers"])
        assert np.allclose(r["widths"], hi - lo)
        assert r["median_half_width"] == pytest.approx(np.median((hi - lo) / 2))
        assert r["spread"] == pytest.approx(np.ptp((hi - lo) / 2))
        assert all(r["inside"]) and r["lower"] <= r["true"] <= r["upper"]
    t22 = [r for r in recs if r["table"] == "22.2"]
    assert [r["param"] for r in t22] == ["a1", "a2", "b1", "b2"]
    a1 = t22[0]
    assert (a1["chapter_lower"], a1["chapter_upper"]) == (-0.7664, -0.7539)
    assert a1["ratio"] == pytest.approx(a1["median_half_width"] / 0.0063)
    other = [r for r in recs if r["N"] == 40]
    assert other[0]["table"] == "N=40" and other[0]["chapter_lower"] is None
    assert other[0]["ratio"] is None
    # stage 2 received exactly the inner bounds of Table 22.1 (own arithmetic, outward)
    h = 0.5e-4
    xh = ((0.2593 - h) * (1 - 0.0579 - h), (0.2609 + h) * (1 - 0.0438 + h))
    xl = (-(0.2509 + h) * (1 - 0.0576 + h), -(0.2493 - h) * (1 - 0.0722 - h))
    for k, seed in enumerate(seeds):
        ex = chapter_example(0.05, N=100, random_state=seed)
        hi_ = ex.prbs.u > 0
        xc = np.where(hi_, sum(xh) / 2, sum(xl) / 2)
        dx = np.where(hi_, (xh[1] - xh[0]) / 2, (xl[1] - xl[0]) / 2)
        b = LinearEIVSetEstimator(output_bound=0.05, method="lp", steady_state_gain=1.0).fit(
            xc, ex.prbs.y, input_bound=dx).bounds_
        assert np.allclose(b[:, 0], [r["lowers"][k] for r in t22], atol=1e-9)
        assert np.allclose(b[:, 1], [r["uppers"][k] for r in t22], atol=1e-9)
    # the inner-signal rows of Table 22.1 carry the implied range as the chapter columns
    xr = next(r for r in recs if r["param"] == "x(+u*)")
    assert (xr["chapter_lower"], xr["chapter_upper"]) == pytest.approx(xh)
    # LP is far looser than the chapter's delta = 2: the acceptance check flags the rows
    assert len(reproduction_misses(recs)) == 4


def test_records_experiment_stage1_is_our_stage1():
    recs = reproduce_chapter("experiment", N=40, noise_levels=(0.3,), seeds=[1], method="lp")
    from hammerbound import BacklashSetEstimator

    ex = chapter_example(0.3, N=40, random_state=1)
    bl = BacklashSetEstimator(0.3).fit(ex.steady.u, ex.steady.y)
    g = {r["param"]: r for r in recs if r["table"] == "22.1"}
    for j, p in enumerate(("ml", "cl", "mr", "cr")):
        assert (g[p]["lower"], g[p]["upper"]) == tuple(bl.gamma_bounds_[j])
    ib = bl.inner_signal_bounds(1.0)
    assert (g["x(+u*)"]["lower"], g["x(+u*)"]["upper"]) == pytest.approx(ib.x_hi)
    assert all(all(r["inside"]) for r in recs)


def test_stdout_to_stderr_keeps_stdout_clean(capfd):
    import os

    with stdout_to_stderr():
        print("python text")
        os.write(1, b"C-level text\n")
    print("after")
    out, err = capfd.readouterr()
    assert out == "after\n"
    assert "python text" in err and "C-level text" in err


# ----------------------------------------------------------------------------- the CLI
_TINY = ["demo", "--N", "100", "--output-bounds", "0.05", "--method", "lp", "--seeds", "0",
         "--report", ""]


def test_demo_json_stdout_parses_and_has_every_row(capfd):
    rc = main(_TINY + ["--stage1", "chapter", "--json", "-"])
    out, err = capfd.readouterr()
    assert rc == 0
    recs = json.loads(out)  # nothing but the JSON on stdout
    assert {(r["table"], r["param"]) for r in recs} == (
        {("22.1", p) for p in ("ml", "cl", "mr", "cr", "x(+u*)", "x(-u*)")}
        | {("22.2", p) for p in ("a1", "a2", "b1", "b2")})
    assert all(r["stage1"] == "chapter" and r["seeds"] == [0] for r in recs)
    assert {r["method"] for r in recs if r["table"] == "22.2"} == {"lp"}
    assert {r["method"] for r in recs if r["table"] == "22.1"} == {"polygon"}
    assert "[1/1] delta_eta=0.05 N=100 seed=0" in err  # progress on stderr


def test_demo_json_file_and_stage1_chapter(tmp_path, capsys):
    path = tmp_path / "out.json"
    rc = main(_TINY + ["--stage1", "chapter", "--json", str(path)])
    out = capsys.readouterr().out
    assert rc == 0
    assert "stage 1: chapter" in out and "Table 22.2" in out and "ratio" in out
    recs = json.loads(path.read_text())
    assert len(recs) == 10 and all(len(r["widths"]) == 1 for r in recs)


def test_demo_json_file_is_never_overwritten_without_force(tmp_path, capsys):
    path = tmp_path / "out.json"
    path.write_text("my earlier results\n")
    rc = main(_TINY + ["--json", str(path)])
    cap = capsys.readouterr()
    assert rc == 2 and "--force" in cap.err and cap.out == ""  # refused before the work
    assert path.read_text() == "my earlier results\n"
    rc = main(_TINY + ["--json", str(path), "--force", "--quiet"])
    assert rc == 0
    recs = json.loads(path.read_text())
    assert len(recs) == 10 and all(r["stage1"] == "experiment" for r in recs)
