"""Which stage-2 method should be the default? LP, moment (order 1) and exact on the same data.

Cases (each a stage-2 fit of ``LinearEIVSetEstimator``; the chapter cases through the
two-stage identifier, stage 1 exact, so their times include stage 1, the same for every
method):

``chapter-N100-0.05``, ``chapter-N100-0.3``, ``chapter-N300-0.05``
    ``hb.chapter_example`` (section 22.5), independent inner-signal errors.
``second-ZOH-N150``
    The second-order system of issue 29 (``c2d(400 / (s^2 + 12 s + 400), 0.01)``, held
    uniform input, N = 150, uniform input and output errors 0.02).
``second-at-bound-N150``
    A second-order system (poles 0.6 +- 0.45j), input and output errors exactly at +-0.02.
``first-ZOH-N150``
    The first-order system of issue 29 (``c2d(2 / (0.1 s + 1), 0.01)``, na = nb = 1).

Per fit: wall time, widths, width / exact width, the set of end statuses, whether every end
is certified and whether the true parameters are inside. ``n_jobs = 1`` for every method.

    python -m benchmarks default_method            # all cases
    python -m benchmarks default_method --cases chapter-N100-0.05 --methods lp exact
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

import hammerbound as hb

OUT = C.RESULTS / "default_method.json"
METHODS = ("lp", "moment", "exact")
LABELS = {"lp": "lp", "moment": "moment1", "exact": "exact"}


def _eiv_case(name):
    """(x, y, bound, na, nb, theta_true) of the issue's and our own EIV records."""
    from scipy.signal import lfilter

    if name == "second-at-bound-N150":
        rng = np.random.default_rng(1)
        a = np.real(np.poly([0.6 + 0.45j, 0.6 - 0.45j]))
        b = np.array([0.5, 0.3])
        x0 = np.repeat(rng.uniform(-1, 1, 26), 6)[:150]
        w = lfilter(np.r_[0.0, b], a, x0)
        dx, eta = 0.02 * rng.choice([-1.0, 1.0], (2, 150))
        return x0 + dx, w + eta, 0.02, 2, 2, np.r_[a[1:], b]
    import control

    dt = 0.01
    first = name.startswith("first")
    G = control.c2d(control.tf([2.0], [0.1, 1.0]) if first else
                    control.tf([400.0], [1, 12, 400]), dt)
    rng = np.random.default_rng(42)
    hold = 8 if first else 6
    x0 = np.repeat(rng.uniform(-1, 1, 150 // hold + 1), hold)[:150]
    w = control.forced_response(G, T=np.arange(150) * dt, U=x0).outputs
    x = x0 + rng.uniform(-0.02, 0.02, 150)
    y = w + rng.uniform(-0.02, 0.02, 150)
    num, den = (np.ravel(v) for v in control.tfdata(G))
    n = 1 if first else 2
    theta = np.r_[den[1:] / den[0], num[-n:] / den[0]]
    return x, y, 0.02, n, n, theta


CASES = {
    "chapter-N100-0.05": ("chapter", 100, 0.05),
    "chapter-N100-0.3": ("chapter", 100, 0.3),
    "chapter-N300-0.05": ("chapter", 300, 0.05),
    "second-ZOH-N150": ("eiv", None, None),
    "second-at-bound-N150": ("eiv", None, None),
    "first-ZOH-N150": ("eiv", None, None),
}


def _row(name, method, wall, est, theta):
    b = np.asarray(est.bounds_)
    infos = est.bound_info_
    return {
        "case": name, "method": method, "wall_s": wall,
        "theta_width": (b[:, 1] - b[:, 0]).tolist(),
        "statuses": sorted({s for pair in est.intervals_.status for s in pair}),
        "all_certified": bool(all(i.certified for i in infos)),
        "theta_inside": bool(np.all((theta >= b[:, 0]) & (theta <= b[:, 1]))),
        "loadavg": C.loadavg(),
    }


def run_case(name, method, time_limit):
    kind, N, noise = CASES[name]
    if kind == "chapter":
        ex = hb.chapter_example(noise, N=N, random_state=0)
        r = C.run_method(ex, LABELS[method], n_jobs=1, time_limit=time_limit)
        return {"case": name, "method": method, "wall_s": r["wall_s"],
                "theta_width": r["theta_width"],
                "statuses": r["statuses"], "all_certified": r["all_certified"],
                "theta_inside": r["theta_inside"], "loadavg": r["loadavg"]}
    x, y, bound, na, nb, theta = _eiv_case(name)
    est = hb.LinearEIVSetEstimator(na=na, nb=nb, output_bound=bound, method=method,
                                   time_limit=time_limit, on_failure="box")
    t0 = time.perf_counter()
    est.fit(x, y, input_bound=bound)
    return _row(name, method, time.perf_counter() - t0, est, theta)


def add_ratios(rows):
    for r in rows:
        ref = [q for q in rows if q["case"] == r["case"] and q["method"] == "exact"
               and "theta_width" in q]
        if ref and "theta_width" in r:
            r["width_over_exact"] = (np.array(r["theta_width"])
                                     / np.maximum(np.array(ref[0]["theta_width"]), 1e-12)).tolist()


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    p.add_argument("--methods", nargs="+", default=list(METHODS), choices=list(METHODS))
    p.add_argument("--time-limit", type=float, default=600.0,
                   help="exact method: seconds per interval end")
    args = p.parse_args(argv)
    env = C.environment()
    rows = []
    for name in args.cases:
        for m in args.methods:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # moment size warnings
                try:
                    r = run_case(name, m, args.time_limit)
                except Exception as exc:  # a failure is a result too
                    r = {"case": name, "method": m, "error": f"{type(exc).__name__}: {exc}"[:300]}
            rows.append(r)
            C.log(f"{name:22s} {m:7s} wall {r.get('wall_s', float('nan')):7.2f} s  widths "
                  f"{np.round(r.get('theta_width', []), 4).tolist()}  {r.get('statuses')}  "
                  f"inside={r.get('theta_inside')} {r.get('error', '')}")
            if r.get("theta_inside") is False:
                C.log("!!! SOUNDNESS: true parameter outside an interval !!!")
    add_ratios(rows)
    C.write_json({"environment": env, "args": vars(args), "rows": rows}, OUT)
    C.log(f"wrote {OUT}")
    return rows


def report_section() -> str:
    """The docs/benchmarks.md section (called by benchmarks/report.py)."""
    if not OUT.exists():
        return ""
    j = C.read_json(OUT)
    rows = j["rows"]
    cases = list(dict.fromkeys(r["case"] for r in rows))
    out = ["| case | method | wall (s) | mean width / exact | statuses | certified | "
           "truth inside |", "|---|---|---|---|---|---|---|"]
    for c in cases:
        for r in (q for q in rows if q["case"] == c):
            if "error" in r:
                out.append(f"| {c} | {r['method']} | – | – | {r['error'][:80]} | – | – |")
                continue
            ratio = r.get("width_over_exact")
            rt = f"{np.mean(ratio):.2f}" if ratio else "–"
            out.append(f"| {c} | {r['method']} | {r['wall_s']:.2f} | {rt} | "
                       f"{', '.join(r['statuses'])} | {r['all_certified']} | "
                       f"{r['theta_inside']} |")
    tot = {m: sum(r.get("wall_s", np.nan) for r in rows if r["method"] == m) for m in METHODS}
    e = j["environment"]
    out.append("")
    out.append("Total wall time over the cases: " + ", ".join(
        f"{m} {t:.1f} s" for m, t in tot.items()) + ".")
    out.append(f"_Run {e['date']}, Python {e['python']}, {e['cpu_count']} CPUs, load average "
               f"at start {e['loadavg_at_start'][0]} (shared machine); `n_jobs = 1`._")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()
