"""Ordinary operating records: one input that is not designed for identification (random
steps, a sine sweep, a multilevel PRBS), for examples and docs of the one-record method."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..data.iodata import IOData
from ..data.validation import as_bound, as_real
from ..exceptions import ParameterValidationError
from .experiments import _check_system, _rng, snr_db, uniform_noise
from .models import HammersteinSystem

__all__ = ["INPUTS", "OrdinaryRecord", "ordinary_record", "random_steps"]

INPUTS = ("steps", "sine", "multilevel")


@dataclass(frozen=True)
class OrdinaryRecord:
    """One record of a system in operation: input ``u``, output ``y = w + eta``, the noise-free
    output ``w``, the inner signal ``x`` and the noise ``eta`` (``|eta_t| <= output_bound``)."""

    u: np.ndarray
    y: np.ndarray
    w: np.ndarray
    x: np.ndarray
    eta: np.ndarray
    output_bound: np.ndarray
    dt: float | None = None

    @property
    def snr_db(self) -> float:
        return snr_db(self.w, self.eta)

    def to_iodata(self) -> IOData:
        """The record as :class:`~hammerbound.IOData` (what a user's CSV would give)."""
        return IOData(self.u, self.y, dt=self.dt)


def _generator(random_state) -> np.random.Generator:
    """A numpy Generator from None, an int seed, a Generator or a RandomState."""
    rng = _rng(random_state)
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(rng.randint(0, 2**31 - 1))


def random_steps(n: int, low: float = -2.0, high: float = 2.0, *, hold=(3, 20),
                 random_state=None) -> np.ndarray:
    """Steps to levels uniform in ``[low, high]``, each held a number of samples uniform in
    ``hold`` (inclusive)."""
    rng = _generator(random_state)
    h0, h1 = (int(h) for h in hold)
    if n < 1 or h0 < 1 or h1 < h0 or not low < high:
        raise ParameterValidationError(
            f"random_steps needs n >= 1, 1 <= hold[0] <= hold[1] and low < high; got n={n}, "
            f"hold={hold}, low={low}, high={high}.")
    levels, total = [], 0
    while total < n:
        k = int(rng.integers(h0, h1 + 1))
        levels.append(np.full(k, rng.uniform(low, high)))
        total += k
    return np.concatenate(levels)[:n]


def _input(kind, n, amplitude, rng):
    if kind == "steps":
        return random_steps(n, -amplitude, amplitude, random_state=rng)
    t = np.arange(n)
    if kind == "sine":  # frequency sweep from 0.005 to 0.055 cycles per sample
        return amplitude * np.sin(2 * np.pi * t * (0.005 + 0.025 * t / n))
    levels = np.linspace(-amplitude, amplitude, 5)
    draws = rng.integers(0, levels.size, int(np.ceil(n / 4)))
    return np.repeat(levels[draws], 4)[:n]


def ordinary_record(system: HammersteinSystem, n: int, output_bound, *, input="steps",
                    amplitude: float = 2.0, dt=None, random_state=None) -> OrdinaryRecord:
    """A record of ``system`` from rest under an ordinary input, output noise uniform in
    ``+-output_bound``.

    ``input``: ``"steps"`` (random levels in ``+-amplitude`` held 3-20 samples), ``"sine"``
    (a frequency sweep) or ``"multilevel"`` (a five-level PRBS held 4 samples).
    """
    _check_system(system)
    if input not in INPUTS:
        raise ParameterValidationError(f"input must be one of {INPUTS}; got {input!r}.")
    amplitude = as_real("amplitude", amplitude, positive=True, example="2.0")
    rng = _generator(random_state)
    u = _input(input, int(n), amplitude, rng)
    x = system.inner(u)
    w = system.simulate(u)
    deta = as_bound("output_bound", output_bound, u.size, allow_zero=True,
                    shape_error=ParameterValidationError)
    eta = uniform_noise(u.size, deta, rng)
    return OrdinaryRecord(u, w + eta, w, x, eta, deta, dt)
