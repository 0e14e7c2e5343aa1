"""CSV files as a new user has them (new-user trial): Excel's UTF-8 with a byte-order
mark, tab-separated files with the tab typed as \\t, decimal commas, no header row, a
directory instead of a file."""

from __future__ import annotations

import numpy as np
import pytest

import hammerbound as hb
from hammerbound.app.cli import main
from hammerbound.exceptions import DataValidationError

U = np.array([0.5, -0.25, 1.0, 0.75, -1.0, 0.125])
Y = np.array([0.0, 0.25, -0.125, 0.5, 0.375, -0.5])


def _write(tmp_path, text, name="rec.csv", encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return path


def _rows(sep=",", dec="."):
    return "".join(f"{0.1 * k:.1f}{sep}{str(u).replace('.', dec)}{sep}"
                   f"{str(y).replace('.', dec)}\n" for k, (u, y) in enumerate(zip(U, Y, strict=True)))


@pytest.mark.parametrize("header", ["u,y", "t,u,y"])
def test_byte_order_mark_is_read(tmp_path, header):
    body = "".join(f"{u},{y}\n" for u, y in zip(U, Y, strict=True)) if header == "u,y" else _rows()
    path = _write(tmp_path, header + "\n" + body, encoding="utf-8-sig")
    data = hb.IOData.from_csv(path)
    assert np.array_equal(data.u, U) and np.array_equal(data.y, Y)
    if header == "t,u,y":
        assert data.dt == pytest.approx(0.1)


@pytest.mark.parametrize("spelling", ["\\t", "tab", "\t"])
def test_tab_spellings(tmp_path, spelling):
    path = _write(tmp_path, "t\tu\ty\n" + _rows("\t"), "rec.tsv")
    data = hb.IOData.from_csv(path, delimiter=spelling)
    assert np.array_equal(data.u, U)


@pytest.mark.parametrize("sep, said", [("\t", "tab"), (";", "';'")])
def test_the_separator_is_guessed_in_the_hint(tmp_path, capsys, sep, said):
    path = _write(tmp_path, f"t{sep}u{sep}y\n" + _rows(sep))
    rc = main(["eiv", str(path), "--na", "1", "--nb", "1", "--output-bound", "0.1",
               "--method", "lp"])
    err = capsys.readouterr().err
    assert rc == 2 and f"seems separated by {said}; pass --delimiter {said}" in err


def test_the_separator_is_guessed_when_columns_are_named(tmp_path, capsys):
    """New-user trial 21: with --u-col/--y-col given, a semicolon file was told only
    "columns are ['time;OP;PV']" (the hint came without the names)."""
    path = _write(tmp_path, "time;OP;PV\n" + _rows(";"))
    rc = main(["diagnose", str(path), "--num", "0 0.2", "--den", "1 -0.8",
               "--output-bound", "0.2", "--u-col", "OP", "--y-col", "PV"])
    err = " ".join(capsys.readouterr().err.split())
    assert rc == 2 and "seems separated by ';'; pass --delimiter ';'" in err


def test_decimal_comma_and_missing_header_and_directory(tmp_path):
    path = _write(tmp_path, "t;u;y\n" + _rows(";", ","))
    with pytest.raises(DataValidationError, match="Decimal commas are not read"):
        hb.IOData.from_csv(path, delimiter=";")
    path = _write(tmp_path, _rows(), "nohead.csv")
    with pytest.raises(DataValidationError, match="seems to have no header row"):
        hb.IOData.from_csv(path)
    with pytest.raises(DataValidationError, match="is a directory, not a CSV file"):
        hb.IOData.from_csv(tmp_path)


def test_a_table_of_both_signals_as_x_gets_advice():
    """A DataFrame holding the input and the output passed as X alone (trial 9): the error
    names its columns and the two ways to pass them."""
    pd = pytest.importorskip("pandas")
    rng = np.random.default_rng(0)
    frame = pd.DataFrame({"valve": rng.uniform(-1, 1, 50), "flow": rng.uniform(-1, 1, 50)})
    est = hb.LinearEIVSetEstimator(output_bound=0.1, method="lp")
    with pytest.raises(hb.exceptions.DataValidationError,
                       match=r"2 columns \(valve, flow\).*IOData\.from_frame\(frame, "
                             r"u='<input column>'"):
        est.fit(frame)
    with pytest.raises(hb.exceptions.DataValidationError, match="2 columns: the model"):
        est.fit(frame.to_numpy())


def _one_decimal_comma(rows: str) -> str:
    """The rows with one value written with a decimal comma (the third line's y)."""
    lines = rows.splitlines(keepends=True)
    lines[2] = lines[2].replace("-0.125", "-0,125")
    return "".join(lines)


@pytest.mark.parametrize("header", ["t,u,y", "u,y,t"])
def test_a_row_with_more_fields_than_the_header_is_refused(tmp_path, header):
    """Trial 17: ``2.38,3.5,8,827`` (a decimal comma in one value) was read as y = 8.0
    with no warning; in a steady-state file the fit then ran on the wrong value."""
    rows = _rows() if header == "t,u,y" else "".join(
        f"{u},{y},{0.1 * k:.1f}\n" for k, (u, y) in enumerate(zip(U, Y, strict=True)))
    path = _write(tmp_path, header + "\n" + _one_decimal_comma(rows))
    with pytest.raises(DataValidationError, match=r"line 4: the row has 4 fields but the "
                       r"header \(or first row\) has 3.*decimal comma"):
        hb.IOData.from_csv(path, t=None)


def test_the_headerless_reader_refuses_a_shifted_row_too(tmp_path):
    from hammerbound.data.csv_reader import read_io_csv

    body = "".join(f"{u},{y}\n" for u, y in zip(U, Y, strict=True)).replace("-0.125", "-0,125")
    with pytest.raises(DataValidationError, match="line 3: the row has 3 fields"):
        read_io_csv(_write(tmp_path, body))


def test_trailing_empty_fields_are_still_read(tmp_path):
    """Spreadsheets pad rows with empty fields: those are not shifted values."""
    body = "".join(f"{u},{y},,\n" for u, y in zip(U, Y, strict=True))
    data = hb.IOData.from_csv(_write(tmp_path, "u,y\n" + body))
    assert np.array_equal(data.u, U) and np.array_equal(data.y, Y)


def test_identify_refuses_a_steady_state_file_with_a_shifted_row(tmp_path, capsys):
    """The command line read the steady-state file of trial 17 and exited 0."""
    steady = "u,y\n1.0,0.2\n-1.0,-0.3\n2.0,0.5\n-2.0,-0,6\n"  # -0,6: a decimal comma
    path = _write(tmp_path, steady, name="steady.csv")
    prbs = _write(tmp_path, "u,y\n" + "".join(f"{u},{y}\n" for u, y in
                                              zip(np.tile([1.0, -1.0], 10), np.zeros(20),
                                                  strict=True)), name="prbs.csv")
    code = main(["identify", "--steady", str(path), "--prbs", str(prbs),
                 "--output-bound", "0.05"])
    assert code == 2
    assert "line 5: the row has 3 fields" in capsys.readouterr().err


def test_a_nan_in_the_record_says_what_to_do(tmp_path):
    """Trial 16: "'nan' is not finite" named the value but not what to do about it."""
    body = "".join(f"{u},{'nan' if k == 3 else y}\n"
                   for k, (u, y) in enumerate(zip(U, Y, strict=True)))
    with pytest.raises(DataValidationError, match=r"line 5, column 'y': 'nan' is not "
                       r"finite\. .*split the record at the gap"):
        hb.IOData.from_csv(_write(tmp_path, "u,y\n" + body))


def test_a_trailing_separator_in_the_header_does_not_hide_a_shifted_row(tmp_path):
    """Review 49: a spreadsheet's header ``u,y,`` has an unnamed third column, and the
    row ``2,38,3`` (2.38 with a decimal comma) was read as u = 2, y = 38."""
    path = _write(tmp_path, "u,y,\n1.5,2.25,\n2,38,3\n1.0,2.0,\n")
    with pytest.raises(DataValidationError, match="line 3: the row has 3 fields"):
        hb.IOData.from_csv(path, t=None)


def test_a_shifted_first_row_of_a_headerless_file_is_refused(tmp_path):
    """Review 49: without a header the first row set the width the others were checked
    against, so a shifted first row was read shifted."""
    from hammerbound.data.csv_reader import read_io_csv

    path = _write(tmp_path, "2,38,3\n1.5,2.25\n1.0,2.0\n0.5,1.0\n")
    with pytest.raises(DataValidationError, match="line 1: the row has 3 fields"):
        read_io_csv(path)


@pytest.mark.parametrize("reader", ["from_csv", "read_io_csv"])
def test_a_decimal_comma_shifting_into_a_named_empty_column_is_refused(tmp_path, reader):
    """Recheck 49: with a header ``u,y,note`` the row ``2,38,3.5`` (u = 2.38) has no more
    fields than named columns, and was read as u = 2, y = 38."""
    from hammerbound.data.csv_reader import read_io_csv

    body = "".join(f"{u},{y},\n" for u, y in zip(U, Y, strict=True))
    path = _write(tmp_path, "u,y,note\n" + body + "2,38,3.5\n0.5,1.75,ok\n")
    read = (lambda p: hb.IOData.from_csv(p, t=None)) if reader == "from_csv" else read_io_csv
    with pytest.raises(DataValidationError, match=r"line 8: the row has 3 values where "
                       r"most rows have 2, and '2' followed by '38' looks like one number "
                       r"with a decimal comma"):
        read(path)


def test_integer_counts_with_a_flag_column_are_still_read(tmp_path):
    """Integer data (ADC counts, a sample index) with a sometimes-filled numeric flag
    column look like the shifted row above, but the columns hold integers in every row."""
    rows = "".join(f"{k},{500 + k},{480 + 2 * k},{'1' if k % 4 == 0 else ''}\n"
                   for k in range(12))
    data = hb.IOData.from_csv(_write(tmp_path, "t,u,y,flag\n" + rows), t="t")
    assert np.array_equal(data.u, 500 + np.arange(12.0))
    assert np.array_equal(data.y, 480 + 2 * np.arange(12.0))


def test_a_note_with_text_is_still_read(tmp_path):
    body = "".join(f"{u},{y},{'calibrated' if k == 2 else ''}\n"
                   for k, (u, y) in enumerate(zip(U, Y, strict=True)))
    data = hb.IOData.from_csv(_write(tmp_path, "u,y,note\n" + body), t=None)
    assert np.array_equal(data.u, U) and np.array_equal(data.y, Y)


def _stamped(tmp_path, stamps, name="rec.csv", sep=","):
    rows = "".join(f"{s}{sep}{u}{sep}{y}\n" for s, u, y in zip(stamps, U, Y, strict=True))
    return _write(tmp_path, f"timestamp{sep}OP [%]{sep}PV [m3/h]\n" + rows, name=name)


def test_iso_timestamps_give_the_sampling_time(tmp_path):
    """Trial 18: a historian's export ``timestamp,OP [%],PV [m3/h]`` with date-times was
    refused as "not a number", with no way out named."""
    stamps = [f"2024-03-05 08:00:{10 * k:02d}" for k in range(U.size)]
    data = hb.IOData.from_csv(_stamped(tmp_path, stamps), u="OP", y="PV")
    assert data.dt == 10.0 and data.time_unit == "s"
    assert np.array_equal(data.u, U) and np.array_equal(data.y, Y)


def test_other_date_formats_say_how_to_read_without_them(tmp_path, capsys):
    stamps = [f"05.03.2024 08:00:{10 * k:02d}" for k in range(U.size)]
    path = _stamped(tmp_path, stamps)
    with pytest.raises(DataValidationError, match=r"'05\.03\.2024 08:00:00' \(row 1 of the "
                       r"data\), neither a number nor a date-time in ISO 8601 form.*pass "
                       r"t=None and dt=<sampling time>"):
        hb.IOData.from_csv(path, u="OP", y="PV")
    assert main(["identify", "--record", str(path), "--u-col", "OP", "--y-col", "PV",
                 "--output-bound", "0.1"]) == 2
    assert "pass --t-col '' and --dt SECONDS" in capsys.readouterr().err


def test_two_time_columns_are_asked_in_command_line_terms(tmp_path, capsys):
    path = _write(tmp_path, "timestamp,time,u,y\n" + "".join(
        f"2024-03-05 08:00:0{k},{k},{u},{y}\n" for k, (u, y) in enumerate(zip(U, Y,
                                                                              strict=True))))
    assert main(["identify", "--record", str(path), "--output-bound", "0.1"]) == 2
    err = capsys.readouterr().err
    assert "pass --t-col NAME for the one to use (or --t-col '' to use none)" in err
    assert "t='<name>'" not in err


def test_a_named_time_column_in_a_semicolon_file_names_the_separator(tmp_path, capsys):
    """Trial 18: "no time column 'time'; the columns are ['timestamp;time;OP [%];PV
    [m3/h]']" gave no hint that the file is separated by semicolons."""
    stamps = [f"2024-03-05 08:00:0{k}" for k in range(U.size)]
    path = _stamped(tmp_path, stamps, sep=";")
    assert main(["identify", "--record", str(path), "--t-col", "timestamp", "--u-col", "OP",
                 "--y-col", "PV", "--output-bound", "0.1"]) == 2
    assert "the header seems separated by ';'; pass --delimiter ';'" in capsys.readouterr().err


@pytest.mark.parametrize("kind", ["datetime", "text", "timedelta", "tz", "period"])
def test_a_frames_date_time_column_is_read_in_seconds(kind):
    """A datetime column of a DataFrame was read as nanoseconds: dt = 1e7 for steps of
    10 s, without a word; a column of periods was cut to days (review 51)."""
    pd = pytest.importorskip("pandas")
    stamps = pd.Series(pd.date_range("2024-03-05 08:00", periods=U.size, freq="10s"))
    column = {"datetime": stamps, "text": stamps.astype(str),
              "timedelta": stamps - stamps[0],
              "tz": stamps.dt.tz_localize("Europe/Berlin"),
              "period": stamps.dt.to_period("10s")}[kind]
    data = hb.IOData.from_frame(pd.DataFrame({"timestamp": column, "u": U, "y": Y}))
    assert data.dt == 10.0 and data.time_unit == "s"


def test_a_row_of_integers_with_a_text_note_is_not_taken_for_a_shift(tmp_path):
    """Review 51: ``t,u,y,note`` with t written as 2 (not 2.0), an integer u and a note on
    that row was refused as a decimal comma; joined, its y would be the note's text."""
    path = _write(tmp_path, "t,u,y,note\n0.1,40.5,3.25,\n0.2,41.5,3.5,\n2,40,3.5,calib\n"
                            "0.3,39.5,3.25,\n")
    data = hb.IOData.from_csv(path, t=None)
    assert data.u.tolist() == [40.5, 41.5, 40.0, 39.5]


def test_a_decimal_comma_in_scientific_notation_is_refused(tmp_path):
    """Review 51: ``2,5E-03`` read u = 2, y = 0.005."""
    path = _write(tmp_path, "u,y,note\n1.5,2.25,\n2,5E-03,3.5,\n0.5,1.75,\n")
    with pytest.raises(DataValidationError, match=r"'2' followed by '5E-03' looks like one "
                                                  r"number with a decimal comma"):
        hb.IOData.from_csv(path, t=None)


def test_date_times_are_never_a_sample_counter_and_follow_a_given_time_unit(tmp_path):
    """Review 51: stamps 1 s apart with dt=0.5 given were taken as a sample counter
    (dt 0.5, no word); time_unit='min' was kept with dt in seconds; a '0' among the
    stamps was read as the year 0; an offset made numpy warn."""
    import warnings

    stamps = [f"2024-03-05 08:00:0{k}" for k in range(U.size)]
    path = _stamped(tmp_path, stamps)
    with pytest.raises(DataValidationError, match="has step 1 but dt=0.5 was given"):
        hb.IOData.from_csv(path, u="OP", y="PV", dt=0.5)
    data = hb.IOData.from_csv(path, u="OP", y="PV", time_unit="min")
    assert data.time_unit == "min" and data.dt == pytest.approx(1 / 60)
    with pytest.raises(DataValidationError, match="time_unit='days' for a time column of "
                                                  "date-times"):
        hb.IOData.from_csv(path, u="OP", y="PV", time_unit="days")
    mixed = _stamped(tmp_path, ["0", *stamps[1:]], name="mixed.csv")
    with pytest.raises(DataValidationError, match=r"holds '0' \(row 1 of the data\)"):
        hb.IOData.from_csv(mixed, u="OP", y="PV")
    offset = _stamped(tmp_path, [f"2024-03-05T08:00:0{k}+01:00" for k in range(U.size)],
                      name="offset.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert hb.IOData.from_csv(offset, u="OP", y="PV").dt == 1.0


def test_a_frames_date_time_index_must_agree_with_a_given_dt():
    """New-user trial 22: with dt given, a gap in the frame's DatetimeIndex was ignored."""
    pd = pytest.importorskip("pandas")
    idx = pd.date_range("2026-01-01", periods=U.size, freq="100ms")
    frame = pd.DataFrame({"cmd": U, "pos": Y}, index=idx)
    assert hb.IOData.from_frame(frame, u="cmd", y="pos", dt=0.1).dt == 0.1
    assert hb.IOData.from_frame(frame, u="cmd", y="pos", dt=100, time_unit="ms").dt == 100
    with pytest.raises(DataValidationError, match=r"index\[3\] - index\[2\] = 0.2, expected "
                                                  r"0.1 \(the most common step\)"):
        hb.IOData.from_frame(frame.drop(frame.index[3]), u="cmd", y="pos", dt=0.1)
    with pytest.raises(DataValidationError, match="steps by 0.1 s but dt=0.2 was given"):
        hb.IOData.from_frame(frame, u="cmd", y="pos", dt=0.2)
    assert hb.IOData.from_frame(frame.reset_index(drop=True), u="cmd", y="pos", dt=0.2).dt == 0.2
