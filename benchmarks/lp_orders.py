"""The cost of high model orders, and how fast the guards refuse what is out of reach.

    python -m benchmarks.lp_orders [--N 60] [--orders 2 3 4 5 6]

Every stage-2 method starts from the polytopic LP over the ``2^p`` sign orthants of theta
(``p = na + nb`` parameters, ``2p + 1`` LPs each), so its time doubles and more with every
order. This script times ``LinearEIVSetEstimator(na=k, nb=k, method="lp")`` on one record
of a second-order system (noise within +-0.05) for each ``k``, then the time to *refuse*
``na = nb = 40`` (issue 29.4: more than 60 s before the guard) and a moment relaxation of
order 8 (48 s from the command line, 236 s in Python before the closed-form count).
Writes ``results/lp_orders.json`` (with the load average: the machine is shared).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.signal import lfilter

import hammerbound as hb
from benchmarks import _common as C


def _record(n, seed=1):
    rng = np.random.default_rng(seed)
    x = np.where(rng.random(n) < 0.5, 1.0, -1.0)
    y = lfilter([0, 0.5, 0.2], [1, -0.6, 0.1], x) + rng.uniform(-0.05, 0.05, n)
    return x, y


def _refusal(est, x, y):
    t = time.perf_counter()
    try:
        est.fit(x, y)
    except hb.HammerboundError as exc:
        return time.perf_counter() - t, type(exc).__name__
    return time.perf_counter() - t, "not refused"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--N", type=int, default=60)
    p.add_argument("--orders", type=int, nargs="+", default=[2, 3, 4, 5, 6])
    args = p.parse_args(argv)
    x, y = _record(args.N)
    rows = []
    for k in args.orders:
        est = hb.LinearEIVSetEstimator(na=k, nb=k, output_bound=0.05, method="lp")
        load0, t = C.loadavg(), time.perf_counter()
        est.fit(x, y)
        wall = time.perf_counter() - t
        rows.append({"na": k, "nb": k, "p": 2 * k, "orthants": 2 ** (2 * k), "wall_s": wall,
                     "loadavg_start": load0, "loadavg_end": C.loadavg()})
        print(f"na = nb = {k} (p = {2 * k}, {2 ** (2 * k)} orthants): {wall:.2f} s "
              f"(load {load0})", flush=True)
    big = _refusal(hb.LinearEIVSetEstimator(na=40, nb=40, output_bound=0.05, method="lp"),
                   x, y)
    ex = hb.chapter_example(0.05, N=100, random_state=0)
    moment8 = _refusal(hb.LinearEIVSetEstimator(output_bound=0.05, steady_state_gain=1.0,
                                                method="moment", relaxation_order=8),
                       ex.prbs.x, ex.prbs.y)
    refusals = {f"na=nb=40, N={args.N}": {"seconds": big[0], "error": big[1]},
                "moment order 8, N=100": {"seconds": moment8[0], "error": moment8[1]}}
    for name, r in refusals.items():
        print(f"refused {name}: {r['error']} after {r['seconds']:.4f} s")
    C.write_json({"environment": C.environment(), "N": args.N, "rows": rows,
                  "refusals": refusals}, C.RESULTS / "lp_orders.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
