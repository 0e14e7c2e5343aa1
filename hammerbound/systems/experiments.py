"""Experiment design and data: square waves (stage 1), PRBS (stage 2), bounded noise, SNR.

The chapter's simulated example (section 22.5) is available as :func:`chapter_example`; a
plain errors-in-variables record to try the own-data workflow on as :func:`eiv_example`.
The chapter does not state the square-wave amplitudes nor the PRBS level u*; our
choices and the reasons are documented on :data:`CHAPTER_AMPLITUDES` and
:data:`CHAPTER_U_STAR`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sklearn.utils import check_random_state

from .._compat import DEPRECATED, renamed_value, warn_renamed
from ..data.iodata import IOData
from ..data.validation import as_bound, as_real
from ..exceptions import DataValidationError, ParameterValidationError
from .models import Backlash, HammersteinSystem

__all__ = [
    "CHAPTER_AMPLITUDES",
    "CHAPTER_BACKLASH",
    "CHAPTER_NOISE_LEVELS",
    "CHAPTER_U_STAR",
    "ChapterExample",
    "EIVExample",
    "PRBSData",
    "SteadyStateData",
    "chapter_example",
    "chapter_system",
    "eiv_example",
    "prbs",
    "prbs_experiment",
    "settling_time",
    "snr_db",
    "square_wave_experiment",
    "uniform_noise",
]

#: The six output error bounds (delta_eta) of Tables 22.1-22.3.
CHAPTER_NOISE_LEVELS = (0.005, 0.02, 0.05, 0.15, 0.2, 0.3)

#: Backlash of section 22.5: m_l = 0.25, c_l = 0.0628, m_r = 0.26, c_r = 0.0489.
CHAPTER_BACKLASH = Backlash(0.25, 0.0628, 0.26, 0.0489)

#: Square-wave amplitudes (M = 50). The chapter does not give them. Its steady-state SNR
#: of 54 dB at Delta eta = 0.005 implies an rms steady-state output of ~1.45, i.e. inputs
#: up to ~10 -- far beyond the crossing u_c ~= 2.84 of the two backlash lines, where (22.1)
#: is ill-posed. We therefore spread the amplitudes evenly over [0.25, 2.5], inside the
#: well-posed range and above the dead zone; our steady-state SNRs are lower than the
#: chapter's as a consequence (see docs/benchmarks.md).
CHAPTER_AMPLITUDES = np.linspace(0.25, 2.5, 50)

#: PRBS level. Must exceed max(c_l, c_r) (Result 1) and stay below the crossing 2.84.
#: The chapter does not state it; u* = 1.0 reproduces the chapter's transient SNRs of
#: Tables 22.2-22.3 (50, 38, 30, 20, 18, 14 dB, mean over seeds) and keeps a wide margin
#: on both sides (dead zone ~0.06, crossing ~2.84).
CHAPTER_U_STAR = 1.0


def _rng(random_state):
    if isinstance(random_state, np.random.Generator):
        return random_state
    try:
        return check_random_state(random_state)
    except (TypeError, ValueError) as exc:
        raise ParameterValidationError(
            f"random_state must be None, an int seed, a numpy Generator or RandomState; got "
            f"{random_state!r}."
        ) from exc


def _check_system(system):
    if not isinstance(system, HammersteinSystem):
        raise ParameterValidationError(
            f"system must be a hammerbound.HammersteinSystem; got {type(system).__name__}. "
            "Build one with HammersteinSystem(Backlash(ml, cl, mr, cr), (A, B))."
        )


def uniform_noise(n: int, bound, random_state=None) -> np.ndarray:
    """Bounded noise ``eta ~ U[-bound, +bound]`` (section 22.5)."""
    bound = as_bound("bound", bound, n, allow_zero=True)
    return _rng(random_state).uniform(-1.0, 1.0, n) * bound


def snr_db(w, eta) -> float:
    """Signal-to-noise ratio ``10 log10(sum w^2 / sum eta^2)`` of (22.38)/(22.39)."""
    w = np.asarray(w, dtype=float)
    eta = np.asarray(eta, dtype=float)
    den = float(np.sum(eta**2))
    return float("inf") if den == 0 else float(10.0 * np.log10(np.sum(w**2) / den))


def settling_time(system: HammersteinSystem, tol: float = 1e-12) -> int:
    """Samples after which the linear block's transient is below ``tol`` (assumption A3)."""
    A = system.A
    rho = float(np.max(np.abs(np.roots(A)))) if A.size > 1 else 0.0
    if rho == 0.0:
        return system.nb + 2
    # a mode rho^k, with a polynomial factor for repeated poles: add a generous margin
    return int(np.ceil(np.log(tol) / np.log(rho))) * 2 + system.nb + system.na + 10


@dataclass(frozen=True)
class SteadyStateData:
    """Steady-state samples of a square-wave experiment (section 22.3).

    ``u`` holds the signed steady input (``+U_k`` on the positive half-wave, ``-U_k`` on the
    negative one); ``y = w + eta`` (22.9)-(22.10).
    """

    u: np.ndarray
    y: np.ndarray
    w: np.ndarray
    eta: np.ndarray
    output_bound: np.ndarray
    settle: int

    @property
    def noise_bound(self):
        """Deprecated name of :attr:`output_bound` (removed in 0.3.0)."""
        warn_renamed("SteadyStateData.noise_bound", "SteadyStateData.output_bound")
        return self.output_bound

    @property
    def snr_db(self) -> float:
        """Steady-state SNR (22.38)."""
        return snr_db(self.w, self.eta)


@dataclass(frozen=True)
class PRBSData:
    """A PRBS experiment (section 22.4): input ``+-u*``, output ``y = w + eta``."""

    u: np.ndarray
    y: np.ndarray
    w: np.ndarray
    x: np.ndarray
    eta: np.ndarray
    output_bound: np.ndarray
    u_star: float

    @property
    def noise_bound(self):
        """Deprecated name of :attr:`output_bound` (removed in 0.3.0)."""
        warn_renamed("PRBSData.noise_bound", "PRBSData.output_bound")
        return self.output_bound

    @property
    def snr_db(self) -> float:
        """Transient SNR (22.39)."""
        return snr_db(self.w, self.eta)


def square_wave_experiment(
    system: HammersteinSystem, amplitudes, output_bound=None, *, settle: int | None = None,
    random_state=None, noise_bound=DEPRECATED,
) -> SteadyStateData:
    """Apply square waves of the given amplitudes and sample their steady state.

    For every amplitude ``U_k`` the input is ``+U_k`` for ``settle`` samples then ``-U_k`` for
    ``settle`` samples; the *dynamic* system is simulated and the last sample of each
    half-wave is measured with noise uniform in ``+-output_bound`` (scalar or one per
    sample, >= 0). Returns ``2 M`` samples (right then left for each amplitude).
    ``noise_bound`` is the deprecated name of ``output_bound`` (removed in 0.3.0).
    """
    output_bound = _bound("square_wave_experiment", output_bound, noise_bound)
    _check_system(system)
    try:
        amps = np.asarray(amplitudes, dtype=float)
    except (TypeError, ValueError):
        amps = np.full((0,), np.nan)  # reported below
    if amps.ndim != 1 or amps.size == 0 or not np.all(np.isfinite(amps)) or np.any(amps <= 0):
        raise DataValidationError("amplitudes must be a non-empty 1-D array of finite values > 0.")
    try:
        settle = settling_time(system) if settle is None else int(settle)
    except (TypeError, ValueError) as exc:
        raise ParameterValidationError(
            f"settle must be a positive integer number of samples; got {settle!r}."
        ) from exc
    if settle < 1:
        raise ParameterValidationError("settle must be >= 1 sample.")
    u_full = np.repeat(np.column_stack([amps, -amps]).ravel(), settle)
    w_full = system.simulate(u_full)
    idx = np.arange(1, 2 * amps.size + 1) * settle - 1
    u = u_full[idx]
    w = w_full[idx]
    deta = as_bound("output_bound", output_bound, u.size, allow_zero=True,
                    shape_error=ParameterValidationError)
    eta = uniform_noise(u.size, deta, random_state)
    return SteadyStateData(u, w + eta, w, eta, deta, settle)


def prbs(n: int, u_star: float, *, hold: int = 1, random_state=None) -> np.ndarray:
    """Pseudo-random binary sequence with levels ``+-u*`` held ``hold`` samples per draw."""
    try:
        n, hold = int(n), int(hold)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ParameterValidationError(
            f"n and hold must be positive integers; got n={n!r}, hold={hold!r}."
        ) from exc
    if n < 1 or hold < 1:
        raise ParameterValidationError("n and hold must be positive integers.")
    u_star = as_real("u_star", u_star, positive=True, example="1.0")
    draws = _rng(random_state).random(int(np.ceil(n / hold))) < 0.5
    return np.repeat(np.where(draws, u_star, -u_star), hold)[:n]


def prbs_experiment(
    system: HammersteinSystem, n: int, u_star: float, output_bound=None, *, hold: int = 1,
    random_state=None, noise_bound=DEPRECATED,
) -> PRBSData:
    """PRBS experiment from rest with output noise uniform in ``+-output_bound`` (section
    22.4). ``noise_bound`` is the deprecated name of ``output_bound`` (removed in 0.3.0)."""
    output_bound = _bound("prbs_experiment", output_bound, noise_bound)
    _check_system(system)
    rng = _rng(random_state)
    u = prbs(n, u_star, hold=hold, random_state=rng)
    x = system.inner(u)
    w = system.simulate(u)
    deta = as_bound("output_bound", output_bound, u.size, allow_zero=True,
                    shape_error=ParameterValidationError)
    eta = uniform_noise(u.size, deta, rng)
    return PRBSData(u, w + eta, w, x, eta, deta, float(u_star))


def chapter_system() -> HammersteinSystem:
    """The simulated system of section 22.5 (unit steady-state gain, as (22.8) requires)."""
    return HammersteinSystem(CHAPTER_BACKLASH, ([1.0, -0.76, 0.82], [0.0, 2.15, -1.09]))


@dataclass(frozen=True)
class ChapterExample:
    """Data of the chapter's example for one noise level."""

    system: HammersteinSystem
    steady: SteadyStateData
    prbs: PRBSData
    output_bound: float

    @property
    def noise_bound(self):
        """Deprecated name of :attr:`output_bound` (removed in 0.3.0)."""
        warn_renamed("ChapterExample.noise_bound", "ChapterExample.output_bound")
        return self.output_bound

    @property
    def gamma_true(self) -> np.ndarray:
        return self.system.backlash.gamma

    @property
    def theta_true(self) -> np.ndarray:
        return self.system.theta


def chapter_example(
    output_bound: float = 0.05, *, N: int = 100, amplitudes=None,
    u_star: float = CHAPTER_U_STAR, random_state=0, noise_bound=DEPRECATED,
) -> ChapterExample:
    """The simulated example of section 22.5 (M = 50 amplitudes, PRBS of length N).

    ``output_bound`` is the chapter's ``Delta eta``: the output noise of both experiments is
    uniform in ``+-output_bound`` (0.05 is the chapter's middle level; the simulated data
    carry it, so nothing is assumed). ``noise_bound``: its deprecated name (removed in
    0.3.0).
    """
    output_bound = renamed_value("chapter_example", "output_bound", output_bound,
                                 "noise_bound", noise_bound, unset=0.05)
    rng = _rng(random_state)
    system = chapter_system()
    amps = CHAPTER_AMPLITUDES if amplitudes is None else amplitudes
    steady = square_wave_experiment(system, amps, output_bound, random_state=rng)
    data = prbs_experiment(system, N, u_star, output_bound, random_state=rng)
    return ChapterExample(system, steady, data, float(output_bound))


def _bound(func, output_bound, noise_bound):
    """``output_bound`` of an experiment (or its deprecated name); required."""
    value = renamed_value(func, "output_bound", output_bound, "noise_bound", noise_bound,
                          stacklevel=4)
    if value is None:
        raise ParameterValidationError(
            f"{func} needs output_bound: the noise of the simulated outputs is uniform in "
            f"+-output_bound (0 for none), e.g. output_bound=0.05.")
    return value


#: The linear system of :func:`eiv_example`: ``(b0 + b1 q^-1) / (1 + a1 q^-1)``.
EIV_EXAMPLE_THETA = (-0.85, 0.6, -0.2)


@dataclass(frozen=True)
class EIVExample:
    """A simulated errors-in-variables record (see :func:`eiv_example`).

    ``data`` holds the *measured* input and output (an :class:`~hammerbound.IOData` with
    ``dt``), ``u0`` and ``w`` the true input and noise-free output, ``theta`` the true
    ``(a1, b0, b1)``; ``input_bound`` and ``output_bound`` bound the input and output errors.
    """

    data: IOData
    u0: np.ndarray
    w: np.ndarray
    theta: np.ndarray
    input_bound: float
    output_bound: float


def eiv_example(N: int = 60, *, output_bound: float = 0.05, input_bound: float = 0.05,
                dt: float = 0.1, noise: str = "uniform", random_state=0) -> EIVExample:
    """A first-order record with bounded errors on input *and* output, to try things on.

    The system is ``G(z) = (b0 z + b1) / (z + a1)`` with ``(a1, b0, b1) =``
    :data:`EIV_EXAMPLE_THETA` (in hammerbound's notation ``na=1, nb=1, nk=0``: a direct term
    and one delayed input), driven by random input levels held for 3 samples, from rest.
    Both the measured input and the measured output carry errors: uniform in
    ``[-bound, bound]`` (``noise="uniform"``) or exactly ``+-bound`` with random signs
    (``noise="at_bound"``). ``ex.data.to_csv(path)`` writes it as a CSV file (columns
    ``t, u, y``) for :meth:`IOData.from_csv` and ``hammerbound eiv``.

    Parameters
    ----------
    N : int, default 60
        Number of samples (>= 10).
    output_bound, input_bound : float, default 0.05
        Bounds of the output and input errors (> 0).
    dt : float, default 0.1
        Sampling time (s) of the record.
    noise : {"uniform", "at_bound"}, default "uniform"
        Errors uniform inside the bounds, or exactly at them with random signs.
    random_state : int, Generator or None, default 0
        Seed of the input levels and the errors.

    Returns
    -------
    EIVExample
    """
    if noise not in ("uniform", "at_bound"):
        raise ParameterValidationError(f"noise must be 'uniform' or 'at_bound'; got {noise!r}.")
    try:
        N = int(N)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ParameterValidationError(f"N must be an integer >= 10; got {N!r}.") from exc
    if N < 10:
        raise ParameterValidationError(f"N must be an integer >= 10; got {N!r}.")
    deta = as_real("output_bound", output_bound, positive=True, example="0.05")
    dx = as_real("input_bound", input_bound, positive=True, example="0.05")
    rng = _rng(random_state)
    u0 = np.repeat(rng.uniform(-1.0, 1.0, -(-N // 3)), 3)[:N]
    a1, b0, b1 = EIV_EXAMPLE_THETA
    w = np.empty(N)
    for t in range(N):  # A w = B u0 from rest
        w[t] = b0 * u0[t] + (b1 * u0[t - 1] - a1 * w[t - 1] if t else 0.0)

    def errors(bound):
        if noise == "uniform":
            return rng.uniform(-bound, bound, N)
        return bound * np.where(rng.random(N) < 0.5, 1.0, -1.0)

    u = u0 + errors(dx)
    y = w + errors(deta)
    return EIVExample(IOData(u, y, dt), u0, w, np.array(EIV_EXAMPLE_THETA), dx, deta)
