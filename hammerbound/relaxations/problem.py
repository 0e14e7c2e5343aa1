"""The bounded errors-in-variables (EIV) problem of stage 2, eq. (22.34).

Every stage-2 method (polytopic LP, sparse moment relaxation, exact branch-and-bound)
works on one :class:`EIVProblem`. Conventions (0-based samples ``t = 0 .. N-1``):

* parameters ``theta = [a_1 .. a_na, b_j for j in b_lags]``; the input delay ``nk`` (the
  first lag of ``B``, MATLAB's ``nk``) defaults to ``1``. ``nb`` counts
  the chapter's coefficients ``b_1 .. b_nb``: ``nk = 1`` gives lags ``1 .. nb`` (the
  chapter), ``nk = 0`` adds the direct term (lags ``0 .. nb``) and
  ``nk > 1`` delays them (lags ``nk .. nk + nb - 1``, MATLAB's ``[na nb nk]``);
* for every ``t`` in :attr:`EIVProblem.equation_times` (``t >= n0 = max(na, last lag)``)::

      (y_t - eta_t) + sum_i a_i (y_{t-i} - eta_{t-i})
          = sum_j b_j (x_t-j - dx_var[g(t-j)])                 (22.34)

  with ``|eta_t| <= deta_t`` (``output_bound``) and ``|dx_var[k]| <= dx_group[k]`` (the
  ``input_bound`` of the group's samples);
* ``g`` is the *input group* map: sample ``t`` uses input-error variable ``groups[t]``.
  Independent per-sample errors (the chapter) use ``groups = arange(N)``. The two-level
  inner signal (Result 1: a PRBS through the backlash takes exactly two unknown values)
  uses ``groups[t] = 0`` where ``u_t = +u*`` and ``1`` where ``u_t = -u*``: every sample at a
  level shares *one* unknown value;
* optional steady-state gain equality (22.8): ``sum_j b_j = g * (1 + sum_i a_i)`` with
  ``g = steady_state_gain``;
* an a priori box ``theta_box`` (p x 2) that every method may use; the feasible set is
  defined *inside* that box. Default: ``|a_i| <= binom(na, i)`` (which every asymptotically
  stable A(q^-1) satisfies, assumption A1) and ``|b_j| <= b_bound``.

The nominal residual of equation t is ``r_t(theta) = y_t + phi_t . theta`` with
``phi_t = [y_{t-1} .. y_{t-na}, -x_{t-j0} .. -x_{t-nb}]``, so that the equation reads::

    r_t(theta) = eta_t + sum_i a_i eta_{t-i} - sum_j b_j dx_var[g(t-j)]
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..data.validation import as_bound, as_signal
from ..exceptions import DataValidationError, ParameterValidationError
from .theta_box import (  # noqa: F401 - re-exported
    DEFAULT_B_BOUND,
    b_lags_of,
    default_theta_box,
    given_rows,
    given_rows_text,
    resolve_theta_box,
    theta_names,
)


def _deprecated(old: str, new: str) -> None:
    from .._compat import warn_renamed

    warn_renamed(old, new, stacklevel=3)


def _as_1d(name, v, n=None, *, positive=False, nonneg=False):
    """A signal (shape (N,) or (N, 1)) or, with ``positive``/``nonneg``, a scalar or
    per-sample bound, validated by :mod:`hammerbound.data.validation`."""
    if positive or nonneg:
        return as_bound(name, v, n, allow_zero=nonneg, shape_error=DataValidationError,
                        error=DataValidationError, sign_error=ParameterValidationError)
    a = as_signal(name, v)
    if n is not None and a.shape[0] != n:
        raise DataValidationError(f"{name} has length {a.shape[0]} but the data have length {n}.")
    return a


_RENAMED = {"dx": "input_bound", "deta": "output_bound", "gain": "steady_state_gain"}


@dataclass(frozen=True, init=False)
class EIVProblem:
    """Data and structure of the EIV feasible set (22.34). See the module docstring.

    Parameters
    ----------
    y, x : array of shape (N,)
        Measured output and central input ``x^c``.
    input_bound : float or array of shape (N,)
        ``|x_t - x^c_t| <= input_bound_t`` (``Delta x``, 22.31); 0: exact input.
    output_bound : float or array of shape (N,)
        ``|eta_t| <= output_bound_t`` (``Delta eta``, 22.5), > 0.
    na, nb : int
        Orders of ``A`` and ``B`` (``nb`` counts the chapter's ``b_1 .. b_nb``).
    nk : int, default 1
        Input delay: first lag of ``B`` (0 adds the direct term ``b_0``).
    steady_state_gain : float or None, default None
        ``B(1) / A(1) = steady_state_gain`` (22.8) as an equality; None: no gain
        constraint (the stage-2 estimators always pass it explicitly).
    groups, theta_box
        Input-error groups and a priori box (see the module docstring).

    The chapter's notation is kept as read-only aliases for the relaxations:
    ``deta`` (= ``output_bound``), ``dx`` (= ``input_bound``), ``gain``
    (= ``steady_state_gain``) and ``b0`` (``nk == 0``). The keywords ``dx=``, ``deta=``,
    ``gain=`` and ``b0=`` are deprecated (removed in 0.3.0).
    """

    y: np.ndarray
    x: np.ndarray
    input_bound: np.ndarray
    output_bound: np.ndarray
    na: int
    nb: int
    nk: int
    steady_state_gain: float | None
    groups: np.ndarray
    theta_box: np.ndarray
    # derived
    n_groups: int = field(init=False)
    dx_group: np.ndarray = field(init=False)

    def __init__(self, y, x, input_bound=None, output_bound=None, na=None, nb=None,
                 b0=None, steady_state_gain=None, groups=None, theta_box=None, nk=None,
                 **old):
        new = {"input_bound": input_bound, "output_bound": output_bound,
               "steady_state_gain": steady_state_gain}
        for key, val in old.items():
            if key not in _RENAMED:
                raise TypeError(f"EIVProblem() got an unexpected keyword argument {key!r}")
            _deprecated(f"EIVProblem({key}=...)", f"{_RENAMED[key]}=...")
            if new[_RENAMED[key]] is not None:
                raise ParameterValidationError(
                    f"EIVProblem got both {key}= and {_RENAMED[key]}= (the same bound); pass "
                    f"only {_RENAMED[key]}=.")
            new[_RENAMED[key]] = val
        if b0 is not None:
            _deprecated("EIVProblem(b0=...)", "nk=0 (direct term) or nk=1")
        for name in ("input_bound", "output_bound"):
            if new[name] is None:
                raise ParameterValidationError(
                    f"EIVProblem needs {name} (the bound every interval rests on; no default): "
                    f"e.g. EIVProblem(y, x, input_bound=0.0, output_bound=0.05, na=2, nb=2).")
        if na is None or nb is None:
            raise ParameterValidationError("EIVProblem needs the orders na and nb.")
        self._setup(y, x, new["input_bound"], new["output_bound"], na, nb, bool(b0), nk,
                    new["steady_state_gain"], groups, theta_box)

    # chapter notation (22.34), read-only: the relaxations' internals use it
    @property
    def deta(self) -> np.ndarray:
        """``Delta eta_t``: same as :attr:`output_bound`."""
        return self.output_bound

    @property
    def dx(self) -> np.ndarray:
        """``Delta x_t``: same as :attr:`input_bound`."""
        return self.input_bound

    @property
    def gain(self) -> float | None:
        """Same as :attr:`steady_state_gain`."""
        return self.steady_state_gain

    @property
    def b0(self) -> bool:
        """Whether ``B`` has the direct term ``b_0`` (``nk == 0``)."""
        return self.nk == 0

    def _setup(self, y, x, dx, deta, na, nb, b0, nk, gain, groups, theta_box):
        y = _as_1d("y", y)
        n = y.shape[0]
        x = _as_1d("x", x, n)
        dx = _as_1d("input_bound", dx, n, nonneg=True)
        deta = _as_1d("output_bound", deta, n, positive=True)
        na, nb = int(na), int(nb)
        nk_given = nk
        nk = (0 if b0 else 1) if nk is None else int(nk)
        if nk_given is not None and b0 and nk != 0:
            raise ParameterValidationError(
                f"b0=True means nk=0 (a direct term); got nk={nk}. Pass only nk."
            )
        lags = b_lags_of(max(nb, 0), max(nk, 0))
        if na < 0 or nb < 0 or nk < 0 or lags.size == 0:
            raise ParameterValidationError(
                f"orders must satisfy na >= 0, nb >= 0, nk >= 0 and B must have a coefficient; "
                f"got na={na}, nb={nb}, nk={nk}."
            )
        n0 = max(na, int(lags[-1]))
        if n - n0 < 1:
            raise DataValidationError(
                f"need more than max(na, last input lag) = {n0} samples to write one "
                f"equation; got {n}."
            )
        if groups is None:
            groups = np.arange(n)
        else:
            groups = np.asarray(groups)
            if groups.shape != (n,) or not np.issubdtype(groups.dtype, np.integer):
                raise DataValidationError(
                    f"the input groups (input_groups= of LinearEIVSetEstimator.fit, groups= "
                    f"here) must be an integer array of shape (N,) = ({n},), one group "
                    f"label per sample; got shape {groups.shape} of dtype {groups.dtype}.")
            if groups.min() < 0:
                raise DataValidationError(
                    "the input groups (input_groups= of LinearEIVSetEstimator.fit) must be "
                    "non-negative integers.")
        # compress group labels to 0..K-1 and check consistency of x / dx inside a group
        labels, groups = np.unique(groups, return_inverse=True)
        k = labels.shape[0]
        dx_group = np.zeros(k)
        x_group = np.zeros(k)
        np.maximum.at(dx_group, groups, dx)
        x_group[groups] = x
        if np.any(np.abs(x_group[groups] - x) > 1e-12 * (1 + np.abs(x))) or np.any(
            np.abs(dx_group[groups] - dx) > 1e-12 * (1 + dx)
        ):
            raise DataValidationError(
                "samples that share an input-error group must have equal x and input_bound."
            )
        box = resolve_theta_box(theta_box, na, nb, nk)
        if gain is not None and (not np.isfinite(gain) or gain == 0):
            raise ParameterValidationError(
                "steady_state_gain must be a finite non-zero number (assumption A2) or None."
            )
        for name, val in (("y", y), ("x", x), ("input_bound", dx), ("output_bound", deta),
                          ("groups", groups), ("na", na), ("nb", nb), ("nk", nk),
                          ("steady_state_gain", None if gain is None else float(gain)),
                          ("theta_box", box), ("n_groups", k), ("dx_group", dx_group)):
            object.__setattr__(self, name, val)

    # ---- structure -------------------------------------------------------------------
    @property
    def N(self) -> int:  # noqa: N802 - chapter notation
        return self.y.shape[0]

    @property
    def p(self) -> int:
        return self.na + self.b_lags.size

    @property
    def j0(self) -> int:
        """First lag of ``B`` (the input delay ``nk``)."""
        return self.nk

    @property
    def b_lags(self) -> np.ndarray:
        return b_lags_of(self.nb, self.nk)

    @property
    def n0(self) -> int:
        return max(self.na, int(self.b_lags[-1]))

    @property
    def equation_times(self) -> np.ndarray:
        return np.arange(self.n0, self.N)

    @property
    def has_input_errors(self) -> bool:
        """Whether any input error bound is nonzero (False: an output-error record, where
        the equations are linear in ``b`` at fixed ``a``)."""
        return bool(np.any(self.dx_group > 0))

    @property
    def param_names(self) -> list[str]:
        return [f"a{i}" for i in range(1, self.na + 1)] + [f"b{j}" for j in self.b_lags]

    def regressors(self) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(Phi, y_t)`` with ``r_t(theta) = y_t + Phi[t] @ theta`` for every equation."""
        t = self.equation_times
        cols = [self.y[t - i] for i in range(1, self.na + 1)]
        cols += [-self.x[t - j] for j in self.b_lags]
        return np.column_stack(cols) if cols else np.zeros((t.size, 0)), self.y[t]

    def eta_index(self) -> np.ndarray:
        """``(n_eq, na+1)`` indices of ``eta_{t-i}``, ``i = 0..na`` for every equation."""
        t = self.equation_times
        return t[:, None] - np.arange(self.na + 1)[None, :]

    def dx_index(self) -> np.ndarray:
        """``(n_eq, n_b)`` input-error variable index ``g(t-j)`` for every equation and lag j."""
        t = self.equation_times
        return self.groups[t[:, None] - self.b_lags[None, :]]

    def gain_row(self) -> tuple[np.ndarray, float] | None:
        """The gain equality as ``(row, rhs)`` with ``row @ theta = rhs``, or None."""
        if self.gain is None:
            return None
        row = np.concatenate([-self.gain * np.ones(self.na), np.ones(self.b_lags.size)])
        return row, float(self.gain)

    def with_theta_box(self, box) -> EIVProblem:
        """Copy of the problem with another a priori box."""
        return EIVProblem(
            self.y, self.x, self.input_bound, self.output_bound, self.na, self.nb,
            steady_state_gain=self.steady_state_gain, groups=self.groups,
            theta_box=np.asarray(box, dtype=float), nk=self.nk,
        )

    def scaled(self, factor: float) -> EIVProblem:
        """Copy with ``y``, ``x`` and both error bounds multiplied by ``factor``.

        The feasible set in ``theta`` is the same (every equation of (22.34) is multiplied
        by ``factor``; the gain equality does not involve the data); the errors of a point
        scale by ``factor``. With a power of two (:func:`.units.unit_scale`) the copy is exact.
        """
        import dataclasses

        f = float(factor)
        return dataclasses.replace(self, y=self.y * f, x=self.x * f,
                                   input_bound=self.dx * f, output_bound=self.deta * f)

    def simulate_noise_free(self, theta) -> np.ndarray:
        """Residuals ``r_t(theta)`` of the nominal equations (zero iff the data fit exactly)."""
        phi, yt = self.regressors()
        return yt + phi @ np.asarray(theta, dtype=float)


@dataclass(frozen=True)
class FeasibilityCheck:
    """Result of :func:`check_theta`: is ``theta`` in the EIV set (22.34)?

    ``max_violation`` is the largest absolute equation residual of the witness,
    ``max_rel_violation`` the largest residual divided by that equation's tolerance
    (``<= 1`` for every accepted point).
    """

    feasible: bool
    max_violation: float
    eta: np.ndarray
    dx: np.ndarray
    gain_residual: float
    max_rel_violation: float = float("nan")


def equation_scale(problem: EIVProblem, theta) -> np.ndarray:
    """Magnitude of the terms of every equation of (22.34) at ``theta`` (shape (n_eq,)).

    ``|y_t| + sum_i |a_i| |y_{t-i}| + sum_j |b_j| |x_{t-j}|`` (the nominal residual) plus
    ``deta_t + sum_i |a_i| deta_{t-i} + sum_j |b_j| dx_{g(t-j)}`` (the largest error term):
    the scale the tolerance policy (:mod:`hammerbound.tolerances`) is relative to.
    """
    theta = np.abs(np.asarray(theta, dtype=float))
    phi, yt = problem.regressors()
    a, b = theta[: problem.na], theta[problem.na :]
    err = problem.deta[problem.eta_index()] @ np.concatenate([[1.0], a])
    if b.size:
        err = err + problem.dx_group[problem.dx_index()] @ b
    return np.abs(yt) + np.abs(phi) @ theta + err


def outward_problem(problem: EIVProblem, box) -> EIVProblem:
    """A copy of ``problem`` whose output-error bounds are relaxed outward (tolerance policy).

    Equation ``t`` of (22.34) holds ``eta_t`` with coefficient one, so widening
    ``|eta_t| <= deta_t`` by ``tau_t = FEASIBILITY_RTOL * equation_scale_t`` (the magnitudes
    of the equation's terms over ``box``) gives every equation a slack of ``tau_t``: the
    relaxed set contains the exact one and every point whose equations hold up to rounding.
    Used by the relaxations whose "empty" and bound certificates are exact for the data they
    are given (moment); the LP and McCormick relaxations relax their rows instead.
    """
    import dataclasses

    from ..tolerances import FEASIBILITY_RTOL

    box = np.asarray(box, dtype=float)
    thmax = np.max(np.abs(box), axis=1)
    if not np.all(np.isfinite(thmax)):
        thmax = np.where(np.isfinite(thmax), thmax, np.max(np.abs(problem.theta_box), axis=1))
    tau = FEASIBILITY_RTOL * equation_scale(problem, thmax)
    deta = problem.deta.copy()
    cur = problem.eta_index()[:, 0]
    deta[cur] = deta[cur] + tau
    return dataclasses.replace(problem, output_bound=deta)


def check_theta(problem: EIVProblem, theta, tol: float | None = None, *,
                witness=None) -> FeasibilityCheck:
    """Decide whether ``theta`` belongs to the EIV feasible set (22.34).

    At fixed theta the constraints are linear in (eta, dx), so this solves the LP
    ``min s  s.t. |r_t(theta) - eta_t - sum a_i eta_{t-i} + sum b_j dx_g| <= s`` over the boxes.
    The witness (``eta``, ``dx``) is clipped into its boxes (``|eta_t| <= deta_t`` and
    ``|dx| <= dx_group`` hold exactly) and its residuals are recomputed. Tolerance policy
    (:mod:`hammerbound.tolerances`): ``feasible`` when every equation's residual is at
    most ``tol * equation_scale`` (:func:`equation_scale`, the magnitudes of its terms),
    the gain equality holds to ``tol`` times the magnitudes of its terms, and ``theta`` is
    inside ``theta_box``. ``tol`` defaults to ``FEASIBILITY_RTOL`` (1e-9): far above the
    rounding of the residuals (~1e-16 per term) and far below any meaningful noise bound.
    Witnesses only ever *accept* points (inner values of the exact method); no outer bound
    depends on this decision.

    ``witness``, an optional candidate ``(eta (N,), dx (K,))`` (e.g. from a warm-started
    solver), is judged first by the same rule (clipped, residuals recomputed); only if it
    fails is the LP solved. A witness can only save the LP, never change the rule.
    """
    from ..tolerances import FEASIBILITY_RTOL

    if tol is None:
        tol = FEASIBILITY_RTOL
    import scipy.sparse as sp
    from scipy.optimize import linprog

    theta = np.asarray(theta, dtype=float)
    if theta.shape != (problem.p,):
        raise ParameterValidationError(f"theta must have shape ({problem.p},); got {theta.shape}.")
    r = problem.simulate_noise_free(theta)
    m = r.size
    n, k = problem.N, problem.n_groups
    from .witness import fixed_theta_matrix

    M = fixed_theta_matrix(problem, theta)  # M z = r  with z = [eta; dx]
    # the LP is solved in scaled units (every error in [-1, 1], every equation divided by
    # the magnitude of its terms), so HiGHS's absolute tolerances act relative to the data
    scale = equation_scale(problem, theta)
    zmax = np.concatenate([problem.deta, problem.dx_group])
    if witness is not None:
        z = np.clip(np.concatenate([np.asarray(witness[0], dtype=float).ravel(),
                                    np.asarray(witness[1], dtype=float).ravel()]), -zmax, zmax)
        if z.shape == zmax.shape:
            chk = _judge(problem, theta, M, r, scale, z, tol)
            if chk.feasible:
                return chk
    Ms = sp.diags(1.0 / scale) @ M @ sp.diags(zmax)
    rs = r / scale
    s_col = -np.ones((m, 1))
    A_ub = sp.vstack([sp.hstack([Ms, s_col]), sp.hstack([-Ms, s_col])]).tocsr()
    b_ub = np.concatenate([rs, -rs])
    c = np.zeros(n + k + 1)
    c[-1] = 1.0
    bounds = np.vstack([np.column_stack([-np.ones(n + k), np.ones(n + k)]), [[0.0, np.inf]]])
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, bounds=bounds, method="highs",
                  options={"primal_feasibility_tolerance": 1e-10})
    for method in ("highs-ds", "highs-ipm"):
        if res.status == 0:
            break
        # the strict tolerance can make HiGHS give up on long records; the default one is
        # as safe here, because the witness is clipped and its violation recomputed below
        res = linprog(c, A_ub=A_ub, b_ub=b_ub, bounds=bounds, method=method)
    if res.status != 0:  # pragma: no cover - the LP is always feasible and bounded
        from ..exceptions import SolverError

        raise SolverError(f"HiGHS failed on the feasibility LP at fixed theta: {res.message}")
    # HiGHS may violate the variable bounds by its feasibility tolerance: clip, so that the
    # witness satisfies |eta| <= deta and |dx| <= dx_group exactly (the violation below is
    # recomputed from the clipped witness)
    z = np.clip(res.x[: n + k], -1.0, 1.0) * zmax
    return _judge(problem, theta, M, r, scale, z, tol)


def _judge(problem, theta, M, r, scale, z, tol) -> FeasibilityCheck:
    """The acceptance rule of :func:`check_theta` for a witness ``z = [eta; dx]`` (clipped)."""
    m = r.size
    n, k = problem.N, problem.n_groups
    eta, dxv = z[:n], z[n : n + k]
    # recompute the violation exactly from the witness rather than trusting the LP value
    resid = np.abs(M @ z - r) if m else np.zeros(0)
    viol = float(np.max(resid)) if m else 0.0
    rel = float(np.max(resid / (tol * scale))) if m else 0.0
    g = problem.gain_row()
    gres = 0.0 if g is None else float(abs(g[0] @ theta - g[1]))
    gscale = 0.0 if g is None else float(np.abs(g[0]) @ np.abs(theta) + abs(g[1]))
    in_box = np.all(theta >= problem.theta_box[:, 0]) and np.all(theta <= problem.theta_box[:, 1])
    feas = bool(in_box and rel <= 1.0 and gres <= tol * gscale)
    return FeasibilityCheck(feas, viol, eta, dxv, gres, rel)
