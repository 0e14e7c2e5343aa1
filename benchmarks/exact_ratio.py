"""The exact method's cost in units of the LP method's (issue 28): exact / LP time per
(N, Delta eta), two-level vs independent inner signal, and peak memory per row.

    python -m benchmarks.exact_ratio [--N 300 1000 3000] [--levels 0.005 0.05 0.3]
                                     [--repeat 2] [--n-jobs 1] [--tag after]
                                     [--reference results/exact_ratio_before.json]

For every (inner signal, N, Delta eta) the chapter example (seed 0) goes through stage 1
and the LP stage 2 once; on that stage-2 EIV problem, in the same run and ``--repeat``
times, ``lp_bounds`` and ``exact_bounds`` (``n_jobs`` jobs) are timed back to back. The
ratio exact / LP (median of 5 LP runs) is taken per repetition (CPU time of this process with one job, which a
shared machine's load disturbs less than wall time; wall time with more jobs) and the
smallest and largest are kept. The two-level rows also give the two-level / independent
ratio of the exact times at the same (N, Delta eta). Peak memory per row: the peak resident
set of the process and its joblib workers together, sampled every 50 ms during the exact
runs (``tracemalloc`` is not used: it slows the search 3x), and the lifetime peaks of
the process and of its largest finished child (``getrusage``). With ``--reference`` (an earlier result
file of this script, e.g. made by the code before a change) every bound is compared with
the reference's: ``diff/tol`` is the largest difference divided by the tolerance
``1e-4 * max(1, |bound|)`` of that end (must stay <= 1: a speed-up changes no bound beyond
the tolerance). Writes ``results/exact_ratio[_tag].json``. Timings are never asserted in
tests.
"""

from __future__ import annotations

import argparse
import resource
import time

import numpy as np

from benchmarks import _common as C
from hammerbound.relaxations import exact_bounds, lp_bounds

TOL = 1e-4


def _timed(fn):
    """``(result, cpu seconds of this process, wall seconds)`` of ``fn()``."""
    c, w = time.process_time(), time.perf_counter()
    res = fn()
    return res, time.process_time() - c, time.perf_counter() - w


def _row(problem, n_jobs, repeat):
    """Time LP and exact ``repeat`` times on ``problem``; memory of the first exact run."""
    reps, peaks = [], []
    for _ in range(repeat):
        # the LP takes 0.01-0.4 s: its median over 5 runs is the denominator
        lp = [_timed(lambda: lp_bounds(problem, check_box=False))[1:] for _ in range(5)]
        lp_cpu, lp_wall = (float(np.median(v)) for v in zip(*lp, strict=True))
        with C.PeakRSS() as m:
            res, ex_cpu, ex_wall = _timed(
                lambda: exact_bounds(problem, tol=TOL, n_jobs=n_jobs, check_box=False))
        peaks.append((m.peak, m.base))
        reps.append({"lp_cpu_s": lp_cpu, "lp_wall_s": lp_wall, "exact_cpu_s": ex_cpu,
                     "exact_wall_s": ex_wall})
    key = "cpu" if n_jobs == 1 else "wall"
    ratios = [r[f"exact_{key}_s"] / max(r[f"lp_{key}_s"], 1e-9) for r in reps]
    return res, {
        "repeats": reps, "ratio_basis": key, "ratio_min": min(ratios),
        "ratio_max": max(ratios), "nodes": int(sum(i.nodes or 0 for i in res.infos)),
        "nodes_per_end": [int(i.nodes or 0) for i in res.infos],
        "statuses": sorted({i.status for i in res.infos}),
        "working_set": res.details.working_set,
        "peak_rss_mb": max(v[0] for v in peaks), "rss_before_mb": peaks[0][1],
        "maxrss_self_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "maxrss_children_mb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024,
        "bounds": np.asarray(res.bounds).tolist()}


def _compare(row, ref_rows):
    """Largest bound difference to the reference row (same inner, N, Delta eta) / tol."""
    for r in ref_rows:
        if (r["inner_signal"], r["N"], r["delta_eta"]) == \
                (row["inner_signal"], row["N"], row["delta_eta"]):
            a, b = np.asarray(row["bounds"]), np.asarray(r["bounds"])
            return float(np.max(np.abs(a - b) / (TOL * np.maximum(1.0, np.abs(b)))))
    return None


def _plan(args):
    plan = [("independent", N, d) for N in args.N for d in args.levels]
    plan += [("two-level", N, d) for N in args.two_level_N for d in args.levels
             if N in args.N or args.two_level_all]
    plan += [("two-level", N, d) for N, d in args.two_level_extra]
    return list(dict.fromkeys(plan))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--N", type=int, nargs="+", default=[300, 1000, 3000])
    p.add_argument("--levels", type=float, nargs="+", default=[0.005, 0.05, 0.3])
    p.add_argument("--two-level-N", type=int, nargs="+", default=[300],
                   help="N of the two-level rows (every level)")
    p.add_argument("--two-level-all", action="store_true",
                   help="two-level rows also for N not in --N")
    p.add_argument("--two-level-extra", type=lambda s: tuple(float(v) for v in s.split(":")),
                   nargs="*", default=[(3000, 0.3)], metavar="N:LEVEL",
                   help="further two-level rows (default 3000:0.3)")
    p.add_argument("--repeat", type=int, default=2)
    p.add_argument("--n-jobs", type=int, default=1)
    p.add_argument("--tag", default="")
    p.add_argument("--reference", default=None, help="earlier result file to compare bounds with")
    args = p.parse_args(argv)
    args.two_level_extra = [(int(n), d) for n, d in args.two_level_extra]
    ref = C.read_json(args.reference)["rows"] if args.reference else []
    rows = []
    name = f"exact_ratio{'_' + args.tag if args.tag else ''}.json"
    for inner, N, deta in _plan(args):
        problem = C.chapter_stage2_problem(deta, N, inner)
        load0 = C.loadavg()
        _, row = _row(problem, args.n_jobs, args.repeat)
        row = {"inner_signal": inner, "N": N, "delta_eta": deta, "n_jobs": args.n_jobs,
               "loadavg_start": load0, **row}
        row["diff_over_tol"] = _compare(row, ref)
        ind = [r for r in rows if r["inner_signal"] == "independent" and r["N"] == N
               and r["delta_eta"] == deta]
        if inner == "two-level" and ind:
            key = f"exact_{row['ratio_basis']}_s"
            row["two_level_over_independent"] = float(
                min(r[key] for r in row["repeats"]) / min(r[key] for r in ind[0]["repeats"]))
        rows.append(row)
        best = min(r[f"exact_{row['ratio_basis']}_s"] for r in row["repeats"])
        C.log(f"{inner:11s} N={N:<5d} deta={deta:<6g} exact {best:7.2f} s "
              f"({row['ratio_basis']}) exact/LP {row['ratio_min']:6.1f}-{row['ratio_max']:6.1f} "
              f"nodes {row['nodes']:5d} peak {row['peak_rss_mb']:.0f} MB "
              f"diff/tol {row['diff_over_tol']} 2lvl/ind {row.get('two_level_over_independent')} "
              f"load {load0}")
        C.write_json({"environment": C.environment(), "reference": args.reference,
                      "rows": rows}, C.RESULTS / name)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
