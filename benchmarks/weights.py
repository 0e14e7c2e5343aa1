"""Certified uncertainty weights by order (issue 29, item 2).

    python -m benchmarks.weights

Records: the issue's two sampled plants (first order, and 400/(s^2 + 12 s + 400), both
zero-order hold at dt = 0.01, N = 150, input and output errors uniform in +-0.02, seed
42), the second one again with every error exactly at +-0.02, and the chapter example of
``docs/robust-control.md`` (N = 200, LP method, dt = 1). For each record, kind and
``order = 0..4``: the order returned, the selection criterion ``excess_db`` (mean
over-bound in dB on the fit grid), ``|W(1)|`` against the exact deviation at DC, the
smallest ``|W| / deviation`` on a dense grid of 100 001 frequencies (>= 1: the weight
covers the set), the proof grid's size and the wall time (2 shared cores, under load).
Writes benchmarks/results/weights.json.
"""

from __future__ import annotations

import json
import time
import warnings
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"


def records():
    import control

    import hammerbound as hb

    rng = np.random.default_rng(42)
    dt = 0.01
    out = {}
    plants = {"first": control.c2d(control.tf([2.0], [0.1, 1.0]), dt),
              "second": control.c2d(control.tf([400.0], [1, 12, 400]), dt)}
    for name, N, hold in (("first", 150, 8), ("second", 150, 6)):
        u0 = np.repeat(rng.uniform(-1, 1, N // hold + 1), hold)[:N]
        y0 = control.forced_response(plants[name], T=np.arange(N) * dt, U=u0).outputs
        u = u0 + rng.uniform(-0.02, 0.02, N)
        y = y0 + rng.uniform(-0.02, 0.02, N)
        n = 1 if name == "first" else 2
        out[name] = (hb.LinearEIVSetEstimator(n, n, output_bound=0.02, method="exact").fit(
            hb.IOData(u, y, dt=dt), input_bound=0.02), dt)
    r2 = np.random.default_rng(7)
    u0 = np.repeat(r2.uniform(-1, 1, 26), 6)[:150]
    y0 = control.forced_response(plants["second"], T=np.arange(150) * dt, U=u0).outputs
    u, y = u0 + 0.02 * r2.choice([-1.0, 1.0], 150), y0 + 0.02 * r2.choice([-1.0, 1.0], 150)
    out["second_at_bound"] = (hb.LinearEIVSetEstimator(2, 2, output_bound=0.02,
                                                       method="exact").fit(
        hb.IOData(u, y, dt=dt), input_bound=0.02), dt)
    ex = hb.chapter_example(0.05, N=200, random_state=0)
    idf = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05), hb.LinearEIVSetEstimator(output_bound=0.05, method="lp"),
    ).fit(hb.IOData(ex.prbs.u, ex.prbs.y, dt=1.0), steady_state=ex.steady)
    out["chapter_lp"] = (idf.linear_, 1.0)
    return out


def main(argv=None):
    from benchmarks._common import environment
    from hammerbound.modelset.uncertainty import deviation_bound

    warnings.simplefilter("ignore")
    env = environment()
    rows = []
    for name, (est, dt) in records().items():
        w = np.linspace(0.0, np.pi / dt, 100001)
        for kind in ("multiplicative", "additive"):
            dev = deviation_bound(est.bounds_, est.na, est._b_lags(), w, dt, kind)
            for order in range(5):
                t0 = time.perf_counter()
                uw = est.uncertainty_weight(kind, order=order, dt=dt)
                t = time.perf_counter() - t0
                Wm = np.abs(uw.W(np.exp(1j * w * dt)))
                rows.append({
                    "record": name, "kind": kind, "order_asked": order, "order": uw.order,
                    "excess_db": uw.excess_db, "W_dc": float(abs(uw.W(1.0))),
                    "deviation_dc": float(dev[0]), "min_W_over_deviation": float(np.min(Wm / dev)),
                    "proof_points": int(uw.certificate.omega.size), "seconds": t})
                print(json.dumps(rows[-1]))
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "weights.json").write_text(json.dumps({"environment": env, "rows": rows},
                                                     indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
