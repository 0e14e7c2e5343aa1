"""Monte Carlo coverage: seeds x noise levels x methods; fraction of runs whose intervals
contain the true theta (and gamma), and width statistics.

The runs are independent joblib tasks, so the same script scales from a laptop to a Dask
cluster: ``--dask`` starts a local ``dask.distributed.LocalCluster`` and runs the tasks under
``joblib.parallel_config(backend="dask")``; ``--scheduler tcp://host:8786`` uses an existing
cluster instead.

    python benchmarks/coverage.py                         # joblib (loky), default grid
    python benchmarks/coverage.py --dask --n-jobs 2       # same on a local Dask cluster
    python benchmarks/coverage.py --quick --dask          # small demo
    python benchmarks/coverage.py --methods lp:200,moment1:20,exact:5 --levels 0.005 0.05 0.3

``--methods`` takes ``label:seeds`` pairs (labels as in ``_common.METHODS``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

from hammerbound.systems.experiments import CHAPTER_NOISE_LEVELS

DEFAULT_METHODS = "lp:100,moment1:3,exact-2level:2"
QUICK_METHODS = "lp:10,lp-2level:10,moment1:2"


def one_run(method: str, noise: float, seed: int, N: int) -> dict:
    """One Monte Carlo run (executed in a joblib / Dask worker)."""
    import hammerbound as hb

    ex = hb.chapter_example(noise, N=N, random_state=seed)
    row = {"method": method, "noise": noise, "seed": seed, "N": N, "snr_prbs_db": ex.prbs.snr_db,
           "worker_pid": os.getpid()}
    try:
        r = C.run_method(ex, method, n_jobs=1, time_limit=300.0)
    except Exception as exc:  # keep going; an error is reported, never counted as covered
        row.update({"error": f"{type(exc).__name__}: {exc}"[:300], "theta_inside": None,
                    "gamma_inside": None})
        return row
    row.update({k: r[k] for k in ("wall_s", "theta_inside", "gamma_inside", "theta_width",
                                  "theta_lower", "theta_upper", "gamma_lower", "gamma_upper",
                                  "all_certified", "statuses")})
    row["error"] = ""
    return row


def summarise(rows):
    out = []
    for m in sorted({r["method"] for r in rows}):
        for lvl in sorted({r["noise"] for r in rows}):
            rr = [r for r in rows if r["method"] == m and r["noise"] == lvl]
            if not rr:
                continue
            ok = [r for r in rr if not r["error"]]
            W = np.array([r["theta_width"] for r in ok]) if ok else np.full((1, 4), np.nan)
            s = {"method": m, "noise": lvl, "runs": len(rr), "errors": len(rr) - len(ok),
                 "theta_coverage": np.mean([bool(r["theta_inside"]) for r in ok]) if ok else np.nan,
                 "gamma_coverage": np.mean([bool(r["gamma_inside"]) for r in ok]) if ok else np.nan,
                 "theta_misses": int(sum(not r["theta_inside"] for r in ok)),
                 "snr_prbs_db_mean": float(np.mean([r["snr_prbs_db"] for r in rr])),
                 "wall_s_median": float(np.median([r["wall_s"] for r in ok])) if ok else np.nan}
            for j, p in enumerate(C.THETA_NAMES):
                s[f"width_{p}_mean"] = float(np.mean(W[:, j]))
                s[f"width_{p}_median"] = float(np.median(W[:, j]))
                s[f"width_{p}_max"] = float(np.max(W[:, j]))
            out.append(s)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--methods", default=None, help=f"label:seeds,... (default {DEFAULT_METHODS})")
    ap.add_argument("--levels", type=float, nargs="+", default=None,
                    help="noise bounds (default: the chapter's six)")
    ap.add_argument("--N", type=int, default=100)
    ap.add_argument("--n-jobs", type=int, default=2)
    ap.add_argument("--dask", action="store_true", help="start a local dask.distributed cluster")
    ap.add_argument("--scheduler", default=None, help="address of an existing Dask scheduler")
    ap.add_argument("--tag", default=None, help="suffix of the result files")
    ap.add_argument("--replot", action="store_true", help="only redraw the figure of --tag")
    args = ap.parse_args(argv)
    if args.replot:
        import csv

        with open(C.RESULTS / f"coverage_runs_{args.tag}.csv") as fh:
            rows = [dict(r, noise=float(r["noise"]),
                         theta_width=[float(v) for v in r["theta_width"].split(";") if v])
                    for r in csv.DictReader(fh)]
        plot(rows, args.tag)
        return None
    spec = args.methods or (QUICK_METHODS if args.quick else DEFAULT_METHODS)
    levels = args.levels or ([0.005, 0.05, 0.2] if args.quick else list(CHAPTER_NOISE_LEVELS))
    plan = [(m, int(k)) for m, k in (item.split(":") for item in spec.split(","))]
    tasks = [(m, lvl, s, args.N) for m, k in plan for lvl in levels for s in range(k)]
    backend = "dask" if (args.dask or args.scheduler) else "loky"
    tag = args.tag or (backend + ("-quick" if args.quick else ""))
    # workers (loky or Dask processes) must import benchmarks/_common.py
    os.environ["PYTHONPATH"] = os.pathsep.join(
        [str(C.HERE), str(C.ROOT)] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else []))
    sys.path[:0] = [str(C.HERE), str(C.ROOT)]
    env = C.environment()
    C.log(f"{len(tasks)} runs ({spec}; levels {levels}; N = {args.N}) on backend {backend}")

    import joblib

    t0 = time.perf_counter()
    client = cluster = None
    dask_info = None
    if backend == "dask":
        from dask.distributed import Client, LocalCluster

        if args.scheduler:
            client = Client(args.scheduler)
        else:
            cluster = LocalCluster(n_workers=args.n_jobs, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        dask_info = {"scheduler": client.scheduler.address,
                     "workers": len(client.scheduler_info()["workers"])}
        C.log(f"Dask client {client} ({dask_info})")
        with joblib.parallel_config(backend="dask"):
            rows = joblib.Parallel(verbose=0)(joblib.delayed(one_run)(*t) for t in tasks)
    else:
        rows = joblib.Parallel(n_jobs=args.n_jobs)(joblib.delayed(one_run)(*t) for t in tasks)
    elapsed = time.perf_counter() - t0
    if client is not None:
        client.close()
    if cluster is not None:
        cluster.close()
    summary = summarise(rows)
    n_pids = len({r["worker_pid"] for r in rows})
    C.log(f"{len(rows)} runs in {elapsed:.1f} s on {n_pids} worker processes")
    for s in summary:
        C.log(f"{s['method']:15s} deta={s['noise']:<6} runs={s['runs']:4d} theta coverage "
              f"{100 * s['theta_coverage']:.1f}%  gamma coverage {100 * s['gamma_coverage']:.1f}%  "
              f"errors {s['errors']}  median width b1 {s['width_b1_median']:.4f}")
    misses = [r for r in rows if r.get("theta_inside") is False or r.get("gamma_inside") is False]
    if misses:
        C.log(f"!!! SOUNDNESS: {len(misses)} runs with the true parameter outside an interval: "
              f"{[(r['method'], r['noise'], r['seed']) for r in misses][:20]}")
    C.write_csv(rows, C.RESULTS / f"coverage_runs_{tag}.csv")
    C.write_csv(summary, C.RESULTS / f"coverage_summary_{tag}.csv")
    C.write_json({"environment": env, "backend": backend, "dask": dask_info, "spec": spec,
                  "levels": levels, "N": args.N, "elapsed_s": elapsed, "n_worker_processes": n_pids,
                  "summary": summary, "misses": misses}, C.RESULTS / f"coverage_{tag}.json")
    if not args.quick:
        plot(rows, tag)
    return summary


def plot(rows, tag):
    plt = C.setup_matplotlib()
    methods = sorted({r["method"] for r in rows})
    levels = sorted({r["noise"] for r in rows})
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    for k, m in enumerate(methods):
        for j, (p, ax) in enumerate(zip(("a1", "b1"), axes, strict=True)):
            idx = C.THETA_NAMES.index(p)
            data = [[r["theta_width"][idx] for r in rows if r["method"] == m and r["noise"] == lvl
                     and not r["error"]] for lvl in levels]
            pos = np.arange(len(levels)) + (k - (len(methods) - 1) / 2) * 0.8 / len(methods)
            if max(len(d) for d in data) >= 10:
                bp = ax.boxplot(data, positions=pos, widths=0.7 / len(methods), patch_artist=True,
                                showfliers=False, manage_ticks=False,
                                medianprops={"color": "black"})
                for b in bp["boxes"]:
                    b.set_facecolor(f"C{k}")
                    b.set_alpha(0.6)
            else:  # few runs: show every run
                for x, d in zip(pos, data, strict=True):
                    ax.plot([x] * len(d), d, "o", color=f"C{k}", ms=4)
            if j == 0:
                ax.plot([], [], "s", color=f"C{k}", label=m)
    for p, ax in zip(("a1", "b1"), axes, strict=True):
        ax.set_yscale("log")
        ax.set_xticks(range(len(levels)))
        ax.set_xticklabels([str(v) for v in levels])
        ax.set_xlabel(r"$\Delta\eta$")
        ax.set_ylabel(f"width of the {p} interval")
        ax.set_title(f"{p}: width over Monte Carlo runs")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(C.FIGURES / f"bench_coverage_{tag}.png")
    plt.close(fig)


if __name__ == "__main__":
    main()
