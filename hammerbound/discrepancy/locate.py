"""Step 1: where and by how much does the model disagree with the data?"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.signal import lfilter

from .._compat import DEPRECATED, renamed_value
from .checks import int_param, validate
from .fitting import Design, certified_above, design, fit_design, outside
from .report import ConditionEvidence, Disagreement

__all__ = ["locate"]


def _conditions(u, resid, flagged, scored, window):
    du = np.diff(u, prepend=u[0])
    n = u.size
    change = np.abs(du) > 1e-12 * (np.max(np.abs(u)) + 1e-300)
    reversal = np.zeros(n, bool)
    last = 0.0
    for t in np.flatnonzero(change):
        sgn = np.sign(du[t])
        if last != 0.0 and sgn != last:
            reversal[t] = True
        last = sgn

    def after(ev):
        m = np.zeros(n, bool)
        for t in np.flatnonzero(ev):
            m[t : t + window] = True
        return m

    au = np.abs(u)
    q25, q75 = np.quantile(au, [0.25, 0.75])
    masks = {
        "after_reversal": after(reversal),
        "after_input_change": after(change),
        "steady_state": ~after(change),
        "large_amplitude": au >= q75,
        "small_amplitude": au <= q25,
    }
    out = []
    nv = int(np.sum(flagged & scored))
    ns = int(np.sum(scored))
    for name, m in masks.items():
        m = m & scored
        share_s = float(np.sum(m)) / max(ns, 1)
        share_v = float(np.sum(m & flagged)) / nv if nv else 0.0
        enr = share_v / share_s if (nv and share_s > 0) else float("nan")
        mar = float(np.mean(np.abs(resid[m]))) if np.any(m) else float("nan")
        out.append(ConditionEvidence(name, share_s, share_v, enr, mar))
    return tuple(out)


#: the conditions of :func:`_conditions` as phrases ("... concentrate <phrase>")
_WHERE = {"after_reversal": "after input reversals",
          "after_input_change": "after input changes",
          "steady_state": "in steady state",
          "large_amplitude": "at large input amplitudes",
          "small_amplitude": "at small input amplitudes"}


def _best_lag(y, yh, max_lag):
    best, bestc = 0, -np.inf
    for k in range(-max_lag, max_lag + 1):
        if k >= 0:
            a, b = y[k:], yh[: yh.size - k]
        else:
            a, b = y[: y.size + k], yh[-k:]
        if a.size < 3 or np.std(a) == 0 or np.std(b) == 0:
            continue
        c = float(np.corrcoef(a, b)[0, 1])
        if c > bestc + 1e-12:
            best, bestc = k, c
    return best


def locate(model, u, y=None, output_bound=None, *, refit: str = "linear", skip: int | str = "auto",
           window: int = 5, max_lag: int = 10, noise_bound=DEPRECATED) -> Disagreement:
    """Step 1: where and by how much does the model disagree with the data?

    Parameters
    ----------
    model, u, y, output_bound, refit, skip
        As in :func:`diagnose` (``noise_bound``: the deprecated name of ``output_bound``).
    window : int
        Samples after an input change / reversal counted as "after" it.
    max_lag : int
        Largest lag examined for ``best_lag``.

    Returns
    -------
    Disagreement
    """
    output_bound = renamed_value("locate", "output_bound", output_bound, "noise_bound",
                                 noise_bound)
    s, u, y, bound, do_refit, skip, _, skip_note = validate(model, u, y, output_bound, refit,
                                                            skip, "locate")
    window = int_param("window", window, 1)
    max_lag = int_param("max_lag", max_lag, 0)
    origin = s if s.origin is None else s.origin
    combo = ()
    if s.origin is not None:
        from . import effects as _effects

        combo = tuple((_effects.get(n), th) for n, th, _ in s.effect_params)
    d = design(origin, u, do_refit, combo, y, bound)
    dis, fit, _, tagged = locate_design(s, d, u, y, bound, skip, window, max_lag)
    return replace(dis, hints=check_hints(origin, combo, u, y, bound, do_refit, skip, max_lag,
                                          fit.error, tagged), skip=skip, skip_note=skip_note)


def check_hints(origin, combo, u, y, bound, refit, skip, max_delay, gap, tagged):
    """Keep a hint that points to a candidate only if that candidate scores: among the
    candidates the hints point to, the consistent ones when there are any, else those
    removing at least half of the gap above the output bound."""
    from . import effects as _effects
    from .effects import Context
    from .search import Problem, fit_combination

    tags = {t for t, _ in tagged if t is not None and t in _effects.REGISTRY}
    if not tags or gap <= bound:
        return tuple(text for t, text in tagged if t is None)
    ctx = Context(float(np.max(np.abs(u))), float(np.max(np.abs(y))), int(u.size),
                  max(1, min(max_delay, u.size - skip - 2)), bound)
    pb = Problem(origin, u, y, bound, refit, skip, 1e3, 24, ctx)
    old = tuple(e for e, _ in combo)
    cfs = {t: fit_combination(pb, (*old, _effects.get(t))) for t in tags}
    errs = {t: cf.error for t, cf in cfs.items()}
    ok = {t for t, cf in cfs.items()
          if not np.any(outside(y, cf.prediction, bound + cf.fit.allowance, skip))}
    keep = ok or {t for t, e in errs.items() if (gap - e) >= 0.5 * (gap - bound)}
    return tuple(text for t, text in tagged if t is None or t in keep)


def _last_direction(u):
    """Sign of the most recent non-zero input increment (0 before the first move)."""
    du = np.diff(u, prepend=u[0])
    tol = 1e-12 * (np.max(np.abs(u)) + 1e-300)
    sgn = np.where(np.abs(du) > tol, np.sign(du), 0.0)
    idx = np.where(sgn != 0, np.arange(u.size), 0)
    np.maximum.accumulate(idx, out=idx)
    return sgn[idx]


def _corr(a, b):
    if a.size < 3 or np.std(a) == 0 or np.std(b) == 0:
        return 0.0
    return float(np.corrcoef(a, b)[0, 1])


def _direction_correlation(s, u, y, f, Phi, skip):
    """Correlation of a refit residual with the model's response to the movement direction.

    A play (backlash) of half-width ``c`` shifts the signal entering the linear block by
    ``-c`` after upward and ``+c`` after downward input movements, so the residual of a
    model without it is about ``-c G(q^-1) dir_t``. The residual used here comes from a
    least-squares refit that includes a constant (so an offset does not leak into the
    refitted ``B`` and fake a correlation); ``G`` is the model's linear block (identity
    for a black box).
    """
    direction = _last_direction(u)
    if s.base is None:
        direction = lfilter(s.B, s.A, direction)
    P = np.column_stack([Phi, np.ones(y.size)])
    z = np.linalg.lstsq(P[skip:], (y - f)[skip:], rcond=None)[0]
    r = y - f - P @ z
    return _corr(r[skip:], direction[skip:])


def locate_design(s, d: Design, u, y, bound, skip, window, max_lag, coef_box=1e3):
    """Localisation for the model class ``d`` (``s``: the model as given).

    Returns ``(Disagreement, Fit, nominal prediction)``.
    """
    nominal = s.predict(u)
    fit = fit_design(y, d, skip, coef_box, bound)
    f, Phi = d.f, d.Phi
    resid = y - fit.prediction
    nres = y - nominal
    # localisation residual: least-squares refit (errors concentrate where the model fails,
    # whereas the minimax fit spreads them evenly)
    if Phi.shape[1]:
        zl = np.linalg.lstsq(Phi[skip:], (y - f)[skip:], rcond=None)[0]
        lres = y - f - Phi @ zl
    else:
        lres = y - f
    scored = np.arange(y.size) >= skip
    # judged against the bound and what the backlash's unknown start can still do
    near = bound + fit.allowance
    flagged = outside(y, y - lres, near, skip)
    # where are the *largest* disagreements? (top quintile of the out-of-band samples)
    worst = flagged.copy()
    if np.any(flagged):
        worst &= np.abs(lres) >= np.quantile(np.abs(lres[flagged]), 0.8)
    conds = _conditions(u, lres, worst, scored, window)
    ms = float(np.mean(resid[skip:]) / fit.error) if fit.error > 0 else 0.0
    dc = _direction_correlation(s, u, y, f, Phi, skip)
    lag = _best_lag(y[skip:], nominal[skip:], max_lag)
    hints = []  # (candidate the hint points to, or None for a plain observation; text)
    out_fit = outside(y, fit.prediction, near, skip)
    if not np.any(out_fit):
        hints.append((None, "the data are consistent with the model class under the output "
                            "bound"))
    else:
        if certified_above(fit.lower, y, fit.error, bound, skip):
            hints.append((None,
                f"certified: no refit of the model's parameters brings the error below "
                f"{fit.lower:.4g} > output bound {bound:.4g}"
            ))
        for c in conds:
            if np.isfinite(c.enrichment) and c.enrichment >= 1.5 and c.share_of_violations > 0.2:
                hints.append((None,
                    f"the largest disagreements concentrate {_WHERE.get(c.name, c.name)} "
                    f"({100 * c.share_of_violations:.0f}% of them vs "
                    f"{100 * c.share_of_samples:.0f}% of samples)"
                ))
        if abs(ms) > 0.5:
            hints.append(("offset", f"residual has a constant shift (mean = {ms:+.2f} x gap)"))
        if abs(dc) > 0.5:
            hints.append(("backlash",
                f"residual follows the direction of the last input movement (correlation "
                f"{dc:+.2f}): a hysteresis / play effect"
            ))
        if lag > 0:
            hints.append(("delay", f"the data lag the model by about {lag} sample(s)"))
    dis = Disagreement(
        gap=fit.error,
        gap_lower=fit.lower,
        fraction_outside=float(np.mean(out_fit[skip:])),
        ls_fraction_outside=float(np.mean(flagged[skip:])),
        nominal_gap=float(np.max(np.abs(nres[skip:]))),
        nominal_fraction_outside=float(np.mean(outside(y, nominal, near, skip)[skip:])),
        indices=np.flatnonzero(flagged),
        residual=resid,
        ls_residual=lres,
        nominal_residual=nres,
        conditions=conds,
        mean_shift=ms,
        direction_correlation=dc,
        best_lag=lag,
        hints=tuple(text for _, text in hints),
    )
    return dis, fit, nominal, hints
