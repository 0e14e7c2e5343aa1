"""Feasible parameter sets: exact polygons (stage 1) and outer-bounding orthotopes.

Stage 1 (section 22.3): each backlash side's feasible set (22.12)/(22.13) is nonconvex
in ``(m, c)`` but, with ``beta = m c``, the model ``y = m u -+ beta`` is *linear*, so in
``(m, beta)`` coordinates it is a convex polygon (computed by :mod:`.halfplanes`). The map
``(m, beta) -> (m, c = beta / m)`` is a bijection on ``m > 0`` that maps vertices to
vertices and straight edges to hyperbolic arcs, so the extremes of ``m``, of ``c``
(linear-fractional) and of any ``a m + b beta`` are attained at vertices (Propositions
22.1 and 22.2). :class:`FeasibleSet` is the result: the set's description and its
orthotope (22.22)-(22.24) as an :class:`~hammerbound.results.IntervalSet`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..data.validation import as_theta
from ..exceptions import ParameterValidationError
from ..results import DeprecatedExtra, IntervalSet, Result, jsonable
from .halfplanes import (  # noqa: F401 - re-exported (their home before the split)
    Constraint,
    _intersect,
    algorithm_22_1,
    farkas_certificate,
    polygon_from_halfplanes,
)

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
