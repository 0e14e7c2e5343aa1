"""Candidate effects of :func:`hammerbound.discrepancy.diagnose`: one module per effect.

Adding a candidate
------------------
Write one module here with a subclass of :class:`Effect` and add **one** registration line
at the end of this file (``register(MyEffect())``). Nothing else changes: the design
matrix, the joint search over combinations, the report, the plot and the command line
read the registry. The name becomes a valid ``candidates=`` entry.

An effect declares:

* ``name`` (registry key), ``description`` (one line), ``param_names`` (its *searched*
  nonlinear parameters) and ``linear_names`` (parameters that enter the output linearly:
  they become linear-program columns and are fitted exactly, like the model's ``B``);
* :meth:`Effect.search_space` ``(ctx) -> tuple of Param(name, lo, hi, log=False,
  integer=False)`` - ranges in absolute units, scaled with :class:`Context` (``u_max``,
  ``y_max``, ``n``, ``max_delay``, ``output_bound``). Integer parameters are enumerated,
  continuous ones searched on a grid (:meth:`Effect.initial_grid`, overridable) and
  refined locally, jointly with the other effects' parameters in a combination;
* the hooks it uses (the others are identities):

  - :meth:`Effect.transform_input` ``(x, theta) -> x``: a static or hysteretic map on the
    signal entering the linear block (backlash, dead zone, saturation, polynomial ...);
  - :meth:`Effect.series_filter` ``(theta) -> (num, den)``: an LTI factor in series with the
    linear block, in powers of ``q^-1`` (delay, extra pole);
  - :meth:`Effect.output_columns` ``(n, theta) -> (n, k) array``: columns added to the
    output whose ``k = len(linear_names)`` coefficients are fitted by the LP (offset, a
    drift ``t/n`` ...);
  - :meth:`Effect.output_gain` ``(n, theta) -> (n,) array``: a time-varying gain on the
    model output (a gain drift); the LP rows are scaled by it, so the fit stays exact;
  - :meth:`Effect.transform_output` ``(yhat, theta) -> yhat`` with
    :meth:`Effect.one_sided` ``(y, theta, output_bound) -> array of {-1, 0, +1} or None``: a nonlinear
    output (sensor) map; the LP is told which samples are only bounded on one side;
* ``default = False`` to leave it out of ``diagnose(candidates=None)`` (tried only when
  named, or with ``candidates="all"``): the library's several-parameter candidates
  (``polynomial``, ``asym_backlash``, ``relay``, ``output_saturation``, ``drift``) cost
  1-3 s each per call (product-grid searches), the one-parameter ones ~0.2 s;
* optionally :meth:`Effect.value` ``(theta, coefs, model)`` - what ``CandidateFit.value``
  shows (default: the single parameter, or a tuple); ``model`` is the refitted
  :class:`~hammerbound.discrepancy.RefinedModel`, for values in its convention;
* optionally ``pins_leading = True`` (``delay``): after the fit, the leading refitted
  coefficients of the numerator are pinned to zero one by one while the data stay
  consistent, so that the model's delay is the one the data need.

``theta`` is always a tuple of floats in ``param_names`` order. Every hook must be a pure
function of its arguments (the search calls it many times). Whatever the hooks do, the
reported minimax error is recomputed from the returned :class:`RefinedModel`'s prediction,
so a hook can make a fit worse, never a reported error wrong.

Example (an offset drift is one linear column; a gain drift ``(1 + g t/n)`` is an
:meth:`Effect.output_gain`, see ``drift.py``)::

    class OffsetDrift(Effect):
        name = "offset_drift"
        linear_names = ("o0", "o1")
        description = "offset o0 + o1 t/n added to the output"

        def output_columns(self, n, theta):
            t = np.arange(n) / n
            return np.column_stack([np.ones(n), t])

    register(OffsetDrift())
"""

from __future__ import annotations

from types import MappingProxyType

from ...exceptions import ParameterValidationError
from .asym_backlash import AsymBacklash
from .backlash import SymmetricBacklash
from .base import Context, Effect, Param
from .deadzone import Deadzone
from .delay import Delay
from .drift import Drift
from .extra_pole import ExtraPole
from .offset import Offset
from .output_saturation import OutputSaturation
from .polynomial import Polynomial
from .relay import Relay
from .saturation import Saturation

__all__ = ["CANDIDATES", "REGISTRY", "Context", "Effect", "Param", "default_candidates", "get",
           "register"]

_REGISTRY: dict = {}
#: Registered effects by name, in the order they are tried (read-only view).
REGISTRY = MappingProxyType(_REGISTRY)


def register(effect: Effect) -> Effect:
    """Add ``effect`` to the registry (its ``name`` must be new); returns it."""
    if not isinstance(effect, Effect) or not effect.name:
        raise ParameterValidationError("register() needs an Effect instance with a name.")
    if effect.name in _REGISTRY:
        raise ParameterValidationError(f"a candidate named {effect.name!r} is registered.")
    _REGISTRY[effect.name] = effect
    _COUNTS[effect.name] = effect.n_params
    return effect


def get(name: str) -> Effect:
    """The registered effect ``name`` (ParameterValidationError if unknown)."""
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise ParameterValidationError(
            f"unknown candidate {name!r}; choose from {list(_REGISTRY)}."
        ) from None


def default_candidates() -> tuple:
    """Names tried by ``diagnose(candidates=None)``: registered effects with ``default``."""
    return tuple(name for name, e in _REGISTRY.items() if e.default)


_COUNTS: dict = {}
#: Every registered candidate name, in the order they are tried, with the number of added
#: parameters (the default set is :func:`default_candidates`).
CANDIDATES = MappingProxyType(_COUNTS)

# ---------------------------------------------------------------- registrations (one line each)
# the first six are tried by default; the rest only when named or with candidates="all"
register(Offset())
register(Delay())
register(SymmetricBacklash())
register(Deadzone())
register(Saturation())
register(ExtraPole())
register(Polynomial())
register(AsymBacklash())
register(Relay())
register(OutputSaturation())
register(Drift())


def __getattr__(name):
    # renamed in 0.2.0 (one class name per concept: systems.Backlash is the chapter's)
    if name == "Backlash":
        from ..._compat import warn_renamed

        warn_renamed("hammerbound.discrepancy.effects.Backlash", "SymmetricBacklash")
        return SymmetricBacklash
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
