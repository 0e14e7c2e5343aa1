"""One interval-set result for every box of the package: :class:`IntervalSet`.

A box ``[lower_k, upper_k]`` of named parameters, each end with a status
(:mod:`hammerbound.status`) and, when a solver produced it, a :class:`BoundInfo` with its
certificate or verified witness. The feasible-set orthotopes, the relaxations' results and
the estimators' interval tables are all this type (or a subclass of it), so ``center``,
``radius``, ``width``, ``contains``, the tables and the figure exist once.

**Membership tolerance** (the one rule of every ``contains``): a point ``x`` lies in the
set when, for every parameter ``k``,
``lower_k - tol max(1, |lower_k|) <= x_k <= upper_k + tol max(1, |upper_k|)``: an absolute
allowance for parameters below 1, a relative one above (like the exact method's ``tol``).
``tol = 0`` (the default) tests the closed box itself; a tolerance only ever widens it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..data.validation import as_theta
from ..exceptions import ParameterValidationError
from ..status import NOT_IDENTIFIED, OPTIMAL, check_status, describe
from .base import DeprecatedExtra, Result, jsonable

__all__ = ["BoundInfo", "DualCertificate", "IntervalSet", "VerifiedPoint", "outward_margin"]

_ENDS = ("lower", "upper")
_SENSES = ("min", "max")


def outward_margin(ends, tol: float) -> np.ndarray:
    """``tol max(1, |end|)`` element-wise (0 for ``tol = 0``, also at infinite ends)."""
    ends = np.asarray(ends, dtype=float)
    if tol == 0:
        return np.zeros_like(ends)
    with np.errstate(invalid="ignore"):
        return float(tol) * np.maximum(1.0, np.abs(ends))


@dataclass(frozen=True)
class DualCertificate:
    """How a moment bound was certified from the dual solution
    (:func:`~hammerbound.solvers.conic.verified_lower_bound`): the solver's dual value and
    the corrections subtracted from it for the PSD, residual and cone errors."""

    dual_value: float
    psd_correction: float
    residual_correction: float
    cone_correction: float


@dataclass(frozen=True, eq=False)
class VerifiedPoint:
    """A verified-feasible point of the EIV set (22.34): ``theta`` with the output errors
    ``eta`` (N,) and the input errors ``dx`` (one per input-error group) that explain the
    data within their bounds."""

    theta: np.ndarray
    eta: np.ndarray
    dx: np.ndarray


@dataclass(frozen=True, eq=False)
class BoundInfo:
    """How one end of one parameter interval was obtained.

    Attributes
    ----------
    param : str
        Parameter name (``"a1"``, ``"b2"`` ...).
    sense : {"min", "max"}
    bound : float
        The *guaranteed* bound reported to the user (a lower bound of the true minimum
        for ``"min"``, an upper bound of the true maximum for ``"max"``).
    solver_value : float
        The solver's own objective value (not guaranteed), NaN if none.
    status : str
        The solve's outcome, one of :mod:`hammerbound.status` (``OPTIMAL``,
        ``INACCURATE``: bound repaired from the dual, ``LIMIT``: time/node/iteration limit,
        outer bound still valid, ``RELAXATION``, ``INFEASIBLE``, ``FAILED``).
    certified : bool
        True when ``bound`` is backed by a rigorous certificate (dual bound with a
        rounding/infeasibility correction).
    time : float
        Wall time in seconds.
    iterations : int or None
    gap : float or None
        For the exact method: ``|bound - best verified feasible value|``.
    witness : ndarray or None
        A verified-feasible parameter vector attaining ``inner`` (exact methods).
    nodes : int or None
    message : str
    certificate : DualCertificate or None
        Moment method: the dual certificate of ``bound``.
    point : VerifiedPoint or object or None
        The verified point behind ``witness`` with the errors that explain the data (a
        :class:`VerifiedPoint`; the one-record method's own witness type there).
    inner : float or None
        The parameter's value at ``witness``: the best verified (inner) value of the end.
    """

    param: str
    sense: str
    bound: float
    solver_value: float = float("nan")
    status: str = OPTIMAL
    certified: bool = True
    time: float = 0.0
    iterations: int | None = None
    gap: float | None = None
    witness: np.ndarray | None = None
    nodes: int | None = None
    message: str = ""
    certificate: DualCertificate | None = None
    point: object = None
    inner: float | None = None

    def __post_init__(self):
        check_status(self.status)
        if self.sense not in _SENSES:
            raise ParameterValidationError(f"sense must be 'min' or 'max'; got {self.sense!r}.")

    @property
    def end(self) -> str:
        """``"lower"`` for ``sense="min"``, ``"upper"`` for ``"max"``."""
        return _ENDS[_SENSES.index(self.sense)]

    @property
    def extra(self):
        """Deprecated (removed in 0.3.0): the old ``extra`` dict, from the typed fields."""
        vals, new = {}, {}
        if self.certificate is not None:
            vals.update(asdict(self.certificate))
            new.update({k: f"BoundInfo.certificate.{k}" for k in vals})
        if isinstance(self.point, VerifiedPoint):
            vals.update({"eta": self.point.eta, "dx": self.point.dx, "value": self.inner})
            new.update({"eta": "BoundInfo.point.eta", "dx": "BoundInfo.point.dx",
                        "value": "BoundInfo.inner"})
        elif self.point is not None:
            vals["witness"], new["witness"] = self.point, "BoundInfo.point"
        return DeprecatedExtra("BoundInfo", vals, new)

    def to_dict(self) -> dict:
        """JSON-serialisable record (without ``point``: its error sequences can be long; an
        infinite ``bound`` and a NaN ``solver_value`` become ``None``)."""
        d = {k: getattr(self, k) for k in ("param", "sense", "bound", "solver_value", "status",
                                          "certified", "time", "iterations", "gap",
                                          "witness", "nodes", "message", "inner")}
        d["certificate"] = None if self.certificate is None else asdict(self.certificate)
        return jsonable(d)

    @classmethod
    def from_dict(cls, d: dict) -> BoundInfo:
        """The :class:`BoundInfo` of :meth:`to_dict` (``point`` is not kept)."""
        kw = dict(d)
        infinite = -np.inf if kw["sense"] == "min" else np.inf
        kw["bound"] = infinite if kw["bound"] is None else float(kw["bound"])
        kw["solver_value"] = float("nan") if kw.get("solver_value") is None else \
            float(kw["solver_value"])
        if kw.get("witness") is not None:
            kw["witness"] = np.asarray(kw["witness"], dtype=float)
        if kw.get("certificate") is not None:
            kw["certificate"] = DualCertificate(**kw["certificate"])
        return cls(**kw)


def _status_of(names, infos, status, bounds):
    """The ``(p, 2)`` status tuple: given, else from ``infos``, else OPTIMAL; infinite ends
    are always NOT_IDENTIFIED."""
    p = len(names)
    if status is not None:
        st = [[check_status(s) for s in pair] for pair in status]
        if len(st) != p or any(len(pair) != 2 for pair in st):
            raise ParameterValidationError(
                f"status must hold a (lower, upper) pair per parameter ({p}); got {len(st)}.")
    else:
        st = [[OPTIMAL, OPTIMAL] for _ in names]
        where = {n: k for k, n in enumerate(names)}
        for info in infos:
            st[where[info.param]][_SENSES.index(info.sense)] = info.status
    for k, e in zip(*np.nonzero(~np.isfinite(bounds)), strict=True):
        st[k][e] = NOT_IDENTIFIED
    return tuple(tuple(pair) for pair in st)


@dataclass(frozen=True, eq=False, repr=False)
class IntervalSet(Result):
    """Named parameter intervals ``[lower, upper]`` with a status per end (22.22)-(22.24), (22.35).

    Parameters
    ----------
    param_names : sequence of str
        One name per parameter (row of ``bounds``).
    bounds : array of shape (p, 2)
        Guaranteed ``[lower, upper]`` of every parameter; an infinite end means the data do
        not bound it (its status is then ``NOT_IDENTIFIED``). Stored as a read-only copy.
    status : sequence of (str, str) pairs or None
        The status of each end (:mod:`hammerbound.status`). Default: from ``infos`` when
        given, else ``OPTIMAL``.
    infos : tuple of BoundInfo
        ``2 p`` records in the order (p0 min, p0 max, p1 min, ...), or empty when no
        solver produced the ends (e.g. the exact stage-1 polygons).
    method : str
        What produced the intervals (``"lp"``, ``"moment"``, ``"exact"``, ``"polygon"``...).
    time : float
        Wall time in seconds.

    Notes
    -----
    ``contains(point, tol)`` follows the module's tolerance rule:
    ``lower - tol max(1, |lower|) <= x <= upper + tol max(1, |upper|)``.
    """

    param_names: tuple
    bounds: np.ndarray
    status: tuple | None = None
    infos: tuple = ()
    method: str = ""
    time: float = 0.0

    def __post_init__(self):
        names = tuple(str(n) for n in self.param_names)
        b = np.array(self.bounds, dtype=float)
        if b.ndim != 2 or b.shape != (len(names), 2) or np.isnan(b).any():
            raise ParameterValidationError(
                f"bounds must be a ({len(names)}, 2) array of [lower, upper] rows without "
                f"NaN, one per name in {names}; got shape {b.shape}.")
        b.setflags(write=False)
        infos = tuple(self.infos)
        if infos and len(infos) != 2 * len(names):
            raise ParameterValidationError(
                f"infos must hold 2 p = {2 * len(names)} BoundInfo; got {len(infos)}.")
        object.__setattr__(self, "param_names", names)
        object.__setattr__(self, "bounds", b)
        object.__setattr__(self, "infos", infos)
        object.__setattr__(self, "status", _status_of(names, infos, self.status, b))
        object.__setattr__(self, "time", float(self.time))

    # ------------------------------------------------------------------ the box
    def __len__(self) -> int:
        return len(self.param_names)

    @property
    def lower(self) -> np.ndarray:
        return self.bounds[:, 0]

    @property
    def upper(self) -> np.ndarray:
        return self.bounds[:, 1]

    @property
    def center(self) -> np.ndarray:
        """Central estimate (22.23): the midpoints (halves first: no overflow); NaN for
        an interval unbounded on both sides (``[-inf, inf]``: no centre)."""
        with np.errstate(invalid="ignore"):
            return 0.5 * self.bounds[:, 0] + 0.5 * self.bounds[:, 1]

    @property
    def radius(self) -> np.ndarray:
        """Uncertainty bound (22.23): the half-widths."""
        return 0.5 * self.bounds[:, 1] - 0.5 * self.bounds[:, 0]

    @property
    def width(self) -> np.ndarray:
        return self.bounds[:, 1] - self.bounds[:, 0]

    def contains(self, point, tol: float = 0.0) -> bool:
        """Whether ``point`` (shape (p,), in :attr:`param_names` order) lies in every interval.

        ``tol`` widens every end by ``tol max(1, |end|)`` (the module's one rule); a NaN
        coordinate raises :class:`~hammerbound.exceptions.DataValidationError`.
        """
        x = as_theta(point, len(self), self.param_names, name="point")
        tol = float(tol)
        if not tol >= 0:
            raise ParameterValidationError(f"tol must be a number >= 0; got {tol!r}.")
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        return bool(np.all(x >= lo - outward_margin(lo, tol))
                    and np.all(x <= hi + outward_margin(hi, tol)))

    def end_status(self, k: int, end: str) -> str:
        """Status of end ``"lower"``/``"upper"`` of parameter ``k``."""
        return self.status[k][_ENDS.index(end)]

    def ends_with(self, status: str) -> tuple:
        """Labels ``"a2 upper"`` of the ends that have ``status``."""
        return tuple(f"{n} {end}" for n, pair in zip(self.param_names, self.status, strict=True)
                     for end, s in zip(_ENDS, pair, strict=True) if s == status)

    # ------------------------------------------------------------------ tables
    def status_text(self) -> list:
        """Per parameter, the ``status`` column of the tables: ``"optimal"`` when both ends
        are, ``"not identified"`` when both are infinite, else each end that is not
        optimal with its status: not identified, set by the a priori box, recovered from
        the dual, stopped at a limit... (guaranteed in every case)."""
        out = []
        for pair in self.status:
            if all(s == NOT_IDENTIFIED for s in pair):
                out.append(describe(NOT_IDENTIFIED))
                continue
            parts = [f"{end} {describe(s)}" for end, s in zip(_ENDS, pair, strict=True)
                     if s != OPTIMAL]
            out.append("; ".join(parts) or OPTIMAL)
        return out

    def records(self) -> list:
        """One dict per parameter: ``parameter, lower, centre, upper, half_width, status``
        (the table's words) and ``lower_status``, ``upper_status`` (each end's status, one
        of :data:`hammerbound.status.STATUSES`, for programs)."""
        from ..tables import interval_records

        recs = interval_records(self.param_names, self.bounds, self.status_text())
        for rec, (lo, hi) in zip(recs, self.status, strict=True):
            rec["lower_status"], rec["upper_status"] = str(lo), str(hi)
        return recs

    def to_frame(self):
        """The table ``parameter, lower, centre, upper, half_width, status``: a pandas
        DataFrame when pandas is installed, else a numpy structured array."""
        from ..tables import interval_frame

        return interval_frame(self.param_names, self.bounds, self.status_text())

    def summary(self, title: str | None = None, assumptions=()) -> str:
        """The intervals as a fixed-width text table (under ``title``, if given), then the
        ``assumptions`` they rest on, one per line (:func:`~hammerbound.tables.assumptions_text`;
        none: the table alone)."""
        from ..tables import assumptions_text, interval_text

        table = interval_text(self.param_names, self.bounds, self.status_text(), title=title)
        return table + "\n" + assumptions_text(assumptions) if assumptions else table

    def to_dict(self) -> dict:
        """JSON-serialisable: ``param_names``, ``bounds`` (an infinite end as ``None``),
        ``status``, ``method``, ``time``, ``infos``; :meth:`from_dict` restores it."""
        return jsonable({"param_names": list(self.param_names), "bounds": self.bounds,
                         "status": [list(p) for p in self.status], "method": self.method,
                         "time": self.time, "infos": [i.to_dict() for i in self.infos]})

    @classmethod
    def from_dict(cls, d: dict) -> IntervalSet:
        """The :class:`IntervalSet` of :meth:`to_dict` (a ``None`` end is infinite)."""
        rows = [[-np.inf if lo is None else lo, np.inf if hi is None else hi]
                for lo, hi in d["bounds"]]
        infos = tuple(BoundInfo.from_dict(i) for i in d.get("infos", ()))
        return IntervalSet(tuple(d["param_names"]), np.array(rows, dtype=float).reshape(-1, 2),
                           tuple(tuple(p) for p in d["status"]), infos, d.get("method", ""),
                           d.get("time", 0.0))

    # ------------------------------------------------------------------ figure
    def plot(self, ax=None, *, true_values=None, label=None, normalise=None):
        """Horizontal interval bars (:func:`hammerbound.plotting.plot_intervals`); returns
        the Axes."""
        from ..plotting import plot_intervals

        return plot_intervals(self.bounds, list(self.param_names), ax, true_values=true_values,
                              labels=[label or self.method or "intervals"],
                              normalise=normalise)

    # ------------------------------------------------------------------ combining
    @classmethod
    def stack(cls, *sets, method: str = "") -> IntervalSet:
        """One set of the parameters of ``sets`` in turn (``infos`` kept when all have them)."""
        keep = all(s.infos for s in sets)
        return IntervalSet(sum((s.param_names for s in sets), ()),
                           np.vstack([s.bounds for s in sets]),
                           sum((s.status for s in sets), ()),
                           sum((s.infos for s in sets), ()) if keep else (), method,
                           sum(s.time for s in sets))

    def __str__(self) -> str:
        return ", ".join(f"{n} in [{lo:.6g}, {hi:.6g}]"
                         for n, (lo, hi) in zip(self.param_names, self.bounds, strict=True))

    def __repr__(self) -> str:
        how = f"; {self.method}" if self.method else ""
        return f"{type(self).__name__}({self}{how})"
