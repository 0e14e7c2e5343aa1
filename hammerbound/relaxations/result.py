"""The result of every stage-2 bounding method: :class:`IntervalResult`, an
:class:`~hammerbound.results.IntervalSet` with what the method learnt on the way, in typed
fields (the LP result behind a moment or exact result, the LP's polytopes, the hull of the
verified witnesses, the root box, the method's size figures)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..results.base import DeprecatedExtra
from ..results.intervals import BoundInfo, DualCertificate, IntervalSet, VerifiedPoint
from ..status import BOX

__all__ = ["BoundInfo", "DualCertificate", "ExactDetails", "IntervalResult", "IntervalSet",
           "LPDetails", "MomentDetails", "Polytope", "VerifiedPoint"]


@dataclass(frozen=True, eq=False)
class Polytope:
    """One sign orthant's part of the polytopic outer set: ``{theta : A theta <= b}``
    (the box, the orthant and the gain equality are rows of it)."""

    signs: np.ndarray
    A: np.ndarray
    b: np.ndarray


@dataclass(frozen=True)
class LPDetails:
    """Size of the polytopic LP: sign orthants inside the box, and feasible ones."""

    n_orthants: int
    n_feasible_orthants: int


@dataclass(frozen=True)
class MomentDetails:
    """Size of the moment relaxation and how it was solved."""

    order: int
    basis: str
    solver: str
    n_moments: int
    n_psd_blocks: int
    psd_sides: dict
    nnz: int
    n_cliques: int
    build_time: float
    eliminated: str | None
    n_rows: int


@dataclass(frozen=True)
class ExactDetails:
    """The exact method's working set: equations in it at the end (None: all, no working set)."""

    working_set: int | None


def _frozen(a):
    if a is None:
        return None
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False, repr=False)
class IntervalResult(IntervalSet):
    """Parameter uncertainty intervals (22.35) from one method.

    An :class:`~hammerbound.results.IntervalSet` (``bounds`` of shape ``(p, 2)``, ``infos``
    with ``2 p`` :class:`BoundInfo` in the order (p0 min, p0 max, p1 min, ...), a status
    per end) and, as typed fields:

    Attributes
    ----------
    lp : IntervalResult or None
        The polytopic LP result the method started from (moment, exact).
    polytopes : tuple of Polytope
        LP: one per feasible sign orthant; their union contains the feasible set.
    inner : ndarray of shape (p, 2) or None
        Exact: the hull of the verified witnesses of the ends (NaN where none).
    root_box : ndarray or None
        Exact: the OBBT box the search started from; one record: the box of every
        variable of the problem after OBBT.
    pool : tuple
        One record: the verified points found on the way (seeds for sampling).
    details : LPDetails, MomentDetails, ExactDetails or None
        The method's size figures.
    """

    lp: IntervalResult | None = None
    polytopes: tuple = ()
    inner: np.ndarray | None = None
    root_box: np.ndarray | None = None
    pool: tuple = ()
    details: object = None

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "polytopes", tuple(self.polytopes))
        object.__setattr__(self, "inner", _frozen(self.inner))
        object.__setattr__(self, "root_box", _frozen(self.root_box))
        object.__setattr__(self, "pool", tuple(self.pool))

    @property
    def extra(self):
        """Deprecated (removed in 0.3.0): the old ``extra`` dict, from the typed fields."""
        vals, new = {}, {}

        def put(key, value, attr):
            vals[key], new[key] = value, f"IntervalResult.{attr}"

        if self.lp is not None:
            put("lp", self.lp, "lp")
        if self.polytopes:
            put("polytopes", [{"signs": q.signs, "A": q.A, "b": q.b} for q in self.polytopes],
                "polytopes")
        if self.inner is not None:
            put("inner", self.inner, "inner")
        if self.root_box is not None:  # "box" and "pool": the one-record method's keys
            put("root_box", self.root_box, "root_box")
            put("box", self.root_box, "root_box")
            put("pool", self.pool, "pool")
        if self.details is not None:
            for k, v in asdict(self.details).items():
                put(k, v, f"details.{k}")
        put("box_limited", list(self.ends_with(BOX)), "ends_with(hammerbound.status.BOX)")
        return DeprecatedExtra("IntervalResult", vals, new)
