"""One ordinary record of a backlash-Hammerstein system as one bounded-error problem.

With ``x = backlash(u; m_l, c_l, m_r, c_r, z0)`` (the play operator of :mod:`.modes` from
``x_0 = z0``) and the unit-gain linear block (22.8), every sample ``t >= n0`` of the record
gives the equation (22.3)-(22.5)::

    (y_t - eta_t) + sum_i a_i (y_{t-i} - eta_{t-i}) = sum_j b_j x_{t-j},   |eta_t| <= deta_t

The feasible set is every ``(theta, gamma, z0)`` for which some noise sequence satisfies all
equations, inside an a priori box (:class:`RecordProblem.box`) that the user gives or that
is printed as an assumption. Optional steady-state points ``(u_i, y_i)`` (square-wave
holds, section 22.3) add ``|y_i - m_r (u_i - c_r)| <= deta_i`` (positive half-wave) or the
left line (negative half-wave).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..exceptions import DataValidationError, ParameterValidationError, SolverError
from ..relaxations.problem import EIVProblem, b_lags_of, check_theta
from ..systems.models import GAMMA_NAMES
from .modes import play

__all__ = ["GAMMA_NAMES", "RecordProblem", "Witness", "verify_point"]


@dataclass(frozen=True)
class RecordProblem:
    """Data, structure and a priori box of the one-record problem.

    Parameters
    ----------
    u, y : ndarray of shape (N,)
        The record (exact input, measured output).
    deta : ndarray of shape (N,)
        Output error bounds.
    na, nb, nk : int
        Orders and delay of the linear block (as :class:`~hammerbound.relaxations.EIVProblem`).
    box : ndarray of shape (p + 5, 2)
        A priori box of ``[theta (p), m_l, c_l, m_r, c_r, z0]``; every bound is inside it.
    steady : tuple (u_ss, y_ss, deta_ss) or None
        Steady-state points (section 22.3).
    gain : float
        Steady-state gain of the linear block (22.8), 1 by default.
    """

    u: np.ndarray
    y: np.ndarray
    deta: np.ndarray
    na: int
    nb: int
    nk: int
    box: np.ndarray
    steady: tuple | None = None
    gain: float = 1.0
    b_lags: np.ndarray = field(init=False)

    def __post_init__(self):
        u = np.asarray(self.u, dtype=float)
        y = np.asarray(self.y, dtype=float)
        deta = np.broadcast_to(np.asarray(self.deta, dtype=float), y.shape).copy()
        if u.shape != y.shape or u.ndim != 1:
            raise DataValidationError("u and y must be 1-D arrays of the same length.")
        lags = b_lags_of(self.nb, self.nk)
        object.__setattr__(self, "u", u)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "deta", deta)
        object.__setattr__(self, "b_lags", lags)
        box = np.asarray(self.box, dtype=float)
        if box.shape != (self.p + 5, 2) or not np.all(np.isfinite(box)) \
                or np.any(box[:, 0] > box[:, 1]):
            raise ParameterValidationError(
                f"the a priori box must be a finite array of shape ({self.p + 5}, 2) with "
                "lower <= upper.")
        object.__setattr__(self, "box", box)

    # ---- structure -------------------------------------------------------------------
    @property
    def N(self) -> int:  # noqa: N802 - identification notation
        return self.y.size

    @property
    def p(self) -> int:
        return self.na + b_lags_of(self.nb, self.nk).size

    @property
    def n0(self) -> int:
        return max(self.na, int(b_lags_of(self.nb, self.nk)[-1]))

    @property
    def theta_names(self) -> list[str]:
        return [f"a{i}" for i in range(1, self.na + 1)] + [f"b{j}" for j in self.b_lags]

    @property
    def names(self) -> list[str]:
        """Names of the rows of :attr:`box`: theta, the backlash and the first inner value."""
        return [*self.theta_names, *GAMMA_NAMES, "z0"]

    def eiv_problem(self, x) -> EIVProblem:
        """The stage-2 problem (22.34) with the inner signal ``x`` known exactly."""
        return EIVProblem(self.y, x, 0.0, self.deta, self.na, self.nb,
                          steady_state_gain=self.gain,
                          theta_box=self.box[: self.p], nk=self.nk)


@dataclass(frozen=True)
class Witness:
    """A verified point of the one-record set: parameters, first inner value, inner signal
    and the noise sequence that explains the record (every ``|eta_t| <= deta_t``)."""

    theta: np.ndarray
    gamma: np.ndarray
    z0: float
    x: np.ndarray
    eta: np.ndarray
    max_rel_violation: float

    @property
    def vector(self) -> np.ndarray:
        """``[theta, m_l, c_l, m_r, c_r, z0]`` (the rows of the problem's box)."""
        return np.concatenate([self.theta, self.gamma, [self.z0]])


def _well_posed(problem: RecordProblem, gamma) -> bool:
    ml, cl, mr, cr = gamma
    u = problem.u
    return bool(np.all(ml * (u + cl) >= mr * (u - cr)))


def _steady_ok(problem: RecordProblem, gamma, tol) -> bool:
    if problem.steady is None:
        return True
    ml, cl, mr, cr = gamma
    us, ys, ds = problem.steady
    pred = np.where(us > 0, mr * (us - cr), ml * (us + cl))
    return bool(np.all(np.abs(ys - pred) <= ds * (1 + tol) + tol * np.abs(ys)))


def verify_point(problem: RecordProblem, vector, tol=None) -> Witness | None:
    """Is ``[theta, gamma, z0]`` in the one-record set? The witness if so, else None.

    Independent of every relaxation: the inner signal is simulated by the play operator
    from ``x_0 = z0`` (which must lie in the band ``[R_0, L_0]``), the backlash must be
    well-posed on the record and inside the a priori box, and the linear block is then
    judged by :func:`~hammerbound.relaxations.check_theta` (a noise sequence within the
    bounds, per-equation tolerance of the tolerance policy).
    """
    v = np.asarray(vector, dtype=float)
    box = problem.box
    if v.shape != (box.shape[0],) or not np.all(np.isfinite(v)):
        return None
    if np.any(v < box[:, 0]) or np.any(v > box[:, 1]):
        return None
    p = problem.p
    theta, gamma, z0 = v[:p], v[p : p + 4], float(v[p + 4])
    ml, cl, mr, cr = gamma
    u0 = problem.u[0]
    if ml <= 0 or mr <= 0 or not (mr * (u0 - cr) <= z0 <= ml * (u0 + cl)):
        return None
    if not _well_posed(problem, gamma):
        return None
    from ..tolerances import FEASIBILITY_RTOL

    tol = FEASIBILITY_RTOL if tol is None else tol
    if not _steady_ok(problem, gamma, tol):
        return None
    x = play(problem.u, ml, cl, mr, cr, z0)
    try:
        chk = check_theta(problem.eiv_problem(x), theta, tol)
    except SolverError:  # the LP could not be decided: the point is not verified
        return None
    if not chk.feasible:
        return None
    return Witness(theta.copy(), np.asarray(gamma, dtype=float).copy(), z0, x, chk.eta,
                   chk.max_rel_violation)
