"""``hammerbound identify``: backlash and linear block from one ordinary record (``--record``)
or from the chapter's two experiments (``--steady`` and ``--prbs``)."""

from __future__ import annotations

import sys

from ..paths import FORCE_FLAG, add_force_option
from .console import cli_terms, recorded_warnings
from .model_set import add_model_set_option, check_model_set, exit_status, write_model_set
from .options import (
    CLI_NAMES,
    UsageError,
    add_bound_options,
    add_csv_options,
    add_model_options,
    add_stage2_options,
    report_dir,
    require,
    stage2_kwargs,
    theta_box_given,
)
from .printing import assumption_lines, data_fields, json_text, record_line, transfer_function

__all__ = ["add_parser", "run"]


def add_parser(sub):
    p = sub.add_parser(
        "identify", help="identify backlash and linear block from CSV files",
        description="Bound backlash and linear block from one ordinary record (--record: "
                    "any input that reverses, e.g. steps, a sine, a closed-loop log) or from "
                    "the chapter's two experiments, a steady-state CSV (--steady) and a PRBS "
                    "CSV (--prbs); every CSV has a header row naming the input and output "
                    "columns.")
    # the records are checked in the command, not by argparse (clear messages, and the
    # deprecated spellings of the options also count)
    p.add_argument("--record", default=None, metavar="CSV",
                   help="one ordinary record (input, output): backlash and linear block "
                        "bounded jointly, initial backlash state unknown")
    p.add_argument("--gamma-box", type=float, nargs=8, default=None,
                   metavar=("ML_LO", "ML_HI", "CL_LO", "CL_HI", "MR_LO", "MR_HI", "CR_LO",
                            "CR_HI"),
                   help="--record: a priori box of the backlash (default: 0 <= m <= 100 "
                        "(range(y) + 2 bound)/range(u), 0 <= c <= range(u), printed as an "
                        "assumption)")
    p.add_argument("--steady", default=None, metavar="CSV",
                   help="CSV of steady-state points (signed input amplitudes, outputs)")
    p.add_argument("--prbs", default=None, metavar="CSV",
                   help="CSV of the PRBS experiment (input +-u*, output)")
    add_bound_options(p, input_bound=False, steady=True)
    add_model_options(p)
    add_csv_options(p)
    add_stage2_options(p, inner_signal=True)
    p.add_argument("--json", action="store_true",
                   help="write the result as JSON to stdout (and nothing else)")
    p.add_argument("--report", default=None, metavar="DIR",
                   help=f"write report.md + figures into DIR (the two experiments' report, "
                        f"or with --record the one-record report; its parent must exist; an "
                        f"existing report there is kept unless {FORCE_FLAG} is given)")
    add_model_set_option(p)
    add_force_option(p, "report files and the --model-set file")
    p.set_defaults(func=run)
    return p


def _bounds(args):
    """``(output bound, steady-state output bound, given, assumed)``."""
    out = require(args.output_bound, "--output-bound",
                  "the bound on the output errors of the PRBS record that the intervals "
                  "rest on, e.g. --output-bound 0.05")
    given = [f"PRBS output error bound {out:g} (--output-bound)"]
    if args.steady_output_bound is None:
        return out, out, given, [
            f"steady-state output error bound {out:g}, the same as --output-bound (same "
            "sensor; pass --steady-output-bound if it differs)"]
    if not args.steady_output_bound > 0:  # (NaN included) named here, not as --output-bound
        raise UsageError(f"--steady-output-bound must be a number > 0 (the bound on the "
                         f"steady-state output errors); got {args.steady_output_bound:g}.")
    given.append(f"steady-state output error bound {args.steady_output_bound:g} "
                 "(--steady-output-bound)")
    return out, args.steady_output_bound, given, []


def run(args) -> int:
    if args.record is not None:
        if args.prbs is not None:
            raise UsageError("give either one ordinary record (--record DATA.csv) or the "
                             "PRBS experiment (--prbs PRBS.csv with --steady STEADY.csv), "
                             "not both")
        from .one_record import run_one_record

        return run_one_record(args)
    if args.gamma_box is not None:
        raise UsageError("--gamma-box is the a priori backlash box of --record; the "
                         "two-stage procedure bounds the backlash from --steady")
    if args.steady is None or args.prbs is None:
        raise UsageError("give one ordinary record (--record DATA.csv), or the chapter's "
                         "two experiments: --steady STEADY.csv (steady-state points) and "
                         "--prbs PRBS.csv (the PRBS experiment)")
    return _two_records(args)


def _two_records(args) -> int:
    from ...data.csv_reader import read_columns
    from ...data.iodata import IOData
    from ...hammerstein.identifier import HammersteinBacklashIdentifier
    from ...stage1.estimator import BacklashSetEstimator
    from ...stage2.estimator import LinearEIVSetEstimator
    from ..report import REPORT_FILES

    output_bound, steady_bound, given, assumed = _bounds(args)
    box_lines, box_json = theta_box_given(args)
    given = given + box_lines
    out_dir = report_dir(args, REPORT_FILES)
    model_set = check_model_set(args)
    ident = HammersteinBacklashIdentifier(
        BacklashSetEstimator(steady_bound),
        LinearEIVSetEstimator(na=args.na, nb=args.nb, nk=args.nk, output_bound=output_bound,
                              **stage2_kwargs(args)),
        inner_signal=args.inner_signal, procedure="two-stage")
    with recorded_warnings() as seen:  # the data's warnings too (JSON)
        ss = read_columns(args.steady, [args.u_col, args.y_col], delimiter=args.delimiter,
                          argument_names=CLI_NAMES)
        data = IOData.from_csv(args.prbs, u=args.u_col, y=args.y_col, t=args.t_col or None,
                               dt=args.dt, delimiter=args.delimiter, argument_names=CLI_NAMES)
        steady = (ss[args.u_col], ss[args.y_col])
        _fit_two(ident, data, steady)
        written = write_model_set(
            model_set, ident.linear_, [cli_terms(a) for a in ident.assumptions_], args.force)
    tf_text, tf = transfer_function(ident.linear_, ident.dt_)
    if args.json:
        out = _record(args, ident, data, output_bound, steady_bound, assumed, tf)
        out["model"]["theta_box"] = box_json
        out["model_set"] = written
        out["warnings"] = seen
        print(json_text(out))
    else:
        print(f"steady-state record {args.steady}: {ss[args.u_col].size} points")
        print("PRBS record " + record_line(args.prbs, data))
        print("\n".join(assumption_lines(given, assumed)))
        print(cli_terms(ident.summary()))
        print(tf_text)
    if out_dir is not None:
        from ..report import write_report

        path = write_report(ident, *steady, data.u, data.y, out_dir, overwrite=args.force,
                            terms=cli_terms)
        print(f"hammerbound identify: report written to {path}", file=sys.stderr)
    return exit_status(model_set, written)


def _fit_two(ident, data, steady):
    """``ident.fit``; a stage-1 empty set names ``--steady-output-bound``, the bound of the
    steady-state record (its message said ``output_bound``, which the command line read as
    ``--output-bound``, the PRBS record's; trial 13)."""
    from ...exceptions import EmptyFeasibleSetError

    try:
        ident.fit(data, steady_state=steady)
    except EmptyFeasibleSetError as exc:
        if exc.side is None:
            raise
        raise EmptyFeasibleSetError(
            str(exc).replace("output_bound", "--steady-output-bound"), side=exc.side,
            first_index=exc.first_index, relaxation=exc.relaxation) from exc


def _record(args, ident, data, output_bound, steady_bound, assumed, tf) -> dict:
    pr = ident.linear_.problem_
    return {"procedure": "two-stage",
            "parameters": list(ident.param_names_),
            "lower": ident.bounds_[:, 0].tolist(), "upper": ident.bounds_[:, 1].tolist(),
            "intervals": ident.intervals_.records(),
            "u_star": ident.u_star_,
            "model": {"na": pr.na, "nb": pr.nb, "nk": pr.nk, "method": args.method,
                      "method_label": ident.linear_.method_label(),
                      "inner_signal": args.inner_signal},
            "data": {"steady": str(args.steady), "prbs": str(args.prbs), **data_fields(data),
                     "output_bound": output_bound, "steady_output_bound": steady_bound},
            "assumed": assumed,
            "assumptions": [cli_terms(a) for a in ident.assumptions_],
            "transfer_function": tf}
