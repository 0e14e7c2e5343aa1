"""The chapter's sections of docs/benchmarks.md: Tables 22.1-22.3, seeds and stage-1
draws, stage 1 speed and extremal noise, Monte Carlo coverage."""

from __future__ import annotations

import numpy as np

try:
    from benchmarks import _common as C
    from benchmarks.report_format import _csv, _json, env_line, f, fs, table
except ImportError:  # run as a script
    import _common as C
    from report_format import _csv, _json, env_line, f, fs, table


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
