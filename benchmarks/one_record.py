"""One ordinary record (issue 26): soundness, tightness against the two-stage method, speed.

    python -m benchmarks.one_record --part soundness [--quick] [--n-jobs 2] [--budget S]
    python -m benchmarks.one_record --part tightness [--quick]
    python -m benchmarks.one_record --part speed [--quick]
    python -m benchmarks.one_record --part excitation

**soundness** -- the chapter's system simulated by ``benchmarks/_record_sim.py`` (own play
operator and recursion; the package's simulator is not used for truths): random-step
records (levels uniform in [-2, 2], holds of 3-20 samples), a sine sweep and a multilevel
PRBS; N = 300 and 1000; output bound 0.005, 0.05, 0.3; noise uniform in the bound and
exactly at +-bound (random signs); ``--seeds`` seeds per configuration (6: 216 runs).
Every run is a fit of the identifier's one-record path (``na = nb = 2, nk = 1``, default a
priori backlash box). ``method="lp"`` for every run except the *exact subset*: seed 0 of
every N = 300 configuration (``--exact-N``, ``--exact-seeds``; ``--exact-end-limit`` S
stops each end's search after S s with status "limit", a certified outer bound, and the
witnesses found so far; ``--time-limit`` S stops every fit after S s, with the certified
outer bounds it has then, maybe infinite ones, which are counted). Per run: is the truth inside
every interval (infinite ends count as inside, and are counted), and for the exact runs is
every witness verified by ``_record_sim.noise_excess`` (own backlash simulation + own LP:
noise within the bound plus ``WITNESS_TOL = 1e-7``, unit gain within 1e-6, the witness's
parameter inside its interval). An ``EmptyFeasibleSetError`` on such data is a soundness
failure (the truth is feasible) and is recorded as one. Runs go over ``--n-jobs``
processes (joblib, one fit per process), the results file is rewritten after every batch
and a re-run resumes from it; ``--budget`` (s) stops starting new batches.

**tightness** -- median width per parameter over seeds: the two-stage method on the
chapter's experiment (``hb.chapter_example``: 2 M steady-state points, M = 50, and a PRBS
of N_prbs = 100 samples) vs the one-record path on one random-step record of 2 M + N_prbs
samples, same output bound, same method (``--method``).

**excitation** -- the stage-2 theta set of every signal given its *true* inner signal:
how much the record itself says about the linear block.

**speed** -- wall time of one fit of a random-step record per N, output bound, seed and
method (``--n-jobs`` processes), with the statuses (``"limit"`` ends are certified outer bounds).

The fits call :func:`hammerbound.hammerstein.one_record.fit_one_record`, which is what
``HammersteinBacklashIdentifier(procedure="one-record").fit`` runs (``fit(...,
identifier=True)`` goes through the identifier itself).
"""

from __future__ import annotations

import argparse
import itertools
import time
import warnings

import numpy as np

try:
    from benchmarks import _common as C
    from benchmarks import _record_sim as S
except ImportError:  # run as a script
    import _common as C
    import _record_sim as S

PARAMS = ("ml", "cl", "mr", "cr", "a1", "a2", "b1", "b2")
TRUTH = np.concatenate([S.GAMMA, S.THETA])


# ------------------------------------------------------------------ one fit
def fit(u, y, deta, method, *, n_jobs=1, identifier=False, time_limit=None,
        end_time_limit=None):
    """Bounds (8, 2) in PARAMS order, statuses, infos (with witnesses), warnings, seconds.

    ``time_limit``: whole fit (s); ``end_time_limit``: per interval end of the exact
    search (an end stopped there has status "limit": a certified outer bound)."""
    import hammerbound as hb

    kw = {} if end_time_limit is None else {"time_limit": end_time_limit}
    lin = hb.LinearEIVSetEstimator(output_bound=deta, na=2, nb=2, nk=1, method=method,
                                   n_jobs=n_jobs, total_time_limit=time_limit, **kw)
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if identifier:
            idf = hb.HammersteinBacklashIdentifier(linear=lin, procedure="one-record").fit(u, y)
            gb, tb, infos = idf.gamma_bounds_, idf.theta_bounds_, idf.bound_info_
        else:
            from hammerbound.hammerstein.one_record import fit_one_record

            f = fit_one_record(lin, hb.IOData(u, y))
            gb, tb, infos = f.gamma_bounds, f.theta_bounds, f.result.infos
    sec = time.perf_counter() - t0
    from hammerbound.exceptions import NotIdentifiedWarning

    notid = [str(w.message) for w in caught if issubclass(w.category, NotIdentifiedWarning)]
    return np.vstack([gb, tb]), [i.status for i in infos], infos, notid, sec


def check_witnesses(u, y, deta, infos):
    """Independent check of every witness: (number checked, number failed, worst excess)."""
    n = bad = 0
    worst = 0.0
    for info in infos:
        w = getattr(info, "point", None)
        if w is None:
            continue
        n += 1
        th, ga = np.asarray(w.theta), np.asarray(w.gamma)
        exc = S.noise_excess(u, y, deta, th, ga, float(w.z0))
        worst = max(worst, exc)
        vec = np.concatenate([ga, th])
        k = PARAMS.index(info.param)
        inside = info.bound - 1e-9 * max(1, abs(info.bound)) <= vec[k] if info.sense == "min" \
            else vec[k] <= info.bound + 1e-9 * max(1, abs(info.bound))
        if not (exc <= S.WITNESS_TOL and S.gain_error(th) <= 1e-6 and inside):
            bad += 1
    return n, bad, worst


def soundness_run(cfg, end_time_limit=None, time_limit=None):
    """One run of the plan; ``time_limit`` (s) stops the whole fit (certified outer bounds,
    maybe infinite: counted as ``infinite_ends``)."""
    signal, N, deta, noise, seed, method = cfg
    from hammerbound.exceptions import EmptyFeasibleSetError

    u, y = S.record(signal, N, deta, noise, seed)
    row = {"signal": signal, "N": N, "deta": deta, "noise": noise, "seed": seed,
           "method": method, "loadavg": C.loadavg(),
           "end_time_limit": end_time_limit if method == "exact" else None,
           "time_limit": time_limit}
    t0 = time.perf_counter()
    try:
        bounds, statuses, infos, notid, sec = fit(
            u, y, deta, method, time_limit=time_limit,
            end_time_limit=end_time_limit if method == "exact" else None)
    except EmptyFeasibleSetError as exc:
        row.update(error=f"EmptyFeasibleSetError: {exc}", inside=False,
                   seconds=time.perf_counter() - t0)
        return row
    except Exception as exc:  # noqa: BLE001 - recorded, never hidden
        row.update(error=f"{type(exc).__name__}: {exc}", inside=None,
                   seconds=time.perf_counter() - t0)
        return row
    inside = (TRUTH >= bounds[:, 0]) & (TRUTH <= bounds[:, 1])
    n_w, bad_w, worst = check_witnesses(u, y, deta, infos)
    row.update(seconds=sec, inside=bool(inside.all()),
               outside=[p for p, ok in zip(PARAMS, inside, strict=True) if not ok],
               lower=bounds[:, 0].tolist(), upper=bounds[:, 1].tolist(),
               infinite_ends=int(np.sum(~np.isfinite(bounds))), not_identified=notid,
               statuses=sorted(set(statuses)), witnesses=n_w, witnesses_failed=bad_w,
               witness_worst_excess=worst)
    return row


def _key(r):
    return (r["signal"], r["N"], r["deta"], r["noise"], r["seed"], r["method"])


def soundness_plan(args):
    plan = []
    for signal, N, deta, noise, seed in itertools.product(
            args.signals, args.N, args.levels, ("uniform", "bound"), range(args.seeds)):
        exact = N in args.exact_N and seed < args.exact_seeds
        plan.append((signal, N, deta, noise, seed, "exact" if exact else "lp"))
    # cheap runs first (N, then method), so a budget stop leaves the costly ones
    return sorted(plan, key=lambda c: (c[1], c[5] == "exact", c[4], c[0], c[2], c[3]))


def run_soundness(args):
    from joblib import Parallel, delayed

    path = C.RESULTS / f"one_record_soundness{args.tag}.json"
    done = {}
    if path.exists():
        done = {_key(r): r for r in C.read_json(path)["rows"] if "error" not in r
                or r["error"].startswith("EmptyFeasibleSetError")}
    todo = [c for c in soundness_plan(args) if c not in done]
    env = C.environment()
    t0 = time.perf_counter()
    C.log(f"soundness: {len(done)} done, {len(todo)} to run")
    def jobs():
        for c in todo:  # a budget stop ends the plan; the runs under way finish
            if args.budget is not None and time.perf_counter() - t0 > args.budget:
                C.log("budget used; re-run to resume")
                return
            yield delayed(soundness_run)(c, args.exact_end_limit, args.time_limit)

    # every finished run is saved at once (a killed run loses only the runs under way)
    for r in Parallel(n_jobs=args.n_jobs, return_as="generator_unordered")(jobs()):
        done[_key(r)] = r
        C.log(f"{_key(r)}: inside={r.get('inside')} {r.get('seconds', 0):.1f} s "
              f"witnesses {r.get('witnesses', 0)} failed {r.get('witnesses_failed', 0)}"
              + (f" ERROR {r['error'][:80]}" if "error" in r else ""))
        C.write_json({"environment": env, "rows": list(done.values())}, path)
    rows = list(done.values())
    C.write_csv([{k: v for k, v in r.items() if k not in ("not_identified",)} for r in rows],
                path.with_suffix(".csv"))
    summarise_soundness(rows)


def summarise_soundness(rows):
    groups = {}
    for r in rows:
        groups.setdefault((r["N"], r["method"], r["signal"]), []).append(r)
    for (N, m, sig), rs in sorted(groups.items()):
        sec = [r["seconds"] for r in rs if "seconds" in r]
        print(f"N={N} {m} {sig}: {len(rs)} runs, truth inside "
              f"{sum(r.get('inside') is True for r in rs)}, errors {sum('error' in r for r in rs)}, "
              f"infinite ends {sum(r.get('infinite_ends', 0) for r in rs)} of {16 * len(rs)}, "
              f"witnesses {sum(r.get('witnesses', 0) for r in rs)} "
              f"(failed {sum(r.get('witnesses_failed', 0) for r in rs)}), time median "
              f"{np.median(sec):.1f} s max {np.max(sec):.1f} s")


# ------------------------------------------------------------------ tightness
def tightness_run(seed, deta, M, n_prbs, method, time_limit=None):
    """One seed: widths of both methods (the one-record fit stopped after ``time_limit`` s
    keeps certified outer bounds on the ends it stops, listed in its statuses)."""
    import hammerbound as hb

    ex = hb.chapter_example(output_bound=deta, N=n_prbs, random_state=seed,
                            amplitudes=np.linspace(0.25, 2.5, M))  # the chapter's for M = 50
    lin = hb.LinearEIVSetEstimator(output_bound=deta, na=2, nb=2, method=method, n_jobs=1)
    t0 = time.perf_counter()
    idf = hb.HammersteinBacklashIdentifier(backlash=hb.BacklashSetEstimator(deta), linear=lin,
                                           procedure="two-stage")
    idf.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    two = np.vstack([idf.gamma_bounds_, idf.theta_bounds_])
    t_two = time.perf_counter() - t0
    u, y = S.record("steps", 2 * M + n_prbs, deta, "uniform", 1000 + seed)
    one, statuses, _, notid, t_one = fit(u, y, deta, method, time_limit=time_limit)
    return {"seed": seed, "deta": deta, "M": M, "N_prbs": n_prbs, "method": method,
            "two_stage_width": (two[:, 1] - two[:, 0]).tolist(),
            "one_record_width": (one[:, 1] - one[:, 0]).tolist(),
            "two_stage_inside": bool(np.all((TRUTH >= two[:, 0]) & (TRUTH <= two[:, 1]))),
            "one_record_inside": bool(np.all((TRUTH >= one[:, 0]) & (TRUTH <= one[:, 1]))),
            "two_stage_s": t_two, "one_record_s": t_one, "one_record_statuses":
            sorted(set(statuses)), "one_record_optimal_ends":
            sum(st == "optimal" for st in statuses), "time_limit": time_limit,
            "not_identified": notid, "loadavg": C.loadavg()}


def run_tightness(args):
    from joblib import Parallel, delayed

    path = C.RESULTS / f"one_record_tightness{args.tag}.json"
    rows = []
    if path.exists():
        rows = C.read_json(path)["rows"]
    have = {(r["seed"], r["deta"], r["method"]) for r in rows}
    plan = [(s, d) for d in args.levels for s in range(args.seeds)
            if (s, d, args.method) not in have]
    env = C.environment()
    for i in range(0, len(plan), args.n_jobs):
        rows += Parallel(n_jobs=args.n_jobs)(
            delayed(tightness_run)(s, d, args.M, args.N_prbs, args.method, args.time_limit)
            for s, d in plan[i: i + args.n_jobs])
        C.write_json({"environment": env, "rows": rows}, path)
        C.log(f"tightness: {len(rows)} runs")
    table = tightness_table(rows)
    C.write_csv(table, path.with_suffix(".csv"))
    for r in table:
        print(r)


def tightness_table(rows):
    out = []
    groups = {}
    for r in rows:
        groups.setdefault((r["deta"], r["method"]), []).append(r)
    for (deta, method), rs in sorted(groups.items()):
        two = np.median([r["two_stage_width"] for r in rs], axis=0)
        one = np.median([r["one_record_width"] for r in rs], axis=0)
        for k, p in enumerate(PARAMS):
            out.append({"deta": deta, "method": method, "param": p, "seeds": len(rs),
                        "two_stage_median_width": two[k], "one_record_median_width": one[k],
                        "ratio": one[k] / two[k] if two[k] > 0 else np.inf})
    return out


# ------------------------------------------------------------------ excitation
def run_excitation(args):
    """How much each record's input excites the linear block: the stage-2 set of theta
    with the *true* inner signal given (input error 1e-6), per signal and output bound,
    ``method="lp"`` and ``"exact"`` (``--time-limit`` per fit). A record whose theta set is
    wide even then cannot give narrow one-record bounds, whatever the backlash step does."""
    import hammerbound as hb

    path = C.RESULTS / f"one_record_excitation{args.tag}.json"
    rows = []
    for signal, deta, method in itertools.product(args.signals, args.levels, ("lp", "exact")):
        u, y = S.record(signal, args.N[0], deta, "uniform", 1)
        x = S.play(u, *S.GAMMA)
        est = hb.LinearEIVSetEstimator(output_bound=deta, na=2, nb=2, nk=1, method=method,
                                       total_time_limit=args.time_limit, on_failure="raise")
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            est.fit(x, y, input_bound=1e-6)
        b = np.asarray(est.bounds_)
        rows.append({"signal": signal, "N": args.N[0], "deta": deta, "method": method,
                     "width": (b[:, 1] - b[:, 0]).tolist(),
                     "inside": bool(np.all((S.THETA >= b[:, 0]) & (S.THETA <= b[:, 1]))),
                     "seconds": time.perf_counter() - t0, "loadavg": C.loadavg()})
        C.log(f"excitation {signal} deta={deta} {method}: widths "
              f"{np.round(rows[-1]['width'], 4).tolist()}")
    C.write_json({"environment": C.environment(), "rows": rows}, path)


# ------------------------------------------------------------------ speed
def gaps_over_width(b, infos):
    """Per end (PARAMS order, min then max): the gap between the certified bound and the
    best verified value, over the interval's width (0 at an optimal end; ``None`` for an
    end without a witness, e.g. the relaxation's)."""
    by_end = {(i.param, i.sense): i for i in infos}
    out = []
    for k, name in enumerate(PARAMS):
        w = b[k, 1] - b[k, 0]
        for sense in ("min", "max"):
            g = getattr(by_end.get((name, sense)), "gap", None)
            out.append(None if g is None or not np.isfinite(g) or not np.isfinite(w)
                       else float(g / max(w, 1e-300)))
    return out


def run_speed(args):
    """Wall time per (N, output bound, seed, method) on random-step records, with the
    statuses of the 16 ends, the nodes and the widths (``--time-limit`` bounds each fit:
    the ends it stops keep certified outer bounds, status "limit")."""
    path = C.RESULTS / f"one_record_speed{args.tag}.json"
    rows = C.read_json(path)["rows"] if path.exists() else []
    hull = args.hull_rows == "on"
    have = {(r["N"], r.get("deta", 0.05), r.get("seed", 7), r["method"]) for r in rows
            if r.get("pricing", "steepest edge") == args.pricing
            and r.get("hull_rows", False) == hull}
    if args.pricing == "steepest edge":  # the ablation: HiGHS's default dual pricing
        from hammerbound.joint import relaxation

        if args.n_jobs != 1:  # worker processes would import the package's options
            raise SystemExit("--pricing 'steepest edge' needs --n-jobs 1")

        relaxation.LP_OPTIONS.pop("simplex_dual_edge_weight_strategy", None)
    if not hull:  # the ablation: no envelope rows of the play operator
        from hammerbound.joint import relaxation

        if args.n_jobs != 1:
            raise SystemExit("--hull-rows off needs --n-jobs 1")
        relaxation.HULL_ROWS = False
    env = C.environment()
    for N, deta, seed, method in itertools.product(args.N, args.levels, range(args.seeds),
                                                   args.methods):
        if (N, deta, seed, method) in have:
            continue
        u, y = S.record("steps", N, deta, "uniform", seed)
        b, statuses, infos, notid, sec = fit(u, y, deta, method, n_jobs=args.n_jobs,
                                             time_limit=args.time_limit)
        rows.append({"N": N, "deta": deta, "seed": seed, "method": method,
                     "n_jobs": args.n_jobs, "seconds": sec,
                     "statuses": sorted(set(statuses)),
                     "optimal_ends": sum(s == "optimal" for s in statuses),
                     "nodes": int(sum(getattr(i, "nodes", 0) or 0 for i in infos)),
                     "width": (b[:, 1] - b[:, 0]).tolist(),
                     "gap_over_width": gaps_over_width(b, infos),
                     "inside": bool(np.all((TRUTH >= b[:, 0]) & (TRUTH <= b[:, 1]))),
                     "not_identified": notid,
                     "loadavg": C.loadavg(), "time_limit": args.time_limit,
                     "pricing": args.pricing, "hull_rows": hull})
        C.log(f"speed N={N} deta={deta} seed={seed} {method}: {sec:.1f} s "
              f"{sorted(set(statuses))}")
        C.write_json({"environment": env, "rows": rows}, path)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=("soundness", "tightness", "speed", "excitation"),
                    required=True)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--n-jobs", type=int, default=2)
    ap.add_argument("--budget", type=float, default=None)
    ap.add_argument("--seeds", type=int, default=None)
    ap.add_argument("--N", type=int, nargs="+", default=None)
    ap.add_argument("--levels", type=float, nargs="+", default=None)
    ap.add_argument("--signals", nargs="+", default=list(S.SIGNALS))
    ap.add_argument("--exact-N", type=int, nargs="*", default=[300])
    ap.add_argument("--exact-seeds", type=int, default=1)
    ap.add_argument("--exact-end-limit", type=float, default=None,
                    help="soundness: time limit (s) per interval end of the exact runs")
    ap.add_argument("--method", default="lp")
    ap.add_argument("--methods", nargs="+", default=["lp", "exact"])
    ap.add_argument("--M", type=int, default=50)
    ap.add_argument("--N-prbs", type=int, default=100)
    ap.add_argument("--time-limit", type=float, default=None)
    ap.add_argument("--tag", default="")
    ap.add_argument("--pricing", choices=("devex", "steepest edge"), default="devex",
                    help="speed: dual pricing of the one-record LPs (the package uses devex; "
                         "'steepest edge' is HiGHS's default, for the ablation)")
    ap.add_argument("--hull-rows", choices=("on", "off"), default="on",
                    help="speed: the play operator's envelope rows (joint.hull_rows; 'off' "
                         "for the ablation, with --n-jobs 1)")
    args = ap.parse_args(argv)
    if args.part == "soundness":
        args.seeds = args.seeds or (2 if args.quick else 6)
        args.N = args.N or ([300] if args.quick else [300, 1000])
        args.levels = args.levels or [0.005, 0.05, 0.3]
        args.tag = args.tag or ("_quick" if args.quick else "")
        run_soundness(args)
    elif args.part == "tightness":
        args.seeds = args.seeds or (3 if args.quick else 10)
        args.levels = args.levels or ([0.05] if args.quick else [0.005, 0.05, 0.3])
        args.tag = args.tag or ("_quick" if args.quick else "")
        run_tightness(args)
    elif args.part == "excitation":
        args.N = args.N or [300]
        args.levels = args.levels or [0.005, 0.05, 0.3]
        args.time_limit = args.time_limit or 120.0
        run_excitation(args)
    else:
        args.N = args.N or ([300] if args.quick else [300, 1000])
        args.seeds = args.seeds or (1 if args.quick else 2)
        args.levels = args.levels or ([0.05] if args.quick else [0.005, 0.05, 0.3])
        args.tag = args.tag or ("_quick" if args.quick else "")
        run_speed(args)


if __name__ == "__main__":
    main()
