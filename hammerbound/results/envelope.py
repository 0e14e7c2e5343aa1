"""The guaranteed one-step output band as a result: :class:`OutputEnvelope`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Result, jsonable
from .intervals import outward_margin

__all__ = ["OutputEnvelope"]


@dataclass(frozen=True, eq=False, repr=False)
class OutputEnvelope(Result):
    """Guaranteed one-step-ahead band ``lower_t <= w_t <= upper_t`` of the noise-free output.

    Unpacks like the pair it used to be: ``lower, upper = est.one_step_envelope(x, y)``
    (also ``env[0]``, ``env[1]``).

    Attributes
    ----------
    lower, upper : ndarray of shape (N,)
        The band; NaN before the first sample that has one (the recursion's start).
    y : ndarray of shape (N,) or None
        The measured output the band was computed from.
    output_bound : ndarray of shape (N,) or None
        Its error bound: a measurement lies within ``output_bound`` of the band.
    """

    lower: np.ndarray
    upper: np.ndarray
    y: np.ndarray | None = None
    output_bound: np.ndarray | None = None

    def __post_init__(self):
        for name in ("lower", "upper", "y", "output_bound"):
            v = getattr(self, name)
            if v is not None:
                v = np.array(v, dtype=float)
                v.setflags(write=False)
                object.__setattr__(self, name, v)

    # the old ``(lower, upper)`` tuple
    def __iter__(self):
        return iter((self.lower, self.upper))

    def __getitem__(self, k):
        return (self.lower, self.upper)[k]

    def __len__(self) -> int:
        return 2

    @property
    def banded(self) -> np.ndarray:
        """Samples that have a band (the first ones start the recursion)."""
        return np.isfinite(self.lower) & np.isfinite(self.upper)

    @property
    def center(self) -> np.ndarray:
        return 0.5 * self.lower + 0.5 * self.upper

    @property
    def width(self) -> np.ndarray:
        return self.upper - self.lower

    def contains(self, w, tol: float = 0.0) -> np.ndarray:
        """Per sample, whether ``w_t`` (shape (N,)) lies in the band (``True`` where there is
        none); ``tol`` widens each end by ``tol max(1, |end|)`` as every ``contains``."""
        w = np.asarray(w, dtype=float)
        lo = np.where(self.banded, self.lower, -np.inf)
        hi = np.where(self.banded, self.upper, np.inf)
        return (w >= lo - outward_margin(lo, tol)) & (w <= hi + outward_margin(hi, tol))

    def coverage(self) -> float:
        """Fraction of the banded samples whose measurement lies within the band widened by
        its output error bound (1.0 for a true model and noise within the bound)."""
        if self.y is None or self.output_bound is None:
            return float("nan")
        b = self.banded
        d = self.output_bound[b]
        y = self.y[b]
        return float(np.mean((y >= self.lower[b] - d) & (y <= self.upper[b] + d)))

    def summary(self) -> str:
        b = self.banded
        w = self.width[b]
        head = (f"one-step output envelope: {b.size} samples, {int(b.sum())} with a band "
                f"(the first {int((~b).sum())} start the recursion)")
        if not w.size:
            return head
        text = (f"{head}\nband width: min {w.min():.4g}, median {np.median(w):.4g}, "
                f"max {w.max():.4g}")
        cov = self.coverage()
        if np.isfinite(cov):
            text += f"\nmeasurements within band +- output bound: {cov:.3f}"
        return text

    def to_dict(self) -> dict:
        """``lower``, ``upper`` (``None`` where there is no band), ``coverage``."""
        return jsonable({"lower": self.lower, "upper": self.upper,
                         "coverage": self.coverage()})

    def plot(self, ax=None, *, t=None, center=None, label="data", dt=None, time_unit=""):
        """The band with the measured output (and a ``center`` line) over ``t``, else over
        time ``k * dt`` when a sampling time ``dt`` is given, else over the sample index;
        returns the Axes."""
        from ..plotting import plot_envelope

        xlabel = "sample t"
        if t is None and dt is not None:
            t, xlabel = np.arange(self.lower.size) * dt, f"time {time_unit}".strip()
        t = np.arange(self.lower.size) if t is None else t
        return plot_envelope(t, self.y, self.lower, self.upper, ax, center=center, label=label,
                             xlabel=xlabel)
