"""Soundness cross-check of the relaxations against verified-feasible witnesses.

For every data set of ``results/methods_delta2.json`` the exact method is re-run; each of its
interval ends carries a *witness*: a theta verified feasible for (22.34). A guaranteed lower
bound (any method) must be <= the witness value of the min problem, an upper bound >= the
witness value of the max problem. Writes ``results/witness_check.json``.

    python benchmarks/witness_check.py
"""

from __future__ import annotations

import numpy as np

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

import hammerbound as hb


def main(argv=None):
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


if __name__ == "__main__":
    main()
