"""The refined simulation model and the conversion of user models into it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.signal import lfilter

from ..exceptions import DataValidationError, HammerboundError, ParameterValidationError
from ..systems.models import Backlash, HammersteinSystem, as_polynomials
from . import effects as _effects

__all__ = ["RefinedModel", "apply_effect"]


def _theta(value) -> tuple:
    """A parameter value (number or sequence) as a tuple of floats."""
    if np.ndim(value) == 0:
        return (float(value),)
    return tuple(float(v) for v in np.ravel(value))


def apply_effect(name: str, value, u) -> np.ndarray:
    """Apply an input-side effect (or a series filter such as a delay) to a signal.

    Parameters
    ----------
    name : str
        A registered candidate acting on the input or in series with the linear block
        (``backlash``, ``deadzone``, ``saturation``, ``delay``, ``extra_pole``, ...).
    value : float or sequence of float
        Its searched parameter(s): backlash half-width ``c`` (unit slopes, state 0 at
        rest), dead-zone half-width ``w``, saturation level ``s``, integer delay ``d``.
    u : array_like
        Input signal.

    Returns
    -------
    ndarray
        Transformed signal (same length; a delay pads with zeros, i.e. rest).

    Raises
    ------
    ParameterValidationError
        Unknown effect, or one that acts on the output (``offset``: see
        :class:`RefinedModel`).
    """
    e = _effects.get(name)
    theta = _theta(value)
    if e.linear_names or type(e).transform_output is not _effects.Effect.transform_output:
        raise ParameterValidationError(
            f"{name!r} acts on the output; use RefinedModel.predict (unknown input effect)."
        )
    x = e.transform_input(np.asarray(u, dtype=float), theta)
    filt = e.series_filter(theta)
    if filt is not None:
        x = lfilter(filt[0], filt[1], x)
    return x


def inner_backlash(bl: Backlash, x: np.ndarray, x0: float, extend: bool) -> np.ndarray:
    """The model's own backlash ``bl`` on ``x`` from state ``x0``.

    ``extend``: added input effects act in front of it and may drive it beyond the
    crossing of its lines, where (22.1) is ill-posed; there the right line wins, as for
    ``asym_backlash``, so that the search can evaluate every parameter value (such values
    fit badly and are not chosen). Without added input effects the measured input must
    keep (22.1) well posed (:class:`~hammerbound.exceptions.IllPosedBacklashError`).
    """
    if not extend:
        return bl.simulate(x, x0=x0)
    from .effects.asym_backlash import play

    return play(x, bl.ml, bl.cl, bl.mr, bl.cr, x0)


def _shift(v: np.ndarray, d: int) -> np.ndarray:
    if d <= 0:
        return v
    out = np.zeros_like(v)
    if d < v.size:
        out[d:] = v[: v.size - d]
    return out


@dataclass(frozen=True)
class RefinedModel:
    """A simulation model plus added effects; callable through :meth:`predict`.

    The output is ``yhat = OUT(G(q^-1) N(u) + offset + sum of effect columns)`` for
    linear-structure models (``A``/``B`` set), where ``N`` is the chain ``input_ops``
    followed by the original Hammerstein backlash ``inner`` (if any); delays and extra
    poles are folded into ``B`` and ``A``; ``OUT`` are the ``output_ops`` (identity for the
    built-in effects). For a black-box base model (anything with ``.predict``) the output
    is ``gain * F(q^-1) base.predict(q^-delay N(u)) + offset`` with ``F`` the product of
    the unit-gain first-order factors ``(1 - p)/(1 - p q^-1)`` of ``post_poles`` and the
    series filters ``post_filters`` of the added effects.

    Attributes
    ----------
    effects : tuple of (str, value)
        Effects added by :func:`diagnose`, in order, with their fitted parameter (a float
        for one-parameter effects, else a tuple).
    A, B : ndarray or None
        Linear block in powers of ``q^-1`` (``A`` monic); ``None`` for black boxes.
    offset : float
        Constant added to the output.
    input_ops : tuple of (str, tuple)
        Input effects (name, parameters) applied first.
    inner : Backlash or None
        Backlash of the original :class:`~hammerbound.systems.models.HammersteinSystem`.
    inner_x0 : float
        Its initial state.
    inner_start_free : bool
        Its initial state is not known (``diagnose(skip="auto")``): certified bounds
        allow every start in its first band, not only ``inner_x0``.
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
    post_filters : tuple of (ndarray, ndarray)
        Series filters ``(num, den)`` of added effects on a black-box prediction.
    output_terms : tuple of (str, tuple, tuple)
        Output columns of added effects other than the offset: (name, parameters,
        coefficients).
    output_ops : tuple of (str, tuple)
        Nonlinear output maps of added effects.
    effect_params : tuple of (str, tuple, tuple)
        Every added effect with its searched parameters and LP coefficients; with
        ``origin`` it lets :func:`diagnose` refit them jointly with new ones.
    origin : RefinedModel or None
        The model before any effect was added (``None``: this model is the origin).
    dt : float or None
        Sampling time: the model's (a ``TransferFunction`` or ``HammersteinSystem`` with a
        numeric ``dt``), else the data's (an :class:`~hammerbound.IOData`); None: not given
        (:attr:`linear` then has python-control's ``dt=True``).
    """

    effects: tuple = ()
    A: np.ndarray | None = field(default=None, repr=False)
    B: np.ndarray | None = field(default=None, repr=False)
    offset: float = 0.0
    input_ops: tuple = ()
    inner: Backlash | None = None
    inner_x0: float = 0.0
    inner_start_free: bool = field(default=False, repr=False)
    base: object | None = field(default=None, repr=False)
    gain: float = 1.0
    post_poles: tuple = ()
    delay: int = 0
    b_free_from: int | None = None
    post_filters: tuple = field(default=(), repr=False)
    output_terms: tuple = field(default=(), repr=False)
    output_ops: tuple = field(default=(), repr=False)
    effect_params: tuple = field(default=(), repr=False)
    origin: RefinedModel | None = field(default=None, repr=False)
    dt: float | None = None

    @property
    def _j0(self) -> int:
        if self.b_free_from is not None:
            return int(self.b_free_from)
        return int(np.flatnonzero(self.B)[0])

    @property
    def linear(self):
        """Linear block ``B/A`` as a discrete ``control.TransferFunction`` (sampling time
        :attr:`dt`, or ``True`` when not given)."""
        if self.A is None:
            return None
        import control

        n = max(self.A.size, self.B.size)
        num = np.concatenate([self.B, np.zeros(n - self.B.size)])
        den = np.concatenate([self.A, np.zeros(n - self.A.size)])
        return control.tf(num, den, True if self.dt is None else self.dt)

    def inner_signal(self, u) -> np.ndarray:
        """Signal entering the linear block (black box: entering ``base.predict``)."""
        x = np.asarray(u, dtype=float)
        for name, theta in self.input_ops:
            x = _effects.get(name).transform_input(x, _theta(theta))
        if self.base is None and self.inner is not None:
            x = inner_backlash(self.inner, x, self.inner_x0, bool(self.input_ops))
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
            yh = self.gain * black_box_predict(self.base, x)
            for p in self.post_poles:
                yh = lfilter([1.0 - p], [1.0, -p], yh)
            for num, den in self.post_filters:
                yh = lfilter(num, den, yh)
        yh = yh + self.offset
        for name, theta, coefs in self.output_terms:
            yh = yh + _effects.get(name).output_columns(yh.size, theta) @ np.asarray(coefs)
        ops = [(_effects.get(name), theta) for name, theta in self.output_ops]
        gains = [op for op in ops if type(op[0]).output_gain is not _effects.Effect.output_gain]
        for e, theta in gains + [op for op in ops if op not in gains]:
            yh = e.transform_output(yh, theta)  # output gains first, as in the fit
        return yh

    def chapter_gain(self, name: str) -> float | None:
        """Gain that the chapter's convention moves from the linear block into the slopes
        of the added backlash ``name`` (``backlash`` or ``asym_backlash``).

        (22.8) normalises the linear block to unit static gain, the backlash slopes
        carrying the gain. That is possible when ``name`` is the last input effect, so that
        it acts directly on the linear block (no backlash of the original model between
        them), and the static gain ``k = B(1)/A(1)`` of the refined linear block is
        positive: then ``k``; otherwise None (the slopes stay normalised as searched).
        """
        if self.A is None or self.inner is not None or not self.input_ops \
                or self.input_ops[-1][0] != name:
            return None
        k = float(np.sum(self.B) / np.sum(self.A))  # A is stable: A(1) != 0
        return k if np.isfinite(k) and k > 0 else None

    def to_hammerstein(self) -> HammersteinSystem:
        """Return a :class:`~hammerbound.systems.models.HammersteinSystem` when representable.

        Possible when the model is linear-structure, has no offset, and its input
        nonlinearity is a single backlash: an added one (``backlash`` or
        ``asym_backlash``, state 0), the original one, or an added ``backlash`` in front of
        the original one. An added play of half-width ``c`` in front of the original
        ``Backlash(m_l, c_l, m_r, c_r)`` equals ``Backlash(m_l, c_l + c, m_r, c_r + c)``
        exactly when the original initial state is a rest state
        (``-m_r c_r <= x0 <= m_l c_l``); the original linear block is kept.

        An added backlash alone is returned in the chapter's convention (22.8): the linear
        block ``B / k`` has unit static gain and the slopes carry ``k = B(1)/A(1)``, so the
        backlash is the reported ``(m_l, c_l, m_r, c_r)`` (``c`` and unit slopes scaled by
        ``k`` for ``backlash``). When ``k <= 0`` (see :meth:`chapter_gain`) the slopes stay
        normalised as searched and the linear block keeps the gain. Either way the system
        simulates exactly as :meth:`predict` (same input range: an ``asym_backlash`` is
        ill-posed beyond the crossing of its lines, where :meth:`predict` lets the right
        line win and the system raises).

        Raises
        ------
        ParameterValidationError
            If the model is not of that form.
        """
        ops = list(self.input_ops)
        if self.A is None or self.offset != 0.0 or self.output_terms or self.output_ops:
            raise ParameterValidationError(
                "only linear-structure models without offset map to a HammersteinSystem; "
                "use RefinedModel.predict instead."
            )
        if self.inner is not None and not ops:
            return HammersteinSystem(self.inner, (self.A, self.B), x0=self.inner_x0,
                                     dt=self.dt)
        bl = self.inner
        single = len(ops) == 1 and ops[0][0] == "backlash"
        if (bl is not None and single and -bl.mr * bl.cr <= self.inner_x0 <= bl.ml * bl.cl):
            c = _theta(ops[0][1])[0]
            merged = Backlash(bl.ml, bl.cl + c, bl.mr, bl.cr + c)
            return HammersteinSystem(merged, (self.A, self.B), x0=self.inner_x0, dt=self.dt)
        if self.inner is None and len(ops) == 1 and ops[0][0] in ("backlash", "asym_backlash"):
            name, theta = ops[0][0], _theta(ops[0][1])
            if name == "backlash":
                ml, cl, mr, cr = 1.0, theta[0], 1.0, theta[0]
            else:
                sl, cl, cr = theta
                ml, mr = 1.0 + sl, 1.0 - sl
            k = self.chapter_gain(name) or 1.0
            return HammersteinSystem(Backlash(k * ml, cl, k * mr, cr), (self.A, self.B / k),
                                     dt=self.dt)
        if self.inner is None and not ops:
            # a linear model: backlash of (numerically) zero width is not allowed in
            # Backlash; report instead of faking one
            raise ParameterValidationError(
                "the model has no backlash; use RefinedModel.linear for the linear block."
            )
        raise ParameterValidationError(
            f"input nonlinearity {ops} is not a single backlash; use RefinedModel.predict."
        )


def black_box_predict(model, x: np.ndarray) -> np.ndarray:
    """``model.predict(x)`` checked: one finite output per input sample."""
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


def as_structure(model) -> RefinedModel:
    """Convert the user's model into a :class:`RefinedModel` (no effects added).

    Accepted, in this order: a :class:`RefinedModel`; a discrete
    ``control.TransferFunction``; a :class:`~hammerbound.systems.models.HammersteinSystem`; a
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
        return RefinedModel(A=A, B=B, dt=None if model.dt is True else float(model.dt))
    name = type(model).__name__
    system = model if isinstance(model, HammersteinSystem) else _fitted_system(model)
    if system is not None:
        A, B = np.array(system.A, dtype=float), np.array(system.B, dtype=float)
        _check_linear(A, B)
        return RefinedModel(A=A, B=B, inner=system.backlash, inner_x0=float(system.x0),
                            dt=getattr(system, "dt", None))
    if callable(getattr(model, "predict", None)):
        return RefinedModel(base=model)
    if callable(getattr(model, "fit", None)):
        raise ParameterValidationError(
            f"{name} has no fitted model: call .fit(...) first (diagnose uses the fitted "
            "central model in its system_ attribute)."
        )
    raise ParameterValidationError(
        f"model of type {name} is not supported: pass a discrete control.TransferFunction, "
        "a hammerbound.systems.models.HammersteinSystem, a fitted hammerbound identifier (with a "
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
            "hammerbound.systems.models.HammersteinSystem (the fitted central model)."
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
