"""Discrepancy diagnosis with noise *exactly* at the bound (issue 13, item 2).

The truth is simulated here with scipy's lfilter (not with the package); the noise is
``+-output_bound`` exactly, so the true model's minimax error equals the bound and only the
tolerance policy (hammerbound.tolerances) separates "consistent" from "inconsistent".
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import control
import numpy as np
import pytest
from oracles import hammerstein
from scipy.signal import lfilter

from hammerbound.discrepancy import diagnose
from hammerbound.tolerances import FEASIBILITY_RTOL

ROOT = Path(__file__).resolve().parents[2]
A = np.array([1.0, -1.2, 0.5])
B = np.array([0.0, 0.2, 0.1])
G = control.tf(B, A, True)
NB = 0.02
#: effect -> (true value, pattern of the +-NB noise)
EFFECTS = {
    "backlash": (0.15, "alternating"),
    "deadzone": (0.2, "random"),
    "saturation": (0.6, "random"),
    "delay": (2, "alternating"),
    "offset": (0.3, "random"),
    "extra_pole": (0.6, "alternating"),
}


def _truth(effect, value, u):
    if effect == "backlash":
        return hammerstein(u, (1.0, value, 1.0, value), B, A)
    if effect == "deadzone":
        return lfilter(B, A, np.sign(u) * np.maximum(np.abs(u) - value, 0.0))
    if effect == "saturation":
        return lfilter(B, A, np.clip(u, -value, value))
    if effect == "delay":
        return lfilter(np.r_[np.zeros(value), B], A, u)
    if effect == "offset":
        return lfilter(B, A, u) + value
    return lfilter([1.0 - value], [1.0, -value], lfilter(B, A, u))


def _data(effect, seed=3):
    value, pattern = EFFECTS[effect]
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, 50), 6)
    n = u.size
    sign = np.where(np.arange(n) % 2 == 0, 1.0, -1.0) if pattern == "alternating" \
        else np.where(rng.random(n) < 0.5, 1.0, -1.0)
    return u, _truth(effect, value, u) + NB * sign


@pytest.mark.parametrize("effect", list(EFFECTS))
def test_noise_exactly_at_the_bound_is_consistent_after_the_right_effect(effect):
    u, y = _data(effect)
    rep = diagnose(G, u, y, output_bound=NB)
    assert rep.effect == effect, rep.summary()
    assert rep.consistent_after and not rep.consistent_before
    assert rep.fraction_outside_after == 0.0  # the same rule as consistent_after
    assert rep.fraction_outside_before > 0.0
    # the refinement makes the gap meet the bound (it was 1e-4..8e-4 relative above it
    # before; now ~1e-13, at most ~2e-9 measured)
    assert rep.gap_after <= NB * (1 + 1e-7)
    # a delay is reported as the total input delay: G's own sample plus the added ones
    want = EFFECTS[effect][0] + (1 if effect == "delay" else 0)
    assert abs(rep.candidate(effect).value - want) <= 1e-6
    # the tolerance is tight: the refined model's residual is achieved on its own prediction
    resid = np.abs(y - rep.refined_model.predict(u))
    assert np.all(resid <= NB + FEASIBILITY_RTOL * (np.abs(y) + np.abs(y - resid) + 2 * NB))


def test_noise_slightly_beyond_the_bound_is_not_called_consistent():
    """The tolerance only covers rounding: 1e-6 beyond the bound is an inconsistency."""
    u, y = _data("backlash")
    rep = diagnose(G, u, y, output_bound=NB * (1 - 1e-6), candidates=["backlash"])
    assert not rep.consistent_after
    assert rep.fraction_outside_after > 0.0


@pytest.mark.parametrize("effect", ["backlash", "extra_pole"])
def test_cli_exits_0_on_a_correct_model_with_noise_at_the_bound(effect, tmp_path):
    u, y = _data(effect)
    path = tmp_path / "io.csv"
    path.write_text("u,y\n" + "".join(f"{a!r},{b!r}\n" for a, b in
                                      zip(u.tolist(), y.tolist(), strict=True)))
    r = subprocess.run(
        [sys.executable, "-m", "hammerbound", "diagnose", str(path), "--num", "0 0.2 0.1",
         "--den", "1 -1.2 0.5", "--output-bound", repr(NB), "--candidates", effect],
        capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "0.0% outside" in r.stdout.split("gap after")[1].splitlines()[0]
