"""Stage-1 speed: exact half-plane polygon vs the chapter's Algorithm 22.1.

Steady-state data of the chapter's backlash (M amplitudes per side, uniform noise) are
generated directly from the steady-state map (22.9)-(22.10) (unit DC gain), so that
M = 1e5 does not require simulating 2e5 square-wave transients. Both methods compute the
same exact feasible sets; the script checks that their orthotopes agree.

    python benchmarks/stage1_speed.py            # full (M up to 1e5 polygon, 3000 algorithm)
    python benchmarks/stage1_speed.py --quick    # smaller
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
from hammerbound.systems.experiments import CHAPTER_BACKLASH


def steady_data(M: int, noise: float, seed: int):
    rng = np.random.default_rng(seed)
    amps = np.linspace(0.25, 2.5, M)
    u = np.column_stack([amps, -amps]).ravel()
    b = CHAPTER_BACKLASH
    w = np.where(u > 0, b.mr * (u - b.cr), b.ml * (u + b.cl))
    return u, w + rng.uniform(-noise, noise, u.size)


def best_time(fn, repeats: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--noise", type=float, default=0.05)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if args.quick:
        poly_M = [100, 1000, 10_000, 100_000]
        alg_M = [100, 300, 1000]
    else:
        poly_M = [100, 300, 1000, 3000, 10_000, 30_000, 100_000]
        alg_M = [100, 300, 1000, 3000]
    env = C.environment()
    rows = []
    bounds = {}
    for method, Ms in (("polygon", poly_M), ("algorithm", alg_M)):
        for M in Ms:
            u, y = steady_data(M, args.noise, args.seed)
            reps = args.repeats if not (method == "algorithm" and M > 1000) else 1
            t, est = best_time(
                lambda m=method, u=u, y=y: hb.BacklashSetEstimator(args.noise, method=m).fit(u, y),
                reps)
            gb = est.gamma_bounds_
            bounds[(method, M)] = gb
            g = CHAPTER_BACKLASH.gamma
            inside = bool(np.all((g >= gb[:, 0]) & (g <= gb[:, 1])))
            rows.append({"method": method, "M_per_side": M, "time_s": t, "repeats": reps,
                         "n_vertices_left": len(est.left_.vertices),
                         "n_vertices_right": len(est.right_.vertices),
                         "gamma_inside": inside, "loadavg": C.loadavg()})
            C.log(f"{method:9s} M={M:>6d}  {t:.4f} s  vertices L/R {rows[-1]['n_vertices_left']}/"
                  f"{rows[-1]['n_vertices_right']}  inside={inside}")
    agree = {M: float(np.max(np.abs(bounds[("polygon", M)] - bounds[("algorithm", M)])))
             for M in alg_M if ("polygon", M) in bounds}
    t_poly = {r["M_per_side"]: r["time_s"] for r in rows if r["method"] == "polygon"}
    t_alg = {r["M_per_side"]: r["time_s"] for r in rows if r["method"] == "algorithm"}
    speedup = {M: t_alg[M] / t_poly[M] for M in t_alg if M in t_poly}
    summary = {
        "environment": env, "noise": args.noise, "quick": args.quick,
        "polygon_1e5_s": t_poly.get(100_000),
        "speedup_at_1000": speedup.get(1000),
        "speedup": speedup,
        "max_abs_diff_polygon_vs_algorithm": agree,
        "targets": {
            "polygon_1e5_lt_0.5s": (t_poly.get(100_000) or np.inf) < 0.5,
            "speedup_ge_100_at_M1000": (speedup.get(1000) or 0) >= 100,
        },
        "rows": rows,
    }
    C.write_csv(rows, C.RESULTS / "stage1_speed.csv")
    C.write_json(summary, C.RESULTS / "stage1_speed.json")
    C.log(f"polygon 1e5: {summary['polygon_1e5_s']}, speed-up at M=1000: {summary['speedup_at_1000']}")
    C.log(f"max |polygon - algorithm| orthotope difference: {agree}")

    plt = C.setup_matplotlib()
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for method, mk in (("polygon", "o-"), ("algorithm", "s-")):
        Ms = sorted(t for (m, t) in bounds if m == method)
        ts = [t_poly[M] if method == "polygon" else t_alg[M] for M in Ms]
        ax.loglog(Ms, ts, mk, label={"polygon": "exact polygon (half-plane intersection)",
                                      "algorithm": "Algorithm 22.1 (chapter)"}[method])
    ax.axhline(0.5, color="gray", ls="--", lw=0.8)
    ax.text(poly_M[0], 0.55, "target 0.5 s", color="gray", fontsize=8)
    ax.set_xlabel("M (steady-state samples per side)")
    ax.set_ylabel("wall time of fit (s), best of repeats")
    ax.set_title("Stage 1: exact backlash feasible sets")
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(C.FIGURES / "bench_stage1_speed.png")
    return summary


if __name__ == "__main__":
    main()
