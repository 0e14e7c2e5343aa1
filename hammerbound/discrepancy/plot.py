"""The diagnosis figure (:meth:`DiagnosisReport.plot`)."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_report"]


def _label(data, which):
    """``u``/``y``, or the IOData's signal name with its unit."""
    if data is None:
        return "u" if which == "input" else "y"
    name, unit = getattr(data, f"{which}_name"), getattr(data, f"{which}_unit")
    return f"{name} [{unit}]" if unit else name


def _panels(axes):
    import matplotlib.pyplot as plt

    if axes is None:
        fig, axes = plt.subplots(
            4, 1, figsize=(10, 10.5), gridspec_kw={"height_ratios": [1, 1.6, 1.6, 1.4]}
        )
        return fig, axes
    axes = list(np.ravel(axes))
    if len(axes) != 4:
        from ..exceptions import ParameterValidationError

        raise ParameterValidationError(
            f"pass 4 axes (input, output, residuals, candidates); got {len(axes)}.")
    return axes[0].figure, axes


def _time_axis(data, n):
    """The first ``n`` sample times and the axis label: the record's time
    (:attr:`~hammerbound.IOData.time`, in its time unit, seconds when none is given) when
    it has a sampling time, else the sample index."""
    if getattr(data, "dt", None) is None:
        return np.arange(n, dtype=float), "sample t"
    return np.asarray(data.time[:n], dtype=float), f"time ({data.time_unit or 's'})"


def plot_report(self, axes=None, *, max_samples=None):
    """Figure of a :class:`~.report.DiagnosisReport` (see its ``plot``) in ``axes`` (4
    Axes) or a new figure; returns the Figure."""
    n = self.y.size if max_samples is None else max(1, min(int(max_samples), self.y.size))
    t, xlabel = _time_axis(self.data, n)
    sl = slice(0, n)
    fig, axes = _panels(axes)
    fig.suptitle(
        f"Discrepancy diagnosis - missing effect: {self.effect_label};  "
        f"gap {self.gap_before:.3g} -> "
        f"{self.gap_after:.3g}  (output bound {self.output_bound:.3g})",
        fontsize=11,
    )
    ax = axes[0]
    ax.step(t, self.u[sl], where="post", color="k", lw=0.9)
    ax.set_ylabel(f"input {_label(self.data, 'input')}")
    ax = axes[1]
    ax.plot(t, self.y[sl], ".", ms=2.5, color="0.35", label="data y")
    ax.plot(t, self.prediction_nominal[sl], color="tab:orange", lw=1.0,
            label="model as given")
    ax.plot(t, self.prediction_after[sl], color="tab:blue", lw=1.0,
            label=f"refined ({self.effect or 'refit only'})")
    ax.set_ylabel(f"output {_label(self.data, 'output')}")
    ax.legend(loc="upper left", fontsize=8, ncol=3, framealpha=0.9)
    ax = axes[2]
    rb = (self.y - self.prediction_before)[sl]
    ra = (self.y - self.prediction_after)[sl]
    bound = self.output_bound
    ax.axhspan(-bound, bound, color="tab:green", alpha=0.2, lw=0,
               label=f"noise band +-{bound:.3g}")
    ax.plot(t, rb, color="tab:red", lw=0.8,
            label=f"before: gap {self.gap_before:.3g}, "
                  f"{100 * self.fraction_outside_before:.0f}% outside")
    ax.plot(t, ra, color="tab:blue", lw=0.8,
            label=f"after: gap {self.gap_after:.3g}, "
                  f"{100 * self.fraction_outside_after:.0f}% outside")
    if self.skip:
        ax.axvspan(t[0], t[min(self.skip, n - 1)], color="0.85", label="not scored (skip)")
    lim = 1.15 * max(np.max(np.abs(rb)), np.max(np.abs(ra)), bound)
    ax.set_ylim(-lim, 1.6 * lim)  # head-room for the legend
    ax.set_ylabel("residual y - yhat\n(minimax refit)")
    ax.set_xlabel(xlabel)
    ax.legend(loc="upper left", fontsize=8, ncol=3, framealpha=0.9)
    for a in axes[:3]:
        a.set_xlim(t[0], t[-1] if n > 1 else t[0] + 1)
    ax = axes[3]
    shown = [*self.candidates, *sorted(self.combinations, key=lambda c: c.minimax_error)[:4]]
    if shown:
        names = [c.name for c in shown]
        errs = np.array([max(c.minimax_error, 1e-300) for c in shown])
        colors = ["tab:blue" if c.name == self.effect
                  else ("tab:green" if c.consistent else "0.6") for c in shown]
        bars = ax.bar(names, errs, color=colors)
        if len(shown) > 6:
            ax.tick_params(axis="x", labelsize=7, labelrotation=20)
        for b, e in zip(bars, errs, strict=True):
            ax.annotate(f"{e:.3g}", (b.get_x() + b.get_width() / 2, e),
                        xytext=(0, 2), textcoords="offset points", ha="center",
                        va="bottom", fontsize=8,
                        bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 1})
        ax.set_yscale("log")
        lo = min(errs.min(), bound) / 2
        hi = max(errs.max(), self.gap_before) * 3
        ax.set_ylim(lo, hi)
    ax.axhline(bound, color="tab:green", ls="--", label="output bound")
    ax.axhline(self.gap_before, color="tab:red", ls=":", label="gap before")
    ax.set_ylabel("minimax error\nof candidate")
    ax.set_title("candidate evidence (blue: chosen, green: also consistent, "
                 "grey: inconsistent)", fontsize=9)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    return fig


