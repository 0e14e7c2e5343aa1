"""Feasible parameter sets: exact polygons (stage 1) and outer-bounding orthotopes.

Stage 1 (section 22.3): each backlash side's feasible set (22.12)/(22.13) is nonconvex
in ``(m, c)`` but, with ``beta = m c``, the model ``y = m u -+ beta`` is *linear*, so in
``(m, beta)`` coordinates it is a convex polygon: the intersection of the slabs
``|y_s - m u_s +- beta| <= Delta eta_s`` and of ``m >= 0, beta >= 0`` (R_+^2).
:func:`polygon_from_halfplanes` computes it exactly (sort by angle + deque, O(M log M));
:func:`algorithm_22_1` is the chapter's incremental procedure (Appendix), kept as an
independent cross-check. The map ``(m, beta) -> (m, c = beta / m)`` is a bijection on
``m > 0`` that maps vertices to vertices and straight edges to hyperbolic arcs, so the
extremes of ``m``, of ``c`` (linear-fractional) and of any ``a m + b beta`` are attained at
vertices (Propositions 22.1 and 22.2).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from ..data.validation import as_theta
from ..exceptions import ParameterValidationError
from ..results import DeprecatedExtra, IntervalSet, Result, jsonable

__all__ = [
    "Constraint",
    "Edge",
    "FeasibleSet",
    "PolygonFeasibleSet",
    "algorithm_22_1",
    "farkas_certificate",
    "polygon_from_halfplanes",
]


@dataclass(frozen=True)
class Constraint:
    """A half-plane ``a . p <= b`` with its origin.

    ``index`` is the measurement index (in the caller's data) and ``sign`` is ``"+"`` for
    the boundary ``y + Delta eta`` (h^+ of (22.14)) and ``"-"`` for ``y - Delta eta`` (h^-,
    (22.15)); positivity constraints have ``index=None`` and ``sign`` ``"m>=0"``/``"c>=0"``.
    ``slack`` is the outward tolerance already added to ``b`` (``docs/tolerances.md``):
    the measured bound is ``b - slack``.
    """

    a: tuple
    b: float
    index: int | None
    sign: str
    slack: float = 0.0

    @property
    def label(self) -> str:
        return self.sign if self.index is None else f"h{self.sign}[{self.index}]"


@dataclass(frozen=True)
class Edge:
    """Edge of a polygon (Definition 22.4): the part of ``constraint`` between two vertices."""

    constraint: Constraint
    start: np.ndarray
    end: np.ndarray


@dataclass(frozen=True, repr=False, eq=False)
class FeasibleSet(Result):
    """A parameter set with an outer-bounding orthotope (22.22)-(22.24).

    Attributes
    ----------
    param_names : tuple of str
    orthotope : ndarray of shape (p, 2)
        Tight (when ``exact``) or outer interval of every parameter (read-only).
    exact : bool
        True when ``vertices``/``edges`` describe the set exactly.
    vertices : ndarray of shape (n_vertices, p) or None
    edges : tuple of Edge
    polytopes : tuple
        Optional outer polytopes ``(A, b)`` with ``A theta <= b`` (their union contains the set).
    method : str
        What computed the set (``"polygon"``, ``"algorithm"``; stage 2: ``"lp"``,
        ``"moment"``, ``"exact"``).
    inner : ndarray of shape (p, 2) or None
        Exact stage 2: the hull of the verified witnesses of the interval ends.
    intervals : IntervalSet
        The orthotope as the package's interval-set result (names, bounds, a status per
        end); default: built from ``param_names`` and ``orthotope``, every end optimal.
        ``center``, ``radius`` and the orthotope test of ``contains`` are its.
    """

    param_names: tuple
    orthotope: np.ndarray
    exact: bool = False
    vertices: np.ndarray | None = None
    edges: tuple = ()
    polytopes: tuple = ()
    method: str = ""
    inner: np.ndarray | None = None
    intervals: IntervalSet | None = None

    def __post_init__(self):
        iv = self.intervals
        if iv is None:
            iv = IntervalSet(self.param_names, self.orthotope, method=self.method)
        elif tuple(iv.param_names) != tuple(self.param_names) or not np.array_equal(
                iv.bounds, np.asarray(self.orthotope, dtype=float)):
            raise ParameterValidationError("intervals must have the set's param_names and "
                                           "orthotope as bounds.")
        object.__setattr__(self, "intervals", iv)
        object.__setattr__(self, "param_names", iv.param_names)
        object.__setattr__(self, "orthotope", iv.bounds)

    @property
    def center(self) -> np.ndarray:
        """Central estimate gamma^c / theta^c (22.23)."""
        return self.intervals.center

    @property
    def radius(self) -> np.ndarray:
        """Uncertainty bound Delta gamma (22.23)."""
        return self.intervals.radius

    @property
    def extra(self):
        """Deprecated (removed in 0.3.0): the old ``extra`` dict, from the typed fields."""
        vals = {"method": self.method}
        new = {"method": "FeasibleSet.method"}
        if self.inner is not None:
            vals["inner"], new["inner"] = self.inner, "FeasibleSet.inner"
        return DeprecatedExtra(type(self).__name__, vals, new)

    def __repr__(self) -> str:
        extra = f", {len(self.polytopes)} outer polytope(s)" if self.polytopes else ""
        return (f"FeasibleSet({self.intervals}; exact={self.exact}{extra})")

    def contains(self, params, tol: float = 0.0) -> bool:
        """Whether ``params`` lies in the orthotope (exact sets override this); ``tol`` as
        :meth:`~hammerbound.results.IntervalSet.contains`."""
        p = as_theta(params, self.orthotope.shape[0], self.param_names, name="params")
        return self.intervals.contains(p, tol)

    def summary(self) -> str:
        """The set's description and its orthotope as a table."""
        return self.intervals.summary(title=repr(self))

    def to_dict(self) -> dict:
        """JSON-serialisable: the orthotope (:meth:`IntervalSet.to_dict`), ``exact``,
        ``method``, ``vertices``, the number of outer polytopes and ``inner``."""
        return jsonable({"intervals": self.intervals.to_dict(), "exact": self.exact,
                         "method": self.method, "vertices": self.vertices,
                         "n_polytopes": len(self.polytopes), "inner": self.inner})

    def plot(self, ax=None, **kwargs):
        """The orthotope's interval bars (:meth:`IntervalSet.plot`); returns the Axes."""
        return self.intervals.plot(ax, **kwargs)


@dataclass(frozen=True, repr=False, eq=False)
class PolygonFeasibleSet(FeasibleSet):
    """Exact feasible set of one backlash side, (22.12) or (22.13).

    ``vertices`` are in ``(m, c)`` coordinates (counter-clockwise in ``(m, beta)``);
    ``vertices_mb`` in ``(m, beta = m c)``; ``constraints`` are the half-planes in
    ``(m, beta)``; ``sigma`` is ``-1`` for the right side (``y = m u - beta``) and ``+1``
    for the left side (``y = m u + beta``). ``tolerance_factor`` is the factor by which the
    outward tolerance had to be widened for the relaxed set to be non-empty (1: the
    policy's tolerance, ``docs/tolerances.md``), ``max_tolerance`` the largest widening
    of a constraint that resulted.
    """

    side: str = "right"
    sigma: float = -1.0
    vertices_mb: np.ndarray | None = None
    constraints: tuple = ()
    tolerance_factor: float = 1.0
    max_tolerance: float = 0.0

    def __repr__(self) -> str:
        nv = 0 if self.vertices is None else len(self.vertices)
        return (f"PolygonFeasibleSet(side={self.side!r}, {self.intervals}; "
                f"{nv} vertices, {len(self.edges)} edges)")

    @property
    def extra(self):
        """Deprecated (removed in 0.3.0): the old ``extra`` dict, from the typed fields."""
        return DeprecatedExtra(
            "PolygonFeasibleSet",
            {"tolerance_factor": self.tolerance_factor, "max_tolerance": self.max_tolerance},
            {"tolerance_factor": "PolygonFeasibleSet.tolerance_factor",
             "max_tolerance": "PolygonFeasibleSet.max_tolerance"})

    def to_dict(self) -> dict:
        """As :meth:`FeasibleSet.to_dict`, with ``side``, ``vertices_mb`` and the tolerance."""
        d = super().to_dict()
        d.update(jsonable({"side": self.side, "vertices_mb": self.vertices_mb,
                           "tolerance_factor": self.tolerance_factor,
                           "max_tolerance": self.max_tolerance}))
        return d

    def contains(self, params, tol: float = 1e-12) -> bool:
        """Membership of ``(m, c)`` in the set (not just in the orthotope).

        The constraints are the measured ones relaxed outward by the tolerance policy
        (``docs/tolerances.md``); ``tol`` is a further relative allowance for the rounding
        of ``a . (m, m c) - b``, relative to the magnitudes of its terms.
        """
        m, c = as_theta(params, 2, self.param_names, name="params")
        p = np.array([m, m * c])
        A = np.array([k.a for k in self.constraints], dtype=float)
        b = np.array([k.b for k in self.constraints], dtype=float)
        scale = np.abs(A[:, 0] * p[0]) + np.abs(A[:, 1] * p[1]) + np.abs(b)
        return bool(np.all(A @ p - b <= tol * scale))

    def linear_range(self, coef_m: float, coef_beta: float) -> tuple[float, float]:
        """``min``/``max`` of ``coef_m m + coef_beta beta`` over the set (at vertices).

        Rounded outward: each end is moved by a few ulps of the terms, so the interval
        contains the exact one whatever the rounding of the products.
        """
        V = self.vertices_mb
        v = V @ np.array([coef_m, coef_beta])
        slop = 8 * np.finfo(float).eps * (np.abs(coef_m * V[:, 0]) + np.abs(coef_beta * V[:, 1]))
        return float(np.min(v - slop)), float(np.max(v + slop))

    @property
    def active_constraints(self) -> tuple:
        """Constraints carrying an edge (Definition 22.3)."""
        return tuple(e.constraint for e in self.edges)

    def boundary_mc(self, points_per_edge: int = 50) -> np.ndarray:
        """Closed boundary curve in ``(m, c)``: straight edges in ``(m, beta)`` are arcs here."""
        pts = []
        for e in self.edges:
            s = np.linspace(0.0, 1.0, points_per_edge)[:, None]
            seg = (1 - s) * e.start + s * e.end
            pts.append(seg)
        mb = np.vstack(pts) if pts else self.vertices_mb
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.column_stack([mb[:, 0], mb[:, 1] / mb[:, 0]])

    def plot(self, ax=None, *, true_params=None, show_orthotope=True, **kwargs):
        """Draw the set in ``(m, c)`` (curved edges), its vertices and orthotope; returns
        the Axes."""
        from ..plotting import plot_feasible_set

        return plot_feasible_set(self, ax=ax, true_params=true_params,
                                 show_orthotope=show_orthotope, **kwargs)


# --------------------------------------------------------------------------------------
# exact 2-D half-plane intersection
# --------------------------------------------------------------------------------------
_EPS = np.finfo(float).eps


def _intersect(c1: Constraint, c2: Constraint):
    """Intersection ``(x, y)`` of the boundary lines of two half-planes (``None`` if parallel).

    One coordinate comes from Cramer's rule, the other is substituted into the line with
    the larger coefficient for it. The point then satisfies that line to rounding and the
    other line to ``~eps |a| |x|`` however close to parallel the two lines are (plain
    Cramer for both coordinates has residuals that grow like the condition number).
    """
    a10, a11 = float(c1.a[0]), float(c1.a[1])
    a20, a21 = float(c2.a[0]), float(c2.a[1])
    det = a10 * a21 - a11 * a20
    if det == 0:
        return None
    # substitute into the line whose largest coefficient is largest, for that coordinate
    k1 = 0 if abs(a10) >= abs(a11) else 1
    k2 = 0 if abs(a20) >= abs(a21) else 1
    if max(abs(a10), abs(a11)) < max(abs(a20), abs(a21)):
        (a10, a11, b1), (a20, a21, b2), k = (a20, a21, c2.b), (a10, a11, c1.b), k2
        det = -det
    else:
        b1, b2, k = c1.b, c2.b, k1
    if k == 0:  # Cramer for y, then x from line 1
        y = (a10 * b2 - b1 * a20) / det
        x = (b1 - a11 * y) / a10
    else:  # Cramer for x, then y from line 1
        x = (b1 * a21 - a11 * b2) / det
        y = (b1 - a10 * x) / a11
    return (float(x), float(y))


def _round_tol(cons: Constraint, p) -> float:
    """Rounding-level tolerance of ``a . p - b`` at a computed vertex ``p``.

    A vertex from :func:`_intersect` satisfies its lines to ``~eps |a| |p|`` (``|p|`` the
    whole point, not just the terms of this line), so that is the scale.
    """
    a0, a1, b = float(cons.a[0]), float(cons.a[1]), float(cons.b)
    return 16 * _EPS * ((abs(a0) + abs(a1)) * (abs(float(p[0])) + abs(float(p[1]))) + abs(b))


def _outside(cons: Constraint, p) -> bool:
    """``p`` is outside ``cons`` beyond rounding (in doubt, keep the constraint)."""
    a0, a1, b = float(cons.a[0]), float(cons.a[1]), float(cons.b)
    x, y = float(p[0]), float(p[1])
    return a0 * x + a1 * y - b > 16 * _EPS * ((abs(a0) + abs(a1)) * (abs(x) + abs(y)) + abs(b))


def _max_violation(A, b, P) -> float:
    """Largest violation of ``A p <= b`` over the rows of ``P``, relative to ``|a| |p| + |b|``."""
    lhs = P @ A.T
    scale = (np.abs(P).sum(axis=1)[:, None] * np.abs(A).sum(axis=1)) + np.abs(b)
    return float(np.max((lhs - b) / np.where(scale > 0, scale, 1.0)))


def polygon_from_halfplanes(constraints) -> tuple[np.ndarray, list] | None:
    """Intersection of half-planes ``a . p <= b`` (bounded result assumed).

    Returns ``(vertices, edge_constraints)`` with vertices counter-clockwise and
    ``edge_constraints[k]`` the constraint carrying the edge from vertex ``k`` to ``k+1``.
    A degenerate intersection is returned as such: one vertex (a point) or two (a
    segment), with the constraints through them. ``None`` means that no point satisfies
    every constraint to rounding; that is *not* a certificate of emptiness (see
    :func:`farkas_certificate`): callers relax the constraints outward before calling.

    Soundness does not rest on the deque's floating-point decisions: the kept lines are a
    subsequence of the angle-sorted ones turning left by less than 180 degrees each (checked),
    and every vertex is computed from its two lines with rounding-size residuals
    (:func:`_intersect`), so the chain of vertices winds once around every point that is
    more than rounding inside all the half-planes -- a redundant line kept by rounding only
    adds a backward edge of rounding size. Every vertex must also satisfy every constraint
    to rounding (a check that the result is not larger than the intersection).
    """
    cons = list(constraints)
    ang = np.array([np.arctan2(c.a[0], -c.a[1]) for c in cons])  # direction d = (-a_y, a_x)
    norms = np.array([np.hypot(*c.a) for c in cons])
    offs = np.array([c.b for c in cons]) / norms
    order = np.lexsort((offs, ang))
    # keep the most restrictive of half-planes with the same direction
    uniq = []
    last = None
    for i in order:
        if last is not None and ang[i] == ang[last]:
            continue
        uniq.append(cons[i])
        last = i
    dq: deque = deque()
    for h in uniq:
        while len(dq) >= 2:
            p = _intersect(dq[-1], dq[-2])
            if p is None or _outside(h, p):
                dq.pop()
            else:
                break
        while len(dq) >= 2:
            p = _intersect(dq[0], dq[1])
            if p is None or _outside(h, p):
                dq.popleft()
            else:
                break
        if dq:
            a1, a2 = np.asarray(dq[-1].a), np.asarray(h.a)
            if a1[0] * a2[1] - a1[1] * a2[0] <= 0:
                # turned by >= 180 degrees: consecutive parallel/anti-parallel planes
                if _intersect(dq[-1], h) is None:
                    return None
        dq.append(h)
    while len(dq) >= 3:
        p = _intersect(dq[-1], dq[-2])
        if p is None or _outside(dq[0], p):
            dq.pop()
        else:
            break
    while len(dq) >= 3:
        p = _intersect(dq[0], dq[1])
        if p is None or _outside(dq[-1], p):
            dq.popleft()
        else:
            break
    if len(dq) < 2:
        return None
    hs = list(dq)
    # the kept lines must turn strictly left, by less than 180 degrees, from each to the
    # next (cyclically): then the chain of their consecutive intersections winds once
    # around the intersection of these half-planes (a subset of all, so it contains the
    # full intersection) -- even if rounding kept a redundant line (a backward edge of
    # rounding size, which never crosses the interior) or dropped a needed one
    if len(hs) >= 3:
        Ah = np.array([c.a for c in hs], dtype=float)
        An = np.roll(Ah, -1, axis=0)
        if np.any(Ah[:, 0] * An[:, 1] - Ah[:, 1] * An[:, 0] <= 0):
            return None
    verts = []
    for k in range(len(hs)):
        p = _intersect(hs[k], hs[(k + 1) % len(hs)])
        if p is None:
            if len(hs) == 2:
                continue
            return None
        verts.append(p)
    if not verts:
        return None
    verts = np.array(verts)
    A = np.array([c.a for c in cons], dtype=float)
    b = np.array([c.b for c in cons], dtype=float)
    # every vertex must satisfy every constraint up to rounding (a sanity check of the
    # tightness; containment does not depend on it)
    if _max_violation(A, b, verts) > _VIOLATION_SANITY:
        return None
    # vertex k sits between hs[k] and hs[k+1]; the edge from vertex k to k+1 lies on hs[k+1]
    edge_cons = [hs[(k + 1) % len(hs)] for k in range(len(verts))]
    # drop zero-length edges (several constraints through one vertex); "zero" is the
    # rounding of the vertices, far below any outward tolerance of the callers
    delta = _VERTEX_ROUNDING * (1.0 + float(np.max(np.abs(verts))))
    keep_v, keep_e = [], []
    n = len(verts)
    for k in range(n):
        nxt = verts[(k + 1) % n]
        if n == 1 or np.max(np.abs(nxt - verts[k])) > delta:
            keep_v.append(verts[k])
            keep_e.append(edge_cons[k])
    if not keep_v:  # every vertex coincides: a single point
        keep_v, keep_e = [verts[0]], [edge_cons[0]]
    return np.array(keep_v), keep_e


#: Relative size below which two computed vertices are the same point (rounding of the
#: intersections: a few hundred ulps of the polygon's magnitude).
_VERTEX_ROUNDING = 1e-13

#: Largest relative violation of a constraint by a computed vertex accepted as rounding.
#: Vertices of nearly parallel lines are ill-determined *along* them (``~eps / angle``);
#: that costs tightness only (never containment), and is ~1e-12 in practice, up to ~1e-9
#: for pencils of hundreds of nearly concurrent lines. Beyond this guard the result is
#: refused (``None``) as a sign of a gross error.
_VIOLATION_SANITY = 1e-6


def farkas_certificate(rows):
    """Exact infeasibility certificate of three half-planes ``a . p <= b`` in rationals.

    ``rows`` is a sequence of three ``(a0, a1, b)`` (floats, ints or
    :class:`fractions.Fraction`; floats are taken at their exact binary value). Returns
    the multipliers ``lambda >= 0`` (Fractions) with ``sum lambda_i a_i = 0`` and
    ``sum lambda_i b_i < 0`` -- a proof that no real point satisfies the three -- or
    ``None``. By Helly's theorem an empty intersection of half-planes in the plane always
    has such a certificate on at most three of them (two anti-parallel ones and any third
    row give a certificate with a zero multiplier).
    """
    (a0, a1, b0), (c0, c1, d0), (e0, e1, f0) = (
        tuple(Fraction(x) for x in r) for r in rows)
    lam = (c0 * e1 - c1 * e0, e0 * a1 - e1 * a0, a0 * c1 - a1 * c0)
    if all(x <= 0 for x in lam):
        lam = tuple(-x for x in lam)
    if not all(x >= 0 for x in lam) or not any(lam):
        return None
    if lam[0] * b0 + lam[1] * d0 + lam[2] * f0 < 0:
        return lam
    return None


def algorithm_22_1(pairs, extra=()) -> np.ndarray:
    """Vertices by the chapter's Algorithm 22.1 (Appendix), in the constraints' coordinates.

    Stage 1 calls it on the outward-relaxed constraints in its centred, scaled ``(p, q)``
    coordinates (``hammerbound.stage1.side_polygon``), like :func:`polygon_from_halfplanes`.

    ``pairs`` is a list of ``(h_plus, h_minus)`` constraint pairs, one per measurement, in
    processing order (the first two must have different amplitudes so that the initial
    four intersections bound the set, Remark 22.2). ``extra`` are further constraints
    (positivity) included from the start. Implemented as written: candidate vertices are
    intersections of the new boundaries with the active list H_L, filtered by the
    measurements seen so far; H_L keeps the boundaries through at least one vertex.
    Complexity O(M^2); kept as an independent check of :func:`polygon_from_halfplanes`.
    """
    pairs = list(pairs)
    seen = [pairs[0][0], pairs[0][1], pairs[1][0], pairs[1][1], *extra]
    HL = list(seen)
    V = []
    for i in range(len(HL)):
        for j in range(i + 1, len(HL)):
            p = _intersect(HL[i], HL[j])
            if p is not None:
                V.append((p, i, j))

    def filt(V, cons_list):
        A = np.array([c.a for c in cons_list])
        b = np.array([c.b for c in cons_list])
        tol = 1e-11 * (np.abs(b) + np.hypot(A[:, 0], A[:, 1]))
        P = np.array([v[0] for v in V]) if V else np.zeros((0, 2))
        ok = np.all(P @ A.T - b <= tol, axis=1) if len(V) else np.zeros(0, bool)
        return [v for v, k in zip(V, ok, strict=True) if k]

    def relabel(V, HL):
        # rebuild H_L: keep boundaries through a vertex (lines 21-27)
        used = sorted({v[1] for v in V} | {v[2] for v in V})
        pos = {old: new for new, old in enumerate(used)}
        return [(p, pos[i], pos[j]) for p, i, j in V], [HL[k] for k in used]

    V = filt(V, seen)
    V, HL = relabel(V, HL)
    for s in range(2, len(pairs)):
        hp, hm = pairs[s]
        L = len(HL)
        new = []
        for z in range(L):  # lines 10-19
            for k, h in ((L, hp), (L + 1, hm)):
                p = _intersect(h, HL[z])
                if p is not None:
                    new.append((p, z, k))
        HL = HL + [hp, hm]
        seen += [hp, hm]
        V = filt(V + new, seen)  # line 20
        V, HL = relabel(V, HL)
    if not V:
        return np.zeros((0, 2))
    P = np.array([v[0] for v in V])
    # merge duplicates (several boundaries through one vertex)
    P = P[np.lexsort((P[:, 1], P[:, 0]))]
    out = [P[0]]
    for q in P[1:]:
        if np.linalg.norm(q - out[-1]) > 1e-14 * (1 + np.linalg.norm(q)):
            out.append(q)
    return np.array(out)
