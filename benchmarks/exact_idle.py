"""Exact intervals at N = 300 (and 100) on an otherwise idle machine: the 20 s target.

    python -m benchmarks.exact_idle [--N 300] [--levels ...] [--n-jobs 2] [--repeat 3]

Writes ``results/exact_idle_N{N}.json`` with wall time (median over ``--repeat`` fits, every
fit's time in ``wall_all_s``), node counts and statuses per noise level (independent and
two-level inner signal). Run it when nothing else loads the machine: the load average at
start and end is recorded.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import hammerbound as hb
from benchmarks import _common as C
from hammerbound.systems.experiments import CHAPTER_NOISE_LEVELS


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--N", type=int, default=300)
    p.add_argument("--levels", type=float, nargs="+", default=list(CHAPTER_NOISE_LEVELS))
    p.add_argument("--n-jobs", type=int, default=2)
    p.add_argument("--time-limit", type=float, default=600.0)
    p.add_argument("--inner", nargs="+", default=["independent", "two-level"])
    p.add_argument("--repeat", type=int, default=3, help="fits per level (median reported)")
    args = p.parse_args(argv)
    rows = []
    for inner in args.inner:
        for deta in args.levels:
            ex = hb.chapter_example(deta, N=args.N, random_state=0)
            ident = hb.HammersteinBacklashIdentifier(
                hb.BacklashSetEstimator(deta),
                hb.LinearEIVSetEstimator(output_bound=deta, method="exact", n_jobs=args.n_jobs,
                                         time_limit=args.time_limit),
                inner_signal=inner)
            load0 = C.loadavg()
            walls = []
            for _ in range(max(1, args.repeat)):
                t = time.perf_counter()
                ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
                walls.append(time.perf_counter() - t)
            wall = float(np.median(walls))
            infos = ident.linear_.bound_info_
            row = {"N": args.N, "delta_eta": deta, "inner_signal": inner, "wall_s": wall,
                   "wall_all_s": walls,
                   "nodes": sum(i.nodes or 0 for i in infos),
                   "statuses": sorted({i.status for i in infos}),
                   "max_gap": max(i.gap or 0.0 for i in infos),
                   "true_inside": ident.contains(ex.gamma_true, ex.theta_true),
                   "loadavg_start": load0, "loadavg_end": C.loadavg()}
            rows.append(row)
            print(f"N={args.N} {inner:11s} deta={deta:<6g} {wall:7.1f} s "
                  f"(max {max(walls):.1f}) nodes={row['nodes']:6d} "
                  f"{row['statuses']} inside={row['true_inside']} load={load0}", flush=True)
    C.write_json({"environment": C.environment(), "rows": rows},
                 C.RESULTS / f"exact_idle_N{args.N}.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
