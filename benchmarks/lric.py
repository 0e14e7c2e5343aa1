"""The LRIC exam record: a real third-party EIV data set, solved with every method.

    python -m benchmarks.lric [--repeat 3]

Data: ``../shared/data/lric/eiv_first_order_2017.csv`` relative to the repository root (30
samples, dt = 0.1, from the public course repository P0li22/LRIC, exam of 22 February
2017, Politecnico di Torino; read in place, never copied into the project). The exam
states ``G(z) = (beta1 z + beta2) / (z + alpha1)`` with input and output errors bounded by
0.05: ``na=1, nb=1, nk=0`` here. For the LP, moment (order 1) and exact methods: the
intervals, their statuses, the wall time (fastest and slowest of ``--repeat`` fits, on a
shared machine: the load average is recorded) and, for the exact method, whether every
witness is feasible by an independent LP (scipy, fixed theta, margin 1e-7). Writes
``benchmarks/results/lric.json``; ``python -m benchmarks report`` tabulates it.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import linprog

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

DATA = C.ROOT.parent / "shared" / "data" / "lric" / "eiv_first_order_2017.csv"
BOUND = 0.05
METHODS = ("lp", "moment", "exact")


def witness_feasible(u, y, theta, dx=BOUND, deta=BOUND, margin=1e-7) -> bool:
    """Independent LP at fixed theta: some |eta| <= deta, |e| <= dx explain every equation
    ``(y_t - eta_t) + a (y_{t-1} - eta_{t-1}) = b0 (u_t - e_t) + b1 (u_{t-1} - e_{t-1})``."""
    a, b0, b1 = theta
    N = u.size
    A = np.zeros((N - 1, 2 * N))
    rhs = np.empty(N - 1)
    for row, t in enumerate(range(1, N)):
        A[row, t], A[row, t - 1] = 1.0, a
        A[row, N + t], A[row, N + t - 1] = -b0, -b1
        rhs[row] = y[t] + a * y[t - 1] - b0 * u[t] - b1 * u[t - 1]
    res = linprog(np.zeros(2 * N), A_ub=np.vstack([A, -A]),
                  b_ub=np.concatenate([rhs + margin, -rhs + margin]),
                  bounds=[(-deta, deta)] * N + [(-dx, dx)] * N, method="highs")
    return res.status == 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    import hammerbound as hb

    if not DATA.is_file():
        raise SystemExit(f"{DATA} not found: the LRIC record is read from ../shared/data/lric/ "
                         "beside the repository.")
    data = hb.IOData.from_csv(DATA, dt=0.1)
    rows = []
    for method in METHODS:
        walls = []
        for _ in range(args.repeat):
            est = hb.LinearEIVSetEstimator(na=1, nb=1, nk=0, noise_bound=BOUND, method=method)
            t0 = time.perf_counter()
            est.fit(data, input_bound=BOUND)
            walls.append(time.perf_counter() - t0)
        status = [str(v) for v in est.to_frame()["status"]]
        row = {"method": method, "params": list(est.param_names_),
               "bounds": est.bounds_.tolist(), "status": list(status),
               "wall_s": walls, "loadavg": C.loadavg()}
        if method == "exact":
            row["witnesses_feasible"] = all(
                witness_feasible(data.u, data.y, i.witness) for i in est.bound_info_)
        C.log(f"{method:7s} {np.round(est.bounds_, 4).tolist()} "
              f"{min(walls):.3f}-{max(walls):.3f} s {status}")
        rows.append(row)
    C.write_json({"environment": C.environment(), "data": "../" + str(DATA.relative_to(C.ROOT.parent)),
                  "N": data.N, "dt": data.dt, "bound": BOUND, "rows": rows},
                 C.RESULTS / "lric.json")


if __name__ == "__main__":
    main()
