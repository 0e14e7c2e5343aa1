"""Backlash compensation: the classic right-inverse and its guaranteed residual error.

The backlash (22.1) is the play operator ``x_t = min(max(x_t-1, R(u_t)), L(u_t))`` with
``R(u) = m_r u - beta_r`` and ``L(u) = m_l u + beta_l`` (``beta = m c``). Its classic
inverse (Tao & Kokotovic) built from the *central* estimate ``(m^, c^)`` commands

* ``u_t = v_t / m^_r + c^_r`` when the desired inner signal rises (``v_t > v_t-1``),
* ``u_t = v_t / m^_l - c^_l`` when it falls, and ``u_t = u_t-1`` when it is constant,

so that ``x = v`` exactly if the true backlash is the central one.

**Guaranteed residual.** For a true backlash ``(m_l, beta_l, m_r, beta_r)`` let
``dR(v) = R(v/m^_r + c^_r) - v`` and ``dL(v) = L(v/m^_l - c^_l) - v`` (affine in ``v``,
slopes ``m/m^ - 1 > -1``). If the backlash is well posed (``R(u) <= L(u)``) at every
``u`` the compensator emits, then for every ``t`` the error ``e_t = x_t - v_t`` satisfies::

    min(dL(v_t), dR(v_t), e_init) <= e_t <= max(dL(v_t), dR(v_t), e_init)

where ``e_init = x_-1 - x0`` is the mismatch between the true initial inner state and
the one the compensator assumes (0 for a system at rest with ``x0 = 0``). Proof by
induction: on a rising step ``e_t = max(e_t-1 - dv, dR(v_t))`` (clipped below ``L``, which
is above ``R``), and ``dL, dR`` change by less than ``dv`` when ``v`` moves by ``dv``; falling
steps are symmetric; constant steps keep ``x``. For fixed ``v``, ``dR`` and ``dL`` are
*linear* in ``(m, beta)``, so their extremes over the exact polygons sit at vertices:
:meth:`BacklashInverse.error_bounds` is exact for the two branches and guaranteed for
every command sequence in the declared range.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..data.validation import as_real, as_signal
from ..exceptions import (
    DataValidationError,
    DataWarning,
    IllPosedBacklashError,
    ParameterValidationError,
)
from ..results import Result, jsonable

__all__ = ["BacklashCompensator", "BacklashInverse", "build_inverse"]


def _signal(v):
    """Commanded values: a number or a 1-D array (:func:`~hammerbound.data.validation.as_signal`)."""
    return as_signal("v", [v] if np.ndim(v) == 0 and isinstance(v, (int, float, np.number))
                     else v)


@dataclass(frozen=True, repr=False)
class BacklashInverse(Result):
    """Backlash-inverse compensator with a guaranteed residual error band.

    Attributes
    ----------
    gamma : ndarray (4,)
        Central ``(m_l, c_l, m_r, c_r)`` the inverse is built from.
    left_vertices, right_vertices : ndarray (k, 2)
        Vertices ``(m, beta)`` of the exact feasible polygons.
    v_range : (float, float)
        Command range over which the guarantee was established (well-posedness checked).
    x0 : float
        Inner state the compensator assumes at start.
    u_range : (float, float)
        Range of the inputs the compensator can emit.
    """

    gamma: np.ndarray
    left_vertices: np.ndarray
    right_vertices: np.ndarray
    v_range: tuple
    x0: float
    u_range: tuple

    # ---------------------------------------------------------------- compensator
    def _u_rise(self, v):
        return v / self.gamma[2] + self.gamma[3]

    def _u_fall(self, v):
        return v / self.gamma[0] - self.gamma[1]

    @property
    def u_init(self) -> float:
        """Input assumed at start: the middle of the central dead band around ``x0``."""
        return float(0.5 * (self._u_rise(self.x0) + self._u_fall(self.x0)))

    def _check_range(self, v):
        lo, hi = self.v_range
        span = hi - lo
        if np.any(v < lo - 1e-12 * (1 + span)) or np.any(v > hi + 1e-12 * (1 + span)):
            raise DataValidationError(
                f"v leaves the command range {self.v_range} the guarantee was built for: "
                "saturate the command to it (np.clip(v, *inverse.v_range)), or build "
                "inverse(v_range=...) with a wider range, which works only as far as every "
                "backlash of the set stays well posed (else IllPosedBacklashError: narrow "
                "the backlash intervals first, e.g. with more data)."
            )

    def compensate(self, v) -> np.ndarray:
        """Backlash input ``u`` that makes the central backlash output the commanded ``v``.

        ``v`` is a whole command *sequence*: every call starts again from :attr:`x0` (the
        branch of each step depends on the previous command). In a control loop, one
        command at a time, use :meth:`compensator` and its ``step(v)``; a single number
        given here is treated as a sequence of length one, with a warning.
        """
        if np.ndim(v) == 0:
            warnings.warn(
                "compensate() takes a command sequence and starts from x0 at every call, so "
                "called once per sample it picks the branch from the sign of v - x0, not "
                "from the direction of the command. In a loop use c = inverse.compensator() "
                "and u_t = c.step(v_t).", DataWarning, stacklevel=2)
        v = _signal(v)
        self._check_range(v)
        c = self.compensator()
        return np.array([c._advance(vt) for vt in v], dtype=float).reshape(v.shape)

    __call__ = compensate

    def compensator(self) -> BacklashCompensator:
        """A stateful compensator for a control loop: ``u_t = c.step(v_t)``, one command at
        a time, from :attr:`x0` (``c.reset()`` starts again). It emits what
        :meth:`compensate` emits for the same sequence, so :meth:`error_bounds` holds."""
        return BacklashCompensator(self)

    # ---------------------------------------------------------------- guarantee
    def branch_errors(self, v) -> dict:
        """Exact ranges of ``dR(v)`` (rising branch) and ``dL(v)`` (falling branch) over the
        feasible polygons: ``{"rise": (lo, hi), "fall": (lo, hi)}``, arrays of v's shape."""
        v = _signal(v)
        ml, cl, mr, cr = self.gamma
        R, L = self.right_vertices, self.left_vertices
        dR = R[None, :, 0] * (v[:, None] / mr + cr) - R[None, :, 1] - v[:, None]
        dL = L[None, :, 0] * (v[:, None] / ml - cl) + L[None, :, 1] - v[:, None]
        pad = 1e-12 * (1 + np.abs(v))  # outward rounding margin
        return {"rise": (dR.min(axis=1) - pad, dR.max(axis=1) + pad),
                "fall": (dL.min(axis=1) - pad, dL.max(axis=1) + pad)}

    def error_bounds(self, v, initial_error=0.0) -> tuple[np.ndarray, np.ndarray]:
        """Guaranteed ``(lo, hi)`` with ``lo <= x_t - v_t <= hi`` whenever ``v_t = v``.

        Valid for every backlash in the feasible set and every command sequence inside
        :attr:`v_range`. ``initial_error`` bounds ``x_-1 - x0`` (a number, or a pair
        ``(lo, hi)``); the default 0 is a system at rest at ``x0``.
        """
        v = _signal(v)
        self._check_range(v)
        e = np.atleast_1d(np.asarray(initial_error, dtype=float))
        if e.size not in (1, 2) or not np.all(np.isfinite(e)):
            raise ParameterValidationError("initial_error must be a number or a pair (lo, hi).")
        b = self.branch_errors(v)
        lo = np.minimum(np.minimum(b["rise"][0], b["fall"][0]), e.min())
        hi = np.maximum(np.maximum(b["rise"][1], b["fall"][1]), e.max())
        return lo, hi

    def error_bound(self, v, initial_error=0.0) -> np.ndarray:
        """Guaranteed ``max |x - v|`` at command ``v``."""
        lo, hi = self.error_bounds(v, initial_error)
        return np.maximum(np.abs(lo), np.abs(hi))

    def summary(self) -> str:
        """The central backlash, the command range and the guaranteed error over it."""
        from ..tables import rounded_text

        v = np.linspace(self.v_range[0], self.v_range[1], 201)
        lo, hi = self.error_bounds(v)
        ml, cl, mr, cr = self.gamma
        return (f"backlash inverse of ml={ml:.4g} cl={cl:.4g} mr={mr:.4g} cr={cr:.4g}, "
                f"from x0 = {self.x0:g}\n"
                f"commands v in [{self.v_range[0]:.4g}, {self.v_range[1]:.4g}], inputs u in "
                f"[{self.u_range[0]:.4g}, {self.u_range[1]:.4g}]\n"
                f"guaranteed residual x - v in [{rounded_text(lo.min(), down=True)}, "
                f"{rounded_text(hi.max(), down=False)}] over the "  # rounded outward
                "command range (every feasible backlash)")

    def to_dict(self) -> dict:
        """JSON-serialisable: ``gamma``, the ranges, ``x0``, the polygons' vertices and the
        guaranteed error band on 201 commands across ``v_range``."""
        v = np.linspace(self.v_range[0], self.v_range[1], 201)
        lo, hi = self.error_bounds(v)
        return jsonable({"gamma": self.gamma, "v_range": self.v_range, "x0": self.x0,
                         "u_range": self.u_range, "left_vertices": self.left_vertices,
                         "right_vertices": self.right_vertices,
                         "error_band": {"v": v, "lower": lo, "upper": hi}})

    def plot(self, ax=None, **kwargs):
        """Figure: backlash band and compensated characteristic (see ``modelset.plots``);
        ``ax`` a pair of Axes or None; returns the Figure."""
        from .plots import plot_compensation

        return plot_compensation(self, ax=ax, **kwargs)


def _wellposed_margin(left_mb, right_mb, u):
    """max over the sets of R(u) - L(u) (<= 0: every feasible backlash well posed at u)."""
    return (np.max(right_mb[:, 0] * u - right_mb[:, 1])
            + np.max(-left_mb[:, 0] * u - left_mb[:, 1]))


class BacklashCompensator:
    """The compensator of a :class:`BacklashInverse` with its state, one command at a time
    (made by :meth:`BacklashInverse.compensator`).

    Attributes
    ----------
    inverse : BacklashInverse
    v_prev, u : float
        The last command and the input emitted for it (at start: ``x0`` and
        :attr:`BacklashInverse.u_init`).
    """

    def __init__(self, inverse: BacklashInverse):
        self.inverse = inverse
        self.reset()

    def reset(self) -> None:
        """Back to the start: the inner signal at ``x0``, the input in its dead band."""
        self.v_prev, self.u = float(self.inverse.x0), self.inverse.u_init

    def step(self, v) -> float:
        """The input for the next command ``v`` (a number inside ``inverse.v_range``)."""
        v = as_real("v", v, example="0.1", error=DataValidationError)
        self.inverse._check_range(np.array([v]))
        return self._advance(v)

    def _advance(self, v: float) -> float:
        """Rising command: the right branch; falling: the left one; constant: hold."""
        if v > self.v_prev:
            self.u = float(self.inverse._u_rise(v))
        elif v < self.v_prev:
            self.u = float(self.inverse._u_fall(v))
        self.v_prev = float(v)
        return self.u

    def __repr__(self) -> str:
        return f"BacklashCompensator(v_prev={self.v_prev:g}, u={self.u:g})"


def _u_range(gamma, v_lo, v_hi, x0):
    ml, cl, mr, cr = gamma
    cands = [v_lo / mr + cr, v_hi / mr + cr, v_lo / ml - cl, v_hi / ml - cl,
             0.5 * (x0 / mr + cr + x0 / ml - cl)]
    return float(min(cands)), float(max(cands))


def build_inverse(estimator, v_range=None, x0=0.0) -> BacklashInverse:
    """The compensator of a fitted :class:`~hammerbound.BacklashSetEstimator` (see
    :func:`build_inverse_from`)."""
    return build_inverse_from(estimator.gamma_center_, estimator.left_.vertices_mb,
                              estimator.right_.vertices_mb, estimator.input_range_,
                              v_range=v_range, x0=x0)


def build_inverse_from(gamma_center, left_vertices_mb, right_vertices_mb, input_range,
                       v_range=None, x0=0.0) -> BacklashInverse:
    """The compensator of a backlash set given by the vertices of (a convex superset of)
    each side's set in ``(m, beta = m c)`` and a central backlash.

    The guarantee needs *every* feasible backlash well posed (``R(u) <= L(u)``) at every
    input the compensator emits; the condition is convex in ``u``, so it is checked at
    the two ends of the input range, on the vertices. ``v_range`` defaults to the central
    inner-signal range of the data's input range ``input_range``
    (``[m^_l (u_min + c^_l), m^_r (u_max - c^_r)]``), shrunk by a common factor until that
    check passes; an explicit ``v_range`` that fails it raises.
    """
    gamma = np.asarray(gamma_center, dtype=float)
    ml, cl, mr, cr = gamma
    u_lo_data, u_hi_data = input_range
    L, R = left_vertices_mb, right_vertices_mb
    try:
        x0 = float(x0)
    except (TypeError, ValueError) as exc:
        raise ParameterValidationError(f"x0 must be a number; got {x0!r}.") from exc

    def ok(lo, hi):
        return all(_wellposed_margin(L, R, u) <= 0 for u in _u_range(gamma, lo, hi, x0))

    if v_range is None:
        d_lo, d_hi = ml * (u_lo_data + cl), mr * (u_hi_data - cr)
        if ok(d_lo, d_hi):
            v_range = (d_lo, d_hi)
        else:
            a, b = 0.0, 1.0
            for _ in range(60):
                mid = 0.5 * (a + b)
                a, b = (mid, b) if ok(x0 + mid * (d_lo - x0), x0 + mid * (d_hi - x0)) else (a, mid)
            if a == 0.0:
                raise IllPosedBacklashError(
                    "no command range around x0 keeps every backlash of the set well posed "
                    "(some feasible backlash has its two lines crossing wherever the "
                    "compensator would drive the input): the set is too wide for a "
                    "guaranteed inverse. Narrow the backlash intervals (more data, a "
                    "narrower gamma_box), or pass a v_range of your own to see where it "
                    "fails.")
            v_range = (x0 + a * (d_lo - x0), x0 + a * (d_hi - x0))
    try:
        v_lo, v_hi = (float(x) for x in v_range)
    except (TypeError, ValueError) as exc:
        raise ParameterValidationError(f"v_range must be a pair (v_min, v_max); got {v_range!r}.") from exc
    if not (np.isfinite(v_lo) and np.isfinite(v_hi) and v_lo < v_hi):
        raise ParameterValidationError(f"v_range must be finite with v_min < v_max; got {v_range!r}.")
    if not (np.isfinite(x0) and v_lo <= x0 <= v_hi):
        raise ParameterValidationError(f"x0 must lie in v_range {v_range}; got {x0!r}.")
    u_range = _u_range(gamma, v_lo, v_hi, x0)
    if not ok(v_lo, v_hi):
        raise IllPosedBacklashError(
            f"the compensator would drive the backlash input over {u_range}, where some "
            "feasible backlash is past the crossing of its two lines ((22.1) ill-posed), so "
            f"no error bound can be guaranteed. Narrow v_range (now {(v_lo, v_hi)})."
        )
    return BacklashInverse(gamma, np.asarray(L, float), np.asarray(R, float), (v_lo, v_hi),
                           x0, u_range)
