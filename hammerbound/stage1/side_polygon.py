"""One backlash side's feasible polygon, sound at every scale (stage 1, section 22.3).

The measurements of one side, ``|y_s - m u_s - sigma beta| <= Delta_s`` in ``(m, beta = m c)``
(``sigma = -1`` right, ``+1`` left), together with ``m >= 0`` and ``beta >= 0``, define a
convex polygon. :class:`SideProblem` computes it by the policy of ``docs/tolerances.md``:

1. **Outward tolerance.** Every bound is relaxed to ``Delta_s + t_s`` with
   ``t_s = feasibility_tol(..., rtol=ARITHMETIC_RTOL)`` (1e-11) of the largest magnitudes
   the terms of the constraint can take over the set (``|y_s|``, ``Delta_s``,
   ``m_ref |u_s|``, ``beta_ref``, and the centre ``|y0|``, ``m_ref |u0|`` of the
   coordinates below), where ``m_ref`` and ``beta_ref`` are
   a priori bounds read off the two slabs of the extreme amplitudes. ``m >= 0`` and
   ``beta >= 0`` are exact model facts and are not relaxed.
2. **Well-conditioned coordinates.** ``u = u0 + su t``, ``y = y0 + sy z`` with ``su``, ``sy``
   powers of two (exact scalings) and ``(p, q) = (m su / sy, (m u0 + sigma beta - y0) / sy)``:
   the slabs become ``|z_s - p t_s - q| <= d_s`` with ``|t_s| <= 1``, ``|z_s| <= 1``,
   ``d_s <= 1``, so every vertex is O(1) and is computed from its two defining constraints
   (:func:`~hammerbound.stage1.feasible_set.polygon_from_halfplanes`), whatever the data's scale.
3. **Empty only when certified.** If no polygon results, three constraints (found by an LP
   that minimises the largest violation) are checked in exact rational arithmetic
   (:func:`~hammerbound.stage1.feasible_set.farkas_certificate`) against the *relaxed* bounds of
   the user's floats. Without a certificate the tolerance is widened (x100, x1e4) rather
   than a set declared empty.
"""

from __future__ import annotations

from fractions import Fraction
from itertools import combinations

import numpy as np

from ..exceptions import SolverError, UnboundedSetError
from ..tolerances import ARITHMETIC_RTOL, feasibility_tol
from .halfplanes import (
    Constraint,
    algorithm_22_1,
    edge_support,
    farkas_certificate,
    polygon_from_halfplanes,
)

__all__ = ["SideProblem", "SidePolygon", "RELAX_FACTORS"]

#: Multiples of the policy tolerance tried, in turn, when the polygon comes out empty but
#: no exact certificate of emptiness is found (never needed in the test-suite; a fallback).
RELAX_FACTORS = (1.0, 1e2, 1e4)

#: Largest relative residual of the nearest constraint boundary along every edge of the
#: pruned Algorithm 22.1 polygon (:meth:`SideProblem._algorithm`): a vertex lost by the
#: pruning would leave an edge on no boundary. Ten times below ``ARITHMETIC_RTOL``.
EDGE_SUPPORT_RTOL = 1e-12

_BOX = 1e6  # in (p, q) the set lies within |p| <= ~2, |q| <= ~3: never active
_SNAP = 1e-14  # relative rounding below which a vertex is on m = 0 / beta = 0


def _pow2(x: float) -> float:
    return float(2.0 ** np.round(np.log2(x)))


def _hull_mask(u, v) -> np.ndarray:
    """Points ``(u_k, v_k)`` that are vertices of their convex hull (all if undecided).

    Points on a line to rounding -- noise at exactly ``+Delta`` on every sample puts every
    ``(t_s, z_s)`` of a side on one line -- make Qhull refuse ("initial simplex is flat").
    Their hull is then taken in sheared, rescaled coordinates ``(u, (v - line(u)) / s)``,
    an affine map that keeps hull vertices hull vertices: a handful of points instead of
    all of them. The caller checks the result against every point either way (the mask can
    only drop constraints, which enlarges the polygon).
    """
    mask = np.zeros(u.size, dtype=bool)
    if u.size <= 8:
        mask[:] = True
        return mask
    from scipy.spatial import ConvexHull, QhullError

    try:
        mask[ConvexHull(np.column_stack([u, v])).vertices] = True
        return mask
    except (QhullError, ValueError):
        pass
    i0, i1 = int(np.argmin(u)), int(np.argmax(u))
    mask[[i0, i1]] = True
    if u[i1] == u[i0]:
        mask[:] = True
        return mask
    r = v - (v[i0] + (u - u[i0]) * ((v[i1] - v[i0]) / (u[i1] - u[i0])))
    s = float(np.max(np.abs(r)))
    if s == 0.0:  # exactly on the line: the two ends carry the hull
        return mask
    try:
        mask[ConvexHull(np.column_stack([(u - u[i0]) / (u[i1] - u[i0]), r / s])).vertices] = True
    except (QhullError, ValueError):
        mask[:] = True
    return mask


class SidePolygon:
    """Result of :meth:`SideProblem.solve`: vertices in ``(m, beta)``, edges, constraints."""

    def __init__(self, verts_mb, edge_cons, constraints, factor, n_filtered):
        self.verts_mb = verts_mb
        self.edge_cons = edge_cons
        self.constraints = constraints
        self.factor = factor
        self.n_filtered = n_filtered


class SideProblem:
    """The relaxed, rescaled constraint system of one backlash side.

    Parameters
    ----------
    side : {"left", "right"}
    u, y, deta, idx : ndarray
        Amplitudes (with the side's sign), outputs, output error bounds and caller's indices.
    """

    def __init__(self, side, u, y, deta, idx):
        self.side = side
        self.sigma = -1.0 if side == "right" else 1.0
        self.u, self.y, self.deta, self.idx = u, y, deta, np.asarray(idx)
        umin, umax = float(u.min()), float(u.max())
        ymin, ymax = float(y.min()), float(y.max())
        iL, iR = int(np.argmin(u)), int(np.argmax(u))
        self.u0 = 0.5 * umin + 0.5 * umax
        self.su = _pow2(0.5 * umax - 0.5 * umin)
        self.y0 = 0.5 * ymin + 0.5 * ymax
        self.sy = _pow2(max(0.5 * ymax - 0.5 * ymin, float(deta.max())))
        # a priori bounds over the set: it lies in the parallelogram of the two slabs of the
        # extreme amplitudes, so |m| <= m_ref and |beta| <= |y_L| + Delta_L + m_ref |u_L|
        self.m_ref = (abs(y[iR] - y[iL]) + deta[iR] + deta[iL]) / (umax - umin)
        self.beta_ref = abs(y[iL]) + deta[iL] + self.m_ref * abs(u[iL])
        self.tol = feasibility_tol(y, self.y0, deta, self.m_ref * u, self.m_ref * self.u0,
                                   self.beta_ref, rtol=ARITHMETIC_RTOL)
        self.t = (u - self.u0) / self.su

    # ------------------------------------------------------------------ constraints
    def bounds(self, factor=1.0):
        """Relaxed bounds ``lo <= m u + sigma beta <= hi`` and their scaled images."""
        cache = self.__dict__.setdefault("_bounds", {})
        if factor not in cache:
            d = self.deta + factor * self.tol
            hi, lo = self.y + d, self.y - d
            cache[factor] = (hi, lo, (hi - self.y0) / self.sy, (lo - self.y0) / self.sy)
        return cache[factor]

    def pairs(self, sel, factor=1.0):
        """``(h+, h-)`` pairs of the selected samples: scaled ``(p, q)`` and original ``(m, beta)``."""
        hi, lo, zu, zl = self.bounds(factor)
        sel = np.arange(self.u.size)[sel]
        s = float(self.sigma)
        cols = (self.idx[sel], self.t[sel], zu[sel], zl[sel], self.u[sel], hi[sel], lo[sel],
                (factor * self.tol)[sel])
        pq, mb = [], []
        for i, t, a, b, u, h, l, sl in zip(*(c.tolist() for c in cols), strict=True):
            pq.append((Constraint((t, 1.0), a, i, "+"), Constraint((-t, -1.0), -b, i, "-")))
            mb.append((Constraint((u, s), h, i, "+", sl), Constraint((-u, -s), -l, i, "-", sl)))
        return pq, mb

    def positivity(self):
        s = self.sigma
        pq = [Constraint((-1.0, 0.0), 0.0, None, "m>=0"),
              Constraint((s * (self.u0 / self.su), -s), s * (self.y0 / self.sy), None, "c>=0")]
        mb = [Constraint((-1.0, 0.0), 0.0, None, "m>=0"), Constraint((0.0, -1.0), 0.0, None, "c>=0")]
        return pq, mb

    @staticmethod
    def box():
        return [Constraint((1.0, 0.0), _BOX, None, "box"), Constraint((0.0, 1.0), _BOX, None, "box"),
                Constraint((0.0, -1.0), _BOX, None, "box")]

    def to_mb(self, V):
        """Map ``(p, q)`` vertices to ``(m, beta)``; ``m, beta >= 0`` hold exactly in the model."""
        m = V[:, 0] * (self.sy / self.su)
        beta = self.sigma * (self.sy * V[:, 1] + self.y0 - m * self.u0)
        # a vertex on m = 0 or beta = 0 comes out within rounding of it: put it there (this
        # only lowers c_min / m_min, i.e. outward; the other extremes sit a tolerance away)
        mag = np.abs(self.sy * V[:, 1]) + abs(self.y0) + np.abs(m * self.u0)
        beta = np.where(beta <= _SNAP * mag, 0.0, beta)
        m = np.where(m <= _SNAP * self.m_ref, 0.0, m)
        return np.column_stack([m, beta])

    def polygon(self, sel, factor=1.0):
        """Polygon of the selected samples in ``(p, q)`` (``None`` if numerically empty)."""
        pq, mb = self.pairs(sel, factor)
        pos_pq, pos_mb = self.positivity()
        cons_pq = [c for pr in pq for c in pr] + pos_pq + self.box()
        cons_mb = [c for pr in mb for c in pr] + pos_mb
        return polygon_from_halfplanes(cons_pq), cons_pq, cons_mb, pq, mb

    # ------------------------------------------------------------------ solve
    def solve(self, method="polygon") -> SidePolygon | None:
        """The relaxed polygon, or ``None`` when its emptiness is certified exactly."""
        for factor in RELAX_FACTORS:
            out = self._solve_at(factor, method)
            if out is not None:
                return out
            if self.certificate(factor=factor) is not None:
                return None
        raise SolverError(
            f"stage 1 could neither build the {self.side} feasible polygon nor certify it "
            "empty, even with the tolerance widened 1e4-fold; please report these data.")

    def filtered_polygon(self, sel=slice(None), factor=1.0):
        """Polygon of the selected samples, through the convex-hull pre-filter.

        Only measurements on the convex hulls of ``(t, z_hi)`` and ``(t, z_lo)`` can carry an
        edge (the others are implied by their neighbours): a C-speed pre-filter that can
        only drop constraints, checked against every selected measurement afterwards.
        Returns ``(res, cons_pq, cons_mb, n_used)``; ``res`` is ``None`` if numerically empty.
        """
        hi, lo, zu, zl = self.bounds(factor)
        idx = np.arange(self.u.size)[sel]
        t, zu, zl = self.t[idx], zu[idx], zl[idx]
        keep = _hull_mask(t, zu) | _hull_mask(t, zl)
        if not keep.all():
            res, cons_pq, cons_mb, pq, _ = self.polygon(idx[keep], factor)
            # None: the hull system (a superset of the set) is numerically empty, so is the
            # full one; the caller certifies it (or widens the tolerance) either way
            if res is None or self._satisfies_all(res[0], t, zu, zl):
                return res, cons_pq, cons_mb, len(pq)
        res, cons_pq, cons_mb, pq, _ = self.polygon(idx, factor)
        return res, cons_pq, cons_mb, len(pq)

    def _solve_at(self, factor, method):
        res, cons_pq, cons_mb, n_used = self.filtered_polygon(slice(None), factor)
        if res is None:
            return None
        V, E = res
        _, _, zu, zl = self.bounds(factor)
        if not self._satisfies_all(V, self.t, zu, zl):
            # a "polygon" whose vertices break the relaxed bounds beyond rounding is a point
            # of an empty intersection (review 49: bound 3e-7 for errors within 3e-6 gave a
            # single vertex 6x outside, every status optimal): the caller certifies it
            # empty, or widens the tolerance
            return None
        if any(c.sign == "box" for c in E):  # pragma: no cover - bounded by construction
            raise UnboundedSetError(
                f"the {self.side} feasible set is unbounded: the data do not bound the slope; "
                "add square waves with more distinct amplitudes.")
        if method == "algorithm":
            V, E, cons_mb = self._algorithm(factor)
            return SidePolygon(V, E, cons_mb, factor, self.u.size)
        # cons_pq ends with the box rows, which have no (m, beta) counterpart
        to_mb = dict(zip(map(id, cons_pq), cons_mb, strict=False))
        return SidePolygon(self.to_mb(V), [to_mb[id(c)] for c in E], cons_mb, factor, n_used)

    @staticmethod
    def _satisfies_all(V, t, zu, zl) -> bool:
        lhs = V[:, :1] * t + V[:, 1:]
        slop = 1e-12 * (np.abs(V).sum(axis=1)[:, None] * (1 + np.abs(t)) + np.abs(zu)
                        + np.abs(zl))
        return bool(np.all(lhs <= zu + slop) and np.all(lhs >= zl - slop))

    def _algorithm(self, factor):
        """Algorithm 22.1 on the same relaxed constraints, in the same coordinates.

        Run with H_L pruned to the edge-carrying boundaries (:func:`algorithm_22_1`), and
        kept only if every edge of the result lies on a constraint boundary to
        :data:`EDGE_SUPPORT_RTOL` (:func:`~hammerbound.feasible_set.edge_support`); else
        (never seen) run again as written, without pruning.
        """
        pq, mb = self.pairs(slice(None), factor)
        pos_pq, pos_mb = self.positivity()
        order = _processing_order(self.u)
        cons_pq = [c for pr in pq for c in pr] + pos_pq
        for prune in (True, False):
            v = algorithm_22_1([pq[i] for i in order], extra=pos_pq, prune=prune)
            if v.shape[0] == 0:  # pragma: no cover - the polygon exists at this tolerance
                raise SolverError(f"Algorithm 22.1 found no vertex of the {self.side} set that "
                                  "the half-plane intersection found non-empty; please report "
                                  "these data.")
            c0 = v.mean(axis=0)
            v = v[np.argsort(np.arctan2(v[:, 1] - c0[1], v[:, 0] - c0[0]))]
            if v.shape[0] < 3 or edge_support(v, cons_pq) <= EDGE_SUPPORT_RTOL:
                break
        cons_mb = [c for pr in mb for c in pr] + pos_mb
        V = self.to_mb(v)
        return V, _common_constraints(V, cons_mb), cons_mb

    # ------------------------------------------------------------------ emptiness
    def certificate(self, sel=slice(None), factor=1.0):
        """Exact proof that the relaxed constraints of ``sel`` admit no ``(m, beta) >= 0``.

        Returns the labels of (at most) three constraints and their Farkas multipliers, or
        ``None``. The check is on the user's floats taken exactly (``Fraction``), with the
        bounds ``Delta_s + factor t_s``; candidates come from an LP in ``(p, q)`` that
        minimises the largest violation (its dual support has at most three rows), first
        among the measurements on the convex hulls (an empty hull system has a certificate
        of its own), then among all.
        """
        hi, lo, zu, zl = self.bounds(factor)
        local = np.arange(self.u.size)[sel]
        keep = _hull_mask(self.t[local], zu[local]) | _hull_mask(self.t[local], zl[local])
        for subset in ((local[keep], local) if not keep.all() else (local,)):
            cert = self._certificate_among(subset, factor)
            if cert is not None:
                return cert
        return None

    def _certificate_among(self, local, factor):
        from scipy.optimize import linprog

        hi, lo, zu, zl = self.bounds(factor)
        k = local.size
        A = np.empty((2 * k + 2, 2))
        b = np.empty(2 * k + 2)
        A[0:2 * k:2, 0], A[0:2 * k:2, 1], b[0:2 * k:2] = self.t[local], 1.0, zu[local]
        A[1:2 * k:2, 0], A[1:2 * k:2, 1], b[1:2 * k:2] = -self.t[local], -1.0, -zl[local]
        pos_pq, _ = self.positivity()
        A[2 * k:], b[2 * k:] = [c.a for c in pos_pq], [c.b for c in pos_pq]
        w = np.r_[np.ones(2 * k), 0.0, 0.0]
        res = linprog([0.0, 0.0, 1.0], A_ub=np.column_stack([A, -w]), b_ub=b,
                      bounds=[(-_BOX, _BOX), (-_BOX, _BOX), (-_BOX, _BOX)], method="highs")
        n = 2 * k + 2
        if res.status == 0:
            marg = np.abs(res.ineqlin.marginals)
            slack = b + w * res.x[2] - A @ res.x[:2]
            cand = list(np.argsort(-marg)[:6]) + list(np.argsort(slack)[:6])
        else:  # pragma: no cover - the LP is feasible by construction (s large enough)
            cand = list(range(min(n, 12)))
        cand = sorted(set(int(r) for r in cand) | {n - 2, n - 1})
        exact = {r: self._exact_row(r, local, factor) for r in cand}
        for trio in combinations(cand, 3):
            lam = farkas_certificate([exact[r] for r in trio])
            if lam is not None:
                return tuple(self._label(r, local) for r in trio), lam
        return None

    def _label(self, r, local):
        if r >= 2 * local.size:
            return ("m>=0", "c>=0")[r - 2 * local.size]
        return f"h{'+-'[r % 2]}[{int(self.idx[local[r // 2]])}]"

    def _exact_row(self, r, local, factor):
        """Row ``r`` of the certificate system exactly: ``(a0, a1, b)`` in ``Fraction``.

        Data rows are ``+-(m u + sigma beta) <= +-y + Delta + s`` with the float slack
        ``s = factor t`` and the user's floats taken at their exact values, so the
        certificate proves emptiness of the relaxed system itself, not of its rounding.
        """
        n_data = 2 * len(local)
        if r >= n_data:  # m >= 0, beta >= 0
            return ((Fraction(-1), Fraction(0), Fraction(0)) if r == n_data
                    else (Fraction(0), Fraction(-1), Fraction(0)))
        k = int(local[r // 2])
        u, s = Fraction(float(self.u[k])), Fraction(self.sigma)
        room = Fraction(float(self.deta[k])) + Fraction(float(factor * self.tol[k]))
        y = Fraction(float(self.y[k]))
        if r % 2 == 0:
            return (u, s, y + room)
        return (-u, -s, -(y - room))


def _processing_order(u):
    """Measurement order for Algorithm 22.1: the first two must differ in amplitude."""
    order = list(range(len(u)))
    j = next(k for k in range(1, len(u)) if u[k] != u[0])
    order.insert(1, order.pop(j))
    return order


def _common_constraints(V, cons, chunk: int = 64):
    """For each edge ``V[k] -> V[k+1]``, the constraint closest to both endpoints
    (``chunk`` edges at a time: memory O(chunk * len(cons)))."""
    A = np.array([c.a for c in cons], dtype=float)
    b = np.array([c.b for c in cons], dtype=float)
    norm = np.abs(b) + np.hypot(A[:, 0], A[:, 1])
    W = np.roll(V, -1, axis=0)
    best = []
    for k in range(0, V.shape[0], chunk):
        score = (np.abs(V[k : k + chunk] @ A.T - b) + np.abs(W[k : k + chunk] @ A.T - b)) / norm
        best.extend(np.argmin(score, axis=1).tolist())
    return [cons[int(k)] for k in best]
