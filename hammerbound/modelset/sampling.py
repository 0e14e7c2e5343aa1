"""Certified samples of the feasible parameter sets.

**Linear block (EIV set (22.34)).** For a fixed ``theta`` the constraints of (22.34) are
linear in the noise sequences, so membership is decided by one LP
(:func:`hammerbound.relaxations.problem.check_theta`), whose witness ``(eta, dx)`` is
the certificate kept with every sample: ``|eta_t| <= deta_t``, ``|dx_k| <= dx_k`` and every
equation of (22.34) holds to ``FEASIBILITY_RTOL`` (1e-9) times the magnitude of its terms
(:func:`~hammerbound.relaxations.problem.equation_scale`; the tolerance policy of
``docs/tolerances.md``).

The sampler is *hit-and-run with shrinkage* (the slice-sampling shrinkage of Neal,
2003) restricted to the gain hyperplane (22.8) when there is one, inside the orthotope
(which contains the set). Chains start at verified points - the witnesses of the exact
method, which sit at the extremes of every parameter, and the centre when it is
feasible - and move round-robin. A proposal is drawn uniformly on the chord of the box
along a random direction (scaled by the box radii); a rejected proposal shrinks the
chord towards the current point, so every step ends inside the set. Only moves are
recorded (with ``thin`` steps between records).

Limits (be aware when you use the samples as "the set"):

* the feasible set need not be convex, nor even connected; a chain explores the
  component it starts in, so components without a seed are missed;
* the samples are correlated and *not* uniformly distributed (seeded at the extremes,
  and only moves are recorded); they are guaranteed members, spread over the set,
  not a probability model;
* each step costs one or a few LPs of size ``N`` (about 10 ms of CPU each at ``N = 300``).

**Backlash (stage 1).** Each side's exact set is a convex polygon in ``(m, beta = m c)``,
the two sides are independent: samples are drawn *uniformly in* ``(m, beta)`` (fan
triangulation, area-weighted), mapped to ``(m, c)`` and each is checked against every
half-plane of its polygon.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..exceptions import ParameterValidationError, SolverError
from ..relaxations.problem import check_theta
from ..relaxations.witness import WitnessLP, seek_feasible
from ..systems.models import GAMMA_NAMES

__all__ = ["BacklashSamples", "CertifiedSamples", "sample_backlash", "sample_eiv"]


def _rng(random_state):
    if isinstance(random_state, np.random.Generator):
        return random_state
    if random_state is None or isinstance(random_state, (int, np.integer)):
        return np.random.default_rng(random_state)
    if isinstance(random_state, np.random.RandomState):
        return np.random.default_rng(random_state.randint(0, 2**31 - 1))
    raise ParameterValidationError(
        f"random_state must be None, an int seed or a numpy Generator; got {random_state!r}."
    )


def _check_n(n):
    if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 1:
        raise ParameterValidationError(f"n must be an integer >= 1; got {n!r}.")
    return int(n)


@dataclass(frozen=True)
class CertifiedSamples:
    """Parameter vectors of the EIV set, each with its feasibility certificate.

    Attributes
    ----------
    theta : ndarray (n, p)
        The samples, columns in :attr:`param_names` order.
    param_names : tuple of str
    eta : ndarray (n, N)
        Witness output errors (``|eta| <= output_bound``) for each sample.
    dx : ndarray (n, K)
        Witness input errors, one per input-error group (``|dx| <= input_bound``).
    max_violation : ndarray (n,)
        Largest equation residual of (22.34) at the witness divided by the magnitude of
        that equation's terms (``equation_scale``); ``<= tol`` for every sample.
    gain_residual : ndarray (n,)
        ``|B(1) - g A(1)|`` (0 without a gain constraint).
    tol : float
        The relative feasibility tolerance the residuals were checked against
        (``FEASIBILITY_RTOL``).
    n_lp : int
        LPs solved (screening and verification).
    """

    theta: np.ndarray
    param_names: tuple
    eta: np.ndarray
    dx: np.ndarray
    max_violation: np.ndarray
    gain_residual: np.ndarray
    tol: float
    n_lp: int = 0

    def __len__(self) -> int:
        return self.theta.shape[0]


class _Verifier:
    """Membership with a witness: the shared warm-started fixed-theta LP
    (:class:`~hammerbound.relaxations.witness.WitnessLP`), :func:`check_theta` as fallback.

    A candidate is accepted only if the clipped witness reproduces every equation of
    (22.34) to ``FEASIBILITY_RTOL`` times the magnitude of its terms, the gain equality holds
    to ``FEASIBILITY_RTOL`` times the magnitude of its terms and ``theta`` is in the a priori
    box - the acceptance rule of :func:`check_theta`.
    """

    def __init__(self, problem):
        self.problem = problem
        self.n_lp = 0
        from ..tolerances import FEASIBILITY_RTOL

        self.tol = FEASIBILITY_RTOL
        try:
            self.lp = WitnessLP(problem)
        except Exception:  # noqa: BLE001 - highspy missing: check_theta only
            self.lp = None

    def __call__(self, theta):
        from ..relaxations.problem import FeasibilityCheck

        pr = self.problem
        theta = np.asarray(theta, dtype=float)
        box = pr.theta_box
        if np.any(theta < box[:, 0]) or np.any(theta > box[:, 1]):
            return None
        g = pr.gain_row()
        gres = 0.0 if g is None else float(abs(g[0] @ theta - g[1]))
        if g is not None and gres > self.tol * float(np.abs(g[0]) @ np.abs(theta) + abs(g[1])):
            return None
        if self.lp is not None:
            self.n_lp += 1
            try:
                res = self.lp.witness(theta)
            except Exception:  # noqa: BLE001 - fall back to check_theta below
                res = None
            if res is not None:
                z, viol = res
                if viol > self.tol:
                    return None
                n = pr.N
                return FeasibilityCheck(True, viol, z[:n], z[n:], gres)
        self.n_lp += 1
        try:
            chk = check_theta(pr, theta)
        except SolverError:
            return None
        if not chk.feasible:
            return None
        # report the relative violation, as the warm-started path does
        return FeasibilityCheck(True, chk.max_rel_violation * self.tol, chk.eta, chk.dx,
                                chk.gain_residual, chk.max_rel_violation)


def _null_basis(problem, radius):
    """Orthonormal basis (in radius-scaled coordinates) of the directions on the gain plane."""
    p = problem.p
    g = problem.gain_row()
    if g is None:
        return np.eye(p)
    row = g[0] * radius
    return np.linalg.svd(row[None, :])[2][1:].T


def _project(problem, theta):
    g = problem.gain_row()
    if g is None:
        return theta
    row, rhs = g
    return theta + row * (rhs - row @ theta) / float(row @ row)


def _seek(problem, box, seeds, ver):
    """A first feasible point by minimising the violation of the fixed-theta witness LP
    (:func:`~hammerbound.relaxations.witness.seek_feasible`, the exact method's search),
    accepted by ``ver``."""
    starts = [np.asarray(s, dtype=float) for s in seeds] or [box.mean(axis=1)]

    def accept(theta):
        chk = ver(theta)
        return None if chk is None else (np.array(theta, dtype=float), chk)

    try:
        screen = ver.lp if ver.lp is not None else WitnessLP(problem)
        hit = seek_feasible(problem, screen, accept, starts, box)
    except Exception:  # noqa: BLE001 - no seed found: the caller raises a clear error
        return []
    return [] if hit is None else [hit]


def sample_eiv(problem, box, n, *, seeds=(), random_state=None, thin=1, max_shrink=40,
               param_names=None) -> CertifiedSamples:
    """``n`` certified members of the EIV set of ``problem`` inside ``box`` (see module doc).

    ``seeds`` are candidate starting points (each is verified; at least one must be
    feasible, else :class:`SolverError` asks for ``method="exact"``).
    """
    n = _check_n(n)
    if not isinstance(thin, (int, np.integer)) or thin < 1:
        raise ParameterValidationError(f"thin must be an integer >= 1; got {thin!r}.")
    rng = _rng(random_state)
    box = np.asarray(box, dtype=float)
    lo, hi = box[:, 0], box[:, 1]
    radius = np.maximum(0.5 * (hi - lo), 1e-300)
    ver = _Verifier(problem)
    chains, out = [], []
    for s in seeds:
        s = _project(problem, np.asarray(s, dtype=float))
        if np.any(s < lo) or np.any(s > hi) or any(np.array_equal(s, c[0]) for c in chains):
            continue
        chk = ver(s)
        if chk is not None:
            chains.append((s, chk))
            if len(out) < n:
                out.append((s, chk))
    if not chains:
        chains = _seek(problem, box, seeds, ver)
        out = list(chains[:n])
    if not chains:
        raise SolverError(
            "no verified feasible starting point for the sampler: none of its starting "
            "points (the centre of the intervals, the fit's witnesses, any seeds given) lies "
            "in the set, and a search from them found no member (the set may be thin). Fit "
            "with method='exact' (its witnesses are feasible points) or pass a known "
            "feasible theta: sample(n, seeds=[theta])."
        )
    basis = _null_basis(problem, radius)
    steps = 0
    max_steps = 50 * n + 1000
    while len(out) < n and steps < max_steps:
        for ci in range(len(chains)):
            if len(out) >= n:
                break
            steps += 1
            th, chk = chains[ci]
            d = radius * (basis @ rng.standard_normal(basis.shape[1]))
            nd = np.linalg.norm(d / radius)
            if nd == 0:
                continue
            d /= nd
            with np.errstate(divide="ignore", invalid="ignore"):
                t_lo = np.where(d > 0, (lo - th) / d, np.where(d < 0, (hi - th) / d, -np.inf))
                t_hi = np.where(d > 0, (hi - th) / d, np.where(d < 0, (lo - th) / d, np.inf))
            a, b = float(np.max(t_lo)), float(np.min(t_hi))
            moved = False
            for _ in range(max_shrink):
                t = rng.uniform(a, b)
                cand = np.clip(_project(problem, th + t * d), lo, hi)
                c = ver(cand)
                if c is not None:
                    chains[ci] = (cand, c)
                    moved = True
                    break
                if t < 0:
                    a = t
                else:
                    b = t
            if moved and steps % thin == 0:
                out.append(chains[ci])
    if len(out) < n:
        raise SolverError(
            f"the sampler recorded only {len(out)} of {n} samples in {steps} steps: the set is "
            "too thin for hit-and-run in this box. Try fewer samples or method='exact'."
        )
    theta = np.array([o[0] for o in out])
    chks = [o[1] for o in out]
    tol = ver.tol
    names = tuple(param_names) if param_names is not None else tuple(problem.param_names)
    return CertifiedSamples(
        theta=theta, param_names=names, eta=np.array([c.eta for c in chks]),
        dx=np.array([c.dx for c in chks]), max_violation=np.array([c.max_violation for c in chks]),
        gain_residual=np.array([c.gain_residual for c in chks]), tol=tol, n_lp=ver.n_lp,
    )


@dataclass(frozen=True)
class BacklashSamples:
    """Backlash parameters ``gamma = (m_l, c_l, m_r, c_r)`` drawn from the exact sets.

    ``max_violation[i]`` is the largest (scaled) violation of the half-planes of the two
    polygons by sample ``i`` (<= 1e-12, the polygon membership tolerance).
    """

    gamma: np.ndarray
    max_violation: np.ndarray
    param_names: tuple = GAMMA_NAMES  # the intervals' names (one name per concept)

    def __len__(self) -> int:
        return self.gamma.shape[0]


def _polygon_points(poly, n, rng):
    v = np.asarray(poly.vertices_mb, dtype=float)
    tri_a = v[1:-1] - v[0]
    tri_b = v[2:] - v[0]
    area = 0.5 * np.abs(tri_a[:, 0] * tri_b[:, 1] - tri_a[:, 1] * tri_b[:, 0])
    k = rng.choice(area.size, size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    flip = r1 + r2 > 1
    r1, r2 = np.where(flip, 1 - r1, r1), np.where(flip, 1 - r2, r2)
    return v[0] + r1[:, None] * tri_a[k] + r2[:, None] * tri_b[k]


def _violation(poly, mb):
    A = np.array([c.a for c in poly.constraints])
    b = np.array([c.b for c in poly.constraints])
    return np.max((mb @ A.T - b) / (1.0 + np.abs(b)), axis=1)


def sample_backlash(left, right, n, random_state=None) -> BacklashSamples:
    """``n`` samples of the product of the two exact polygons (uniform in ``(m, beta)``)."""
    n = _check_n(n)
    rng = _rng(random_state)
    cols, viol = [], np.zeros(n)
    for poly in (left, right):
        mb = _polygon_points(poly, n, rng)
        v = _violation(poly, mb)
        for _ in range(20):  # rounding can put a point a few ulps outside an edge
            bad = v > 1e-12
            if not bad.any():
                break
            mb[bad] = _polygon_points(poly, int(bad.sum()), rng)
            v[bad] = _violation(poly, mb[bad])
        else:  # pragma: no cover
            raise SolverError("could not draw backlash samples inside the polygon.")
        cols += [mb[:, 0], mb[:, 1] / mb[:, 0]]
        viol = np.maximum(viol, v)
    return BacklashSamples(np.column_stack(cols), viol)
