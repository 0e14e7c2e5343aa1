"""Order-2 moment relaxation (delta = 2) at the chapter's size: size, time and tightness.

For the chapter example (Delta eta = 0.05, seed 0, stage 1 exact) and N = 10, 20, 50, 100
this runs, on the *same* stage-2 problem as the estimator builds it (LP box as a priori
box and fallback):

* ``moment_bounds(order=2, basis="sparse")`` (the default) with ``n_jobs`` workers;
* ``moment_bounds(order=2, basis="full")`` (the relaxation before issue 15) at the N of
  ``--full-N`` only (10 by default: it takes minutes there);
* ``exact_bounds(tol=1e-6)`` as reference.

Reported per run: conic size (moment variables, rows, PSD blocks by side, nonzeros of A),
build time, wall time, solver time per bound and iterations, peak resident memory of the
process and its workers (sampled every 50 ms), certification, and the signed
difference per interval end relative to the exact width (positive = the moment bound lies
inside the exact outer bound, which is possible up to the exact method's tolerance).
The machine is shared: timings are under load (load average stored per row).

    python -m benchmarks moment2 [--N 10 20 50 100] [--full-N 10] [--n-jobs 2]
    python -m benchmarks moment2 --N 300 --full-N --append   # the chapter's size, added
"""

from __future__ import annotations

import argparse
import time

import numpy as np

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

import hammerbound as hb
from hammerbound.relaxations.exact.bnb import exact_bounds
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.moment.relaxation import moment_bounds
from hammerbound.relaxations.moment.size import estimate_moment_relaxation

OUT = C.RESULTS / "moment_order2.json"


def stage2_problem(N: int, noise: float, seed: int):
    """The stage-2 EIV problem of the chapter example, as the estimator builds it."""
    ex = hb.chapter_example(noise, N=N, random_state=seed)
    lin = hb.LinearEIVSetEstimator(na=2, nb=2, output_bound=noise, method="lp")
    idf = hb.HammersteinBacklashIdentifier(backlash=hb.BacklashSetEstimator(noise), linear=lin)
    idf.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    pr = idf.linear_.problem_
    return pr, np.asarray(ex.theta_true, dtype=float)


def run_moment(pr, lp, basis, n_jobs):
    with C.PeakRSS() as mem:
        t0 = time.perf_counter()
        res = moment_bounds(pr, order=2, theta_box=lp.bounds, fallback=lp.bounds,
                            n_jobs=n_jobs, max_work=float("inf"), basis=basis)
        wall = time.perf_counter() - t0
    e = res.details
    return {
        "basis": basis, "wall_s": wall, "build_s": e.build_time,
        "solve_sum_s": float(sum(i.time for i in res.infos)),
        "solve_max_s": float(max(i.time for i in res.infos)),
        "iterations": [i.iterations for i in res.infos],
        "statuses": [i.status for i in res.infos],
        "certified": [bool(i.certified) for i in res.infos],
        "n_moments": e.n_moments, "n_rows": e.n_rows, "nnz": e.nnz,
        "n_psd_blocks": e.n_psd_blocks,
        "psd_sides": {str(k): v for k, v in e.psd_sides.items()},
        "bounds": res.bounds.tolist(), "loadavg": C.loadavg(),
        "peak_rss_mb": round(mem.peak, 1), "rss_before_mb": round(mem.base, 1),
    }


def rel_diff(bounds, exact):
    """Signed (moment - exact) / exact width per end, positive = inside the exact bound."""
    b, x = np.asarray(bounds), np.asarray(exact)
    w = x[:, 1] - x[:, 0]
    return np.stack([(b[:, 0] - x[:, 0]) / w, (x[:, 1] - b[:, 1]) / w], axis=1).tolist()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--N", type=int, nargs="+", default=[10, 20, 50, 100])
    ap.add_argument("--full-N", type=int, nargs="*", default=[10])
    ap.add_argument("--noise", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--n-jobs", type=int, default=2)
    ap.add_argument("--append", action="store_true",
                    help="keep the stored rows of other N (and bases) and add these")
    args = ap.parse_args(argv)
    old = C.read_json(OUT) if args.append and OUT.exists() else None
    rows = [r for r in (old or {}).get("rows", []) if r["N"] not in args.N]
    for N in args.N:
        pr, theta = stage2_problem(N, args.noise, args.seed)
        lp = lp_bounds(pr, check_box=False)
        t0 = time.perf_counter()
        ex = exact_bounds(pr, tol=1e-6, check_box=False, n_jobs=args.n_jobs)
        t_ex = time.perf_counter() - t0
        C.log(f"N={N} exact {t_ex:.1f} s")
        for basis in ["sparse"] + (["full"] if N in args.full_N else []):
            est = estimate_moment_relaxation(pr, 2, lp.bounds, basis=basis)
            r = run_moment(pr, lp, basis, args.n_jobs)
            r.update(N=N, noise=args.noise, seed=args.seed, exact_s=t_ex,
                     run_at=time.strftime("%Y-%m-%d %H:%M:%S"),
                     exact_bounds=ex.bounds.tolist(),
                     exact_status=[i.status for i in ex.infos],
                     rel_diff=rel_diff(r["bounds"], ex.bounds),
                     truth_inside=bool(np.all((theta >= np.asarray(r["bounds"])[:, 0])
                                              & (theta <= np.asarray(r["bounds"])[:, 1]))),
                     est_rows=est.n_rows, est_moments=est.n_moments)
            d = np.abs(np.asarray(r["rel_diff"]))
            C.log(f"N={N} {basis:6s} wall {r['wall_s']:7.1f} s (build {r['build_s']:.1f} s) "
                  f"moments {r['n_moments']} rows {r['n_rows']} nnz {r['nnz']} "
                  f"blocks {r['psd_sides']} max|rel diff| {d.max():.2e} "
                  f"certified {all(r['certified'])} inside {r['truth_inside']}")
            rows.append(r)
            C.write_json({"environment": C.environment(), "args": vars(args), "rows": rows},
                         OUT)
    C.write_json({"environment": C.environment(), "args": vars(args), "rows": rows}, OUT)
    return rows


if __name__ == "__main__":
    main()
