"""Generate docs/benchmarks.md from benchmarks/results/ (tables) and docs/figures/ (plots).

    python -m benchmarks report

The prose that interprets the results lives in benchmarks/report_notes.md (hand-written
after looking at the results) and is inserted verbatim; every number in the tables below is
read from a results file.
"""

from __future__ import annotations

try:
    from benchmarks import _common as C
    from benchmarks import default_method, units
    from benchmarks import report_chapter as RC
    from benchmarks import report_exact as RE
    from benchmarks import report_one_record as R1
    from benchmarks.report_format import _json, env_line, f, fs, notes_section, table
except ImportError:  # run as a script
    import _common as C
    import default_method
    import report_chapter as RC
    import report_exact as RE
    import report_one_record as R1
    import units
    from report_format import _json, env_line, f, fs, notes_section, table

OUT = C.ROOT / "docs" / "benchmarks.md"


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
    rows += RE._ratio_targets()
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


def main(argv=None):
    replot()
    doc = [notes_section("intro"), "## Performance targets\n", section_targets(None),
           RE.section_ablation(), notes_section("targets"),
           "### Exact method in units of the LP method\n", RE.section_exact_ratio(),
           notes_section("exact-ratio-findings"),
           "## 1. Chapter reproduction (section 22.5)\n", notes_section("chapter-setup"),
           RC.section_chapter(), notes_section("chapter-findings"),
           RC.section_chapter_seeds(), RC.section_stage1_draws(), notes_section("chapter-seeds-findings"),
           "## 2. Method comparison\n", notes_section("methods-intro"), section_methods(),
           notes_section("methods-findings"),
           "### Default method\n", notes_section("default-method-intro"),
           default_method.report_section(), notes_section("default-method-findings"),
           "### Order-2 moment relaxation at the chapter's size\n", notes_section("moment2-intro"),
           RE.section_moment2(), notes_section("moment2-findings"),
           "### LRIC exam record\n", RE.section_lric(),
           "### The same records in other units\n", notes_section("units-intro"),
           units.report_section(), notes_section("units-findings"),
           "### Exact intervals on long records\n", RE.section_scaling(),
           notes_section("scaling-findings"),
           "### Exact witnesses against an independent LP\n", notes_section("witness-intro"),
           RE.section_witness_widening(), notes_section("witness-findings"),
           "## 3. Stage 1 speed\n", RC.section_stage1(), notes_section("stage1-findings"),
           "### Noise exactly at the bound\n", notes_section("stage1-extremal-intro"),
           RC.section_stage1_extremal(), notes_section("stage1-extremal-findings"),
           "## 4. Monte Carlo coverage\n", notes_section("coverage-intro"), RC.section_coverage(),
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
