"""Guaranteed frequency-response envelope of every model in a parameter orthotope.

The linear block is ``G(z) = B(z) / A(z)`` with ``A = 1 + sum_i a_i z^-i`` and
``B = sum_j b_j z^-j``. Over the orthotope the ``a``'s and ``b``'s are *separate*
coordinates, so at ``z = e^{j w dt}`` the value sets ``Z_A`` of ``A`` and ``Z_B`` of ``B``
are independent 2-D zonotopes (:mod:`.zonotope`) and the set of responses is exactly
``{b / a : a in Z_A, b in Z_B}``. Hence, **exactly** (up to an outward rounding margin):

* ``max |G| = max |Z_B| / min |Z_A|`` (max modulus at a zonotope vertex, min modulus =
  distance from 0 to the convex zonotope; ``inf`` when ``0 in Z_A``);
* ``min |G| = min |Z_B| / max |Z_A|``;
* ``arg G - arg G0`` ranges over ``[min arg Z_B - max arg Z_A, max arg Z_B - min arg Z_A]``
  (arguments relative to the centres ``B0``, ``A0`` of the zonotopes, i.e. to the central
  model ``G0 = B0/A0``) when 0 is outside both zonotopes; otherwise the phase is
  unbounded (reported as NaN with ``phase_bounded = False``).

**Between grid frequencies.** For every coefficient vector in the box,
``|d/dw P(e^{jw dt})| <= L_P = dt sum_k k max(|lo_k|, |hi_k|)``, so ``max |Z_P|`` and
``min |Z_P|`` are ``L_P``-Lipschitz in ``w``. On ``[w_k, w_k+1]`` (width ``h``) this gives
``max |Z_B| <= (M_k + M_k+1)/2 + L_B h/2`` and ``min |Z_A| >= (m_k + m_k+1)/2 - L_A h/2``,
hence guaranteed bounds on ``|G|`` over the whole interval
(:attr:`FrequencyEnvelope.mag_upper_between` / ``mag_lower_between``), and with
``|d arg G / dw| <= L_B/min|B| + L_A/min|A|`` on the phase (``phase_*_between``).
:meth:`FrequencyEnvelope.refine` bisects the intervals where these differ from the grid
values by more than a relative tolerance.

**On the gain plane.** A box cannot express the steady-state gain equality (22.8)
``B(1) = g A(1)`` that every feasible model satisfies, so at low frequencies the box's
models spread where the feasible ones do not. With ``gain=g`` the magnitude bounds are
intersected with bounds valid on the box *intersected with* that hyperplane: eliminating
the last ``b_L`` (and dropping its interval, an outer step) gives ``G = N/D`` with ``N``
and ``D`` affine in the remaining coordinates but both depending on ``a``; the ``a``-box
is cut into sub-boxes and on each one ``max|Z_N| / min|Z_D|`` (decoupled, outward)
bounds ``|G|``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field, replace

import numpy as np

from ..exceptions import DataValidationError, DataWarning, ParameterValidationError
from ..results import Result, jsonable
from .gain_plane import plane_numerator, plane_numerator_lipschitz
from .zonotope import Zonotopes, value_sets

__all__ = ["FrequencyEnvelope", "frequency_envelope", "default_omega", "denominators_stable"]


def default_omega(dt: float, n: int = 512) -> np.ndarray:
    """``n`` log-spaced frequencies from ``1e-3`` of Nyquist to Nyquist ``pi/dt`` (in rad per
    unit of ``dt``)."""
    nyq = np.pi / dt
    return np.logspace(np.log10(1e-3 * nyq), np.log10(nyq), n)


def check_omega(omega, dt, unit="rad/s"):
    """Validated, sorted, finite, non-negative frequencies (in ``unit``: rad/s, or
    rad/sample with ``dt = 1`` when the data have no sampling time)."""
    if not (isinstance(dt, (int, float, np.floating, np.integer)) and np.isfinite(dt) and dt > 0):
        raise ParameterValidationError(f"dt must be a finite sampling time > 0; got {dt!r}.")
    if omega is None:
        return default_omega(float(dt))
    try:
        w = np.asarray(omega, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DataValidationError(f"omega must be an array of frequencies in rad/s; got {omega!r}.") from exc
    w = np.atleast_1d(w)
    if w.ndim != 1 or w.size == 0 or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise DataValidationError(
            "omega must be a non-empty 1-D array of finite frequencies >= 0 (rad/s)."
        )
    if np.any(np.diff(w) <= 0):
        raise DataValidationError("omega must be strictly increasing; sort it (np.unique).")
    nyq = np.pi / float(dt)
    if w[-1] > nyq * (1 + 1e-12):
        import warnings

        where = ("pi rad/sample (no sampling time)" if unit == "rad/sample" else
                 f"pi/dt = {nyq:g} {unit} (dt = {float(dt):g} {unit.split('/')[-1]})")
        warnings.warn(
            f"omega reaches {w[-1]:g} {unit}, above the Nyquist frequency {where}: a "
            "sampled system's response repeats there (it is that of an alias frequency), "
            "so those bounds hold but tell nothing new; keep omega at or below Nyquist.",
            DataWarning, stacklevel=3)
    return w


def _lipschitz(lo, hi, lags, dt):
    return float(dt * np.sum(np.asarray(lags, float) * np.maximum(np.abs(lo), np.abs(hi))))


@dataclass(frozen=True, repr=False)
class FrequencyEnvelope(Result):
    """Guaranteed bounds on ``G(e^{j w dt})`` for every parameter vector in a box.

    Attributes
    ----------
    omega : ndarray (n,)
        Frequencies in rad/s (``z = e^{j omega dt}``).
    dt : float
    mag_lower, mag_upper : ndarray (n,)
        Bounds on ``|G|`` at each frequency (exact over the box, widened by rounding).
        ``mag_upper`` is ``inf`` where some ``A`` in the box vanishes on the unit circle.
    phase_lower, phase_upper : ndarray (n,)
        Bounds on the phase in radians, on the branch of the (unwrapped) central phase
        :attr:`phase_central`; NaN where ``phase_bounded`` is False.
    phase_bounded : bool ndarray (n,)
        False where 0 lies in the value set of ``A`` or of ``B``: the phase can take any
        value there.
    central : complex ndarray (n,)
        Response of the central model ``G0`` (centre of the box).
    num_abs, den_abs : ndarray (n, 2)
        ``[min, max]`` of ``|B|`` and ``|A|`` over the box.
    mag_lower_between, mag_upper_between : ndarray (n - 1,)
        Bounds on ``|G|`` valid on the *whole* interval ``[omega_k, omega_k+1]``.
    phase_lower_between, phase_upper_between : ndarray (n - 1,)
        Same for the phase (NaN where not bounded).
    frequency_unit : str
        Unit of ``omega``: ``"rad/s"`` (rad per unit of ``dt``, e.g. ``"rad/ms"``) or
        ``"rad/sample"`` when no sampling time is known (then ``dt`` is 1 sample).
    signal_names, signal_units : tuple of str
        ``(input, output)`` names and units of the data (labels of :meth:`plot`).
    """

    omega: np.ndarray
    dt: float
    mag_lower: np.ndarray
    mag_upper: np.ndarray
    phase_lower: np.ndarray
    phase_upper: np.ndarray
    phase_bounded: np.ndarray
    central: np.ndarray
    num_abs: np.ndarray
    den_abs: np.ndarray
    mag_lower_between: np.ndarray
    mag_upper_between: np.ndarray
    phase_lower_between: np.ndarray
    phase_upper_between: np.ndarray
    _spec: dict = field(default=None, repr=False)
    frequency_unit: str = "rad/s"
    signal_names: tuple = ("u", "y")
    signal_units: tuple = ("", "")

    @property
    def phase_central(self) -> np.ndarray:
        """Unwrapped phase of the central model (rad)."""
        return np.unwrap(np.angle(self.central))

    @property
    def mag_central(self) -> np.ndarray:
        return np.abs(self.central)

    def contains(self, response, *, rtol: float = 0.0) -> np.ndarray:
        """Whether complex responses (shape (..., n)) lie in the envelope, per frequency.

        ``response`` may also be a discrete SISO python-control model (``TransferFunction``
        or ``StateSpace``): its response at ``z = e^{j omega dt}`` is tested. The phase is
        compared relative to the central model (``angle(G / G0)``) and modulo ``2 pi``: it
        is inside when one of its values ``angle(G / G0) + 2 pi k`` lies in the bounds (a
        range relative to ``G0`` can reach past ``+-pi``; the test compared the principal
        value only and rejected models inside the envelope, new-user trial 12).
        """
        from ..data.validation import as_real

        want = ("rtol must be a finite number >= 0 (it widens the bounds; a negative one "
                "would narrow them)")
        rtol = as_real("rtol", rtol, want=want)
        if rtol < 0:
            raise ParameterValidationError(f"{want}; got {rtol!r}.")
        r = np.asarray(self._response_of(response), dtype=complex)
        mag = np.abs(r)
        ok = (mag >= self.mag_lower * (1 - rtol)) & (mag <= self.mag_upper * (1 + rtol))
        rel = np.angle(r / self.central)
        ph0 = self.phase_central
        lo = self.phase_lower - ph0
        hi = self.phase_upper - ph0
        pad = rtol * np.maximum(hi - lo, 1e-300)
        with np.errstate(invalid="ignore"):  # NaN bounds where the phase is not bounded
            # the smallest value rel + 2 pi k at or above the lower bound
            turns = np.ceil((lo - pad - rel) / (2 * np.pi))
            first = rel + 2 * np.pi * np.nan_to_num(turns)
            inside = first <= hi + pad
        ph_ok = np.where(self.phase_bounded, inside, True)
        return ok & ph_ok

    def _response_of(self, model):
        """``model``'s response at the envelope's frequencies when it is a python-control
        LTI model (discrete SISO, as :func:`~hammerbound.systems.models.as_polynomials`
        checks, and of the envelope's sampling time), else ``model``."""
        import control

        from ..systems.models import as_polynomials

        if not isinstance(model, control.LTI):
            return model
        if not isinstance(model, (control.TransferFunction, control.StateSpace)):
            raise ParameterValidationError(
                f"give a discrete SISO TransferFunction or StateSpace, or the complex "
                f"response at the envelope's frequencies; got a {type(model).__name__}.")
        A, B = as_polynomials(model)
        per_sample = self.frequency_unit == "rad/sample"
        if model.dt is not True and not per_sample and \
                not np.isclose(model.dt, self.dt, rtol=1e-9, atol=0.0):
            raise ParameterValidationError(
                f"the model's sampling time dt = {model.dt:g} differs from the envelope's "
                f"({self.dt:g}): their frequencies do not correspond.")
        zi = np.exp(-1j * self.omega * self.dt)  # q^-1 on the unit circle
        return np.polyval(B[::-1], zi) / np.polyval(A[::-1], zi)

    def refine(self, rtol: float = 0.01, max_points: int = 20000) -> FrequencyEnvelope:
        """Bisect the intervals whose between-grid magnitude bounds exceed the grid bounds
        by more than ``rtol`` (relative), until none does or ``max_points`` is reached."""
        spec = self._spec
        env = self
        while env.omega.size < max_points:
            up = np.maximum(env.mag_upper[:-1], env.mag_upper[1:])
            lo = np.minimum(env.mag_lower[:-1], env.mag_lower[1:])
            bad = (env.mag_upper_between > up * (1 + rtol)) | (
                env.mag_lower_between < lo * (1 - rtol))
            bad &= np.isfinite(up)
            if not bad.any():
                break
            mids = 0.5 * (env.omega[:-1] + env.omega[1:])[bad]
            mids = mids[: max_points - env.omega.size]
            env = replace(frequency_envelope(spec["bounds"], spec["na"], spec["b_lags"],
                                             np.union1d(env.omega, mids), dt=env.dt,
                                             gain=spec.get("gain")),
                          frequency_unit=self.frequency_unit, signal_names=self.signal_names,
                          signal_units=self.signal_units)
        return env

    def summary(self) -> str:
        """Frequencies, the range of the magnitude bounds and where they are infinite or
        the phase is unbounded."""
        w, up = self.omega, self.mag_upper
        fin = np.isfinite(up)
        lines = [f"frequency-response envelope of {self.signal_names[1]}/{self.signal_names[0]}: "
                 f"{w.size} frequencies in [{w[0]:.4g}, {w[-1]:.4g}] {self.frequency_unit}",
                 f"|G| lower bound in [{self.mag_lower.min():.4g}, {self.mag_lower.max():.4g}]"]
        if fin.any():
            lines.append(f"|G| upper bound in [{up[fin].min():.4g}, {up[fin].max():.4g}]"
                         + ("" if fin.all() else f"; infinite at {int((~fin).sum())} "
                            "frequencies (some A of the box vanishes on the unit circle)"))
        else:
            lines.append("|G| upper bound infinite at every frequency")
        nb = int((~self.phase_bounded).sum())
        lines.append("phase bounded at every frequency" if nb == 0 else
                     f"phase unbounded at {nb} frequencies")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-serialisable: ``omega``, the magnitude and phase bounds (``None`` where
        infinite or unbounded), the central model's magnitude and phase, the units."""
        return jsonable({"omega": self.omega, "dt": self.dt,
                         "frequency_unit": self.frequency_unit,
                         "signal_names": list(self.signal_names),
                         "signal_units": list(self.signal_units),
                         "mag_lower": self.mag_lower, "mag_upper": self.mag_upper,
                         "phase_lower": self.phase_lower, "phase_upper": self.phase_upper,
                         "phase_bounded": self.phase_bounded,
                         "mag_central": self.mag_central,
                         "phase_central": self.phase_central})

    def plot(self, ax=None, **kwargs):
        """Bode plot of the envelope (see :func:`hammerbound.modelset.plots.plot_bode_envelope`);
        ``ax`` a pair of Axes (magnitude, phase) or None; returns the Figure."""
        from .plots import plot_bode_envelope

        return plot_bode_envelope(self, ax=ax, **kwargs)


#: relative outward margin of the few operations after the zonotope extremes
_OUT = 1e-12


def _gain_plane_magnitude(bounds, na, b_lags, w, dt, gain, a_min, LA, n_sub=256):
    """Magnitude bounds over the box intersected with ``sum b = gain (1 + sum a)``.

    Eliminating the last ``b_L`` (and dropping its interval: an outer bound),
    ``G = N / D`` with ``N = sum_{j<L} b_j (z^-j - z^-L) + gain z^-L (1 + sum a_i)`` and
    ``D = A``. Both depend on ``a``; the ``a``-box is cut into ``n_sub`` sub-boxes and on
    each one ``max|N| / min|D|`` and ``min|N| / max|D|`` bound the ratio (zonotope
    extremes, decoupled: outward), intersected with ``|G| = gain +- max|B - gA| / min|A|``
    (exact at the steady state). ``a_min``: ``min |A|`` over the box at ``w`` and ``LA`` its
    Lipschitz constant (the caller's, :func:`frequency_envelope`). Returns lower, upper
    and the between-grid bounds.
    """
    bounds = np.asarray(bounds, dtype=float)
    b_lags = np.asarray(b_lags)
    L = float(b_lags[-1])
    free = b_lags[:-1].astype(float)
    bf = bounds[na:na + free.size]
    k = max(1, int(np.floor(n_sub ** (1.0 / max(na, 1))))) if na else 1
    edges = [np.linspace(lo, hi, k + 1) for lo, hi in bounds[:na]]
    cells = list(itertools.product(range(k), repeat=na)) if na else [()]
    ac = np.array([[0.5 * (edges[i][c[i]] + edges[i][c[i] + 1]) for i in range(na)]
                   for c in cells]).reshape(len(cells), na)
    ar = np.array([[0.5 * (edges[i][c[i] + 1] - edges[i][c[i]]) for i in range(na)]
                   for c in cells]).reshape(len(cells), na)
    wd = w * dt
    zl = np.exp(-1j * wd * L)                                    # (nw,)
    phi = np.exp(-1j * np.outer(wd, free)) - zl[:, None]          # (nw, nf)
    psi = np.exp(-1j * np.outer(wd, np.arange(1, na + 1)))        # (nw, na)
    nw, ns = w.size, len(cells)
    bc, br = bf.mean(axis=1), 0.5 * (bf[:, 1] - bf[:, 0])
    n_c = (phi @ bc)[:, None] + gain * zl[:, None] * (1 + ac.sum(axis=1))[None, :]
    n_g = np.concatenate([np.broadcast_to((phi * br)[:, None, :], (nw, ns, free.size)),
                          gain * zl[:, None, None] * ar[None, :, :]], axis=2)
    d_c = 1 + psi @ ac.T
    d_g = psi[:, None, :] * ar[None, :, :]
    ZN = Zonotopes(n_c.ravel(), n_g.reshape(nw * ns, -1))
    ZD = Zonotopes(d_c.ravel(), d_g.reshape(nw * ns, -1))
    nmax, nmin = ZN.max_abs().reshape(nw, ns), ZN.min_abs().reshape(nw, ns)
    dmax, dmin = ZD.max_abs().reshape(nw, ns), ZD.min_abs().reshape(nw, ns)
    # Lipschitz constants in omega, valid for every point of the (extended) box
    amax = np.max(np.abs(bounds[:na]), axis=1) if na else np.zeros(0)
    LN = dt * (float(np.sum(np.max(np.abs(bf), axis=1) * (free + L)))
               + abs(gain) * L * (1 + float(np.sum(amax))))
    h = np.diff(w)[:, None]

    def ratio(num, den):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(den > 0, num / np.where(den > 0, den, 1.0), np.inf)

    def combine(nmx, nmn, dmx, dmn):
        return ratio(nmn, dmx).min(axis=1), ratio(nmx, dmn).max(axis=1)

    lo, up = combine(nmax, nmin, dmax, dmin)

    def up_i(x, lip):
        return 0.5 * (x[:-1] + x[1:]) + 0.5 * lip * h

    def dn_i(x, lip):
        return np.maximum(0.5 * (x[:-1] + x[1:]) - 0.5 * lip * h, 0.0)

    lo_b, up_b = combine(up_i(nmax, LN), dn_i(nmin, LN), up_i(dmax, LA), dn_i(dmin, LA))  # D = A
    # |G - g| <= max|B - gA| / min|A| on the plane: exact (0) at the steady state, where the
    # ratio of the decoupled sub-box bounds above is loosest (:mod:`.gain_plane`)
    emax = plane_numerator(bounds, na, b_lags, wd, gain, 1.0, gain).max_abs()
    LE = plane_numerator_lipschitz(bounds, na, b_lags, gain, dt)
    e = ratio(emax, a_min)[:, None]
    e_b = ratio(up_i(emax[:, None], LE), dn_i(a_min[:, None], LA))
    lo = np.maximum(lo, (abs(gain) - e[:, 0]) * (1 - _OUT))
    up = np.minimum(up, (abs(gain) + e[:, 0]) * (1 + _OUT))
    lo_b = np.maximum(lo_b, (abs(gain) - e_b[:, 0]) * (1 - _OUT))
    up_b = np.minimum(up_b, (abs(gain) + e_b[:, 0]) * (1 + _OUT))
    return lo, up, lo_b, up_b


def frequency_envelope(bounds, na, b_lags, omega, dt=1.0, gain=None) -> FrequencyEnvelope:
    """Envelope of ``B/A`` over the box ``bounds`` (rows ``a_1..a_na``, then ``b_j``, j in
    ``b_lags``) at the frequencies ``omega`` (rad/s, strictly increasing).

    With ``gain``, the magnitude bounds are intersected with bounds valid on the box
    *intersected with the gain equality* ``B(1) = gain A(1)`` (22.8), which every
    feasible model satisfies (much tighter at low frequencies); they then no longer
    hold for box points off that hyperplane. The phase stays the box's."""
    bounds = np.asarray(bounds, dtype=float)
    w = np.asarray(omega, dtype=float)
    wd = w * dt
    a_lo = np.concatenate([[1.0], bounds[:na, 0]])
    a_hi = np.concatenate([[1.0], bounds[:na, 1]])
    a_lags = np.arange(na + 1)
    b_lags = np.asarray(b_lags)
    ZA = value_sets(a_lo, a_hi, a_lags, wd)
    ZB = value_sets(bounds[na:, 0], bounds[na:, 1], b_lags, wd)
    a_min, a_max = ZA.min_abs(), ZA.max_abs()
    b_min, b_max = ZB.min_abs(), ZB.max_abs()
    with np.errstate(divide="ignore"):
        upper = np.where(a_min > 0, b_max / np.where(a_min > 0, a_min, 1.0), np.inf)
    lower = b_min / a_max
    with np.errstate(divide="ignore", invalid="ignore"):
        central = ZB.centre / ZA.centre
    bounded = (a_min > 0) & (b_min > 0)
    blo, bhi = ZB.arg_range()
    alo, ahi = ZA.arg_range()
    ph0 = np.unwrap(np.angle(central))
    ph_lo = np.where(bounded, ph0 + blo - ahi, np.nan)
    ph_hi = np.where(bounded, ph0 + bhi - alo, np.nan)
    # ---- guarantees between grid frequencies (Lipschitz in omega)
    LA = _lipschitz(a_lo, a_hi, a_lags, dt)
    LB = _lipschitz(bounds[na:, 0], bounds[na:, 1], b_lags, dt)
    h = np.diff(w)
    amin_i = np.maximum(0.5 * (a_min[:-1] + a_min[1:]) - 0.5 * LA * h, 0.0)
    amax_i = 0.5 * (a_max[:-1] + a_max[1:]) + 0.5 * LA * h
    bmin_i = np.maximum(0.5 * (b_min[:-1] + b_min[1:]) - 0.5 * LB * h, 0.0)
    bmax_i = 0.5 * (b_max[:-1] + b_max[1:]) + 0.5 * LB * h
    with np.errstate(divide="ignore", invalid="ignore"):
        up_b = np.where(amin_i > 0, bmax_i / np.where(amin_i > 0, amin_i, 1.0), np.inf)
        lo_b = bmin_i / amax_i
        lph = np.where((amin_i > 0) & (bmin_i > 0),
                       LB / np.where(bmin_i > 0, bmin_i, 1.0) + LA / np.where(amin_i > 0, amin_i, 1.0),
                       np.inf)
    # the unwrapped central phase follows the continuous branch if it moves < pi per step
    ok = np.isfinite(lph) & (lph * h < np.pi) & bounded[:-1] & bounded[1:]
    ph_lo_b = np.where(ok, 0.5 * (ph_lo[:-1] + ph_lo[1:]) - 0.5 * lph * h, np.nan)
    ph_hi_b = np.where(ok, 0.5 * (ph_hi[:-1] + ph_hi[1:]) + 0.5 * lph * h, np.nan)
    if gain is not None and b_lags.size >= 1:
        g_lo, g_up, g_lo_b, g_up_b = _gain_plane_magnitude(bounds, na, b_lags, w, dt, float(gain),
                                                            a_min, LA)
        lower, upper = np.maximum(lower, g_lo), np.minimum(upper, g_up)
        lo_b, up_b = np.maximum(lo_b, g_lo_b), np.minimum(up_b, g_up_b)
    spec = {"bounds": bounds, "na": na, "b_lags": b_lags, "gain": gain}
    return FrequencyEnvelope(
        omega=w, dt=float(dt), mag_lower=lower, mag_upper=upper, phase_lower=ph_lo,
        phase_upper=ph_hi, phase_bounded=bounded, central=central,
        num_abs=np.column_stack([b_min, b_max]), den_abs=np.column_stack([a_min, a_max]),
        mag_lower_between=lo_b, mag_upper_between=up_b, phase_lower_between=ph_lo_b,
        phase_upper_between=ph_hi_b, _spec=spec,
    )


def denominators_stable(a_bounds, n_grid: int = 4096) -> bool:
    """Certify that every ``A(z) = 1 + sum a_i z^-i`` with ``a`` in the box is Schur stable.

    Zero-exclusion principle: the box is path-connected and ``z^na A(z)`` is monic (its
    degree never drops), so all members are stable iff the central one is and 0 is
    outside the value set ``Z_A(w)`` for every ``w`` in ``[0, pi]``. The latter is checked
    on a uniform grid with the Lipschitz bound between grid points; ``False`` means "not
    certified" (the grid may be refined by raising ``n_grid``).
    """
    a_bounds = np.asarray(a_bounds, dtype=float).reshape(-1, 2)
    na = a_bounds.shape[0]
    if na == 0:
        return True
    centre = np.concatenate([[1.0], a_bounds.mean(axis=1)])
    if np.max(np.abs(np.roots(centre))) >= 1.0:
        return False
    lo = np.concatenate([[1.0], a_bounds[:, 0]])
    hi = np.concatenate([[1.0], a_bounds[:, 1]])
    w = np.linspace(0.0, np.pi, n_grid)
    Z = value_sets(lo, hi, np.arange(na + 1), w)
    m = Z.min_abs()
    L = _lipschitz(lo, hi, np.arange(na + 1), 1.0)
    return bool(np.all(0.5 * (m[:-1] + m[1:]) - 0.5 * L * np.diff(w) > 0))
