"""The one-record sections of docs/benchmarks.md (issue 26): soundness, tightness, speed,
and the valve loops (read by benchmarks/report.py; every number from benchmarks/results/)."""

from __future__ import annotations

import numpy as np

try:
    from benchmarks.report_format import _json, _with_rows
    from benchmarks.report_format import table as _table
except ImportError:  # run as a script
    from report_format import _json, _with_rows
    from report_format import table as _table

PARAMS = ("ml", "cl", "mr", "cr", "a1", "a2", "b1", "b2")


def _env(j):
    e = j.get("environment") or {}
    return (f"_Run {e.get('date')}, {e.get('cpu_count')} CPUs, load average at start "
            f"{(e.get('loadavg_at_start') or ['?'])[0]} (shared machine)._")


def _stopped(r) -> bool:
    """A fit its time limit stopped: it ran to the limit and did not end with every end
    optimal (an exact fit that overran its limit, before the fix of 2026-11-26, with all
    ends optimal, was not stopped)."""
    lim = r.get("time_limit")
    return (lim is not None and r.get("seconds", 0) >= lim - 0.5
            and set(r.get("statuses") or []) != {"optimal"})


def section_soundness():
    parts = []
    for tag in ("", "_n1000", "_s35", "_s36", "_s37", "_s38", "_quick"):
        j = _json(f"one_record_soundness{tag}.json")
        if not j or not j["rows"]:
            continue
        rows = j["rows"]
        groups = {}
        for r in rows:
            groups.setdefault((r["N"], r["method"], r["signal"]), []).append(r)
        body = []
        for (N, m, sig), rs in sorted(groups.items()):
            sec = [r["seconds"] for r in rs if "seconds" in r]
            body.append([N, m, sig, len(rs), sum(r.get("inside") is True for r in rs),
                         sum("error" in r for r in rs),
                         sum(r.get("infinite_ends", 0) > 0 for r in rs),
                         f"{sum(r.get('infinite_ends', 0) for r in rs)}/{16 * len(rs)}",
                         sum(_stopped(r) for r in rs),
                         sum(r.get("witnesses", 0) for r in rs),
                         sum(r.get("witnesses_failed", 0) for r in rs),
                         f"{np.median(sec):.1f}" if sec else "–",
                         f"{np.max(sec):.1f}" if sec else "–"])
        levels = sorted({r["deta"] for r in rows})
        lim = sorted({r.get("end_time_limit") for r in rows if r["method"] == "exact"} - {None})
        fit_lim = sorted({r.get("time_limit") for r in rows} - {None})
        parts.append(
            f"Plan `one_record_soundness{tag}`: {len(rows)} runs (output bounds {levels}, "
            "noise uniform and exactly at ±bound, seeds per configuration as run"
            + (f"; exact runs stopped at {lim} s per interval end, status \"limit\"" if lim
               else "") + (f"; every fit stopped at {fit_lim} s (its bounds then are the "
                           "certified outer bounds it has, maybe infinite)" if fit_lim else "")
            + "). Truth inside = all 8 intervals hold the chapter's parameters "
            "(infinite ends count as inside; runs with any are counted); witnesses are "
            "checked by `benchmarks/_record_sim.py` (own play operator and recursion, own LP: "
            "noise within the bound + 1e-7, unit gain within 1e-6).\n\n"
            + _table(["N", "method", "signal", "runs", "truth inside", "errors",
                      "runs with infinite ends", "infinite ends", "stopped by the time limit",
                      "witnesses", "witnesses failed",
                      "median s", "max s"], body) + "\n\n" + _env(j))
        bad = [r for r in rows if r.get("inside") is not True]
        if bad:
            parts.append(f"**{len(bad)} runs with the truth outside or an error:** " + "; ".join(
                f"{r['signal']} N={r['N']} Δη={r['deta']} {r['noise']} seed {r['seed']} "
                f"{r['method']}: {r.get('error') or r.get('outside')}" for r in bad[:10]))
    return "\n\n".join(parts) + "\n" if parts else ""


def section_tightness():
    parts = []
    for tag in ("", "_quick"):
        j = _json(f"one_record_tightness{tag}.json")
        if not j or not j["rows"]:
            continue
        rows = j["rows"]
        body = []
        for key in sorted({(r["deta"], r["method"]) for r in rows}):
            rs = [r for r in rows if (r["deta"], r["method"]) == key]
            two = np.median([r["two_stage_width"] for r in rs], axis=0)
            one = np.median([r["one_record_width"] for r in rs], axis=0)
            for k, p in enumerate(PARAMS):
                ratio = one[k] / two[k] if two[k] > 0 else np.inf
                body.append([key[0], key[1], p, len(rs), f"{two[k]:.4g}", f"{one[k]:.4g}",
                             f"{ratio:.3g}"])
        r0 = rows[0]
        inside = (sum(r["two_stage_inside"] for r in rows), sum(r["one_record_inside"]
                                                                  for r in rows))
        lim = [r for r in rows if r.get("time_limit") and r["one_record_s"]
               >= r["time_limit"] - 0.5]
        stopped = (f"One-record fits stopped by their time limit of "
                   f"{rows[0]['time_limit']:g} s (widths then are certified outer ones): "
                   + ", ".join(f"Δη = {d}: {sum(r['deta'] == d for r in lim)} of "
                               f"{sum(r['deta'] == d for r in rows)}"
                               for d in sorted({r['deta'] for r in rows}))
                   + ".\n\n") if any(r.get("time_limit") for r in rows) else ""
        parts.append(
            f"Plan `one_record_tightness{tag}`: two-stage = `hb.chapter_example` with M = "
            f"{r0['M']} amplitudes (2M = {2 * r0['M']} steady-state points) and a PRBS of "
            f"N = {r0['N_prbs']}; one record = a random-step record of {2 * r0['M'] + r0['N_prbs']}"
            f" samples; same output bound and method. Median width over seeds; ratio = one "
            f"record / two-stage (issue goal: θ ≤ 1, backlash ≤ 2). Truth inside: two-stage "
            f"{inside[0]}/{len(rows)}, one record {inside[1]}/{len(rows)}.\n\n"
            + _table(["Δη", "method", "parameter", "seeds", "two-stage width",
                      "one-record width", "ratio"], body) + "\n\n" + stopped + _limits(rows)
            + _env(j))
    return "\n\n".join(parts) + "\n" if parts else ""


def _limits(rows):
    """Which exact one-record fits a time limit stopped (their stopped ends keep certified
    outer bounds, so their widths are upper bounds of the exact widths)."""
    ex = [r for r in rows if r["method"] == "exact"]
    if not ex:
        return ""
    full = sum(r.get("one_record_optimal_ends", 0) == 16 for r in ex)
    lims = sorted({r.get("time_limit") for r in ex} - {None})
    return (f"Exact one-record fits with all 16 ends optimal: {full} of {len(ex)}"
            + (f" (time limit {', '.join(f'{v:g}' for v in lims)} s per fit; the other "
               "fits' stopped ends are certified outer bounds)" if lims else "") + ".\n\n")


def section_excitation():
    j = _json("one_record_excitation.json")
    if not j or not j["rows"]:
        return ""
    body = [[r["signal"], r["N"], r["deta"], r["method"],
             " / ".join(f"{w:.4g}" for w in r["width"]), "yes" if r["inside"] else "**no**",
             f"{r['seconds']:.1f}"] for r in j["rows"]]
    return ("`python -m benchmarks.one_record --part excitation`: the stage-2 set of θ of "
            "each signal's record (seed 1, noise uniform) when its *true* inner signal is "
            "given (input error 1e-6): what the record says about the linear block, "
            "whatever the backlash step does.\n\n"
            + _table(["signal", "N", "Δη", "method", "widths a1 / a2 / b1 / b2",
                      "truth inside", "s"], body) + "\n\n" + _env(j) + "\n")


def _gaps(r):
    """Median and largest gap of an exact fit's ends (bound to best verified value) over
    the interval's width; "–" when the run did not record it."""
    g = [v for v in r.get("gap_over_width", []) if v is not None]
    return f"{np.median(g):.3f} / {max(g):.3f}" if g else "–"


def section_speed():
    parts = []
    for tag in ("_s38", "_s38_check", "_s38_long", "_s37", "_s37_hull", "_s36", "_s35",
                "_s35_pricing", "_n300", "_n1000", "", "_quick"):
        j = _json(f"one_record_speed{tag}.json")
        if not j or not j["rows"]:
            continue
        body = [[r["N"], r.get("deta", 0.05), r.get("seed", 7), r["method"],
                 r.get("pricing", "steepest edge"),
                 "on" if r.get("hull_rows", False) else "off", r["n_jobs"],
                 f"{r['seconds']:.1f}", ", ".join(r["statuses"]),
                 r.get("optimal_ends", "–") if r["method"] == "exact" else "–",
                 _gaps(r) if r["method"] == "exact" else "–",
                 r.get("nodes", "–") if r["method"] == "exact" else "–",
                 "–" if r.get("time_limit") is None else f"{r['time_limit']:g}",
                 " ".join(f"{w:.3g}" for w in r["width"][:4]),
                 "yes" if r["inside"] else "**no**", r["loadavg"]]
                for r in j["rows"]]
        parts.append(f"`one_record_speed{tag}`\n\n" + _table(
            ["N", "Δη", "seed", "method", "LP pricing", "hull rows", "jobs", "wall s",
             "statuses", "optimal ends (of 16)", "gap / width, median / max", "nodes",
             "time limit s", "widths m_l c_l m_r c_r", "truth inside", "load"], body) + "\n\n" + _env(j))
    return "\n\n".join(parts) + "\n" if parts else "_No results (`--part speed` not run)._\n"


def section_valve():
    j = _with_rows("valve_loops.json")
    if j is None:
        return ""
    rows = j["rows"]
    conf = j.get("confusion") or {}
    calls = ("stiction", "no stiction", "degenerate", "error")
    body = [[lab] + [conf.get(f"{lab}|{c}", 0) for c in calls] for lab in ("stiction",
                                                                           "no stiction")]
    sec = [r["seconds"] for r in rows if "seconds" in r]
    out = [f"{len(rows)} of 80 loops analysed (random order, seed 0), "
           + (f"median {np.median(sec):.0f} s per loop (max {max(sec):.0f} s). " if sec else "")
           + "Confusion table (rows: the "
           "experts' folder labels; columns: the rule's call):\n",
           _table(["label \\ call", *calls], body)]
    det = []
    for r in sorted(rows, key=lambda r: r["key"]):
        bl = r.get("backlash") or {}
        det.append([r["key"], r.get("label", "?"), r["call"], r.get("nk", "–"),
                    f"{r['lin_lo']:.3g}–{r['lin_hi']:.3g}" if "lin_lo" in r else "–",
                    f"{r['delta_star']:.3g}" if "delta_star" in r else "–",
                    bl.get("set", "–"),
                    f"{bl['deadband_lower']:.3g}" if "deadband_lower" in bl else "–",
                    f"{r['op_range']:.3g}" if "op_range" in r else "–",
                    f"{r.get('seconds', 0):.0f}", (r.get("why") or "")[:60]])
    out.append("\nPer loop (linear bound bracket and δ* in PV standard deviations; dead band "
               "lower bound and OP range in OP units):\n")
    out.append(_table(["loop", "label", "call", "nk*", "linear bound", "δ*", "set at δ*",
                       "dead band ≥", "OP range", "s", "note"], det))
    out.append("\n" + _env(j))
    return "\n".join(out) + "\n"
