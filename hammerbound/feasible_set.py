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
from dataclasses import dataclass, field

import numpy as np

from .validation import as_theta

__all__ = [
    "Constraint",
    "Edge",
    "FeasibleSet",
    "PolygonFeasibleSet",
    "algorithm_22_1",
    "polygon_from_halfplanes",
]


@dataclass(frozen=True)
class Constraint:
    """A half-plane ``a . p <= b`` with its origin.

    ``index`` is the measurement index (in the caller's data) and ``sign`` is ``"+"`` for
    the boundary ``y + Delta eta`` (h^+ of (22.14)) and ``"-"`` for ``y - Delta eta`` (h^-,
    (22.15)); positivity constraints have ``index=None`` and ``sign`` ``"m>=0"``/``"c>=0"``.
    """

    a: tuple
    b: float
    index: int | None
    sign: str

    @property
    def label(self) -> str:
        return self.sign if self.index is None else f"h{self.sign}[{self.index}]"


@dataclass(frozen=True)
class Edge:
    """Edge of a polygon (Definition 22.4): the part of ``constraint`` between two vertices."""

    constraint: Constraint
    start: np.ndarray
    end: np.ndarray


@dataclass(frozen=True)
class FeasibleSet:
    """A parameter set with an outer-bounding orthotope (22.22)-(22.24).

    Attributes
    ----------
    param_names : tuple of str
    orthotope : ndarray of shape (p, 2)
        Tight (when ``exact``) or outer interval of every parameter.
    exact : bool
        True when ``vertices``/``edges`` describe the set exactly.
    vertices : ndarray of shape (n_vertices, p) or None
    edges : tuple of Edge
    polytopes : tuple
        Optional outer polytopes ``(A, b)`` with ``A theta <= b`` (their union contains the set).
    """

    param_names: tuple
    orthotope: np.ndarray
    exact: bool = False
    vertices: np.ndarray | None = None
    edges: tuple = ()
    polytopes: tuple = ()
    extra: dict = field(default_factory=dict)

    @property
    def center(self) -> np.ndarray:
        """Central estimate gamma^c / theta^c (22.23)."""
        return self.orthotope.mean(axis=1)

    @property
    def radius(self) -> np.ndarray:
        """Uncertainty bound Delta gamma (22.23)."""
        return 0.5 * (self.orthotope[:, 1] - self.orthotope[:, 0])

    def _intervals_repr(self) -> str:
        return ", ".join(f"{n} in [{lo:.6g}, {hi:.6g}]"
                         for n, (lo, hi) in zip(self.param_names, self.orthotope, strict=False))

    def __repr__(self) -> str:
        extra = f", {len(self.polytopes)} outer polytope(s)" if self.polytopes else ""
        return (f"FeasibleSet({self._intervals_repr()}; exact={self.exact}{extra})")

    def contains(self, params, tol: float = 0.0) -> bool:
        """Whether ``params`` lies in the orthotope (exact sets override this)."""
        p = as_theta(params, self.orthotope.shape[0], self.param_names, name="params")
        return bool(np.all(p >= self.orthotope[:, 0] - tol) and np.all(p <= self.orthotope[:, 1] + tol))


@dataclass(frozen=True)
class PolygonFeasibleSet(FeasibleSet):
    """Exact feasible set of one backlash side, (22.12) or (22.13).

    ``vertices`` are in ``(m, c)`` coordinates (counter-clockwise in ``(m, beta)``);
    ``vertices_mb`` in ``(m, beta = m c)``; ``constraints`` are the half-planes in
    ``(m, beta)``; ``sigma`` is ``-1`` for the right side (``y = m u - beta``) and ``+1``
    for the left side (``y = m u + beta``).
    """

    side: str = "right"
    sigma: float = -1.0
    vertices_mb: np.ndarray | None = None
    constraints: tuple = ()

    def __repr__(self) -> str:
        nv = 0 if self.vertices is None else len(self.vertices)
        return (f"PolygonFeasibleSet(side={self.side!r}, {self._intervals_repr()}; "
                f"{nv} vertices, {len(self.edges)} edges)")

    def contains(self, params, tol: float = 1e-12) -> bool:
        """Exact membership of ``(m, c)`` in the set (not just in the orthotope)."""
        m, c = as_theta(params, 2, self.param_names, name="params")
        p = np.array([m, m * c])
        A = np.array([k.a for k in self.constraints])
        b = np.array([k.b for k in self.constraints])
        scale = 1.0 + np.abs(b)
        return bool(np.all(A @ p - b <= tol * scale))

    def linear_range(self, coef_m: float, coef_beta: float) -> tuple[float, float]:
        """Exact ``min``/``max`` of ``coef_m m + coef_beta beta`` over the set (at vertices)."""
        v = self.vertices_mb @ np.array([coef_m, coef_beta])
        return float(v.min()), float(v.max())

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
        """Draw the set in ``(m, c)`` (curved edges), its vertices and orthotope."""
        from .plotting import plot_feasible_set

        return plot_feasible_set(self, ax=ax, true_params=true_params,
                                 show_orthotope=show_orthotope, **kwargs)


# --------------------------------------------------------------------------------------
# exact 2-D half-plane intersection
# --------------------------------------------------------------------------------------
def _intersect(c1: Constraint, c2: Constraint):
    a1, a2 = np.asarray(c1.a), np.asarray(c2.a)
    det = a1[0] * a2[1] - a1[1] * a2[0]
    if det == 0:
        return None
    x = (c1.b * a2[1] - a1[1] * c2.b) / det
    y = (a1[0] * c2.b - c1.b * a2[0]) / det
    return np.array([x, y])


def _tol(cons: Constraint) -> float:
    return 1e-12 * (abs(cons.b) + np.hypot(*cons.a))


def _outside(cons: Constraint, p) -> bool:
    return cons.a[0] * p[0] + cons.a[1] * p[1] > cons.b + _tol(cons)


def polygon_from_halfplanes(constraints) -> tuple[np.ndarray, list] | None:
    """Exact intersection of half-planes ``a . p <= b`` (bounded result assumed).

    Returns ``(vertices, edge_constraints)`` with vertices counter-clockwise and
    ``edge_constraints[k]`` the constraint carrying the edge from vertex ``k`` to ``k+1``,
    or ``None`` if the intersection is empty (or of zero area).
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
        if last is not None and abs(ang[i] - ang[last]) <= 1e-15:
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
    if len(dq) < 3:
        return None
    hs = list(dq)
    verts = []
    for k in range(len(hs)):
        p = _intersect(hs[k], hs[(k + 1) % len(hs)])
        if p is None:
            return None
        verts.append(p)
    verts = np.array(verts)
    # every vertex must satisfy every constraint (guards against degenerate/empty cases)
    A = np.array([c.a for c in cons])
    b = np.array([c.b for c in cons])
    scale = np.abs(b) + np.hypot(A[:, 0], A[:, 1])
    viol = (verts @ A.T - b) / scale
    if np.max(viol) > 1e-9:
        return None
    # vertex k sits between hs[k] and hs[k+1]; the edge from vertex k-1 to k lies on hs[k]
    edge_cons = [hs[(k + 1) % len(hs)] for k in range(len(hs))]
    # drop zero-length edges (several constraints through one vertex)
    keep_v, keep_e = [], []
    n = len(verts)
    for k in range(n):
        nxt = verts[(k + 1) % n]
        if np.linalg.norm(nxt - verts[k]) > 1e-14 * (1 + np.linalg.norm(verts[k])):
            keep_v.append(verts[k])
            keep_e.append(edge_cons[k])
    if len(keep_v) < 3:
        return None
    area = 0.5 * np.sum(
        np.array(keep_v)[:, 0] * np.roll(np.array(keep_v)[:, 1], -1)
        - np.roll(np.array(keep_v)[:, 0], -1) * np.array(keep_v)[:, 1]
    )
    if area <= 0:
        return None
    return np.array(keep_v), keep_e


def algorithm_22_1(pairs, extra=()) -> np.ndarray:
    """Vertices by the chapter's Algorithm 22.1 (Appendix), in ``(m, beta)`` coordinates.

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
        if np.linalg.norm(q - out[-1]) > 1e-12 * (1 + np.linalg.norm(q)):
            out.append(q)
    return np.array(out)
