"""The exact method's sections of docs/benchmarks.md: the ablation, the ratio to the LP
method, long records, witnesses, the order-2 moment relaxation and the LRIC exam."""

from __future__ import annotations

import numpy as np

try:
    from benchmarks import _common as C
    from benchmarks.report_format import _json, _with_rows, env_line, f, fs, table
except ImportError:  # run as a script
    import _common as C
    from report_format import _json, _with_rows, env_line, f, fs, table


def section_ablation():
    """What each part of the exact search buys (benchmarks/exact_ablation.py)."""
    j = _with_rows("exact_ablation.json")
    if j is None:
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
    j = _with_rows("exact_scaling.json")
    if j is None:
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


def section_moment2():
    """Order-2 moment relaxation at the chapter's size (benchmarks/moment_order2.py)."""
    j = _with_rows("moment_order2.json")
    if j is None:
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
    j = _with_rows("lric.json")
    if j is None:
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
