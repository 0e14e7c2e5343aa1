"""Issue 29 item 7 (data part): the time column of a record -- recognised under its usual
names, its step to the precision the column supports, and a clear word when a column
that might be time is not used."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.app.cli import main
from hammerbound.data.timebase import time_unit_of, uniform_step
from hammerbound.exceptions import DataValidationError, DataWarning


def write(path, header, cols, fmt="%.10g"):
    np.savetxt(path, np.column_stack(cols), delimiter=",", fmt=fmt, header=",".join(header),
               comments="")
    return path


def record(N=60, seed=0):
    """Own simulation of a first-order plant, output errors exactly at +-0.01."""
    rng = np.random.default_rng(seed)
    u = np.where(rng.random(N) < 0.5, 1.0, -1.0)
    y = lfilter([0, 0.5], [1, -0.6], u) + 0.01 * rng.choice([-1.0, 1.0], N)
    return u, y


@pytest.mark.parametrize("step", [0.01, 0.1, 0.001, 0.02, 2.5e-4, 5.0])
def test_step_of_a_decimal_column_is_that_decimal(tmp_path, step):
    """np.arange(N) * 0.01 written with %.10g used to give dt = 0.010000000000000009."""
    u, y = record()
    t = np.arange(u.size) * step
    d = hb.IOData.from_csv(write(tmp_path / "r.csv", ["t", "u", "y"], [t, u, y]))
    assert d.dt == step
    est = hb.LinearEIVSetEstimator(1, 1, output_bound=0.01, method="lp").fit(d)
    assert est.dt_ == step and est.to_transfer_function().dt == step
    assert hb.IOData.from_frame({"t": t, "u": u, "y": y}).dt == step


def test_step_keeps_the_precision_the_column_has():
    t = np.arange(50) / 3.0  # not a short decimal: kept to float precision
    assert uniform_step(t) == pytest.approx(1 / 3, rel=1e-15)
    t = 0.0123456789 * np.arange(50)
    assert uniform_step(t) == pytest.approx(0.0123456789, rel=1e-15)
    # Unix time stamps: 1e-7 s rounding on every value, the step is still 0.01
    assert uniform_step(1.7e9 + 0.01 * np.arange(1000)) == 0.01
    # a step that really is 0.0100001 is not rounded to 0.01
    assert uniform_step(0.0100001 * np.arange(100)) == pytest.approx(0.0100001, rel=1e-12)


@pytest.mark.parametrize("name,unit", [("t", ""), ("time", ""), ("Time", ""), ("TIME", ""),
                                       ("t [s]", "s"), ("time (ms)", "ms"), ("t_s", "s"),
                                       ("Time [s]", "s"), ("timestamp", "")])
def test_usual_time_column_names_are_recognised(tmp_path, name, unit):
    u, y = record()
    t = 5.0 + 0.05 * np.arange(u.size)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # recognised: no warning
        d = hb.IOData.from_csv(write(tmp_path / "r.csv", [name, "u", "y"], [t, u, y]))
    assert d.dt == 0.05 and d.t0 == 5.0 and d.time_unit == unit
    assert d[3:9].time_unit == unit and d[3:9].t0 == pytest.approx(5.15)
    assert time_unit_of(name) == unit
    assert ("dt=0.05 " + unit).strip() in repr(d)


def test_unknown_time_column_is_named_in_a_warning(tmp_path):
    u, y = record()
    p = write(tmp_path / "r.csv", ["clock", "u", "y"], [0.1 * np.arange(u.size), u, y])
    with pytest.warns(DataWarning, match=r"\['clock'\].*t='<name>'"):
        d = hb.IOData.from_csv(p)
    assert d.dt is None
    assert hb.IOData.from_csv(p, t="clock").dt == 0.1  # the fix the message gives
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert hb.IOData.from_csv(p, t=None).dt is None
        assert hb.IOData.from_csv(p, dt=0.1).dt == 0.1
        only = write(tmp_path / "uy.csv", ["u", "y"], [u, y])
        assert hb.IOData.from_csv(only).dt is None  # nothing unused: nothing to say


def test_ambiguous_or_missing_time_columns_are_errors(tmp_path):
    u, y = record()
    t = 0.1 * np.arange(u.size)
    p = write(tmp_path / "r.csv", ["t", "time", "u", "y"], [t, t, u, y])
    with pytest.raises(DataValidationError, match=r"several columns.*t='<name>'"):
        hb.IOData.from_csv(p)
    assert hb.IOData.from_csv(p, t="time").dt == 0.1
    with pytest.raises(DataValidationError, match="no time column 'secs'"):
        hb.IOData.from_csv(p, t="secs")
    with pytest.raises(DataValidationError, match="several columns"):
        hb.IOData.from_frame({"t": t, "Time": t, "u": u, "y": y})


def test_time_column_that_counts_samples_with_dt(tmp_path):
    u, y = record()
    p = write(tmp_path / "r.csv", ["time", "u", "y"], [np.arange(u.size), u, y])
    d = hb.IOData.from_csv(p, dt=0.1)
    assert d.dt == 0.1 and d.time_unit == ""
    p2 = write(tmp_path / "r2.csv", ["t [ms]", "u", "y"], [2.0 * np.arange(u.size), u, y])
    with pytest.raises(DataValidationError, match="step 2 but dt=0.1"):
        hb.IOData.from_csv(p2, dt=0.1)


def test_cli_eiv_reads_a_time_column_named_time(tmp_path, capsys):
    u, y = record()
    p = write(tmp_path / "r.csv", ["time", "u", "y"], [0.01 * np.arange(u.size), u, y])
    rc = main(["eiv", str(p), "--na", "1", "--nb", "1", "--input-bound", "0",
               "--output-bound", "0.01", "--method", "lp", "--json"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["data"]["dt"] == 0.01 and out["transfer_function"]["dt"] == 0.01


def test_a_frames_datetime_index_is_its_time_base():
    """New-user trial 14: a frame indexed by time stamps (a historian's export) gave dt =
    None without a word. The index is the time base (seconds) when no time column or dt
    is given; a plain row index says nothing of the time; an uneven one is refused."""
    pd = pytest.importorskip("pandas")
    u, y = record()
    n = u.size
    stamps = pd.date_range("2026-01-01 08:00", periods=n, freq="10s", name="time")
    d = hb.IOData.from_frame(pd.DataFrame({"OP": u, "PV": y}, index=stamps), u="OP", y="PV")
    assert d.dt == 10.0 and d.time_unit == "s"
    lag = pd.to_timedelta(0.5 * np.arange(n), unit="s")
    assert hb.IOData.from_frame(pd.DataFrame({"u": u, "y": y}, index=lag)).dt == 0.5
    assert hb.IOData.from_frame(pd.DataFrame({"u": u, "y": y})).dt is None
    # a dt given must agree with the index (new-user trial 22: a gap was ignored beside it)
    assert hb.IOData.from_frame(pd.DataFrame({"u": u, "y": y}, index=stamps),
                                dt=10.0).dt == 10.0
    with pytest.raises(DataValidationError, match="reset_index"):
        hb.IOData.from_frame(pd.DataFrame({"u": u, "y": y}, index=stamps), dt=2.0)
    uneven = stamps.delete(3)
    with pytest.raises(DataValidationError, match="not uniformly sampled"):
        hb.IOData.from_frame(pd.DataFrame({"u": u[:-1], "y": y[:-1]}, index=uneven))


def test_a_period_index_is_a_time_base_and_an_uneven_index_is_named():
    """Review: a PeriodIndex still gave dt = None; an uneven index's error named a column
    "time [s]" that the frame does not have."""
    pd = pytest.importorskip("pandas")
    u, y = record()
    periods = pd.period_range("2026-01-01 08:00", periods=u.size, freq="10s")
    d = hb.IOData.from_frame(pd.DataFrame({"u": u, "y": y}, index=periods))
    assert d.dt == 10.0 and d.time_unit == "s"
    stamps = pd.date_range("2026-01-01 08:00", periods=u.size, freq="10s").delete(3)
    with pytest.raises(DataValidationError, match="the frame's index"):
        hb.IOData.from_frame(pd.DataFrame({"u": u[:-1], "y": y[:-1]}, index=stamps))


def test_a_missing_sample_is_named_where_it_is():
    """New-user trial 21: with one row deleted the message named time[1] - time[0] = 1
    against the mean step 1.00125, not the gap."""
    t = np.delete(np.arange(800.0), 100)
    with pytest.raises(DataValidationError,
                       match=r"time\[100\] - time\[99\] = 2, expected 1 \(the most common "
                             r"step\) \(1 sample\(s\) missing there\?\)"):
        uniform_step(t, "time")
