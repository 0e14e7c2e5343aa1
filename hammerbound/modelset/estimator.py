"""The fitted linear block's guaranteed model set (issue 16): certified samples, transfer
functions, frequency-response envelope and uncertainty weight.

:class:`ModelSetMixin` is mixed into :class:`~hammerbound.LinearEIVSetEstimator`; the work
is done in :mod:`hammerbound.modelset`.
"""

from __future__ import annotations

import numpy as np
from sklearn.utils.validation import check_is_fitted

from ..exceptions import ParameterValidationError
from .frequency import check_omega
from .gain_plane import plane_centre

__all__ = ["ModelSetMixin"]


class ModelSetMixin:
    """Model-set views of a fitted :class:`~hammerbound.LinearEIVSetEstimator`."""

    def _b_lags(self):
        return [int(j) for j in self._lags()]

    def _fitted_dt(self):
        """Sampling time of the fitted data, or None when it was not given."""
        return getattr(self, "dt_", None)

    def _frequency_axis(self, dt):
        """``(period, unit)``: ``z = e^{j omega period}`` and the unit of ``omega``.

        ``dt`` if given, else that of the fitted data; when neither is known (``None`` or
        python-control's ``True``) the period is one *sample* and ``omega`` is in
        rad/sample -- said so by the unit, never passed off as seconds."""
        if dt is None or dt is True:
            dt = self._fitted_dt()
        if dt is None or dt is True:
            return 1.0, "rad/sample"
        check_omega(None, dt)  # a finite number > 0
        return float(dt), f"rad/{getattr(self, 'time_unit_', '') or 's'}"

    def _labels(self, unit):
        return {"frequency_unit": unit,
                "signal_names": tuple(getattr(self, "signal_names_", ("u", "y"))),
                "signal_units": tuple(getattr(self, "signal_units_", ("", "")))}

    def sample(self, n, random_state=None, *, thin=1, seeds=None):
        """``n`` parameter vectors of the feasible set (22.34), each *certified* feasible.

        Hit-and-run with shrinkage inside :attr:`bounds_` (on the gain hyperplane when
        ``steady_state_gain`` is set), seeded at the exact method's witnesses and the
        centre; every sample carries its witness noise sequences. The samples are spread
        over the set but neither uniform nor independent, and a nonconvex set's
        components without a seed are missed: see :mod:`hammerbound.modelset.sampling`.

        Parameters
        ----------
        n : int
        random_state : None, int or numpy Generator
        thin : int, default 1
            Record one move out of ``thin``.
        seeds : array of shape (k, p), optional
            Extra starting points (each is verified first).

        Returns
        -------
        CertifiedSamples
            ``theta`` (n, p) with the certificates ``eta``, ``dx``, ``max_violation``.

        Raises
        ------
        SolverError
            No feasible starting point (fit with ``method="exact"`` or pass ``seeds``).
        """
        check_is_fitted(self, "bounds_")
        from .sampling import sample_eiv

        starts = [] if seeds is None else [np.asarray(s, float) for s in np.atleast_2d(seeds)]
        starts += [i.witness for i in self.bound_info_ if getattr(i, "witness", None) is not None]
        starts.append(self.center_)
        return sample_eiv(self.problem_, self.bounds_, n, seeds=starts,
                          random_state=random_state, thin=thin, param_names=self.param_names_)

    def to_transfer_functions(self, n, dt=None, random_state=None):
        """``n`` certified members of the set as discrete ``control.TransferFunction`` (period
        ``dt``; default as :meth:`to_transfer_function`)."""
        self.to_transfer_function(dt=dt)  # a wrong dt is refused before the sampling
        smp = self.sample(n, random_state=random_state)
        return [self.to_transfer_function(dt=dt, theta=th) for th in smp.theta]

    def frequency_response_bounds(self, omega=None, dt=None, *, on_gain_plane=False):
        """Guaranteed magnitude/phase bounds of every model in :attr:`bounds_`.

        Exact over the orthotope at each frequency (zonotope value sets of ``A`` and
        ``B``), with guaranteed bounds between grid frequencies as well; see
        :mod:`hammerbound.modelset.frequency`.

        Parameters
        ----------
        omega : array, optional
            Frequencies in rad/s (rad per unit of ``dt``), or in rad/sample when no
            sampling time is known. Strictly increasing, >= 0. Default: 512 log-spaced
            points up to the Nyquist frequency ``pi/dt``.
        dt : float or None, default None
            Sampling time of the data (``z = e^{j omega dt}``); default: that of the fitted
            :class:`~hammerbound.IOData` (:attr:`dt_`). When neither is known, ``omega``
            is in rad/sample (Nyquist ``pi``) and the envelope says so in
            ``frequency_unit`` and its plot.
        on_gain_plane : bool, default False
            Tighten the magnitude bounds to the orthotope *intersected with the gain
            equality* (22.8) (every feasible model satisfies it; the box alone cannot
            express it, which makes the plain envelope wide at low frequencies). The
            bounds then no longer cover box points off that hyperplane. Needs
            ``steady_state_gain``.

        Returns
        -------
        FrequencyEnvelope
        """
        check_is_fitted(self, "bounds_")
        from dataclasses import replace

        from .frequency import frequency_envelope

        dt, unit = self._frequency_axis(dt)
        w = check_omega(omega, dt, unit)
        gain = self._plane_gain(on_gain_plane)
        env = frequency_envelope(self.bounds_, self.na, self._b_lags(), w, dt=dt, gain=gain)
        return replace(env, **self._labels(unit))

    def uncertainty_weight(self, kind="multiplicative", order=2, dt=None, *, margin=0.05,
                           omega=None, n_grid=8192, on_gain_plane=False):
        """A stable, minimum-phase weight ``W`` bounding the set around the central model.

        ``kind="multiplicative"``: ``|G/G0 - 1| <= |W|``; ``"additive"``: ``|G - G0| <= |W|``,
        for every ``theta`` in :attr:`bounds_` and *every* frequency (proved on a grid of
        ``n_grid`` points over ``[0, pi/dt]`` with Lipschitz bounds in between; the proof is
        returned in ``.certificate``). ``order`` is the largest order tried: the certified
        weight of order ``0 .. order`` with the smallest mean over-bound (``.excess_db``)
        is returned. ``dt`` defaults to the sampling time of the fitted
        :class:`~hammerbound.IOData` (:attr:`dt_`); when neither is known the weight and
        ``.central`` get python-control's ``dt=True`` (sampling time not given) and
        ``.omega`` is in rad/sample (``.frequency_unit``). See
        :mod:`hammerbound.modelset.uncertainty`.

        ``on_gain_plane=True`` bounds only the models on the gain plane (22.8) -- every
        feasible model satisfies it, the box alone does not express it -- around the box
        centre moved onto that plane (``.central``; its last ``b`` is set by the gain).
        All these models have the same steady-state gain, so the bound vanishes at
        ``omega = 0`` and a controller with integral action can pass a robust-stability
        test that the box's weight (wide at low frequencies) makes impossible. Needs
        ``steady_state_gain``.

        Returns
        -------
        UncertaintyWeight
            ``.W`` (control.TransferFunction), ``.central`` (G0), ``.certificate``.

        Raises
        ------
        UnboundedSetError
            Some ``A`` in the box vanishes on the unit circle: no finite weight exists.
        """
        check_is_fitted(self, "bounds_")
        from .uncertainty import KINDS, fit_weight

        if kind not in KINDS:
            raise ParameterValidationError(f"kind must be one of {KINDS}; got {kind!r}.")
        dt, unit = self._frequency_axis(dt)
        tf_dt = True if unit == "rad/sample" else dt
        w = None if omega is None else check_omega(omega, dt, unit)
        gain = self._plane_gain(on_gain_plane)
        theta0 = None if gain is None else plane_centre(self.bounds_, self.na, gain)
        return fit_weight(self.bounds_, self.na, self._b_lags(),
                          self.to_transfer_function(tf_dt, theta=theta0), dt=dt, kind=kind,
                          order=order, omega=w, margin=margin, n_grid=n_grid, tf_dt=tf_dt,
                          frequency_unit=unit, gain=gain)

    def _plane_gain(self, on_gain_plane):
        """The steady-state gain when ``on_gain_plane`` (checked), else None."""
        from ..data.validation import as_flag

        if not as_flag("on_gain_plane", on_gain_plane):
            return None
        if self.steady_state_gain is None:
            raise ParameterValidationError(
                "on_gain_plane=True needs a gain constraint: fit with steady_state_gain set "
                "(or use the plain bound over the box, on_gain_plane=False)."
            )
        return float(self.steady_state_gain)
