"""Fitted views of the two blocks when they were bounded jointly (one-record path).

The identifier's two-stage path holds a fitted :class:`~hammerbound.BacklashSetEstimator`
(``backlash_``) and :class:`~hammerbound.LinearEIVSetEstimator` (``linear_``). The
one-record path bounds both blocks in one problem; these views give it the same
``backlash_`` / ``linear_`` interface -- intervals, central model, transfer function,
frequency envelope, uncertainty weight, one-step band, backlash inverse -- so the model set,
the compensator and the report work on it unchanged. Samples are drawn *jointly*
(:func:`joint_samples`): the linear block's feasible set depends on the backlash here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..data.validation import as_bound
from ..modelset.estimator import ModelSetMixin
from ..results import IntervalSet
from ..stage2.linear_model import LinearModelMixin
from ..systems.models import GAMMA_NAMES

__all__ = ["BacklashBoxView", "JointSamples", "LinearBlockView", "joint_samples"]


def require_bounded(what, names, bounds, advice):
    """Raise UnboundedSetError "no ``what``" naming the parameters whose interval is
    infinite (the one-record fit did not bound them), followed by ``advice``."""
    bad = [n for n, row in zip(names, bounds, strict=True) if not np.all(np.isfinite(row))]
    if bad:
        from ..exceptions import UnboundedSetError

        raise UnboundedSetError(f"no {what}: the record does not bound {', '.join(bad)} (see "
                                f"the NotIdentifiedWarning of fit){advice}")


class LinearBlockView(LinearModelMixin, ModelSetMixin):
    """The linear block's certified intervals from the one-record path (read-only)."""

    method = "one-record"

    def __init__(self, problem, bounds, infos, *, method, dt, names, units, time_unit,
                 sampler, theta_box=None, assumptions=()):
        self.na, self.nb, self.nk = problem.na, problem.nb, problem.nk
        self.steady_state_gain = float(problem.gain)
        self.method = method
        self.problem_ = problem
        self.intervals_ = IntervalSet(problem.theta_names, bounds, infos=infos, method=method)
        self.bounds_ = np.array(self.intervals_.bounds)
        self.center_ = self.intervals_.center
        self.radius_ = self.intervals_.radius
        self.param_names_ = self.intervals_.param_names
        self.bound_info_ = self.intervals_.infos
        self.box_limited_ = ()
        self.dt_ = dt
        self.signal_names_ = names
        self.signal_units_ = units
        self.time_unit_ = time_unit
        self._sampler = sampler
        self.theta_box = theta_box
        self.assumptions_ = tuple(assumptions)

    def __sklearn_tags__(self):
        """scikit-learn's tags (its validation helpers read them): a fitted regressor."""
        from sklearn.utils import Tags, TargetTags

        return Tags(estimator_type="regressor", target_tags=TargetTags(required=True))

    def __sklearn_is_fitted__(self) -> bool:
        return True

    def fit(self, *args, **kwargs):
        """A view is not refitted: fit the identifier that holds it."""
        raise TypeError("this is a read-only view of an identifier's one-record fit; "
                        "fit the HammersteinBacklashIdentifier instead.")

    def _nk(self) -> int:
        return int(self.nk)

    def _lags(self) -> np.ndarray:
        return np.asarray(self.problem_.b_lags)

    def _output_bound(self, n, output_bound=None):
        if output_bound is not None:
            return as_bound("output_bound", output_bound, n)
        return as_bound("output_bound", float(np.max(self.problem_.deta)), n)

    def summary(self) -> str:
        """Text summary: the linear block's intervals of the joint (one-record) fit and the
        assumptions the fit rests on (those of the whole identifier)."""
        pr = self.problem_
        from ..tables import dt_text

        head = (f"linear block of a one-record fit: method {self.method}, na={pr.na} "
                f"nb={pr.nb} nk={pr.nk}, N = {pr.N}, "
                f"dt = {dt_text(self.dt_, self.time_unit_)}, "
                f"gain B(1)/A(1) = {self.steady_state_gain:g}")
        return self.intervals_.summary(title=head, assumptions=self.assumptions_)

    def _require_bounded(self, what):
        """Refuse ``what`` (it needs every interval finite) when the record left an
        interval of the linear block unbounded (a ``b_j`` at the default box)."""
        require_bounded(what, self.param_names_, self.bounds_,
                        ". Identify from a record that moves the input more often, or with "
                        "lower na, nb if the plant may be of lower order, or give a "
                        "theta_box from what you know.")

    def _polys(self, theta=None):
        """The central (or given ``theta``) polynomials; no central model when an
        interval of the linear block is infinite (the record did not bound it)."""
        if theta is None:
            self._require_bounded("central model of the linear block "
                                  "(to_transfer_function(theta=...) gives one of your choice)")
        return super()._polys(theta)

    def frequency_response_bounds(self, omega=None, dt=None, *, on_gain_plane=False):
        self._require_bounded("frequency envelope of the linear block")
        return super().frequency_response_bounds(omega, dt, on_gain_plane=on_gain_plane)

    frequency_response_bounds.__doc__ = ModelSetMixin.frequency_response_bounds.__doc__

    def uncertainty_weight(self, *args, **kwargs):
        self._require_bounded("uncertainty weight of the linear block")
        return super().uncertainty_weight(*args, **kwargs)

    uncertainty_weight.__doc__ = ModelSetMixin.uncertainty_weight.__doc__

    def sample(self, n, random_state=None, **_):
        """``n`` certified points of the joint set (:class:`JointSamples`: ``theta`` rows,
        each with the backlash ``gamma`` that makes it feasible)."""
        return self._sampler(n, random_state)


class BacklashBoxView:
    """The backlash's certified intervals from the one-record path (read-only)."""

    def __init__(self, bounds, input_range, sampler):
        self.intervals_ = IntervalSet(GAMMA_NAMES, bounds, method="one-record")
        self.gamma_bounds_ = np.array(self.intervals_.bounds)
        self.gamma_center_ = self.intervals_.center
        self.input_range_ = tuple(float(v) for v in input_range)
        self._sampler = sampler

    def _vertices_mb(self, m, c):
        """Corners of the box's image in ``(m, beta = m c)``: the convex hull of the set of
        every ``(m, m c)`` of the box (its extremes of anything linear in ``(m, beta)``)."""
        return np.array([[mm, mm * cc] for mm in m for cc in c])

    def inverse(self, v_range=None, x0=0.0):
        """Backlash-inverse compensator with a guaranteed error over the whole box (see
        :meth:`hammerbound.BacklashSetEstimator.inverse`)."""
        from ..modelset.compensation import build_inverse_from

        g = self.gamma_bounds_
        if not np.all(np.isfinite(g)):
            from ..exceptions import UnboundedSetError

            raise UnboundedSetError(
                "the record does not bound every backlash parameter, so no compensator "
                "error can be guaranteed; identify from a record that reverses by more "
                "than the dead band.")
        return build_inverse_from(self.gamma_center_, self._vertices_mb(g[0], g[1]),
                                  self._vertices_mb(g[2], g[3]), self.input_range_,
                                  v_range=v_range, x0=x0)

    def sample(self, n, random_state=None):
        """``n`` certified points of the joint set (:class:`JointSamples`: ``gamma`` rows,
        each with the linear block ``theta`` that makes it feasible)."""
        return self._sampler(n, random_state)


@dataclass(frozen=True)
class JointSamples:
    """Certified points of the one-record set, each with its witness: the fields of
    :class:`~hammerbound.modelset.sampling.CertifiedSamples` (new-user trial 20: the model
    set's docs read ``max_violation``, ``tol`` and ``eta``, which a one-record fit's samples
    lacked), and the backlash that goes with each row.

    Attributes
    ----------
    theta : ndarray (n, p)
        The linear block, columns in :attr:`param_names` order.
    param_names : tuple of str
    gamma : ndarray (n, 4)
        The backlash ``(m_l, c_l, m_r, c_r)`` of each row.
    z0 : ndarray (n,)
        The first inner value ``x_0`` (in the band ``[R_0, L_0]``).
    x : ndarray (n, N)
        The inner signal: the play operator from ``z0`` (the witness's backlash output).
    eta : ndarray (n, N)
        Witness output errors (``|eta| <= output_bound``).
    dx : ndarray (n, 0)
        No input errors: the input of a one-record fit is known exactly.
    max_violation : ndarray (n,)
        Largest equation residual at the witness over that equation's terms; ``<= tol``.
    max_rel_violation : ndarray (n,)
        The same over its tolerance (``max_violation / tol``, ``<= 1``).
    gain_residual : ndarray (n,)
        ``|B(1) - g A(1)|`` (``g = 1``: the unit gain (22.8)).
    tol : float
        The relative feasibility tolerance (``FEASIBILITY_RTOL``).
    n_tries : int
        Random starts taken to the set (the seeds not counted).
    """

    theta: np.ndarray
    param_names: tuple
    gamma: np.ndarray
    z0: np.ndarray
    x: np.ndarray
    eta: np.ndarray
    dx: np.ndarray
    max_violation: np.ndarray
    max_rel_violation: np.ndarray
    gain_residual: np.ndarray
    tol: float
    n_tries: int = 0

    @classmethod
    def of(cls, witnesses, param_names, na, gain=1.0, n_tries=0):
        from ..tolerances import FEASIBILITY_RTOL

        theta = np.array([w.theta for w in witnesses])
        rel = np.array([w.max_rel_violation for w in witnesses])
        a_one = gain * (1.0 + np.sum(theta[:, :na], axis=1))
        return cls(theta, tuple(param_names), np.array([w.gamma for w in witnesses]),
                   np.array([w.z0 for w in witnesses]), np.array([w.x for w in witnesses]),
                   np.array([w.eta for w in witnesses]), np.zeros((len(witnesses), 0)),
                   rel * FEASIBILITY_RTOL, rel,
                   np.abs(np.sum(theta[:, na:], axis=1) - a_one), FEASIBILITY_RTOL, n_tries)

    def __len__(self):
        return self.theta.shape[0]


def joint_samples(problem, box, seeds, n, random_state=None, max_tries=None, progress=False):
    """``n`` verified points of the one-record set inside ``box``.

    Random points of the box (and the seeds, the interval ends' witnesses) are taken to the
    set by the local search (:func:`hammerbound.joint.local.restore`); only points that
    :func:`hammerbound.joint.verify_point` accepts are kept. Spread over the set, neither
    uniform nor independent. Each random start costs a local search (about a second at
    N = 350, new-user trial 20); ``progress`` counts them on stderr.

    Raises
    ------
    SolverError
        Fewer than ``n`` points were verified within ``max_tries`` attempts.
    """
    from ..exceptions import SolverError
    from ..joint.local import restore
    from ..joint.progress import PROGRESS_EVERY, RecordProgress

    rng = np.random.default_rng(random_state)
    out = [w for w in seeds if w is not None][:n]
    tries, max_tries = 0, (max_tries or 20 * n)
    bar = RecordProgress(progress)
    bar.start("sample", n - len(out), every=PROGRESS_EVERY)
    while len(out) < n and tries < max_tries:
        tries += 1
        v = box[:, 0] + (box[:, 1] - box[:, 0]) * rng.random(box.shape[0])
        w = restore(problem, v, box, max_iter=12)
        if w is not None:
            out.append(w)
            bar.done(f"{tries} start(s)")
    bar.close()
    if len(out) < n:
        raise SolverError(f"only {len(out)} of {n} points of the one-record set were "
                          f"verified in {tries} attempts; ask for fewer samples.")
    return JointSamples.of(out, problem.theta_names, problem.na, float(problem.gain), tries)
