"""The ``hammerbound`` command: ``demo``, ``identify``, ``benchmark``, ``diagnose``."""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from .cli_paths import FORCE_FLAG, add_force_option, check_output_dir, check_output_file
from .exceptions import HammerboundError

__all__ = ["main"]


def _fmt(v, w=8, d=4):
    return f"{v:{w}.{d}f}"


def _chapter_rows(table, n=None):
    from .io import load_chapter_tables

    rows = {}
    for r in load_chapter_tables():
        if r["table"] != table or (n is not None and r["N"] and int(r["N"]) != n):
            continue
        rows[(float(r["delta_eta"]), r["param"])] = r
    return rows


def _print_table(title, names, results, chapter, file=None):
    file = sys.stdout if file is None else file
    """results: list of (deta, snr, bounds (p,2), true (p,))."""
    print(f"\n{title}", file=file)
    print("  ours: lower / centre / upper (half-width), chapter's in [ ]; * = true value "
          "inside our interval", file=file)
    for deta, snr, bounds, true in results:
        ch = chapter.get((deta, names[0]))
        snr_ch = f", chapter {ch['snr_db']} dB" if ch else ""
        print(f"  delta_eta = {deta:g}  (SNR {snr:.1f} dB{snr_ch})", file=file)
        for k, name in enumerate(names):
            lo, hi = bounds[k]
            ok = "*" if lo <= true[k] <= hi else "!"
            line = (f"    {name:3s} true {_fmt(true[k])}  ours {_fmt(lo)} {_fmt(0.5 * (lo + hi))} "
                    f"{_fmt(hi)} ({0.5 * (hi - lo):.4f}){ok}")
            c = chapter.get((deta, name))
            if c:
                line += (f"  [{float(c['lower']):.4f} {float(c['center']):.4f} "
                         f"{float(c['upper']):.4f} ({float(c['half_width']):.4f})]")
            print(line, file=file)


def _table_json(names, results, chapter):
    """The rows of one demo table as JSON-ready dicts (ours, the truth, the chapter's)."""
    out = []
    for deta, snr, bounds, true in results:
        params = []
        for k, name in enumerate(names):
            lo, hi = float(bounds[k][0]), float(bounds[k][1])
            row = {"parameter": name, "true": float(true[k]), "lower": lo,
                   "centre": 0.5 * (lo + hi), "upper": hi, "half_width": 0.5 * (hi - lo),
                   "true_inside": bool(lo <= true[k] <= hi)}
            c = chapter.get((deta, name))
            if c:
                row["chapter"] = {"lower": float(c["lower"]), "centre": float(c["center"]),
                                  "upper": float(c["upper"]),
                                  "half_width": float(c["half_width"])}
            params.append(row)
        ch = chapter.get((deta, names[0]))
        out.append({"delta_eta": deta, "snr_db": float(snr),
                    "chapter_snr_db": float(ch["snr_db"]) if ch and ch["snr_db"] else None,
                    "parameters": params})
    return out


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
    """The chapter's example end to end (section 22.5) on the built-in default."""
    from . import BacklashSetEstimator, HammersteinBacklashIdentifier, LinearEIVSetEstimator
    from .experiments import CHAPTER_NOISE_LEVELS, chapter_example
    from .report import REPORT_FILES

    # every output is checked before the (minutes long) computation
    report_dir = (check_output_dir(args.report, REPORT_FILES, force=args.force,
                                   option="--report",
                                   hint="choose another directory (--report DIR; --report '' "
                                        "for no report)")
                  if args.report else None)
    levels = CHAPTER_NOISE_LEVELS if args.noise_levels is None else tuple(args.noise_levels)
    text = None if args.json else sys.stdout
    progress = _Progress(not args.quiet)
    method = (f"{args.method}" + (f" (order {args.order}, {args.solver})"
                                  if args.method == "moment" else ""))
    if text:
        print("hammerbound demo: the simulated example of section 22.5 (Cerone, Piga & Regruto)")
        print("  backlash m_l=0.25 c_l=0.0628 m_r=0.26 c_r=0.0489; G = (2.15 q^-1 - 1.09 q^-2) "
              "/ (1 - 0.76 q^-1 + 0.82 q^-2), normalised to unit gain (22.8)")
        print(f"  M = 50 square-wave amplitudes, PRBS N = {' and '.join(map(str, args.N))}, "
              f"stage-2 method {method}, inner signal {args.inner_signal}", flush=True)
    n_fits = len(args.N) * len(levels)
    progress(f"{n_fits} fits ({len(args.N)} PRBS length(s) x {len(levels)} noise level(s)), "
             f"each stage 1 (backlash, exact polygons) then stage 2 (linear block, method "
             f"{method}); progress on stderr, --quiet to hide it")
    t0 = time.perf_counter()
    failures = 0
    report_fit = None
    doc = {"example": "Cerone, Piga & Regruto, section 22.5", "method": args.method,
           "relaxation_order": args.order if args.method == "moment" else None,
           "inner_signal": args.inner_signal, "seed": args.seed, "N": list(args.N),
           "noise_levels": list(levels), "stage1": None, "inner_signal_bounds": None,
           "stage2": []}
    k_fit = 0
    for n_idx, N in enumerate(args.N):
        res1, res2, inner_rows, fitted = [], [], [], []
        t_n = time.perf_counter()
        for deta in levels:
            k_fit += 1
            progress(f"[{k_fit}/{n_fits}] N = {N}, delta_eta = {deta:g}: stage 1 + stage 2 ...")
            ex = chapter_example(deta, N=N, random_state=args.seed)
            ident = HammersteinBacklashIdentifier(
                BacklashSetEstimator(deta),
                LinearEIVSetEstimator(noise_bound=deta, method=args.method,
                                      relaxation_order=args.order, solver=args.solver,
                                      n_jobs=args.n_jobs, progress=args.progress),
                inner_signal=args.inner_signal,
            )
            t = time.perf_counter()
            ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
            dt = time.perf_counter() - t
            ok = ident.contains(ex.gamma_true, ex.theta_true)
            progress(f"[{k_fit}/{n_fits}] N = {N}, delta_eta = {deta:g}: done in {dt:.1f} s "
                     f"(true parameters inside: {'yes' if ok else 'NO'}; elapsed "
                     f"{progress.elapsed():.1f} s)")
            res1.append((deta, ex.steady.snr_db, ident.gamma_bounds_, ex.gamma_true))
            res2.append((deta, ex.prbs.snr_db, ident.theta_bounds_, ex.theta_true))
            inner_rows.append((deta, ident.u_star_, ident.inner_bounds_, ex.prbs.x))
            failures += int(not ok)
            fitted.append((ex, ident, dt))
        progress(f"N = {N}: {len(levels)} noise level(s) in {time.perf_counter() - t_n:.1f} s")
        if n_idx == 0:
            ch1 = _chapter_rows("22.1")
            doc["stage1"] = {"table": "22.1", "rows": _table_json(("ml", "cl", "mr", "cr"),
                                                                  res1, ch1)}
            doc["inner_signal_bounds"] = [
                {"delta_eta": deta, "u_star": float(us),
                 "x_plus": [float(ib.x_hi[0]), float(ib.x_hi[1])],
                 "x_minus": [float(ib.x_lo[0]), float(ib.x_lo[1])],
                 "x_true_plus": float(x.max()), "x_true_minus": float(x.min())}
                for deta, us, ib, x in inner_rows]
            if text:
                _print_table("Table 22.1 - backlash parameter bounds (stage 1)",
                             ("ml", "cl", "mr", "cr"), res1, ch1)
                print("\nInner-signal bounds (22.25)-(22.30) for the PRBS level u*")
                for deta, us, ib, x in inner_rows:
                    print(f"  delta_eta = {deta:g}: u* = {us:g}, x(+u*) in [{ib.x_hi[0]:.5f}, "
                          f"{ib.x_hi[1]:.5f}], x(-u*) in [{ib.x_lo[0]:.5f}, {ib.x_lo[1]:.5f}] "
                          f"(true {x.max():.5f}, {x.min():.5f})")
            report_fit = min(fitted, key=lambda f: abs(f[0].noise_bound - 0.05))
        table = {100: "22.2", 300: "22.3"}.get(N)
        ch2 = _chapter_rows(table, N) if table else {}
        doc["stage2"].append({
            "N": N, "table": table, "rows": _table_json(("a1", "a2", "b1", "b2"), res2, ch2),
            "time_s": {f"{ex.noise_bound:g}": dt for ex, _, dt in fitted}})
        if text:
            _print_table(f"Table {table or '(N=' + str(N) + ')'} - linear block bounds "
                         f"(stage 2, N = {N})", ("a1", "a2", "b1", "b2"), res2, ch2)
            print(f"\ntime per noise level (N = {N}): "
                  + ", ".join(f"{ex.noise_bound:g}: {dt:.1f} s" for ex, _, dt in fitted),
                  flush=True)
    total = time.perf_counter() - t0
    doc["total_time_s"] = total
    doc["all_true_inside"] = failures == 0
    if text:
        print(f"total {total:.1f} s; true parameters inside every interval: "
              f"{'yes' if failures == 0 else f'NO ({failures} case(s))'}")
        print("Note: the chapter does not state the square-wave amplitudes nor u*; our choices "
              "(amplitudes 0.25..2.5, u* = 1) keep the backlash well posed (below the line "
              "crossing at u = 2.84) and reproduce the chapter's transient SNRs; see "
              "hammerbound.experiments and docs/benchmarks.md.", flush=True)
    doc["report"] = None
    if report_dir is not None:
        from .report import write_report

        ex, ident, _ = report_fit
        progress(f"writing the report (delta_eta = {ex.noise_bound:g}) to {report_dir} ...")
        path = write_report(ident, ex.steady.u, ex.steady.y, ex.prbs.u, ex.prbs.y, report_dir,
                            gamma_true=ex.gamma_true, theta_true=ex.theta_true,
                            title=f"Chapter example, delta_eta = {ex.noise_bound:g}, "
                                  f"N = {ex.prbs.u.size}", overwrite=args.force)
        doc["report"] = str(path)
        print(f"hammerbound demo: report with figures written to {path}", file=sys.stderr)
    if args.json:
        print(json.dumps(doc, indent=2))
    progress(f"done in {progress.elapsed():.1f} s")
    return 0 if failures == 0 else 1


def cmd_identify(args) -> int:
    """Identify from CSV files."""
    from . import BacklashSetEstimator, HammersteinBacklashIdentifier, LinearEIVSetEstimator
    from .io import read_columns
    from .report import REPORT_FILES

    report_dir = (check_output_dir(args.report, REPORT_FILES, force=args.force,
                                   option="--report") if args.report else None)
    ss = read_columns(args.steady, [args.u_column, args.y_column])
    pr = read_columns(args.prbs, [args.u_column, args.y_column])
    ident = HammersteinBacklashIdentifier(
        BacklashSetEstimator(args.steady_noise),
        LinearEIVSetEstimator(na=args.na, nb=args.nb, noise_bound=args.prbs_noise,
                              method=args.method, relaxation_order=args.order,
                              solver=args.solver, n_jobs=args.n_jobs, progress=args.progress),
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


def cmd_benchmark(args) -> int:
    """Quick method comparison on the chapter example (the full suite is in benchmarks/)."""
    from . import HammersteinBacklashIdentifier, LinearEIVSetEstimator
    from .backlash import BacklashSetEstimator
    from .cli_paths import write_output_text
    from .experiments import chapter_example

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
          "'hammerbound benchmark suite list' from the repository root (docs/benchmarks.md).")
    return 0


def _add_stage2_options(p, method="moment"):
    p.add_argument("--method", default=method, choices=["lp", "moment", "exact"],
                   help=f"stage-2 method (default {method})")
    p.add_argument("--order", type=int, default=1, help="moment relaxation order (default 1)")
    p.add_argument("--solver", default="clarabel", help="conic backend for --method moment")
    p.add_argument("--inner-signal", default="independent", choices=["independent", "two-level"])
    p.add_argument("--n-jobs", type=int, default=1, help="parallel bound problems")


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
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--report", default="demo-report", metavar="DIR",
                   help="directory of the Markdown report with figures for delta_eta = 0.05 "
                        f"(default demo-report; '' to skip; an existing report there is "
                        f"kept unless {FORCE_FLAG} is given)")
    p.add_argument("--json", action="store_true",
                   help="print the tables as JSON on stdout (nothing else goes to stdout)")
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no progress lines on stderr")
    p.add_argument("--progress", action="store_true", help="progress bars (exact method)")
    add_force_option(p, "report files")
    _add_stage2_options(p)
    p.set_defaults(func=cmd_demo)

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

    p = sub.add_parser("benchmark", help="quick method comparison (or the full suite)",
                       description="LP vs moment vs exact (independent and two-level) on the "
                                   "chapter example. 'hammerbound benchmark suite NAME "
                                   "[options]' runs the full suite of benchmarks/ (from the "
                                   "repository root; 'suite list' shows the names).")
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
    from . import __version__

    return __version__


def _diagnose(argv) -> int:
    """``hammerbound diagnose``: check ``--plot`` (and take ``--force``) before the work, then
    hand the rest to :func:`hammerbound.discrepancy.diagnose_cli_main`."""
    pre = argparse.ArgumentParser(add_help=False, prog="hammerbound diagnose")
    pre.add_argument("--plot", default=None)
    pre.add_argument(FORCE_FLAG, action="store_true")
    known, rest = pre.parse_known_args(argv)
    if any(a in ("-h", "--help") for a in rest):
        from .discrepancy import diagnose_cli_main

        rc = diagnose_cli_main(rest)
        print(f"\n{FORCE_FLAG}: overwrite an existing --plot file (refused by default)")
        return rc
    if known.plot is not None:
        check_output_file(known.plot, force=known.force, option="--plot")
        rest = [*rest, "--plot", known.plot]
    from .discrepancy import diagnose_cli_main

    return diagnose_cli_main(rest)


def _run_suite(rest) -> int:
    """Forward ``hammerbound benchmark suite ...`` to ``python -m benchmarks ...``."""
    sys.path.insert(0, str(Path.cwd()))
    try:
        import benchmarks.__main__ as suite  # noqa: PLC0415
    except ImportError:
        print("hammerbound benchmark suite: the benchmark suite lives in the repository's "
              "benchmarks/ directory; run this command from the repository root.",
              file=sys.stderr)
        return 2
    finally:
        sys.path.pop(0)
    return int(suite.main(rest) or 0)


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
