"""Model-discrepancy diagnosis: locate, name and add the effect a simulation model misses.

Workflow (see ``docs/discrepancy.md``)
-------------------------------------
1. **Locate.** The model is simulated on the measured input and compared with the data.
   The *gap* of a model class is the smallest noise bound under which the data are
   consistent with it (a Chebyshev / minimax fit)::

       gap = min_theta max_{t >= skip} |y_t - yhat_t(theta)|

   where ``theta`` are the parameters the model is allowed to change ("parameter
   uncertainty": the numerator ``B`` of the linear block, or an output gain for a
   black-box model; see ``refit``). The data are consistent with the model class under
   the noise bound ``Delta`` iff ``gap <= Delta`` - in floating point, iff every scored
   residual satisfies ``|y_t - yhat_t| <= Delta + 1e-9 (|y_t| + |yhat_t| + Delta)`` (the
   outward tolerance of :mod:`hammerbound.tolerances`; the same rule counts the samples
   "outside"). Samples whose best-fit residual lies outside that band are flagged and
   grouped by operating condition (after input reversals, after input changes, in steady
   state, at large / small amplitude), with constant-shift and lag indicators.
2. **Name.** Each candidate effect adds *one* parameter to the model class:

   ==============  ===========================================================  =====
   name            added block                                                  param
   ==============  ===========================================================  =====
   ``backlash``    play operator of half-width ``c`` (unit slopes) on the input  ``c``
   ``deadzone``    ``sign(u) max(|u| - w, 0)`` on the input                      ``w``
   ``saturation``  ``clip(u, -s, s)`` on the input                               ``s``
   ``delay``       ``q^-d`` (integer ``d >= 1``) extra input delay               ``d``
   ``offset``      constant ``o`` added to the output                            ``o``
   ``extra_pole``  ``(1 - p) / (1 - p q^-1)`` in series, ``-1 < p < 1``          ``p``
   ==============  ===========================================================  =====

   For every candidate the augmented class is refitted by minimax: for a fixed value
   of the nonlinear parameter the fit is a linear program in ``(B, offset)``; the
   nonlinear parameter is searched on a grid and refined locally (``delay`` is
   enumerated, ``offset`` is an LP variable). A candidate is *consistent* when its
   minimax error is ``<= Delta``. Every candidate is always refitted and reported.
   Selection: if the original class is consistent the answer is ``None`` (nothing is
   invented; effects below the noise level cannot be confirmed or excluded); otherwise,
   among consistent candidates the one with the fewest added parameters, then the
   smallest minimax error, wins; if none is consistent the candidate with the smallest
   error is named only if it shrinks the gap by ``min_improvement``
   (``consistent_after=False``), else ``None``.
3. **Add.** The chosen effect is inserted, the model refitted, and the report carries
   ``gap_before``, ``gap_after``, the :class:`RefinedModel` and :meth:`plot`.

Guarantees. Every reported minimax error is *achieved* by the returned parameters
(it is recomputed from the residual of the refined model), so "consistent" is a
certificate. ``report.gap_before_lower`` is a rigorous lower bound of the original
class's gap (weak duality, :mod:`hammerbound.relaxations.safe_lp`) over a coefficient box
(each refitted column may contribute at most ``coef_box`` times the output scale): when
it exceeds ``Delta`` the model is *certified* inconsistent.
For grid-searched candidates, inconsistency is only established on the grid.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass, field, replace
from types import MappingProxyType

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import lfilter

from .exceptions import DataValidationError, HammerboundError, ParameterValidationError
from .relaxations.safe_lp import safe_minimize
from .tolerances import feasibility_tol
from .systems import Backlash, HammersteinSystem, as_polynomials, simulate_backlash
from .validation import as_real, check_scale

__all__ = [
    "CANDIDATES",
    "CandidateFit",
    "ConditionEvidence",
    "Disagreement",
    "DiagnosisReport",
    "RefinedModel",
    "apply_effect",
    "diagnose",
    "diagnose_cli_main",
    "locate",
    "read_io_csv",
]

#: Candidate effects in the order they are tried, with the number of added parameters.
CANDIDATES: MappingProxyType = MappingProxyType(
    {
        "offset": 1,
        "delay": 1,
        "backlash": 1,
        "deadzone": 1,
        "saturation": 1,
        "extra_pole": 1,
    }
)

_INPUT_OPS = ("backlash", "deadzone", "saturation")
_LP_OPTIONS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}


# --------------------------------------------------------------------------------------
# the consistency rule (tolerance policy, hammerbound.tolerances)
# --------------------------------------------------------------------------------------
def _outside(y, pred, nb, skip) -> np.ndarray:
    """Scored samples outside the noise band, relaxed outward by the tolerance policy.

    Sample ``t >= skip`` is *inside* when ``|y_t - yhat_t| <= nb + feasibility_tol(y_t,
    yhat_t, nb)``, i.e. within ``1e-9 (|y_t| + |yhat_t| + nb)`` of the band: the rounding
    of the residual itself is far below that, so a model whose error is exactly the noise
    bound is consistent. The same rule decides ``consistent_*`` and every "% outside".
    """
    out = np.abs(y - pred) > nb + feasibility_tol(y, pred, nb)
    out[:skip] = False
    return out


def _certified_above(lower, y, gap, nb, skip) -> bool:
    """Whether a certified lower bound of the gap exceeds the relaxed band of every sample."""
    ymax = float(np.max(np.abs(y[skip:]))) if y.size > skip else 0.0
    # |yhat_t| <= |y_t| + gap, so every sample's relaxed band is below this
    return lower > nb + feasibility_tol(2.0 * ymax + gap, nb)


# --------------------------------------------------------------------------------------
# effects
# --------------------------------------------------------------------------------------
def apply_effect(name: str, value: float, u) -> np.ndarray:
    """Apply a static or hysteretic input effect to a signal.

    Parameters
    ----------
    name : {"backlash", "deadzone", "saturation", "delay"}
        Effect name (``offset`` and ``extra_pole`` act on the output side, see
        :class:`RefinedModel`).
    value : float
        Backlash half-width ``c`` (unit slopes, state 0 at rest), dead-zone half-width
        ``w``, saturation level ``s`` or integer delay ``d``.
    u : array_like
        Input signal.

    Returns
    -------
    ndarray
        Transformed signal (same length; a delay pads with zeros, i.e. rest).
    """
    u = np.asarray(u, dtype=float)
    if name == "backlash":
        return simulate_backlash(u, 1.0, value, 1.0, value, x0=0.0)
    if name == "deadzone":
        return np.sign(u) * np.maximum(np.abs(u) - value, 0.0)
    if name == "saturation":
        return np.clip(u, -value, value)
    if name == "delay":
        return _shift(u, int(round(value)))
    raise ParameterValidationError(f"unknown input effect {name!r}.")


def _shift(v: np.ndarray, d: int) -> np.ndarray:
    if d <= 0:
        return v
    out = np.zeros_like(v)
    if d < v.size:
        out[d:] = v[: v.size - d]
    return out


# --------------------------------------------------------------------------------------
# model structure
# --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RefinedModel:
    """A simulation model plus added effects; callable through :meth:`predict`.

    The output is ``yhat = G(q^-1) N(u) + offset`` for linear-structure models
    (``A``/``B`` set), where ``N`` is the chain ``input_ops`` followed by the original
    Hammerstein backlash ``inner`` (if any); delays and extra poles are folded into
    ``B`` and ``A``. For a black-box base model (anything with ``.predict``) the output
    is ``gain * P(q^-1) base.predict(q^-delay N(u)) + offset`` with ``P`` the product of
    the unit-gain first-order factors ``(1 - p)/(1 - p q^-1)`` of ``post_poles``.

    Attributes
    ----------
    effects : tuple of (str, float)
        Effects added by :func:`diagnose`, in order, with their fitted parameter.
    A, B : ndarray or None
        Linear block in powers of ``q^-1`` (``A`` monic); ``None`` for black boxes.
    offset : float
        Constant added to the output.
    input_ops : tuple of (str, float)
        Input nonlinearities (``backlash``/``deadzone``/``saturation``) applied first.
    inner : Backlash or None
        Backlash of the original :class:`~hammerbound.systems.HammersteinSystem`.
    inner_x0 : float
        Its initial state.
    base : object or None
        Black-box base model with ``.predict(u)``.
    gain : float
        Output gain of a black-box base model.
    post_poles : tuple of float
        Extra unit-gain poles applied to a black-box prediction.
    delay : int
        Extra input delay of a black-box base model.
    b_free_from : int or None
        Index of the first coefficient of ``B`` that ``refit="linear"`` may change (the
        leading zeros before it - the model's input delay - are kept). ``None``: the
        first non-zero coefficient of ``B``.
    """

    effects: tuple = ()
    A: np.ndarray | None = field(default=None, repr=False)
    B: np.ndarray | None = field(default=None, repr=False)
    offset: float = 0.0
    input_ops: tuple = ()
    inner: Backlash | None = None
    inner_x0: float = 0.0
    base: object | None = field(default=None, repr=False)
    gain: float = 1.0
    post_poles: tuple = ()
    delay: int = 0
    b_free_from: int | None = None

    @property
    def _j0(self) -> int:
        if self.b_free_from is not None:
            return int(self.b_free_from)
        return int(np.flatnonzero(self.B)[0])

    @property
    def offset_free(self) -> bool:
        """True when an offset is part of the model class (it is refitted)."""
        return any(name == "offset" for name, _ in self.effects)

    @property
    def linear(self):
        """Linear block ``B/A`` as a discrete ``control.TransferFunction`` (dt=True)."""
        if self.A is None:
            return None
        import control

        n = max(self.A.size, self.B.size)
        num = np.concatenate([self.B, np.zeros(n - self.B.size)])
        den = np.concatenate([self.A, np.zeros(n - self.A.size)])
        return control.tf(num, den, True)

    def inner_signal(self, u) -> np.ndarray:
        """Signal entering the linear block (black box: entering ``base.predict``)."""
        x = np.asarray(u, dtype=float)
        for name, v in self.input_ops:
            x = apply_effect(name, v, x)
        if self.base is None and self.inner is not None:
            x = self.inner.simulate(x, x0=self.inner_x0)
        if self.base is not None:
            x = _shift(x, self.delay)
        return x

    def predict(self, u) -> np.ndarray:
        """Simulated output for input ``u`` from rest.

        Parameters
        ----------
        u : array_like
            Input signal.

        Returns
        -------
        ndarray
        """
        x = self.inner_signal(u)
        if self.base is None:
            yh = lfilter(self.B, self.A, x)
        else:
            yh = self.gain * _black_box_predict(self.base, x)
            for p in self.post_poles:
                yh = lfilter([1.0 - p], [1.0, -p], yh)
        return yh + self.offset

    def to_hammerstein(self) -> HammersteinSystem:
        """Return a :class:`~hammerbound.systems.HammersteinSystem` when representable.

        Possible when the model is linear-structure, has no offset, and its input
        nonlinearity is a single backlash: an added one (unit slopes, state 0), the
        original one, or both combined. An added play of half-width ``c`` in front of the
        original ``Backlash(m_l, c_l, m_r, c_r)`` equals ``Backlash(m_l, c_l + c, m_r,
        c_r + c)`` exactly when the original initial state is a rest state
        (``-m_r c_r <= x0 <= m_l c_l``).

        Raises
        ------
        ParameterValidationError
            If the model is not of that form.
        """
        ops = [op for op in self.input_ops]
        if self.A is None or self.offset != 0.0:
            raise ParameterValidationError(
                "only linear-structure models without offset map to a HammersteinSystem; "
                "use RefinedModel.predict instead."
            )
        if self.inner is not None and not ops:
            return HammersteinSystem(self.inner, (self.A, self.B), x0=self.inner_x0)
        bl = self.inner
        if (bl is not None and len(ops) == 1 and ops[0][0] == "backlash"
                and -bl.mr * bl.cr <= self.inner_x0 <= bl.ml * bl.cl):
            c = ops[0][1]
            merged = Backlash(bl.ml, bl.cl + c, bl.mr, bl.cr + c)
            return HammersteinSystem(merged, (self.A, self.B), x0=self.inner_x0)
        if self.inner is None and len(ops) == 1 and ops[0][0] == "backlash":
            c = ops[0][1]
            return HammersteinSystem(Backlash(1.0, c, 1.0, c), (self.A, self.B))
        if self.inner is None and not ops:
            # a linear model: backlash of (numerically) zero width is not allowed in
            # Backlash; report instead of faking one
            raise ParameterValidationError(
                "the model has no backlash; use RefinedModel.linear for the linear block."
            )
        raise ParameterValidationError(
            f"input nonlinearity {ops} is not a single backlash; use RefinedModel.predict."
        )


def _black_box_predict(model, x: np.ndarray) -> np.ndarray:
    try:
        yh = np.asarray(model.predict(x), dtype=float)
    except HammerboundError:
        raise
    except Exception as exc:  # noqa: BLE001 - user code; re-raise typed
        raise ParameterValidationError(
            f"model.predict(u) failed ({type(exc).__name__}: {exc}); it must accept a 1-D "
            "float array and return the simulated output of the same length."
        ) from exc
    yh = np.ravel(yh)
    if yh.shape != x.shape:
        raise DataValidationError(
            f"model.predict(u) returned {yh.size} samples for {x.size} inputs; it must "
            "return one output per input sample."
        )
    if not np.all(np.isfinite(yh)):
        raise DataValidationError("model.predict(u) returned NaN or inf; check the model.")
    return yh


def _as_structure(model) -> RefinedModel:
    """Convert the user's model into a :class:`RefinedModel` (no effects added).

    Accepted, in this order: a :class:`RefinedModel`; a discrete
    ``control.TransferFunction``; a :class:`~hammerbound.systems.HammersteinSystem`; a
    fitted hammerbound estimator exposing its central model as ``system_`` (a
    ``HammersteinSystem``, e.g. ``HammersteinBacklashIdentifier``); any object with
    ``.predict(u)`` (black box).
    """
    try:
        import control
    except ImportError:  # pragma: no cover
        control = None
    if isinstance(model, RefinedModel):
        return model
    if control is not None and isinstance(model, control.TransferFunction):
        if model.dt is None or model.dt == 0:
            raise ParameterValidationError(
                "the model is a continuous-time TransferFunction; discretise it at the data's "
                "sampling period first, e.g. control.sample_system(G, Ts)."
            )
        A, B = as_polynomials(model)
        _check_linear(A, B)
        return RefinedModel(A=A, B=B)
    name = type(model).__name__
    system = model if isinstance(model, HammersteinSystem) else _fitted_system(model)
    if system is not None:
        A, B = np.array(system.A, dtype=float), np.array(system.B, dtype=float)
        _check_linear(A, B)
        return RefinedModel(A=A, B=B, inner=system.backlash, inner_x0=float(system.x0))
    if callable(getattr(model, "predict", None)):
        return RefinedModel(base=model)
    if callable(getattr(model, "fit", None)):
        raise ParameterValidationError(
            f"{name} has no fitted model: call .fit(...) first (diagnose uses the fitted "
            "central model in its system_ attribute)."
        )
    raise ParameterValidationError(
        f"model of type {name} is not supported: pass a discrete control.TransferFunction, "
        "a hammerbound.systems.HammersteinSystem, a fitted hammerbound identifier (with a "
        "system_ attribute), or an object with a .predict(u) method."
    )


def _fitted_system(model):
    """``model.system_`` when it is a HammersteinSystem; None when absent; else an error.

    Unfitted scikit-learn style estimators raise a clear "call fit first" error.
    """
    try:
        system = getattr(model, "system_", None)
    except Exception:  # noqa: BLE001 - properties of unfitted estimators may raise
        system = None
    if system is None:
        if callable(getattr(model, "fit", None)) and callable(getattr(model, "get_params", None)):
            try:
                from sklearn.exceptions import NotFittedError
                from sklearn.utils.validation import check_is_fitted

                check_is_fitted(model)
            except NotFittedError as exc:
                raise ParameterValidationError(
                    f"{type(model).__name__} is not fitted: call .fit(...) first (diagnose "
                    "uses the fitted central model in its system_ attribute)."
                ) from exc
            except (ImportError, TypeError):  # pragma: no cover - not an sklearn estimator
                pass
        return None
    if not isinstance(system, HammersteinSystem):
        raise ParameterValidationError(
            f"{type(model).__name__}.system_ is a {type(system).__name__}, expected a "
            "hammerbound.systems.HammersteinSystem (the fitted central model)."
        )
    return system


def _check_linear(A, B):
    if A.size > 1 and not np.all(np.abs(np.roots(A)) < 1.0):
        raise ParameterValidationError(
            "the model's linear block is unstable (a pole on or outside the unit circle); "
            "simulation-based diagnosis needs a stable model - stabilise or re-identify it."
        )
    if not np.any(B != 0):
        raise ParameterValidationError("the model's numerator B is identically zero.")


# --------------------------------------------------------------------------------------
# minimax fits
# --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Fit:
    error: float  # achieved max |residual| over t >= skip
    lower: float  # rigorous lower bound of the minimax LP (box-restricted)
    z: np.ndarray
    f: np.ndarray
    Phi: np.ndarray

    @property
    def prediction(self) -> np.ndarray:
        return self.f + (self.Phi @ self.z if self.Phi.shape[1] else 0.0)


def _minimax(y, f, Phi, skip, coef_box, target=None) -> _Fit:
    """Chebyshev fit ``min_z max_{t>=skip} |y_t - f_t - (Phi z)_t|`` as a linear program.

    The free coefficients are boxed, ``|z_j| max_t |Phi_tj| <= coef_box (max|y - f| + 2)``
    (a column may contribute at most ``coef_box`` times the output scale), so that
    :func:`safe_minimize` can return a rigorous lower bound by weak duality. The returned
    ``error`` is recomputed from the returned ``z`` (it is achieved); ``lower`` is a
    certified lower bound of the boxed minimum. When the error lands just above
    ``target`` (within 1 %), the LP is solved again to HiGHS' finest tolerances: the
    default ones (``1e-7``) leave the achieved error up to ~1e-6 relative above the
    optimum, which decides "consistent" when the noise sits exactly at the bound.
    """
    r0 = (y - f)[skip:]
    k = Phi.shape[1]
    if k == 0:
        e = float(np.max(np.abs(r0)))
        return _Fit(e, e, np.zeros(0), f, Phi)
    P = Phi[skip:]
    scale = np.max(np.abs(P), axis=0)
    scale[scale == 0] = 1.0
    Ps = P / scale
    m = r0.size
    ones = np.ones((m, 1))
    A_ub = np.vstack([np.hstack([Ps, -ones]), np.hstack([-Ps, -ones])])
    b_ub = np.concatenate([r0, -r0])
    T = float(np.max(np.abs(r0))) + 1.0
    Z = coef_box * (T + 1.0)
    bounds = np.array([[-Z, Z]] * k + [[0.0, T]])
    c = np.zeros(k + 1)
    c[-1] = 1.0
    e0 = float(np.max(np.abs(r0)))

    def solve(options):
        res = safe_minimize(c, A_ub, b_ub, bounds=bounds, options=options)
        z = np.zeros(k) if res.x is None else res.x[:k] / scale
        e = float(np.max(np.abs((y - f - Phi @ z)[skip:])))
        if e > e0:  # solver failure: z = 0 is always available
            z, e = np.zeros(k), e0
        return z, e, (float(res.bound) if res.status == "optimal" else 0.0)

    z, e, lower = solve(None)
    if target is not None and target < e <= 1.01 * target:
        z2, e2, lower2 = solve(_LP_OPTIONS)
        lower = max(lower, lower2)  # both are certified lower bounds
        if e2 < e:
            z, e = z2, e2
    return _Fit(e, max(min(lower, e), 0.0), z, f, Phi)


def _design(s: RefinedModel, u, refit, *, op=None, pole=None, delay=0, offset=False):
    """Return ``(f, Phi)``: fixed part and free columns of the (augmented) model class."""
    x = np.asarray(u, dtype=float)
    for name, v in s.input_ops:
        x = apply_effect(name, v, x)
    if op is not None:
        x = apply_effect(op[0], op[1], x)
    n = x.size
    cols = []
    f = np.zeros(n)
    if s.base is None:
        if s.inner is not None:
            x = s.inner.simulate(x, x0=s.inner_x0)
        A = s.A if pole is None else np.convolve(s.A, [1.0, -pole])
        x = _shift(x, delay)
        if refit:
            v = lfilter([1.0], A, x)
            for j in range(s._j0, s.B.size):
                cols.append(_shift(v, j))
        else:
            B = s.B if pole is None else s.B * (1.0 - pole)
            f = lfilter(B, A, x)
    else:
        x = _shift(x, s.delay + delay)
        yh = _black_box_predict(s.base, x)
        for p in (*s.post_poles, *(() if pole is None else (pole,))):
            yh = lfilter([1.0 - p], [1.0, -p], yh)
        if refit:
            cols.append(yh)
        else:
            f = s.gain * yh
    if offset or s.offset_free:
        cols.append(np.ones(n))
    elif s.offset != 0.0:
        f = f + s.offset
    Phi = np.column_stack(cols) if cols else np.zeros((n, 0))
    return f, Phi


def _rebuild(s: RefinedModel, refit, fit: _Fit, *, effect=None, value=None, offset=False):
    """Refined model carrying the fitted coefficients of ``fit``."""
    z = fit.z
    new_off = s.offset
    if offset or s.offset_free:
        new_off, z = float(z[-1]), z[:-1]
    effects = s.effects if effect is None else (*s.effects, (effect, value))
    kw = dict(effects=effects, offset=new_off)
    if effect in _INPUT_OPS:
        kw["input_ops"] = (*s.input_ops, (effect, value))
    if s.base is None:
        A, B, j0 = s.A, s.B, s._j0
        if effect == "extra_pole":
            A = np.convolve(A, [1.0, -value])
            B = B * (1.0 - value)
        if effect == "delay":
            B = np.concatenate([np.zeros(int(value)), B])
            j0 += int(value)
        if refit:
            B = np.concatenate([np.zeros(j0), z])
        kw.update(A=A, B=B, b_free_from=j0)
    else:
        if effect == "extra_pole":
            kw["post_poles"] = (*s.post_poles, value)
        if effect == "delay":
            kw["delay"] = s.delay + int(value)
        if refit:
            kw["gain"] = float(z[0])
    return replace(s, **kw)


# --------------------------------------------------------------------------------------
# results
# --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CandidateFit:
    """Evidence for one candidate effect.

    Attributes
    ----------
    name : str
        Candidate name (see :data:`CANDIDATES`).
    n_params : int
        Parameters the candidate adds to the model class.
    param_name : str
        Name of the added parameter (``c``, ``w``, ``s``, ``d``, ``o``, ``p``).
    value : float
        Fitted parameter value (the one with the smallest minimax error).
    minimax_error : float
        Achieved ``max_t |y_t - yhat_t|`` of the refitted augmented model: the smallest
        noise bound under which the data are consistent with it (up to the search).
    lower_bound : float
        Rigorous lower bound of the minimax error *at* ``value`` (for ``offset`` and
        ``delay`` - searched exhaustively - a bound over the whole candidate class).
    consistent : bool
        ``minimax_error <= noise_bound`` (every residual within the noise band, relaxed
        outward by the tolerance policy: ``1e-9 (|y_t| + |yhat_t| + noise_bound)``).
    fraction_outside : float
        Fraction of samples whose residual exceeds the noise bound after the refit.
    improvement : float
        ``gap_before / minimax_error`` (``> 1`` means the candidate shrinks the gap).
    exhaustive : bool
        True when the parameter was searched exhaustively (``offset``: LP; ``delay``:
        all integers up to ``max_delay``), so ``lower_bound`` covers the candidate class.
    n_evaluations : int
        Number of minimax LPs solved for this candidate.
    """

    name: str
    n_params: int
    param_name: str
    value: float
    minimax_error: float
    lower_bound: float
    consistent: bool
    fraction_outside: float
    improvement: float
    exhaustive: bool
    n_evaluations: int


@dataclass(frozen=True)
class ConditionEvidence:
    """Where the out-of-band samples fall, for one operating condition.

    Attributes
    ----------
    name : str
        ``after_reversal``, ``after_input_change``, ``steady_state``,
        ``large_amplitude`` or ``small_amplitude``.
    share_of_samples : float
        Fraction of all (scored) samples in this condition.
    share_of_violations : float
        Fraction of the *largest* disagreements that are in this condition: samples whose
        least-squares-refit residual is outside the noise band and in the top 20% of the
        out-of-band magnitudes.
    enrichment : float
        ``share_of_violations / share_of_samples`` (``> 1``: over-represented; NaN when
        there are no violations or no samples in the condition).
    mean_abs_residual : float
        Mean ``|residual|`` in this condition (least-squares refit of the original model).
    """

    name: str
    share_of_samples: float
    share_of_violations: float
    enrichment: float
    mean_abs_residual: float


@dataclass(frozen=True)
class Disagreement:
    """Where and by how much the model disagrees with the data (step 1).

    Attributes
    ----------
    gap : float
        Smallest noise bound making the data consistent with the original model class
        (minimax over the refittable parameters, see ``refit``).
    gap_lower : float
        Rigorous lower bound of ``gap`` (weak duality); ``gap_lower > noise_bound``
        certifies that the model class is inconsistent with the data.
    fraction_outside : float
        Fraction of samples whose minimax-refit residual exceeds the noise bound (the
        minimax fit spreads the error evenly, so this is often close to 1 when
        ``gap > noise_bound``).
    ls_fraction_outside : float
        Fraction of samples whose *least-squares* refit residual exceeds the noise bound;
        these samples (``indices``) are used to locate the disagreement.
    nominal_gap : float
        ``max |y - model(u)|`` of the model as given (no refit).
    nominal_fraction_outside : float
        Same fraction for the model as given.
    indices : ndarray of int
        Samples outside the band after the least-squares refit.
    residual : ndarray
        Minimax-refit residual ``y - yhat``.
    ls_residual : ndarray
        Least-squares-refit residual (localisation residual).
    nominal_residual : ndarray
        Residual of the model as given.
    conditions : tuple of ConditionEvidence
        Distribution of the out-of-band samples over operating conditions.
    mean_shift : float
        Mean minimax-refit residual divided by ``gap`` (near +-1: a constant shift).
    direction_correlation : float
        Correlation of the residual of a least-squares refit (with a constant) with the
        model's linear response to the sign of the most recent input movement. A missing
        backlash drives it towards -1; wrong dynamics (delay, pole) also correlate
        moderately, so it is a hint, not a decision.
    best_lag : int
        Shift ``k`` (samples) maximising the correlation of ``y`` with the nominal
        prediction delayed by ``k`` (``> 0``: the data lag the model).
    hints : tuple of str
        Human-readable observations (heuristics; the decision is made in step 2).
    """

    gap: float
    gap_lower: float
    fraction_outside: float
    ls_fraction_outside: float
    nominal_gap: float
    nominal_fraction_outside: float
    indices: np.ndarray = field(repr=False)
    residual: np.ndarray = field(repr=False)
    ls_residual: np.ndarray = field(repr=False)
    nominal_residual: np.ndarray = field(repr=False)
    conditions: tuple = ()
    mean_shift: float = 0.0
    direction_correlation: float = 0.0
    best_lag: int = 0
    hints: tuple = ()


@dataclass(frozen=True)
class DiagnosisReport:
    """Result of :func:`diagnose`.

    Attributes
    ----------
    effect : str or None
        Name of the chosen missing effect; ``None`` when the model is already consistent
        with the data, or when no candidate shrinks the gap by ``min_improvement``.
    gap_before, gap_after : float
        Minimax error (smallest consistent noise bound) of the original and refined
        model classes. ``gap_after == gap_before`` when ``effect is None``. When an
        effect is named, ``gap_after <= noise_bound`` unless no candidate is consistent
        (then ``consistent_after`` is False and the message says so).
    noise_bound : float
    consistent_before, consistent_after : bool
        ``gap <= noise_bound`` before / after, up to the outward tolerance
        ``1e-9 (|y_t| + |yhat_t| + noise_bound)`` per sample (hammerbound.tolerances).
    fraction_outside_before, fraction_outside_after : float
        Fraction of samples outside the noise band before / after (same tolerance).
    refined_model : RefinedModel
        The model with the effect added and refitted (the refitted original model when
        ``effect is None``).
    candidates : tuple of CandidateFit
        Evidence for every candidate that was tried (always all requested candidates,
        also when the original model is already consistent).
    disagreement : Disagreement
        Localisation of the disagreement (step 1).
    message : str
        One-paragraph conclusion.
    """

    effect: str | None
    gap_before: float
    gap_after: float
    noise_bound: float
    consistent_before: bool
    consistent_after: bool
    fraction_outside_before: float
    fraction_outside_after: float
    refined_model: RefinedModel
    candidates: tuple
    disagreement: Disagreement
    message: str
    u: np.ndarray = field(repr=False, default=None)
    y: np.ndarray = field(repr=False, default=None)
    prediction_nominal: np.ndarray = field(repr=False, default=None)
    prediction_before: np.ndarray = field(repr=False, default=None)
    prediction_after: np.ndarray = field(repr=False, default=None)
    skip: int = 0

    @property
    def gap_before_lower(self) -> float:
        """Certified lower bound of ``gap_before`` (see :attr:`Disagreement.gap_lower`)."""
        return self.disagreement.gap_lower

    @property
    def gap_reduction(self) -> float:
        """``gap_before / gap_after`` (1 when no effect was added)."""
        return self.gap_before / self.gap_after if self.gap_after > 0 else float("inf")

    def candidate(self, name: str) -> CandidateFit:
        """Evidence of candidate ``name``.

        Raises
        ------
        KeyError
            If the candidate was not tried.
        """
        for c in self.candidates:
            if c.name == name:
                return c
        raise KeyError(name)

    def summary(self) -> str:
        """Multi-line human-readable summary (gaps, locations, candidate table)."""
        d = self.disagreement
        lines = [
            f"noise bound              : {self.noise_bound:.6g}",
            f"nominal model max |error|: {d.nominal_gap:.6g} "
            f"({100 * d.nominal_fraction_outside:.1f}% of samples outside the band)",
            f"gap before (refit)       : {self.gap_before:.6g} "
            f"(certified >= {d.gap_lower:.6g}; "
            f"{100 * self.fraction_outside_before:.1f}% outside)",
            f"effect                   : {self.effect}",
            f"gap after                : {self.gap_after:.6g} "
            f"({100 * self.fraction_outside_after:.1f}% outside)",
        ]
        for h in d.hints:
            lines.append(f"  - {h}")
        if self.candidates:
            lines.append("candidate     param        value   minimax err  consistent  improvement")
            for c in self.candidates:
                lines.append(
                    f"{c.name:<13} {c.param_name:>5} {c.value:>12.5g} {c.minimax_error:>13.5g}"
                    f"  {str(c.consistent):>10} {c.improvement:>12.3g}"
                )
        lines.append(self.message)
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-serialisable summary (no signals; NaN and inf become None)."""
        d = self.disagreement
        rm = self.refined_model
        return _json_clean({
            "effect": self.effect,
            "noise_bound": self.noise_bound,
            "gap_before": self.gap_before,
            "gap_before_certified_lower": d.gap_lower,
            "gap_after": self.gap_after,
            "consistent_before": self.consistent_before,
            "consistent_after": self.consistent_after,
            "fraction_outside_before": self.fraction_outside_before,
            "fraction_outside_after": self.fraction_outside_after,
            "nominal_gap": d.nominal_gap,
            "hints": list(d.hints),
            "conditions": [c.__dict__ for c in d.conditions],
            "candidates": [c.__dict__ for c in self.candidates],
            "refined_model": {
                "effects": [list(e) for e in rm.effects],
                "A": None if rm.A is None else rm.A.tolist(),
                "B": None if rm.B is None else rm.B.tolist(),
                "offset": rm.offset,
                "gain": rm.gain,
            },
            "message": self.message,
        })

    def plot(self, path=None, *, max_samples: int | None = None):
        """Figure: input, output and predictions, residuals with the noise band, candidates.

        Panels: (1) the input; (2) data, the model as given and the refined model;
        (3) the minimax residual before (original class, refitted) and after adding the
        effect, with the noise band ``+-noise_bound`` - the gap is the largest excursion;
        (4) the minimax error of every candidate against the noise bound and the gap
        before (log scale).

        Parameters
        ----------
        path : str or path-like, optional
            If given, the figure is also saved there (PNG recommended).
        max_samples : int, optional
            Show only the first ``max_samples`` samples in the time panels (long records).

        Returns
        -------
        matplotlib.figure.Figure
        """
        import matplotlib.pyplot as plt

        n = self.y.size if max_samples is None else max(1, min(int(max_samples), self.y.size))
        t = np.arange(n)
        sl = slice(0, n)
        fig, axes = plt.subplots(
            4, 1, figsize=(10, 10.5), gridspec_kw={"height_ratios": [1, 1.6, 1.6, 1.4]}
        )
        name = self.effect or "none"
        fig.suptitle(
            f"Discrepancy diagnosis - missing effect: {name};  gap {self.gap_before:.3g} -> "
            f"{self.gap_after:.3g}  (noise bound {self.noise_bound:.3g})",
            fontsize=11,
        )
        ax = axes[0]
        ax.step(t, self.u[sl], where="post", color="k", lw=0.9)
        ax.set_ylabel("input u")
        ax = axes[1]
        ax.plot(t, self.y[sl], ".", ms=2.5, color="0.35", label="data y")
        ax.plot(t, self.prediction_nominal[sl], color="tab:orange", lw=1.0,
                label="model as given")
        ax.plot(t, self.prediction_after[sl], color="tab:blue", lw=1.0,
                label=f"refined ({self.effect or 'refit only'})")
        ax.set_ylabel("output y")
        ax.legend(loc="upper left", fontsize=8, ncol=3, framealpha=0.9)
        ax = axes[2]
        rb = (self.y - self.prediction_before)[sl]
        ra = (self.y - self.prediction_after)[sl]
        nb = self.noise_bound
        ax.axhspan(-nb, nb, color="tab:green", alpha=0.2, lw=0,
                   label=f"noise band +-{nb:.3g}")
        ax.plot(t, rb, color="tab:red", lw=0.8,
                label=f"before: gap {self.gap_before:.3g}, "
                      f"{100 * self.fraction_outside_before:.0f}% outside")
        ax.plot(t, ra, color="tab:blue", lw=0.8,
                label=f"after: gap {self.gap_after:.3g}, "
                      f"{100 * self.fraction_outside_after:.0f}% outside")
        if self.skip:
            ax.axvspan(0, min(self.skip, n), color="0.85", label="not scored (skip)")
        lim = 1.15 * max(np.max(np.abs(rb)), np.max(np.abs(ra)), nb)
        ax.set_ylim(-lim, 1.6 * lim)  # head-room for the legend
        ax.set_ylabel("residual y - yhat\n(minimax refit)")
        ax.set_xlabel("sample t")
        ax.legend(loc="upper left", fontsize=8, ncol=3, framealpha=0.9)
        for a in axes[:3]:
            a.set_xlim(0, max(n - 1, 1))
        ax = axes[3]
        if self.candidates:
            names = [c.name for c in self.candidates]
            errs = np.array([c.minimax_error for c in self.candidates])
            colors = ["tab:blue" if c.name == self.effect
                      else ("tab:green" if c.consistent else "0.6") for c in self.candidates]
            bars = ax.bar(names, errs, color=colors)
            for b, e in zip(bars, errs, strict=True):
                ax.annotate(f"{e:.3g}", (b.get_x() + b.get_width() / 2, e),
                            xytext=(0, 2), textcoords="offset points", ha="center",
                            va="bottom", fontsize=8,
                            bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 1})
            ax.set_yscale("log")
            lo = min(errs.min(), nb) / 2
            hi = max(errs.max(), self.gap_before) * 3
            ax.set_ylim(lo, hi)
        ax.axhline(nb, color="tab:green", ls="--", label="noise bound")
        ax.axhline(self.gap_before, color="tab:red", ls=":", label="gap before")
        ax.set_ylabel("minimax error\nof candidate")
        ax.set_title("candidate evidence (blue: chosen, green: also consistent, "
                     "grey: inconsistent)", fontsize=9)
        ax.legend(fontsize=8, loc="upper right")
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=110)
        return fig


def _json_clean(obj):
    if isinstance(obj, dict):
        return {k: _json_clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_clean(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if np.isfinite(obj) else None
    return obj


# --------------------------------------------------------------------------------------
# step 1: locate
# --------------------------------------------------------------------------------------
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


def locate(model, u, y, noise_bound, *, refit: str = "linear", skip: int = 0,
           window: int = 5, max_lag: int = 10) -> Disagreement:
    """Step 1: where and by how much does the model disagree with the data?

    Parameters
    ----------
    model, u, y, noise_bound, refit, skip
        As in :func:`diagnose`.
    window : int
        Samples after an input change / reversal counted as "after" it.
    max_lag : int
        Largest lag examined for ``best_lag``.

    Returns
    -------
    Disagreement
    """
    s, u, y, nb, do_refit, skip = _validate(model, u, y, noise_bound, refit, skip)
    window = _int_param("window", window, 1)
    max_lag = _int_param("max_lag", max_lag, 0)
    return _locate(s, u, y, nb, do_refit, skip, window, max_lag)[0]


def _last_direction(u):
    """Sign of the most recent non-zero input increment (0 before the first move)."""
    du = np.diff(u, prepend=u[0])
    tol = 1e-12 * (np.max(np.abs(u)) + 1e-300)
    sgn = np.where(np.abs(du) > tol, np.sign(du), 0.0)
    idx = np.where(sgn != 0, np.arange(u.size), 0)
    np.maximum.accumulate(idx, out=idx)
    out = sgn[idx]
    return out


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


def _locate(s, u, y, nb, do_refit, skip, window, max_lag, coef_box=1e3):
    nominal = s.predict(u)
    f, Phi = _design(s, u, do_refit)
    fit = _minimax(y, f, Phi, skip, coef_box, target=nb)
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
    flagged = _outside(y, y - lres, nb, skip)
    # where are the *largest* disagreements? (top quintile of the out-of-band samples)
    worst = flagged.copy()
    if np.any(flagged):
        worst &= np.abs(lres) >= np.quantile(np.abs(lres[flagged]), 0.8)
    conds = _conditions(u, lres, worst, scored, window)
    ms = float(np.mean(resid[skip:]) / fit.error) if fit.error > 0 else 0.0
    dc = _direction_correlation(s, u, y, f, Phi, skip)
    lag = _best_lag(y[skip:], nominal[skip:], max_lag)
    hints = []
    if not np.any(_outside(y, fit.prediction, nb, skip)):
        hints.append("the data are consistent with the model class under the noise bound")
    else:
        if _certified_above(fit.lower, y, fit.error, nb, skip):
            hints.append(
                f"certified: no refit of the model's parameters brings the error below "
                f"{fit.lower:.4g} > noise bound {nb:.4g}"
            )
        for c in conds:
            if np.isfinite(c.enrichment) and c.enrichment >= 1.5 and c.share_of_violations > 0.2:
                hints.append(
                    f"the largest disagreements concentrate {c.name.replace('_', ' ')} "
                    f"({100 * c.share_of_violations:.0f}% of them vs "
                    f"{100 * c.share_of_samples:.0f}% of samples)"
                )
        if abs(ms) > 0.5:
            hints.append(f"residual has a constant shift (mean = {ms:+.2f} x gap)")
        if abs(dc) > 0.5:
            hints.append(
                f"residual follows the direction of the last input movement (correlation "
                f"{dc:+.2f}): a hysteresis / play effect"
            )
        if lag > 0:
            hints.append(f"the data lag the model by about {lag} sample(s)")
    d = Disagreement(
        gap=fit.error,
        gap_lower=fit.lower,
        fraction_outside=float(np.mean(_outside(y, fit.prediction, nb, skip)[skip:])),
        ls_fraction_outside=float(np.mean(flagged[skip:])),
        nominal_gap=float(np.max(np.abs(nres[skip:]))),
        nominal_fraction_outside=float(np.mean(_outside(y, nominal, nb, skip)[skip:])),
        indices=np.flatnonzero(flagged),
        residual=resid,
        ls_residual=lres,
        nominal_residual=nres,
        conditions=conds,
        mean_shift=ms,
        direction_correlation=dc,
        best_lag=lag,
        hints=tuple(hints),
    )
    return d, fit, nominal


# --------------------------------------------------------------------------------------
# step 2: candidates
# --------------------------------------------------------------------------------------
_PARAM_NAMES = {
    "backlash": "c", "deadzone": "w", "saturation": "s",
    "delay": "d", "offset": "o", "extra_pole": "p",
}


def _search_1d(evaluate, lo, hi, grid_size, log=False, target=None):
    """Grid search then bounded Brent refinement of a 1-D minimax error.

    When the error found lies just above ``target`` (the noise bound: within 1 %), a final
    golden-section refinement brings it to the rounding level of the fit, so that data
    whose noise sits exactly at the bound are recognised as consistent.
    """
    grid = np.geomspace(lo, hi, grid_size) if log else np.linspace(lo, hi, grid_size)
    cache = {}

    def g(v):
        v = float(v)
        if v not in cache:
            cache[v] = evaluate(v)
        return cache[v].error

    errs = np.array([g(v) for v in grid])
    i = int(np.argmin(errs))
    a = grid[max(i - 1, 0)]
    b = grid[min(i + 1, grid.size - 1)]
    converged = False
    if b > a:
        res = minimize_scalar(g, bounds=(a, b), method="bounded",
                              options={"xatol": 1e-4 * (hi - lo), "maxiter": 25})
        converged = bool(res.success)
    vbest = min(cache, key=lambda v: cache[v].error)
    # final local refinement: the minimax error is V-shaped (non-smooth) at its minimum, so
    # the first search leaves the parameter ~xatol off, i.e. an error above the optimum by
    # ~slope * 1e-4 (hi - lo). Noise at exactly the bound makes the optimum *equal* to the
    # bound, so shrink that excess to the rounding level of the fit itself (scipy's bounded
    # Brent stops at ~1.5e-8 |v|, too coarse: golden section, on the grid bracket when the
    # first search did not converge).
    if target is not None and target < cache[vbest].error <= 1.01 * target:
        span = 3e-4 * (hi - lo)
        if converged:
            a, b = max(a, vbest - span), min(b, vbest + span)
        _golden(g, a, b, 1e-14 * (hi - lo), stop=target)
        vbest = min(cache, key=lambda v: cache[v].error)
    return vbest, cache[vbest], len(cache)


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


def _fit_candidate(name, s, u, y, do_refit, skip, coef_box, grid_size, max_delay, target=None):
    U = float(np.max(np.abs(u)))
    if name == "offset":
        f, Phi = _design(s, u, do_refit, offset=True)
        fit = _minimax(y, f, Phi, skip, coef_box, target=target)
        return float(fit.z[-1]), fit, fit.lower, 1, True
    if name == "delay":
        best = None
        lows = []
        for d in range(1, max_delay + 1):
            f, Phi = _design(s, u, do_refit, delay=d)
            fit = _minimax(y, f, Phi, skip, coef_box, target=target)
            lows.append(fit.lower)
            if best is None or fit.error < best[1].error:
                best = (d, fit)
        return float(best[0]), best[1], float(min(lows)), max_delay, True
    if name == "extra_pole":
        def ev(p):
            return _minimax(y, *_design(s, u, do_refit, pole=p), skip, coef_box, target=target)

        v, fit, n = _search_1d(ev, -0.9, 0.98, grid_size, target=target)
        return v, fit, fit.lower, n, False
    if name in _INPUT_OPS:
        if U == 0:
            raise DataValidationError("the input is identically zero; nothing can be identified.")
        lo, hi = {"backlash": (0.002, 0.5), "deadzone": (0.002, 0.8),
                  "saturation": (0.05, 0.999)}[name]

        def ev(v):
            return _minimax(y, *_design(s, u, do_refit, op=(name, v)), skip, coef_box,
                            target=target)

        v, fit, n = _search_1d(ev, lo * U, hi * U, grid_size, log=(name != "saturation"),
                               target=target)
        return v, fit, fit.lower, n, False
    raise ParameterValidationError(f"unknown candidate {name!r}.")  # pragma: no cover


# --------------------------------------------------------------------------------------
# validation and main entry point
# --------------------------------------------------------------------------------------
def _signal(name, a):
    try:
        a = np.asarray(a, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DataValidationError(f"{name} must be a numeric 1-D array.") from exc
    if a.ndim != 1:
        a2 = np.squeeze(a)
        if a2.ndim != 1:
            raise DataValidationError(
                f"{name} must be one-dimensional; got shape {a.shape}. Pass a single channel."
            )
        a = a2
    if not np.all(np.isfinite(a)):
        bad = int(np.flatnonzero(~np.isfinite(a))[0])
        raise DataValidationError(
            f"{name} contains NaN or inf (first at index {bad}); remove or interpolate those "
            "samples (keep u and y aligned)."
        )
    return a


def _int_param(name, value, minimum):
    """``value`` as an int ``>= minimum`` or a ParameterValidationError."""
    ok = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
    if not ok and isinstance(value, (float, np.floating)) and float(value).is_integer():
        ok = True
    if not ok or value < minimum:
        raise ParameterValidationError(
            f"{name} must be an integer >= {minimum}; got {value!r}."
        )
    return int(value)


def _validate(model, u, y, noise_bound, refit, skip):
    u = _signal("u", u)
    y = _signal("y", y)
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
    skip = _int_param("skip", skip, 0)
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
    s = _as_structure(model)
    return s, u, y, nb, refit == "linear", skip


def diagnose(
    model,
    u,
    y,
    noise_bound: float,
    *,
    candidates=None,
    refit: str = "linear",
    skip: int = 0,
    max_delay: int = 10,
    grid_size: int = 24,
    window: int = 5,
    coef_box: float = 1e3,
    min_improvement: float = 1.1,
) -> DiagnosisReport:
    """Locate, name and add the effect a simulation model is missing.

    Parameters
    ----------
    model : control.TransferFunction, HammersteinSystem, RefinedModel or object
        A *discrete-time*, stable SISO transfer function (powers of ``q^-1`` as in
        :func:`hammerbound.systems.as_polynomials`), a Hammerstein system, a model
        returned by a previous :func:`diagnose` (to look for a second effect), or any
        object with ``.predict(u) -> y`` (a black box).
    u, y : array_like
        Measured input and output, same length; the data are assumed to start from rest
        (zero initial state) unless the first ``skip`` samples are excluded.
    noise_bound : float
        Known bound ``|eta_t| <= noise_bound`` of the output error (22.5).
    candidates : sequence of str, optional
        Subset of :data:`CANDIDATES` to try (default: all).
    refit : {"linear", "none"}
        ``"linear"`` (default): the model's parameter uncertainty is the numerator ``B``
        of its linear block (leading zeros kept, ``A`` fixed) - or an output gain for a
        black-box model - refitted by minimax with and without each candidate.
        ``"none"``: the model is taken as exact; only the candidate's parameter (and the
        offset for ``offset``) is fitted.
    skip : int
        Number of initial samples excluded from every error (unknown initial state).
    max_delay : int
        Largest extra delay tried by ``delay`` (and lag examined in step 1).
    grid_size : int
        Grid points of the 1-D search for ``backlash``, ``deadzone``, ``saturation`` and
        ``extra_pole`` before local refinement.
    window : int
        Samples after an input change / reversal counted as "after" it (step 1).
    coef_box : float
        Coefficient box (relative to the output scale) for the certified lower bounds.
    min_improvement : float
        When *no* candidate is consistent, the best one is named only if it shrinks the
        gap by at least this factor (``gap_before / gap_after >= min_improvement``);
        otherwise ``effect`` is None. Guards against naming an effect for a noise bound
        that is simply too small.

    Returns
    -------
    DiagnosisReport

    Raises
    ------
    DataValidationError
        NaN/inf in ``u`` or ``y``, mismatched lengths, too few samples, a black-box model
        returning the wrong number of samples.
    ParameterValidationError
        Non-positive noise bound, unknown candidate, continuous-time or unstable
        transfer function, unsupported model type.

    Examples
    --------
    >>> import control, numpy as np
    >>> from hammerbound.discrepancy import diagnose
    >>> G = control.tf([0, 0.5], [1, -0.5], True)
    >>> u = np.repeat(np.random.default_rng(0).uniform(-1, 1, 40), 8)
    >>> y = control.forced_response(G, U=u).outputs + 0.3
    >>> diagnose(G, u, y, noise_bound=0.01).effect
    'offset'
    """
    s, u, y, nb, do_refit, skip = _validate(model, u, y, noise_bound, refit, skip)
    names = _candidate_names(candidates)
    max_delay = _int_param("max_delay", max_delay, 1)
    max_delay = min(max_delay, u.size - skip - 2)
    grid_size = _int_param("grid_size", grid_size, 3)
    window = _int_param("window", window, 1)
    if not (isinstance(coef_box, (int, float, np.integer, np.floating))
            and np.isfinite(coef_box) and coef_box > 0):
        raise ParameterValidationError(f"coef_box must be a finite number > 0; got {coef_box!r}.")
    if not (isinstance(min_improvement, (int, float, np.integer, np.floating))
            and np.isfinite(min_improvement) and min_improvement >= 1):
        raise ParameterValidationError(
            f"min_improvement must be a finite number >= 1; got {min_improvement!r}."
        )

    disagreement, base_fit, nominal = _locate(
        s, u, y, nb, do_refit, skip, window, max_delay, coef_box
    )
    gap_before = base_fit.error
    consistent_before = not np.any(_outside(y, base_fit.prediction, nb, skip))
    base_model = _rebuild(s, do_refit, base_fit)
    frac_before = disagreement.fraction_outside

    def frac(pred):
        return float(np.mean(_outside(y, pred, nb, skip)[skip:]))

    # step 2: refit every candidate (also when the model is already consistent, so that
    # the report always carries the evidence for each of them)
    fits = []
    cand_models = {}
    for name in names:
        value, fit, lower, n_ev, exhaustive = _fit_candidate(
            name, s, u, y, do_refit, skip, coef_box, grid_size, max_delay, target=nb
        )
        refined = _rebuild(s, do_refit, fit, effect=name, value=value,
                           offset=(name == "offset"))
        # the reported error is the one *achieved* by the returned model
        pred = refined.predict(u)
        err = float(np.max(np.abs((y - pred)[skip:])))
        cand_models[name] = (refined, pred)
        fits.append(
            CandidateFit(
                name=name,
                n_params=CANDIDATES[name],
                param_name=_PARAM_NAMES[name],
                value=float(value),
                minimax_error=err,
                lower_bound=min(lower, err),
                consistent=not np.any(_outside(y, pred, nb, skip)),
                fraction_outside=frac(pred),
                improvement=gap_before / err if err > 0 else float("inf"),
                exhaustive=exhaustive,
                n_evaluations=n_ev,
            )
        )

    pred_before = base_fit.prediction
    effect = None
    if consistent_before:
        msg = (
            f"No missing effect: the model (after refitting its parameters) reproduces the "
            f"data within the noise bound (gap {gap_before:.4g} <= {nb:.4g}), so the data "
            f"give no evidence for any candidate."
        )
        better = sorted((c for c in fits if c.minimax_error * min_improvement <= gap_before),
                        key=lambda c: c.minimax_error)
        if better:
            c = better[0]
            msg += (
                f" An effect whose size is below the noise bound can neither be confirmed nor "
                f"excluded: e.g. {c.name} ({c.param_name} = {c.value:.4g}) would lower the "
                f"error to {c.minimax_error:.4g}, which is not required by the data."
            )
    else:
        ok = sorted((c for c in fits if c.consistent),
                    key=lambda c: (c.n_params, c.minimax_error))
        if ok:
            best = ok[0]
            effect = best.name
            msg = (
                f"Missing effect: {best.name} ({best.param_name} = {best.value:.4g}); with it "
                f"the data are consistent with the noise bound (gap {gap_before:.4g} -> "
                f"{best.minimax_error:.4g} <= {nb:.4g})."
            )
            if len(ok) > 1:
                others = ", ".join(f"{c.name} ({c.minimax_error:.4g})" for c in ok[1:])
                msg += (
                    f" Also consistent, with a larger error or more parameters: {others}; "
                    f"the data do not exclude them."
                )
        elif fits:
            best = min(fits, key=lambda c: c.minimax_error)
            if best.minimax_error * min_improvement <= gap_before:
                effect = best.name
                msg = (
                    f"No single candidate makes the data consistent with the noise bound "
                    f"{nb:.4g}; the best is {best.name} ({best.param_name} = "
                    f"{best.value:.4g}), gap {gap_before:.4g} -> {best.minimax_error:.4g}. "
                    f"Either the noise bound is too small or something else (or a "
                    f"combination) is missing - run diagnose on report.refined_model to look "
                    f"for a second effect."
                )
            else:
                msg = (
                    f"The model is inconsistent with the data (gap {gap_before:.4g} > "
                    f"{nb:.4g}) but no candidate shrinks the gap by the factor "
                    f"min_improvement = {min_improvement:g} (best: {best.name}, "
                    f"{best.minimax_error:.4g}). Check the noise bound, or the missing effect "
                    f"is not in the candidate library."
                )
    if effect is None:
        refined, pred_after, gap_after = base_model, pred_before, gap_before
    else:
        refined, pred_after = cand_models[effect]
        gap_after = best.minimax_error
    return DiagnosisReport(
        effect=effect,
        gap_before=gap_before,
        gap_after=gap_after,
        noise_bound=nb,
        consistent_before=consistent_before,
        consistent_after=not np.any(_outside(y, pred_after, nb, skip)),
        fraction_outside_before=frac_before,
        fraction_outside_after=frac(pred_after),
        refined_model=refined,
        candidates=tuple(fits),
        disagreement=disagreement,
        message=msg,
        u=u,
        y=y,
        prediction_nominal=nominal,
        prediction_before=pred_before,
        prediction_after=pred_after,
        skip=skip,
    )


def _candidate_names(candidates):
    if candidates is None:
        return tuple(CANDIDATES)
    if isinstance(candidates, str):
        candidates = (candidates,)
    try:
        names = tuple(dict.fromkeys(candidates))
    except TypeError as exc:
        raise ParameterValidationError(
            f"candidates must be a sequence of names from {list(CANDIDATES)}; got "
            f"{candidates!r}."
        ) from exc
    unknown = [c for c in names if c not in CANDIDATES]
    if unknown:
        raise ParameterValidationError(
            f"unknown candidate(s) {unknown}; choose from {list(CANDIDATES)}."
        )
    if not names:
        raise ParameterValidationError(
            f"candidates is empty; pass None (all) or a subset of {list(CANDIDATES)}."
        )
    return names


# --------------------------------------------------------------------------------------
# command line
# --------------------------------------------------------------------------------------
def _coeffs(text, flag):
    try:
        vals = [float(v) for v in text.replace(",", " ").split()]
    except ValueError as exc:
        raise ParameterValidationError(
            f"{flag} must be numbers separated by spaces or commas, e.g. {flag} \"1 -0.5\"; "
            f"got {text!r}."
        ) from exc
    if not vals:
        raise ParameterValidationError(f"{flag} is empty; give at least one coefficient.")
    return np.array(vals)


def _column_index(spec, header, ncols, which, default, path):
    """Position of column ``spec`` (a header name or a 0-based index)."""
    spec = str(spec).strip()
    cols = None if header is None else [h.strip() for h in header]
    if cols is not None and spec.lower() in [c.lower() for c in cols]:
        j = [c.lower() for c in cols].index(spec.lower())
    elif spec.isdigit():
        j = int(spec)
    elif cols is None and spec == which:
        j = default
    elif cols is None:
        raise DataValidationError(
            f"{path} has no header line, so the {which} column cannot be found by the name "
            f"{spec!r}; add a header (e.g. 'u,y') or give a 0-based column index."
        )
    else:
        raise DataValidationError(
            f"column {spec!r} (the {which} column) not found in the header of {path}; columns "
            f"are {cols}. Rename it or pass --{which}-column NAME."
        )
    if j >= ncols:
        found = f"{ncols} column(s)" + ("" if cols is None else f" {cols}")
        raise DataValidationError(
            f"{path} needs an input and an output column (u,y) but the {which} column "
            f"(index {j}) is missing: found {found}."
        )
    return j


def read_io_csv(path, u_column="u", y_column="y", delimiter=","):
    """Read an input/output record from a CSV file.

    The file may start with a header line naming the columns (then ``u_column`` and
    ``y_column`` are looked up by name, case-insensitively); without a header the
    columns are taken by 0-based index (default: the first two columns are ``u, y``).
    Blank lines and lines starting with ``#`` are ignored.

    Returns
    -------
    u, y : ndarray

    Raises
    ------
    DataValidationError
        Unreadable file, missing column, non-numeric or incomplete rows (the message lists
        the offending line numbers), fewer than two columns.
    """
    import csv

    try:
        with open(path, newline="") as fh:
            rows = [(i + 1, r) for i, r in enumerate(csv.reader(fh, delimiter=delimiter))]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise DataValidationError(f"cannot read {path}: {exc}") from exc
    rows = [(ln, r) for ln, r in rows
            if r and any(f.strip() for f in r) and not r[0].lstrip().startswith("#")]
    if not rows:
        raise DataValidationError(f"{path} contains no data rows.")

    def numeric(field):
        try:
            float(field)
            return True
        except ValueError:
            return False

    header = None
    if not all(numeric(f) for f in rows[0][1]):
        header, rows = rows[0][1], rows[1:]
    ncols = len(header) if header is not None else len(rows[0][1])
    ju = _column_index(u_column, header, ncols, "u", 0, path)
    jy = _column_index(y_column, header, ncols, "y", 1, path)
    if ju == jy:
        raise DataValidationError(
            f"the u and y columns of {path} are the same column (index {ju}); pass "
            "--u-column / --y-column."
        )
    if not rows:
        raise DataValidationError(f"{path} has a header but no data rows.")
    u, y, bad = [], [], []
    for ln, r in rows:
        try:
            uv, yv = float(r[ju]), float(r[jy])
        except (IndexError, ValueError):
            bad.append((ln, delimiter.join(r)))
            continue
        if not (np.isfinite(uv) and np.isfinite(yv)):
            bad.append((ln, delimiter.join(r)))
            continue
        u.append(uv)
        y.append(yv)
    if bad:
        shown = "; ".join(f"line {ln}: {text!r}" for ln, text in bad[:5])
        more = f" (and {len(bad) - 5} more)" if len(bad) > 5 else ""
        raise DataValidationError(
            f"{path}: {len(bad)} row(s) without two finite numbers in the u and y columns - "
            f"{shown}{more}. Fix or remove them (keep u and y aligned)."
        )
    return np.array(u), np.array(y)


def diagnose_cli_main(argv=None) -> int:
    """Entry point of ``hammerbound diagnose``.

    Usage::

        hammerbound diagnose DATA.csv --num "0 0.5" --den "1 -0.5" --noise-bound 0.02
                             [--candidates offset,delay] [--refit linear|none] [--skip K]
                             [--max-delay D] [--u-column u] [--y-column y]
                             [--plot out.png] [--json]

    ``DATA.csv`` holds the input and output columns (see :func:`read_io_csv`: with a
    header they are found by name, default ``u`` and ``y``; without one the first two
    columns are used). ``--num``/``--den`` are the model's coefficients in powers of
    ``q^-1``.

    Parameters
    ----------
    argv : list of str, optional
        Arguments after the subcommand (default ``sys.argv[1:]``).

    Returns
    -------
    int
        0 when the (refined) model is consistent with the data, 1 when it is not,
        2 on invalid input or usage (message on stderr).
    """
    p = argparse.ArgumentParser(
        prog="hammerbound diagnose",
        description="Locate, name and add the effect a linear simulation model misses.",
    )
    p.add_argument("data", help="CSV file with input and output columns (optional header)")
    p.add_argument("--num", required=True, help="numerator B in powers of q^-1, e.g. '0 0.5'")
    p.add_argument("--den", required=True, help="denominator A in powers of q^-1, e.g. '1 -0.5'")
    p.add_argument("--noise-bound", required=True, type=float,
                   help="bound on the output error |eta_t|")
    p.add_argument("--candidates", default=None,
                   help=f"comma-separated subset of {','.join(CANDIDATES)}")
    p.add_argument("--refit", default="linear", choices=["linear", "none"])
    p.add_argument("--skip", type=int, default=0, help="initial samples not scored")
    p.add_argument("--max-delay", type=int, default=10)
    p.add_argument("--u-column", default="u", help="input column: header name or 0-based index")
    p.add_argument("--y-column", default="y",
                   help="output column: header name or 0-based index")
    p.add_argument("--delimiter", default=",")
    p.add_argument("--plot", default=None, help="save the diagnosis figure to this PNG")
    p.add_argument("--json", action="store_true", help="print a JSON report")
    try:
        args = p.parse_args(argv)
    except SystemExit as exc:  # usage errors (already printed) and --help
        return int(exc.code or 0)
    try:
        u, y = read_io_csv(args.data, args.u_column, args.y_column, args.delimiter)
        num, den = _coeffs(args.num, "--num"), _coeffs(args.den, "--den")
        A, B = as_polynomials((den, num))
        import control

        n = max(A.size, B.size)
        G = control.tf(np.r_[B, np.zeros(n - B.size)], np.r_[A, np.zeros(n - A.size)], True)
        cands = None if args.candidates is None else [
            c.strip() for c in args.candidates.split(",") if c.strip()
        ]
        rep = diagnose(G, u, y, args.noise_bound, candidates=cands,
                       refit=args.refit, skip=args.skip, max_delay=args.max_delay)
    except HammerboundError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        try:
            fig = rep.plot(args.plot)
        except OSError as exc:
            print(f"error: cannot write the figure to {args.plot}: {exc}", file=sys.stderr)
            return 2
        plt.close(fig)
    print(json.dumps(rep.to_dict(), indent=2) if args.json else rep.summary())
    return 0 if rep.consistent_after else 1
