"""Parameter search for one combination of effects, fitted jointly.

For a combination ``E1 .. Ek`` the searched parameters of every effect are one vector;
for each value of it the model's refitted coefficients and the effects' linear
coefficients come from one minimax LP (:func:`.fitting.minimax`). Integer parameters are
enumerated; continuous ones are searched on a grid (1-D: bounded Brent; several: a
coarse product grid plus the given starting points, then Nelder-Mead) and refined down
to the rounding level when the error ends just above the output bound.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize, minimize_scalar

from .fitting import Design, Fit, design, fit_design, outside, rebuild
from .model import RefinedModel

__all__ = ["ComboFit", "Problem", "fit_combination"]


@dataclass(frozen=True)
class Problem:
    """Everything a fit needs besides the combination."""

    origin: RefinedModel
    u: np.ndarray
    y: np.ndarray
    bound: float
    refit: bool
    skip: int
    coef_box: float
    grid_size: int
    ctx: object
    refine_to_bound: bool = True  # refine errors just above the bound down to rounding
    on_lp: object = None  # called once per minimax LP solved (progress), or None


@dataclass(frozen=True)
class ComboFit:
    """Result of :func:`fit_combination`.

    ``error`` is achieved by ``model`` (recomputed from ``model.predict``); ``lower`` is a
    certified lower bound of the minimax error at ``thetas`` - over the whole class when
    ``exhaustive`` (no continuous parameter).
    """

    effects: tuple
    thetas: tuple
    fit: Fit
    design: Design
    model: RefinedModel
    prediction: np.ndarray
    error: float
    lower: float
    exhaustive: bool
    n_evaluations: int
    seconds: float
    int_ranking: dict = None

    @property
    def names(self) -> tuple:
        return tuple(e.name for e in self.effects)

    @property
    def n_params(self) -> int:
        return sum(e.n_params for e in self.effects)


class _Objective:
    """Cached minimax error as a function of the flat parameter vector."""

    def __init__(self, pb: Problem, effects, layout):
        self.pb, self.effects, self.layout = pb, effects, layout
        self.cache = {}

    def split(self, vec):
        out, k = [], 0
        for e in self.effects:
            n = len(e.param_names)
            out.append(tuple(float(v) for v in vec[k:k + n]))
            k += n
        return tuple(out)

    def __call__(self, vec):
        key = tuple(float(v) for v in vec)
        if key not in self.cache:
            pb = self.pb
            combo = tuple(zip(self.effects, self.split(key), strict=True))
            d = design(pb.origin, pb.u, pb.refit, combo, pb.y, pb.bound)
            target = pb.bound if pb.refine_to_bound else None
            self.cache[key] = (fit_design(pb.y, d, pb.skip, pb.coef_box, target, fast=True), d)
            _tick(pb)
        return self.cache[key][0].error

    def best(self):
        key = min(self.cache, key=lambda k: self.cache[k][0].error)
        return key, *self.cache[key]


def _tick(pb: Problem) -> None:
    if pb.on_lp is not None:
        pb.on_lp()


def _golden(g, a, b, xtol, max_iter=90, stop=None):
    """Golden-section search of ``g`` on ``[a, b]`` down to a bracket of width ``xtol``
    (or until a value ``<= stop`` is found)."""
    if not b > a:
        return
    r = 0.5 * (np.sqrt(5.0) - 1.0)
    c, d = b - r * (b - a), a + r * (b - a)
    fc, fd = g(c), g(d)
    for _ in range(max_iter):
        if b - a <= xtol or (stop is not None and min(fc, fd) <= stop):
            break
        if fc <= fd:
            b, d, fd = d, c, fc
            c = b - r * (b - a)
            fc = g(c)
        else:
            a, c, fc = c, d, fd
            d = a + r * (b - a)
            fd = g(d)


def _search_1d(g, p, grid_size, target, starts=(), coarse=False):
    """Grid search then bounded Brent refinement of a 1-D minimax error ``g``.

    When the error found lies just above ``target`` (the output bound: within 1 %), a final
    golden-section refinement brings it to the rounding level of the fit, so that data
    whose noise sits exactly at the bound are recognised as consistent.
    """
    lo, hi = p.lo, p.hi
    grid = np.unique(np.r_[p.grid(8 if coarse else grid_size),
                           [s for s in starts if lo <= s <= hi]])
    errs = np.array([g(v) for v in grid])
    i = int(np.argmin(errs))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    converged = False
    if b > a:
        res = minimize_scalar(g, bounds=(a, b), method="bounded",
                              options={"xatol": 1e-4 * (hi - lo), "maxiter": 8 if coarse else 25})
        converged = bool(res.success)
    # the minimax error is V-shaped (non-smooth) at its minimum, so the first search leaves
    # the parameter ~xatol off. Noise at exactly the bound makes the optimum *equal* to the
    # bound, so shrink that excess to the rounding level of the fit itself (golden
    # section, on the grid bracket when the first search did not converge).
    vbest = min((v for v in g.cache_keys()), key=g)
    if target is not None and target < g(vbest) <= 1.01 * target:
        span = 3e-4 * (hi - lo)
        if converged:
            a, b = max(a, vbest - span), min(b, vbest + span)
        _golden(g, a, b, 1e-14 * (hi - lo), stop=target)


class _Slice:
    """The objective along continuous coordinates, other coordinates fixed."""

    def __init__(self, obj, base, idx):
        self.obj, self.base, self.idx = obj, list(base), list(idx)
        self._keys = {}  # points evaluated, in order (no duplicates)

    def vec(self, v):
        x = list(self.base)
        for i, vi in zip(self.idx, np.atleast_1d(v), strict=True):
            x[i] = float(vi)
        return x

    def __call__(self, v):
        x = self.vec(v)
        self._keys.setdefault(tuple(np.atleast_1d(v).astype(float)), None)
        return self.obj(x)

    @property
    def keys(self):
        return list(self._keys)

    def cache_keys(self):
        return [k[0] for k in self._keys]


#: Nelder-Mead restarts from the best point of a several-parameter search while it is above
#: the output bound (a fresh simplex leaves the kinks the old one collapsed on)
RESTARTS = 2


def _search_nd(obj, base, cidx, params, grid_size, target, starts, coarse=False):
    """Joint search of several continuous parameters (coarse grid, then Nelder-Mead)."""
    k = len(cidx)
    f = _Slice(obj, base, cidx)
    per = 3 if coarse else max(3, int(round(min(grid_size, 40) ** (1.0 / k))))
    grids = [p.grid(per) for p in params]
    pts = [tuple(pt) for pt in itertools.product(*grids)]
    pts += [tuple(s) for s in starts]
    vals = [f(pt) for pt in pts]
    lo = np.array([p.lo for p in params])
    hi = np.array([p.hi for p in params])
    logs = np.array([p.log for p in params])

    def tr(v):
        return np.where(logs, np.log(np.where(logs, np.maximum(v, 1e-300), 1.0)), v)

    a, b = tr(lo), tr(hi)

    def to_unit(v):
        return (tr(v) - a) / (b - a)

    def from_unit(w):
        v = a + np.clip(w, 0.0, 1.0) * (b - a)
        return np.where(logs, np.exp(np.where(logs, v, 0.0)), v)

    opts = {"maxfev": (8 if coarse else 30) * k, "xatol": 1e-4,
            "fatol": 1e-12 * (1 + (target or 0.0))}

    def nelder_mead(start):
        minimize(lambda w: f(from_unit(w)), to_unit(np.asarray(start)), method="Nelder-Mead",
                 options=opts)

    def best_point():
        return np.array(min(list(f.keys), key=f))

    for j in np.argsort(vals)[: 1 if coarse else 2]:
        nelder_mead(pts[j])
    if coarse:
        return
    for _ in range(RESTARTS):  # Nelder-Mead stalls on the minimax error's kinks: restart
        if target is not None and f(best_point()) <= target:
            break
        nelder_mead(best_point())
    best = best_point()
    if target is not None and target < f(best) <= 1.01 * target:
        _pattern(f, best, lo, hi, target)


def _pattern(f, best, lo, hi, target, span=3e-3, xtol=1e-14):
    """Pattern search of ``f`` from ``best`` near the bound, down to the rounding level.

    The minimax error is a maximum of V-shaped terms (e.g. ``|lo - L|`` and ``|hi - H|``
    for two sensor limits): a coordinate-wise search stalls on its plateaus, so every
    direction of ``{-1, 0, 1}^k`` is polled (diagonals move all terms at once); the step
    starts at ``span`` of each range and is halved when no direction improves, down to
    ``xtol`` of the range, or until the error reaches ``target``.
    """
    k = best.size
    dirs = [np.array(d, float) for d in itertools.product((-1, 0, 1), repeat=k) if any(d)]
    dirs.sort(key=lambda d: -np.count_nonzero(d))  # diagonals first
    width = hi - lo
    step, fb = span, f(best)
    while step > xtol and fb > target:
        for d in dirs:
            x = np.clip(best + step * width * d, lo, hi)
            fx = f(x)
            if fx < fb:
                best, fb = x, fx
                break
        else:
            step /= 2.0


def fit_combination(pb: Problem, effects, *, starts=None, int_choices=None,
                    coarse=False) -> ComboFit:
    """Fit the effects ``effects`` (a sequence of :class:`~.effects.Effect`) jointly.

    Parameters
    ----------
    starts : sequence of tuple of tuples, optional
        Extra starting points, one parameter tuple per effect (e.g. the best single fits).
    int_choices : dict, optional
        ``{(effect index, parameter index): values}`` restricting integer parameters
        (default: every integer in the parameter's range).
    coarse : bool
        A cheap screening search (small grids, short refinement).
    """
    t0 = time.perf_counter()
    effects = tuple(effects)
    spaces = [e.search_space(pb.ctx) for e in effects]
    flat = [(i, j, p) for i, sp in enumerate(spaces) for j, p in enumerate(sp)]
    obj = _Objective(pb, effects, flat)
    int_idx = [n for n, (_, _, p) in enumerate(flat) if p.integer]
    cont_idx = [n for n, (_, _, p) in enumerate(flat) if not p.integer]
    int_vals = []
    for n in int_idx:
        i, j, p = flat[n]
        vals = None if int_choices is None else int_choices.get((i, j))
        int_vals.append(sorted({int(round(v)) for v in (vals if vals is not None
                                                          else p.grid(0))}))
    full_enum = int_choices is None or all(
        int_choices.get((flat[n][0], flat[n][1])) is None for n in int_idx)
    flat_starts = [tuple(v for th in s for v in th) for s in (starts or ())]
    target = pb.bound if pb.refine_to_bound else None
    for ivals in itertools.product(*int_vals):
        base = [0.0] * len(flat)
        for n, v in zip(int_idx, ivals, strict=True):
            base[n] = float(v)
        if not cont_idx:
            obj(base)
            continue
        cs = [tuple(s[n] for n in cont_idx) for s in flat_starts if len(s) == len(flat)]
        if len(cont_idx) == 1:
            f = _Slice(obj, base, cont_idx)
            _search_1d(f, flat[cont_idx[0]][2], pb.grid_size, target, [c[0] for c in cs],
                       coarse)
        else:
            _search_nd(obj, base, cont_idx, [flat[n][2] for n in cont_idx], pb.grid_size,
                       target, cs, coarse)
    key, fit, d = obj.best()
    # the final point, solved certified (and to the finest tolerances near the bound)
    sure = fit_design(pb.y, d, pb.skip, pb.coef_box, target)
    _tick(pb)
    if sure.error <= fit.error or not np.isfinite(fit.error):
        fit = sure
    else:
        fit = replace(fit, lower=sure.lower)
    ranking = {}
    for n in int_idx:
        i, j, _ = flat[n]
        best_by_v = {}
        for kk, (ff, _) in obj.cache.items():
            v = int(round(kk[n]))
            best_by_v[v] = min(best_by_v.get(v, np.inf), ff.error)
        ranking[(i, j)] = sorted(best_by_v, key=best_by_v.get)
    thetas = obj.split(key)
    combo = tuple(zip(effects, thetas, strict=True))
    exhaustive = not cont_idx and full_enum
    if exhaustive:  # certified bound over the whole class: every enumerated point, certified
        lower = fit.lower
        for kk, (_ff, dd) in obj.cache.items():
            if kk != key:
                lower = min(lower, fit_design(pb.y, dd, pb.skip, pb.coef_box).lower)
    else:
        lower = fit.lower
    origin, d, fit, n_pinned = _pin_leading(pb, combo, d, fit)
    model = rebuild(origin, pb.refit, combo, d, fit)
    pred = model.predict(pb.u)
    err = float(np.max(np.abs((pb.y - pred)[pb.skip:])))
    # ``lower`` bounds the whole class; the pinned fit lies in it, so it stays a bound
    return ComboFit(effects, thetas, fit, d, model, pred, err, min(lower, err), exhaustive,
                    len(obj.cache) + 1 + n_pinned, time.perf_counter() - t0, ranking)


def _pin_leading(pb: Problem, combo, d: Design, fit: Fit):
    """For a combination with a delay (``Effect.pins_leading``) whose fit is consistent:
    pin the leading refitted coefficient of the numerator to zero, one at a time, while the
    refit stays consistent; the delay of the refined model is then the one the data need
    (the reported total delay is the refit's). Returns ``(origin, design, fit, n_lps)``."""
    origin, n = pb.origin, 0
    if not (pb.refit and origin.base is None and any(e.pins_leading for e, _ in combo)):
        return origin, d, fit, n
    while np.isfinite(fit.error) \
            and not np.any(outside(pb.y, fit.prediction, pb.bound + fit.allowance, pb.skip)) \
            and origin._j0 + 1 < origin.B.size:  # keep one free coefficient
        pinned = replace(origin, b_free_from=origin._j0 + 1)
        d2 = design(pinned, pb.u, pb.refit, combo, pb.y, pb.bound)
        fit2 = fit_design(pb.y, d2, pb.skip, pb.coef_box, pb.bound)
        n += 1
        _tick(pb)
        if np.any(outside(pb.y, fit2.prediction, pb.bound + fit2.allowance, pb.skip)):
            break
        origin, d, fit = pinned, d2, fit2
    return origin, d, fit, n
