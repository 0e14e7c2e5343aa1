"""Method comparison on the same data: LP, moment delta=1/2 (per backend), exact, two-level.

Parts (each writes its own results file, so they can be run separately):

``same``    N = 100, one noise level: every method on the same data set (delta = 2 excluded:
            too expensive at N = 100, see part ``delta2``).
``delta2``  small N (10, 20[, 30]): LP, delta = 1, delta = 2, exact on the same data, so
            that the width ratio delta=2 / exact and the cost growth of delta = 2 are measured.
``scaling`` N = 50 ... 1000: time, width, iterations against N.
``order``   model order n = na = nb = 1 ... 4 (systems with the chapter's backlash).

    python benchmarks/methods.py                 # all parts, full configuration
    python benchmarks/methods.py --quick         # smaller grids
    python benchmarks/methods.py --part delta2   # one part
"""

from __future__ import annotations

import argparse

import numpy as np

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

import hammerbound as hb
from hammerbound.systems.experiments import (
    CHAPTER_AMPLITUDES,
    CHAPTER_BACKLASH,
    CHAPTER_U_STAR,
    ChapterExample,
    prbs_experiment,
    square_wave_experiment,
)
from hammerbound.systems.models import HammersteinSystem

PARTS = ("same", "delta2", "scaling", "order")


def _record(ex, label, n_jobs, extra, time_limit=300.0, **kw):
    try:
        r = C.run_method(ex, label, n_jobs=n_jobs, time_limit=time_limit, **kw)
        r["error"] = ""
    except Exception as exc:  # a failure is a result too
        r = {"method": label, "error": f"{type(exc).__name__}: {exc}"[:300]}
    r.update(extra)
    msg = (f"{label:15s} {extra}  wall {r.get('wall_s', float('nan')):8.2f} s  "
           f"widths {np.round(r.get('theta_width', []), 4).tolist()}  inside={r.get('theta_inside')}"
           f"  {r['error']}")
    C.log(msg)
    if r.get("theta_inside") is False or r.get("gamma_inside") is False:
        C.log("!!! SOUNDNESS: true parameter outside an interval !!!")
    return r


def add_ratios(rows, keys):
    """width / exact width for rows sharing the same values of ``keys``."""
    for r in rows:
        ref = [q for q in rows if q["method"] == "exact" and all(q.get(k) == r.get(k) for k in keys)
               and "theta_width" in q]
        if ref and "theta_width" in r:
            r["width_over_exact"] = (np.array(r["theta_width"]) / np.array(ref[0]["theta_width"])).tolist()
        ref2 = [q for q in rows if q["method"] == "exact-2level" and all(q.get(k) == r.get(k) for k in keys)
                and "theta_width" in q]
        if ref2 and "theta_width" in r and r["method"].endswith("2level"):
            r["width_over_exact2level"] = (
                np.array(r["theta_width"]) / np.array(ref2[0]["theta_width"])).tolist()


def part_same(args):
    ex = hb.chapter_example(args.noise, N=100, random_state=args.seed)
    labels = ["lp", "moment1", "moment1-cvxopt", "exact", "lp-2level", "moment1-2level", "exact-2level"]
    extra = {"N": 100, "noise": args.noise, "seed": args.seed, "snr_prbs_db": ex.prbs.snr_db}
    rows = [_record(ex, m, args.n_jobs, extra) for m in labels]
    add_ratios(rows, ["N"])
    return rows


def _checkpoint(part, rows, args):
    C.write_json({"environment": C.environment(), "quick": args.quick, "args": vars(args),
                  "partial": True, "rows": rows}, C.RESULTS / f"methods_{part}.json")


def part_delta2(args):
    Ns = args.delta2_N or ([10, 20] if args.quick else [10, 20, 30])
    rows = []
    for N in Ns:
        ex = hb.chapter_example(args.noise, N=N, random_state=args.seed)
        extra = {"N": N, "noise": args.noise, "seed": args.seed, "snr_prbs_db": ex.prbs.snr_db}
        labels = ["lp", "moment1", "exact", "moment2"]
        if args.cvxopt2 and N == Ns[0]:
            labels.append("moment2-cvxopt")
        for m in labels:
            rows.append(_record(ex, m, args.n_jobs, extra, time_limit=900.0))
            _checkpoint("delta2", rows, args)
    add_ratios(rows, ["N"])
    return rows


def part_scaling(args):
    Ns = args.scaling_N or ([50, 100, 200, 300] if args.quick else [50, 100, 200, 300, 500, 1000])
    rows = []
    for N in Ns:
        ex = hb.chapter_example(args.noise, N=N, random_state=args.seed)
        extra = {"N": N, "noise": args.noise, "seed": args.seed, "snr_prbs_db": ex.prbs.snr_db}
        for m in ["lp", "moment1", "exact", "lp-2level", "exact-2level"]:
            if m.startswith("moment") and N > args.moment_max_N:
                continue
            rows.append(_record(ex, m, args.n_jobs, extra))
            _checkpoint("scaling", rows, args)
    add_ratios(rows, ["N"])
    return rows


def order_system(n: int) -> HammersteinSystem:
    """A stable order-n linear block with unit DC gain (poles 0.6-0.8, alternating real/complex)."""
    poles = {1: [0.7], 2: [0.6 + 0.45j, 0.6 - 0.45j], 3: [0.7, 0.5 + 0.4j, 0.5 - 0.4j],
             4: [0.6 + 0.45j, 0.6 - 0.45j, 0.4 + 0.3j, 0.4 - 0.3j]}[n]
    A = np.real(np.poly(poles))
    b = np.array([1.0, -0.5, 0.25, -0.125][:n])
    b = b * (A.sum() / b.sum())  # unit steady-state gain (22.8)
    return HammersteinSystem(CHAPTER_BACKLASH, (A, np.concatenate([[0.0], b])))


def part_order(args):
    orders = args.orders or ([1, 2, 3] if args.quick else [1, 2, 3, 4])
    N = 100
    rows = []
    for n in orders:
        sys_ = order_system(n)
        rng = np.random.RandomState(args.seed)
        steady = square_wave_experiment(sys_, CHAPTER_AMPLITUDES, args.noise, random_state=rng)
        data = prbs_experiment(sys_, N, CHAPTER_U_STAR, args.noise, random_state=rng)
        ex = ChapterExample(sys_, steady, data, float(args.noise))
        extra = {"order": n, "N": N, "noise": args.noise, "seed": args.seed, "snr_prbs_db": data.snr_db}
        for m in ["lp", "moment1", "exact"]:
            rows.append(_record(ex, m, args.n_jobs, extra, na=n, nb=n))
            _checkpoint("order", rows, args)
    add_ratios(rows, ["order"])
    return rows


def plot_scaling(rows):
    plt = C.setup_matplotlib()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    styles = {"lp": "o-", "moment1": "s-", "exact": "^-", "lp-2level": "o--", "exact-2level": "^--",
              "moment2": "D-"}
    for m, st in styles.items():
        rr = sorted((r for r in rows if r["method"] == m and "wall_s" in r), key=lambda r: r["N"])
        if not rr:
            continue
        Ns = [r["N"] for r in rr]
        axes[0].loglog(Ns, [r["wall_s"] for r in rr], st, label=m)
        axes[1].loglog(Ns, [np.mean(r["theta_width"]) for r in rr], st, label=m)
    axes[0].set_xlabel("N (PRBS samples)")
    axes[0].set_ylabel("wall time, all 8 bounds (s)")
    axes[0].set_title("Time against N")
    axes[1].set_xlabel("N (PRBS samples)")
    axes[1].set_ylabel("mean interval width over a1, a2, b1, b2")
    axes[1].set_title("Width against N")
    for ax in axes:
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(C.FIGURES / "bench_methods_scaling.png")
    plt.close(fig)


def plot_delta2(rows):
    plt = C.setup_matplotlib()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    for m, st in {"lp": "o-", "moment1": "s-", "moment2": "D-", "exact": "^-"}.items():
        rr = sorted((r for r in rows if r["method"] == m and "wall_s" in r), key=lambda r: r["N"])
        if not rr:
            continue
        Ns = [r["N"] for r in rr]
        axes[0].semilogy(Ns, [r["wall_s"] for r in rr], st, label=m)
        if m != "exact":
            axes[1].plot(Ns, [np.mean(r.get("width_over_exact", [np.nan] * 4)) for r in rr], st, label=m)
    axes[0].set_xlabel("N")
    axes[0].set_ylabel("wall time, all 8 bounds (s)")
    axes[0].set_title("Cost of the relaxation order")
    axes[1].axhline(1.0, color="gray", lw=0.8)
    axes[1].set_xlabel("N")
    axes[1].set_ylabel("mean of width / exact width")
    axes[1].set_title("Conservatism (1 = tight)")
    for ax in axes:
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(C.FIGURES / "bench_methods_delta2.png")
    plt.close(fig)


def plot_order(rows):
    plt = C.setup_matplotlib()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    for m, st in {"lp": "o-", "moment1": "s-", "exact": "^-"}.items():
        rr = sorted((r for r in rows if r["method"] == m and "wall_s" in r), key=lambda r: r["order"])
        if not rr:
            continue
        axes[0].semilogy([r["order"] for r in rr], [r["wall_s"] for r in rr], st, label=m)
        if m != "exact":
            axes[1].plot([r["order"] for r in rr],
                         [np.mean(r.get("width_over_exact", [np.nan])) for r in rr], st, label=m)
    axes[0].set_xlabel("model order n = na = nb")
    axes[0].set_ylabel("wall time, all 4n bounds (s)")
    axes[0].set_title("Time against model order (N = 100)")
    axes[1].axhline(1.0, color="gray", lw=0.8)
    axes[1].set_xlabel("model order n")
    axes[1].set_ylabel("mean of width / exact width")
    axes[1].set_title("Conservatism against model order")
    for ax in axes:
        ax.legend(fontsize=7)
    for ax in axes:
        ax.set_xticks(sorted({r["order"] for r in rows}))
    fig.tight_layout()
    fig.savefig(C.FIGURES / "bench_methods_order.png")
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--part", choices=PARTS, action="append", help="default: all parts")
    ap.add_argument("--noise", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--n-jobs", type=int, default=2)
    ap.add_argument("--delta2-N", type=int, nargs="+", default=None,
                    help="N values of part delta2 (default 10 20 30; --quick: 10 20)")
    ap.add_argument("--scaling-N", type=int, nargs="+", default=None,
                    help="N values of part scaling (default 50 100 200 300 500 1000)")
    ap.add_argument("--moment-max-N", type=int, default=10**9,
                    help="part scaling: skip the moment method above this N")
    ap.add_argument("--orders", type=int, nargs="+", default=None, help="part order (default 1 2 3 4)")
    ap.add_argument("--cvxopt2", action="store_true", help="also delta = 2 with CVXOPT at the smallest N")
    args = ap.parse_args(argv)
    env = C.environment()
    out = {}
    for part in args.part or PARTS:
        C.log(f"== part {part}")
        rows = globals()[f"part_{part}"](args)
        C.write_csv(rows, C.RESULTS / f"methods_{part}.csv")
        C.write_json({"environment": env, "quick": args.quick, "args": vars(args), "rows": rows},
                     C.RESULTS / f"methods_{part}.json")
        if part == "scaling":
            plot_scaling(rows)
        elif part == "delta2":
            plot_delta2(rows)
        elif part == "order":
            plot_order(rows)
        out[part] = rows
    return out


if __name__ == "__main__":
    main()
