"""The identifier of a backlash-Hammerstein system: two stages, or one record.

:class:`HammersteinBacklashIdentifier` bounds ``gamma = (m_l, c_l, m_r, c_r)`` and the
unit-gain linear block ``theta`` in one of two ways (``procedure``):

* **two-stage** (the chapter; with steady-state square-wave data and a PRBS ``+-u*``):

  1. stage 1 (a :class:`~hammerbound.BacklashSetEstimator`) bounds ``gamma`` exactly;
  2. the PRBS level ``u*`` is read from the input and checked against Result 1 for
     *every* feasible backlash;
  3. the inner signal is bounded by ``x^c_t +- dx_t`` (22.25)-(22.33), handed to stage 2
     as a :class:`~hammerbound.stage1.Stage2Record`;
  4. stage 2 (a :class:`~hammerbound.LinearEIVSetEstimator`) bounds ``theta`` from it, with
     independent per-sample input errors (``inner_signal="independent"``, the chapter) or
     one unknown value per PRBS level (``"two-level"``, what Result 1 implies);

* **one-record** (any ordinary record: steps, sines, closed-loop logs, and records that
  hold steady-state holds and PRBS segments; :mod:`hammerbound.joint`): both blocks and
  the unknown initial backlash state are bounded jointly from all samples, with the stage-2
  estimator's orders, output bound, method (``"exact"`` or ``"lp"``) and limits.
"""

from __future__ import annotations

from functools import partial

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted

from ..data.validation import as_signal, as_theta
from ..exceptions import DataValidationError, ParameterValidationError
from ..results import IntervalSet
from ..stage2.linear_model import is_vector_like
from ..systems.models import GAMMA_NAMES, Backlash, HammersteinSystem
from ..tables import units_line
from .setup import (
    GAIN_ASSUMPTION,
    check_bounds,
    choose_procedure,
    record_of,
    stage_estimators,
    steady_bound,
)

__all__ = ["HammersteinBacklashIdentifier", "central_system"]



def _theta_box_text(lin) -> str:
    """The a priori box of the linear block that stage 2 assumed (a bound at it says
    "from a priori box")."""
    from ..stage2.fitting import assumption_list

    return assumption_list(lin, lin.problem_)[3]


def _inner_text(inner_signal, x, bound) -> str:
    """The stage-2 assumption on the inner signal ``x`` (its centre values): an error per
    sample, or (two-level, Result 1) one unknown value per PRBS level (trial 13: "(per
    sample)" was said of both)."""
    from ..tables import bound_text, rounded_text

    if inner_signal != "two-level":
        return f"inner signal within the stage-1 bounds |dx_t| <= {bound_text(bound)}"
    x, bound = np.asarray(x, dtype=float), np.broadcast_to(bound, np.shape(x))
    up, down = (rounded_text(float(np.max(bound[s], initial=0)), down=True)  # no weaker
                for s in (x > 0, x < 0))                                   # than used
    return ("inner signal at two unknown levels (Result 1), one per PRBS level, within "
            f"their stage-1 bounds |dx| <= {up} (u = +u*) and {down} (u = -u*)")


def _past_crossing_text(bl, u_star) -> tuple:
    """The assumption a PRBS level past the crossing of some feasible backlash's lines
    rests on (new-user trial 19: it was admitted without a word): the square waves reached
    that far and showed each side's line there (``well_posed_on_data``)."""
    limit = bl.crossing_limit()
    if not u_star >= limit:
        return ()
    reach = min(-bl.input_range_[0], bl.input_range_[1])
    which = ("every" if bl.crossed_for_every(u_star) or bl.crossed_for_every(-u_star)
             else "some")  # of u* itself (review 51: "every" came from the data's reach)
    return (f"u* = {u_star:g} lies past the crossing of the backlash lines of {which} "
            f"feasible backlash (from |u| = {limit:.4g} on); admitted because the square "
            f"waves reached +-{reach:g}: the inner values at +-u* lie on the lines their "
            "steady states showed (well_posed_on_data)",)


def central_system(backlash, A, B, dt=None):
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


class HammersteinBacklashIdentifier(RegressorMixin, BaseEstimator):
    """Guaranteed bounds on a backlash-Hammerstein system, from two experiments or one record.

    Parameters
    ----------
    backlash : BacklashSetEstimator or None
        Stage-1 estimator (two-stage path; default ``BacklashSetEstimator()``); its output
        bound is the bound on the steady-state output errors (also used for steady-state
        points given to the one-record path).
    linear : LinearEIVSetEstimator or None
        Stage-2 estimator (default ``LinearEIVSetEstimator()``); its orders, delay, output
        bound, method and limits serve both paths. The linear block always has unit
        steady-state gain (22.8), which makes the backlash/linear split identifiable: a
        ``linear`` estimator with ``steady_state_gain=None`` (its default) is cloned with
        ``steady_state_gain=1``; any other gain raises ``ParameterValidationError``. Its
        ``total_time_limit`` (default 600 s, shared by all interval ends; ends stopped by it
        report guaranteed outer bounds) bounds the time of the linear block's fit (of the
        whole one-record fit), e.g.
        ``LinearEIVSetEstimator(method="exact", total_time_limit=60)``.
    inner_signal : {"independent", "two-level"}, default "independent"
        Two-stage path: how stage 2 treats the inner-signal uncertainty. ``"independent"``
        follows the chapter (22.31)-(22.34): one error ``|dx_t| <= Delta x_t`` per sample.
        ``"two-level"`` uses that under Result 1 the inner signal takes exactly two
        (unknown) values: one shared error per PRBS level. Both are guaranteed. Only the
        exact and moment methods use the shared errors: ``method="lp"`` bounds every
        equation's errors by their worst case, so its intervals are the same for both
        (the summary says so).
    prbs_level : float or None
        Two-stage path: ``u*``. Default: read from the PRBS input (two values ``+-u*``).
    procedure : {"auto", "two-stage", "one-record"}, default "auto"
        ``"auto"``: two-stage when steady-state data are given and the record is a PRBS
        ``+-u*``; one-record otherwise (no steady-state data, or an ordinary record: the
        steady-state points, if given, then join the record's equations). ``"one-record"``
        uses all data jointly also for the chapter's experiments.
    gamma_box : array of shape (4, 2) or None
        One-record path: a priori box of ``(m_l, c_l, m_r, c_r)`` (rows ``[lower, upper]``).
        Default: ``0 <= m <= 100 * (range(y) + 2 output_bound) / range(u)`` and
        ``0 <= c <= range(u)``, printed
        as an assumption; ends that only such an assumed limit holds are reported as
        infinite with a :class:`~hammerbound.exceptions.NotIdentifiedWarning`.

    Attributes
    ----------
    procedure_ : str
        ``"two-stage"`` or ``"one-record"``.
    backlash_, linear_ : fitted estimators (two-stage) or read-only views of the joint
        intervals with the same interface (one-record; :mod:`.views`)
    gamma_bounds_ : ndarray (4, 2)
        Bounds on ``(m_l, c_l, m_r, c_r)``.
    theta_bounds_ : ndarray (p, 2)
        Bounds on ``(a_1.., b_1..)``.
    bounds_ : ndarray (4 + p, 2)
        Both, stacked; names in :attr:`param_names_`.
    intervals_ : IntervalSet
        Every interval (backlash, then linear block) as one
        :class:`~hammerbound.results.IntervalSet`: a status per end, ``contains``,
        ``to_frame``, ``summary``, ``to_dict``, ``plot``.
    bound_info_ : tuple of BoundInfo
        Per interval end: status, certified bound, verified witness (one-record: of the
        backlash's ends too; two-stage: of the linear block's ends).
    assumptions_ : tuple of str
        What the bounds rest on.
    u_star_, inner_bounds_, xc_, dx_ : two-stage path only
        PRBS level, inner-signal bounds, central inner signal and its radius.
    system_ : HammersteinSystem
        The central model (centres of all intervals; None when some end is infinite).

    Notes
    -----
    ``fit(X, y, steady_state=...)``: ``X`` is the input ``u`` (shape (N,) or (N, 1)) or an
    IOData, ``y`` the output. Inside ``GridSearchCV`` pass ``steady_state`` as a dict or
    SteadyStateData so that it is not split with the record's samples.
    """

    def __init__(self, backlash=None, linear=None, *, inner_signal="independent",
                 prbs_level=None, procedure="auto", gamma_box=None):
        self.backlash = backlash
        self.linear = linear
        self.inner_signal = inner_signal
        self.prbs_level = prbs_level
        self.procedure = procedure
        self.gamma_box = gamma_box

    def fit(self, X, y=None, steady_state=None, *, output_bound=None):
        """Bound both blocks from the record ``(X, y)`` (and steady-state data if given).

        Parameters
        ----------
        X : array-like of shape (N,) or (N, 1), or IOData
            The input (a PRBS ``+-u*`` for the two-stage path; any record for the one-record
            path), or an :class:`~hammerbound.IOData` with input, output and ``dt``.
        y : array-like of shape (N,) or None
            Measured output (None with an IOData).
        steady_state : SteadyStateData, dict with keys "u" and "y", pair (u_ss, y_ss), or None
            Steady-state square-wave data (input amplitudes of both signs and the measured
            steady outputs).
        output_bound : float or array of shape (N,), optional
            Per-sample bound on the record's output errors for this fit, overriding the
            stage-2 estimator's; sample-aligned, so scikit-learn's CV splits it with the data.

        Returns
        -------
        self

        Raises
        ------
        ResultOneViolationError
            Two-stage: ``u*`` is inside the dead zone or past the crossing of the two
            backlash lines for some feasible backlash; the message gives the admissible range.
        DataValidationError
            Malformed data; two-stage without a two-level PRBS or steady-state data.
        EmptyFeasibleSetError, UnboundedSetError, SolverError
            From either path.

        Warns
        -----
        NotIdentifiedWarning
            One-record: the record does not bound some backlash parameter (named, with the
            cause); those ends are infinite.
        """
        bl, lin = stage_estimators(self)
        data = record_of(X, y)
        self.procedure_ = choose_procedure(self, data.u, steady_state)
        check_bounds(bl, lin, output_bound, steady_state is not None)
        if self.procedure_ == "two-stage":
            self._fit_two_stage(bl, lin, data, steady_state, output_bound)
        else:
            self._fit_one_record(bl, lin, data, steady_state, output_bound)
        self.bounds_ = np.array(self.intervals_.bounds)
        self.param_names_ = self.intervals_.param_names
        self.dt_ = data.dt
        self.units_ = (data.input_unit, data.output_unit)
        self.output_bound_ = output_bound
        self.n_features_in_ = 1
        return self

    def _fit_two_stage(self, bl, lin, data, steady_state, output_bound):
        from .two_stage import fit_two_stage

        f = fit_two_stage(bl, lin, data, steady_state, prbs_level=self.prbs_level,
                          inner_signal=self.inner_signal, output_bound=output_bound)
        self.backlash_, self.linear_ = f.backlash, f.linear
        self.u_star_, self.inner_bounds_ = f.u_star, f.inner
        self.xc_, self.dx_ = f.record.data.u, f.record.input_bound
        self.gamma_bounds_ = bl.gamma_bounds_
        self.theta_bounds_ = lin.bounds_
        self.bound_info_ = tuple(lin.bound_info_)
        self.intervals_ = IntervalSet.stack(bl.intervals_, lin.intervals_, method="two-stage")
        from ..stage1.smallest_bound import smallest_bound_text
        from ..tables import bound_text

        self.assumptions_ = (
            f"steady-state output errors |eta| <= {bound_text(bl.output_bound_)}"
            + smallest_bound_text(bl.smallest_bound_factor_, bl.output_bound_),
            "u > 0 steady states on the right line, u < 0 on the left (square waves), "
            "settled: a transient left counts against the steady-state output bound",
            f"PRBS output errors |eta_t| <= {bound_text(lin.problem_.output_bound)}",
            _inner_text(self._inner_used(), self.xc_, lin.problem_.input_bound),
            *_past_crossing_text(bl, f.u_star),
            GAIN_ASSUMPTION,
            _theta_box_text(lin),
        )
        ml, cl, mr, cr = bl.gamma_center_
        self.system_ = central_system(Backlash(ml, cl, mr, cr), lin.A_, lin.B_, data.dt)

    def _fit_one_record(self, bl, lin, data, steady_state, output_bound):
        from .one_record import fit_one_record, in_param_order
        from .setup import checked_steady
        from .views import BacklashBoxView, LinearBlockView, joint_samples

        steady = checked_steady(bl, steady_state)
        f = fit_one_record(lin, data, gamma_box=self.gamma_box, steady=steady,
                           steady_bound=None if steady is None else steady_bound(bl),
                           output_bound=output_bound)
        self.one_record_ = f
        # a partial of a module-level function (not a closure): the fitted identifier
        # pickles (joblib.dump, pickle), as the two-stage one does
        sampler = partial(joint_samples, f.problem, f.result.root_box,
                          [i.point for i in f.result.infos],
                          progress=bool(getattr(lin, "progress", False)))

        ends_theta, ends_gamma = in_param_order(f.result.infos, f.problem.p)
        self.linear_ = LinearBlockView(
            f.problem, f.theta_bounds, ends_theta[1], method=lin.method,
            dt=data.dt, names=(data.input_name, data.output_name),
            units=(data.input_unit, data.output_unit),
            time_unit=getattr(data, "time_unit", ""), sampler=sampler,
            theta_box=lin.theta_box, assumptions=f.assumptions)
        self.backlash_ = BacklashBoxView(f.gamma_bounds, (data.u.min(), data.u.max()),
                                         sampler)
        self.gamma_bounds_, self.theta_bounds_ = f.gamma_bounds, f.theta_bounds
        # the search's ends are theta's then the backlash's: here in the order of bounds_
        self.bound_info_ = ends_gamma + ends_theta[0]
        self.intervals_ = IntervalSet(GAMMA_NAMES + self.linear_.param_names_,
                                      np.vstack([f.gamma_bounds, f.theta_bounds]),
                                      infos=self.bound_info_, method="one-record")
        self.assumptions_ = f.assumptions
        self.system_ = None
        if np.all(np.isfinite(f.gamma_bounds)) and np.all(np.isfinite(f.theta_bounds)):
            ml, cl, mr, cr = f.gamma_bounds.mean(axis=1)
            self.system_ = central_system(Backlash(ml, cl, mr, cr), self.linear_.A_,
                                           self.linear_.B_, data.dt)

    def to_frame(self):
        """All intervals (backlash, then linear block) as a table: parameter, lower,
        centre, upper, half_width, status. A pandas DataFrame when pandas is installed,
        else a numpy structured array with the same fields."""
        check_is_fitted(self, "bounds_")
        return self.intervals_.to_frame()

    def _inner_used(self) -> str:
        """The inner-signal model the stage-2 bounds rest on: the LP method bounds each
        equation's errors on their own, so its bounds rest on the per-sample bounds only."""
        return "independent" if self.linear_.method == "lp" else self.inner_signal

    def summary(self) -> str:
        """Text summary: the procedure and its settings, the interval table (and, for one
        record, the assumptions the bounds rest on)."""
        check_is_fitted(self, "bounds_")
        from ..tables import dt_text

        lin = self.linear_
        pr = lin.problem_
        dt = dt_text(self.dt_, getattr(lin, "time_unit_", ""))
        units = units_line(getattr(self, "units_", ("", "")))
        if self.procedure_ == "one-record":
            head = (f"HammersteinBacklashIdentifier: one record, method {lin.method}, "
                    f"na={pr.na} nb={pr.nb} nk={pr.nk}, N = {pr.N}, dt = {dt}{units}")
            return self.intervals_.summary(title=head, assumptions=self.assumptions_)
        inner = self.inner_signal
        if inner == "two-level" and lin.method == "lp":
            inner += (" (not used by method 'lp', which bounds each equation's errors on "
                      "their own; method='exact' uses it)")
        head = (f"HammersteinBacklashIdentifier: u* = {self.u_star_:g}, stage 2 method "
                f"{lin.method}, na={pr.na} nb={pr.nb} nk={pr.nk}, inner signal "
                f"{inner}, N = {pr.N}, dt = {dt}{units}")
        return self.intervals_.summary(title=head, assumptions=self.assumptions_)

    @property
    def center_(self):
        check_is_fitted(self, "bounds_")
        return self.intervals_.center

    @property
    def radius_(self):
        check_is_fitted(self, "bounds_")
        return self.intervals_.radius

    def contains(self, gamma, theta=None, tol=0.0) -> bool:
        """Whether the backlash ``gamma`` and linear ``theta`` lie in all intervals.

        ``gamma``: ``(ml, cl, mr, cr)`` or a :class:`Backlash`; ``theta``: a vector in
        ``linear_.param_names_`` order, a discrete ``control.TransferFunction`` or an
        ``(A, B)`` pair. ``contains(system)`` with a :class:`HammersteinSystem` checks both.
        ``tol`` widens every end by ``tol max(1, |end|)``, as the other ``contains``
        (new-user trial 19: this one had none).
        """
        check_is_fitted(self, "bounds_")
        if isinstance(gamma, HammersteinSystem) and theta is None:
            gamma, theta = gamma.backlash, (gamma.A, gamma.B)
        if isinstance(gamma, Backlash):
            gamma = gamma.gamma
        if theta is None:
            raise DataValidationError("contains needs theta (or a HammersteinSystem).")
        g = as_theta(gamma, 4, GAMMA_NAMES, name="gamma")
        lin = self.linear_
        th = as_theta(theta if is_vector_like(theta) else lin.theta_of(theta),
                      len(lin.param_names_), lin.param_names_)
        return self.intervals_.contains(np.concatenate([g, th]), tol=tol)

    def predict(self, X):
        """Output of the central model simulated on input ``X``.

        ``X`` an array: from rest. ``X`` an :class:`~hammerbound.IOData`: the linear block
        starts from the segment's *measured* outputs ``y[:n0]`` and runs freely from there,
        the backlash from the state in its first band that matches the segment best (see
        :meth:`score`).
        """
        check_is_fitted(self, "bounds_")
        from ..data.iodata import IOData
        from ..timeseries import simulate_matched

        self._check_central()
        if isinstance(X, IOData):
            return simulate_matched(self.system_, X.u, X.y, self.linear_._n0())
        u = as_signal("X", X)
        return self.system_.simulate(u)

    def score(self, X, y=None, sample_weight=None):
        """R^2 of the central model's free-run simulation on a (held-out) segment.

        Neither state is measured: the linear block starts from the measured outputs of
        the first ``n0 = max(na, last input lag)`` samples and runs on the input alone from
        there, the backlash from the state in its first band that matches the segment best
        (least squares; for a PRBS outside the dead zone the state is on a line after the
        first sample anyway); R^2 is taken over ``t >= n0``. A
        multi-step (simulation) score, meaningful for a ``TimeSeriesSplit`` test fold:
        ``score(data) == r2_score(data.y[n0:], predict(data)[n0:])``. scikit-learn's
        scorers (``scoring="r2"``, ...) need ``y``: pass the IOData and ``data.y``.
        """
        check_is_fitted(self, "bounds_")
        from ..data.iodata import unpack
        from ..timeseries import segment_r2, simulate_matched

        self._check_central()
        X, y, _ = unpack(X, y, func="score")
        u, yy = as_signal("X", X), as_signal("y", y)
        if u.shape != yy.shape:
            raise DataValidationError("X and y must have the same length.")
        n0 = self.linear_._n0()
        if u.size <= n0 + 1:
            raise DataValidationError(
                f"the scored segment needs more than n0 + 1 = {n0 + 1} samples; got {u.size}.")
        w = simulate_matched(self.system_, u, yy, n0)
        return segment_r2(yy, w, n0, sample_weight)

    def _check_central(self):
        if self.system_ is None:
            from ..exceptions import UnboundedSetError
            from ..joint.prior import reversal_summary

            fit = getattr(self, "one_record_", None)
            details = getattr(getattr(fit, "result", None), "details", None)
            timed = getattr(details, "stopped_by_time", False) and not (  # recheck 52b
                reversal_summary(fit.problem.u)["monotone"])  # no time bounds c then
            raise UnboundedSetError(  # (the time limit named: new-user trial 22)
                "no central model: " + ("the time limit stopped the search before every "
                "parameter was bounded" if timed else "the record does not bound every "
                "parameter") + " (see the NotIdentifiedWarning of fit and the infinite ends "
                "of summary()); " + ("raise total_time_limit" if timed else "identify from a "
                "record that reverses by more than the dead band and moves the input often")
                + ", or give a gamma_box / theta_box from what you know.")

    def output_envelope(self, X, y=None, output_bound=None):
        """Guaranteed one-step-ahead band of the noise-free output.

        Uses the inner-signal bounds for ``X`` (two-stage: of stage 1 for a PRBS; one
        record: the play operator's envelope over the backlash intervals from an unknown
        initial state) and the linear block's intervals (see
        :meth:`LinearEIVSetEstimator.one_step_envelope`). ``X`` may be an
        :class:`~hammerbound.IOData` (then ``y`` is omitted). ``output_bound``: per-sample
        output error bound of ``(X, y)``; default that of the fit.
        """
        from ..data.iodata import unpack

        check_is_fitted(self, "bounds_")
        X, y, _ = unpack(X, y, func="output_envelope")
        u = as_signal("X", X)
        if self.procedure_ == "one-record":
            from ..joint.modes import inner_envelope
            from .views import require_bounded

            require_bounded("output envelope", GAMMA_NAMES, self.gamma_bounds_,
                            "; identify from a record that reverses by more than the dead "
                            "band, or give a gamma_box from what you know.")
            lo, hi = inner_envelope(u, self.gamma_bounds_)
            xc, dx = 0.5 * (lo + hi), 0.5 * (hi - lo) * (1 + 1e-12) + 1e-300
        else:
            xc, dx = self.inner_bounds_.transform(u)
        return self.linear_.one_step_envelope(xc, y, input_bound=dx,
                                              output_bound=self.output_bound_
                                              if output_bound is None else output_bound)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.one_d_array = True
        return tags

    # ------------------------------------------------------------------ model set (issue 16)
    def sample(self, n, random_state=None, *, seeds=None):
        """Certified samples of both blocks: ``(backlash_samples, linear_samples)``.

        ``seeds`` (two-stage only): starting points of the linear block's sampler, rows of
        ``theta`` (each verified first; see :meth:`LinearEIVSetEstimator.sample`), e.g. when
        an LP fit's set is too thin for the sampler to find a member by itself.

        Two-stage: the stage-2 set does not depend on which feasible backlash is true (it
        accounts for all of them through the inner-signal bounds), so the joint set is the
        product and any pairing of the two sample sets is feasible. One record: the
        linear block's set depends on the backlash, so the points are drawn jointly and
        both items are the same :class:`~hammerbound.hammerstein.views.JointSamples`
        (row ``i`` of ``gamma`` goes with row ``i`` of ``theta``).
        """
        check_is_fitted(self, "bounds_")
        rng = np.random.default_rng(random_state) if not isinstance(
            random_state, np.random.Generator) else random_state
        if self.procedure_ == "one-record":
            if seeds is not None:
                raise ParameterValidationError(
                    "seeds apply to the linear block of a two-stage fit; the one-record "
                    "samples start from the witnesses of its search (fit with "
                    "method='exact' for more of them).")
            smp = self.linear_.sample(n, random_state=rng)
            return smp, smp
        return (self.backlash_.sample(n, random_state=rng),
                self.linear_.sample(n, random_state=rng, seeds=seeds))

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
