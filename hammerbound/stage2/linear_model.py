"""The fitted linear block as a model: its interval table, central transfer function,
membership test, predictions, score and guaranteed one-step band.

:class:`LinearModelMixin` is mixed into :class:`~hammerbound.LinearEIVSetEstimator`; it
reads the fitted attributes (``intervals_``, ``bounds_``, ``center_``, ``param_names_``,
``problem_``, ``dt_``, ``signal_names_``) and the structure (``na``, ``nb``, ``_lags()``,
``_nk()``, ``_output_bound()``).
"""

from __future__ import annotations

import numbers

import numpy as np
from scipy.signal import lfilter
from sklearn.utils.validation import check_is_fitted

from ..data.iodata import signal_label
from ..data.validation import as_bound, as_signal, as_theta
from ..exceptions import DataValidationError, ParameterValidationError
from ..results import OutputEnvelope
from ..tables import dt_text
from .fitting import assumption_list

__all__ = ["LinearModelMixin", "is_vector_like"]


def is_vector_like(theta) -> bool:
    """A flat sequence of numbers (not a TransferFunction nor an (A, B) pair)."""
    if hasattr(theta, "num") and hasattr(theta, "den"):
        return False
    try:
        arr = np.asarray(theta, dtype=float)
    except (TypeError, ValueError):
        return False
    return arr.ndim == 1


class LinearModelMixin:
    """Tables, central model, membership and predictions of a fitted linear block."""

    # ------------------------------------------------------------------ tables
    def _status(self):
        return self.intervals_.status_text()

    def to_frame(self):
        """The intervals as a table: parameter, lower, centre, upper, half_width, status.

        A pandas DataFrame when pandas is installed, else a numpy structured array with
        the same fields. ``status`` is ``"optimal"`` or says which end is set by the a
        priori box or by a solver/time limit (still guaranteed).
        """
        check_is_fitted(self, "bounds_")
        return self.intervals_.to_frame()

    def summary(self) -> str:
        """Text summary: model structure, assumptions, data and the interval table."""
        check_is_fitted(self, "bounds_")
        pr = self.problem_
        g = self.steady_state_gain
        dt = dt_text(getattr(self, "dt_", None), getattr(self, "time_unit_", ""))
        head = (f"LinearEIVSetEstimator: method {self.method_label()}, na={pr.na} nb={pr.nb} "
                f"nk={pr.nk}, N = {pr.N}, dt = {dt}, "
                + ("no gain constraint" if g is None else f"gain B(1)/A(1) = {g:g}"))
        sig = signal_label(getattr(self, "signal_names_", ("u", "y")),
                           getattr(self, "signal_units_", ("", "")))
        if sig:
            head += f"\nsignals: {sig}"
        return self.intervals_.summary(title=head, assumptions=assumption_list(self, pr))

    def method_label(self) -> str:
        """The method as the summary names it: the moment method with its relaxation
        order, basis (order >= 2) and solver, e.g. ``moment (order 2, sparse basis,
        clarabel)``."""
        order = getattr(self, "relaxation_order", None)
        if self.method != "moment" or order is None:
            return self.method
        basis = f", {self.relaxation_basis} basis" if order >= 2 else ""
        return f"moment (order {order}{basis}, {self.solver})"

    # ------------------------------------------------------------------ model
    def _polys(self, theta=None):
        check_is_fitted(self, "bounds_")
        th = self.center_ if theta is None else as_theta(theta, self.bounds_.shape[0],
                                                                  self.param_names_)
        na = self.na
        A = np.concatenate([[1.0], th[:na]])
        lags = self._lags()
        B = np.zeros(int(lags[-1]) + 1)
        B[lags] = th[na:]
        return A, B

    @property
    def A_(self):
        """Central denominator ``[1, a_1, ..., a_na]``."""
        return self._polys()[0]

    @property
    def B_(self):
        """Central numerator ``[b_0, b_1, ...]`` up to the last lag (zeros before ``nk``)."""
        return self._polys()[1]

    def to_transfer_function(self, dt=None, theta=None):
        """The central (or given ``theta``) model as a discrete ``control.TransferFunction``.

        ``dt`` defaults to the sampling time of the fitted data (an :class:`IOData`), or
        ``True`` (discrete, sampling time not given) as in python-control.
        """
        import control

        from ..data.validation import discrete_dt

        dt = discrete_dt(dt, getattr(self, "dt_", None))
        A, B = self._polys(theta)
        n = max(A.size, B.size)
        A = np.concatenate([A, np.zeros(n - A.size)])
        B = np.concatenate([B, np.zeros(n - B.size)])
        names = getattr(self, "signal_names_", None)
        if names is None or names == ("u", "y"):
            return control.tf(B, A, dt)
        return control.tf(B, A, dt, inputs=names[0], outputs=names[1])

    def theta_of(self, G):
        """``theta`` in :attr:`param_names_` order of a model ``G``: a discrete
        ``control.TransferFunction`` or a pair ``(A, B)`` in powers of ``q^-1``.

        Raises ParameterValidationError if ``G`` has a coefficient outside this model
        structure (a higher order, another delay).
        """
        check_is_fitted(self, "bounds_")
        from ..systems.models import as_polynomials

        G_dt = getattr(G, "dt", None)
        dt = getattr(self, "dt_", None)
        if dt is not None and isinstance(G_dt, numbers.Real) and not isinstance(G_dt, bool) \
                and not np.isclose(float(G_dt), dt, rtol=1e-9, atol=0):
            raise ParameterValidationError(
                f"the transfer function has dt={G_dt:g} but the data were sampled with "
                f"dt={dt:g}; discretise it at dt={dt:g} first.")
        A, B = as_polynomials(G)
        lags = self._lags()
        na = self.na
        a = np.zeros(na)
        a[:min(na, A.size - 1)] = A[1:na + 1]
        extra_a = A[na + 1:]
        b = np.zeros(lags.size)
        keep = lags[lags < B.size]
        b[:keep.size] = B[keep]
        mask = np.ones(B.size, bool)
        mask[keep] = False
        if np.any(extra_a != 0) or np.any(B[mask] != 0):
            # new-user trial 20 gave [b1, b2] for [0, b1, b2]
            lead = ("" if self._nk() == 0 or B.size == 0 or B[0] == 0 else
                    f" B is in powers of q^-1 from q^0: B[0] is b0, which a delay "
                    f"nk={self._nk()} makes 0: B = [0, ..., b{lags[0]}, ...].")
            raise ParameterValidationError(
                f"the model has coefficients outside this structure (na={na}, nb={self.nb}, "
                f"nk={self._nk()}: A = {A.tolist()}, B = {B.tolist()}).{lead} "
                f"{'Or pass' if lead else 'Pass'} theta in order {self.param_names_}.")
        return np.concatenate([a, b])

    def contains(self, theta, tol=0.0) -> bool:
        """Whether ``theta`` lies in every reported interval.

        ``theta`` is a vector in :attr:`param_names_` order, a discrete
        ``control.TransferFunction`` or a pair ``(A, B)`` (see :meth:`theta_of`). ``tol``
        widens each end by ``tol max(1, |end|)``
        (:meth:`hammerbound.results.IntervalSet.contains`).
        """
        check_is_fitted(self, "bounds_")
        if not is_vector_like(theta):
            theta = self.theta_of(theta)
        th = as_theta(theta, self.bounds_.shape[0], self.param_names_)
        return self.intervals_.contains(th, tol)

    def _n0(self) -> int:
        return max(self.na, int(self._lags()[-1]))

    def predict(self, X):
        """Noise-free output of the central model simulated on input ``X``.

        ``X`` an array: free-run simulation from zero initial state. ``X`` an
        :class:`~hammerbound.IOData`: free-run simulation started from its *measured*
        outputs ``y[:n0]`` (``n0 = max(na, last input lag)``), the meaningful prediction
        for a held-out segment (see :mod:`hammerbound.timeseries`).
        """
        check_is_fitted(self, "bounds_")
        from ..data.iodata import IOData
        from ..timeseries import simulate_from_measured

        A, B = self._polys()
        if isinstance(X, IOData):
            return simulate_from_measured(A, B, X.u, X.y, self._n0())
        x = as_signal("X", X)
        return lfilter(B, A, x)

    def score(self, X, y=None, sample_weight=None):
        """R^2 of the central model's free-run simulation on a (held-out) segment.

        The simulation starts from the measured outputs of the segment's first ``n0 =
        max(na, last input lag)`` samples and runs on the input alone from there; R^2 is
        taken over the simulated samples ``t >= n0``. This is a multi-step (simulation)
        score, not a one-step-ahead one, and is meaningful for a ``TimeSeriesSplit`` test
        fold that starts mid-record. ``X`` may be an IOData (then ``y`` is None or
        ``X.y``): ``score(data) == r2_score(data.y[n0:], predict(data)[n0:])``.
        scikit-learn's scorers (``scoring="r2"``, ...) call :meth:`predict` and need
        ``y``: ``cross_val_score(est, data, data.y, scoring="r2", cv=TimeSeriesSplit())``.
        ``predict`` on a plain array simulates from rest, so ``r2_score(y, predict(u))``
        differs from ``score(u, y)`` by the initial transient.
        """
        check_is_fitted(self, "bounds_")
        from ..data.iodata import unpack
        from ..timeseries import segment_r2, simulate_from_measured

        X, y, _ = unpack(X, y, func="score")
        x, yy = as_signal("X", X), as_signal("y", y)
        if x.shape != yy.shape:
            raise DataValidationError("X and y must have the same length.")
        n0 = self._n0()
        if x.size <= n0 + 1:
            raise DataValidationError(
                f"the scored segment needs more than n0 + 1 = {n0 + 1} samples; got {x.size}.")
        A, B = self._polys()
        return segment_r2(yy, simulate_from_measured(A, B, x, yy, n0), n0, sample_weight)

    def one_step_envelope(self, X, y=None, input_bound=0.0, output_bound=None):
        """Guaranteed one-step-ahead band of the noise-free output ``w_t``.

        For every ``t >= max(na, last input lag)`` and every ``theta`` in :attr:`bounds_`, every past
        ``w_{t-i}`` in ``y_{t-i} +- deta`` and input ``x_{t-j}`` in ``X +- input_bound``,
        ``w_t = -sum a_i w_{t-i} + sum b_j x_{t-j}`` lies in ``[lower_t, upper_t]``
        (interval arithmetic, hence an outer bound). Earlier samples are NaN.

        ``X`` may be an :class:`~hammerbound.IOData` (then ``y`` is omitted).

        Returns
        -------
        OutputEnvelope
            ``lower``, ``upper`` of shape (N,) with the measured ``y`` and its bound; it
            unpacks as before: ``lower, upper = est.one_step_envelope(X, y)``.
        """
        from ..data.iodata import unpack

        check_is_fitted(self, "bounds_")
        X, y, _ = unpack(X, y, func="one_step_envelope")
        x = as_signal("X", X)
        yy = as_signal("y", y)
        if x.shape != yy.shape:
            raise DataValidationError("X and y must have the same length.")
        n = x.size
        deta = self._output_bound(n, output_bound)
        dx = as_bound("input_bound", input_bound, n, allow_zero=True)
        na = self.na
        lags = [int(j) for j in self._lags()]
        lo = np.full(n, np.nan)
        hi = np.full(n, np.nan)
        n0 = max(na, lags[-1])
        t = np.arange(n0, n)
        acc_lo = np.zeros(t.size)
        acc_hi = np.zeros(t.size)

        def add_product(pl, ph, vl, vh):
            # an unbounded end times 0 is 0 (the interval's numbers are real; a one-record
            # b_j the record does not bound is [-inf, inf]): not NaN
            with np.errstate(invalid="ignore"):
                c = np.stack([pl * vl, pl * vh, ph * vl, ph * vh])
            c = np.where(np.isnan(c), 0.0, c)
            return c.min(axis=0), c.max(axis=0)

        for i in range(1, na + 1):
            al, ah = self.bounds_[i - 1]
            wl = yy[t - i] - deta[t - i]
            wh = yy[t - i] + deta[t - i]
            pl, ph = add_product(-ah, -al, wl, wh)
            acc_lo += pl
            acc_hi += ph
        for k, j in enumerate(lags):
            bl, bh = self.bounds_[na + k]
            pl, ph = add_product(bl, bh, x[t - j] - dx[t - j], x[t - j] + dx[t - j])
            acc_lo += pl
            acc_hi += ph
        # outward rounding margin for the floating-point sums
        eps = 8 * np.finfo(float).eps * (np.abs(acc_lo) + np.abs(acc_hi) + 1)
        lo[t] = acc_lo - eps
        hi[t] = acc_hi + eps
        return OutputEnvelope(lo, hi, y=yy, output_bound=deta)
