"""The certified uncertainty weight as a result (:class:`UncertaintyWeight`) and its proof
(:class:`WeightCertificate`); computed by :mod:`.uncertainty`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..results import Result, jsonable

__all__ = ["UncertaintyWeight", "WeightCertificate"]


@dataclass(frozen=True)
class WeightCertificate:
    """Proof that ``|W| >= deviation`` on every interval of a grid covering ``[0, pi/dt]``.

    ``omega`` is the proof grid (uniform, with some intervals bisected), ``deviation``
    the exact bound at its points, ``deviation_between[k]`` bounds the deviation on
    ``[omega_k, omega_k+1]`` and ``weight_lower[k]`` bounds ``|W|`` from below there;
    ``holds`` is ``all(weight_lower >= deviation_between)`` and ``min_ratio`` the smallest
    ratio.
    """

    omega: np.ndarray
    deviation: np.ndarray
    deviation_between: np.ndarray
    weight_lower: np.ndarray
    holds: bool
    min_ratio: float


@dataclass(frozen=True, repr=False)
class UncertaintyWeight(Result):
    """A certified uncertainty weight.

    Attributes
    ----------
    W : control.TransferFunction
        Stable, minimum-phase weight with the data's sampling time.
    kind : {"multiplicative", "additive"}
    central : control.TransferFunction
        The central model ``G0`` the uncertainty is measured around.
    omega, deviation : ndarray
        Fit grid (in :attr:`frequency_unit`) and the exact deviation bound there.
    certificate : WeightCertificate
        The proof over all frequencies (``certificate.holds`` is always True for a
        returned weight).
    excess_db : float
        The selection criterion: mean over-bound ``mean 20 log10(|W| / deviation)`` on
        ``omega`` in dB (deviation floored at ``1e-6`` of its maximum); the smallest of
        all certified candidates.
    frequency_unit : str
        Unit of ``omega`` and ``certificate.omega``: ``"rad/s"`` (rad per unit of the
        sampling time) or ``"rad/sample"`` when no sampling time is known.
    on_gain_plane : bool
        True: the bound holds for the models of the set *on the gain plane* (22.8) (every
        feasible model), around a central model on that plane; not for box points off it.
    """

    W: object
    kind: str
    central: object
    omega: np.ndarray
    deviation: np.ndarray
    certificate: WeightCertificate
    excess_db: float = float("nan")
    frequency_unit: str = "rad/s"
    on_gain_plane: bool = False

    @property
    def order(self) -> int:
        """Order of ``W`` (degree of its denominator)."""
        return int(np.ravel(np.asarray(self.W.den[0][0])).size - 1)

    @property
    def poles(self):
        return np.asarray(self.W.poles())

    @property
    def zeros(self):
        return np.asarray(self.W.zeros())

    @property
    def dt(self) -> float:
        """The period of ``z = e^{j omega dt}``: ``W``'s sampling time, 1 (a sample) when
        it is not known."""
        dt = self.W.dt
        return 1.0 if dt is True or dt is None else float(dt)

    def magnitude(self, omega=None) -> np.ndarray:
        """``|W(e^{j omega dt})|`` (default: on :attr:`omega`)."""
        w = self.omega if omega is None else np.asarray(omega, dtype=float)
        return np.abs(self.W(np.exp(1j * w * self.dt)))

    def summary(self) -> str:
        """The weight, its kind and order, the proof and the over-bound."""
        c = self.certificate
        rel = "|G/G0 - 1|" if self.kind == "multiplicative" else "|G - G0|"
        where = (" on the gain plane (every model with the steady-state gain)"
                 if self.on_gain_plane else "")
        return (f"{self.kind} uncertainty weight of order {self.order}: {rel} <= |W| at every "
                f"frequency, for every model of the set{where}\n"
                f"G0 = .central = {_tf_text(self.central)} (design against this model: "
                "the bound holds around it, not around another central model)\n"
                f"W = {_tf_text(self.W)}\n"
                f"proof: {c.omega.size} grid points on [0, {c.omega[-1]:.4g}] "
                f"{self.frequency_unit}, smallest |W| / deviation bound {c.min_ratio:.4g} "
                f"(holds: {c.holds})\n"
                f"mean over-bound on the fit grid: {self.excess_db:.3g} dB")

    def to_dict(self) -> dict:
        """JSON-serialisable: kind, order, ``W``'s numerator/denominator and ``dt``, the
        central model ``G0`` the bound holds around (``central``: numerator, denominator;
        on the gain plane it is not the box centre), poles and zeros as ``[re, im]``, the
        fit grid, deviation and ``|W|``, the proof."""
        c = self.certificate
        num, den = num_den(self.W)
        g0_num, g0_den = num_den(self.central)
        g0 = {"num": g0_num, "den": g0_den, "variable": "z"}
        return jsonable({
            "kind": self.kind, "order": self.order, "num": num, "den": den, "central": g0,
            "dt": None if self.W.dt is True else self.W.dt,
            "poles": [[z.real, z.imag] for z in self.poles],
            "zeros": [[z.real, z.imag] for z in self.zeros],
            "frequency_unit": self.frequency_unit, "on_gain_plane": self.on_gain_plane,
            "omega": self.omega,
            "deviation": self.deviation, "magnitude": self.magnitude(),
            "excess_db": self.excess_db,
            "certificate": {"holds": c.holds, "min_ratio": c.min_ratio,
                            "n_points": int(c.omega.size)}})

    def plot(self, ax=None, *, db=True):
        """``|W|`` over the exact deviation bound on the fit grid; returns the Axes."""
        from .plots import plot_weight

        return plot_weight(self, ax, db=db)


def num_den(tf) -> tuple:
    """The numerator and denominator coefficients of a SISO transfer function (float
    arrays, highest power of z first)."""
    return tuple(np.ravel(np.asarray(c[0][0], dtype=float)) for c in (tf.num, tf.den))


def _tf_text(W) -> str:
    num, den = num_den(W)
    return (f"({' '.join(f'{v:+.4g}' for v in num)}) / ({' '.join(f'{v:+.4g}' for v in den)})"
            " in powers of z, highest first")
