"""Stage 1 with the noise exactly at its bound: time and peak memory per fit.

The configuration of issue 29 (item 3): backlash ``(ml, cl, mr, cr) = (0.8, 0.1, 0.84,
0.12)``, amplitudes ``linspace(0.15, 3.0, M)`` per side, ``Delta = 1e-3``, noise ``+Delta``
on every sample ("plus"), alternating ``+-Delta`` ("alternating") or uniform inside the bound
("uniform", the reference). Each fit runs in a fresh Python process, which reports the wall
time of ``BacklashSetEstimator(Delta, method=...).fit`` and its peak resident memory
(``ru_maxrss``, the imports included: about 140 MB). Writes
``results/stage1_extremal.json`` and ``.csv``.

    python -m benchmarks.stage1_extremal                 # polygon M = 2000, 4000, 10000; algorithm M = 500
    python -m benchmarks.stage1_extremal --quick         # polygon M = 2000; algorithm M = 200
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

GAMMA = (0.8, 0.1, 0.84, 0.12)
DELTA = 1e-3
KINDS = ("plus", "alternating", "uniform")

CHILD = rf'''
import json, resource, sys, time
import numpy as np
import hammerbound as hb
method, M, kind = sys.argv[1], int(sys.argv[2]), sys.argv[3]
ml, cl, mr, cr = {GAMMA}
D = {DELTA}
amps = np.linspace(0.15, 3.0, M)
u = np.concatenate([amps, -amps])
w = np.where(u > 0, mr * (u - cr), ml * (u + cl))
if kind == "plus":
    e = np.full(u.size, D)
elif kind == "alternating":
    e = D * np.where(np.arange(u.size) % 2 == 0, 1.0, -1.0)
else:
    e = np.random.default_rng(0).uniform(-D, D, u.size)
t0 = time.perf_counter()
est = hb.BacklashSetEstimator(D, method=method).fit(u, w + e)
t = time.perf_counter() - t0
g = np.array([ml, cl, mr, cr])
gb = est.gamma_bounds_
print(json.dumps({{"time_s": t, "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "n_vertices_left": len(est.left_.vertices), "n_vertices_right": len(est.right_.vertices),
                  "gamma_inside": bool(np.all((gb[:, 0] <= g) & (g <= gb[:, 1]))),
                  "gamma_bounds": gb.tolist()}}))
'''


def run_one(method: str, M: int, kind: str, timeout: float) -> dict:
    env = {**os.environ, "PYTHONPATH": str(C.ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    row = {"method": method, "M_per_side": M, "noise": kind, "loadavg": C.loadavg()}
    try:
        res = subprocess.run([sys.executable, "-c", CHILD, method, str(M), kind],
                             capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return {**row, "status": f"no answer in {timeout:g} s"}
    if res.returncode != 0:
        return {**row, "status": "error: " + res.stderr.strip().splitlines()[-1]}
    return {**row, "status": "ok", **json.loads(res.stdout.strip().splitlines()[-1])}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--timeout", type=float, default=600.0, help="per fit (s)")
    args = ap.parse_args(argv)
    plan = ([("polygon", 2000), ("algorithm", 200)] if args.quick else
            [("polygon", 2000), ("polygon", 4000), ("polygon", 10000), ("algorithm", 500)])
    rows = []
    for method, M in plan:
        for kind in KINDS:
            r = run_one(method, M, kind, args.timeout)
            rows.append(r)
            C.log(f"{method:9s} M={M:>6d} {kind:11s} " + (
                f"{r['time_s']:.3f} s  {r['peak_rss_mb']:.0f} MB  vertices "
                f"{r['n_vertices_left']}/{r['n_vertices_right']}  inside={r['gamma_inside']}"
                if r["status"] == "ok" else r["status"]))
    summary = {"environment": C.environment(), "delta": DELTA, "gamma": GAMMA,
               "quick": args.quick, "rows": rows}
    C.write_csv([{k: v for k, v in r.items() if k != "gamma_bounds"} for r in rows],
                C.RESULTS / "stage1_extremal.csv")
    C.write_json(summary, C.RESULTS / "stage1_extremal.json")
    return summary


if __name__ == "__main__":
    main()
