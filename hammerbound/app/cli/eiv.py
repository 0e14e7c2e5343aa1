"""``hammerbound eiv``: bound a linear model B/A from one CSV record whose input and output
errors are bounded (errors in variables)."""

from __future__ import annotations

from ..paths import add_force_option
from .console import cli_terms, recorded_warnings
from .model_set import add_model_set_option, check_model_set, exit_status, write_model_set
from .options import (
    CLI_NAMES,
    add_bound_options,
    add_csv_options,
    add_model_options,
    add_stage2_options,
    deprecated,
    require,
    stage2_kwargs,
    theta_box_given,
)
from .printing import assumption_lines, data_fields, json_text, record_line, transfer_function

__all__ = ["add_parser", "input_bound_assumption", "run"]


def add_parser(sub):
    p = sub.add_parser(
        "eiv", help="bound a linear model from one CSV record (errors in variables)",
        description="Guaranteed intervals of A(q^-1) y = B(q^-1) u from a CSV record whose "
                    "input and output errors are bounded: |u_t - u0_t| <= --input-bound, "
                    "|y_t - y0_t| <= --output-bound. B = b_nk q^-nk + ... (nk=0: direct term "
                    "b0 plus b1..b_nb; nk>=1: nb coefficients from lag nk). A column 't' "
                    "(if present) is the time base.")
    p.add_argument("data", help="CSV file with a header row")
    add_model_options(p, required=True)
    add_bound_options(p)
    p.add_argument("--steady-state-gain", type=float, default=None, metavar="G",
                   help="impose the steady-state gain B(1)/A(1) = G (default: none)")
    deprecated(p, "--gain", "--steady-state-gain", "steady_state_gain", type=float)
    add_csv_options(p)
    add_stage2_options(p)
    p.add_argument("--json", action="store_true",
                   help="write the result as JSON to stdout (and nothing else)")
    add_model_set_option(p)
    add_force_option(p, "--model-set file")
    p.set_defaults(func=run)
    return p


def input_bound_assumption(value):
    """``(bound, given, assumed)``: an input bound not given is 0, printed as assumed."""
    if value is None:
        return 0.0, [], ["input error bound 0 (exact input; pass --input-bound if the input "
                         "is measured with errors)"]
    return value, [f"input error bound {value:g} (--input-bound)"], []


def run(args) -> int:
    from ...data.iodata import IOData
    from ...stage2.estimator import LinearEIVSetEstimator
    from ...stage2.fitting import assumption_list

    output_bound = require(args.output_bound, "--output-bound",
                           "the bound on the output errors that the intervals rest on, "
                           "e.g. --output-bound 0.05")
    input_bound, given, assumed = input_bound_assumption(args.input_bound)
    model_set = check_model_set(args)
    box_lines, box_json = theta_box_given(args)
    given = [f"output error bound {output_bound:g} (--output-bound)"] + given + box_lines
    est = LinearEIVSetEstimator(na=args.na, nb=args.nb, nk=args.nk, output_bound=output_bound,
                                steady_state_gain=args.steady_state_gain,
                                **stage2_kwargs(args))
    with recorded_warnings() as seen:  # the data's warnings too (JSON)
        data = IOData.from_csv(args.data, u=args.u_col, y=args.y_col, t=args.t_col or None,
                               dt=args.dt, delimiter=args.delimiter, argument_names=CLI_NAMES)
        est.fit(data, input_bound=input_bound)
        written = write_model_set(
            model_set, est, [cli_terms(a) for a in assumption_list(est, est.problem_)],
            args.force)
    tf_text, tf = transfer_function(est, data.dt)
    if args.json:
        out = {
            "parameters": list(est.param_names_),
            "lower": est.bounds_[:, 0].tolist(), "upper": est.bounds_[:, 1].tolist(),
            "intervals": est.intervals_.records(),
            "model": {"na": args.na, "nb": args.nb, "nk": est.problem_.nk,
                      "steady_state_gain": args.steady_state_gain, "method": args.method,
                      "method_label": est.method_label(), "theta_box": box_json},
            "data": {"file": str(args.data), **data_fields(data),
                     "input_bound": input_bound, "output_bound": output_bound},
            "assumed": assumed,
            "transfer_function": tf,
            "model_set": written,
            "warnings": seen,
        }
        print(json_text(out))
        return exit_status(model_set, written)
    print(record_line(args.data, data))
    print("\n".join(assumption_lines(given, assumed)))
    print(cli_terms(est.summary()))
    print(tf_text)
    return exit_status(model_set, written)
