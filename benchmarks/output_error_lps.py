"""Exact method on output-error records (no input errors): node-LP scaling and the growth
of the working set.

    python -m benchmarks.output_error_lps [--short 120 300] [--long 1000 3000] [--seeds 2]
                                          [--time-limit 120]

Records: those of :mod:`benchmarks.thin_output_error` (second-order output-error plant,
output errors uniform within +-0.1). Each record is fitted by ``exact_bounds`` of two
versions of the package, each in its own child process so that a crash of the solver is
recorded, not fatal:

* ``current``: the working tree (products with a zero error bound dropped from the
  McCormick LPs, scaled node LPs without input errors, a working set that doubles after
  ``GROW_AFTER`` re-solves of one LP);
* ``base``: the package at the git revision ``--base`` (extracted with ``git archive`` into
  a temporary directory, the child's working directory).

Short records run to completion; long ones with ``total_time_limit``. Reported per run:
CPU time of the child and of the worker process of its search, if any (shut down
before the count), wall time, the
exit code (-11: segmentation fault), the crashes the fit survived (a worker process of the
search that died, ``relaxations.exact.isolation``), end statuses, nodes, and the widths
of the intervals against those of the LP method. Writes
``results/output_error_lps.json``. Timings are never asserted in tests.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile

import numpy as np

from benchmarks import _common as C

_CHILD = r"""
import json, sys, time, resource, warnings
import numpy as np
from benchmarks.thin_output_error import record
import hammerbound as hb
from hammerbound.relaxations import exact_bounds
n, seed, limit = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
x, y = record(n, seed)
pr = hb.EIVProblem(y, x, input_bound=0.0, output_bound=0.1, na=2, nb=2, nk=2)
t, w0 = time.process_time(), time.perf_counter()
kw = {} if limit == "none" else dict(total_time_limit=float(limit), time_limit=float(limit) / 4)
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    r = exact_bounds(pr, **kw)
try:  # the worker of an isolated search (not in older versions): its CPU time counts
    from hammerbound.relaxations.exact.isolation import shutdown
    shutdown(wait=True)
except ImportError:
    pass
kids = resource.getrusage(resource.RUSAGE_CHILDREN)
cpu = time.process_time() - t + kids.ru_utime + kids.ru_stime
wall = time.perf_counter() - w0
died = [str(w.message) for w in caught if "died" in str(w.message)]
print(json.dumps(dict(cpu_s=cpu, wall_s=wall, package=hb.__file__, crashes_survived=died,
                      statuses=[i.status for i in r.infos],
                      nodes=[int(i.nodes or 0) for i in r.infos],
                      bounds=r.bounds.tolist(), lp_bounds=r.lp.bounds.tolist(),
                      working_set=r.details.working_set,
                      peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)))
"""


def _child(n, seed, config, limit, base_dir):
    # "python -c" puts the working directory first on sys.path: its hammerbound is imported
    cwd = base_dir if config == "base" else C.ROOT
    proc = subprocess.run([sys.executable, "-c", _CHILD, str(n), str(seed), str(limit)],
                          capture_output=True, text=True, cwd=cwd)
    row = {"N": n, "seed": seed, "config": config, "time_limit": limit,
           "returncode": proc.returncode}
    if proc.returncode == 0:
        row.update(json.loads(proc.stdout.strip().splitlines()[-1]))
        b, lp = np.array(row["bounds"]), np.array(row["lp_bounds"])
        row["width_vs_lp"] = float(np.median((b[:, 1] - b[:, 0]) / (lp[:, 1] - lp[:, 0])))
    else:
        row["error"] = proc.stderr.strip().splitlines()[-1:] if proc.stderr else []
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--short", type=int, nargs="*", default=[120, 300])
    ap.add_argument("--long", type=int, nargs="*", default=[1000, 3000])
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--time-limit", type=float, default=120.0)
    ap.add_argument("--base", default="23a7c43", help="git revision to compare with")
    args = ap.parse_args(argv)
    rows = []
    plan = [(n, "none") for n in args.short] + [(n, args.time_limit) for n in args.long]
    with tempfile.TemporaryDirectory() as base_dir:
        archive = subprocess.run(["git", "archive", args.base, "hammerbound", "benchmarks"],
                                 cwd=C.ROOT, capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", base_dir], input=archive, check=True)
        for n, limit in plan:
            for seed in range(args.seeds):
                for config in ("current", "base"):
                    row = _child(n, seed, config, limit, base_dir)
                    rows.append(row)
                    print(f"N={n} seed={seed} {config:7s} rc={row['returncode']} "
                          f"cpu={row.get('cpu_s', float('nan')):.1f}s "
                          f"wall={row.get('wall_s', float('nan')):.1f}s "
                          f"nodes={sum(row.get('nodes', []))} "
                          f"width/LP={row.get('width_vs_lp', float('nan')):.3f} "
                          f"survived={len(row.get('crashes_survived', []))} "
                          f"{sorted(set(row.get('statuses', [])))}", flush=True)
    C.write_json({"environment": C.environment(), "args": vars(args), "rows": rows},
                 C.RESULTS / "output_error_lps.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
