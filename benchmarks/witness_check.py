"""Cross-checks of the exact method's witnesses (verified-feasible theta of (22.34)).

``--part consistency``: for every data set of ``results/methods_delta2.json`` the exact method
is re-run; a guaranteed lower bound (any method) must be <= the witness value of the min
problem, an upper bound >= the witness value of the max problem. Writes
``results/witness_check.json``.

``--part widening``: chapter data over inner signals, noise levels, N and seeds; for every
witness an independent LP (scipy's HiGHS, rows divided by the magnitudes of their terms,
tolerances 1e-10) finds the smallest factor ``s`` by which both error bounds must be scaled
for the witness to explain the data; ``s - 1`` is the widening it needs, in units of the
bounds (negative: strictly inside). ``--no-polish`` measures the witnesses as accepted,
without :func:`hammerbound.relaxations.exact.local.polish`. Writes
``results/witness_widening.json`` (``witness_widening_unpolished.json``).

    python benchmarks/witness_check.py                    # both parts
    python benchmarks/witness_check.py --part widening --seeds 4
"""

from __future__ import annotations

import argparse

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

import hammerbound as hb


def consistency():
    j = C.read_json(C.RESULTS / "methods_delta2.json")
    out = []
    for N in sorted({r["N"] for r in j["rows"]}):
        rows = [r for r in j["rows"] if r["N"] == N and "theta_lower" in r]
        seed, noise = rows[0]["seed"], rows[0]["noise"]
        ex = hb.chapter_example(noise, N=N, random_state=seed)
        idf = hb.HammersteinBacklashIdentifier(
            backlash=hb.BacklashSetEstimator(noise),
            linear=hb.LinearEIVSetEstimator(output_bound=noise, method="exact", n_jobs=2)).fit(
            ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
        infos = idf.linear_.bound_info_
        wlo = np.array([infos[2 * k].witness[k] for k in range(4)])
        whi = np.array([infos[2 * k + 1].witness[k] for k in range(4)])
        gaps = [i.gap for i in infos]
        for r in rows:
            lo, hi = np.array(r["theta_lower"]), np.array(r["theta_upper"])
            ok = bool(np.all(lo <= wlo + 1e-12) and np.all(hi >= whi - 1e-12))
            rec = {"N": N, "method": r["method"], "lower": lo.tolist(), "upper": hi.tolist(),
                   "witness_min_value": wlo.tolist(), "witness_max_value": whi.tolist(),
                   "slack_lower": (wlo - lo).tolist(), "slack_upper": (hi - whi).tolist(),
                   "consistent": ok, "exact_gaps": gaps}
            out.append(rec)
            C.log(f"N={N} {r['method']:8s} consistent={ok}  min slack "
                  f"{min(min(rec['slack_lower']), min(rec['slack_upper'])):.2e}")
    C.write_json({"environment": C.environment(), "rows": out}, C.RESULTS / "witness_check.json")


def error_scale(pr, theta) -> float:
    """Smallest ``s`` with ``theta`` feasible for (22.34) when ``|eta| <= s deta`` and
    ``|dx| <= s dx`` (an LP in the errors, written out equation by equation here)."""
    theta = np.asarray(theta, dtype=float)
    a, b, lags = theta[: pr.na], theta[pr.na :], pr.b_lags
    n, k = pr.N, pr.n_groups
    T = np.arange(pr.n0, pr.N)
    rows, cols, vals = [], [], []
    r, scale = np.empty(T.size), np.empty(T.size)
    for row, t in enumerate(T):
        ylag = pr.y[t - np.arange(1, pr.na + 1)]
        xlag = pr.x[t - lags]
        rows += [row] * (1 + pr.na + lags.size)
        cols += [t, *(t - np.arange(1, pr.na + 1)), *(n + pr.groups[t - lags])]
        vals += [-1.0, *(-a), *b]
        r[row] = -(pr.y[t] + a @ ylag - b @ xlag)
        scale[row] = abs(pr.y[t]) + np.abs(a) @ np.abs(ylag) + np.abs(b) @ np.abs(xlag)
    M = sp.csr_matrix((vals, (rows, cols)), shape=(T.size, n + k))
    bound = np.concatenate([pr.deta, pr.dx_group])
    Ms = sp.diags(1 / scale) @ M @ sp.diags(bound)  # variables z / bound, rows / terms
    nz = n + k
    eye = sp.identity(nz, format="csr")
    ones = sp.csr_matrix(-np.ones((nz, 1)))
    res = linprog(np.r_[np.zeros(nz), 1.0],
                  A_ub=sp.vstack([sp.hstack([eye, ones]), sp.hstack([-eye, ones])]),
                  b_ub=np.zeros(2 * nz), A_eq=sp.hstack([Ms, sp.csr_matrix((T.size, 1))]),
                  b_eq=r / scale, bounds=[(None, None)] * nz + [(0, None)], method="highs",
                  options={"primal_feasibility_tolerance": 1e-10,
                           "dual_feasibility_tolerance": 1e-10})
    if res.status != 0:
        raise RuntimeError(res.message)
    return float(res.fun)


def widening(seeds: int, polish: bool):
    from hammerbound.relaxations.exact.bnb import SearchOptions, exact_bounds

    rows = []
    for inner in ("independent", "two-level"):
        for noise in (0.005, 0.05, 0.3):
            for N in (30, 100):
                for seed in range(seeds):
                    ex = hb.chapter_example(noise, N=N, random_state=seed)
                    idf = hb.HammersteinBacklashIdentifier(
                        hb.BacklashSetEstimator(noise),
                        hb.LinearEIVSetEstimator(output_bound=noise, method="lp"),
                        inner_signal=inner).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
                    pr = idf.linear_.problem_
                    # the estimator's exact method (its defaults), witnesses polished or not
                    res = exact_bounds(pr, tol=1e-4, check_box=False,
                                       options=SearchOptions(polish=polish))
                    w = [error_scale(pr, i.witness) - 1.0 for i in res.infos
                         if i.witness is not None]
                    rows.append({"inner": inner, "noise": noise, "N": N, "seed": seed,
                                 "widening": w})
                    C.log(f"{inner:11s} dη={noise:<5} N={N:<4} seed={seed}  max widening "
                          f"{max(w):.2e}")
    w = np.concatenate([r["widening"] for r in rows])
    summary = {"environment": C.environment(), "polish": polish, "n_witnesses": int(w.size),
               "max": float(w.max()), "median": float(np.median(w)),
               "n_above_0": int((w > 0).sum()), "n_above_2e-7": int((w > 2e-7).sum()),
               "rows": rows}
    name = "witness_widening.json" if polish else "witness_widening_unpolished.json"
    C.write_json(summary, C.RESULTS / name)
    C.log(f"{w.size} witnesses: widening max {w.max():.2e}, median {np.median(w):.2e}, "
          f"{summary['n_above_0']} above 0, {summary['n_above_2e-7']} above 2e-7")
    return summary


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=("consistency", "widening", "all"), default="all")
    ap.add_argument("--seeds", type=int, default=4, help="seeds per configuration (widening)")
    ap.add_argument("--no-polish", action="store_true", help="witnesses as accepted (widening)")
    args = ap.parse_args(argv)
    if args.part in ("consistency", "all"):
        consistency()
    if args.part in ("widening", "all"):
        widening(args.seeds, polish=not args.no_polish)


if __name__ == "__main__":
    main()
