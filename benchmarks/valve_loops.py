"""Real plant data: 80 industrial valve loops, one-record backlash bounds, a fixed stiction rule.

    python -m benchmarks.valve_loops [--n-jobs 2] [--limit K]

Data: ``../shared/data/valve_loops/`` beside the repository (80 closed control loops, OP ->
PV, experts' labels by folder; read in place, never copied). The rule below was written
and committed *before* the benchmark was run on any loop; it reads only the OP and PV
columns (never file names or tag names); the folder label is attached after every call
is made, for the confusion table only.

The rule (fixed before any result was seen)
-------------------------------------------
Per loop:

1. **Data.** OP (``u``) and PV (``y``) columns. *Degenerate* if OP or PV is constant over
   the record or over the window below (``ptp == 0``): reported as "degenerate", no call.
2. **Window.** Budget: every ``k``-th sample from the first, ``k = max(1, N // 100)`` (751
   samples at 10 s -> 108 samples at 70 s; the 126-sample loop is used whole). No
   anti-alias filter: the linear model of the decimated record is an approximation whose
   error the bounds absorb (it makes both bounds larger, not the rule unsound).
3. **Scaling.** ``u = OP - mean(OP)`` (OP units: dead bands are in OP units);
   ``y = (PV - mean(PV)) / std(PV)``: output-error bounds are in units of the PV's
   standard deviation. The offset is removed by this centring (not searched). The model's
   convention ``c_l, c_r >= 0`` puts ``u = 0`` (the mean OP) inside the dead band.
4. **Linear bound.** Linear output-error model ``A(q) y = B(q) u`` with ``na = nb = 2``
   (contains every order <= 2), exact input, delay ``nk`` in ``{0, 1, 2}`` (decimated
   samples; ``nk = 0`` adds the direct term ``b_0``: at 70 s a fast loop is nearly
   static), no gain constraint. For each delay, a geometric bisection (6 steps) of the
   output-error bound ``delta`` on ``[1e-3, max|y| * 1.001]`` with
   :func:`hammerbound.relaxations.consistency` (3 s per decision): ``lin_lo(nk)`` is the
   largest bound certified *empty*, ``lin_hi(nk)`` the smallest not certified empty (a
   verified witness, or "undecided" at the time limit: counted on the upper side, and
   counted in the results). ``lin_lo = min_nk lin_lo(nk)`` is a certified lower bracket
   of the smallest bound at which some linear model of orders <= 2 and delay 0-2 is
   consistent; ``nk*`` is the delay of the smallest ``lin_hi`` (ties: smallest
   ``lin_lo``).
5. **Sign.** The unit-gain backlash model needs a positive process gain: if the
   least-squares equation-error fit (na = nb = 2, ``nk*``) has ``B(1) / A(1) < 0``, ``y``
   is negated (a reverse-acting loop).
6. **Backlash + linear at ``delta* = lin_lo / 2``** (half the error no linear model
   reaches): the one-record identifier's path
   (:func:`hammerbound.hammerstein.one_record.fit_one_record`, ``na = nb = 2``, ``nk*``,
   ``method="lp"`` -- the relaxation's certified outer bounds; exact is too slow for 80
   loops -- default a priori backlash box, 90 s deadline: what OBBT has certified by
   then). Outcomes: *empty* (certified:
   no backlash + linear model explains the record within ``delta*``), or the certified
   lower bound ``db_lo = c_l_lo + c_r_lo`` of the dead band ``c_l + c_r`` (OP units)
   over every model that does.
7. **Call.** "stiction" iff the set at ``delta*`` is not certified empty and
   ``db_lo > 0.01 * ptp(OP window)`` (a guaranteed dead band of more than 1 % of the OP
   range); otherwise "no stiction". A loop where a step fails with an error is reported
   as "error" (counted as "no stiction" in the confusion table and listed).

The smallest bound at which backlash + linear is consistent is not bisected (budget): at
``delta*`` the benchmark reports only the bracket side it certifies (empty: the smallest
bound is above ``delta*``).

Closed loop: bounded-error identification needs no independence between the noise and the
input, so the guarantees hold for a record taken in closed loop (the controller makes OP
depend on past noise; the bounds only assume ``|eta_t| <= delta`` on every sample). The
model class (unit-gain linear block, backlash with ``c >= 0`` around the mean OP,
delay <= 2 decimated samples) is itself an assumption that plant data need not satisfy;
stiction also has a stick-slip jump that a backlash does not model.

Loops are processed in a fixed random order (seed 0), so a run stopped early (budget) has
analysed a random subset of both labels; it resumes from ``benchmarks/results/valve_loops.json``
and writes ``valve_loops.csv`` and the confusion table over the loops analysed so far.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

DATA = C.ROOT.parent / "shared" / "data" / "valve_loops"
OUT_JSON = C.RESULTS / "valve_loops.json"
OUT_CSV = C.RESULTS / "valve_loops.csv"
WINDOW = 100
DELAYS = (0, 1, 2)
BISECT_STEPS = 6
DECISION_S = 3.0
FIT_DEADLINE_S = 90.0
DEADBAND_FRACTION = 0.01


# ------------------------------------------------------------------ data
def read_loop(path):
    """``(op, pv, dt)`` of one loop file (columns 2 and 3 of the data rows; line 2: dt)."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        lines = fh.read().splitlines()
    dt = float(lines[1].split("\t")[1])
    rows = [ln.split("\t") for ln in lines[5:] if ln.strip()]
    op = np.array([float(r[1]) for r in rows])
    pv = np.array([float(r[2]) for r in rows])
    return op, pv, dt


def loop_files():
    """``(key, path, label)`` of every loop; ``key`` is an anonymous index."""
    out = []
    for label, folder in (("stiction", "stiction_data"), ("no stiction", "non-stiction_data")):
        for p in sorted((DATA / folder).glob("*.txt")):
            out.append((p, label))
    return [(f"loop{i:02d}", p, lab) for i, (p, lab) in enumerate(out)]


def window(op, pv):
    k = max(1, op.size // WINDOW)
    return op[::k], pv[::k], k


# ------------------------------------------------------------------ step 4: linear
def _decide(y, u, delta, nk):
    from hammerbound.relaxations import EIVProblem, consistency

    pr = EIVProblem(y, u, 0.0, delta, 2, 2, nk=nk)
    return consistency(pr, time_limit=DECISION_S).status


def linear_bracket(y, u, nk):
    """Geometric bisection: (largest certified-empty bound, smallest bound not certified
    empty, number of undecided steps)."""
    lo, hi = 1e-3, float(np.max(np.abs(y))) * 1.001
    if _decide(y, u, lo, nk) != "empty":
        return 0.0, lo, 0
    undecided = 0
    for _ in range(BISECT_STEPS):
        mid = float(np.sqrt(lo * hi))
        s = _decide(y, u, mid, nk)
        if s == "empty":
            lo = mid
        else:
            hi = mid
            undecided += s == "undecided"
    return lo, hi, undecided


def ls_gain(y, u, nk):
    """Steady-state gain B(1)/A(1) of the least-squares equation-error fit (na = nb = 2)."""
    lags = np.arange(nk, 3) if nk == 0 else np.arange(nk, nk + 2)
    n0 = max(2, int(lags[-1]))
    t = np.arange(n0, y.size)
    phi = np.column_stack([-y[t - 1], -y[t - 2]] + [u[t - j] for j in lags])
    th = np.linalg.lstsq(phi, y[t], rcond=None)[0]
    a1 = 1.0 + th[0] + th[1]
    return float(np.sum(th[2:]) / a1) if a1 != 0 else np.inf


# ------------------------------------------------------------------ step 6: backlash
def backlash_at(u, y, delta, nk):
    import hammerbound as hb
    from hammerbound.exceptions import EmptyFeasibleSetError
    from hammerbound.hammerstein.one_record import fit_one_record

    lin = hb.LinearEIVSetEstimator(output_bound=delta, na=2, nb=2, nk=nk, method="lp",
                                   total_time_limit=FIT_DEADLINE_S)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            f = fit_one_record(lin, hb.IOData(u, y))
    except EmptyFeasibleSetError:
        return {"set": "empty"}
    g = f.gamma_bounds
    return {"set": "not certified empty", "gamma_lower": g[:, 0].tolist(),
            "gamma_upper": g[:, 1].tolist(), "theta_bounds": f.theta_bounds.tolist(),
            "deadband_lower": float(g[1, 0] + g[3, 0]),
            "unidentified": [n for n, _ in f.unidentified]}


# ------------------------------------------------------------------ the rule
def analyse(key, path):
    """Steps 1-7 for one loop (the label is not read here)."""
    t0 = time.perf_counter()
    op, pv, dt = read_loop(path)
    out = {"key": key, "N": int(op.size), "dt": dt}
    opw, pvw, k = window(op, pv)
    out.update(decimation=k, N_window=int(opw.size))
    if np.ptp(op) == 0 or np.ptp(pv) == 0 or np.ptp(opw) == 0 or np.ptp(pvw) == 0:
        out.update(call="degenerate", why="constant OP or PV", seconds=time.perf_counter() - t0)
        return out
    u = opw - opw.mean()
    y = (pvw - pvw.mean()) / pvw.std()
    brackets = {nk: linear_bracket(y, u, nk) for nk in DELAYS}
    nk = min(DELAYS, key=lambda d: (brackets[d][1], brackets[d][0]))
    lin_lo = min(v[0] for v in brackets.values())
    out.update(linear={str(d): list(v) for d, v in brackets.items()}, nk=nk, lin_lo=lin_lo,
               lin_hi=brackets[nk][1], undecided=sum(v[2] for v in brackets.values()),
               op_range=float(np.ptp(opw)))
    gain = ls_gain(y, u, nk)
    if gain < 0:
        y = -y
    out["negated"] = bool(gain < 0)
    if lin_lo <= 0:
        out.update(call="no stiction", why="a linear model is consistent at 1e-3",
                   seconds=time.perf_counter() - t0)
        return out
    delta = lin_lo / 2
    bl = backlash_at(u, y, delta, nk)
    out.update(delta_star=delta, backlash=bl)
    stiction = bl["set"] != "empty" and bl["deadband_lower"] > DEADBAND_FRACTION * out["op_range"]
    out.update(call="stiction" if stiction else "no stiction", seconds=time.perf_counter() - t0)
    return out


def _safe(key, path):
    try:
        return analyse(key, path)
    except Exception as exc:  # noqa: BLE001 - reported per loop, never hidden
        return {"key": key, "call": "error", "why": f"{type(exc).__name__}: {exc}"}


def confusion(rows, labels):
    tab = {(lab, c): 0 for lab in ("stiction", "no stiction")
           for c in ("stiction", "no stiction", "degenerate", "error")}
    for r in rows:
        tab[(labels[r["key"]], r["call"])] += 1
    return tab


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-jobs", type=int, default=2)
    ap.add_argument("--limit", type=int, default=None, help="first K loops (random order)")
    ap.add_argument("--budget", type=float, default=None, help="stop starting loops after S s")
    args = ap.parse_args(argv)
    if not DATA.is_dir():
        raise SystemExit(f"{DATA} not found: the loops are read from ../shared/data/valve_loops/.")
    files = loop_files()
    order = np.random.default_rng(0).permutation(len(files))
    files = [files[i] for i in order][: args.limit]
    done = {}
    if OUT_JSON.exists():
        done = {r["key"]: r for r in C.read_json(OUT_JSON).get("rows", []) if r["call"] != "error"}
    todo = [(k, p) for k, p, _ in files if k not in done]
    env = C.environment()
    t0 = time.perf_counter()
    from joblib import Parallel, delayed

    for i in range(0, len(todo), 4):  # save after every batch (resume)
        if args.budget is not None and time.perf_counter() - t0 > args.budget:
            C.log(f"budget of {args.budget:g} s used: {len(todo) - i} loops left (resume later)")
            break
        batch = Parallel(n_jobs=args.n_jobs)(delayed(_safe)(k, p) for k, p in todo[i: i + 4])
        for r in batch:
            done[r["key"]] = r
            C.log(f"{r['key']}: {r['call']} ({r.get('seconds', 0):.0f} s)")
        C.write_json({"environment": env, "rows": list(done.values())}, OUT_JSON)
    labels = {k: lab for k, _, lab in files}  # attached only now, after every call
    rows = [done[k] for k, _, _ in files if k in done]
    for r in rows:
        r["label"] = labels[r["key"]]
    tab = confusion(rows, labels)
    C.write_json({"environment": env, "rule_constants": {
        "window": WINDOW, "delays": DELAYS, "bisect_steps": BISECT_STEPS,
        "decision_s": DECISION_S, "fit_deadline_s": FIT_DEADLINE_S,
        "deadband_fraction": DEADBAND_FRACTION},
        "rows": rows, "confusion": {f"{a}|{b}": v for (a, b), v in tab.items()},
        "wall_s": time.perf_counter() - t0}, OUT_JSON)
    C.write_csv([{k: v for k, v in r.items() if k not in ("backlash", "linear")} |
                 {"deadband_lower": (r.get("backlash") or {}).get("deadband_lower"),
                  "set_at_delta_star": (r.get("backlash") or {}).get("set")} for r in rows],
                OUT_CSV)
    print("label \\ call     stiction  no-stiction  degenerate  error")
    for lab in ("stiction", "no stiction"):
        print(f"{lab:15s} {tab[(lab, 'stiction')]:9d} {tab[(lab, 'no stiction')]:12d} "
              f"{tab[(lab, 'degenerate')]:11d} {tab[(lab, 'error')]:6d}")


if __name__ == "__main__":
    main()
