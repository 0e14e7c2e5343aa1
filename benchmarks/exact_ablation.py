"""What each part of the exact method's search buys: one feature off at a time.

    python -m benchmarks.exact_ablation [--N 300] [--levels 0.15 0.3] [--inner two-level]

The stage-2 problem of the identifier (chapter example, seed 0, two-level or independent
inner signal) is built once per level; then ``exact_bounds`` runs on one core (``n_jobs=1``,
so the total is the sum over the 8 ends) with every feature on, and with each of these off:

* ``no-local``: the SLP walk to a near-optimal incumbent (:mod:`hammerbound.relaxations.exact.local`);
* ``no-shared-branching``: branching on the shared input errors of the two-level signal;
* ``no-parent-basis``: children start from their parent's simplex basis.

Writes ``results/exact_ablation.json`` (time, nodes and simplex iterations per variant, and
the largest difference of its bounds from the all-on run, which must stay within the
tolerance: every variant certifies the same intervals).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks import _common as C

VARIANTS = ("all", "no-local", "no-shared-branching", "no-parent-basis")


#: the search options of each variant (explicit options: they reach joblib workers too)
OPTIONS = {"all": {}, "no-local": {"local_search": False},
           "no-shared-branching": {"shared_branching": False},
           "no-parent-basis": {"parent_basis": False}}


def _run(problem, variant, tol):
    from hammerbound.relaxations.exact.bnb import SearchOptions, exact_bounds

    t = time.perf_counter()
    res = exact_bounds(problem, tol=tol, n_jobs=1, options=SearchOptions(**OPTIONS[variant]))
    return res, time.perf_counter() - t


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--N", type=int, default=300)
    p.add_argument("--levels", type=float, nargs="+", default=[0.15, 0.3])
    p.add_argument("--inner", default="two-level", choices=["two-level", "independent"])
    p.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=VARIANTS)
    p.add_argument("--tol", type=float, default=1e-4)
    args = p.parse_args(argv)
    rows = []
    for deta in args.levels:
        problem = C.chapter_stage2_problem(deta, args.N, args.inner)
        ref = None
        for variant in args.variants:
            load0 = C.loadavg()
            res, wall = _run(problem, variant, args.tol)
            if ref is None:
                ref = res
            diff = float(np.max(np.abs(res.bounds - ref.bounds)))
            row = {"N": args.N, "delta_eta": deta, "inner_signal": args.inner,
                   "variant": variant, "wall_s": wall,
                   "nodes": sum(i.nodes or 0 for i in res.infos),
                   "iterations": sum(i.iterations or 0 for i in res.infos),
                   "statuses": sorted({i.status for i in res.infos}),
                   "max_bound_diff": diff, "loadavg_start": load0}
            rows.append(row)
            print(f"N={args.N} {args.inner} deta={deta:<5g} {variant:20s} {wall:6.1f} s "
                  f"nodes={row['nodes']:5d} iterations={row['iterations']:7d} "
                  f"{row['statuses']} |bounds - all| <= {diff:.1e} load={load0}", flush=True)
    C.write_json({"environment": C.environment(), "rows": rows}, C.RESULTS / "exact_ablation.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
