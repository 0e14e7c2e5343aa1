"""Matplotlib figures: feasible sets, parameter intervals, output envelopes."""

from __future__ import annotations

import numpy as np

from ._compat import DEPRECATED, renamed_value

__all__ = ["backlash_band", "plot_backlash", "plot_envelope", "plot_feasible_set",
           "plot_intervals", "plot_relative_intervals"]


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


def plot_intervals(bounds, names, ax=None, *, true_values=None, labels=None, normalise=None):
    """Horizontal interval bars, one group per parameter, several methods side by side.

    ``bounds`` is a ``(p, 2)`` array or a list of them (one per method). With ``normalise``
    every interval is drawn relative to the true value (or to the first method's centre)
    and scaled by the first method's half-width, so that parameters of different size fit
    one axis. ``normalise=None`` (default): normalise when there is a true value or more
    than one method to compare; a single set of intervals without a true value is drawn in
    its own units, with its centre marked.
    """
    ax = _axes(ax)
    blist = [np.asarray(bounds)] if np.asarray(bounds[0]).ndim == 1 else [np.asarray(b) for b in bounds]
    labels = labels or [f"method {k}" for k in range(len(blist))]
    p = len(names)
    if normalise is None:
        normalise = true_values is not None or len(blist) > 1
    if normalise:
        ref = np.asarray(true_values, float) if true_values is not None else blist[0].mean(axis=1)
        scale = np.maximum(0.5 * (blist[0][:, 1] - blist[0][:, 0]), 1e-300)
    else:
        ref, scale = np.zeros(p), np.ones(p)
    for k, (b, lab) in enumerate(zip(blist, labels, strict=False)):
        off = (k - (len(blist) - 1) / 2) * 0.15
        lo = (b[:, 0] - ref) / scale
        hi = (b[:, 1] - ref) / scale
        ax.hlines(np.arange(p) + off, lo, hi, color=f"C{k}", lw=4, label=lab)
        if not normalise:
            ax.plot(0.5 * (lo + hi), np.arange(p) + off, "k|", ms=10, label="centre"
                    if k == 0 else None)
    if true_values is not None:
        tv = (np.asarray(true_values, float) - ref) / scale
        ax.plot(tv, np.arange(p), "r|", ms=14, mew=2, label="true value")
    ax.set_yticks(np.arange(p), names)
    ax.set_xlabel("(bound - true) / half-width of first method" if normalise else "value")
    ax.legend(fontsize=7)
    return ax


def plot_relative_intervals(bounds, names, ax=None, *, true_values=None):
    """Each interval relative to its centre, in per cent of ``|centre|`` (of the half-width
    for an interval about 0, which then spans +-100 %): intervals of very
    different sizes and widths on one axis (in their own units, narrow intervals next to
    large values were invisible; new-user trial 15). An infinite interval is named as not
    bounded; ``true_values`` are marked."""
    ax = _axes(ax)
    b = np.asarray(bounds, dtype=float)
    p = len(names)
    finite = np.all(np.isfinite(b), axis=1)
    centre = np.where(finite, b.mean(axis=1), 0.0)
    half = np.where(finite, 0.5 * (b[:, 1] - b[:, 0]), 0.0)
    # |centre|, or the half-width for an interval about 0 (review: b in [-0.05, 0.05]
    # divided by 1e-300 hid every other interval)
    scale = np.where(finite, np.maximum(np.maximum(np.abs(centre), half), 1e-300), 1.0) / 100
    rows = np.arange(p)
    ax.hlines(rows[finite], ((b[:, 0] - centre) / scale)[finite],
              ((b[:, 1] - centre) / scale)[finite], color="C0", lw=4, label="interval")
    for k in rows[~finite]:
        ax.text(0.0, k, "not bounded", ha="center", va="center", fontsize=8)
    if true_values is not None:
        tv = (np.asarray(true_values, dtype=float) - centre) / scale
        ax.plot(tv[finite], rows[finite], "r|", ms=14, mew=2, label="true value")
    ax.axvline(0.0, color="k", lw=0.5)
    ax.set_yticks(rows, names)
    ax.set_xlabel("(bound - centre) / max(|centre|, half-width)  [%]")
    ax.legend(fontsize=7)
    return ax


def backlash_band(bl, u):
    """Exact range of the left and right backlash lines over the feasible sets.

    For a fitted :class:`~hammerbound.BacklashSetEstimator` ``bl`` and inputs ``u``:
    ``(left_lo, left_hi, right_lo, right_hi)``, the min/max over the exact feasible set of
    ``m_l (u + c_l) = m_l u + beta_l`` and of ``m_r (u - c_r) = m_r u - beta_r``
    (linear in ``(m, beta)``, so attained at polygon vertices).
    """
    u = np.atleast_1d(np.asarray(u, dtype=float))
    out = np.empty((4, u.size))
    for k, uk in enumerate(u):
        out[0:2, k] = bl.left_.linear_range(uk, 1.0)
        out[2:4, k] = bl.right_.linear_range(uk, -1.0)
    return tuple(out)


def plot_backlash(bl, u=None, y=None, ax=None, *, output_bound=None, u_star=None,
                  inner_bounds=None, true_backlash=None, noise_bound=DEPRECATED):
    """The backlash characteristic ``x`` versus ``u`` with its guaranteed band.

    Draws the central left and right lines, the band each line can occupy over the exact
    feasible set (:func:`backlash_band`), the steady-state points ``(u, y)`` with their
    error bars (with the unit gain (22.8), the steady output is the inner signal), and,
    when given, the inner-signal bounds at the PRBS levels ``+-u*`` and the true lines.
    ``output_bound``: half-length of the error bars (default: none drawn);
    ``noise_bound`` is its deprecated name (removed in 0.3.0).
    """
    output_bound = renamed_value("plot_backlash", "output_bound", output_bound,
                                 "noise_bound", noise_bound)
    ax = _axes(ax)
    if u is not None:
        umax = float(np.max(np.abs(u)))
    else:
        umax = float(max(abs(v) for v in bl.input_range_))
    grid = np.linspace(-1.05 * umax, 1.05 * umax, 200)
    llo, lhi, rlo, rhi = backlash_band(bl, grid)
    ml, cl, mr, cr = bl.gamma_center_
    ax.fill_between(grid, llo, lhi, color="C0", alpha=0.25, lw=0, label="left line band")
    ax.fill_between(grid, rlo, rhi, color="C1", alpha=0.25, lw=0, label="right line band")
    ax.plot(grid, ml * (grid + cl), color="C0", lw=1, label="central left line")
    ax.plot(grid, mr * (grid - cr), color="C1", lw=1, label="central right line")
    if true_backlash is not None:
        g = getattr(true_backlash, "gamma", true_backlash)
        ax.plot(grid, g[0] * (grid + g[1]), "r--", lw=0.8, label="true lines")
        ax.plot(grid, g[2] * (grid - g[3]), "r--", lw=0.8)
    if u is not None and y is not None:
        yerr = None if output_bound is None else np.broadcast_to(
            np.asarray(output_bound, float), np.shape(y))
        ax.errorbar(u, y, yerr=yerr, fmt=".", color="k", ms=3, lw=0.6, capsize=0,
                    label="steady-state points")
    if u_star is not None and inner_bounds is not None:
        for uu, (lo, hi) in ((u_star, inner_bounds.x_hi), (-u_star, inner_bounds.x_lo)):
            ax.plot([uu, uu], [lo, hi], color="C3", lw=3)
        ax.plot([], [], color="C3", lw=3, label="inner-signal bounds at +-u*")
    ax.axhline(0, color="0.7", lw=0.5)
    ax.axvline(0, color="0.7", lw=0.5)
    ax.set_xlabel("input u")
    ax.set_ylabel("inner signal x (steady output, unit gain)")
    ax.legend(fontsize=7)
    return ax


def plot_envelope(t, y, lower, upper, ax=None, *, center=None, label="data", xlabel="sample t"):
    """Measured output (``y``; None: not drawn) with the guaranteed output envelope."""
    ax = _axes(ax)
    ax.fill_between(t, lower, upper, color="C0", alpha=0.3, step="mid", label="output envelope")
    if center is not None:
        ax.plot(t, center, color="C0", lw=1, label="central model")
    if y is not None:
        ax.plot(t, y, ".", color="k", ms=3, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("output")
    ax.legend(fontsize=7)
    return ax
