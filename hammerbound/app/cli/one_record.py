"""``hammerbound identify --record``: backlash and linear block from one ordinary record."""

from __future__ import annotations

import sys

import numpy as np

from .console import cli_terms, recorded_warnings
from .model_set import check_model_set, exit_status, write_model_set
from .options import CLI_NAMES, UsageError, report_dir, require, stage2_kwargs
from .printing import assumption_lines, data_fields, json_text, record_line, transfer_function

__all__ = ["run_one_record"]


def _gamma_box(args):
    """The ``--gamma-box`` option as a (4, 2) array (rows m_l, c_l, m_r, c_r) or None."""
    if args.gamma_box is None:
        return None
    box = np.asarray(args.gamma_box, dtype=float).reshape(4, 2)
    return box


def run_one_record(args) -> int:
    from ...hammerstein.identifier import HammersteinBacklashIdentifier
    from ...stage2.estimator import LinearEIVSetEstimator

    output_bound = require(args.output_bound, "--output-bound",
                           "the bound on the record's output errors that the intervals rest "
                           "on, e.g. --output-bound 0.05")
    if getattr(args, "inner_signal", "independent") != "independent":
        raise UsageError("--inner-signal belongs to the PRBS experiment (--prbs); with "
                         "--record the backlash's output is bounded jointly with the linear "
                         "block from the record itself (drop --inner-signal)")
    if args.steady_output_bound is not None:
        raise UsageError("--steady-output-bound belongs to --steady; one record has one "
                         "output error bound (--output-bound)")
    model_set = check_model_set(args)
    from ..record_report import RECORD_REPORT_FILES

    out_dir = report_dir(args, RECORD_REPORT_FILES)
    with recorded_warnings() as seen:  # the data's warnings too (JSON)
        data, steady = _read(args)
        ident = HammersteinBacklashIdentifier(
            linear=LinearEIVSetEstimator(na=args.na, nb=args.nb, nk=args.nk,
                                         output_bound=output_bound, **stage2_kwargs(args)),
            procedure="one-record", gamma_box=_gamma_box(args))
        ident.fit(data, steady_state=steady)
        written = write_model_set(
            model_set, ident.linear_, [cli_terms(a) for a in ident.assumptions_], args.force)
    given = [f"output error bound {output_bound:g} (--output-bound)"]
    # the linear block's central model needs only its own intervals finite (a backlash end
    # the record does not bound leaves the linear block's model as it is, as
    # ident.linear_ in Python); it then says so, and that it is the centre of the
    # intervals (trial 16 read 0.835/(z - 0.165), the middle of a set the record barely
    # limited, as an estimate of 0.15/(z - 0.85))
    tf_text, tf = (transfer_function(ident.linear_, ident.dt_)
                   if np.all(np.isfinite(ident.theta_bounds_))
                   else ("central model: not given (a linear-block interval is infinite)",
                         None))
    if tf is not None and not np.all(np.isfinite(ident.gamma_bounds_)):
        tf_text += (" -- of the linear block alone, the centre of its intervals (the "
                    "backlash is not bounded: no model of the whole system)")
    if args.json:
        print(json_text({**_record(args, ident, data, output_bound, tf),
                         "model_set": written, "warnings": seen}))
    else:
        print("record " + record_line(args.record, data))
        if steady is not None:
            print(f"steady-state points {args.steady}: {steady[0].size}, used jointly")
        print("\n".join(assumption_lines(given, [])))
        print(cli_terms(ident.summary()))
        print(tf_text)
    if out_dir is not None:
        from ..record_report import write_record_report

        path = write_record_report(ident, data.u, data.y, out_dir, overwrite=args.force,
                                   terms=cli_terms)
        print(f"hammerbound identify: report written to {path}", file=sys.stderr)
    return exit_status(model_set, written)


def _read(args):
    """The record (an IOData) and the optional steady-state points ``(u, y)``."""
    from ...data.csv_reader import read_columns
    from ...data.iodata import IOData

    data = IOData.from_csv(args.record, u=args.u_col, y=args.y_col, t=args.t_col or None,
                           dt=args.dt, delimiter=args.delimiter, argument_names=CLI_NAMES)
    if args.steady is None:
        return data, None
    ss = read_columns(args.steady, [args.u_col, args.y_col], delimiter=args.delimiter,
                      argument_names=CLI_NAMES)
    return data, (ss[args.u_col], ss[args.y_col])


def _finite(v):
    """JSON has no infinity: an interval end the record does not bound is ``null``."""
    return [float(x) if np.isfinite(x) else None for x in v]


def _record(args, ident, data, output_bound, tf) -> dict:
    pr = ident.linear_.problem_
    return {"procedure": "one-record",
            "parameters": list(ident.param_names_),
            "lower": _finite(ident.bounds_[:, 0]), "upper": _finite(ident.bounds_[:, 1]),
            "intervals": ident.intervals_.records(),
            "model": {"na": pr.na, "nb": pr.nb, "nk": pr.nk, "method": args.method},
            "data": {"record": str(args.record), **data_fields(data),
                     "output_bound": output_bound,
                     "steady": None if args.steady is None else str(args.steady)},
            "assumptions": [cli_terms(a) for a in ident.assumptions_],
            "transfer_function": tf}
