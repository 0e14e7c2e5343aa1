"""``hammerbound diagnose``: locate, name and add the effect a linear model misses."""

from __future__ import annotations

import argparse
import csv
import sys

import numpy as np

from ...exceptions import HammerboundError, ParameterValidationError
from ..paths import add_force_option, check_output_file
from .console import cli_terms, cli_warnings, print_error
from .fitted_model import fitted_model
from .options import (
    CLI_NAMES,
    UsageError,
    add_csv_options,
    deprecated,
    progress_wanted,
    require,
)
from .printing import data_fields, json_text, record_line

__all__ = ["add_arguments", "add_parser", "diagnose_cli_main", "run"]

DESCRIPTION = "Locate, name and add the effect a linear simulation model misses."


def add_parser(sub):
    p = sub.add_parser("diagnose", help="model-discrepancy workflow", description=DESCRIPTION)
    add_arguments(p)
    return p


def add_arguments(p):
    from ...discrepancy import CANDIDATES

    p.add_argument("data", help="CSV file with input and output columns (optional header)")
    p.add_argument("--num", help="numerator B in powers of q^-1, e.g. '0 0.5' (with --den)")
    p.add_argument("--den", help="denominator A in powers of q^-1, e.g. '1 -0.5' (with --num)")
    p.add_argument("--backlash", default=None, metavar="'ML CL MR CR'",
                   help="a backlash before --num/--den (slopes and widths, e.g. "
                        "'0.25 0.6 0.25 0.4'; it starts from x0 = 0, clamped into its band)")
    p.add_argument("--model", default=None, metavar="FIT.json",
                   help="the model of a fit: the JSON of 'hammerbound identify --json' (its "
                        "central model, every parameter at the centre of its interval; "
                        "instead of --num/--den/--backlash)")
    p.add_argument("--output-bound", type=float, default=None, metavar="BOUND",
                   help="bound on the output errors |eta_t| <= BOUND (required: every "
                        "verdict rests on it)")
    deprecated(p, "--noise-bound", "--output-bound", "output_bound", type=float)
    p.add_argument("--candidates", default=None,
                   help=f"comma-separated subset of {','.join(CANDIDATES)}, or 'all' "
                        "(every registered effect)")
    p.add_argument("--refit", default="linear", choices=["linear", "none"])
    p.add_argument("--skip", type=int, default=None,
                   help="initial samples not scored (default 0; with a backlash model, "
                        "the samples its unknown initial state can reach, see below)")
    p.add_argument("--max-delay", type=int, default=10)
    p.add_argument("--max-effects", type=int, default=2, choices=(1, 2, 3),
                   help="largest number of effects searched jointly (1, 2 or 3)")
    add_csv_options(p)
    p.add_argument("--plot", default=None, help="save the diagnosis figure to this PNG "
                                                "(checked before the work)")
    p.add_argument("--json", action="store_true", help="print a JSON report")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="show the search's progress on stderr (default: on when stderr is a "
                        "terminal; bars on a terminal, plain lines otherwise)")
    add_force_option(p, "--plot files")
    p.set_defaults(func=run)


def _coeffs(text, flag):
    try:
        vals = [float(v) for v in text.replace(",", " ").split()]
    except ValueError as exc:
        raise ParameterValidationError(
            f"{flag} must be numbers separated by spaces or commas, e.g. {flag} \"1 -0.5\"; "
            f"got {text!r}."
        ) from exc
    if not vals:
        raise ParameterValidationError(f"{flag} is empty; give at least one coefficient.")
    return np.array(vals)


def _header(path, delimiter):
    """The header row of ``path`` (None when the first data row is numeric)."""
    try:
        with open(path, newline="") as fh:
            for row in csv.reader(fh, delimiter=delimiter):
                if row and any(f.strip() for f in row) and not row[0].lstrip().startswith("#"):
                    return None if all(_numeric(f) for f in row) else [f.strip() for f in row]
    except (OSError, UnicodeDecodeError, csv.Error):
        return None  # read_io_csv reports it
    return None


def _numeric(field):
    try:
        float(field)
        return True
    except ValueError:
        return False


def _column(header, spec):
    """The header name ``spec`` refers to (case-insensitive), or None."""
    low = [h.lower() for h in header]
    return header[low.index(spec.lower())] if spec.lower() in low else None


def read_record(args):
    """The record as IOData: with a time column (``--t-col``), through
    :meth:`IOData.from_csv`; otherwise the columns by name or index
    (:func:`read_io_csv`, headerless files too) with ``--dt``."""
    from ...data.csv_reader import read_io_csv
    from ...data.iodata import IOData
    from ...data.timebase import find_time_column

    header = _header(args.data, args.delimiter) if len(args.delimiter) == 1 else None
    if header is not None and args.t_col:
        u, y = _column(header, args.u_col), _column(header, args.y_col)
        t = (find_time_column(header, exclude=(u, y), where=str(args.data), spell=CLI_NAMES)
             if args.t_col == "auto" else args.t_col)
        if u and y and t:
            return IOData.from_csv(args.data, u=u, y=y, t=t, dt=args.dt,
                                   delimiter=args.delimiter, argument_names=CLI_NAMES)
    u, y = read_io_csv(args.data, args.u_col, args.y_col, args.delimiter,
                       argument_names=CLI_NAMES)
    names = {} if header is None else {"input_name": _column(header, args.u_col) or "u",
                                       "output_name": _column(header, args.y_col) or "y"}
    return IOData(u, y, dt=args.dt, **names)


def run(args) -> int:
    """0 when the (refined) model is consistent with the data, 1 when it is not."""
    from ...discrepancy import diagnose

    bound = require(args.output_bound, "--output-bound",
                    "the bound on the output errors that every verdict rests on, e.g. "
                    "--output-bound 0.02")
    if args.plot is not None:
        check_output_file(args.plot, force=args.force, option="--plot")
    data = read_record(args)
    G = _model(args)
    skip = "auto" if args.skip is None else args.skip
    cands = None if args.candidates is None else (
        "all" if args.candidates.strip() == "all" else
        [c.strip() for c in args.candidates.split(",") if c.strip()])
    rep = diagnose(G, data, output_bound=bound, candidates=cands, refit=args.refit,
                   skip=skip, max_delay=args.max_delay, max_effects=args.max_effects,
                   progress=progress_wanted(args))
    if args.plot:
        _plot(rep, args.plot)
    if args.json:
        print(json_text({**rep.to_dict(), "record": data_fields(data)}))
    else:  # what was read first, as identify and eiv do (new-user trial 21)
        print("record " + record_line(args.data, data))
        print(cli_terms(rep.summary()))
    return 0 if rep.consistent_after else 1


def _model(args):
    """The model to diagnose: ``--model FIT.json`` (a fit's central model), or ``--num``
    and ``--den`` (a transfer function; with ``--backlash`` a Hammerstein system)."""
    from ...systems.models import Backlash, HammersteinSystem, as_polynomials

    if args.model is not None:
        if any(v is not None for v in (args.num, args.den, args.backlash)):
            raise UsageError("--model FIT.json gives the whole model: drop --num, --den and "
                             "--backlash (or drop --model)")
        return fitted_model(args.model)
    if args.num is None or args.den is None:
        raise UsageError("the model is required: --num and --den (its linear block, e.g. "
                         "--num '0 0.5' --den '1 -0.5'; add --backlash 'ML CL MR CR' for a "
                         "backlash before it), or --model FIT.json (the JSON of "
                         "'hammerbound identify --json')")
    den = _coeffs(args.den, "--den")
    if den[0] != 1.0 and den[0] != 0.0:
        import warnings

        # new-user trial 21: continuous-time coefficients "4.5 1" were read as 4.5 + q^-1
        warnings.warn(f"--den starts with {den[0]:g}, not 1: the model is read in powers of "
                      f"q^-1 and divided by it (A = {np.round(den / den[0], 6).tolist()}); a "
                      "continuous-time model (powers of s) must be discretised first",
                      UserWarning, stacklevel=2)
    A, B = as_polynomials((den, _coeffs(args.num, "--num")))
    if args.backlash is not None:
        gamma = _coeffs(args.backlash, "--backlash")
        if gamma.size != 4:
            raise ParameterValidationError(
                f"--backlash takes four numbers 'ML CL MR CR' (slopes m_l, m_r and widths "
                f"c_l, c_r), e.g. --backlash '0.25 0.6 0.25 0.4'; got {gamma.size}.")
        return HammersteinSystem(Backlash(*gamma), (A, B))
    import control

    n = max(A.size, B.size)
    # dt=True (not given): the diagnosis takes the record's dt
    return control.tf(np.r_[B, np.zeros(n - B.size)], np.r_[A, np.zeros(n - A.size)], True)


def _plot(rep, path):
    import matplotlib

    matplotlib.use("Agg")
    try:
        rep.save(path)
    except OSError as exc:
        raise UsageError(f"cannot write the figure to {path}: {exc}") from None


def diagnose_cli_main(argv=None) -> int:
    """Entry point of ``hammerbound diagnose`` (the same as ``hammerbound diagnose ...``).

    Usage::

        hammerbound diagnose DATA.csv --num "0 0.5" --den "1 -0.5" --output-bound 0.02
                             [--backlash "ML CL MR CR"] (or --model FIT.json instead
                             of --num/--den) [--candidates offset,delay] [--refit linear|none] [--skip K]
                             [--max-delay D] [--max-effects {1,2,3}] [--u-col u]
                             [--y-col y] [--t-col auto] [--dt DT] [--delimiter ,]
                             [--plot out.png [--force]] [--json] [--progress]

    ``DATA.csv`` holds the input and output columns (see
    :func:`hammerbound.data.csv_reader.read_io_csv`: with a header they are found by name,
    default ``u`` and ``y``; without one the first two columns are used). ``--num``/``--den``
    are the model's coefficients in powers of ``q^-1``, ``--backlash`` a backlash before
    them; ``--model FIT.json`` takes the central model of a fit saved by ``hammerbound
    identify --json`` instead (:mod:`.fitted_model`).

    Parameters
    ----------
    argv : list of str, optional
        Arguments after the subcommand (default ``sys.argv[1:]``).

    Returns
    -------
    int
        0 when the (refined) model is consistent with the data, 1 when it is not,
        2 on invalid input or usage (message on stderr).
    """
    p = argparse.ArgumentParser(prog="hammerbound diagnose", description=DESCRIPTION)
    add_arguments(p)
    try:
        args = p.parse_args(argv)
    except SystemExit as exc:  # usage errors (already printed) and --help
        return int(exc.code or 0)
    with cli_warnings("diagnose"):
        try:
            return run(args)
        except UsageError as exc:
            print(f"hammerbound diagnose: error: {exc}", file=sys.stderr)
            return 2
        except (HammerboundError, ValueError, OSError) as exc:
            return print_error("diagnose", exc)
