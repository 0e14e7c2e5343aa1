"""``hammerbound benchmark``: a quick method comparison on the chapter example (the full
suite is ``python -m benchmarks`` in the repository, not installed)."""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from ..paths import FORCE_FLAG, add_force_option, check_output_file
from .console import Progress
from .options import deprecated

__all__ = ["add_parser", "run", "run_suite"]

CONFIGS = [("lp", 1, "independent"), ("moment", 1, "independent"),
           ("exact", 1, "independent"), ("exact", 1, "two-level")]


def add_parser(sub):
    p = sub.add_parser("benchmark", help="quick method comparison on the chapter example",
                       description="LP vs moment vs exact (independent and two-level) on the "
                                   "chapter example. The full suite is not installed: run "
                                   "'python -m benchmarks list' from the repository root.")
    p.add_argument("--N", type=int, default=100)
    p.add_argument("--output-bound", type=float, default=0.05, metavar="BOUND",
                   help="output error bound of the simulated chapter example, delta_eta "
                        "(default 0.05; the noise is drawn within it)")
    deprecated(p, "--noise-bound", "--output-bound", "output_bound", type=float)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--n-jobs", type=int, default=1)
    p.add_argument("--output", default=None,
                   help=f"write JSON results to this file (checked before the run; an "
                        f"existing file is kept unless {FORCE_FLAG} is given)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress lines on stderr")
    add_force_option(p)
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    from ...hammerstein.identifier import HammersteinBacklashIdentifier
    from ...stage1.estimator import BacklashSetEstimator
    from ...stage2.estimator import LinearEIVSetEstimator
    from ...systems.experiments import chapter_example
    from ..paths import write_output_text

    output = (check_output_file(args.output, force=args.force, option="--output")
              if args.output else None)
    bound = args.output_bound
    ex = chapter_example(bound, N=args.N, random_state=args.seed)
    rows = []
    progress = Progress(not args.quiet, prefix="hammerbound benchmark")
    for k, (method, order, inner) in enumerate(CONFIGS, start=1):
        progress(f"[{k}/{len(CONFIGS)}] {method} ({inner}) ...")
        ident = HammersteinBacklashIdentifier(
            BacklashSetEstimator(bound),
            LinearEIVSetEstimator(output_bound=bound, method=method, relaxation_order=order,
                                  n_jobs=args.n_jobs),
            inner_signal=inner)
        t = time.perf_counter()
        ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
        rows.append({"method": method, "order": order, "inner_signal": inner,
                     "time_s": time.perf_counter() - t,
                     "width": (ident.theta_bounds_[:, 1] - ident.theta_bounds_[:, 0]).tolist(),
                     "true_inside": ident.contains(ex.gamma_true, ex.theta_true)})
        progress(f"[{k}/{len(CONFIGS)}] {method} ({inner}): done in {rows[-1]['time_s']:.1f} s")
    _print_table(rows, bound, args.N)
    if output is not None:
        write_output_text(output, json.dumps(rows, indent=2), force=args.force,
                          option="--output")
        print(f"hammerbound benchmark: results written to {output}", file=sys.stderr)
    print("The full benchmark suite (chapter tables, scaling, Monte Carlo coverage): "
          "'python -m benchmarks list' from the repository root (docs/benchmarks.md).")
    return 0


def _print_table(rows, bound, n):
    exact_w = np.array(rows[2]["width"])
    print(f"chapter example, delta_eta = {bound:g}, N = {n}")
    print(f"{'method':28s} {'time [s]':>9s}  width / exact width (a1 a2 b1 b2)   true inside")
    for r in rows:
        ratio = " ".join(f"{w / e:5.2f}" for w, e in zip(r["width"], exact_w, strict=True))
        order = f" d={r['order']}" if r["method"] == "moment" else ""
        name = f"{r['method']}{order} ({r['inner_signal']})"
        print(f"{name:28s} {r['time_s']:9.2f}  {ratio}              {r['true_inside']}")


def run_suite(rest) -> int:
    """``hammerbound benchmark suite ...`` (removed in 0.2.0): the suite is not installed with
    the package; say where it is instead of importing it from the working directory."""
    cmd = " ".join(["python -m benchmarks", *rest]).strip()
    print("hammerbound benchmark suite: the full benchmark suite lives in the repository's "
          f"benchmarks/ folder and is not installed; from the repository root run: {cmd}",
          file=sys.stderr)
    return 2
