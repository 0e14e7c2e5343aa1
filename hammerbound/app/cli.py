"""The ``hammerbound`` command: ``demo``, ``identify``, ``eiv``, ``benchmark``, ``diagnose``."""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import time

import numpy as np

from ..exceptions import HammerboundError, ParameterValidationError
from .paths import FORCE_FLAG, add_force_option, check_output_dir, check_output_file

__all__ = ["diagnose_cli_main", "main"]


class _Progress:
    """Progress lines on stderr (stdout stays the program's tables or JSON)."""

    def __init__(self, enabled, prefix="hammerbound demo"):
        self.enabled = enabled
        self.prefix = prefix
        self.t0 = time.perf_counter()

    def elapsed(self):
        return time.perf_counter() - self.t0

    def __call__(self, msg):
        if self.enabled:
            print(f"{self.prefix}: {msg}", file=sys.stderr, flush=True)


def cmd_demo(args) -> int:
    """The chapter's example end to end (section 22.5): Tables 22.1-22.3 over several noise
    draws beside the chapter's numbers (:func:`hammerbound.app.chapter.run_demo`)."""
    from ..systems.experiments import CHAPTER_NOISE_LEVELS
    from .chapter import DEMO_SEEDS, fit_example, records_json, run_demo, stdout_to_stderr
    from .paths import write_output_text
    from .report import REPORT_FILES

    # every output is checked before the (minutes long) computation
    report_dir = (check_output_dir(args.report, REPORT_FILES, force=args.force,
                                   option="--report",
                                   hint="choose another directory (--report DIR; --report '' "
                                        "for no report)")
                  if args.report else None)
    json_stdout = args.json == "-"
    json_path = (check_output_file(args.json, force=args.force, option="--json")
                 if args.json and not json_stdout else None)
    levels = CHAPTER_NOISE_LEVELS if args.noise_levels is None else tuple(args.noise_levels)
    seeds = args.seeds if args.seeds is not None else (
        [args.seed] if args.seed is not None else list(DEMO_SEEDS))
    progress = _Progress(not args.quiet)
    # with JSON on stdout, nothing else goes there (a C library's banner included)
    with stdout_to_stderr() if json_stdout else contextlib.nullcontext():
        records = run_demo(args.stage1, tuple(args.N), levels, seeds, args.method,
                           inner_signal=args.inner_signal, relaxation_order=args.order,
                           solver=args.solver, n_jobs=args.n_jobs, progress=progress,
                           linear_options={"progress": args.progress,
                                           "time_limit": args.time_limit,
                                           "total_time_limit": args.total_time_limit},
                           file=False if json_stdout else sys.stdout)
        if report_dir is not None:
            from .report import write_report

            deta = min(levels, key=lambda d: abs(d - 0.05))
            progress(f"writing the report (delta_eta = {deta:g}, N = {args.N[0]}, seed "
                     f"{seeds[0]}, our stage 1) to {report_dir} ...")
            ex, ident = fit_example(deta, args.N[0], seeds[0], args.method,
                                    inner_signal=args.inner_signal,
                                    relaxation_order=args.order, solver=args.solver,
                                    n_jobs=args.n_jobs)
            path = write_report(ident, ex.steady.u, ex.steady.y, ex.prbs.u, ex.prbs.y,
                                report_dir, gamma_true=ex.gamma_true,
                                theta_true=ex.theta_true, overwrite=args.force,
                                title=f"Chapter example, delta_eta = {deta:g}, "
                                      f"N = {args.N[0]}, seed {seeds[0]}")
            print(f"hammerbound demo: report with figures written to {path}", file=sys.stderr)
    if args.json:
        if json_stdout:
            print(records_json(records), flush=True)
        else:
            write_output_text(json_path, records_json(records) + "\n", force=args.force,
                              option="--json")
            print(f"hammerbound demo: {len(records)} records written to {json_path}",
                  file=sys.stderr)
    progress(f"done in {progress.elapsed():.1f} s")
    return 0 if all(all(r["inside"]) for r in records) else 1


def cmd_identify(args) -> int:
    """Identify from CSV files."""
    from .. import BacklashSetEstimator, HammersteinBacklashIdentifier, LinearEIVSetEstimator
    from ..data.csv_reader import read_columns
    from .report import REPORT_FILES

    report_dir = (check_output_dir(args.report, REPORT_FILES, force=args.force,
                                   option="--report") if args.report else None)
    ss = read_columns(args.steady, [args.u_column, args.y_column])
    pr = read_columns(args.prbs, [args.u_column, args.y_column])
    ident = HammersteinBacklashIdentifier(
        BacklashSetEstimator(args.steady_noise),
        LinearEIVSetEstimator(na=args.na, nb=args.nb, noise_bound=args.prbs_noise,
                              method=args.method, relaxation_order=args.order,
                              solver=args.solver, n_jobs=args.n_jobs, progress=args.progress,
                              time_limit=args.time_limit,
                              total_time_limit=args.total_time_limit),
        inner_signal=args.inner_signal,
    )
    ident.fit(pr[args.u_column], pr[args.y_column],
              steady_state=(ss[args.u_column], ss[args.y_column]))
    out = {"parameters": list(ident.param_names_),
           "lower": ident.bounds_[:, 0].tolist(), "upper": ident.bounds_[:, 1].tolist(),
           "u_star": ident.u_star_}
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print(f"PRBS level u* = {ident.u_star_:g}")
        print(f"{'param':6s} {'lower':>12s} {'centre':>12s} {'upper':>12s} {'half-width':>12s}")
        for k, n in enumerate(ident.param_names_):
            lo, hi = ident.bounds_[k]
            print(f"{n:6s} {lo:12.6f} {0.5 * (lo + hi):12.6f} {hi:12.6f} {0.5 * (hi - lo):12.6f}")
    if report_dir is not None:
        from .report import write_report

        path = write_report(ident, ss[args.u_column], ss[args.y_column], pr[args.u_column],
                            pr[args.y_column], report_dir, overwrite=args.force)
        print(f"report written to {path}", file=sys.stderr)
    return 0


def cmd_eiv(args) -> int:
    """Bound a linear model B/A from one CSV record with bounded input and output errors."""
    from .. import LinearEIVSetEstimator
    from ..data.iodata import IOData
    from ..tables import interval_records

    data = IOData.from_csv(args.data, u=args.u_col, y=args.y_col, t=args.t_col or None,
                           dt=args.dt)
    est = LinearEIVSetEstimator(
        na=args.na, nb=args.nb, nk=args.nk, noise_bound=args.output_noise,
        steady_state_gain=args.gain, method=args.method, relaxation_order=args.order,
        solver=args.solver, n_jobs=args.n_jobs, progress=args.progress,
        time_limit=args.time_limit, total_time_limit=args.total_time_limit)
    est.fit(data, input_bound=args.input_noise)
    tf = est.to_transfer_function()
    num = np.ravel(tf.num[0][0]).tolist()
    den = np.ravel(tf.den[0][0]).tolist()
    recs = interval_records(est.param_names_, est.bounds_, est._status())
    if args.json:
        out = {
            "parameters": list(est.param_names_),
            "lower": est.bounds_[:, 0].tolist(), "upper": est.bounds_[:, 1].tolist(),
            "intervals": recs,
            "model": {"na": args.na, "nb": args.nb, "nk": est.problem_.nk,
                      "steady_state_gain": args.gain, "method": args.method},
            "data": {"file": str(args.data), "N": data.N, "dt": data.dt,
                     "input": data.input_name, "output": data.output_name,
                     "input_noise": args.input_noise, "output_noise": args.output_noise},
            "transfer_function": {"num": num, "den": den, "dt": data.dt,
                                  "variable": "z"},
        }
        print(json.dumps(out, indent=2))
        return 0
    print(f"{args.data}: N = {data.N}, dt = "
          f"{'not given' if data.dt is None else f'{data.dt:g}'}, input {data.input_name!r} "
          f"(|error| <= {args.input_noise:g}), output {data.output_name!r} "
          f"(|error| <= {args.output_noise:g})")
    print(est.summary())
    dt = "not given" if data.dt is None else f"{data.dt:g}"
    print(f"central model: G(z) = ({_poly_z(num)}) / ({_poly_z(den)}), dt = {dt}")
    return 0


def _poly_z(coefs) -> str:
    """``[0.75, -0.28]`` -> ``"0.75 z - 0.28"`` (descending powers of z)."""
    c = np.trim_zeros(np.asarray(coefs, dtype=float), "f")
    if c.size == 0:
        return "0"
    terms = []
    for k, v in enumerate(c):
        p = c.size - 1 - k
        if v == 0:
            continue
        mag = abs(v)
        num = "" if (mag == 1 and p > 0) else f"{mag:.4g}"
        zp = "" if p == 0 else ("z" if p == 1 else f"z^{p}")
        term = " ".join(t for t in (num, zp) if t)
        sign = "-" if v < 0 else "+"
        terms.append(term if not terms and v > 0 else f"{sign} {term}" if terms
                     else f"-{term}")
    return " ".join(terms)


def _add_time_options(p):
    """Exact-method stopping rules: per interval end and for the whole fit."""
    p.add_argument("--time-limit", type=float, default=600.0,
                   help="exact method: seconds per interval end (default 600)")
    p.add_argument("--total-time-limit", type=float, default=None,
                   help="exact method: seconds for the whole stage-2 fit, shared by every "
                        "interval end and job; ends it stops report their certified LP/OBBT "
                        "bound with status 'limit' (default: none)")


def _add_eiv_parser(sub):
    p = sub.add_parser(
        "eiv", help="bound a linear model from one CSV record (errors in variables)",
        description="Guaranteed intervals of A(q^-1) y = B(q^-1) u from a CSV record whose "
                    "input and output errors are bounded: |u_t - u0_t| <= input noise, "
                    "|y_t - y0_t| <= output noise. B = b_nk q^-nk + ... (nk=0: direct term "
                    "b0 plus b1..b_nb; nk>=1: nb coefficients from lag nk). A column 't' "
                    "(if present) is the time base.")
    p.add_argument("data", help="CSV file with a header row")
    p.add_argument("--na", type=int, required=True, help="order of A")
    p.add_argument("--nb", type=int, required=True,
                   help="number of B coefficients after the direct term (b1..b_nb)")
    p.add_argument("--nk", type=int, default=1,
                   help="input delay: 0 adds b0, 1 = chapter (default), >1 more delay")
    p.add_argument("--input-noise", type=float, default=0.0,
                   help="bound on the input errors (default 0: exact input)")
    p.add_argument("--output-noise", type=float, required=True,
                   help="bound on the output errors")
    p.add_argument("--gain", type=float, default=None,
                   help="impose the steady-state gain B(1)/A(1) = G (default: none)")
    p.add_argument("--dt", type=float, default=None,
                   help="sampling time (default: from the t column, else not given)")
    p.add_argument("--u-col", default="u", help="input column name (default u)")
    p.add_argument("--y-col", default="y", help="output column name (default y)")
    p.add_argument("--t-col", default="auto",
                   help="time column name (default auto: a column named t, time, 't [s]'..."
                        " if there is one; '' to ignore)")
    p.add_argument("--method", default="moment", choices=["lp", "moment", "exact"],
                   help="bounding method (default moment; exact gives the tight intervals)")
    p.add_argument("--order", type=int, default=1, help="moment relaxation order (default 1)")
    p.add_argument("--solver", default="clarabel", help="conic backend for --method moment")
    p.add_argument("--n-jobs", type=int, default=1, help="parallel bound problems")
    _add_time_options(p)
    p.add_argument("--progress", action="store_true",
                   help="progress bars on stderr (exact method)")
    p.add_argument("--json", action="store_true",
                   help="write the result as JSON to stdout (and nothing else)")
    p.set_defaults(func=cmd_eiv)
    return p


def cmd_benchmark(args) -> int:
    """Quick method comparison on the chapter example (the full suite is in benchmarks/)."""
    from .. import HammersteinBacklashIdentifier, LinearEIVSetEstimator
    from ..stage1.estimator import BacklashSetEstimator
    from ..systems.experiments import chapter_example
    from .paths import write_output_text

    output = (check_output_file(args.output, force=args.force, option="--output")
              if args.output else None)
    ex = chapter_example(args.noise_bound, N=args.N, random_state=args.seed)
    configs = [("lp", 1, "independent"), ("moment", 1, "independent"),
               ("exact", 1, "independent"), ("exact", 1, "two-level")]
    rows = []
    progress = _Progress(not args.quiet, prefix="hammerbound benchmark")
    for k, (method, order, inner) in enumerate(configs, start=1):
        progress(f"[{k}/{len(configs)}] {method} ({inner}) ...")
        ident = HammersteinBacklashIdentifier(
            BacklashSetEstimator(args.noise_bound),
            LinearEIVSetEstimator(noise_bound=args.noise_bound, method=method,
                                  relaxation_order=order, n_jobs=args.n_jobs),
            inner_signal=inner)
        t = time.perf_counter()
        ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
        rows.append({"method": method, "order": order, "inner_signal": inner,
                     "time_s": time.perf_counter() - t,
                     "width": (ident.theta_bounds_[:, 1] - ident.theta_bounds_[:, 0]).tolist(),
                     "true_inside": ident.contains(ex.gamma_true, ex.theta_true)})
        progress(f"[{k}/{len(configs)}] {method} ({inner}): done in {rows[-1]['time_s']:.1f} s")
    exact_w = np.array(rows[2]["width"])
    print(f"chapter example, delta_eta = {args.noise_bound:g}, N = {args.N}")
    print(f"{'method':28s} {'time [s]':>9s}  width / exact width (a1 a2 b1 b2)   true inside")
    for r in rows:
        ratio = " ".join(f"{w / e:5.2f}" for w, e in zip(r["width"], exact_w, strict=True))
        order = f" d={r['order']}" if r["method"] == "moment" else ""
        name = f"{r['method']}{order} ({r['inner_signal']})"
        print(f"{name:28s} {r['time_s']:9.2f}  {ratio}              {r['true_inside']}")
    if output is not None:
        write_output_text(output, json.dumps(rows, indent=2), force=args.force,
                          option="--output")
        print(f"results written to {output}", file=sys.stderr)
    print("The full benchmark suite (chapter tables, scaling, Monte Carlo coverage): "
          "'python -m benchmarks list' from the repository root (docs/benchmarks.md).")
    return 0


def _add_stage2_options(p, method="moment"):
    p.add_argument("--method", default=method, choices=["lp", "moment", "exact"],
                   help=f"stage-2 method (default {method})")
    p.add_argument("--order", type=int, default=1, help="moment relaxation order (default 1)")
    p.add_argument("--solver", default="clarabel", help="conic backend for --method moment")
    p.add_argument("--inner-signal", default="independent", choices=["independent", "two-level"])
    p.add_argument("--n-jobs", type=int, default=1, help="parallel bound problems")
    _add_time_options(p)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hammerbound",
        description="Guaranteed bounds on backlash-Hammerstein systems (set-membership).",
        epilog=f"Output files are checked before any work starts and never overwritten "
               f"unless {FORCE_FLAG} is given.")
    parser.add_argument("--version", action="version", version=f"hammerbound {_version()}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("demo", help="the chapter's example end to end",
                       description="Run stages 1 and 2 on the chapter's simulated example and "
                                   "print Tables 22.1-22.3 beside the chapter's numbers.")
    p.add_argument("--N", type=int, nargs="+", default=[100, 300],
                   help="PRBS length(s) (default: the chapter's 100 and 300)")
    p.add_argument("--noise-levels", type=float, nargs="+", default=None,
                   help="noise bounds (default: the chapter's six)")
    p.add_argument("--seed", type=int, default=None, help="one noise draw (= --seeds SEED)")
    p.add_argument("--report", default="demo-report", metavar="DIR",
                   help="directory of the Markdown report with figures for delta_eta = 0.05 "
                        f"(default demo-report; '' to skip; an existing report there is "
                        f"kept unless {FORCE_FLAG} is given)")
    p.add_argument("--json", nargs="?", const="-", default=None, metavar="PATH",
                   help="write one JSON record per table row to PATH ('-' or no PATH: to "
                        "stdout, and nothing else goes to stdout)")
    p.add_argument("--stage1", default="experiment", choices=["experiment", "chapter"],
                   help="inner-signal bounds for stage 2: from our stage 1 (default) or "
                        "implied by the chapter's Table 22.1")
    p.add_argument("--seeds", type=int, nargs="+", default=None,
                   help="noise draws; rows give the median over them (default 0 1: a quick "
                        "run; the benchmark uses 0 1 2 3 4)")
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no progress lines on stderr")
    p.add_argument("--progress", action="store_true", help="progress bars (exact method)")
    add_force_option(p, "report files")
    _add_stage2_options(p, method="exact")
    p.set_defaults(func=cmd_demo, n_jobs=2)

    p = sub.add_parser("identify", help="identify from CSV files",
                       description="Bound backlash and linear block from a steady-state CSV "
                                   "and a PRBS CSV (header row with input/output columns).")
    p.add_argument("--steady", required=True, help="CSV of steady-state points")
    p.add_argument("--prbs", required=True, help="CSV of the PRBS experiment")
    p.add_argument("--u-column", default="u")
    p.add_argument("--y-column", default="y")
    p.add_argument("--steady-noise", type=float, required=True, help="steady-state noise bound")
    p.add_argument("--prbs-noise", type=float, required=True, help="PRBS output noise bound")
    p.add_argument("--na", type=int, default=2)
    p.add_argument("--nb", type=int, default=2)
    p.add_argument("--json", action="store_true", help="print the intervals as JSON")
    p.add_argument("--report", default=None, metavar="DIR",
                   help=f"write report.md + figures into DIR (its parent must exist; an "
                        f"existing report there is kept unless {FORCE_FLAG} is given)")
    p.add_argument("--progress", action="store_true", help="progress bars (exact method)")
    add_force_option(p, "report files")
    _add_stage2_options(p)
    p.set_defaults(func=cmd_identify)

    _add_eiv_parser(sub)

    p = sub.add_parser("benchmark", help="quick method comparison on the chapter example",
                       description="LP vs moment vs exact (independent and two-level) on the "
                                   "chapter example. The full suite is not installed: run "
                                   "'python -m benchmarks list' from the repository root.")
    p.add_argument("--N", type=int, default=100)
    p.add_argument("--noise-bound", type=float, default=0.05)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--n-jobs", type=int, default=1)
    p.add_argument("--output", default=None,
                   help=f"write JSON results to this file (checked before the run; an "
                        f"existing file is kept unless {FORCE_FLAG} is given)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress lines on stderr")
    add_force_option(p)
    p.set_defaults(func=cmd_benchmark)

    p = sub.add_parser("diagnose", help="model-discrepancy workflow", add_help=False)
    p.add_argument("rest", nargs=argparse.REMAINDER)
    p.set_defaults(func=None)
    return parser


def _version() -> str:
    from .. import __version__

    return __version__


def _diagnose(argv) -> int:
    """``hammerbound diagnose``: check ``--plot`` (and take ``--force``) before the work, then
    hand the rest to :func:`diagnose_cli_main`."""
    pre = argparse.ArgumentParser(add_help=False, prog="hammerbound diagnose")
    pre.add_argument("--plot", default=None)
    pre.add_argument(FORCE_FLAG, action="store_true")
    known, rest = pre.parse_known_args(argv)
    if any(a in ("-h", "--help") for a in rest):
        rc = diagnose_cli_main(rest)
        print(f"\n{FORCE_FLAG}: overwrite an existing --plot file (refused by default)")
        return rc
    if known.plot is not None:
        check_output_file(known.plot, force=known.force, option="--plot")
        rest = [*rest, "--plot", known.plot]
    return diagnose_cli_main(rest)


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


def diagnose_cli_main(argv=None) -> int:
    """Entry point of ``hammerbound diagnose``.

    Usage::

        hammerbound diagnose DATA.csv --num "0 0.5" --den "1 -0.5" --noise-bound 0.02
                             [--candidates offset,delay] [--refit linear|none] [--skip K]
                             [--max-delay D] [--max-effects {1,2,3}] [--u-column u]
                             [--y-column y]
                             [--plot out.png] [--json] [--progress]

    ``DATA.csv`` holds the input and output columns (see
    :func:`hammerbound.data.csv_reader.read_io_csv`: with a header they are found by name,
    default ``u`` and ``y``; without one the first two columns are used). ``--num``/``--den`` are the model's coefficients in powers of
    ``q^-1``.

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
    from ..data.csv_reader import read_io_csv
    from ..discrepancy import CANDIDATES, diagnose
    from ..systems.models import as_polynomials

    p = argparse.ArgumentParser(
        prog="hammerbound diagnose",
        description="Locate, name and add the effect a linear simulation model misses.",
    )
    p.add_argument("data", help="CSV file with input and output columns (optional header)")
    p.add_argument("--num", required=True, help="numerator B in powers of q^-1, e.g. '0 0.5'")
    p.add_argument("--den", required=True, help="denominator A in powers of q^-1, e.g. '1 -0.5'")
    p.add_argument("--noise-bound", required=True, type=float,
                   help="bound on the output error |eta_t|")
    p.add_argument("--candidates", default=None,
                   help=f"comma-separated subset of {','.join(CANDIDATES)}")
    p.add_argument("--refit", default="linear", choices=["linear", "none"])
    p.add_argument("--skip", type=int, default=0, help="initial samples not scored")
    p.add_argument("--max-delay", type=int, default=10)
    p.add_argument("--max-effects", type=int, default=2, choices=(1, 2, 3),
                   help="largest number of effects searched jointly (1, 2 or 3)")
    p.add_argument("--u-column", default="u", help="input column: header name or 0-based index")
    p.add_argument("--y-column", default="y",
                   help="output column: header name or 0-based index")
    p.add_argument("--delimiter", default=",")
    p.add_argument("--plot", default=None, help="save the diagnosis figure to this PNG")
    p.add_argument("--json", action="store_true", help="print a JSON report")
    p.add_argument("--progress", action="store_true",
                   help="show the search's progress on stderr (bars on a terminal, plain "
                        "lines otherwise)")
    try:
        args = p.parse_args(argv)
    except SystemExit as exc:  # usage errors (already printed) and --help
        return int(exc.code or 0)
    try:
        u, y = read_io_csv(args.data, args.u_column, args.y_column, args.delimiter)
        num, den = _coeffs(args.num, "--num"), _coeffs(args.den, "--den")
        A, B = as_polynomials((den, num))
        import control

        n = max(A.size, B.size)
        G = control.tf(np.r_[B, np.zeros(n - B.size)], np.r_[A, np.zeros(n - A.size)], True)
        cands = None if args.candidates is None else [
            c.strip() for c in args.candidates.split(",") if c.strip()
        ]
        rep = diagnose(G, u, y, args.noise_bound, candidates=cands,
                       refit=args.refit, skip=args.skip, max_delay=args.max_delay,
                       max_effects=args.max_effects, progress=args.progress)
    except HammerboundError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        try:
            fig = rep.plot(args.plot)
        except OSError as exc:
            print(f"error: cannot write the figure to {args.plot}: {exc}", file=sys.stderr)
            return 2
        plt.close(fig)
    print(json.dumps(rep.to_dict(), indent=2) if args.json else rep.summary())
    return 0 if rep.consistent_after else 1


def _run_suite(rest) -> int:
    """``hammerbound benchmark suite ...`` (removed in 0.2.0): the suite is not installed with
    the package; say where it is instead of importing it from the working directory."""
    cmd = " ".join(["python -m benchmarks", *rest]).strip()
    print("hammerbound benchmark suite: the full benchmark suite lives in the repository's "
          f"benchmarks/ folder and is not installed; from the repository root run: {cmd}",
          file=sys.stderr)
    return 2


def _error(command, exc) -> int:
    msg = " ".join(str(exc).split())  # one line, whatever the exception carries
    print(f"hammerbound {command}: error: {type(exc).__name__}: {msg}", file=sys.stderr)
    return 2


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:2] == ["benchmark", "suite"]:
        return _run_suite(argv[2:])
    command = argv[0] if argv else None
    try:
        if command == "diagnose":
            return _diagnose(argv[1:])
        args = build_parser().parse_args(argv)
        return args.func(args)
    except BrokenPipeError:  # the reader of stdout left (e.g. `| head`): stop quietly
        with contextlib.suppress(OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except (HammerboundError, ValueError, TypeError, OSError) as exc:
        return _error(command, exc)
    except KeyboardInterrupt:
        print(f"hammerbound {command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
