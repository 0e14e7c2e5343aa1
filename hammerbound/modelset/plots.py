"""Figures of the model set: Bode envelope and backlash compensation (matplotlib)."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_bode_envelope", "plot_compensation", "plot_weight"]


def _axes(ax, n):
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(n, 1, figsize=(7, 2.6 * n), sharex=(n > 1), squeeze=False)
        return fig, list(ax[:, 0])
    ax = list(np.ravel(ax))
    if len(ax) != n:
        from ..exceptions import ParameterValidationError

        raise ParameterValidationError(f"pass {n} axes (magnitude, phase); got {len(ax)}.")
    return ax[0].figure, ax


def _db(x):
    with np.errstate(divide="ignore"):
        return 20 * np.log10(np.asarray(x, dtype=float))


def _magnitude_limits(env, db, mag_range_db):
    """``(bottom, top)`` of the magnitude axis: every finite bound and the central model,
    but not more than ``mag_range_db`` below the largest finite upper bound (dB only)."""
    conv = _db if db else np.asarray
    up = conv(env.mag_upper[np.isfinite(env.mag_upper)])
    cen = conv(env.mag_central[np.isfinite(env.mag_central)])
    lo = conv(env.mag_lower)
    vals = np.concatenate([up, cen, lo])
    vals = vals[np.isfinite(vals)]
    top = float(np.max(vals)) if vals.size else 1.0
    bottom = float(np.min(vals)) if vals.size else 0.0
    if db:
        bottom = max(bottom, top - float(mag_range_db))
    pad = 0.05 * (top - bottom) if top > bottom else 1.0
    return bottom, top + pad


def plot_bode_envelope(env, ax=None, *, samples=None, max_samples=200, db=True,
                       mag_range_db=120.0):
    """Magnitude and phase envelope, the central model and (optionally) sampled responses.

    ``samples``: complex responses of shape (k, n) at ``env.omega`` (e.g. from certified
    samples), drawn thin and grey. The magnitude axis spans at most ``mag_range_db`` (dB)
    below the largest finite upper bound: where a lower bound is smaller (e.g. 0, a zero
    of ``B`` in the box) the band is drawn on to the bottom edge -- it continues below the
    axis, never stops at a bound that is not one -- and the legend says so; likewise the
    band runs to the top edge where there is no upper bound. Returns the figure.
    """
    from ..data.iodata import signal_label

    fig, (am, ap) = _axes(ax, 2)
    w = env.omega
    conv = _db if db else np.asarray
    bottom, top = _magnitude_limits(env, db, mag_range_db)
    span = top - bottom
    lo, up = conv(env.mag_lower), conv(env.mag_upper)
    below = ~(lo >= bottom)  # includes 0 (-inf dB)
    unbounded = ~np.isfinite(env.mag_upper)
    # beyond the axis limits (clipped by matplotlib): the band visibly runs off the axes
    lo_shown = np.where(below, bottom - span, lo)
    up_shown = np.where(unbounded, top + span, up)
    am.fill_between(w, lo_shown, up_shown, color="C0", alpha=0.25, lw=0,
                    label="guaranteed envelope")
    ph0 = env.phase_central
    ap.fill_between(w, np.degrees(env.phase_lower), np.degrees(env.phase_upper), color="C0",
                    alpha=0.25, lw=0)
    if samples is not None:
        s = np.asarray(samples)[:max_samples]
        rel = np.angle(s / env.central)
        for k, r in enumerate(s):
            am.plot(w, conv(np.abs(r)), color="0.4", lw=0.3, alpha=0.5,
                    label="certified samples" if k == 0 else None)
            ap.plot(w, np.degrees(ph0 + rel[k]), color="0.4", lw=0.3, alpha=0.5)
    am.plot(w, conv(env.mag_central), color="C3", lw=1.2, label="central model")
    ap.plot(w, np.degrees(ph0), color="C3", lw=1.2)
    unit = "dB" if db else ""
    if below.any():
        what = "0" if np.any(env.mag_lower <= 0) else f"< {bottom:.3g} {unit}".rstrip()
        am.plot([], [], " ", label=f"lower bound {what} where the band meets the bottom "
                                   "edge (axis cut)")
    if unbounded.any():
        am.plot([], [], " ", label="no upper bound where the band meets the top edge")
    am.set_ylim(bottom, top)
    for a in (am, ap):
        a.set_xscale("log")
        a.grid(True, which="both", alpha=0.3)
    names, units = env.signal_names, env.signal_units
    def par(x):
        return f"({x})" if "/" in x or " " in x else x

    ratio = f" re 1 {par(units[1])}/{par(units[0])}" if db and all(units) else ""
    am.set_ylabel(f"magnitude [dB{ratio}]" if db else "magnitude")
    ap.set_ylabel("phase [deg]")
    ap.set_xlabel(f"frequency [{env.frequency_unit}]")
    title = signal_label(names, units)
    if title:
        am.set_title(title, fontsize=9)
    am.legend(loc="best", fontsize=8)
    return fig


def plot_weight(uw, ax=None, *, db=True):
    """``|W|`` of an :class:`~hammerbound.modelset.UncertaintyWeight` over the exact
    deviation bound on its fit grid (log frequency axis). Returns the Axes."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(7, 3.5))
    conv = _db if db else np.asarray
    w = uw.omega
    keep = w > 0  # log axis
    ax.plot(w[keep], conv(uw.deviation[keep]), color="C0", lw=1.2,
            label=f"exact {uw.kind} deviation bound")
    ax.plot(w[keep], conv(uw.magnitude()[keep]), color="C3", lw=1.2,
            label=f"|W| (order {uw.order}, certified)")
    ax.set_xscale("log")
    ax.grid(True, which="both", alpha=0.3)
    ax.set_xlabel(f"frequency [{uw.frequency_unit}]")
    ax.set_ylabel("magnitude [dB]" if db else "magnitude")
    ax.legend(loc="best", fontsize=8)
    return ax


def plot_compensation(inv, ax=None, *, n=400, samples=None, max_samples=30):
    """Left: backlash lines with their feasible bands. Right: residual ``x - v`` of the
    compensated backlash vs the command ``v``, its guaranteed band, the uncompensated
    error for reference, and simulated cycles for backlash ``samples`` of shape (k, 4),
    if given. Returns the figure."""
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    fig = np.ravel(ax)[0].figure
    a1, a2 = np.ravel(ax)[:2]
    ml, cl, mr, cr = inv.gamma
    u = np.linspace(inv.u_range[0], inv.u_range[1], n)
    R, L = inv.right_vertices, inv.left_vertices
    r_all = R[None, :, 0] * u[:, None] - R[None, :, 1]
    l_all = L[None, :, 0] * u[:, None] + L[None, :, 1]
    # left line C0, right line C1, as in every other figure of the package (trial 15)
    a1.fill_between(u, l_all.min(1), l_all.max(1), color="C0", alpha=0.3, lw=0,
                    label="left line, feasible band")
    a1.fill_between(u, r_all.min(1), r_all.max(1), color="C1", alpha=0.3, lw=0,
                    label="right line, feasible band")
    a1.plot(u, ml * (u + cl), "C0", lw=1)
    a1.plot(u, mr * (u - cr), "C1", lw=1)
    a1.set_xlabel("u")
    a1.set_ylabel("x")
    a1.set_title("backlash characteristic")
    a1.legend(fontsize=8)
    v = np.linspace(inv.v_range[0], inv.v_range[1], n)
    lo, hi = inv.error_bounds(v)
    a2.fill_between(v, lo, hi, color="C2", alpha=0.3, lw=0, label="guaranteed band of x - v")
    a2.axhline(0.0, color="k", lw=0.8)
    # slopes inverted but no dead-band compensation (u = v / m): x trails by m c
    a2.axhline(-mr * cr, color="k", ls="--", lw=0.8, label="no dead-band inverse, rising")
    a2.axhline(ml * cl, color="k", ls=":", lw=0.8, label="no dead-band inverse, falling")
    if samples is not None:
        from ..systems.models import simulate_backlash

        cyc = np.concatenate([np.linspace(inv.x0, inv.v_range[1], n // 2),
                              np.linspace(inv.v_range[1], inv.v_range[0], n),
                              np.linspace(inv.v_range[0], inv.v_range[1], n)])
        uu = inv.compensate(cyc)
        for k, g in enumerate(np.asarray(samples)[:max_samples]):
            x = simulate_backlash(uu, *g, x0=inv.x0)
            a2.plot(cyc, x - cyc, color="0.3", lw=0.4, alpha=0.6,
                    label="compensated, feasible backlashes" if k == 0 else None)
    a2.set_xlabel("commanded v")
    a2.set_ylabel("residual x - v")
    a2.set_title("compensated characteristic: residual error")
    a2.legend(fontsize=7)
    fig.tight_layout()
    return fig
