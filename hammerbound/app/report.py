"""Markdown report (with PNG figures) of a fitted two-stage :class:`HammersteinBacklashIdentifier`.

:class:`IdentificationReport` is the report as a result, with the shape of every result
(``summary()`` the Markdown text, ``to_dict()``, ``plot(ax=None)`` all figures in one,
``save(path)``) and :meth:`IdentificationReport.write` for the directory of ``report.md``
and its figures; :func:`write_report` builds and writes it in one call.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..results import IntervalSet, OutputEnvelope, Result, jsonable
from ..systems.experiments import snr_db
from ..tables import bound_text, outward_text
from .paths import check_output_dir

__all__ = ["REPORT_FILES", "IdentificationReport", "assumption_lines", "checked_axes",
           "envelope_lines", "interval_table", "linear_panels", "write_panels",
           "write_report"]

#: The files :func:`write_report` writes into its directory (nothing else there is touched).
REPORT_FILES = ("report.md", "backlash_characteristic.png", "backlash_sets.png", "intervals.png",
                "envelope.png")


def interval_table(names, bounds, true=None, fmt="4f") -> str:
    """Markdown table of intervals: parameter, lower, centre, upper, half-width (, true,
    inside); the ends rounded outward, the half-width up (:func:`~hammerbound.tables.
    outward_text`), as in every summary."""
    iv = IntervalSet(names, bounds)
    head = "| parameter | lower | centre | upper | half-width |"
    sep = "|---|---:|---:|---:|---:|"
    if true is not None:
        head += " true | inside |"
        sep += "---:|:---:|"
    rows = [head, sep]
    for k, name in enumerate(iv.param_names):
        cells = (iv.lower[k], iv.center[k], iv.upper[k], iv.radius[k])
        r = f"| {name} | " + " | ".join(outward_text(c, fmt, side) for c, side in
                                         zip(cells, (-1, 0, 1, 1), strict=True)) + " |"
        if true is not None:
            inside = IntervalSet((name,), iv.bounds[k:k + 1]).contains([true[k]])
            r += f" {outward_text(true[k], fmt, 0)} | {'yes' if inside else '**NO**'} |"
        rows.append(r)
    return "\n".join(rows)


def assumption_lines(ident) -> list:
    """The report's Assumptions section: what every interval of the fitted identifier
    ``ident`` rests on, and the central model with its sampling time (the report had
    neither; the text and JSON outputs do, trial 13)."""
    from ..tables import dt_text, poly_z, units_line

    lines = ["## Assumptions", "", *[f"- {a}" for a in ident.assumptions_], ""]
    units = units_line(getattr(ident, "units_", ("", ""))).strip()
    if units:  # recheck 49: the report had no units where the summary has them
        lines += [units[0].upper() + units[1:] + ".", ""]
    if not np.all(np.isfinite(ident.linear_.bounds_)):
        return lines + ["Central model: not given (a linear-block interval is "
                        "infinite).", ""]
    tf = ident.linear_.to_transfer_function()
    num, den = np.ravel(tf.num[0][0]), np.ravel(tf.den[0][0])
    unit = getattr(ident.linear_, "time_unit_", "")
    return lines + [f"Central model (the centre of the intervals): G(z) = "
                    f"({poly_z(num)}) / ({poly_z(den)}), sampling time "
                    f"{dt_text(getattr(ident, 'dt_', None), unit)}.", ""]


def envelope_lines(envelope) -> list:
    """What the one-step output envelope says of the data, and its figure."""
    b = envelope.banded
    return ["Every noise-free output consistent with the intervals and the past data lies "
            "in the one-step band; measurements may deviate from it by at most the noise "
            f"bound. Fraction of measurements within band +- output bound: "
            f"{envelope.coverage():.3f} (over the {int(b.sum())} samples that have a "
            f"band; the first {int((~b).sum())} start the recursion).",
            "", "![envelope](envelope.png)", ""]


def time_axis(ident) -> dict:
    """The keywords of :meth:`OutputEnvelope.plot` that draw a report's envelope over time
    when the fit knows its sampling time (trial 15: the envelope was in samples)."""
    return {"dt": getattr(ident, "dt_", None),
            "time_unit": getattr(ident.linear_, "time_unit_", "")}


def checked_axes(ax, names: str) -> list:
    """``ax`` as a flat list of one Axes per name of ``names`` (comma-separated), else a
    ParameterValidationError naming them."""
    ax = list(np.ravel(ax))
    n = len(names.split(","))
    if len(ax) != n:
        from ..exceptions import ParameterValidationError

        raise ParameterValidationError(f"pass {n} axes ({names}); got {len(ax)}.")
    return ax


def linear_panels(report) -> tuple:
    """The figures both reports draw of the linear block: its intervals and the output
    envelope (``report._draw_intervals``, ``report._draw_envelope``)."""
    return (("intervals.png", (1, 1), (6, 3.5), report._draw_intervals),
            ("envelope.png", (1, 1), (9, 3.5), report._draw_envelope))


def write_panels(out: Path, panels) -> None:
    """Draw and save each figure of ``panels`` -- ``(file name, subplot shape, size,
    draw(axes))`` -- into the directory ``out`` (created; matplotlib's Agg backend)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(exist_ok=True)
    for name, shape, size, draw in panels:
        fig, axes = plt.subplots(*shape, figsize=size)
        draw(axes)
        fig.tight_layout()
        fig.savefig(out / name, dpi=120)
        plt.close(fig)


@dataclass(frozen=True, eq=False, repr=False)
class IdentificationReport(Result):
    """The identification report of a fitted two-stage identifier and its data.

    Build it with :meth:`build`; ``summary()`` is the Markdown text of ``report.md``.
    """

    ident: object
    steady_u: np.ndarray
    steady_y: np.ndarray
    prbs_u: np.ndarray
    prbs_y: np.ndarray
    envelope: OutputEnvelope
    gamma_true: np.ndarray | None = None
    theta_true: np.ndarray | None = None
    title: str = "hammerbound identification report"

    @classmethod
    def build(cls, ident, steady_u, steady_y, prbs_u, prbs_y, *, gamma_true=None,
              theta_true=None, title="hammerbound identification report"):
        """The report of ``ident`` (fitted, two-stage) on its steady-state and PRBS data."""
        env = ident.output_envelope(prbs_u, prbs_y)
        return cls(ident, np.asarray(steady_u), np.asarray(steady_y), np.asarray(prbs_u),
                   np.asarray(prbs_y, dtype=float), env, gamma_true, theta_true, title)

    # ------------------------------------------------------------------ text
    def _experiment(self) -> list:
        ident = self.ident
        bl, lin = ident.backlash_, ident.linear_
        deta = lin.problem_.output_bound
        rng = bl.admissible_prbs_range()
        return ["## Experiment", "",
                f"- steady-state points: {np.size(self.steady_u)} (output error bound "
                f"{bound_text(bl.output_bound_)})",
                f"- PRBS samples: N = {np.size(self.prbs_u)}, level u* = {ident.u_star_:g} "
                f"(admissible range for Result 1: ({rng[0]:.4g}, {rng[1]:.4g}))",
                f"- PRBS output error bound {bound_text(deta)}; SNR of the measured output "
                f"against the bound (22.39): {snr_db(self.prbs_y - 0, deta):.1f} dB",
                f"- stage 2: method `{lin.method}`"
                + (f", relaxation order {lin.relaxation_order}, solver {lin.solver}"
                   if lin.method == "moment" else "")
                + f", inner signal `{ident.inner_signal}`", ""]

    def _stage1(self) -> list:
        bl, ib = self.ident.backlash_, self.ident.inner_bounds_
        lines = ["## Stage 1: backlash", "",
                 interval_table(bl.intervals_.param_names, bl.gamma_bounds_, self.gamma_true),
                 "", "![backlash characteristic](backlash_characteristic.png)", "",
                 "![backlash feasible sets](backlash_sets.png)", ""]
        for fs in (bl.left_, bl.right_):
            v = np.asarray(fs.vertices_mb)
            lines.append(f"- {fs.side} set: {v.shape[0]} vertices in (m, beta = m c)")
        return lines + ["", "### Inner-signal bounds (22.25)-(22.30)", "",
                        f"- x for u = +u*: [{ib.x_hi[0]:.6f}, {ib.x_hi[1]:.6f}]",
                        f"- x for u = -u*: [{ib.x_lo[0]:.6f}, {ib.x_lo[1]:.6f}]", ""]

    def _stage2(self) -> list:
        lin = self.ident.linear_
        lines = ["## Stage 2: linear block", "",
                 interval_table(lin.param_names_, lin.bounds_, self.theta_true), ""]
        if lin.box_limited_:
            lines += [f"Interval ends set by the a priori stability box (A1): "
                      f"{', '.join(lin.box_limited_)}.", ""]
        lines += ["| bound | status | certified | time [s] | iterations/nodes |",
                  "|---|---|:---:|---:|---:|"]
        for info in lin.bound_info_:
            it = info.nodes if info.nodes is not None else info.iterations
            lines.append(f"| {info.sense} {info.param} | {info.status} | "
                         f"{'yes' if info.certified else 'no'} | {info.time:.2f} | {it} |")
        return lines + ["", "![intervals](intervals.png)", "", "### Output envelope", "",
                        *envelope_lines(self.envelope)]

    def summary(self) -> str:
        """The Markdown text of ``report.md`` (figures referenced by file name)."""
        return "\n".join([f"# {self.title}", "", *self._experiment(),
                          *assumption_lines(self.ident), *self._stage1(), *self._stage2()])

    def to_dict(self) -> dict:
        """JSON-serialisable: the intervals of both blocks, ``u_star``, the inner-signal
        bounds, the envelope's coverage and the assumptions."""
        ident = self.ident
        ib = ident.inner_bounds_
        return jsonable({"title": self.title, "intervals": ident.intervals_.to_dict(),
                         "u_star": ident.u_star_,
                         "inner_bounds": {"x_hi": ib.x_hi, "x_lo": ib.x_lo},
                         "envelope": {"coverage": self.envelope.coverage(),
                                      "n_banded": int(self.envelope.banded.sum())},
                         "assumptions": list(ident.assumptions_)})

    # ------------------------------------------------------------------ figures
    def _draw_sets(self, axes):
        from ..plotting import plot_feasible_set

        bl = self.ident.backlash_
        for ax, fs, k in ((axes[0], bl.left_, 0), (axes[1], bl.right_, 2)):
            tp = None if self.gamma_true is None else self.gamma_true[k:k + 2]
            plot_feasible_set(fs, ax, true_params=tp)
            ax.set_title(f"{fs.side} side")

    def _draw_characteristic(self, ax):
        from ..plotting import plot_backlash

        bl = self.ident.backlash_
        plot_backlash(bl, self.steady_u, self.steady_y, ax, output_bound=bl.output_bound_,
                      u_star=self.ident.u_star_, inner_bounds=self.ident.inner_bounds_,
                      true_backlash=self.gamma_true)
        ax.set_title("backlash characteristic and its guaranteed band")

    def _draw_intervals(self, ax):
        lin = self.ident.linear_
        lin.intervals_.plot(ax, true_values=self.theta_true, label=lin.method)

    def _draw_envelope(self, ax):
        self.envelope.plot(ax, center=self.ident.predict(self.prbs_u), **time_axis(self.ident))
        ax.set_title("PRBS output, central model and guaranteed one-step envelope")

    def plot(self, ax=None):
        """Every figure of the report in one (feasible sets, characteristic, intervals,
        envelope); ``ax``: 5 Axes or None. Returns the Figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig = plt.figure(figsize=(12, 11))
            grid = fig.add_gridspec(3, 2)
            ax = [fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1]),
                  fig.add_subplot(grid[1, 0]), fig.add_subplot(grid[1, 1]),
                  fig.add_subplot(grid[2, :])]
        ax = checked_axes(ax, "left set, right set, characteristic, intervals, envelope")
        self._draw_sets(ax[:2])
        self._draw_characteristic(ax[2])
        self._draw_intervals(ax[3])
        self._draw_envelope(ax[4])
        fig = ax[0].figure
        fig.tight_layout()
        return fig

    def write(self, outdir, *, overwrite=False, terms=None) -> Path:
        """Write ``report.md`` and its figures into ``outdir`` (see :func:`write_report`)."""
        out = check_output_dir(outdir, REPORT_FILES, force=overwrite,
                               force_hint="pass overwrite=True")
        write_panels(out, (("backlash_sets.png", (1, 2), (10, 4), self._draw_sets),
                           ("backlash_characteristic.png", (1, 1), (6, 4.5),
                            self._draw_characteristic),
                           *linear_panels(self)))
        path = out / "report.md"
        text = self.summary()
        path.write_text(text if terms is None else terms(text))
        return path


def write_report(ident, steady_u, steady_y, prbs_u, prbs_y, outdir, *, gamma_true=None,
                 theta_true=None, title="hammerbound identification report",
                 overwrite=False, terms=None) -> Path:
    """Write ``report.md`` and figures into ``outdir``; return the path of the report.

    ``outdir`` is created if missing (its parent must exist). An existing report there
    (any of :data:`REPORT_FILES`) is replaced only with ``overwrite=True``; other files in
    ``outdir`` are never touched. The paths are checked before anything is computed.
    ``terms``: a function that rewrites the report's text (the command line passes
    :func:`~hammerbound.app.cli.console.cli_terms`, so its advice names flags).

    Raises
    ------
    OutputExistsError
        A report file exists in ``outdir`` and ``overwrite`` is false.
    OutputPathError
        ``outdir`` is a file, its parent is missing or it is not writable.

    The report lists the experiment (sizes, output error bounds, SNR of the PRBS output against
    the bound), the backlash feasible sets (vertices, orthotope, figure), the
    inner-signal bounds, the linear-block intervals with per-bound solver information,
    and the guaranteed one-step output envelope against the data. The same report as a
    result: :class:`IdentificationReport`.
    """
    check_output_dir(outdir, REPORT_FILES, force=overwrite, force_hint="pass overwrite=True")
    rep = IdentificationReport.build(ident, steady_u, steady_y, prbs_u, prbs_y,
                                     gamma_true=gamma_true, theta_true=theta_true, title=title)
    return rep.write(outdir, overwrite=overwrite, terms=terms)
