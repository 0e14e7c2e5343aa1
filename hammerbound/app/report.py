"""Markdown report (with PNG figures) of a fitted :class:`HammersteinBacklashIdentifier`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..systems.experiments import snr_db
from ..tables import bound_text
from .paths import check_output_dir

__all__ = ["REPORT_FILES", "write_report", "interval_table"]

#: The files :func:`write_report` writes into its directory (nothing else there is touched).
REPORT_FILES = ("report.md", "backlash_characteristic.png", "backlash_sets.png", "intervals.png",
                "envelope.png")


def interval_table(names, bounds, true=None, fmt="{:.4f}") -> str:
    """Markdown table of intervals: parameter, lower, centre, upper, half-width (, true, inside)."""
    head = "| parameter | lower | centre | upper | half-width |"
    sep = "|---|---:|---:|---:|---:|"
    if true is not None:
        head += " true | inside |"
        sep += "---:|:---:|"
    rows = [head, sep]
    for k, name in enumerate(names):
        lo, hi = bounds[k]
        cells = (lo, 0.5 * (lo + hi), hi, 0.5 * (hi - lo))
        r = f"| {name} | " + " | ".join(fmt.format(c) for c in cells) + " |"
        if true is not None:
            r += f" {fmt.format(true[k])} | {'yes' if lo <= true[k] <= hi else '**NO**'} |"
        rows.append(r)
    return "\n".join(rows)


def write_report(ident, steady_u, steady_y, prbs_u, prbs_y, outdir, *, gamma_true=None,
                 theta_true=None, title="hammerbound identification report",
                 overwrite=False) -> Path:
    """Write ``report.md`` and figures into ``outdir``; return the path of the report.

    ``outdir`` is created if missing (its parent must exist). An existing report there
    (any of :data:`REPORT_FILES`) is replaced only with ``overwrite=True``; other files in
    ``outdir`` are never touched. The paths are checked before anything is computed.

    Raises
    ------
    OutputExistsError
        A report file exists in ``outdir`` and ``overwrite`` is false.
    OutputPathError
        ``outdir`` is a file, its parent is missing or it is not writable.

    The report lists the experiment (sizes, output error bounds, SNR of the PRBS output against
    the bound), the backlash feasible sets (vertices, orthotope, figure), the
    inner-signal bounds, the linear-block intervals with per-bound solver information,
    and the guaranteed one-step output envelope against the data.
    """
    out = check_output_dir(outdir, REPORT_FILES, force=overwrite,
                           force_hint="pass overwrite=True")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plotting import plot_backlash, plot_envelope, plot_feasible_set, plot_intervals

    out.mkdir(exist_ok=True)
    bl, lin = ident.backlash_, ident.linear_
    lines = [f"# {title}", ""]
    deta = lin.problem_.output_bound
    lines += ["## Experiment", "",
              f"- steady-state points: {np.size(steady_u)} (output error bound "
              f"{bound_text(bl.output_bound_)})",
              f"- PRBS samples: N = {np.size(prbs_u)}, level u* = {ident.u_star_:g} "
              f"(admissible range for Result 1: ({bl.admissible_prbs_range()[0]:.4g}, "
              f"{bl.admissible_prbs_range()[1]:.4g}))",
              f"- PRBS output error bound {bound_text(deta)}; SNR of the measured output "
              f"against the bound (22.39): {snr_db(np.asarray(prbs_y) - 0, deta):.1f} dB",
              f"- stage 2: method `{lin.method}`"
              + (f", relaxation order {lin.relaxation_order}, solver {lin.solver}"
                 if lin.method == "moment" else "")
              + f", inner signal `{ident.inner_signal}`", ""]
    # stage 1
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, fs, k in ((axes[0], bl.left_, 0), (axes[1], bl.right_, 2)):
        tp = None if gamma_true is None else gamma_true[k:k + 2]
        plot_feasible_set(fs, ax, true_params=tp)
        ax.set_title(f"{fs.side} side")
    fig.tight_layout()
    fig.savefig(out / "backlash_sets.png", dpi=120)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(6, 4.5))
    plot_backlash(bl, steady_u, steady_y, ax, output_bound=bl.output_bound_,
                  u_star=ident.u_star_, inner_bounds=ident.inner_bounds_,
                  true_backlash=gamma_true)
    ax.set_title("backlash characteristic and its guaranteed band")
    fig.tight_layout()
    fig.savefig(out / "backlash_characteristic.png", dpi=120)
    plt.close(fig)
    lines += ["## Stage 1: backlash", "", interval_table(
        ("ml", "cl", "mr", "cr"), bl.gamma_bounds_, gamma_true), "",
        "![backlash characteristic](backlash_characteristic.png)", "",
        "![backlash feasible sets](backlash_sets.png)", ""]
    for fs in (bl.left_, bl.right_):
        v = np.asarray(fs.vertices_mb)
        lines.append(f"- {fs.side} set: {v.shape[0]} vertices in (m, beta = m c)")
    ib = ident.inner_bounds_
    lines += ["", "### Inner-signal bounds (22.25)-(22.30)", "",
              f"- x for u = +u*: [{ib.x_hi[0]:.6f}, {ib.x_hi[1]:.6f}]",
              f"- x for u = -u*: [{ib.x_lo[0]:.6f}, {ib.x_lo[1]:.6f}]", ""]
    # stage 2
    lines += ["## Stage 2: linear block", "",
              interval_table(lin.param_names_, lin.bounds_, theta_true), ""]
    if lin.box_limited_:
        lines += [f"Interval ends set by the a priori stability box (A1): "
                  f"{', '.join(lin.box_limited_)}.", ""]
    lines += ["| bound | status | certified | time [s] | iterations/nodes |",
              "|---|---|:---:|---:|---:|"]
    for info in lin.bound_info_:
        it = info.nodes if info.nodes is not None else info.iterations
        lines.append(f"| {info.sense} {info.param} | {info.status} | "
                     f"{'yes' if info.certified else 'no'} | {info.time:.2f} | {it} |")
    fig, ax = plt.subplots(figsize=(6, 3.5))
    plot_intervals(lin.bounds_, list(lin.param_names_), ax, true_values=theta_true,
                   labels=[lin.method])
    fig.tight_layout()
    fig.savefig(out / "intervals.png", dpi=120)
    plt.close(fig)
    lo, hi = ident.output_envelope(prbs_u, prbs_y)
    t = np.arange(np.size(prbs_y))
    fig, ax = plt.subplots(figsize=(9, 3.5))
    plot_envelope(t, prbs_y, lo, hi, ax, center=ident.predict(prbs_u))
    ax.set_title("PRBS output, central model and guaranteed one-step envelope")
    fig.tight_layout()
    fig.savefig(out / "envelope.png", dpi=120)
    plt.close(fig)
    banded = np.isfinite(lo) & np.isfinite(hi)   # the first n0 samples have no band
    yv = np.asarray(prbs_y, dtype=float)
    inside = float(np.mean((yv[banded] >= lo[banded] - deta[banded])
                           & (yv[banded] <= hi[banded] + deta[banded])))
    lines += ["", "![intervals](intervals.png)", "",
              "### Output envelope", "",
              "Every noise-free output consistent with the intervals and the past data lies "
              "in the one-step band; measurements may deviate from it by at most the noise "
              f"bound. Fraction of measurements within band +- output bound: {inside:.3f} "
              f"(over the {int(banded.sum())} samples that have a band; the first "
              f"{int((~banded).sum())} start the recursion).",
              "", "![envelope](envelope.png)", ""]
    path = out / "report.md"
    path.write_text("\n".join(lines))
    return path

