"""Exact intervals on long records: working-set node LPs vs the full LPs (issue 18).

    python -m benchmarks.exact_scaling [--N 300 1000 3000 10000] [--old-max 3000]
                                       [--delta 0.05] [--n-jobs 2]

For every N, the chapter example (independent inner signal) goes through stage 1 and the LP
stage 2 once; the stage-2 EIV problem is then solved by the exact method twice on the same
problem in the same run: with the working set (``working_set=True``, new) and, for
``N <= --old-max``, with the full node LPs (``working_set=False``, old). Reported: wall
time, nodes, node LP sizes (working-set equations out of all), simplex iterations, peak
memory (resident set of the process and its joblib workers, sampled every 50 ms), the
largest width difference between old and new relative to the tolerance, and the growth
exponent of the time fitted over N (least squares on log time vs log N). Writes
``results/exact_scaling.json``. The machine is usually shared: the load average is stored
and the old/new ratio is measured in the same run.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import hammerbound as hb
from benchmarks import _common as C
from hammerbound.relaxations.exact.bnb import exact_bounds


def _problem(N, deta):
    ex = hb.chapter_example(deta, N=N, random_state=0)
    ident = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(deta), hb.LinearEIVSetEstimator(output_bound=deta, method="lp"),
        inner_signal="independent")
    t = time.perf_counter()
    ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    return ident.linear_.problem_, time.perf_counter() - t


def _run(pr, working_set, n_jobs, tol):
    with C.PeakRSS() as mem:
        t = time.perf_counter()
        res = exact_bounds(pr, tol=tol, n_jobs=n_jobs, working_set=working_set)
        wall = time.perf_counter() - t
    infos = res.infos
    return res, {
        "wall_s": wall, "nodes": sum(i.nodes or 0 for i in infos),
        "iterations": sum(i.iterations or 0 for i in infos),
        "statuses": sorted({i.status for i in infos}),
        "max_gap": max(i.gap or 0.0 for i in infos),
        "working_set_equations": res.details.working_set,
        "peak_rss_mb": round(mem.peak, 1), "rss_before_mb": round(mem.base, 1),
    }


def _exponent(ns, ts):
    ns, ts = np.asarray(ns, float), np.asarray(ts, float)
    if ns.size < 2:
        return float("nan")
    return float(np.polyfit(np.log(ns), np.log(ts), 1)[0])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--N", type=int, nargs="+", default=[300, 1000, 3000, 10000])
    p.add_argument("--old-max", type=int, default=3000, help="largest N run with full LPs")
    p.add_argument("--delta", type=float, default=0.05)
    p.add_argument("--n-jobs", type=int, default=2)
    p.add_argument("--tol", type=float, default=1e-4)
    p.add_argument("--merge", action="store_true",
                   help="replace only the rows of these N in results/exact_scaling.json")
    args = p.parse_args(argv)
    rows = []
    out = C.RESULTS / "exact_scaling.json"
    kept = [r for r in C.read_json(out)["rows"] if r["N"] not in args.N] \
        if args.merge and out.exists() else []
    for N in args.N:
        pr, t_lp = _problem(N, args.delta)
        load0 = C.loadavg()
        new, rn = _run(pr, True, args.n_jobs, args.tol)
        row = {"N": N, "equations": int(pr.equation_times.size), "delta_eta": args.delta,
               "n_jobs": args.n_jobs, "lp_fit_s": t_lp, "new": rn}
        if N <= args.old_max:
            old, ro = _run(pr, False, args.n_jobs, args.tol)
            # both are certified outer bounds within tol of verified values: compare the
            # difference with the tolerance of each end
            scale = np.maximum(1.0, np.abs(old.bounds))
            row["old"] = ro
            row["ratio_old_new"] = ro["wall_s"] / rn["wall_s"]
            row["max_bound_diff_over_tol"] = float(
                np.max(np.abs(new.bounds - old.bounds) / (args.tol * scale)))
        row["loadavg_start"], row["loadavg_end"] = load0, C.loadavg()
        rows.append(row)
        old_s = (f" old {row['old']['wall_s']:6.1f} s ({row['old']['nodes']} nodes, "
                 f"{row['old']['peak_rss_mb']:.0f} MB) ratio {row['ratio_old_new']:.1f}x "
                 f"diff/tol {row['max_bound_diff_over_tol']:.2f}" if "old" in row else "")
        print(f"N={N:6d} new {rn['wall_s']:6.1f} s ({rn['nodes']} nodes, "
              f"{rn['working_set_equations']}/{row['equations']} eqs, "
              f"{rn['peak_rss_mb']:.0f} MB){old_s} load={load0}", flush=True)
    rows = sorted(kept + rows, key=lambda r: r["N"])
    fit = {"new": _exponent([r["N"] for r in rows], [r["new"]["wall_s"] for r in rows])}
    olds = [r for r in rows if "old" in r]
    fit["old"] = _exponent([r["N"] for r in olds], [r["old"]["wall_s"] for r in olds])
    print(f"growth exponent of the time in N: new {fit['new']:.2f}, old {fit['old']:.2f}")
    C.write_json({"environment": C.environment(), "rows": rows, "exponent": fit}, out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
