"""New-user trial 17 (a hydraulic valve positioner in a lab, both experiments, volts and
mm): what the fits assume about an output offset, and the command line's hints."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from oracles import one_record

import hammerbound as hb


def _first_order_fit(data, bound):
    """A one-record fit (na = nb = 1, method "lp", 60 s) of ``data``, warnings ignored."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return hb.HammersteinBacklashIdentifier(
            linear=hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=bound, method="lp",
                                            total_time_limit=60),
            procedure="one-record").fit(data)


def _no_offset_said(assumptions) -> bool:
    return any("no output offset" in a and "subtract a sensor offset" in a
               for a in assumptions)


def test_both_procedures_say_the_model_has_no_output_offset():
    """Trial 17: a sensor offset of 0.3 mm moved both dead bands past the truth (every
    status optimal); nothing the fit printed said the model has no offset."""
    ex = hb.chapter_example(0.05, N=60)
    two = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05), hb.LinearEIVSetEstimator(output_bound=0.05, method="lp"),
    ).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    assert _no_offset_said(two.assumptions_) and "no output offset" in two.summary()
    u, y, _ = one_record(80, 0.02, "uniform", 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        one = hb.HammersteinBacklashIdentifier(
            linear=hb.LinearEIVSetEstimator(output_bound=0.02, na=2, nb=2, method="lp",
                                            total_time_limit=2),  # the assumptions only
            procedure="one-record").fit(u, y)
    assert _no_offset_said(one.assumptions_) and "no output offset" in one.summary()


def test_an_offset_is_what_moves_the_dead_bands():
    """Why the assumption is printed: the same steady states with 0.3 added to y give
    dead-band intervals that exclude the truth (the model has no term to carry it)."""
    rng = np.random.default_rng(0)
    a = np.linspace(0.8, 5.0, 10)
    u = np.r_[a, -a]
    y = np.where(u > 0, 2.1 * (u - 0.3), 2.0 * (u + 0.4)) + rng.uniform(-0.05, 0.05, u.size)
    clean = hb.BacklashSetEstimator(0.05).fit(u, y)
    shifted = hb.BacklashSetEstimator(0.05).fit(u, y + 0.3)
    cl, cr = clean.gamma_bounds_[1], clean.gamma_bounds_[3]
    assert cl[0] <= 0.4 <= cl[1] and cr[0] <= 0.3 <= cr[1]
    cl, cr = shifted.gamma_bounds_[1], shifted.gamma_bounds_[3]
    assert cl[0] > 0.4 and cr[1] < 0.3


def test_units_in_the_column_names_are_the_record_units(tmp_path):
    """Trial 17: ``u [V]`` and ``y [mm]`` kept their units inside the names, the units
    stayed empty and no parameter carried one."""
    from oracles import play
    from scipy.signal import lfilter

    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-3, 3, 20), 10)
    y = lfilter([0, 0.3], [1, -0.7], play(u, 2.0, 0.4, 2.1, 0.3)) + rng.uniform(-0.05, 0.05,
                                                                               u.size)
    path = tmp_path / "valve.csv"
    path.write_text("time [s],u [V],y (mm)\n" + "".join(
        f"{0.02 * k:.2f},{float(a)!r},{float(b)!r}\n" for k, (a, b) in enumerate(zip(u, y, strict=True))))
    data = hb.IOData.from_csv(path, u="u [V]", y="y (mm)")
    assert (data.input_name, data.input_unit) == ("u", "V")
    assert (data.output_name, data.output_unit) == ("y", "mm")
    given = hb.IOData.from_csv(path, u="u [V]", y="y (mm)", input_unit="volt")
    assert (given.input_name, given.input_unit) == ("u [V]", "volt")  # what is given wins
    idf = _first_order_fit(data, 0.05)
    assert "units: m_l, m_r in mm/V; c_l, c_r in V" in idf.summary()
    plain = hb.IOData(u, y)
    assert (plain.input_unit, plain.output_unit) == ("", "")


def test_the_command_line_says_whose_central_model_it_prints(tmp_path, capsys):
    """Trial 16: with the backlash not bounded, ``identify --record`` printed "central
    model: G(z) = ..." (the linear block's interval centre) as if it were the system's
    estimate; Python has ``system_ = None`` there."""
    from oracles import play
    from scipy.signal import lfilter

    from hammerbound.app.cli import main

    u = np.linspace(-2.0, 2.0, 40)  # never reverses: the left line is not identified
    y = lfilter([0.0, 0.5], [1.0, -0.5], play(u, 0.25, 0.06, 0.26, 0.05))
    y = y + 0.02 * np.random.default_rng(0).uniform(-1, 1, u.size)
    path = tmp_path / "ramp.csv"
    path.write_text("u,y\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(u.tolist(), y.tolist(),
                                                                       strict=True)))
    code = main(["identify", "--record", str(path), "--na", "1", "--nb", "1", "--output-bound",
                 "0.02", "--method", "lp", "--total-time-limit", "60"])
    out = capsys.readouterr().out
    assert code == 0 and "inf" in out
    line = next(ln for ln in out.splitlines() if ln.startswith("central model"))
    assert "G(z)" in line and "of the linear block alone" in line
    assert "the backlash is not bounded: no model of the whole system" in line


@pytest.mark.deep
def test_a_swapped_record_is_told_it_may_be_swapped():
    """Trial 16: swapped columns gave "the gain is negative: fit -y", which stays empty;
    the message now names swapped columns too (17 s on one core)."""
    from oracles import play
    from scipy.signal import lfilter

    from hammerbound.exceptions import EmptyFeasibleSetError

    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1, 1, 20), 10)
    y = lfilter([0, 0.15], [1, -0.85], play(u, 1.0, 0.08, 1.0, 0.12))
    y = y + rng.uniform(-0.01, 0.01, u.size)
    ident = hb.HammersteinBacklashIdentifier(
        linear=hb.LinearEIVSetEstimator(output_bound=0.01, na=1, nb=1, method="lp",
                                        total_time_limit=120), procedure="one-record")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(EmptyFeasibleSetError, match="output columns swapped") as info:
            ident.fit(y, u)
    text = str(info.value)  # the likeliest cause before the general checklist
    assert text.index("swapped") < text.index("Likely causes")
    # new-user trial 22: KFold joined pieces of the record and got this checklist
    assert "(7) samples that are not consecutive (a cross-validation split such as KFold" \
        in " ".join(text.split())


def test_a_not_identified_warning_blames_the_record_only_for_the_record_causes():
    """Trial 16: "the record does not bound cl, cr" where the same record, with a
    gamma_box, bounded both: the relaxation over the default box was too weak to tell.
    The record is named only when the input never reverses (or does not excite)."""
    from oracles import play
    from scipy.signal import lfilter

    from hammerbound.exceptions import NotIdentifiedWarning
    from hammerbound.hammerstein.one_record import _lead
    from hammerbound.joint.prior import unidentified

    u = np.linspace(-2.0, 2.0, 40)
    y = lfilter([0.0, 0.5], [1.0, -0.5], play(u, 0.25, 0.06, 0.26, 0.05))
    y = y + 0.02 * np.random.default_rng(0).uniform(-1, 1, u.size)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hb.HammersteinBacklashIdentifier(
            linear=hb.LinearEIVSetEstimator(output_bound=0.02, na=1, nb=1, method="lp",
                                            total_time_limit=60),
            procedure="one-record").fit(u, y)
    said = [str(w.message) for w in caught if w.category is NotIdentifiedWarning]
    assert said and all(m.startswith("the record does not bound") for m in said), said
    # a reversing input whose end sits at the assumed limit: the cause is the search's
    rev = np.r_[np.linspace(-2, 2, 20), np.linspace(2, -2, 20)]
    box = np.array([[0, 10.0], [0, 4.0], [0, 10.0], [0, 4.0]])
    bounds = box.copy()
    assumed = np.zeros((4, 2), dtype=bool)
    assumed[:, 1] = True
    causes = [c for _, c in unidentified(rev, ("ml", "cl", "mr", "cr"), bounds, box, assumed)]
    assert causes and _lead(False, causes) == "the search did not bound"
    assert _lead(True, causes).startswith("within the time limit")


def test_command_line_warnings_name_no_python_attribute():
    """Trial 16: a command-line warning said "(in assumptions_)"."""
    from hammerbound.app.cli.console import to_cli

    text = to_cli("The other intervals rest on the default backlash box (in assumptions_): a")
    assert "assumptions_" not in text and "(in the assumptions printed)" in text


def test_dead_bands_over_every_input_are_said_to_leave_one_way_moves():
    """Trial 16: an output bound 5x too small left c_l >= 1.21 and c_r >= 0.97 over inputs
    in [-0.98, 0.97] after the time limit (150 s on its record), with only time-limit
    warnings. The warning's condition on the certified bounds, and its numbers rounded to
    the safe side."""
    from hammerbound.exceptions import DataWarning
    from hammerbound.hammerstein.record_checks import warn_dead_band_covers_record

    u = np.r_[-0.9757, 0.3, 0.966096]
    gb = np.array([[0.0, 11.0], [1.2136225, np.inf], [0.0, 11.0], [0.970898, np.inf]])
    with pytest.warns(DataWarning, match=r"over all the record's inputs \[-0.9757, 0.966096\] "
                      r"\(c_l >= 1.21362, c_r >= 0.970898\).*output bound is probably too "
                      r"small"):
        warn_dead_band_covers_record(u, gb)
    for row, value in ((1, 0.97), (3, 0.96)):  # one side inside the inputs: no warning
        part = gb.copy()
        part[row, 0] = value
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            warn_dead_band_covers_record(u, part)


@pytest.mark.parametrize("name, read", [
    ("u [V]", ("u", "V")), ("y (mm)", ("y", "mm")), ("T (°C)", ("T", "°C")),
    ("flow (m3/h)", ("flow", "m3/h")),
    # review 49: indices, arguments and unmatched brackets were read as units
    ("x[1]", ("x[1]", "")), ("y(t)", ("y(t)", "")), ("sin(wt)", ("sin(wt)", "")),
    ("P [kPa)", ("P [kPa)", "")), ("x [1]", ("x [1]", "")),
    ("y [mm] (filtered)", ("y [mm] (filtered)", "")), ("u []", ("u []", "")),
])
def test_a_unit_is_read_only_from_a_bracket_after_a_space(name, read):
    from hammerbound.data.timebase import name_and_unit

    assert name_and_unit(name) == read


def test_two_columns_that_would_read_the_same_name_keep_their_names():
    """Review 49: ``x [a]`` and ``x [b]`` both became ``x``."""
    data = hb.IOData.from_frame({"x [V]": np.arange(4.0), "x [mm]": np.ones(4)},
                                u="x [V]", y="x [mm]", t=None)
    assert (data.input_name, data.output_name) == ("x [V]", "x [mm]")


def test_a_record_written_with_units_reads_back_with_them(tmp_path):
    """Review 49: ``to_csv`` wrote ``u`` for a record read from ``u [V]`` (the unit lost),
    and reading it with ``u="u [V]"`` failed. It writes ``u [V]`` now, and ``u="u"``
    finds that column when none is called ``u`` alone."""
    data = hb.IOData(np.arange(5.0), np.ones(5), dt=0.5, input_name="u", output_name="y",
                     input_unit="V", output_unit="mm", time_unit="s")
    path = tmp_path / "rec.csv"
    data.to_csv(path)
    assert path.read_text().splitlines()[0] == "t [s],u [V],y [mm]"
    back = hb.IOData.from_csv(path)
    assert (back.input_name, back.input_unit, back.output_name, back.output_unit) == (
        "u", "V", "y", "mm")
    assert np.array_equal(back.u, data.u) and back.dt == 0.5
    again = hb.IOData.from_csv(path, u="u [V]", y="y [mm]")
    assert np.array_equal(again.y, data.y)


def test_the_command_line_finds_columns_with_units_by_their_names(tmp_path, capsys):
    """``--u-col u --y-col y`` (the defaults) find ``u [V]`` and ``y [mm]`` in both files of
    ``identify`` (the steady-state file is read by another reader than the record)."""
    from hammerbound.app.cli import main

    ex = hb.chapter_example(0.05, N=60)
    steady = tmp_path / "steady.csv"
    steady.write_text("u [V],y [mm]\n" + "".join(
        f"{a!r},{b!r}\n" for a, b in zip(ex.steady.u.tolist(), ex.steady.y.tolist(),
                                         strict=True)))
    prbs = tmp_path / "prbs.csv"
    prbs.write_text("u [V],y [mm]\n" + "".join(
        f"{a!r},{b!r}\n" for a, b in zip(ex.prbs.u.tolist(), ex.prbs.y.tolist(), strict=True)))
    code = main(["identify", "--steady", str(steady), "--prbs", str(prbs), "--output-bound",
                 "0.05", "--method", "lp"])
    out = capsys.readouterr().out
    assert code == 0 and "units: m_l, m_r in mm/V; c_l, c_r in V" in out


def test_the_record_line_and_json_carry_the_units(tmp_path, capsys):
    """Recheck 49: with ``u [V]`` read as name ``u`` and unit ``V`` the record line said
    ``input 'u'`` (not the column the user named) and the JSON had no units."""
    import json

    from hammerbound.app.cli import main
    from hammerbound.app.cli.printing import record_line

    data = hb.IOData(np.arange(3.0), np.ones(3), input_name="u", input_unit="V",
                     output_name="y", output_unit="mm")
    assert record_line("r.csv", data).endswith("input 'u' [V], output 'y' [mm]")
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1, 1, 20), 4)
    y = np.convolve(u, [0.0, 0.5, 0.25])[: u.size] + rng.uniform(-0.01, 0.01, u.size)
    path = tmp_path / "rec.csv"
    path.write_text("u [V],y [mm]\n" + "".join(f"{a!r},{b!r}\n" for a, b in
                                               zip(u.tolist(), y.tolist(), strict=True)))
    assert main(["eiv", str(path), "--na", "1", "--nb", "2", "--nk", "0", "--output-bound",
                 "0.05", "--input-bound", "0", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert (out["data"]["input_unit"], out["data"]["output_unit"]) == ("V", "mm")


def test_an_empty_cell_is_a_gap_with_advice(tmp_path):
    from hammerbound.exceptions import DataValidationError

    path = tmp_path / "gap.csv"
    path.write_text("u,y\n1,2\n2,\n3,4\n")
    with pytest.raises(DataValidationError, match="An empty cell is a gap.*split the record"):
        hb.IOData.from_csv(path, t=None)


def test_the_negative_gain_hint_asks_about_swapped_columns_first():
    """Recheck 49: it led with "fit -y", which on swapped columns is empty again."""
    from hammerbound.data.gain_sign import negative_gain_hint

    hint = negative_gain_hint(-2.95)
    assert hint.index("swapped") < hint.index("fit the negated output")


def test_the_report_states_the_units(tmp_path):
    """Recheck 49: report.md had no units where the summary has them."""
    from oracles import play
    from scipy.signal import lfilter

    from hammerbound.app.record_report import write_record_report

    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(-2, 2, 12), 8)
    y = lfilter([0.0, 0.5], [1.0, -0.5], play(u, 0.25, 0.06, 0.26, 0.05))
    y = y + 0.02 * rng.uniform(-1, 1, u.size)
    data = hb.IOData(u, y, dt=0.5, input_name="u", output_name="y", input_unit="V",
                     output_unit="mm", time_unit="s")
    ident = _first_order_fit(data, 0.02)
    text = write_record_report(ident, u, y, tmp_path / "rep").read_text()
    assert "Units: m_l, m_r in mm/V; c_l, c_r in V" in text
