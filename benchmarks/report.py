"""Generate docs/benchmarks.md from benchmarks/results/ (tables) and docs/figures/ (plots).

    python benchmarks/report.py

The prose that interprets the results lives in benchmarks/report_notes.md (hand-written
after looking at the results) and is inserted verbatim; every number in the tables below is
read from a results file.
"""

from __future__ import annotations

import csv

import numpy as np

try:
    from benchmarks import _common as C
    from benchmarks import default_method, units
    from benchmarks import report_one_record as R1
except ImportError:  # run as a script
    import _common as C
    import default_method
    import report_one_record as R1
    import units

OUT = C.ROOT / "docs" / "benchmarks.md"
NOTES = C.HERE / "report_notes.md"


def _csv(name):
    p = C.RESULTS / name
    if not p.exists():
        return None
    with open(p) as fh:
        return list(csv.DictReader(fh))


def _json(name):
    p = C.RESULTS / name
    return C.read_json(p) if p.exists() else None


def f(v, nd=4):
    if v is None or v == "":
        return "–"
    try:
        x = float(v)
    except (TypeError, ValueError):
        return str(v)
    if np.isnan(x):
        return "–"
    return f"{x:.{nd}f}"


def fs(v):
    """seconds"""
    if v is None or v == "":
        return "–"
    x = float(v)
    return f"{x:.3f}" if x < 1 else (f"{x:.2f}" if x < 10 else f"{x:.1f}")


table = C.markdown_table


def notes_section(key):
    """Text between '<!-- key -->' and the next '<!-- ' marker of report_notes.md."""
    if not NOTES.exists():
        return ""
    text = NOTES.read_text()
    marker = f"<!-- {key} -->"
    if marker not in text:
        return ""
    part = text.split(marker, 1)[1]
    return part.split("<!-- ", 1)[0].strip() + "\n"


def env_line(j):
    if not j or "environment" not in j:
        return ""
    e = j["environment"]
    return (f"_Run {e['date']}, Python {e['python']}, {e['cpu_count']} CPUs, load average at start "
            f"{e['loadavg_at_start'][0]} (shared machine)._")


def section_targets(parts):
    s1 = _json("stage1_speed.json")
    ch = _json("chapter_tables.json")
    d2 = _json("methods_delta2.json")
    rows = []
    if s1:
        t = s1["polygon_1e5_s"]
        rows.append(["Stage 1 exact polygon, 1e5 points per side", "< 0.5 s", f"{fs(t)} s",
                     "met" if t is not None and t < 0.5 else f"**missed** ({t / 0.5:.0f}× over)"])
        sp = s1["speedup_at_1000"]
        rows.append(["Stage 1 polygon vs Algorithm 22.1 at M = 1000", "≥ 100×", f"{sp:.1f}×",
                     "met" if sp >= 100 else f"**missed** ({100 / sp:.1f}× short)"])
    idle = _json("exact_idle_N300.json")
    idle_ind = [r for r in (idle or {}).get("rows", []) if r["inner_signal"] == "independent"]
    for inner in ("independent", "two-level"):
        runs = [r for r in (idle or {}).get("rows", []) if r["inner_signal"] == inner]
        if not runs:
            continue
        # the idle-machine measurement is the one the target is judged on, and on the
        # slowest of the repeated fits (not the median)
        def slowest(r):
            return max(r.get("wall_all_s") or [r["wall_s"]])

        worst = max(runs, key=slowest)
        n_ok = sum(slowest(r) <= 20 for r in runs)
        reps = len(worst.get("wall_all_s") or [1])
        rows.append([f"Exact intervals, {inner} inner signal, N = 300, all 8 bounds (per noise "
                     "level, idle machine)", "≤ 20 s",
                     f"{fs(min(slowest(r) for r in runs))}–{fs(slowest(worst))} s "
                     f"(slowest of {reps} fits per level; worst Δη = {worst['delta_eta']})",
                     "met at all levels" if n_ok == len(runs) else
                     f"**missed** at {len(runs) - n_ok} of {len(runs)} levels "
                     f"(worst {slowest(worst) / 20:.1f}× over)"])
    if ch:
        ex300 = [r for r in ch["runs"] if r.get("method") == "exact" and r.get("N") == 300 and "wall_s" in r]
        if ex300 and not idle_ind:
            worst = max(ex300, key=lambda r: r["wall_s"])
            n_ok = sum(r["wall_s"] <= 20 for r in ex300)
            rows.append(["Exact intervals, N = 300, all 8 bounds (per noise level)", "≤ 20 s",
                         f"{fs(min(r['wall_s'] for r in ex300))}–{fs(worst['wall_s'])} s "
                         f"(worst Δη = {worst['delta_eta']})",
                         "met" if n_ok == len(ex300) else f"**missed** at {len(ex300) - n_ok} of "
                         f"{len(ex300)} levels (worst {worst['wall_s'] / 20:.1f}× over)"])
        lp300 = [r for r in ch["runs"] if r.get("method") == "lp" and r.get("N") == 300 and "wall_s" in r]
        if lp300:
            w = max(r["wall_s"] for r in lp300)
            rows.append(["LP baseline, N = 300, all 8 bounds", "≤ 1 s", f"≤ {fs(w)} s (all 6 levels)",
                         "met" if w <= 1 else "**missed**"])
    if d2:
        m2 = [r for r in d2["rows"] if r["method"] == "moment2" and "wall_s" in r]
        if m2:
            big = max(m2, key=lambda r: r["N"])
            rows.append(["Moment δ = 2, N = 100, all 8 bounds", "≤ 120 s",
                         f"not run at N = 100; {fs(big['wall_s'])} s at N = {big['N']}",
                         "**missed** (see the δ = 2 section)"])
    sc = _json("exact_scaling.json")
    by_n = {r["N"]: r for r in (sc or {}).get("rows", [])}
    for n_, goal in ((3000, 30.0), (10000, 120.0)):
        r = by_n.get(n_)
        if r:
            w = r["new"]["wall_s"]
            rows.append([f"Exact intervals, independent, Δη = {r['delta_eta']:g}, N = {n_}, "
                         f"{r['n_jobs']} jobs (shared machine)", f"≤ {goal:g} s",
                         f"{fs(w)} s, {r['new']['peak_rss_mb']:.0f} MB peak (load "
                         f"{r['loadavg_start']})",
                         "met" if w <= goal else f"**missed** ({w / goal:.1f}× over, under load)"])
    rows += _ratio_targets()
    if not rows:
        return ""
    out = table(["target", "goal", "measured", "verdict"], rows) + "\n"
    if idle and idle.get("rows"):
        levels = sorted({r["delta_eta"] for r in idle["rows"]})
        by = {(r["inner_signal"], r["delta_eta"]): r for r in idle["rows"]}
        trows = []
        def cell(r):
            walls = r.get("wall_all_s") or [r["wall_s"]]
            spread = f"–{fs(max(walls))}" if len(walls) > 1 else ""
            return f"{fs(min(walls))}{spread} s ({r['nodes']})"

        for inner in ("independent", "two-level"):
            trows.append([inner] + [cell(by[(inner, d)]) if (inner, d) in by else ""
                                    for d in levels])
        out += ("\nExact method at N = 300 on the idle machine (`python -m benchmarks.exact_idle "
                "--N 300`, 2 jobs; wall time of the whole identifier fit, fastest–slowest of the "
                "repeated fits, B&B nodes over the 8 ends in brackets; every end `optimal`: "
                f"{all(r['statuses'] == ['optimal'] for r in idle['rows'])}, true parameters "
                f"inside: {all(r['true_inside'] for r in idle['rows'])}):\n\n")
        out += table(["inner signal"] + [f"Δη = {d:g}" for d in levels], trows) + "\n\n"
        out += env_line(idle).replace(" (shared machine)", "") + "\n"
    return out


def section_ablation():
    """What each part of the exact search buys (benchmarks/exact_ablation.py)."""
    j = _json("exact_ablation.json")
    if not j or not j.get("rows"):
        return ""
    rows = [[r["inner_signal"], f"{r['delta_eta']:g}", r["variant"], f"{fs(r['wall_s'])} s",
             r["nodes"], r["iterations"], ", ".join(r["statuses"]),
             f"{r['max_bound_diff']:.1e}", r["loadavg_start"]] for r in j["rows"]]
    out = ("Each part of the exact search switched off in turn (`python -m "
           "benchmarks.exact_ablation`; chapter example, seed 0, N = "
           f"{j['rows'][0]['N']}, stage 2 only, 1 job, so the time is the sum over the 8 "
           "ends; *all*: everything on; |Δ bounds|: largest difference of a bound from *all*, "
           "within the tolerance 1e-4·max(1, |value|) as every variant certifies the same "
           "intervals):\n\n")
    out += table(["inner signal", "Δη", "variant", "time", "nodes", "simplex iterations",
                  "status", "|Δ bounds|", "load"], rows) + "\n\n"
    return out + env_line(j) + "\n"


def _ratio_key(r):
    return (r["inner_signal"], r["N"], r["delta_eta"])


def _ratio_after():
    """results/exact_ratio_after.json with the rows of a later partial run
    (exact_ratio_after300.json, the final code at N = 300) in place of its own."""
    j = _json("exact_ratio_after.json") or _json("exact_ratio.json")
    late = _json("exact_ratio_after300.json")
    if not j or not late:
        return j or late
    new = {_ratio_key(r): r for r in late["rows"]}
    rows = [new.pop(_ratio_key(r), r) for r in j["rows"]] + list(new.values())
    return {**late, "rows": rows}


def _ratio_targets():
    """Rows of the issue-28 targets from results/exact_ratio_after.json."""
    j = _ratio_after()
    if not j or not j.get("rows"):
        return []
    out = []
    ind = [r for r in j["rows"] if r["inner_signal"] == "independent"]
    if ind:
        worst = max(ind, key=lambda r: r["ratio_max"])
        n_ok = sum(r["ratio_max"] <= 10 for r in ind)
        out.append([f"Exact within 10× of the LP method, independent, N = "
                    f"{', '.join(str(n) for n in sorted({r['N'] for r in ind}))}, Δη = "
                    f"{', '.join(f'{d:g}' for d in sorted({r['delta_eta'] for r in ind}))} "
                    f"({ind[0]['ratio_basis'].upper()} time, {ind[0]['n_jobs']} job)", "≤ 10×",
                    f"{min(r['ratio_min'] for r in ind):.0f}–{worst['ratio_max']:.0f}× "
                    f"(worst N = {worst['N']}, Δη = {worst['delta_eta']:g})",
                    "met" if n_ok == len(ind) else
                    f"**missed** at {len(ind) - n_ok} of {len(ind)} rows"])
    for r in j["rows"]:
        two = r.get("two_level_over_independent")
        if r["inner_signal"] == "two-level" and r["N"] == 300 and r["delta_eta"] == 0.3 \
                and two is not None:
            out.append(["Two-level / independent exact time, N = 300, Δη = 0.3", "≤ 1.5",
                        f"{two:.2f}", "met" if two <= 1.5 else "**missed**"])
        if r["inner_signal"] == "two-level" and r["N"] == 3000:
            basis = r["ratio_basis"]
            t = min(x[f"exact_{basis}_s"] for x in r["repeats"])
            out.append([f"Two-level exact, N = 3000, Δη = {r['delta_eta']:g}", "≤ 30 s",
                        f"{fs(t)} s ({basis.upper()} time, {r['n_jobs']} job, load "
                        f"{r['loadavg_start']}), {r['peak_rss_mb']:.0f} MB peak",
                        "met" if t <= 30 else f"**missed** ({t / 30:.1f}× over)"])
    return out


def section_exact_ratio():
    """Exact / LP time per (N, Delta eta), before and after a change
    (benchmarks/exact_ratio.py: results/exact_ratio_before.json, exact_ratio_after.json)."""
    after = _ratio_after()
    if not after or not after.get("rows"):
        return ""
    before = {_ratio_key(r): r for r in (_json("exact_ratio_before.json") or {}).get("rows", [])}
    rows = []
    for r in after["rows"]:
        b = before.get(_ratio_key(r))
        basis = r["ratio_basis"]
        best = min(x[f"exact_{basis}_s"] for x in r["repeats"])
        lp = float(np.median([x[f"lp_{basis}_s"] for x in r["repeats"]]))
        diff = "–"
        if b is not None:
            a_b, b_b = np.asarray(r["bounds"]), np.asarray(b["bounds"])
            diff = f"{np.max(np.abs(a_b - b_b) / (1e-4 * np.maximum(1.0, np.abs(b_b)))):.2f}"
        two = r.get("two_level_over_independent")
        rows.append([r["inner_signal"], r["N"], f"{r['delta_eta']:g}", f"{fs(lp)} s",
                     f"{fs(min(x[f'exact_{basis}_s'] for x in b['repeats']))} s" if b else "–",
                     f"{fs(best)} s",
                     f"{b['ratio_min']:.0f}–{b['ratio_max']:.0f}×" if b else "–",
                     f"{r['ratio_min']:.0f}–{r['ratio_max']:.0f}×",
                     f"{b['nodes']} → {r['nodes']}" if b else r["nodes"],
                     f"{b['two_level_over_independent']:.2f} → {two:.2f}"
                     if two is not None and b and b.get("two_level_over_independent")
                     else (f"{two:.2f}" if two is not None else "–"),
                     f"{r['peak_rss_mb']:.0f} MB", diff, ", ".join(r["statuses"]),
                     r["loadavg_start"]])
    n_jobs = after["rows"][0]["n_jobs"]
    out = ("The exact method in units of the LP method (`python -m benchmarks.exact_ratio`; "
           "chapter example, seed 0, stage 2 only, the same EIV problem for both methods, "
           f"{n_jobs} job(s), each fit repeated "
           f"{len(after['rows'][0]['repeats'])}×; times are the "
           f"{'CPU time of the process' if after['rows'][0]['ratio_basis'] == 'cpu' else 'wall time'}"
           " (fastest repeat for the exact method, median of 5 runs for the LP), which the "
           "load of the shared machine disturbs less than wall time; *before*: the code "
           "before the issue-28 work, *after*: with it; the two full runs ran at the same time "
           "on the same machine, rows from `exact_ratio_after300.json` (if any) come from a "
           "later run of the final code at another load; exact/LP: smallest–largest ratio "
           "over the repeats; 2-level/indep.: "
           "exact time of the two-level inner signal over the independent one at the same "
           "N and Δη; memory: peak resident set of the process and its workers; diff/tol: "
           "largest difference of a bound after vs before, divided by the tolerance "
           "1e-4·max(1, |bound|) of that end):\n\n")
    out += table(["inner signal", "N", "Δη", "LP", "exact before", "exact after",
                  "exact/LP before", "exact/LP after", "nodes", "2-level/indep.", "memory",
                  "diff/tol", "status", "load"], rows) + "\n\n"
    return out + env_line(after) + "\n"


def section_scaling():
    """Exact intervals on long records (benchmarks/exact_scaling.py)."""
    j = _json("exact_scaling.json")
    if not j or not j.get("rows"):
        return ""
    rows = []
    for r in j["rows"]:
        n, o = r["new"], r.get("old")
        rows.append([r["N"], f"{fs(n['wall_s'])} s", n["nodes"],
                     f"{n['working_set_equations']} / {r['equations']}",
                     f"{n['peak_rss_mb']:.0f} MB",
                     f"{fs(o['wall_s'])} s" if o else "not run",
                     o["nodes"] if o else "–", f"{o['peak_rss_mb']:.0f} MB" if o else "–",
                     f"{r['ratio_old_new']:.1f}×" if o else "–",
                     f"{r['max_bound_diff_over_tol']:.2f}" if o else "–",
                     ", ".join(n["statuses"]), r["loadavg_start"]])
    e = j.get("exponent", {})
    out = ("Exact method on long records (`python -m benchmarks.exact_scaling`; chapter "
           f"example, independent inner signal, Δη = {j['rows'][0]['delta_eta']:g}, "
           f"{j['rows'][0]['n_jobs']} jobs, stage 2 only, the same EIV problem solved by both "
           "variants in the same run; *new*: node and OBBT LPs on a working set of equations, "
           "*old*: full node LPs; memory: peak resident set of the process and its workers; "
           "diff/tol: largest difference of a bound between the two variants divided by the "
           "tolerance of that end; timings **under load** on a shared 2-core machine):\n\n")
    out += table(["N", "new time", "new nodes", "working set / equations", "new memory",
                  "old time", "old nodes", "old memory", "old/new", "diff/tol", "status",
                  "load"], rows) + "\n\n"
    out += (f"Fitted growth exponent of the time in N (least squares, log–log): new "
            f"{e.get('new', float('nan')):.2f}, old {e.get('old', float('nan')):.2f} "
            f"(old only up to N = {max((r['N'] for r in j['rows'] if 'old' in r), default=0)})."
            "\n\n")
    out += env_line(j) + "\n"
    return out


def section_chapter():
    t1 = _csv("chapter_table_22_1.csv")
    t23 = _csv("chapter_tables_22_2_3.csv")
    inner = _csv("chapter_inner_signal.csv")
    ch = _json("chapter_tables.json")
    out = []
    if ch:
        out.append(env_line(ch) + "\n")
    if t1:
        rows = []
        for r in t1:
            rows.append([r["delta_eta"], f(r["snr_ours_db"], 1), f(r["snr_chapter_db"], 0), r["param"],
                         f(r["true"]), f(r["lower"]), f(r["upper"]), f(r["half_width"]),
                         f(r["chapter_lower"]), f(r["chapter_upper"]), f(r["chapter_half_width"]),
                         "yes" if r["inside"] == "True" else "**NO**"])
        out.append("### Table 22.1 — backlash parameters (stage 1, exact), M = 50\n")
        out.append(table(["Δη", "SNR ours (dB)", "SNR ch. (dB)", "γ", "true", "ours min", "ours max",
                          "ours Δγ", "ch. min", "ch. max", "ch. Δγ", "true inside"], rows))
        out.append("\n![Table 22.1 half-widths](figures/bench_chapter_table_22_1.png)\n")
    if t23:
        methods = []
        for r in t23:
            if r["method"] not in methods:
                methods.append(r["method"])
        for N, name in (("100", "22.2"), ("300", "22.3")):
            sel = [r for r in t23 if r["N"] == N]
            if not sel:
                continue
            main_m = methods[0]
            rows = []
            for r in sel:
                if r["method"] != main_m:
                    continue
                others = {q["method"]: q for q in sel if q["delta_eta"] == r["delta_eta"]
                          and q["param"] == r["param"]}
                inside_all = all(q["inside"] == "True" for q in others.values())
                rows.append([r["delta_eta"], f(r["snr_ours_db"], 1), f(r["snr_chapter_db"], 0), r["param"],
                             f(r["true"]), f(r["lower"]), f(r["upper"]), f(r["half_width"])]
                            + [f(others[m]["half_width"]) if m in others else "–" for m in methods[1:]]
                            + [f(r["chapter_lower"]), f(r["chapter_upper"]), f(r["chapter_half_width"]),
                               f(r["half_width_ratio_ours_over_chapter"], 2),
                               "yes" if inside_all else "**NO**"])
            out.append(f"### Table {name} — linear block, N = {N}\n")
            out.append(f"Ours: `{main_m}` intervals (min, max, Δθ = half-width); then the half-widths "
                       f"of {', '.join('`' + m + '`' for m in methods[1:])} on the same data; then the "
                       "chapter's δ = 2 values. *ratio* = ours (exact) Δθ / chapter Δθ. "
                       "*inside*: the true value is inside the intervals of every method.\n")
            out.append(table(["Δη", "SNR ours", "SNR ch.", "θ", "true", "ours min", "ours max", "ours Δθ"]
                             + [f"Δθ {m}" for m in methods[1:]]
                             + ["ch. min", "ch. max", "ch. Δθ", "ratio", "inside"], rows))
            out.append("")
        times = [r for r in (ch or {}).get("runs", []) if "wall_s" in r]
        if times:
            Ns = sorted({r["N"] for r in times})
            lv = sorted({r["delta_eta"] for r in times})
            rows = []
            for N in Ns:
                for m in methods:
                    row = [N, m]
                    for L in lv:
                        q = [r for r in times if r["N"] == N and r["method"] == m and r["delta_eta"] == L]
                        row.append(fs(q[0]["wall_s"]) if q else "–")
                    rows.append(row)
            out.append("Wall time (s) of stage 2, all 8 bounds, 2 joblib workers:\n")
            out.append(table(["N", "method"] + [f"Δη={L}" for L in lv], rows))
        out.append("\n![Tables 22.2/22.3 half-widths](figures/bench_chapter_tables_22_2_3.png)\n")
    if inner:
        rows = [[r["delta_eta"], r["N"], f(r["u_star"], 2), f(r["x_hi_min"], 5), f(r["x_hi_max"], 5),
                 f(r["x_hi_true"], 5), f(r["x_lo_min"], 5), f(r["x_lo_max"], 5), f(r["x_lo_true"], 5)]
                for r in inner if r["N"] == inner[0]["N"]]
        out.append("### Inner-signal bounds (22.25)-(22.26) used by stage 2\n")
        out.append(table(["Δη", "N", "u*", "x̄* min", "x̄* max", "x̄* true", "x̲* min", "x̲* max",
                          "x̲* true"], rows))
    return "\n".join(out)


def _rng(r, nd=4):
    return f"{f(r['median_half_width'], nd)} ({f(r['half_width_min'], nd)}–{f(r['half_width_max'], nd)})"


def section_chapter_seeds():
    """Medians over seeds, both stage-1 modes (benchmarks/chapter_tables.py --seeds)."""
    runs = [(s1, _json(f"chapter_seeds_{s1}_exact.json")) for s1 in ("chapter", "experiment")]
    runs.append(("chapter, Table 22.1 ends as printed (no outward rounding)",
                 _json("chapter_seeds_chapter_exact_as-printed.json")))
    runs = [(s1, j) for s1, j in runs if j]
    if not runs:
        return ""
    out = ["### Over several noise draws: exact method, both stage-1 modes\n",
           "`python benchmarks/chapter_tables.py --seeds 0 1 2 3 4 --stage1 chapter experiment "
           "--methods exact --n-jobs 1` (`hammerbound.app.chapter.reproduce_chapter`). *stage 1 = "
           "chapter*: stage 2 receives the inner-signal bounds implied by the chapter's Table "
           "22.1 (interval arithmetic on its box of (m, c), printed ends moved outward by half a "
           r"unit of the last digit, u\* = 1); *stage 1 = experiment*: our exact stage 1 on our "
           "square-wave data. Half-widths: median over the seeds (min–max); *ratio* = median / "
           "chapter's δ = 2 half-width; *inside*: the true value is inside the interval of every "
           "seed.\n"]
    for s1, j in runs:
        recs = j["records"]
        seeds = recs[0]["seeds"]
        st2 = [r for r in recs if r["table"] in ("22.2", "22.3")]
        ok = [r for r in st2 if r["ratio"] is not None and 0.7 <= r["ratio"] <= 1.5]
        inside = all(all(r["inside"]) for r in recs)
        ratios = [r["ratio"] for r in st2 if r["ratio"] is not None]
        out.append(f"#### Stage 1 = {s1} (seeds {seeds})\n")
        out.append(env_line(j) + "\n")
        out.append(f"Rows with ratio in [0.7, 1.5]: **{len(ok)}/{len(st2)}** (ratios "
                   f"{min(ratios):.2f}–{max(ratios):.2f}); true value inside every interval of "
                   f"every seed: **{'yes' if inside else 'NO'}**.\n")
        levels = sorted({r["delta_eta"] for r in st2})
        params = ["a1", "a2", "b1", "b2"]
        by = {(r["table"], r["delta_eta"], r["param"]): r for r in st2}
        for table_name, N in (("22.2", 100), ("22.3", 300)):
            rows = []
            for d in levels:
                for p in params:
                    r = by.get((table_name, d, p))
                    if r is None:
                        continue
                    t = r.get("time_s") or []
                    rows.append([d, p, f(float(np.median(r["snr_db"])), 1) if r.get("snr_db")
                                 else "–", f(r["chapter_snr_db"], 0), f(r["true"]),
                                 f(r["lower"]), f(r["upper"]), _rng(r),
                                 f(r["chapter_half_width"]), f(r["ratio"], 2),
                                 "yes" if all(r["inside"]) else "**NO**",
                                 fs(float(np.median(t))) if t else "–"])
            if rows:
                out.append(f"Table {table_name} (N = {N}), stage 1 = {s1}:\n")
                out.append(table(["Δη", "θ", "SNR med.", "SNR ch.", "true", "min (median seed)",
                                  "max (median seed)", "Δθ median (min–max)", "ch. Δθ (δ = 2)",
                                  "ratio", "inside", "median fit (s)"], rows) + "\n")
    # inner-signal radius: ours vs implied by Table 22.1 (same in both runs)
    recs = runs[0][1]["records"]
    xs = [r for r in recs if r["table"] == "22.1" and r["param"].startswith("x")]
    if xs:
        rows = [[r["delta_eta"], r["param"], f(r["true"], 5), _rng(r, 5),
                 f(r["chapter_lower"], 5), f(r["chapter_upper"], 5),
                 f(r["chapter_half_width"], 5), f(r["ratio"], 2),
                 "yes" if all(r["inside"]) else "**NO**"] for r in xs]
        out.append(r"Inner-signal levels at u\* = 1: radius Δx of our exact stage 1 (median over "
                   "the seeds, min–max) against the range implied by Table 22.1:\n")
        out.append(table(["Δη", "level", "true", "our Δx median (min–max)", "implied min",
                          "implied max", "implied Δx", "ratio", "inside"], rows) + "\n")
    exp = dict(runs).get("experiment")
    if exp:
        out.append(_box_loss(exp["records"]))
    return "\n".join(out)


def _box_loss(recs, u=1.0):
    """How much the Table-22.1-style box mapping loses against the exact polygon, measured on
    our own stage-1 sets: radius from the box of our (m, c) intervals / our exact radius."""
    rows = []
    for d in sorted({r["delta_eta"] for r in recs}):
        g = {r["param"]: r for r in recs if r["table"] == "22.1" and r["delta_eta"] == d}
        if not {"ml", "cl", "mr", "cr", "x(+u*)", "x(-u*)"} <= set(g):
            continue
        hi, lo = [], []
        for k in range(len(g["ml"]["seeds"])):
            def iv(p, k=k, g=g):
                return g[p]["lowers"][k], g[p]["uppers"][k]
            (ml0, ml1), (cl0, cl1), (mr0, mr1), (cr0, cr1) = iv("ml"), iv("cl"), iv("mr"), iv("cr")
            hi.append((mr1 * (u - cr0) - mr0 * (u - cr1)) / g["x(+u*)"]["widths"][k])
            lo.append((ml1 * (u - cl0) - ml0 * (u - cl1)) / g["x(-u*)"]["widths"][k])
        rows.append([d, f"{np.median(hi):.2f} ({min(hi):.2f}–{max(hi):.2f})",
                     f"{np.median(lo):.2f} ({min(lo):.2f}–{max(lo):.2f})"])
    if not rows:
        return ""
    return ("The mapping from Table 22.1 uses only the box of the (m, c) intervals. On our own "
            "stage-1 sets (stage 1 = experiment run, same seeds) the radius that box gives is "
            "this many times the exact radius (22.25)–(22.26) of the polygon (median over the "
            "seeds, min–max):\n\n"
            + table(["Δη", "x(+u*) box / exact", "x(−u*) box / exact"], rows) + "\n")


def section_stage1_draws():
    j = _json("chapter_stage1_draws.json")
    if not j:
        return ""
    rows = [[r["delta_eta"], r["design"], r["draws"], f(r["chapter_dx"][0], 5),
             f(r["chapter_dx"][1], 5), f(r["dx_hi_median"], 5), f(r["dx_lo_median"], 5),
             f(r["dx_hi_min"], 5), f(r["dx_lo_min"], 5), r["draws_reaching_chapter_dx"],
             f"{r['seed0_dx_hi_percentile']:.0f} / {r['seed0_dx_lo_percentile']:.0f}",
             f"{r['seed0_snr_db']:.1f} ({r['seed0_snr_percentile']:.0f})"] for r in j["rows"]]
    return ("Stage 1 over many draws (`python benchmarks/chapter_stage1_draws.py --draws "
            f"{j['args']['draws']} --levels {' '.join(map(str, j['args']['levels']))}`): the "
            r"inner-signal radius Δx at u\* = 1 of our exact stage 1 (M = 50, uniform noise) for "
            "three amplitude designs, against the Δx implied by Table 22.1; *reaching* = draws "
            "with both radii ≤ the implied ones; seed 0's percentile among the draws (Δx̄ / Δx̲; "
            "transient SNR of the N = 100 PRBS in dB, percentile in brackets).\n\n"
            + env_line(j) + "\n\n"
            + table(["Δη", "amplitudes", "draws", "implied Δx̄", "implied Δx̲", "Δx̄ median",
                     "Δx̲ median", "Δx̄ min", "Δx̲ min", "reaching", "seed 0 pct. Δx̄ / Δx̲",
                     "seed 0 SNR (pct.)"], rows) + "\n")


def _method_rows(rows, key=None):
    out = []
    for r in rows:
        if r.get("error"):
            out.append(([r.get(key)] if key else []) + [r["method"], "error: " + r["error"][:80]]
                       + ["–"] * 10)
            continue
        w = r["theta_width"]
        ratio = r.get("width_over_exact")
        out.append(([r.get(key)] if key else []) + [
            r["method"], fs(r["wall_s"]), fs(r["bound_time_sum_s"]), fs(r["bound_time_max_s"]),
            f(r.get("loadavg"), 1), " / ".join(f(x) for x in w),
            " / ".join(f(x, 2) for x in ratio) if ratio else "–",
            r["iterations_sum"] if r.get("iterations_sum") is not None else "–",
            r["nodes_sum"] if r.get("nodes_sum") is not None else "–",
            ", ".join(r["statuses"]), "yes" if r["all_certified"] else "no",
            "yes" if (r["theta_inside"] and r["gamma_inside"]) else "**NO**"])
    return out


def _methods_json(part, keys):
    j = _json(f"methods_{part}.json")
    if j:
        try:
            from benchmarks import methods as M
        except ImportError:
            import methods as M
        M.add_ratios(j["rows"], keys)
    return j


def section_methods():
    out = []
    hdr = ["method", "wall (s)", "Σ per-bound (s)", "max per-bound (s)", "load",
           "widths a1 / a2 / b1 / b2", "width / exact width", "solver iter.",
           "B&B nodes", "statuses", "certified", "true inside"]
    same = _methods_json("same", ["N"])
    if same:
        r0 = same["rows"][0]
        out.append(f"### Same data: N = {r0['N']}, Δη = {r0['noise']}, seed {r0['seed']} "
                   f"(transient SNR {r0['snr_prbs_db']:.1f} dB)\n")
        out.append(env_line(same) + "\n")
        out.append(table(hdr, _method_rows(same["rows"])))
        out.append("\nFor the `-2level` rows the ratio is to the *independent-error* exact width; "
                   "the exact two-level width is the `exact-2level` row.\n")
    # part, table key, its column title, section title, note, figure caption
    parts = [
        ("delta2", "N", "N", "Relaxation order δ = 2 on small N ({noise})", None,
         "delta=2 cost and conservatism"),
        ("scaling", "N", "N", "Scaling in N ({noise})", None, "time and width against N"),
        ("order", "order", "n", "Scaling in model order (N = 100, {noise})",
         "Widths are listed for the first four parameters only (a1, a2 or b1 ...).\n",
         "time and width against model order"),
    ]
    for part, key, col, title, note, caption in parts:
        res = _methods_json(part, [key])
        if not res:
            continue
        out.append("### " + title.format(noise=f"Δη = {res['rows'][0]['noise']}") + "\n")
        out.append(env_line(res) + "\n")
        if note:
            out.append(note)
        out.append(table([col] + hdr, _method_rows(res["rows"], key)))
        out.append(f"\n![{caption}](figures/bench_methods_{part}.png)\n")
    return "\n".join(out)


def section_stage1():
    s1 = _json("stage1_speed.json")
    if not s1:
        return ""
    rows = []
    Ms = sorted({r["M_per_side"] for r in s1["rows"]})
    for M in Ms:
        p = [r for r in s1["rows"] if r["M_per_side"] == M and r["method"] == "polygon"]
        a = [r for r in s1["rows"] if r["M_per_side"] == M and r["method"] == "algorithm"]
        rows.append([M, fs(p[0]["time_s"]) if p else "–", fs(a[0]["time_s"]) if a else "–",
                     f"{a[0]['time_s'] / p[0]['time_s']:.1f}×" if (a and p) else "–",
                     f"{p[0]['n_vertices_left']}/{p[0]['n_vertices_right']}" if p else "–"])
    out = [env_line(s1) + "\n",
           table(["M per side", "polygon (s)", "Algorithm 22.1 (s)", "speed-up", "vertices L/R"], rows),
           f"\nPolygon and Algorithm 22.1 orthotopes agree to "
           f"{max(s1['max_abs_diff_polygon_vs_algorithm'].values()):.1e} at every common M.\n",
           "![stage 1 speed](figures/bench_stage1_speed.png)\n"]
    return "\n".join(out)


def section_stage1_extremal():
    j = _json("stage1_extremal.json")
    if not j:
        return ""
    body = []
    for r in j["rows"]:
        ok = r["status"] == "ok"
        body.append([r["method"], r["M_per_side"], r["noise"],
                     fs(r["time_s"]) if ok else r["status"],
                     f"{r['peak_rss_mb']:.0f}" if ok else "–",
                     f"{r['n_vertices_left']}/{r['n_vertices_right']}" if ok else "–",
                     ("yes" if r["gamma_inside"] else "**no**") if ok else "–"])
    return "\n".join([env_line(j) + "\n", table(
        ["method", "M per side", "noise", "fit (s)", "peak memory (MB)", "vertices L/R",
         "γ inside"], body)]) + "\n"


def section_witness_widening():
    rows = []
    for name, label in (("witness_widening_unpolished.json", "as accepted (not polished)"),
                        ("witness_widening.json", "polished (default)")):
        j = _json(name)
        if j:
            rows.append([label, j["n_witnesses"], f"{j['max']:.1e}", f"{j['median']:.1e}",
                         j["n_above_0"], j["n_above_2e-7"]])
    if not rows:
        return ""
    j = _json("witness_widening.json") or _json("witness_widening_unpolished.json")
    return "\n".join([env_line(j) + "\n", table(
        ["witnesses", "count", "max widening", "median", "> 0", "> 2e-7"], rows)]) + "\n"


def section_coverage():
    out = []
    for p in sorted(C.RESULTS.glob("coverage_*.json")):
        j = C.read_json(p)
        tag = p.stem.removeprefix("coverage_")
        out.append(f"\n### Run `{tag}` — backend {j['backend']}"
                   + (f" ({j['dask']['workers']} Dask workers, scheduler {j['dask']['scheduler']})"
                      if j.get("dask") else "") + "\n")
        out.append(env_line(j) + "\n")
        out.append(f"Plan `{j['spec']}` (method:seeds), noise levels {j['levels']}, N = {j['N']}; "
                   f"{sum(s['runs'] for s in j['summary'])} runs in {j['elapsed_s']:.1f} s on "
                   f"{j['n_worker_processes']} worker processes.\n")
        rows = [[s["method"], s["noise"], s["runs"], s["errors"], f"{100 * s['theta_coverage']:.1f} %",
                 f"{100 * s['gamma_coverage']:.1f} %", f(s["snr_prbs_db_mean"], 1),
                 f(s["width_a1_median"]), f(s["width_a1_max"]), f(s["width_b1_median"]),
                 f(s["width_b1_max"]), fs(s["wall_s_median"])] for s in j["summary"]]
        out.append(table(["method", "Δη", "runs", "errors", "θ coverage", "γ coverage", "mean SNR (dB)",
                          "a1 width median", "a1 width max", "b1 width median", "b1 width max",
                          "median wall (s)"], rows))
        fig = C.FIGURES / f"bench_coverage_{tag}.png"
        if fig.exists():
            out.append(f"\n![coverage widths]({fig.relative_to(C.ROOT / 'docs')})\n")
        else:
            out.append("")
        if j["misses"]:
            out.append(f"\n**{len(j['misses'])} runs with the true parameter outside an interval.**\n")
    return "\n".join(out)


def section_modelset():
    """The guaranteed model set (hammerbound.modelset): time and tightness of each feature."""
    j = _json("modelset.json")
    if not j:
        return ""
    out = [env_line(j) + "\n",
           f"`python -m benchmarks.modelset`: N = {j['N']} (chapter example, exact method) and "
           f"the LRIC CSV; {j['n_samples']} certified samples per block.\n"]
    rows = []
    for b in j["blocks"]:
        wm, wa = b["weight_multiplicative"], b["weight_additive"]
        rows.append([b["name"], b["p"], fs(b["t_fit"]), fs(b["t_sample"]),
                     f"{b['samples_verified_by_own_lp']}/{b['n_samples']}",
                     f"{1e3 * b['t_envelope_512']:.0f} ms",
                     "yes" if (b["envelope_contains_vertices"] and b["envelope_contains_samples"]
                               and b["envelope_contains_random"]) else "NO",
                     f(b["mag_width_ratio_to_box_points"]["max"], 3),
                     f(b["phase_width_ratio_to_box_points"]["max"], 3),
                     f(b["mag_width_ratio_to_samples"]["median"], 3),
                     fs(wm["t_fit_and_certify"]), fs(wa["t_fit_and_certify"]),
                     "yes" if (wm["bounds_vertices"] and wm["bounds_samples"]
                               and wa["bounds_vertices"] and wa["bounds_samples"]) else "NO"])
    out.append(table(["block", "p", "fit (s)", "1000 samples (s)", "samples re-verified (own LP)",
                      "envelope, 512 ω", "envelope contains all", "mag width / box range (max)",
                      "phase width / box range (max)", "mag width / sample range (median)",
                      "W mult. (s)", "W add. (s)", "W bounds all"], rows))
    return "\n".join(out) + "\n"


def section_weights():
    """Certified uncertainty weights by order (benchmarks/weights.py)."""
    j = _json("weights.json")
    if not j:
        return ""
    rows = j["rows"]
    out = [env_line(j) + "\n",
           "`python -m benchmarks.weights`: the certified weight returned for `order = 0..4` "
           "(the best certified one of order <= `order`, by the mean over-bound `excess_db`); "
           "`min |W| / dev` on 100 001 frequencies up to Nyquist (>= 1: the weight covers "
           "the orthotope's exact deviation there).\n"]
    body = []
    for r in rows:
        body.append([r["record"], r["kind"], r["order_asked"], r["order"],
                     f(r["excess_db"], 2), f(r["W_dc"] / r["deviation_dc"], 3),
                     f(r["min_W_over_deviation"], 4), r["proof_points"], fs(r["seconds"])])
    out.append(table(["record", "kind", "order asked", "order", "excess (dB)",
                      "W(1) / dev(0) (abs.)", "min of abs. W / dev", "proof points", "time (s)"], body))
    return "\n".join(out) + "\n"


def replot():
    """Redraw the method figures from the JSON results (also for partial runs)."""
    try:
        from benchmarks import methods as M
    except ImportError:
        import methods as M
    for part, fn, keys in (("delta2", M.plot_delta2, ["N"]), ("scaling", M.plot_scaling, ["N"]),
                           ("order", M.plot_order, ["order"])):
        j = _json(f"methods_{part}.json")
        if j:
            M.add_ratios(j["rows"], keys)
            fn(j["rows"])


def section_moment2():
    """Order-2 moment relaxation at the chapter's size (benchmarks/moment_order2.py)."""
    j = _json("moment_order2.json")
    if not j or not j.get("rows"):
        return ""
    rows = sorted(j["rows"], key=lambda r: (r["N"], r["basis"] != "sparse"))
    out = [env_line(j)]
    hdr = ["N", "basis", "moments", "conic rows", "nnz(A)", "PSD blocks (side: count)",
           "build s", "wall s (8 bounds)", "solver s (sum)", "iterations (median)",
           "peak memory (process + workers)", "all certified", "max rel. diff. vs exact",
           "truth inside", "load"]
    body = []
    for r in rows:
        blocks = ", ".join(f"{k}: {v}" for k, v in sorted(r["psd_sides"].items(),
                                                           key=lambda kv: int(kv[0])) if k != "1")
        d = float(np.max(np.abs(np.asarray(r["rel_diff"]))))
        body.append([r["N"], r["basis"], r["n_moments"], r["n_rows"], r["nnz"], blocks,
                     fs(r["build_s"]), fs(r["wall_s"]), fs(r["solve_sum_s"]),
                     int(np.median(r["iterations"])),
                     f"{r['peak_rss_mb']:.0f} MB" if r.get("peak_rss_mb") else "not measured",
                     "yes" if all(r["certified"]) else "**no**",
                     f"{d:.1e}", "yes" if r["truth_inside"] else "**no**", r["loadavg"]])
    out.append(table(hdr, body))
    ratios = []
    for r in rows:
        if r["basis"] != "full":
            continue
        sp = [q for q in rows if q["basis"] == "sparse" and q["N"] == r["N"]]
        if sp:
            ratios.append(f"N = {r['N']}: full / sparse wall time = "
                          f"{r['wall_s'] / sp[0]['wall_s']:.0f}x (same run)")
    if ratios:
        out.append("; ".join(ratios) + ".")
    big = [r for r in rows if r["basis"] == "sparse"]
    if big:
        r = max(big, key=lambda q: q["N"])
        hdr2 = ["parameter", "exact lower", "exact upper", "moment lower", "moment upper",
                "rel. diff. lower", "rel. diff. upper"]
        names = C.THETA_NAMES
        body2 = []
        for k, (el, eu) in enumerate(r["exact_bounds"]):
            ml, mu = r["bounds"][k]
            dl, du = r["rel_diff"][k]
            body2.append([names[k], f(el, 6), f(eu, 6), f(ml, 6), f(mu, 6), f"{dl:.1e}",
                          f"{du:.1e}"])
        out.append(f"Per interval end at N = {r['N']} (relative difference = (moment - "
                   "exact) / exact width, positive = inside the exact outer bound):")
        out.append(table(hdr2, body2))
    return "\n" + "\n\n".join(o.strip("\n") for o in out if o) + "\n"


def section_lric():
    """The third-party LRIC exam record (benchmarks/lric.py)."""
    j = _json("lric.json")
    if not j or not j.get("rows"):
        return ""
    rows = []
    for r in j["rows"]:
        ends = ", ".join(f"{n} [{lo:.4f}, {hi:.4f}]" for n, (lo, hi)
                         in zip(r["params"], r["bounds"], strict=True))
        wit = {True: "yes", False: "**no**"}.get(r.get("witnesses_feasible"), "–")
        rows.append([r["method"], ends, ", ".join(sorted(set(r["status"]))),
                     f"{fs(min(r['wall_s']))}–{fs(max(r['wall_s']))} s", wit, r["loadavg"]])
    out = (f"The exam record of P0li22/LRIC (22 February 2017; `{j['data']}`, read in place, "
           f"not shipped): N = {j['N']}, dt = {j['dt']:g}, input and output errors bounded by "
           f"{j['bound']:g}, `na=1, nb=1, nk=0` (`python -m benchmarks lric`; wall time of "
           f"the fit, fastest–slowest of {len(j['rows'][0]['wall_s'])}; witnesses: every "
           "exact end's witness feasible by an independent LP):\n\n")
    out += table(["method", "intervals", "status", "time", "witnesses", "load"], rows) + "\n\n"
    return out + env_line(j) + "\n"


def main(argv=None):
    replot()
    doc = [notes_section("intro"), "## Performance targets\n", section_targets(None),
           section_ablation(), notes_section("targets"),
           "### Exact method in units of the LP method\n", section_exact_ratio(),
           notes_section("exact-ratio-findings"),
           "## 1. Chapter reproduction (section 22.5)\n", notes_section("chapter-setup"),
           section_chapter(), notes_section("chapter-findings"),
           section_chapter_seeds(), section_stage1_draws(), notes_section("chapter-seeds-findings"),
           "## 2. Method comparison\n", notes_section("methods-intro"), section_methods(),
           notes_section("methods-findings"),
           "### Default method\n", notes_section("default-method-intro"),
           default_method.report_section(), notes_section("default-method-findings"),
           "### Order-2 moment relaxation at the chapter's size\n", notes_section("moment2-intro"),
           section_moment2(), notes_section("moment2-findings"),
           "### LRIC exam record\n", section_lric(),
           "### The same records in other units\n", notes_section("units-intro"),
           units.report_section(), notes_section("units-findings"),
           "### Exact intervals on long records\n", section_scaling(),
           notes_section("scaling-findings"),
           "### Exact witnesses against an independent LP\n", notes_section("witness-intro"),
           section_witness_widening(), notes_section("witness-findings"),
           "## 3. Stage 1 speed\n", section_stage1(), notes_section("stage1-findings"),
           "### Noise exactly at the bound\n", notes_section("stage1-extremal-intro"),
           section_stage1_extremal(), notes_section("stage1-extremal-findings"),
           "## 4. Monte Carlo coverage\n", notes_section("coverage-intro"), section_coverage(),
           notes_section("coverage-findings"),
           "## 4b. One ordinary record (issue 26)\n", notes_section("one-record-intro"),
           "### Soundness\n", R1.section_soundness(),
           "### What each record says about the linear block\n", R1.section_excitation(),
           "### Tightness against the two-stage "
           "method\n", R1.section_tightness(), "### Speed\n", R1.section_speed(),
           notes_section("one-record-findings"),
           "### Real plant data: 80 valve loops\n", notes_section("valve-intro"),
           R1.section_valve(), notes_section("valve-findings"),
           "## 5. Guaranteed model set (robust control)\n", section_modelset(),
           notes_section("modelset-findings"),
           "### Uncertainty weights by order\n", notes_section("weights-intro"),
           section_weights(), notes_section("weights-findings"),
           notes_section("limitations")]
    OUT.write_text("\n".join(d for d in doc if d) + "\n")
    C.log(f"wrote {OUT}")


if __name__ == "__main__":
    main()
