"""Markdown report (with PNG figures) of a one-record :class:`HammersteinBacklashIdentifier`.

The report of the two experiments is :mod:`.report`; this one is the same for a fit from
one ordinary record (``procedure_ == "one-record"``): the record, the assumptions and the
central model, the intervals of both blocks with each end's status, the characteristic
band of the backlash intervals and the guaranteed one-step envelope against the record.
:func:`write_record_report` builds and writes it in one call.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..results import OutputEnvelope, Result, jsonable
from ..systems.experiments import snr_db
from ..tables import bound_text
from .paths import check_output_dir
from .report import assumption_lines, checked_axes, envelope_lines, interval_table, time_axis

__all__ = ["RECORD_REPORT_FILES", "RecordReport", "write_record_report"]

#: The files :func:`write_record_report` writes into its directory (nothing else there is
#: touched).
RECORD_REPORT_FILES = ("report.md", "backlash_characteristic.png", "intervals.png",
                       "envelope.png")


def _status_table(infos) -> list:
    lines = ["| bound | status | time [s] | nodes |", "|---|---|---:|---:|"]
    for info in infos:
        nodes = "" if info.nodes is None else info.nodes
        lines.append(f"| {info.sense} {info.param} | {info.status} | {info.time:.2f} | "
                     f"{nodes} |")
    return lines


def line_bands(gamma_bounds, u):
    """Range of the left line ``m_l (u + c_l)`` and of the right line ``m_r (u - c_r)``
    over the box ``gamma_bounds`` (rows m_l, c_l, m_r, c_r), at the inputs ``u``: each is
    bilinear in its two parameters, so its extremes lie at the box's corners."""
    g = np.asarray(gamma_bounds, dtype=float)
    u = np.atleast_1d(np.asarray(u, dtype=float))
    left = np.array([m * (u + c) for m in g[0] for c in g[1]])
    right = np.array([m * (u - c) for m in g[2] for c in g[3]])
    return left.min(axis=0), left.max(axis=0), right.min(axis=0), right.max(axis=0)


@dataclass(frozen=True, eq=False, repr=False)
class RecordReport(Result):
    """The identification report of a one-record fit and its record.

    Build it with :meth:`build`; ``summary()`` is the Markdown text of ``report.md``.
    ``envelope`` is None when an interval is infinite (the record does not bound it).
    """

    ident: object
    u: np.ndarray
    y: np.ndarray
    envelope: OutputEnvelope | None
    gamma_true: np.ndarray | None = None
    theta_true: np.ndarray | None = None
    title: str = "hammerbound identification report (one record)"

    @classmethod
    def build(cls, ident, u, y, *, gamma_true=None, theta_true=None,
              title="hammerbound identification report (one record)"):
        """The report of ``ident`` (fitted on the one-record path) on its record."""
        from ..exceptions import ParameterValidationError

        if getattr(ident, "procedure_", None) != "one-record":
            raise ParameterValidationError(
                "RecordReport is the report of a one-record fit; a fit of the two "
                "experiments has hammerbound.app.report.IdentificationReport.")
        u, y = np.asarray(u, dtype=float), np.asarray(y, dtype=float)
        env = (ident.output_envelope(u, y) if np.all(np.isfinite(ident.bounds_)) else None)
        return cls(ident, u, y, env, gamma_true, theta_true, title)

    # ------------------------------------------------------------------ text
    def _record(self) -> list:
        from ..joint import reversal_summary
        from ..tables import dt_text

        ident, lin = self.ident, self.ident.linear_
        pr, rev = lin.problem_, reversal_summary(self.u)
        deta = np.asarray(pr.deta, dtype=float)  # per sample, as the fit used it
        return ["## Record", "",
                f"- N = {self.u.size} samples, sampling time "
                f"{dt_text(getattr(ident, 'dt_', None), getattr(lin, 'time_unit_', ''))}",
                f"- input range [{self.u.min():.4g}, {self.u.max():.4g}]; largest "
                f"reversals {rev['down']:.4g} down, {rev['up']:.4g} up (the dead band is "
                "identified only where the input moves back by more than it)",
                f"- output error bound {bound_text(deta)}; SNR of the measured output "
                f"against the bound: {snr_db(self.y, float(np.max(deta))):.1f} dB",
                f"- method `{lin.method}`, na = {pr.na}, nb = {pr.nb}, nk = {pr.nk}, initial "
                "backlash state unknown", ""]

    def _backlash(self) -> list:
        ident = self.ident
        return ["## Backlash", "",
                interval_table(ident.backlash_.intervals_.param_names, ident.gamma_bounds_,
                               self.gamma_true), "",
                *_status_table(ident.bound_info_[:8]), "",
                "![backlash characteristic](backlash_characteristic.png)", ""]

    def _linear(self) -> list:
        lin = self.ident.linear_
        lines = ["## Linear block", "",
                 interval_table(lin.param_names_, lin.bounds_, self.theta_true), "",
                 *_status_table(self.ident.bound_info_[8:]), "",
                 "![intervals of both blocks](intervals.png)", "", "### Output envelope", ""]
        if self.envelope is None:
            return lines + ["No envelope: an interval is infinite (the record does not "
                            "bound it).", ""]
        return lines + envelope_lines(self.envelope)

    def summary(self) -> str:
        """The Markdown text of ``report.md`` (figures referenced by file name)."""
        return "\n".join([f"# {self.title}", "", *self._record(),
                          *assumption_lines(self.ident), *self._backlash(), *self._linear()])

    def to_dict(self) -> dict:
        """JSON-serialisable: the intervals of both blocks, the envelope's coverage and the
        assumptions."""
        env = None if self.envelope is None else {
            "coverage": self.envelope.coverage(), "n_banded": int(self.envelope.banded.sum())}
        return jsonable({"title": self.title, "procedure": "one-record",
                         "intervals": self.ident.intervals_.to_dict(), "envelope": env,
                         "assumptions": list(self.ident.assumptions_)})

    # ------------------------------------------------------------------ figures
    def _draw_characteristic(self, ax):
        g = self.ident.gamma_bounds_
        umax = 1.05 * float(np.max(np.abs(self.u)))
        grid = np.linspace(-umax, umax, 200)
        if np.all(np.isfinite(g)):
            llo, lhi, rlo, rhi = line_bands(g, grid)
            ax.fill_between(grid, llo, lhi, color="C0", alpha=0.25, lw=0,
                            label="left line over the box")
            ax.fill_between(grid, rlo, rhi, color="C1", alpha=0.25, lw=0,
                            label="right line over the box")
            ml, cl, mr, cr = g.mean(axis=1)
            ax.plot(grid, ml * (grid + cl), color="C0", lw=1, label="central left line")
            ax.plot(grid, mr * (grid - cr), color="C1", lw=1, label="central right line")
        else:
            ax.text(0.5, 0.5, "a backlash interval is infinite:\nno band", ha="center",
                    va="center", transform=ax.transAxes)
        if self.gamma_true is not None:
            tl, tcl, tr, tcr = self.gamma_true
            ax.plot(grid, tl * (grid + tcl), "k--", lw=0.8, label="true lines")
            ax.plot(grid, tr * (grid - tcr), "k--", lw=0.8)
        ax.set_xlabel("u")
        ax.set_ylabel("x")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize="small")
        ax.set_title("backlash lines over the intervals")

    def _draw_intervals(self, ax):
        from ..plotting import plot_relative_intervals

        truth = (None if self.gamma_true is None or self.theta_true is None
                 else np.r_[self.gamma_true, self.theta_true])
        plot_relative_intervals(self.ident.bounds_, self.ident.param_names_, ax,
                                true_values=truth)
        ax.set_title("intervals of both blocks, relative to their centres")

    def _draw_envelope(self, ax):
        if self.envelope is None:
            ax.text(0.5, 0.5, "an interval is infinite: no envelope", ha="center",
                    va="center", transform=ax.transAxes)
            return
        self.envelope.plot(ax, center=self.ident.predict(self.u), **time_axis(self.ident))
        ax.set_title("record output, central model and guaranteed one-step envelope")

    def plot(self, ax=None):
        """Every figure of the report in one (characteristic, intervals, envelope); ``ax``:
        3 Axes or None. Returns the Figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig = plt.figure(figsize=(12, 8))
            grid = fig.add_gridspec(2, 2)
            ax = [fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1]),
                  fig.add_subplot(grid[1, :])]
        ax = checked_axes(ax, "characteristic, intervals, envelope")
        self._draw_characteristic(ax[0])
        self._draw_intervals(ax[1])
        self._draw_envelope(ax[2])
        fig = ax[0].figure
        fig.tight_layout()
        return fig

    def write(self, outdir, *, overwrite=False, terms=None) -> Path:
        """Write ``report.md`` and its figures into ``outdir`` (see
        :func:`write_record_report`)."""
        from .report import linear_panels, write_panels

        out = check_output_dir(outdir, RECORD_REPORT_FILES, force=overwrite,
                               force_hint="pass overwrite=True")
        write_panels(out, (("backlash_characteristic.png", (1, 1), (6, 4.5),
                            self._draw_characteristic), *linear_panels(self)))
        path = out / "report.md"
        text = self.summary()
        path.write_text(text if terms is None else terms(text))
        return path


def write_record_report(ident, u, y, outdir, *, gamma_true=None, theta_true=None,
                        title="hammerbound identification report (one record)",
                        overwrite=False, terms=None) -> Path:
    """Write ``report.md`` and figures of a one-record fit into ``outdir``; return the path
    of the report. ``outdir`` as in :func:`hammerbound.app.report.write_report` (created if
    missing, its parent must exist, an existing report replaced only with
    ``overwrite=True``, other files never touched; the paths are checked first).
    ``terms``: a function that rewrites the report's text (the command line's
    :func:`~hammerbound.app.cli.console.cli_terms`: its advice then names flags)."""
    check_output_dir(outdir, RECORD_REPORT_FILES, force=overwrite,
                     force_hint="pass overwrite=True")
    rep = RecordReport.build(ident, u, y, gamma_true=gamma_true, theta_true=theta_true,
                             title=title)
    return rep.write(outdir, overwrite=overwrite, terms=terms)
