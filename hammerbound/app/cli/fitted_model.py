"""The central model of a fit saved by ``hammerbound identify --json``.

``hammerbound diagnose --model FIT.json`` tests the model an identification gave on new data
(new-user trial 17: the command line took only a transfer function, so an identified
backlash could not be diagnosed). The central model is the one the identifier's
``system_`` holds: every parameter at the centre of its interval.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ...exceptions import ParameterValidationError
from ...systems.models import GAMMA_NAMES

__all__ = ["fitted_model"]


def _load(path) -> dict:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterValidationError(f"--model: cannot read {path}: {exc}") from None
    try:
        fit = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ParameterValidationError(
            f"--model: {path} is not JSON ({exc.msg}, line {exc.lineno}); give the output "
            "of 'hammerbound identify ... --json > FIT.json'.") from None
    if not isinstance(fit, dict) or not all(k in fit for k in ("parameters", "lower", "upper")):
        raise ParameterValidationError(
            f"--model: {path} has no 'parameters', 'lower' and 'upper' fields; give the "
            "output of 'hammerbound identify ... --json > FIT.json'.")
    return fit


def _centres(fit, path) -> dict:
    names, lo, hi = fit["parameters"], fit["lower"], fit["upper"]
    if not (len(names) == len(lo) == len(hi)):
        raise ParameterValidationError(
            f"--model: {path} lists {len(names)} parameters but {len(lo)} lower and "
            f"{len(hi)} upper ends.")
    unbounded = [n for n, a, b in zip(names, lo, hi, strict=True)
                 if a is None or b is None or not (math.isfinite(a) and math.isfinite(b))]
    if unbounded:
        raise ParameterValidationError(
            f"--model: the fit in {path} did not bound {', '.join(unbounded)} (an infinite "
            "interval has no centre), so it gives no central model. Diagnose a model you "
            "choose instead: --num, --den and --backlash.")
    return {n: 0.5 * (a + b) for n, a, b in zip(names, lo, hi, strict=True)}


def _polynomials(c, path):
    """``A = [1, a1, ...]`` and ``B[j] = b_j`` from the centres (names ``a<i>``, ``b<j>``)."""
    a = sorted((int(n[1:]), v) for n, v in c.items() if n[0] == "a" and n[1:].isdigit())
    b = sorted((int(n[1:]), v) for n, v in c.items() if n[0] == "b" and n[1:].isdigit())
    if not b or [i for i, _ in a] != list(range(1, len(a) + 1)):
        raise ParameterValidationError(
            f"--model: {path} does not hold a linear block (parameters a1..a_na and b_j); "
            f"it has {list(c)}.")
    A = np.array([1.0] + [v for _, v in a])
    B = np.zeros(b[-1][0] + 1)
    for j, v in b:
        B[j] = v
    return A, B


def fitted_model(path):
    """The central model of the fit in ``path`` (JSON of ``hammerbound identify --json``),
    as a fitted set for :func:`hammerbound.discrepancy.diagnose`: its ``system_`` is the
    central Hammerstein system, ``bounds_`` and ``procedure_`` say that it is a set's
    centre (so a verdict against it says so)."""
    from ...hammerstein.identifier import central_system
    from ...systems.models import Backlash

    fit = _load(path)
    c = _centres(fit, path)
    missing = [n for n in GAMMA_NAMES if n not in c]
    if missing:
        raise ParameterValidationError(
            f"--model: {path} has no backlash parameters {missing}; for a linear model "
            "pass --num and --den.")
    A, B = _polynomials({n: v for n, v in c.items() if n not in GAMMA_NAMES}, path)
    dt = (fit.get("data") or {}).get("dt")
    system = central_system(Backlash(*(c[n] for n in GAMMA_NAMES)), A, B, dt)
    bounds = np.array([fit["lower"], fit["upper"]], dtype=float).T
    return SimpleNamespace(system_=system, bounds_=bounds, procedure_=fit.get("procedure"))
