"""The two-stage procedure of the chapter: backlash first, then the linear block.

:class:`HammersteinBacklashIdentifier` composes a :class:`~hammerbound.BacklashSetEstimator`
(stage 1, steady-state square-wave data) and a :class:`~hammerbound.LinearEIVSetEstimator`
(stage 2, PRBS data):

1. stage 1 bounds ``gamma = (m_l, c_l, m_r, c_r)`` exactly;
2. the PRBS level ``u*`` is read from the input and checked against Result 1 for *every*
   feasible backlash (outside the dead zone, before the crossing of the two lines);
3. the inner signal ``x_t`` is bounded by ``x^c_t +- dx_t`` (22.25)-(22.33);
4. stage 2 bounds ``theta`` from ``(x^c, dx, y)``, either with independent per-sample input
   errors as in the chapter (``inner_signal="independent"``) or - what Result 1 actually
   implies - with *one* unknown value per PRBS level (``inner_signal="two-level"``), which
   gives much tighter intervals.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.utils.validation import check_is_fitted

from .._compat import is_given
from ..data.validation import as_signal, as_theta, check_scale
from ..exceptions import DataValidationError, ParameterValidationError
from ..stage1.estimator import BacklashSetEstimator
from ..stage1.inner_signal import INNER_SIGNALS, read_prbs_level
from ..stage2.estimator import LinearEIVSetEstimator
from ..systems.models import Backlash, HammersteinSystem

__all__ = ["HammersteinBacklashIdentifier"]



def _steady_pair(steady_state):
    """Accept SteadyStateData, a dict with 'u'/'y', or a pair (u, y)."""
    if steady_state is None:
        raise DataValidationError(
            "fit needs the steady-state square-wave data for stage 1: pass "
            "steady_state=(u_ss, y_ss) (or a dict {'u': ..., 'y': ...} / SteadyStateData)."
        )
    if hasattr(steady_state, "u") and hasattr(steady_state, "y"):
        return steady_state.u, steady_state.y
    if isinstance(steady_state, dict):
        try:
            return steady_state["u"], steady_state["y"]
        except KeyError as exc:
            raise DataValidationError(
                "steady_state dict must have keys 'u' and 'y'."
            ) from exc
    try:
        u, y = steady_state
    except (TypeError, ValueError) as exc:
        raise DataValidationError(
            "steady_state must be a pair (u_ss, y_ss), a dict with 'u' and 'y', or "
            "SteadyStateData."
        ) from exc
    return u, y


def _central_system(backlash, A, B, dt=None):
    """The central model; its A need not be stable (the centre of intervals that contain
    stable A's may lie outside the stability region): warn instead of failing the fit."""
    try:
        return HammersteinSystem(backlash, (A, B), dt=dt)
    except ParameterValidationError:
        import warnings

        warnings.warn(
            "the central model (centre of the parameter intervals) has an unstable A(q^-1); "
            "the intervals are still guaranteed, but predict()/score() simulate an unstable "
            "model. Narrow the intervals (more data, method='exact', inner_signal='two-level').",
            RuntimeWarning, stacklevel=3,
        )
        return HammersteinSystem._unchecked(backlash, (A, B), dt=dt)


def _stage_estimator(value, cls, name, example):
    """A clone of the stage estimator ``value`` (an instance of ``cls``), or a typed error
    that says what to pass (a class, a string, another estimator)."""
    if isinstance(value, cls):
        return clone(value)
    if isinstance(value, type) and issubclass(value, cls):
        got = f"the class {cls.__name__} itself"
    elif isinstance(value, str):
        got = f"the string {value!r}"
    else:
        got = f"a {type(value).__name__}"
    raise ParameterValidationError(
        f"{name} must be a {cls.__name__} instance; got {got}. Pass e.g. {name}={example} "
        f"(its options, such as method=..., go to the {cls.__name__}).")


def _stage_estimators(backlash, linear, output_bound):
    """Clones of both stage estimators; refuses, before any work, a missing output bound."""
    bl_example = "BacklashSetEstimator(output_bound=0.05)"
    lin_example = "LinearEIVSetEstimator(na=2, nb=2, output_bound=0.05)"
    bl = None if backlash is None else _stage_estimator(
        backlash, BacklashSetEstimator, "backlash", bl_example)
    if bl is None or _no_bound(bl):
        raise ParameterValidationError(
            "HammersteinBacklashIdentifier: the stage-1 estimator has no output_bound. Stage "
            "1 rests on the bound of the steady-state output errors, which has no default: "
            f"pass backlash={bl_example} (your sensor's error bound).")
    lin = LinearEIVSetEstimator() if linear is None else _stage_estimator(
        linear, LinearEIVSetEstimator, "linear", lin_example)
    if output_bound is None and _no_bound(lin):
        raise ParameterValidationError(
            "HammersteinBacklashIdentifier: the stage-2 estimator has no output_bound. Stage "
            "2 rests on the bound of the PRBS output errors, which has no default: pass "
            f"linear={lin_example} (or fit(..., output_bound=...)).")
    return bl, lin


def _no_bound(est) -> bool:
    """Whether a stage estimator was given no output bound (under either name)."""
    return est.output_bound is None and not is_given(est.noise_bound)


class HammersteinBacklashIdentifier(RegressorMixin, BaseEstimator):
    """Guaranteed bounds on a backlash-Hammerstein system (stages 1 and 2 of the chapter).

    Parameters
    ----------
    backlash : BacklashSetEstimator
        Stage-1 estimator, e.g. ``BacklashSetEstimator(output_bound=0.05)``; its
        ``output_bound`` is the bound on the steady-state output errors. Required (``None``,
        the default for scikit-learn, makes :meth:`fit` raise
        :class:`~hammerbound.exceptions.ParameterValidationError`): the guarantee rests on
        that bound.
    linear : LinearEIVSetEstimator
        Stage-2 estimator, e.g. ``LinearEIVSetEstimator(na=2, nb=2, output_bound=0.05)``;
        its ``output_bound`` bounds the PRBS output errors. Required like ``backlash``
        (unless ``fit`` gets ``output_bound=``: then ``None`` means
        ``LinearEIVSetEstimator()``, ``na = nb = 2``, order-1 moment relaxation).
        Stage 2 always imposes the unit steady-state gain (22.8) that makes the
        backlash/linear split identifiable (stage 1 measures ``G(1) m``, read as ``m``):
        a ``linear`` estimator with ``steady_state_gain=None`` (its default) is cloned
        with ``steady_state_gain=1``; any other gain raises ``ParameterValidationError``.
        To bound the time of stage 2, give it a total budget:
        ``linear=LinearEIVSetEstimator(method="exact", total_time_limit=60)`` or
        ``set_params(linear__total_time_limit=60)`` (seconds, shared by all interval ends;
        ends stopped by it report guaranteed bounds, never wider than the LP ones).
    inner_signal : {"independent", "two-level"}, default "independent"
        How stage 2 treats the inner-signal uncertainty. ``"independent"`` follows the
        chapter (22.31)-(22.34): one error ``|dx_t| <= Delta x_t`` per sample.
        ``"two-level"`` uses that under Result 1 the inner signal takes exactly two
        (unknown) values: one shared error per PRBS level. Both are guaranteed.
    prbs_level : float or None
        ``u*``. Default: read from the PRBS input (which must take the two values
        ``+-u*``).

    Attributes
    ----------
    backlash_, linear_ : fitted estimators
    gamma_bounds_ : ndarray (4, 2)
        Bounds on ``(m_l, c_l, m_r, c_r)``.
    theta_bounds_ : ndarray (p, 2)
        Bounds on ``(a_1.., b_1..)``.
    bounds_ : ndarray (4 + p, 2)
        Both, stacked; names in :attr:`param_names_`.
    u_star_ : float
    inner_bounds_ : InnerSignalBounds
    xc_, dx_ : ndarray (N,)
        Central inner signal and its radius used in stage 2.
    system_ : HammersteinSystem
        The central model (centres of all intervals).

    Notes
    -----
    ``fit(X, y, steady_state=...)``: ``X`` is the PRBS input ``u`` (shape (N,) or (N, 1)),
    ``y`` the PRBS output; ``steady_state`` the square-wave steady-state data. Inside
    ``GridSearchCV`` pass ``steady_state`` as a dict or SteadyStateData so that it is not
    split with the PRBS samples.
    """

    def __init__(self, backlash=None, linear=None, *, inner_signal="independent",
                 prbs_level=None):
        self.backlash = backlash
        self.linear = linear
        self.inner_signal = inner_signal
        self.prbs_level = prbs_level

    def fit(self, X, y=None, steady_state=None, *, output_bound=None):
        """Run stage 1 on ``steady_state``, check Result 1, run stage 2 on ``(X, y)``.

        Parameters
        ----------
        X : array-like of shape (N,) or (N, 1), or IOData
            PRBS input, taking the two values ``+-u*``; or an :class:`~hammerbound.IOData`
            with the PRBS input and output (its ``dt`` flows into :attr:`system_`).
        y : array-like of shape (N,) or None
            Measured PRBS output (None with an IOData).
        steady_state : SteadyStateData, dict with keys "u" and "y", or pair (u_ss, y_ss)
            Steady-state square-wave data for stage 1 (input amplitudes of both signs and
            the measured steady outputs).
        output_bound : float or array of shape (N,), optional
            Per-sample bound on the PRBS output errors for this fit, overriding the stage-2
            ``output_bound``; sample-aligned, so scikit-learn's CV splits it with the data.

        Returns
        -------
        self

        Raises
        ------
        ResultOneViolationError
            ``u*`` is inside the dead zone or past the crossing of the two backlash lines
            for some feasible backlash; the message gives the admissible range.
        DataValidationError
            ``X`` is not a two-level PRBS, lengths differ, missing steady-state data.
        EmptyFeasibleSetError, UnboundedSetError, SolverError
            From either stage.
        """
        if self.inner_signal not in INNER_SIGNALS:
            raise ParameterValidationError(
                f"inner_signal must be one of {INNER_SIGNALS}; got {self.inner_signal!r}."
            )
        bl, lin = _stage_estimators(self.backlash, self.linear, output_bound)
        g = lin.steady_state_gain
        if g is None:
            lin.set_params(steady_state_gain=1.0)  # (22.8), explicitly on the clone
        elif not (isinstance(g, (int, float, np.number)) and float(g) == 1.0):
            raise ParameterValidationError(
                f"the identifier normalises the linear block to unit steady-state gain (22.8) "
                f"and lets the backlash slopes carry the gain; got linear steady_state_gain="
                f"{g!r}. Use steady_state_gain=None (or 1.0) on the stage-2 estimator."
            )
        from ..data.iodata import IOData, unpack

        X, y, data = unpack(X, y)
        u = as_signal("X (PRBS input)", X)
        yy = as_signal("y (PRBS output)", y)
        if u.shape != yy.shape:
            raise DataValidationError(
                f"X and y must have the same number of samples; got {u.size} and {yy.size}."
            )
        check_scale("HammersteinBacklashIdentifier.fit", {"X (PRBS input)": u,
                                                          "y (PRBS output)": yy},
                    hint=" (the slopes m_l, m_r and theta are unchanged; multiply the bounds "
                         "on c_l, c_r by s)")
        if data is None:
            data = IOData(u, yy)
        u_ss, y_ss = _steady_pair(steady_state)
        bl.fit(u_ss, y_ss)
        u_star = read_prbs_level(u, self.prbs_level)
        inner = bl.inner_signal_bounds(u_star)  # checks Result 1
        record = inner.stage2_record(data, self.inner_signal)
        lin.fit(record.data, input_bound=record.input_bound, input_groups=record.input_groups,
                output_bound=output_bound)
        dt = lin.dt_
        xc, dx = record.data.u, record.input_bound
        self.backlash_ = bl
        self.linear_ = lin
        self.u_star_ = u_star
        self.inner_bounds_ = inner
        self.xc_, self.dx_ = xc, dx
        self.gamma_bounds_ = bl.gamma_bounds_
        self.theta_bounds_ = lin.bounds_
        self.bounds_ = np.vstack([bl.gamma_bounds_, lin.bounds_])
        self.param_names_ = ("ml", "cl", "mr", "cr") + tuple(lin.param_names_)
        ml, cl, mr, cr = bl.gamma_center_
        self.system_ = _central_system(Backlash(ml, cl, mr, cr), lin.A_, lin.B_, dt)
        self.dt_ = dt
        self.output_bound_ = output_bound
        self.n_features_in_ = 1
        return self

    def _status(self):
        return ["optimal"] * 4 + list(self.linear_._status())

    def to_frame(self):
        """All intervals (backlash, then linear block) as a table: parameter, lower,
        centre, upper, half_width, status. A pandas DataFrame when pandas is installed,
        else a numpy structured array with the same fields."""
        check_is_fitted(self, "bounds_")
        from ..tables import interval_frame

        return interval_frame(self.param_names_, self.bounds_, self._status())

    def summary(self) -> str:
        """Text summary: PRBS level, stage-2 settings and the interval table."""
        check_is_fitted(self, "bounds_")
        from ..tables import bound_text, interval_text

        lin = self.linear_
        pr = lin.problem_
        head = (f"HammersteinBacklashIdentifier: u* = {self.u_star_:g}, stage 2 method "
                f"{lin.method}, na={pr.na} nb={pr.nb} nk={pr.nk}, inner signal "
                f"{self.inner_signal}, N = {pr.N}, dt = "
                f"{'not given' if self.dt_ is None else f'{self.dt_:g}'}\n"
                f"assumptions: output error bounds |eta| <= "
                f"{bound_text(self.backlash_.output_bound_)} (steady state), "
                f"{bound_text(pr.output_bound)} (PRBS); inner signal within the stage-1 "
                f"bounds |dx_t| <= {bound_text(pr.input_bound)}; unit steady-state gain of "
                "the linear block (22.8)")
        return interval_text(self.param_names_, self.bounds_, self._status(), title=head)

    @property
    def center_(self):
        check_is_fitted(self, "bounds_")
        return self.bounds_.mean(axis=1)

    @property
    def radius_(self):
        check_is_fitted(self, "bounds_")
        return 0.5 * (self.bounds_[:, 1] - self.bounds_[:, 0])

    def contains(self, gamma, theta=None) -> bool:
        """Whether the backlash ``gamma`` and linear ``theta`` lie in all intervals.

        ``gamma``: ``(ml, cl, mr, cr)`` or a :class:`Backlash`; ``theta``: a vector in
        ``linear_.param_names_`` order, a discrete ``control.TransferFunction`` or an
        ``(A, B)`` pair. ``contains(system)`` with a :class:`HammersteinSystem` checks both.
        """
        check_is_fitted(self, "bounds_")
        if isinstance(gamma, HammersteinSystem) and theta is None:
            gamma, theta = gamma.backlash, (gamma.A, gamma.B)
        if isinstance(gamma, Backlash):
            gamma = gamma.gamma
        if theta is None:
            raise DataValidationError("contains needs theta (or a HammersteinSystem).")
        g = as_theta(gamma, 4, ("ml", "cl", "mr", "cr"), name="gamma")
        in_gamma = np.all((g >= self.gamma_bounds_[:, 0]) & (g <= self.gamma_bounds_[:, 1]))
        return bool(in_gamma) and self.linear_.contains(theta)

    def predict(self, X):
        """Output of the central model simulated on input ``X``.

        ``X`` an array: from rest. ``X`` an :class:`~hammerbound.IOData`: the linear block
        starts from the segment's *measured* outputs ``y[:n0]`` and runs freely from there
        (see :meth:`score`).
        """
        check_is_fitted(self, "bounds_")
        from ..data.iodata import IOData
        from ..timeseries import simulate_from_measured

        if isinstance(X, IOData):
            x = self.system_.inner(X.u)
            return simulate_from_measured(self.system_.A, self.system_.B, x, X.y,
                                          self.linear_._n0())
        u = as_signal("X", X)
        return self.system_.simulate(u)

    def score(self, X, y=None, sample_weight=None):
        """R^2 of the central model's free-run simulation on a (held-out) segment.

        The backlash is simulated from its initial state (for a PRBS outside the dead zone
        the state is on a line after the first sample, whatever it was); the linear block
        starts from the measured outputs of the first ``n0 = max(na, last input lag)``
        samples and runs on the input alone from there; R^2 is taken over ``t >= n0``. A
        multi-step (simulation) score, meaningful for a ``TimeSeriesSplit`` test fold.
        """
        check_is_fitted(self, "bounds_")
        from ..data.iodata import unpack
        from ..timeseries import segment_r2, simulate_from_measured

        X, y, _ = unpack(X, y)
        u, yy = as_signal("X", X), as_signal("y", y)
        if u.shape != yy.shape:
            raise DataValidationError("X and y must have the same length.")
        n0 = self.linear_._n0()
        if u.size <= n0 + 1:
            raise DataValidationError(
                f"the scored segment needs more than n0 + 1 = {n0 + 1} samples; got {u.size}.")
        w = simulate_from_measured(self.system_.A, self.system_.B, self.system_.inner(u), yy,
                                   n0)
        return segment_r2(yy, w, n0, sample_weight)

    def output_envelope(self, X, y, output_bound=None):
        """Guaranteed one-step-ahead band of the noise-free PRBS output.

        Uses the inner-signal bounds of stage 1 for ``X`` and the parameter intervals of
        stage 2 (see :meth:`LinearEIVSetEstimator.one_step_envelope`). ``output_bound``:
        per-sample output error bound of ``(X, y)``; default that of the fit.
        """
        check_is_fitted(self, "bounds_")
        u = as_signal("X", X)
        xc, dx = self.inner_bounds_.transform(u)
        return self.linear_.one_step_envelope(xc, y, input_bound=dx,
                                              output_bound=self.output_bound_
                                              if output_bound is None else output_bound)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.one_d_array = True
        return tags

    # ------------------------------------------------------------------ model set (issue 16)
    def sample(self, n, random_state=None):
        """Certified samples of both blocks: ``(backlash_samples, linear_samples)``.

        The stage-2 set does not depend on which feasible backlash is true (it accounts
        for all of them through the inner-signal bounds), so the joint set is the product
        and any pairing of the two sample sets is feasible.
        """
        check_is_fitted(self, "bounds_")
        rng = np.random.default_rng(random_state) if not isinstance(
            random_state, np.random.Generator) else random_state
        return self.backlash_.sample(n, random_state=rng), self.linear_.sample(n, random_state=rng)

    def _fitted_dt(self):
        """Sampling time of the fitted data, or None when it was not given."""
        return getattr(self, "dt_", None)

    def frequency_response_bounds(self, omega=None, dt=None, *, on_gain_plane=False):
        """Envelope of the linear block (see :meth:`LinearEIVSetEstimator.frequency_response_bounds`).

        ``dt`` defaults to the sampling time of the fitted data (:attr:`dt_`); when none is
        known, frequencies are in rad/sample."""
        check_is_fitted(self, "bounds_")
        dt = self._fitted_dt() if dt is None else dt
        return self.linear_.frequency_response_bounds(omega, dt=dt, on_gain_plane=on_gain_plane)

    def uncertainty_weight(self, kind="multiplicative", order=2, dt=None, **kwargs):
        """Weight of the linear block (see :meth:`LinearEIVSetEstimator.uncertainty_weight`);
        ``dt`` as in :meth:`frequency_response_bounds`."""
        check_is_fitted(self, "bounds_")
        dt = self._fitted_dt() if dt is None else dt
        return self.linear_.uncertainty_weight(kind, order, dt, **kwargs)

    def inverse(self, v_range=None, x0=0.0):
        """Backlash compensator (see :meth:`BacklashSetEstimator.inverse`)."""
        check_is_fitted(self, "bounds_")
        return self.backlash_.inverse(v_range=v_range, x0=x0)
