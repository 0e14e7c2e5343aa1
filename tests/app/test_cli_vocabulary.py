"""The command line speaks one vocabulary (issue 29.13, 29.7, 29.6): the same flag for the
same thing in every subcommand (old spellings accepted with a message on stderr), the
bounds the results rest on required or printed as assumptions, ``identify`` printing like
``eiv``, ``--dt``/``--t-col``/``--delimiter`` wherever a CSV is read, warnings and errors
one line in command-line terms, progress without cursor codes into a file, and messages
that name the interface in use.

Data are simulated here (scipy's ``lfilter`` and the tests' own play operator)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from oracles import play
from scipy.signal import lfilter

from hammerbound.app.cli import build_parser, diagnose_cli_main, main
from hammerbound.exceptions import DataValidationError

ROOT = Path(__file__).resolve().parents[2]
A, B = [1.0, -0.6, 0.2], [0.0, 0.5, 0.1]
GAMMA = (0.25, 0.06, 0.26, 0.05)


def _csv(path, columns, delimiter=","):
    names = list(columns)
    rows = zip(*(columns[n] for n in names), strict=True)
    path.write_text(delimiter.join(names) + "\n" + "".join(
        delimiter.join(repr(float(v)) for v in r) + "\n" for r in rows))
    return path


@pytest.fixture(scope="module")
def rec(tmp_path_factory):
    """One EIV record (t sampled at 0.1) in several spellings, and the two records of the
    two-stage method (steady state and PRBS) sampled at 0.01."""
    d = tmp_path_factory.mktemp("vocab")
    rng = np.random.default_rng(7)
    n = 80
    x = np.where(rng.random(n) < 0.5, 1.0, -1.0)
    y = lfilter(B, A, x) + rng.uniform(-0.05, 0.05, n)
    t = 0.1 * np.arange(n)
    files = {"eiv": _csv(d / "eiv.csv", {"t": t, "u": x, "y": y}),
             "eiv_semi": _csv(d / "eiv_semi.csv", {"t": t, "u": x, "y": y}, ";"),
             "eiv_named": _csv(d / "eiv_named.csv", {"volt": x, "speed": y}),
             "eiv_extra": _csv(d / "eiv_extra.csv", {"u": x, "y": y, "temp": 0 * x})}
    amps = np.linspace(0.3, 2.5, 20)
    u_ss = np.r_[amps, -amps]
    x_ss = np.array([play([v], *GAMMA)[0] for v in u_ss])
    y_ss = x_ss + rng.uniform(-0.02, 0.02, u_ss.size)
    u = np.where(rng.random(60) < 0.5, -1.0, 1.0)
    xi = play(u, *GAMMA)
    g = (0.5 + 0.1) / (1 - 0.6 + 0.2)
    yp = lfilter(np.array(B) / g, A, xi) + rng.uniform(-0.02, 0.02, u.size)
    clock = 0.01 * np.arange(u.size)
    for sep, tag in ((",", ""), (";", "_semi")):
        files["steady" + tag] = _csv(d / f"steady{tag}.csv", {"u": u_ss, "y": y_ss}, sep)
        files["prbs" + tag] = _csv(d / f"prbs{tag}.csv", {"clock": clock, "u": u, "y": yp},
                                   sep)
    return files


def _run(capsys, *argv):
    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


EIV = ("--na", 2, "--nb", 2, "--method", "lp")


# ------------------------------------------------------------------ one flag per concept
@pytest.mark.parametrize("old, new, value", [
    ("--output-noise", "--output-bound", 0.05), ("--input-noise", "--input-bound", 0.01),
    ("--gain", "--steady-state-gain", 1.0)])
def test_eiv_old_spellings_work_and_say_so(capsys, rec, old, new, value):
    base = ["eiv", rec["eiv"], *EIV, "--json"] + ([] if old == "--output-noise" else
                                                  ["--output-bound", 0.05])
    rc_new, out_new, err_new = _run(capsys, *base, new, value)
    rc_old, out_old, err_old = _run(capsys, *base, old, value)
    assert rc_new == rc_old == 0
    assert json.loads(out_new) == json.loads(out_old)
    assert f"{old} is deprecated and will be removed in 0.3.0; use {new}" in err_old
    assert "deprecated" not in err_new


def test_column_flags_are_the_same_in_every_subcommand(capsys, rec):
    """--u-col/--y-col everywhere; --u-column/--y-column still work (with a message)."""
    parser = build_parser()
    for cmd in (["eiv", "f.csv", "--na", "1", "--nb", "1"], ["identify"],
                ["diagnose", "f.csv", "--num", "0 1", "--den", "1 -0.5"]):
        args = parser.parse_args([*cmd, "--u-col", "volt", "--y-col", "speed", "--t-col", "s",
                                  "--dt", "0.5", "--delimiter", ";"])
        assert (args.u_col, args.y_col, args.t_col, args.dt, args.delimiter) == \
            ("volt", "speed", "s", 0.5, ";")
    rc, out, err = _run(capsys, "eiv", rec["eiv_named"], *EIV, "--output-bound", 0.05,
                        "--u-column", "volt", "--y-column", "speed", "--json")
    assert rc == 0 and json.loads(out)["data"]["input"] == "volt"
    assert "--u-column is deprecated" in err and "use --u-col" in err
    assert "--y-column is deprecated" in err


def test_every_noise_spelling_maps_to_one_bound():
    parser = build_parser()
    cases = [(["benchmark", "--noise-bound", "0.02"], "output_bound", 0.02),
             (["diagnose", "f.csv", "--num", "1", "--den", "1", "--noise-bound", "0.02"],
              "output_bound", 0.02),
             (["identify", "--prbs-noise", "0.02"], "output_bound", 0.02),
             (["identify", "--steady-noise", "0.03"], "steady_output_bound", 0.03),
             (["eiv", "f", "--na", "1", "--nb", "1", "--output-noise", "0.02"],
              "output_bound", 0.02),
             (["eiv", "f", "--na", "1", "--nb", "1", "--input-noise", "0.01"],
              "input_bound", 0.01),
             (["demo", "--noise-levels", "0.005", "0.05"], "output_bounds", [0.005, 0.05])]
    for argv, dest, value in cases:
        assert getattr(parser.parse_args(argv), dest) == value, argv


# ------------------------------------------------------------------ no silent assumption
@pytest.mark.parametrize("argv", [
    ["eiv", "{eiv}", "--na", "2", "--nb", "2"],
    ["identify", "--steady", "{steady}", "--prbs", "{prbs}"],
    ["diagnose", "{eiv}", "--num", "0 0.5", "--den", "1 -0.6"]])
def test_output_bound_is_required(capsys, rec, argv):
    argv = [a.format(**rec) for a in argv]
    rc, out, err = _run(capsys, *argv)
    assert rc == 2 and out == ""
    assert f"hammerbound {argv[0]}: error: --output-bound is required" in err


def test_input_bound_given_or_printed_as_assumed(capsys, rec):
    rc, out, _ = _run(capsys, "eiv", rec["eiv"], *EIV, "--output-bound", 0.05)
    assert rc == 0
    assert "given: output error bound 0.05 (--output-bound)" in out
    assert "assumed: input error bound 0 (exact input" in out
    assert "assumptions:\n  - output error bound |eta_t| <= 0.05" in out  # the summary's
    rc, out, _ = _run(capsys, "eiv", rec["eiv"], *EIV, "--output-bound", 0.05,
                      "--input-bound", 0.0)
    assert "assumed:" not in out and "input error bound 0 (--input-bound)" in out
    rc, out, _ = _run(capsys, "eiv", rec["eiv"], *EIV, "--output-bound", 0.05, "--json")
    assert json.loads(out)["assumed"][0].startswith("input error bound 0")


# ------------------------------------------------------------------ identify like eiv
def test_identify_prints_statuses_dt_and_the_transfer_function(capsys, rec):
    rc, out, err = _run(capsys, "identify", "--steady", rec["steady"], "--prbs", rec["prbs"],
                        "--output-bound", 0.02, "--t-col", "clock", "--method", "lp")
    assert rc == 0, err
    assert "PRBS record" in out and "dt = 0.01" in out
    assert "assumed: steady-state output error bound 0.02, the same as --output-bound" in out
    head = [ln for ln in out.splitlines() if ln.startswith("parameter")]
    assert head and head[0].split()[-1] == "status"
    rows = [ln.split() for ln in out.splitlines() if ln.split()[:1] in (["ml"], ["a1"])]
    assert len(rows) == 2 and all(r[-1] == "optimal" for r in rows)
    tf = [ln for ln in out.splitlines() if ln.startswith("central model: G(z) = (")]
    assert len(tf) == 1 and tf[0].endswith("dt = 0.01")
    rc, out, _ = _run(capsys, "identify", "--steady", rec["steady"], "--prbs", rec["prbs"],
                      "--output-bound", 0.02, "--steady-output-bound", 0.02, "--t-col",
                      "clock", "--method", "lp", "--json")
    res = json.loads(out)
    assert res["data"]["dt"] == 0.01 and res["transfer_function"]["dt"] == 0.01
    assert res["assumed"] == []
    assert [r["status"] for r in res["intervals"]] == ["optimal"] * 8
    lo, hi = np.array(res["lower"]), np.array(res["upper"])
    assert np.all((lo[:4] <= GAMMA) & (np.array(GAMMA) <= hi[:4]))


def test_identify_dt_and_time_column(capsys, rec):
    common = ("identify", "--steady", rec["steady"], "--prbs", rec["prbs"], "--output-bound",
              0.02, "--method", "lp", "--json")
    # the time column is not named like one: without --t-col it is not used (and said so)
    rc, out, err = _run(capsys, *common)
    assert rc == 0 and json.loads(out)["data"]["dt"] is None
    assert "DataWarning" in err and "--t-col NAME" in err and "t='" not in err
    rc, out, _ = _run(capsys, *common, "--t-col", "", "--dt", 0.5)
    assert json.loads(out)["data"]["dt"] == 0.5
    rc, out, err = _run(capsys, *common, "--t-col", "clock", "--dt", 0.5)
    assert rc == 2 and "step 0.01" in err


def test_delimiter_wherever_csv_is_read(capsys, rec):
    rc, out, err = _run(capsys, "identify", "--steady", rec["steady_semi"], "--prbs",
                        rec["prbs_semi"], "--output-bound", 0.02, "--t-col", "clock",
                        "--method", "lp", "--json", "--delimiter", ";")
    assert rc == 0, err
    ref = _run(capsys, "identify", "--steady", rec["steady"], "--prbs", rec["prbs"],
               "--output-bound", 0.02, "--t-col", "clock", "--method", "lp", "--json")[1]
    assert json.loads(out)["lower"] == json.loads(ref)["lower"]
    rc, out, err = _run(capsys, "eiv", rec["eiv_semi"], *EIV, "--output-bound", 0.05,
                        "--delimiter", ";", "--json")
    assert rc == 0 and json.loads(out)["data"]["dt"] == 0.1
    # a wrong separator: the message suggests --delimiter
    rc, out, err = _run(capsys, "eiv", rec["eiv_semi"], *EIV, "--output-bound", 0.05)
    assert rc == 2 and "--delimiter" in err
    rc = diagnose_cli_main([str(rec["eiv_semi"]), "--num", "0 0.5 0.1", "--den", "1 -0.6 0.2",
                            "--output-bound", "0.05", "--candidates", "offset",
                            "--delimiter", ";", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["refined_model"]["dt"] == 0.1  # the t column gave dt


def test_diagnose_takes_dt(capsys, rec):
    rc = diagnose_cli_main([str(rec["eiv_named"]), "--num", "0 0.5 0.1", "--den",
                            "1 -0.6 0.2", "--output-bound", "0.05", "--u-col", "volt",
                            "--y-col", "speed", "--candidates", "offset", "--dt", "0.2",
                            "--json"])
    assert rc == 0
    assert json.loads(capsys.readouterr().out)["refined_model"]["dt"] == 0.2


# ------------------------------------------------------------------ messages
def test_reader_messages_name_the_interface_in_use(capsys, rec):
    from hammerbound import IOData
    from hammerbound.data.csv_reader import read_io_csv

    with pytest.raises(DataValidationError) as ei:
        IOData.from_csv(rec["eiv_named"])
    py = str(ei.value)
    assert "u='<name>'" in py and "--help" not in py and "--u-col" not in py
    with pytest.raises(DataValidationError) as ei:
        read_io_csv(rec["eiv_named"], "volt", "rpm")
    assert "y_column=" in str(ei.value) and "--y-col" not in str(ei.value)
    rc, _, err = _run(capsys, "eiv", rec["eiv_named"], *EIV, "--output-bound", 0.05)
    assert rc == 2 and "--u-col NAME" in err and "u='" not in err and "--help" not in err
    rc = diagnose_cli_main([str(rec["eiv_named"]), "--num", "1", "--den", "1",
                            "--output-bound", "0.1", "--u-col", "volt", "--y-col", "rpm"])
    err = capsys.readouterr().err
    assert rc == 2 and "--y-col NAME" in err and "y_column" not in err


def test_library_messages_in_cli_terms():
    from hammerbound.app.cli.console import to_cli

    msg = ("the moment relaxation is too large: ..., above the budget of 3600 s "
           "(relaxation_max_work; raise it to build anyway). Use method='lp' (polytopic "
           "outer bounds, seconds) or\n"
           "method='exact' (tight bounds; bound its time with total_time_limit), a shorter "
           "record, or a lower relaxation_order.")
    out = to_cli(msg)
    assert "\n" not in out and "max_work" not in out and "3600 s. Use" in out
    mem = ("the moment relaxation is too large: ..., more than this machine's 100 MB of "
           "memory (relaxation_max_work=inf builds it anyway). Use method='lp' ...")
    assert to_cli(mem).startswith("the moment relaxation is too large: ..., more than this "
                                  "machine's 100 MB of memory. Use --method lp")
    assert "--method lp" in out and "--method exact" in out
    assert "--total-time-limit" in out and "--order" in out and "method='" not in out
    assert to_cli("LinearEIVSetEstimator(na=40, nb=40, nk=1) has p = 80") == \
        "--na 40 --nb 40 --nk 1 has p = 80"


def test_order_guard_in_cli_terms(capsys, rec):
    rc, out, err = _run(capsys, "eiv", rec["eiv"], "--na", 40, "--nb", 40, "--output-bound",
                        0.05, "--method", "lp")
    assert rc == 2 and out == ""
    line = err.strip()
    assert "\n" not in line and line.startswith("hammerbound eiv: error: Parameter")
    assert "--na 40 --nb 40 --nk 1 has p = 80" in line and "na = nb = 6" in line


# ------------------------------------------------------------------ separate processes
def _process(args, **kw):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(
        os.pathsep)
    return subprocess.run([sys.executable, "-m", "hammerbound", *map(str, args)], text=True,
                          env=env, timeout=600, **kw)


def test_warning_is_one_cli_line_in_a_real_process(rec):
    res = _process(["eiv", rec["eiv_extra"], *EIV, "--output-bound", 0.05],
                   capture_output=True)
    assert res.returncode == 0, res.stderr
    lines = res.stderr.splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith("hammerbound eiv: warning: DataWarning: ")
    assert "--t-col NAME" in lines[0] and "--dt SECONDS" in lines[0]
    assert ".py" not in res.stderr and "warnings.warn" not in res.stderr


def test_progress_into_a_file_has_no_cursor_codes(rec, tmp_path):
    err = tmp_path / "stderr.txt"
    with err.open("w") as fh:
        res = _process(["eiv", rec["eiv"], "--na", 2, "--nb", 2, "--output-bound", 0.05,
                        "--method", "exact", "--progress", "--json"], stdout=subprocess.PIPE,
                       stderr=fh)
    text = err.read_text()
    assert res.returncode == 0, text
    json.loads(res.stdout)
    assert "\r" not in text and "\x1b" not in text
    done = [ln for ln in text.splitlines() if ln.startswith("exact ") and "finished" in ln]
    assert len(done) == 8  # one line per interval end (a1 .. b2; lower and upper)


def test_the_u_star_advice_names_no_python_call():
    """The command line has no suggest_prbs_level(): its message keeps the admissible range
    (found by a new-user trial)."""
    from hammerbound.app.cli.console import to_cli

    msg = ("u* = 0.03 is inside the dead zone: Result 1 needs u* > max(c_l^max, c_r^max) = "
           "0.114626. Choose u* in (0.114626, 2.5), e.g. with suggest_prbs_level().")
    out = to_cli(msg)
    assert "suggest_prbs_level" not in out and out.endswith("Choose u* in (0.114626, 2.5).")
