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

__all__ = ["Constraint", "algorithm_22_1", "farkas_certificate", "polygon_from_halfplanes"]


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
