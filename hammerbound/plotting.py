"""Matplotlib figures: feasible sets, parameter intervals, output envelopes."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_envelope", "plot_feasible_set", "plot_intervals"]


def _axes(ax):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5, 4))
    return ax


def plot_feasible_set(fs, ax=None, *, true_params=None, show_orthotope=True, color="C0",
                      label=None):
    """Draw an exact backlash feasible set in ``(m, c)``: curved edges, vertices, orthotope."""
    ax = _axes(ax)
    curve = fs.boundary_mc()
    ax.fill(curve[:, 0], curve[:, 1], alpha=0.25, color=color,
            label=label or f"feasible set ({fs.side})")
    ax.plot(curve[:, 0], curve[:, 1], color=color, lw=1)
    ax.plot(fs.vertices[:, 0], fs.vertices[:, 1], "o", color=color, ms=4, label="vertices")
    if show_orthotope:
        (m0, m1), (c0, c1) = fs.orthotope
        ax.plot([m0, m1, m1, m0, m0], [c0, c0, c1, c1, c0], "--", color="k", lw=1,
                label="tight orthotope (22.22)")
    if true_params is not None:
        ax.plot(*true_params, "r*", ms=10, label="true value")
    n = [str(k).replace("_", "") for k in fs.param_names]  # "ml" -> $m_l$
    ax.set_xlabel(f"${n[0][0]}_{{{n[0][1:]}}}$")
    ax.set_ylabel(f"${n[1][0]}_{{{n[1][1:]}}}$")
    ax.ticklabel_format(useOffset=False)
    ax.legend(fontsize=7)
    return ax


def plot_intervals(bounds, names, ax=None, *, true_values=None, labels=None, normalise=True):
    """Horizontal interval bars, one group per parameter, several methods side by side.

    ``bounds`` is a ``(p, 2)`` array or a list of them (one per method). With ``normalise``
    every interval is drawn relative to the true value (or to the first method's centre)
    and scaled by the first method's half-width, so that parameters of different size fit
    one axis.
    """
    ax = _axes(ax)
    blist = [np.asarray(bounds)] if np.asarray(bounds[0]).ndim == 1 else [np.asarray(b) for b in bounds]
    labels = labels or [f"method {k}" for k in range(len(blist))]
    p = len(names)
    ref = np.asarray(true_values, float) if true_values is not None else blist[0].mean(axis=1)
    scale = np.maximum(0.5 * (blist[0][:, 1] - blist[0][:, 0]), 1e-300) if normalise else np.ones(p)
    for k, (b, lab) in enumerate(zip(blist, labels, strict=False)):
        off = (k - (len(blist) - 1) / 2) * 0.15
        lo = (b[:, 0] - ref) / scale
        hi = (b[:, 1] - ref) / scale
        ax.hlines(np.arange(p) + off, lo, hi, color=f"C{k}", lw=4, label=lab)
    if true_values is not None:
        ax.plot(np.zeros(p), np.arange(p), "r|", ms=14, mew=2, label="true value")
    ax.set_yticks(np.arange(p), names)
    ax.set_xlabel("(bound - true) / half-width of first method" if normalise else "value")
    ax.legend(fontsize=7)
    return ax


def plot_envelope(t, y, lower, upper, ax=None, *, center=None, label="data"):
    """Measured output with the guaranteed output envelope of the identified model."""
    ax = _axes(ax)
    ax.fill_between(t, lower, upper, color="C0", alpha=0.3, step="mid", label="output envelope")
    if center is not None:
        ax.plot(t, center, color="C0", lw=1, label="central model")
    ax.plot(t, y, ".", color="k", ms=3, label=label)
    ax.set_xlabel("sample t")
    ax.set_ylabel("output")
    ax.legend(fontsize=7)
    return ax
