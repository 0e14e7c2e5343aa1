"""Exact 2-D half-plane intersection for the stage-1 polygons.

With ``beta = m c`` each backlash side's feasible set is the intersection of the slabs
``|y_s - m u_s +- beta| <= Delta eta_s`` and of ``m >= 0, beta >= 0`` (R_+^2), a convex
polygon in ``(m, beta)``. :func:`polygon_from_halfplanes` computes it exactly (sort by
angle + deque, O(M log M)); :func:`algorithm_22_1` is the chapter's incremental procedure
(Appendix), kept as an independent cross-check; :func:`farkas_certificate` proves an empty
intersection in exact arithmetic.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

__all__ = ["Constraint", "algorithm_22_1", "edge_support", "farkas_certificate",
           "polygon_from_halfplanes"]


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


def _excess(cons: Constraint, p) -> float:
    """``a . p - b`` in units of its rounding (``16 eps`` of the terms' magnitudes)."""
    a0, a1, b = float(cons.a[0]), float(cons.a[1]), float(cons.b)
    x, y = float(p[0]), float(p[1])
    return (a0 * x + a1 * y - b) / (16 * _EPS * ((abs(a0) + abs(a1)) * (abs(x) + abs(y))
                                                  + abs(b)) or 1.0)


def _turns_left(c1: Constraint, c2: Constraint) -> bool:
    """The boundary of ``c2`` turns left from that of ``c1`` by less than 180 degrees."""
    return float(c1.a[0]) * float(c2.a[1]) - float(c1.a[1]) * float(c2.a[0]) > 0


def _drop(h: Constraint, p, before: Constraint, after: Constraint) -> bool:
    """Whether the deque of :func:`polygon_from_halfplanes` drops the line between
    ``before`` and ``after`` whose vertex with its neighbour is ``p`` (None: parallel).

    Dropped when ``p`` is outside ``h`` beyond rounding, and also when ``p`` is on ``h``'s
    line to rounding, unless ``before`` and ``after`` would then turn by 180 degrees or
    more (a segment or a point, whose antiparallel boundaries must stay apart). In doubt
    the line goes: a needed line dropped by rounding only enlarges the polygon by a sliver
    of rounding size (outward), while keeping every line of a pencil of nearly concurrent
    ones (noise at ``+Delta`` on every sample) kept a cluster of ~M vertices within
    rounding of one point, and the tightness check then cost O(M^2) time and memory.
    """
    if p is None:
        return True
    e = _excess(h, p)
    return e > 1.0 or (e >= -1.0 and _turns_left(before, after))


def _max_violation(A, b, P, chunk: int = 64) -> float:
    """Largest violation of ``A p <= b`` over the rows of ``P``, relative to ``|a| |p| + |b|``.

    Evaluated ``chunk`` points at a time: memory O(chunk * len(A)), not O(len(P) len(A)).
    """
    absA = np.abs(A).sum(axis=1)
    absb = np.abs(b)
    worst = -np.inf
    for k in range(0, P.shape[0], chunk):
        Q = P[k : k + chunk]
        scale = np.abs(Q).sum(axis=1)[:, None] * absA + absb
        v = (Q @ A.T - b) / np.where(scale > 0, scale, 1.0)
        worst = max(worst, float(np.max(v)))
    return worst


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
        while len(dq) >= 2 and _drop(h, _intersect(dq[-1], dq[-2]), dq[-2], h):
            dq.pop()
        while len(dq) >= 2 and _drop(h, _intersect(dq[0], dq[1]), h, dq[1]):
            dq.popleft()
        if dq:
            a1, a2 = np.asarray(dq[-1].a), np.asarray(h.a)
            if a1[0] * a2[1] - a1[1] * a2[0] <= 0:
                # turned by >= 180 degrees: consecutive parallel/anti-parallel planes
                if _intersect(dq[-1], h) is None:
                    return None
        dq.append(h)
    while len(dq) >= 3 and _drop(dq[0], _intersect(dq[-1], dq[-2]), dq[-2], dq[0]):
        dq.pop()
    while len(dq) >= 3 and _drop(dq[-1], _intersect(dq[0], dq[1]), dq[-1], dq[1]):
        dq.popleft()
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


def _merge_vertices(V):
    """Merge the vertices ``(point, lines, cond)`` of ``V`` that coincide to the rounding
    of their computation: one point per cluster, carrying the union of the clusters' lines.

    ``cond`` is ``1 / sin`` of the angle between the two lines that made the point: its
    error along them is about ``eps |p| cond`` (:func:`_intersect`). A point merges into a
    better-conditioned one within ``max(_VERTEX_ROUNDING, 16 eps cond)`` of the largest
    coordinate (at most :data:`_MERGE_CAP`): nearly parallel boundaries through one vertex
    (consecutive amplitudes, noise at ``+Delta``) otherwise leave copies of it a few
    ``1e-13`` apart, each keeping its boundaries alive.
    """
    if len(V) <= 1:
        return V
    V = sorted(V, key=lambda v: v[2])
    P = np.array([v[0] for v in V])
    mag = 1.0 + float(np.max(np.abs(P)))
    radius = mag * np.minimum(np.maximum(_VERTEX_ROUNDING, 16 * _EPS * np.array(
        [v[2] for v in V])), _MERGE_CAP)
    dist = np.max(np.abs(P[:, None, :] - P[None, :, :]), axis=2)
    reps: list = []
    for i, (p, lines, cond) in enumerate(V):
        near = next((r for r in reps if dist[i, r[3]] <= radius[i]), None)
        if near is not None:
            near[1].update(lines)
            continue
        reps.append((p, set(lines), cond, i))
    return [(p, lines, cond) for p, lines, cond, _ in reps]


#: Largest merge radius (relative) of :func:`_merge_vertices`, for the worst-conditioned
#: intersections; the polygon is verified afterwards (:func:`edge_support`).
_MERGE_CAP = 1e-9


def _cond(c1: Constraint, c2: Constraint) -> float:
    """``1 / sin`` of the angle between two boundaries (``inf`` if parallel)."""
    a10, a11 = float(c1.a[0]), float(c1.a[1])
    a20, a21 = float(c2.a[0]), float(c2.a[1])
    s = abs(a10 * a21 - a11 * a20) / (np.hypot(a10, a11) * np.hypot(a20, a21))
    return 1.0 / s if s > 0 else np.inf


def _edge_lines_only(V, HL):
    """The vertices ``(point, lines)`` of ``V`` (merged, :func:`_merge_vertices`) with only
    the lines of ``HL`` that carry an edge between neighbouring vertices.

    A boundary through a single vertex of a convex polygon touches it there only, and
    every later set is a subset: it can never carry an edge again, so dropping it from H_L
    loses no vertex. Neighbours that share two or more lines are copies of one vertex
    (made by different, nearly parallel pairs a few 1e-13 apart) and count as one. The
    edge between two neighbours is carried by the lines that made both; if they share
    none, by those of their lines that pass through both to :data:`_EDGE_RESIDUAL`, else
    by all their lines. With fewer than three vertices ``V`` is returned unchanged. The
    caller verifies the final polygon (:func:`edges_supported`): this only saves time.
    """
    if len(V) < 3:
        return V
    P = np.array([v[0] for v in V])
    c0 = P.mean(axis=0)
    order = np.argsort(np.arctan2(P[:, 1] - c0[1], P[:, 0] - c0[0])).tolist()
    groups = [[order[0]]]
    for i in order[1:]:
        if len(V[groups[-1][-1]][1] & V[i][1]) >= 2:
            groups[-1].append(i)
        else:
            groups.append([i])
    if len(groups) > 1 and len(V[groups[-1][-1]][1] & V[groups[0][0]][1]) >= 2:
        groups[0] = groups.pop() + groups[0]
    if len(groups) < 3:
        return V
    lines = [set().union(*(V[i][1] for i in g)) for g in groups]
    keep = set()
    for a in range(len(groups)):
        b = (a + 1) % len(groups)
        shared = lines[a] & lines[b]
        if not shared:
            ends = (P[groups[a][-1]], P[groups[b][0]])
            shared = {k for k in lines[a] | lines[b]
                      if all(_residual(HL[k], q) <= _EDGE_RESIDUAL for q in ends)}
            shared = shared or (lines[a] | lines[b])
        keep |= shared
    return [(p, ls & keep, c) for p, ls, c in V]


def _residual(cons: Constraint, p) -> float:
    """``|a . p - b|`` relative to ``|a| |p| + |b|``."""
    a0, a1, b = float(cons.a[0]), float(cons.a[1]), float(cons.b)
    x, y = float(p[0]), float(p[1])
    return abs(a0 * x + a1 * y - b) / ((abs(a0) + abs(a1)) * (abs(x) + abs(y)) + abs(b) or 1.0)


#: Relative residual up to which a line counts as passing through a vertex when the edge
#: lines of Algorithm 22.1 are chosen geometrically (:func:`_edge_lines_only`): generous,
#: since keeping a line too many only costs time.
_EDGE_RESIDUAL = 1e-10


def edge_support(V, constraints, chunk: int = 64) -> float:
    """Largest, over the edges ``V[k] -> V[k+1]`` of a polygon (vertices in order), of the
    smallest relative residual of a constraint line at both ends of the edge.

    Small (rounding) when every edge lies on a constraint boundary: then the polygon is the
    intersection of those constraints' half-planes (it contains the set they define). A
    vertex of the set missing from ``V`` leaves a chord that lies on no boundary, with a
    residual of the order of the missing vertex's depth. ``inf`` for fewer than 3 vertices.
    """
    V = np.asarray(V, dtype=float)
    if V.shape[0] < 3:
        return np.inf
    A = np.array([c.a for c in constraints], dtype=float)
    b = np.array([c.b for c in constraints], dtype=float)
    absA, absb = np.abs(A).sum(axis=1), np.abs(b)
    W = np.roll(V, -1, axis=0)
    worst = 0.0
    for k in range(0, V.shape[0], chunk):
        r = np.zeros((V[k : k + chunk].shape[0], A.shape[0]))
        for E in (V[k : k + chunk], W[k : k + chunk]):
            scale = np.abs(E).sum(axis=1)[:, None] * absA + absb
            r = np.maximum(r, np.abs(E @ A.T - b) / np.where(scale > 0, scale, 1.0))
        worst = max(worst, float(np.max(np.min(r, axis=1))))
    return worst


def algorithm_22_1(pairs, extra=(), prune: bool = True) -> np.ndarray:
    """Vertices by the chapter's Algorithm 22.1 (Appendix), in the constraints' coordinates.

    Stage 1 calls it on the outward-relaxed constraints in its centred, scaled ``(p, q)``
    coordinates (``hammerbound.stage1.side_polygon``), like :func:`polygon_from_halfplanes`.

    ``pairs`` is a list of ``(h_plus, h_minus)`` constraint pairs, one per measurement, in
    processing order (the first two must have different amplitudes so that the initial
    four intersections bound the set, Remark 22.2). ``extra`` are further constraints
    (positivity) included from the start. Implemented as written: candidate vertices are
    intersections of the new boundaries with the active list H_L, filtered by the
    measurements seen so far; H_L keeps the boundaries through at least one vertex.

    Three additions for sets with many boundaries through one vertex (noise at ``+Delta``
    on every sample makes every lower boundary of a side pass through the true point; M =
    500 gave no answer in 200 s): vertices that coincide to rounding
    (:data:`_VERTEX_ROUNDING`) are merged after every step, each keeping the boundaries of
    all its copies; H_L keeps only the boundaries that carry an edge
    (:func:`_edge_lines_only`); and the filter allows rounding only (the constraints come
    already relaxed outward by the callers' tolerance; a filter as wide as that tolerance
    let hundreds of intersections just outside a set of the tolerance's width survive).
    ``prune=False`` keeps every boundary through a vertex (the procedure as written; the
    caller falls back to it when :func:`edge_support` does not confirm a pruned result).
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
                V.append((p, {i, j}, _cond(HL[i], HL[j])))

    # the constraints seen so far as arrays, filled as they come (rows of ``seen``)
    n_all = len(seen) + 2 * (len(pairs) - 2)
    A_seen, b_seen = np.empty((n_all, 2)), np.empty(n_all)
    A_seen[: len(seen)] = [c.a for c in seen]
    b_seen[: len(seen)] = [c.b for c in seen]

    def filt(V, n):
        if not V:
            return V
        A, b = A_seen[:n], b_seen[:n]
        P = np.array([v[0] for v in V])
        # rounding slack only (_VERTEX_ROUNDING of the terms): the constraints are already
        # relaxed outward by the callers' tolerance
        tol = _VERTEX_ROUNDING * (np.abs(P).sum(axis=1)[:, None] * np.abs(A).sum(axis=1)
                                  + np.abs(b))
        ok = np.all(P @ A.T - b <= tol, axis=1)
        return _merge_vertices([v for v, k in zip(V, ok, strict=True) if k])

    def relabel(V, HL):
        # rebuild H_L: keep boundaries through a vertex (lines 21-27)
        if prune:
            V = _edge_lines_only(V, HL)
        used = sorted(set().union(*(v[1] for v in V)))
        pos = {old: new for new, old in enumerate(used)}
        return [(p, {pos[i] for i in lines}, c) for p, lines, c in V], [HL[k] for k in used]

    n = len(seen)
    V = filt(V, n)
    V, HL = relabel(V, HL)
    for s in range(2, len(pairs)):
        hp, hm = pairs[s]
        L = len(HL)
        new = []
        for z in range(L):  # lines 10-19
            for k, h in ((L, hp), (L + 1, hm)):
                p = _intersect(h, HL[z])
                if p is not None:
                    new.append((p, {z, k}, _cond(h, HL[z])))
        HL = HL + [hp, hm]
        A_seen[n : n + 2] = (hp.a, hm.a)
        b_seen[n : n + 2] = (hp.b, hm.b)
        n += 2
        V = filt(V + new, n)  # line 20
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
