"""``hammerbound demo``: the chapter's example end to end (section 22.5)."""

from __future__ import annotations

import contextlib
import sys

from ..paths import FORCE_FLAG, add_force_option, check_output_dir, check_output_file
from .console import Progress, cli_terms
from .options import add_stage2_options, deprecated, progress_wanted, total_budget

__all__ = ["add_parser", "run"]


def add_parser(sub):
    p = sub.add_parser("demo", help="the chapter's example end to end",
                       description="Run stages 1 and 2 on the chapter's simulated example and "
                                   "print Tables 22.1-22.3 beside the chapter's numbers.")
    p.add_argument("--N", type=int, nargs="+", default=[100, 300],
                   help="PRBS length(s) (default: the chapter's 100 and 300)")
    p.add_argument("--output-bounds", type=float, nargs="+", default=None,
                   metavar="BOUND",
                   help="output error bounds of the simulated records, the chapter's delta_eta "
                        "(default: the chapter's six)")
    deprecated(p, "--noise-levels", "--output-bounds", "output_bounds", type=float,
               nargs="+")
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
    add_force_option(p, "report files")
    add_stage2_options(p, method="exact", inner_signal=True, theta_box=False)
    p.set_defaults(func=run, n_jobs=2)
    return p


def run(args) -> int:
    """Tables 22.1-22.3 over several noise draws beside the chapter's numbers
    (:func:`hammerbound.app.chapter.run_demo`)."""
    from ...systems.experiments import CHAPTER_NOISE_LEVELS
    from ..chapter import DEMO_SEEDS, run_demo
    from ..chapter_output import records_json, stdout_to_stderr
    from ..paths import write_output_text
    from ..report import REPORT_FILES

    # every output is checked before the (minutes long) computation
    report_dir = (check_output_dir(args.report, REPORT_FILES, force=args.force,
                                   option="--report",
                                   hint="choose another directory (--report DIR; --report '' "
                                        "for no report)")
                  if args.report else None)
    json_stdout = args.json == "-"
    json_path = (check_output_file(args.json, force=args.force, option="--json")
                 if args.json and not json_stdout else None)
    levels = (CHAPTER_NOISE_LEVELS if args.output_bounds is None
              else tuple(args.output_bounds))
    seeds = args.seeds if args.seeds is not None else (
        [args.seed] if args.seed is not None else list(DEMO_SEEDS))
    progress = Progress(not args.quiet)
    # with JSON on stdout, nothing else goes there (a C library's banner included)
    with stdout_to_stderr() if json_stdout else contextlib.nullcontext():
        records = run_demo(args.stage1, tuple(args.N), levels, seeds, args.method,
                           inner_signal=args.inner_signal, relaxation_order=args.order,
                           solver=args.solver, n_jobs=args.n_jobs, progress=progress,
                           linear_options={"progress": progress_wanted(args) and not args.quiet,
                                           "time_limit": args.time_limit,
                                           "total_time_limit": total_budget(args),
                                           "max_nodes": args.max_nodes},
                           file=False if json_stdout else sys.stdout)
        if report_dir is not None:
            _report(args, levels, seeds, report_dir, progress)
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


def _report(args, levels, seeds, report_dir, progress):
    from ..chapter import fit_example
    from ..report import write_report

    deta = min(levels, key=lambda d: abs(d - 0.05))
    progress(f"writing the report (delta_eta = {deta:g}, N = {args.N[0]}, seed "
             f"{seeds[0]}, our stage 1) to {report_dir} ...")
    ex, ident = fit_example(deta, args.N[0], seeds[0], args.method,
                            inner_signal=args.inner_signal, relaxation_order=args.order,
                            solver=args.solver, n_jobs=args.n_jobs)
    path = write_report(ident, ex.steady.u, ex.steady.y, ex.prbs.u, ex.prbs.y, report_dir,
                        gamma_true=ex.gamma_true, theta_true=ex.theta_true,
                        overwrite=args.force, terms=cli_terms,
                        title=f"Chapter example, delta_eta = {deta:g}, N = {args.N[0]}, "
                              f"seed {seeds[0]}")
    print(f"hammerbound demo: report with figures written to {path}", file=sys.stderr)
