"""Options shared by the subcommands: one flag per concept, the same in every subcommand.

* error bounds: ``--output-bound`` (and ``--steady-output-bound`` for the steady-state
  record of ``identify``), ``--input-bound``;
* CSV records: ``--u-col``, ``--y-col``, ``--t-col``, ``--dt``, ``--delimiter``;
* model: ``--na``, ``--nb``, ``--nk``; stage 2: ``--method``, ``--order``, ``--solver``,
  ``--n-jobs``, ``--time-limit``, ``--total-time-limit``, ``--max-nodes``, ``--theta-box``.

Old spellings (``--noise-bound``, ``--output-noise``, ``--input-noise``,
``--prbs-noise``, ``--steady-noise``, ``--u-column``, ``--y-column``, ``--gain``,
``--noise-levels``) still work: :class:`DeprecatedFlag` says on stderr which flag
replaces them (removed in 0.3.0).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from ..._compat import REMOVAL
from ...relaxations.exact.limits import DEFAULT_TOTAL_TIME_LIMIT

__all__ = ["CLI_NAMES", "DeprecatedFlag", "UsageError", "add_bound_options",
           "add_csv_options", "add_model_options", "add_stage2_options", "deprecated",
           "require"]

#: how the data readers' messages name their settings on the command line
CLI_NAMES = {"u": "--u-col NAME", "y": "--y-col NAME", "t": "--t-col NAME",
             "no_t": "--t-col ''", "auto_t": "--t-col auto", "dt": "--dt SECONDS",
             "delimiter": "--delimiter ';'"}


class UsageError(Exception):
    """A missing or contradictory option (exit status 2, like argparse's own errors)."""


class DeprecatedFlag(argparse.Action):
    """An old spelling: stores into the new flag's ``dest`` and says so on stderr."""

    def __init__(self, option_strings, dest, new_flag, **kwargs):
        self.new_flag = new_flag
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"{parser.prog}: {option_string} is deprecated and will be removed in "
              f"{REMOVAL}; use {self.new_flag}", file=sys.stderr)
        setattr(namespace, self.dest, values)


def deprecated(p, old, new, dest, **kwargs):
    """Accept ``old`` as a hidden spelling of ``new`` (same ``dest``)."""
    p.add_argument(old, dest=dest, action=DeprecatedFlag, new_flag=new,
                   help=argparse.SUPPRESS, **kwargs)


def require(value, flag: str, why: str):
    """``value``, or a :class:`UsageError` saying that ``flag`` is required and why."""
    if value is None:
        raise UsageError(f"{flag} is required: {why}")
    return value


def report_dir(args, files):
    """The directory of ``--report DIR``, checked before the fit for the report's ``files``
    (None without the option)."""
    if not args.report:
        return None
    from ..paths import check_output_dir

    return check_output_dir(args.report, files, force=args.force, option="--report")


def add_bound_options(p, *, input_bound=True, steady=False):
    """``--output-bound`` (required: checked by :func:`require` in the command, so that
    the old spellings also count) and ``--input-bound`` (default 0, printed as an
    assumption)."""
    p.add_argument("--output-bound", type=float, default=None, metavar="BOUND",
                   help="bound on the output errors |eta_t| <= BOUND (required: the "
                        "guaranteed bounds rest on it)")
    if steady:
        p.add_argument("--steady-output-bound", type=float, default=None, metavar="BOUND",
                       help="bound on the output errors of the steady-state record (default: "
                            "--output-bound, printed as an assumption)")
        deprecated(p, "--prbs-noise", "--output-bound", "output_bound", type=float)
        deprecated(p, "--steady-noise", "--steady-output-bound", "steady_output_bound",
                   type=float)
    else:
        deprecated(p, "--noise-bound", "--output-bound", "output_bound", type=float)
        deprecated(p, "--output-noise", "--output-bound", "output_bound", type=float)
    if input_bound:
        p.add_argument("--input-bound", type=float, default=None, metavar="BOUND",
                       help="bound on the input errors |dx_t| <= BOUND (default 0: exact "
                            "input; printed as an assumption)")
        deprecated(p, "--input-noise", "--input-bound", "input_bound", type=float)


def add_csv_options(p, *, time=True):
    """Column names, time base and field separator of the CSV records."""
    p.add_argument("--u-col", default="u", metavar="NAME",
                   help="input column (default u)")
    p.add_argument("--y-col", default="y", metavar="NAME",
                   help="output column (default y)")
    deprecated(p, "--u-column", "--u-col", "u_col")
    deprecated(p, "--y-column", "--y-col", "y_col")
    if time:
        p.add_argument("--t-col", default="auto", metavar="NAME",
                       help="time column (default auto: a column named t, time, 't [s]'... "
                            "if there is one; '' to ignore)")
        p.add_argument("--dt", type=float, default=None, metavar="SECONDS",
                       help="sampling time (default: from the time column, else not given)")
    p.add_argument("--delimiter", default=",",
                   help="field separator of the CSV files (default ','; e.g. ';', or tab "
                        "(also written \\t))")


def add_model_options(p, *, required=False):
    """Orders of A and B and the input delay."""
    kw = {"required": True} if required else {"default": 2}
    p.add_argument("--na", type=int, help="order of A" + ("" if required else " (default 2)"),
                   **kw)
    p.add_argument("--nb", type=int,
                   help="number of B coefficients after the direct term (b1..b_nb)"
                        + ("" if required else " (default 2)"), **kw)
    p.add_argument("--nk", type=int, default=1,
                   help="input delay: 0 adds b0, 1 = chapter (default), >1 more delay")


def theta_box_row(text):
    """``NAME=LOWER:UPPER`` of ``--theta-box`` as ``(name, (lower, upper))``."""
    name, sep, rng = str(text).partition("=")
    lo, sep2, hi = rng.partition(":")
    try:
        if not (sep and sep2 and name.strip()):
            raise ValueError
        row = (float(lo), float(hi))
        if not (np.isfinite(row).all() and row[0] <= row[1]):
            raise argparse.ArgumentTypeError(
                f"{text!r}: LOWER and UPPER must be finite with LOWER <= UPPER")
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected NAME=LOWER:UPPER, e.g. a1=-3:3 or b1=-1e6:1e6; got {text!r}") from None
    return name.strip(), row


def budget(text):
    """``--total-time-limit``, ``--time-limit``: a number of seconds >= 0, ``inf`` or
    ``none`` for no limit (a negative or NaN limit was accepted and the fit returned the a
    priori box, trial 11)."""
    word = str(text).strip().lower()
    if word == "none":
        return np.inf
    try:
        value = float(word)
    except ValueError:
        value = np.nan
    if not value >= 0:  # also NaN
        raise argparse.ArgumentTypeError(
            "must be a number of seconds >= 0, or inf (or none) for no limit; "
            f"got {text!r}")
    return value


def add_stage2_options(p, method="exact", *, inner_signal=False, theta_box=True):
    """Method, relaxation, solver, parallel jobs and the exact method's stopping rules
    (and, with ``theta_box``, the a priori box of the linear block)."""
    p.add_argument("--method", default=method, choices=["lp", "moment", "exact"],
                   help=f"stage-2 method (default {method}; exact gives the tight intervals)")
    p.add_argument("--order", type=int, default=1, help="moment relaxation order (default 1)")
    p.add_argument("--solver", default="clarabel", help="conic backend for --method moment")
    if inner_signal:
        p.add_argument("--inner-signal", default="independent",
                       choices=["independent", "two-level"],
                       help="the PRBS experiment's inner signal in stage 2: independent "
                            "errors per sample (default) or the two unknown levels of "
                            "Result 1 (two experiments only)")
    p.add_argument("--n-jobs", type=int, default=1, help="parallel bound problems")
    p.add_argument("--time-limit", type=budget, default=600.0,
                   help="exact method: seconds per interval end (default 600)")
    p.add_argument("--total-time-limit", type=budget, default=DEFAULT_TOTAL_TIME_LIMIT,
                   help="seconds for the whole fit of the linear block (the exact method's "
                        "stage 2, or a one-record fit with any method), shared by every "
                        "interval end and job; ends it stops report their certified bound "
                        f"with status 'limit' (default {DEFAULT_TOTAL_TIME_LIMIT:g}; inf or "
                        "none for no limit)")
    p.add_argument("--max-nodes", type=int, default=20000,
                   help="exact method: nodes per interval end (default 20000)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress on stderr (default: on when stderr is a terminal; exact "
                        "method and one record: bars on a terminal, plain lines otherwise; "
                        "moment method: a line per solved bound)")
    if theta_box:
        p.add_argument("--theta-box", type=theta_box_row, action="append", default=None,
                       metavar="NAME=LO:HI",
                       help="a priori bounds of one parameter of the linear block (repeat "
                            "for others), e.g. --theta-box a1=-3:3 for an unstable A; the "
                            "others keep the default box (|a_i| <= binom(na, i): stable A; "
                            "|b_j| <= 1e4)")


def theta_box_given(args) -> tuple[list[str], dict | None]:
    """The ``--theta-box`` rows as a "given" line (empty without rows) and as a JSON
    record ``{name: [lower, upper]}`` (None without rows)."""
    rows = getattr(args, "theta_box", None)
    if not rows:
        return [], None
    text = ", ".join(f"{n} in [{lo:g}, {hi:g}]" for n, (lo, hi) in rows)
    return [f"a priori box {text} (--theta-box)"], {n: [lo, hi] for n, (lo, hi) in rows}


def total_budget(args) -> float | None:
    """``--total-time-limit`` for the estimators: ``inf`` means no budget (None)."""
    t = args.total_time_limit
    return None if t is not None and t == np.inf else t


def progress_wanted(args) -> bool:
    """``--progress`` / ``--no-progress``, else on when stderr is a terminal: a long fit
    was silent for minutes unless ``--progress`` was given (new-user trial 11)."""
    from ...terminal import is_terminal

    given = getattr(args, "progress", None)
    return is_terminal() if given is None else bool(given)


def stage2_kwargs(args) -> dict:
    """Keyword arguments of LinearEIVSetEstimator from the stage-2 options."""
    rows = getattr(args, "theta_box", None)
    if rows and len({n for n, _ in rows}) < len(rows):
        raise UsageError("--theta-box names a parameter twice: give each one once")
    return {"method": args.method, "relaxation_order": args.order, "solver": args.solver,
            "n_jobs": args.n_jobs, "progress": progress_wanted(args),
            "time_limit": args.time_limit,
            "total_time_limit": total_budget(args), "max_nodes": args.max_nodes,
            "theta_box": dict(rows) if rows else None}
