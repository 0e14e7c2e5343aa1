"""Argument checks of :func:`~.diagnose` and :func:`~.locate` (through
:mod:`hammerbound.data.validation`: one validation of signals and bounds for the package)."""

from __future__ import annotations

import numpy as np

from ..data.validation import as_real, as_signal, check_scale
from ..exceptions import DataValidationError, ParameterValidationError
from . import effects as _effects
from .model import as_structure

__all__ = ["candidate_names", "int_param", "positive", "validate"]


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


def validate(model, u, y, noise_bound, refit, skip):
    """Checked ``(structure, u, y, noise_bound, refit_flag, skip)``."""
    u = as_signal("u", u)
    y = as_signal("y", y)
    if u.size != y.size:
        raise DataValidationError(
            f"u has {u.size} samples but y has {y.size}; pass aligned input/output records."
        )
    nb = as_real("noise_bound", noise_bound,
                 want="noise_bound must be a single positive number (the bound "
                      "|eta_t| <= noise_bound), e.g. noise_bound=0.05")
    if nb <= 0:
        raise ParameterValidationError(
            f"noise_bound must be a finite number > 0; got {noise_bound!r}."
        )
    if refit not in ("linear", "none"):
        raise ParameterValidationError(
            f"refit must be 'linear' (refit B / output gain) or 'none'; got {refit!r}."
        )
    skip = int_param("skip", skip, 0)
    if u.size - skip < 10:
        raise DataValidationError(
            f"only {u.size - skip} scored samples (length {u.size}, skip {skip}); at least 10 "
            "are needed - record longer data."
        )
    if not np.any(u[skip:] != 0):
        raise DataValidationError(
            "the input u is identically zero on the scored samples; a simulation model "
            "cannot be compared with data that were not excited - record data with a "
            "varying input."
        )
    check_scale("diagnose", {"u": u, "y": y}, {"noise_bound": nb})
    s = as_structure(model)
    return s, u, y, nb, refit == "linear", skip


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
