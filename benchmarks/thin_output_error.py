"""Exact method on thin output-error sets, with and without the completion of a node's
``a`` by its best ``b`` (new-user trial 8; ``_Pool.complete`` and ``complete_line`` in
``hammerbound/relaxations/exact/points.py``).

    python -m benchmarks.thin_output_error [--N 60 90 120] [--seeds 4] [--time-limit 20]

Records simulated here: a second-order output-error plant (A = 1 - 0.5 q^-1 + 0.06 q^-2,
B = q^-2 + 0.5 q^-3, nk = 2), input +-1 plus uniform +-0.3, output errors uniform within
+-0.1, no input errors. Each record is fitted by ``exact_bounds`` twice with the step off and
twice with it on, alternating, in one process (CPU time). Writes
``results/thin_output_error.json``. Timings are never asserted in tests.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.signal import lfilter

from benchmarks import _common as C


def record(n, seed, bound=0.1):
    rng = np.random.default_rng(seed)
    x = np.where(rng.random(n) < 0.5, 1.0, -1.0) + 0.3 * rng.uniform(-1, 1, n)
    y = lfilter([0, 0, 1.0, 0.5], [1.0, -0.5, 0.06], x) + rng.uniform(-bound, bound, n)
    return x, y


def _fit(problem, on, time_limit):
    from hammerbound.relaxations import exact_bounds
    from hammerbound.relaxations.exact import points

    saved = points._Pool.complete, points._Pool.complete_line
    if not on:
        points._Pool.complete = points._Pool.complete_line = lambda self, *a, **k: None
    try:
        t = time.process_time()
        res = exact_bounds(problem, time_limit=time_limit)
        return time.process_time() - t, res
    finally:
        points._Pool.complete, points._Pool.complete_line = saved


def main(argv=None) -> int:
    import hammerbound as hb

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--N", type=int, nargs="+", default=[60, 90, 120])
    p.add_argument("--seeds", type=int, default=4)
    p.add_argument("--time-limit", type=float, default=20.0)
    args = p.parse_args(argv)
    rows = []
    for n in args.N:
        for seed in range(args.seeds):
            x, y = record(n, seed)
            pr = hb.EIVProblem(y, x, input_bound=0.0, output_bound=0.1, na=2, nb=2, nk=2)
            row = {"N": n, "seed": seed, "loadavg_start": C.loadavg()}
            for on in (False, True, False, True):
                cpu, res = _fit(pr, on, args.time_limit)
                key = "on" if on else "off"
                row.setdefault(f"cpu_{key}", []).append(cpu)
                row[f"optimal_{key}"] = int(sum(i.status == "optimal" for i in res.infos))
                row[f"nodes_{key}"] = int(sum(i.nodes or 0 for i in res.infos))
                row[f"bounds_{key}"] = np.asarray(res.bounds).tolist()
            rows.append(row)
            C.log(f"N={n} seed={seed}: off {min(row['cpu_off']):.1f} s "
                  f"({row['optimal_off']}/8 optimal), on {min(row['cpu_on']):.1f} s "
                  f"({row['optimal_on']}/8 optimal)")
    out = {"environment": C.environment(), "time_limit": args.time_limit, "rows": rows}
    C.write_json(out, C.RESULTS / "thin_output_error.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
