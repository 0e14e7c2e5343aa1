"""Which backlash branch every sample is on, for *all* parameters in a box.

The backlash (22.1) in its well-posed region is the play operator
``x_t = max(R_t, min(L_t, x_{t-1}))`` with the lines ``R_t = m_r (u_t - c_r) = m_r u_t - d_r``
and ``L_t = m_l (u_t + c_l) = m_l u_t + d_l`` (``d = m c``). Along a record, ``x_t`` is always
one of

* ``R(s)``: the right line at an earlier (or the same) input ``u_s``, ``m_r u_s - d_r``;
* ``L(s)``: the left line at ``u_s``, ``m_l u_s + d_l``;
* ``INIT``: the unknown first value ``z0 = x_0`` (any point of the band ``[R_0, L_0]``),

each *linear* in ``beta = (m_l, d_l, m_r, d_r, z0)``. :func:`inner_structure` runs the play
operator symbolically over a box of ``(m_l, c_l, m_r, c_r, z0)``: a sample gets one of those
forms only when it is the same for every parameter in the box (decided by exact comparisons
of inputs or by interval bounds with an outward margin); otherwise it becomes an
*ambiguous* value ``V(k)``, a variable with an interval envelope and the linear inequalities
that hold on every branch (:class:`Ambiguous`). Later samples that hold it share it. The
ambiguity shrinks with the box: the play operator is continuous in its parameters, so the
envelopes shrink to points.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..systems.models import play_lines

__all__ = ["INIT", "LEFT", "RIGHT", "AMBIG", "UP", "DOWN", "HOLD", "Ambiguous", "Decided",
           "InnerStructure", "band_range", "inner_structure", "line_range", "line_ranges"]

INIT, RIGHT, LEFT, AMBIG = 0, 1, 2, 3
#: branches a sample can be *decided* to take (see :class:`Decided`)
UP, DOWN, HOLD = "up", "down", "hold"
# relative margin of the interval decisions (far above rounding, far below any data scale)
_MARGIN = 1e-12


def line_range(u, m, c, sign):
    """Range of ``m (u + sign c)`` over ``m in [m0, m1]``, ``c in [c0, c1]`` (bilinear:
    extremes at the corners). ``sign = +1``: left line; ``-1``: right line."""
    v = [mm * (u + sign * cc) for mm in m for cc in c]
    lo, hi = min(v), max(v)
    pad = _MARGIN * (abs(lo) + abs(hi) + abs(u) * max(m) + 1e-300)
    return lo - pad, hi + pad


def line_ranges(u, m, c, sign):
    """:func:`line_range` for an array of inputs ``u`` (arrays ``lo, hi``; the same
    corners and margin, element by element)."""
    u = np.asarray(u, dtype=float)
    v = np.stack([mm * (u + sign * cc) for mm in m for cc in c])
    lo, hi = v.min(axis=0), v.max(axis=0)
    pad = _MARGIN * (np.abs(lo) + np.abs(hi) + np.abs(u) * max(m) + 1e-300)
    return lo - pad, hi + pad


def band_range(u, gamma_box) -> tuple[float, float]:
    """Where an inner value can be at input ``u`` for every backlash in ``gamma_box``
    (rows ``m_l, c_l, m_r, c_r``): from the lowest right line ``R`` to the highest left
    line ``L`` (the play operator keeps every value in the band ``[R, L]``)."""
    g = np.asarray(gamma_box, dtype=float)
    return line_range(u, g[2], g[3], -1.0)[0], line_range(u, g[0], g[1], 1.0)[1]


@dataclass(frozen=True)
class Ambiguous:
    """A sample whose branch depends on the parameters: ``x_t = max(R_t, min(L_t, S))``.

    Attributes
    ----------
    t : int
        The sample.
    lo, hi : float
        Interval envelope of ``x_t`` over the box (monotone interval extension).
    src_kind, src : int
        The state ``S`` before the sample (its kind and index, as in
        :class:`InnerStructure`).
    up, down : bool
        Whether moving up (``x_t = R_t > S``) and moving down (``x_t = L_t < S``) are still
        possible. ``not up`` gives ``x_t <= S``; ``not down`` gives ``x_t >= S``.
    """

    t: int
    lo: float
    hi: float
    src_kind: int
    src: int
    up: bool
    down: bool


@dataclass(frozen=True)
class Decided:
    """A sample whose branch a branch-and-bound node fixes: ``branch`` is ``UP``
    (``x_t = R_t >= S``), ``DOWN`` (``x_t = L_t <= S``) or ``HOLD`` (``R_t <= S <= L_t``,
    ``x_t = S``), with ``S`` the state before it (``src_kind, src`` as in
    :class:`InnerStructure`). Every parameter point takes one of the three (ties take
    two), so the children of a sample cover the node; the node's relaxation holds the
    branch's inequalities (:func:`~.relaxation.build_relaxation`)."""

    t: int
    branch: str
    src_kind: int
    src: int


@dataclass(frozen=True)
class InnerStructure:
    """The symbolic inner signal over a box (see the module docstring).

    ``kind[t]`` is one of ``INIT, RIGHT, LEFT, AMBIG``; ``src[t]`` the sample ``s`` of
    ``R(s)``/``L(s)``, the index ``k`` of ``ambiguous[k]``, or -1 for ``INIT``;
    ``decided`` the samples whose branch was given (:class:`Decided`).
    """

    kind: np.ndarray
    src: np.ndarray
    ambiguous: tuple
    decided: tuple = ()

    @property
    def n_ambiguous(self) -> int:
        return len(self.ambiguous)

    def key(self) -> tuple:
        """Hashable form (two boxes with equal keys give LPs of the same structure)."""
        return (self.kind.tobytes(), self.src.tobytes(),
                tuple((a.t, a.src_kind, a.src, a.up, a.down) for a in self.ambiguous),
                tuple((d.t, d.branch, d.src_kind, d.src) for d in self.decided))


class _Pass:
    """State of the symbolic forward pass."""

    def __init__(self, u, box, decisions=None):
        self.u = u
        self.ml, self.cl, self.mr, self.cr, self.z0 = (tuple(map(float, box[i])) for i in range(5))
        self.amb = []
        self.decisions = dict(decisions or {})
        self.decided = []

    def decide(self, t, kind, src):
        """The state after sample ``t`` on its given branch (recorded for the rows)."""
        branch = self.decisions[t]
        self.decided.append(Decided(t, branch, kind, src))
        if branch == UP:
            return RIGHT, t
        if branch == DOWN:
            return LEFT, t
        return kind, src

    def R(self, t):  # noqa: N802 - the chapter's line names
        return line_range(self.u[t], self.mr, self.cr, -1.0)

    def L(self, t):  # noqa: N802
        return line_range(self.u[t], self.ml, self.cl, 1.0)

    def state_range(self, kind, src):
        if kind == RIGHT:
            return self.R(src)
        if kind == LEFT:
            return self.L(src)
        if kind == INIT:
            return self.z0
        a = self.amb[src]
        return a.lo, a.hi

    def band_source(self, kind, src):
        """Input ``u_k`` of the band ``[R_k, L_k]`` that holds the state (every state lies
        in the band of the sample it was set at)."""
        if kind in (RIGHT, LEFT):
            return self.u[src]
        if kind == INIT:
            return self.u[0]
        return self.u[self.amb[src].t]

    def diff_range(self, t, kind, src, line):
        """Range of ``line_t - S`` where ``line`` is "R" or "L", using that the state ``S``
        lies in its band ``[R_k, L_k]``: ``R_t - S <= R_t - R_k``, ``L_t - S >= L_t - L_k``."""
        uk = self.band_source(kind, src)
        slo, shi = self.state_range(kind, src)
        if line == "R":
            lo_t, hi_t = self.R(t)
            # upper: R_t - S <= min(hi_t - slo, m_r (u_t - u_k))   (S >= R_k)
            up_line = max(m * (self.u[t] - uk) for m in self.mr)
            lo_line = -np.inf
            if kind == RIGHT:  # S = R_k exactly
                lo_line = min(m * (self.u[t] - uk) for m in self.mr)
            return max(lo_t - shi, lo_line), min(hi_t - slo, up_line)
        lo_t, hi_t = self.L(t)
        lo_line = min(m * (self.u[t] - uk) for m in self.ml)  # S <= L_k
        hi_line = np.inf
        if kind == LEFT:
            hi_line = max(m * (self.u[t] - uk) for m in self.ml)
        return max(lo_t - shi, lo_line), min(hi_t - slo, hi_line)

    def step(self, t, kind, src):
        """Branch of sample ``t`` from the state ``(kind, src)``: the new state."""
        if t in self.decisions:
            return self.decide(t, kind, src)
        u = self.u
        if kind == RIGHT and u[t] >= u[src]:
            return (RIGHT, t) if u[t] > u[src] else (kind, src)
        if kind == LEFT and u[t] <= u[src]:
            return (LEFT, t) if u[t] < u[src] else (kind, src)
        r_lo, r_hi = self.diff_range(t, kind, src, "R")
        l_lo, l_hi = self.diff_range(t, kind, src, "L")
        if r_lo >= 0.0:  # R_t >= S for every parameter: moves up
            return RIGHT, t
        if l_hi <= 0.0:  # L_t <= S: moves down
            return LEFT, t
        up, down = r_hi > 0.0, l_lo < 0.0
        if not up and not down:  # R_t <= S <= L_t: holds
            return kind, src
        (rl, rh), (ll, lh) = self.R(t), self.L(t)
        slo, shi = self.state_range(kind, src)
        lo = max(rl, min(ll, slo))
        hi = max(rh, min(lh, shi))
        self.amb.append(Ambiguous(t, lo, hi, kind, src, up, down))
        return AMBIG, len(self.amb) - 1


def inner_structure(u, box, decisions=None) -> InnerStructure:
    """Symbolic play operator over ``box`` (rows ``m_l, c_l, m_r, c_r, z0``; ``z0 = x_0``).

    Sound for every parameter in the box with ``L_t >= R_t`` on the record (well-posed):
    a sample is given the form ``R(s)``, ``L(s)`` or ``INIT`` only if the play operator gives
    it for all of them (exact input comparisons, or interval bounds with an outward
    margin); everything else is ambiguous. ``decisions`` (``{t: UP | DOWN | HOLD}``, samples
    whose input changes) fix branches: the structure then stands for the parameters of the
    box that take them (:class:`Decided`; a decision the box contradicts makes the node's
    relaxation infeasible, never wrong).
    """
    u = np.asarray(u, dtype=float)
    box = np.asarray(box, dtype=float)
    n = u.size
    kind = np.empty(n, dtype=np.int64)
    src = np.empty(n, dtype=np.int64)
    ps = _Pass(u, box, decisions)
    state = (INIT, -1)
    kind[0], src[0] = state
    for t in range(1, n):
        if u[t] != u[t - 1]:  # the same input keeps the same value (clamp is idempotent)
            state = ps.step(t, *state)
        kind[t], src[t] = state
    return InnerStructure(kind, src, tuple(ps.amb), tuple(ps.decided))


def play(u, ml, cl, mr, cr, z0) -> np.ndarray:
    """The play operator from ``x_0 = z0`` (inside the band ``[R_0, L_0]``): the point
    evaluation the symbolic pass stands for (used for witnesses and local search)."""
    u = np.asarray(u, dtype=float)
    return play_lines(mr * (u - cr), ml * (u + cl), z0)


def branch_forms(u, ml, cl, mr, cr, z0) -> tuple[np.ndarray, np.ndarray]:
    """The exact form (``kind, src``, no ambiguity) of every sample at one parameter point:
    which line (at which input) or ``INIT`` gives ``x_t``. Ties go to holding the state."""
    u = np.asarray(u, dtype=float)
    n = u.size
    kind = np.empty(n, dtype=np.int64)
    src = np.empty(n, dtype=np.int64)
    x = float(min(max(z0, mr * (u[0] - cr)), ml * (u[0] + cl)))
    state = (INIT, -1)
    kind[0], src[0] = state
    for t in range(1, n):
        r, lv = mr * (u[t] - cr), ml * (u[t] + cl)
        if r > x:
            x, state = r, (RIGHT, t)
        elif lv < x:
            x, state = lv, (LEFT, t)
        kind[t], src[t] = state
    return kind, src


def inner_envelope(u, gamma_box, z0=None) -> tuple[np.ndarray, np.ndarray]:
    """Guaranteed per-sample bounds ``[lo_t, hi_t]`` of the inner signal for every backlash
    in ``gamma_box`` (rows ``m_l, c_l, m_r, c_r``) and every first value ``z0`` in
    ``z0 = (lo, hi)`` (default: anywhere in the band ``[R_0, L_0]``).

    The play operator is nondecreasing in ``R_t``, ``L_t`` and the previous value, so two
    forward passes with the lower and the upper ends give the bounds (interval extension
    with outward margins).
    """
    u = np.asarray(u, dtype=float)
    g = np.asarray(gamma_box, dtype=float)
    R = [line_range(v, g[2], g[3], -1.0) for v in u.tolist()]
    L = [line_range(v, g[0], g[1], 1.0) for v in u.tolist()]
    lo = np.empty(u.size)
    hi = np.empty(u.size)
    a, b = band_range(float(u[0]), g) if z0 is None else (float(z0[0]), float(z0[1]))
    for t in range(u.size):
        a = max(R[t][0], min(L[t][0], a))
        b = max(R[t][1], min(L[t][1], b))
        lo[t], hi[t] = a, b
    return lo, hi
