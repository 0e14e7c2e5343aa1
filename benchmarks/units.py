"""The same record in other units: time and intervals of stage 2 and of one record.

    python -m benchmarks units [--no-units] [--tag before] [--one-record-limit 60]

Stage 2: the chapter example's PRBS record (N = 300, Delta eta = 0.05, seed 0, inner signal
known to +-0.003) as an EIV problem with the input times ``sx`` and the output times
``sy`` (``b_j`` and the gain times ``g = sy / sx``, a priori box ``|b_j| <= 1e3 |g|``), by the
LP and the exact method. One record: a random-step record of the chapter's system
(N = 150, Delta eta = 0.05, uniform noise, seed 0, ``benchmarks/_record_sim.py``) with ``u``
times ``su`` and ``y`` times ``sy``, by the exact one-record method (``time_limit`` per end).
Each row: wall time, widths in the record's first units (divided by the unit factors),
the largest difference of a bound from the first unit system's divided by the exact
method's tolerance ``1e-4 max(1, |bound|)``, the statuses, whether the truth is inside.

``--no-units`` runs the code as it was before the search units (``Units.of`` and
``RecordUnits.of`` replaced by identities), with a total budget per fit
(``--budget``, 600 s) since a fit could run for over 40 minutes. Writes
``results/units[_tag].json``.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import hammerbound as hb
from benchmarks import _common as C
from benchmarks import _record_sim as S
from hammerbound.relaxations.problem import EIVProblem

STAGE2_UNITS = [(1.0, 1.0), (1e3, 1e-3), (1e-4, 1e4), (100.0, 1e-3)]
RECORD_UNITS = [(1.0, 1.0), (100.0, 1e-3), (1.0, 1e-3)]
TOL = 1e-4


def _no_units():
    """Replace the search units by identities (the code before them)."""
    from hammerbound.joint import bounds as JB
    from hammerbound.joint.units import RecordUnits
    from hammerbound.relaxations import lp as LP
    from hammerbound.relaxations.exact import bnb as BNB
    from hammerbound.relaxations.units import Units

    class _U(Units):
        @classmethod
        def of(cls, problem, b_bounds=None):
            return Units(1.0, 1.0, problem.na)

    class _R(RecordUnits):
        @classmethod
        def of(cls, problem):
            return RecordUnits(1.0, 1.0)

    LP.Units, BNB.Units, JB.RecordUnits = _U, _U, _R


def _stage2_rows(budget):
    ex = hb.chapter_example(0.05, N=300, random_state=0)
    x, y, theta = ex.prbs.x, ex.prbs.y, ex.theta_true
    rows, ref = [], {}
    for sx, sy in STAGE2_UNITS:
        g = sy / sx
        box = np.array([[-2.0, 2.0], [-1.0, 1.0]] + [[-1e3 * abs(g), 1e3 * abs(g)]] * 2)
        pr = EIVProblem(y * sy, x * sx, input_bound=0.003 * abs(sx), output_bound=0.05 * sy,
                        na=2, nb=2, steady_state_gain=g, theta_box=box)
        f = np.r_[1.0, 1.0, g, g]
        for method in ("lp", "exact"):
            load0, t = C.loadavg(), time.perf_counter()
            if method == "lp":
                res = hb.relaxations.lp_bounds(pr)
            else:
                res = hb.relaxations.exact_bounds(pr, tol=TOL, total_time_limit=budget)
            wall = time.perf_counter() - t
            rows.append(_row("stage 2", method, (sx, sy), res.bounds / f[:, None], theta,
                             [i.status for i in res.infos], wall, load0, ref))
    return rows


def _record_rows(limit, budget):
    u, y = S.record("steps", 150, 0.05, "uniform", 0)
    truth = np.concatenate([S.THETA, S.GAMMA])
    rows, ref = [], {}
    for su, sy in RECORD_UNITS:
        lin = hb.LinearEIVSetEstimator(na=2, nb=2, nk=1, output_bound=0.05 * sy,
                                       method="exact", time_limit=limit,
                                       total_time_limit=budget)
        load0, t = C.loadavg(), time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ident = hb.HammersteinBacklashIdentifier(linear=lin).fit(u * su, y * sy)
        wall = time.perf_counter() - t
        f = np.r_[np.ones(4), sy / su, su, sy / su, su]
        b = np.vstack([ident.theta_bounds_, ident.gamma_bounds_]) / f[:, None]
        rows.append(_row("one record", "exact", (su, sy), b, truth,
                         [i.status for i in ident.bound_info_], wall, load0, ref))
    return rows


def _row(part, method, units, bounds, truth, statuses, wall, load0, ref):
    """One row; ``ref`` keeps the first unit system's bounds per method."""
    first = ref.setdefault(method, bounds)
    tol = TOL * np.maximum(1.0, np.abs(first))
    with np.errstate(invalid="ignore"):
        d = np.where(np.isfinite(first), np.abs(bounds - first) / tol, 0.0)
    inside = bool(np.all((bounds[:, 0] <= truth * (1 + 1e-12) + 1e-12)
                         & (truth <= bounds[:, 1] * (1 + 1e-12) + 1e-12)))
    row = {"part": part, "method": method, "units": list(units), "wall_s": wall,
           "widths": (bounds[:, 1] - bounds[:, 0]).tolist(), "bounds": bounds.tolist(),
           "diff_over_tol": float(np.max(d)), "statuses": sorted(set(statuses)),
           "truth_inside": inside, "loadavg_start": load0}
    C.log(f"{part:10s} {method:5s} units {units}: {wall:7.1f} s, diff/tol "
          f"{row['diff_over_tol']:.2f}, statuses {row['statuses']}, truth inside {inside}")
    return row


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--no-units", action="store_true")
    p.add_argument("--tag", default="")
    p.add_argument("--one-record-limit", type=float, default=60.0)
    p.add_argument("--budget", type=float, default=600.0)
    args = p.parse_args(argv)
    if args.no_units:
        _no_units()
    rows = _stage2_rows(args.budget) + _record_rows(args.one_record_limit, args.budget)
    name = f"units{'_' + args.tag if args.tag else ''}.json"
    C.write_json({"environment": C.environment(), "no_units": args.no_units,
                  "budget_s": args.budget, "rows": rows}, C.RESULTS / name)
    return 0


def report_section() -> str:
    """The table of ``results/units.json`` (and ``units_before.json`` if present)."""
    out = []
    for tag, what in (("", "with the search units"), ("_before", "before them")):
        path = C.RESULTS / f"units{tag}.json"
        if not path.exists():
            continue
        j = C.read_json(path)
        body = [[r["part"], r["method"], f"x{r['units'][0]:g}, y{r['units'][1]:g}",
                 f"{r['wall_s']:.1f} s", " ".join(f"{w:.4g}" for w in r["widths"]),
                 f"{r['diff_over_tol']:.2f}", ", ".join(r["statuses"]),
                 "yes" if r["truth_inside"] else "**no**", r["loadavg_start"]]
                for r in j["rows"]]
        out.append(f"Code {what} (`results/units{tag}.json`, total budget per fit "
                   f"{j['budget_s']:g} s):\n\n" + C.markdown_table(
                       ["part", "method", "units (input, output)", "time", "widths",
                        "diff/tol", "statuses", "truth inside", "load"], body))
    return "\n\n".join(out) + "\n" if out else ""


if __name__ == "__main__":
    raise SystemExit(main())
