"""Argument checks of :func:`~.diagnose` and :func:`~.locate` (through
:mod:`hammerbound.data.validation`: one validation of signals and bounds for the package)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..data.iodata import IOData
from ..data.validation import as_real, as_signal, check_scale
from ..exceptions import DataValidationError, ParameterValidationError
from . import effects as _effects
from .model import RefinedModel, as_structure

__all__ = ["START_EFFECT", "candidate_names", "initial_state_skip", "int_param",
           "max_effects_param", "positive", "validate"]

#: Largest ``max_effects`` :func:`~.diagnose` searches (triples of the best singles).
MAX_EFFECTS = 3

#: ``skip="auto"``: the backlash's unknown start may move the output by this fraction of
#: the output bound in the samples that are scored
START_EFFECT = 0.01


def int_param(name, value, minimum):
    """``value`` as an int ``>= minimum`` or a ParameterValidationError."""
    ok = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
    if not ok and isinstance(value, (float, np.floating)) and float(value).is_integer():
        ok = True
    if not ok or value < minimum:
        raise ParameterValidationError(
            f"{name} must be an integer >= {minimum}; got {value!r}."
        )
    return int(value)


def positive(name, value, minimum=0.0, strict=True):
    """A finite real ``> minimum`` (``>=`` when not strict) or a ParameterValidationError."""
    want = f"{name} must be a finite number {'>' if strict else '>='} {minimum:g}"
    v = as_real(name, value, want=want)
    if v < minimum or (strict and v == minimum):
        raise ParameterValidationError(f"{want}; got {value!r}.")
    return v


def max_effects_param(value):
    """``max_effects`` as an int in ``1..MAX_EFFECTS`` or a ParameterValidationError."""
    v = int_param("max_effects", value, 1)
    if v > MAX_EFFECTS:
        raise ParameterValidationError(
            f"max_effects must be 1, 2 or {MAX_EFFECTS} (single effects, pairs, triples of "
            f"the four best single candidates); got {value!r}. Larger combinations are not "
            "searched."
        )
    return v


def unpack(u, y, output_bound, func="diagnose"):
    """``(u, y, data)`` from ``(u, y)`` arrays or from an :class:`~hammerbound.IOData`
    passed as ``u`` (``data``; None for arrays), with a typed error for every other mix."""
    call = f"{func}(model, data, output_bound=...)"
    if isinstance(y, IOData):
        raise DataValidationError(
            f"y is an IOData; pass it in place of u (it holds both signals): {call}."
        )
    if isinstance(u, IOData):
        if y is not None:
            what = ("a number: the output bound goes by keyword" if np.ndim(y) == 0
                    and output_bound is None else "given too, but the IOData holds the output")
            raise DataValidationError(
                f"u is an IOData and y is {what}; call {call} without y."
            )
        if not u.is_contiguous():
            k = int(np.flatnonzero(np.diff(u.sample_index) != 1)[0])
            raise DataValidationError(
                f"the IOData's samples are not consecutive (a jump from sample "
                f"{u.sample_index[k]} to {u.sample_index[k + 1]}); the model is simulated "
                "over consecutive samples: pass a contiguous record (data[a:b])."
            )
        return u.u, u.y, u
    if y is None:
        raise DataValidationError(
            f"y (the measured output) is missing: call {func}(model, u, y, output_bound=...) "
            f"with arrays, or {call} with an IOData holding u and y."
        )
    return u, y, None


def _with_dt(s, data):
    """The structure ``s`` with the data's sampling time (they must agree)."""
    dt = None if data is None else data.dt
    if dt is None:
        return s
    if s.dt is None:
        origin = None if s.origin is None else replace(s.origin, dt=dt)
        return replace(s, dt=dt, origin=origin)
    if abs(s.dt - dt) > 1e-9 * max(s.dt, dt):
        raise ParameterValidationError(
            f"the model is sampled at dt = {s.dt:g} but the data at dt = {dt:g}; "
            "discretise or resample one of them at the other's sampling time."
        )
    return s


def validate(model, u, y, output_bound, refit, skip, func="diagnose"):
    """Checked ``(structure, u, y, output_bound, refit_flag, skip, data)``; ``u`` may be an
    :class:`~hammerbound.IOData` (``data``, then ``y`` is None; its ``dt`` goes to the
    structure)."""
    u, y, data = unpack(u, y, output_bound, func)
    u = as_signal("u", u)
    y = as_signal("y", y)
    if u.size != y.size:
        raise DataValidationError(
            f"u has {u.size} samples but y has {y.size}; pass aligned input/output records."
        )
    if output_bound is None:
        raise ParameterValidationError(
            "output_bound is required (the bound |eta_t| <= output_bound that every verdict "
            f"rests on; no default): e.g. {func}(model, u, y, output_bound=0.05)."
        )
    bound = as_real("output_bound", output_bound,
                 want="output_bound must be a single positive number (the bound "
                      "|eta_t| <= output_bound), e.g. output_bound=0.05")
    if bound <= 0:
        raise ParameterValidationError(
            f"output_bound must be a finite number > 0; got {output_bound!r}."
        )
    if refit not in ("linear", "none"):
        raise ParameterValidationError(
            f"refit must be 'linear' (refit B / output gain) or 'none'; got {refit!r}."
        )
    check_scale(func, {"u": u, "y": y}, {"output_bound": bound})
    s = _with_dt(as_structure(model), data)
    asked = skip
    s, skip, skip_note = _skip(s, u, bound, skip)
    if u.size - skip < 10:
        auto = (" by skip='auto'; skip=0 scores every sample" if isinstance(asked, str) and skip
                else "")
        raise DataValidationError(
            f"only {u.size - skip} scored samples (length {u.size}, skip {skip}{auto}); at "
            "least 10 are needed - record longer data."
        )
    if not np.any(u[skip:] != 0):
        raise DataValidationError(
            "the input u is identically zero on the scored samples; a simulation model "
            "cannot be compared with data that were not excited - record data with a "
            "varying input."
        )
    return s, u, y, bound, refit == "linear", skip, data, skip_note


def _skip(s, u, bound, skip) -> tuple:
    """``(structure, skip, why)``. ``skip="auto"``: :func:`initial_state_skip`, and the
    backlash's start is free in every certified bound (``inner_start_free``); an int is the
    user's, and the model's own start is taken as known."""
    auto = isinstance(skip, str) and skip == "auto"
    if isinstance(skip, str) and not auto:
        raise ParameterValidationError(f"skip must be 'auto' or an integer >= 0; got {skip!r}.")
    if not auto:
        skip = int_param("skip", skip, 0)
    free = auto and s.inner is not None
    origin = s.origin
    s = replace(s, inner_start_free=free,
                origin=None if origin is None else replace(origin, inner_start_free=free))
    if not auto:
        return s, skip, (f"skip={skip} given; the model's own start taken as known" if skip
                         else "")
    return (s, *initial_state_skip(s, u, bound)[:2])


def initial_state_skip(s, u, bound) -> tuple[int, str, float]:
    """``(skip, why, allowance)``: the samples not scored for the model ``s`` (or its structure, from
    :func:`~.model.as_structure`) when its backlash's initial state is not known (a
    one-record fit leaves it free), and why (empty when none).

    ``skip`` is where the start's largest possible effect on the output
    (:func:`~.fitting.start_spread`, with the absolute impulse response: review 52 found
    the gap's own response no bound) stays below :data:`START_EFFECT` of the output bound
    for good; at most half the record. What a start can still do after it to the model as
    given (``allowance``) is said; every fit's consistency is judged against the bound
    plus its own allowance (:attr:`~.fitting.Fit.allowance`), and certified bounds hold
    for every start."""
    from .fitting import design

    if not isinstance(s, RefinedModel):
        s = as_structure(s)
    if s.inner is None or s.base is not None:
        return 0, "", 0.0
    origin = s if s.origin is None else s.origin
    combo = tuple((_effects.get(n), th) for n, th, _ in s.effect_params) if s.origin else ()
    effect = design(replace(origin, inner_start_free=True), u, False, combo).spread[0]
    late = np.flatnonzero(effect > START_EFFECT * float(bound))
    need = 0 if late.size == 0 else int(late[-1]) + 1
    skip = min(need, u.size // 2)
    left = float(np.max(effect[skip:], initial=0.0))
    rest = (f"every verdict allows for what a start can still do to each fit there (at "
            f"most {left:.3g} to the model as given); skip=K takes the model's own start as "
            "known")
    if not skip:
        return 0, f"the backlash's start is not known: {rest}" if left > 0 else "", left
    capped = ", capped at half the record" if skip < need else ""
    return skip, (f"the backlash's start is not known: the first {skip} samples are not "
                  f"scored (up to there a start elsewhere in its first band can move the "
                  f"output by more than {100 * START_EFFECT:g} % of the output "
                  f"bound{capped}) and {rest}"), left


def candidate_names(candidates):
    """Checked tuple of candidate names (default: :func:`~.effects.default_candidates`;
    ``"all"``: every registered one)."""
    known = list(_effects.REGISTRY)
    if candidates is None:
        return _effects.default_candidates()
    if isinstance(candidates, str) and candidates == "all":
        return tuple(known)
    if isinstance(candidates, str):
        candidates = (candidates,)
    try:
        names = tuple(dict.fromkeys(candidates))
    except TypeError as exc:
        raise ParameterValidationError(
            f"candidates must be a sequence of names from {known}; got {candidates!r}."
        ) from exc
    unknown = [c for c in names if c not in _effects.REGISTRY]
    if unknown:
        raise ParameterValidationError(
            f"unknown candidate(s) {unknown}; choose from {known}."
        )
    if not names:
        raise ParameterValidationError(
            f"candidates is empty; pass None (all) or a subset of {known}."
        )
    return names
