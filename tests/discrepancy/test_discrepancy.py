"""Model-discrepancy workflow (hammerbound.discrepancy): locate, name, add the missing effect.

Every test generates data from a system that contains an effect the starting model lacks
(or none), with uniform output noise strictly inside the noise bound, and checks that
``diagnose`` names the effect and that the gap shrinks to within the bound.
"""

from __future__ import annotations

import json

import control
import matplotlib
import numpy as np
import pytest
from scipy.signal import lfilter

matplotlib.use("Agg")

from hammerbound.app.cli import diagnose_cli_main  # noqa: E402
from hammerbound.discrepancy import (  # noqa: E402
    DiagnosisReport,
    RefinedModel,
    apply_effect,
    default_candidates,
    diagnose,
    locate,
    read_io_csv,
)
from hammerbound.exceptions import (  # noqa: E402
    DataValidationError,
    HammerboundError,
    ParameterValidationError,
)
from hammerbound.systems.models import Backlash, HammersteinSystem  # noqa: E402

A = np.array([1.0, -1.2, 0.5])
B = np.array([0.0, 0.2, 0.1])  # unit steady-state gain, one sample of delay
G = control.tf([0.0, 0.2, 0.1], [1.0, -1.2, 0.5], True)
NB = 0.02  # noise bound; the noise is uniform in +-0.95 NB
N = 300

#: hidden effect -> (true parameter, tolerance on the fitted parameter)
EFFECTS = {
    "backlash": (0.15, 0.01),
    "deadzone": (0.2, 0.01),
    "saturation": (0.6, 0.01),
    "delay": (2, 0),
    "offset": (0.3, 0.01),
    "extra_pole": (0.6, 0.02),
}


def _input(seed, n=N, hold=6):
    rng = np.random.default_rng(seed)
    return np.repeat(rng.uniform(-1.0, 1.0, n // hold), hold)


def _noise(seed, n, level=0.95 * NB):
    return np.random.default_rng(1000 + seed).uniform(-level, level, n)


def _true_output(effect, value, u, linear=None):
    """Noise-free output of the true system: the model G (or ``linear``) plus ``effect``."""
    simulate = (lambda x: lfilter(B, A, x)) if linear is None else linear
    if effect in ("backlash", "deadzone", "saturation", "delay"):
        return simulate(apply_effect(effect, value, u))
    if effect == "extra_pole":
        return lfilter([1.0 - value], [1.0, -value], simulate(u))
    if effect == "offset":
        return simulate(u) + value
    assert effect is None
    return simulate(u)


def make_data(effect, value, seed, noise_level=0.95 * NB):
    u = _input(seed)
    y = _true_output(effect, value, u) + _noise(seed, u.size, noise_level)
    return u, y


# --------------------------------------------------------------------------------------
# the workflow names every candidate effect and the gap shrinks to within the bound
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("effect", list(EFFECTS))
def test_names_hidden_effect_and_closes_gap(effect, seed):
    value, tol = EFFECTS[effect]
    u, y = make_data(effect, value, seed)
    rep = diagnose(G, u, y, output_bound=NB)

    assert rep.effect == effect, rep.summary()
    assert rep.gap_after <= NB < rep.gap_before
    assert rep.consistent_after and not rep.consistent_before
    assert rep.gap_before_lower > NB  # the original class is *certified* inconsistent
    assert rep.fraction_outside_after == 0.0 < rep.fraction_outside_before
    # evidence for every candidate; the chosen one is the only consistent one here
    assert [c.name for c in rep.candidates] == list(default_candidates())
    chosen = rep.candidate(effect)
    assert chosen.consistent and chosen.minimax_error == rep.gap_after
    # a delay is reported as the total input delay (G's own sample + the hidden ones)
    assert abs(chosen.value - (value + (effect == "delay"))) <= tol
    assert not any(c.consistent for c in rep.candidates if c.name != effect)
    # the reported gap is achieved by the returned refined model
    achieved = np.max(np.abs(y - rep.refined_model.predict(u)))
    assert achieved == pytest.approx(rep.gap_after, rel=1e-12, abs=1e-15)
    assert rep.refined_model.effects[0][0] == effect
    assert effect in rep.message


def test_locate_reports_conditions_shift_lag_and_hysteresis():
    u, y = make_data("offset", 0.3, 0)
    d = locate(G, u, y, NB)
    assert d.gap > NB and d.mean_shift > 0.9
    assert any("constant shift" in h for h in d.hints)

    u, y = make_data("delay", 2, 0)
    d = locate(G, u, y, NB)
    assert d.best_lag == 2
    assert any("lag the model by about 2" in h for h in d.hints)

    u, y = make_data("backlash", 0.15, 0)
    d = locate(G, u, y, NB)
    assert d.direction_correlation < -0.5
    assert any("hysteresis" in h for h in d.hints)

    u, y = make_data("saturation", 0.6, 0)
    d = locate(G, u, y, NB)
    large = {c.name: c for c in d.conditions}["large_amplitude"]
    assert large.enrichment > 1.5
    assert d.indices.size == round(d.ls_fraction_outside * u.size)


# --------------------------------------------------------------------------------------
# no missing effect, and noise bounds near the effect's size
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", [0, 1])
def test_no_missing_effect_is_not_invented(seed):
    u, y = make_data(None, 0.0, seed)
    rep = diagnose(G, u, y, output_bound=NB)
    assert rep.effect is None
    assert rep.consistent_before and rep.consistent_after
    assert rep.gap_after == rep.gap_before <= NB
    assert "No missing effect" in rep.message
    assert rep.refined_model.effects == ()
    # the evidence is still reported: no candidate is needed
    assert len(rep.candidates) == len(default_candidates())


def test_noise_bound_too_small_for_the_noise_does_not_invent_an_effect():
    # true noise +-0.019 but the user claims 0.01: the model is inconsistent, yet no
    # candidate explains the excess, so none is named and the message says why
    u, y = make_data(None, 0.0, 0)
    rep = diagnose(G, u, y, output_bound=0.01)
    assert rep.effect is None
    assert not rep.consistent_before and not rep.consistent_after
    assert rep.gap_after == rep.gap_before > 0.01
    assert "Check the output bound" in rep.message


def test_effect_below_noise_bound_is_reported_as_undecidable():
    # offset 0.02 with noise +-0.019: consistent under a bound of 0.04, so nothing may be
    # named, but the report says an offset would reduce the error
    u, y = make_data("offset", 0.02, 0)
    rep = diagnose(G, u, y, output_bound=0.04)
    assert rep.effect is None and rep.consistent_before
    assert rep.gap_before <= 0.04
    assert "neither be confirmed nor excluded" in rep.message
    assert "offset" in rep.message
    assert rep.candidate("offset").minimax_error < 0.6 * rep.gap_before


@pytest.mark.parametrize(("effect", "value"), [("offset", 0.03), ("backlash", 0.02)])
def test_effect_just_above_noise_bound_is_found(effect, value):
    u, y = make_data(effect, value, 1)
    rep = diagnose(G, u, y, output_bound=NB)
    assert NB < rep.gap_before < 3 * NB
    assert rep.effect == effect
    assert rep.gap_after <= NB


def test_noise_bound_smaller_than_noise_with_effect_is_honest():
    # a real offset, but the claimed noise bound is below the actual noise: nothing makes
    # the data consistent, so nothing is named; the offset is reported as the closest
    # candidate with the share of the gap it removes, in separate fields
    u, y = make_data("offset", 0.3, 0)
    rep = diagnose(G, u, y, output_bound=0.01, max_effects=1)
    assert rep.effect is None and rep.effects_added == ()
    assert not rep.consistent_after and rep.gap_after == rep.gap_before
    assert rep.closest[0] == "offset"
    assert rep.closest_gap_removed[0] > 0.9
    assert 0.01 < rep.closest_minimax_error[0] < rep.gap_before / 10
    assert "None of the candidates explains the data" in rep.message
    assert "none of the candidates explains the data" in rep.summary()


def test_second_effect_found_on_refined_model():
    # diagnose on a RefinedModel refits the effects already in it together with the new one
    u = _input(0)
    first = diagnose(G, u, _true_output("delay", 2, u) + _noise(0, u.size), output_bound=NB,
                     candidates=["delay", "offset"])
    assert first.effect == "delay" and first.consistent_after
    y = _true_output("delay", 2, u) + 0.3 + _noise(0, u.size)
    second = diagnose(first.refined_model, u, y, output_bound=NB, candidates=["offset"])
    assert second.effect == "offset" and second.effects_added == ("offset",)
    assert second.gap_after <= NB < second.gap_before
    assert [e for e, _ in second.refined_model.effects] == ["delay", "offset"]
    assert second.refined_model.effects[0][1] == 3.0  # total delay: 1 + 2
    assert second.refined_model.offset == pytest.approx(0.3, abs=0.02)


def test_refit_none_and_candidate_subset():
    u, y = make_data("offset", 0.3, 0)
    rep = diagnose(G, u, y, output_bound=NB, refit="none", candidates=["delay", "offset"])
    assert [c.name for c in rep.candidates] == ["delay", "offset"]
    assert rep.effect == "offset"
    np.testing.assert_allclose(rep.refined_model.B, B)  # the model was not refitted
    assert rep.refined_model.offset == pytest.approx(0.3, abs=0.01)


# --------------------------------------------------------------------------------------
# fitted hammerbound models: HammersteinSystem and estimators with system_
# --------------------------------------------------------------------------------------
BL = Backlash(0.9, 0.1, 0.9, 0.1)


def _hammerstein_data(effect, value, seed=3):
    H = HammersteinSystem(BL, (A, B))
    u = _input(seed)
    y = _true_output(effect, value, u, linear=H.simulate) + _noise(seed, u.size)
    return H, u, y


@pytest.mark.parametrize(("effect", "value"), [("saturation", 0.6), ("delay", 1)])
def test_hammerstein_system_model(effect, value):
    H, u, y = _hammerstein_data(effect, value)
    rep = diagnose(H, u, y, output_bound=NB)
    assert rep.effect == effect
    assert rep.gap_after <= NB < rep.gap_before
    assert rep.refined_model.inner == BL


def test_hammerstein_system_with_extra_backlash_maps_back():
    H, u, y = _hammerstein_data("backlash", 0.1)
    rep = diagnose(H, u, y, output_bound=NB)
    assert rep.effect == "backlash" and rep.gap_after <= NB
    H2 = rep.refined_model.to_hammerstein()
    assert isinstance(H2, HammersteinSystem)
    assert H2.backlash.cl == pytest.approx(0.2, abs=0.01)
    np.testing.assert_allclose(H2.simulate(u), rep.refined_model.predict(u), atol=1e-12)


class _FittedIdentifier:
    """Stand-in for a fitted identifier: exposes its central model as ``system_``."""

    def __init__(self, system):
        self.system_ = system

    def fit(self, X, y):  # pragma: no cover - never called
        return self

    def predict(self, X):  # diagnose must use system_, not this
        raise AssertionError("predict should not be called when system_ is available")


def test_object_with_system_attribute():
    H, u, y = _hammerstein_data("offset", 0.2)
    rep = diagnose(_FittedIdentifier(H), u, y, output_bound=NB)
    assert rep.effect == "offset" and rep.gap_after <= NB < rep.gap_before
    assert rep.refined_model.inner == BL


def test_unfitted_or_wrong_system_attribute():
    from sklearn.base import BaseEstimator

    class Identifier(BaseEstimator):
        def fit(self, X, y):  # pragma: no cover
            self.system_ = None
            return self

        def predict(self, X):  # pragma: no cover
            return X

    u, y = make_data(None, 0.0, 0)
    with pytest.raises(ParameterValidationError, match="not fitted.*fit"):
        diagnose(Identifier(), u, y, output_bound=NB)
    with pytest.raises(ParameterValidationError, match="system_ is a tuple"):
        diagnose(_FittedIdentifier((A, B)), u, y, output_bound=NB)


def test_black_box_model_with_predict():
    class Sim:
        def predict(self, u):
            return lfilter(B, A, u)

    u, y = make_data("offset", 0.3, 1)
    rep = diagnose(Sim(), u, y, output_bound=NB, candidates=["offset", "delay"])
    assert rep.effect == "offset" and rep.gap_after <= NB
    assert rep.refined_model.base is not None


# --------------------------------------------------------------------------------------
# bad input -> typed errors with helpful messages
# --------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def clean():
    return make_data(None, 0.0, 0)


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"output_bound": 0.0}, ParameterValidationError, "output_bound must be a finite"),
        ({"output_bound": -1}, ParameterValidationError, "output_bound"),
        ({"output_bound": float("nan")}, ParameterValidationError, "output_bound"),
        ({"output_bound": "0.1"}, ParameterValidationError, "single positive number"),
        ({"candidates": ["friction"]}, ParameterValidationError, "unknown candidate.*friction"),
        ({"candidates": []}, ParameterValidationError, "candidates is empty"),
        ({"refit": "all"}, ParameterValidationError, "refit must be"),
        ({"skip": -1}, ParameterValidationError, "skip must be an integer >= 0"),
        ({"skip": None}, ParameterValidationError, "skip must be an integer"),
        ({"skip": 295}, DataValidationError, "only 5 scored samples"),
        ({"max_delay": 0}, ParameterValidationError, "max_delay"),
        ({"grid_size": 2.5}, ParameterValidationError, "grid_size"),
        ({"min_improvement": 0.5}, ParameterValidationError, "min_improvement"),
    ],
)
def test_bad_parameters(clean, kwargs, exc, match):
    u, y = clean
    kw = {"output_bound": NB, **kwargs}
    with pytest.raises(exc, match=match):
        diagnose(G, u, y, **kw)


def test_bad_data(clean):
    u, y = clean
    y_nan = y.copy()
    y_nan[7] = np.nan
    with pytest.raises(DataValidationError, match="y contains NaN or inf.*sample 7"):
        diagnose(G, u, y_nan, output_bound=NB)
    with pytest.raises(DataValidationError, match="u has 300 samples but y has 299"):
        diagnose(G, u, y[:-1], output_bound=NB)
    with pytest.raises(DataValidationError, match="1-D signal"):
        diagnose(G, np.ones((10, 3)), np.ones((10, 3)), output_bound=NB)
    with pytest.raises(DataValidationError, match="real numbers"):
        diagnose(G, ["a"] * 20, y[:20], output_bound=NB)
    with pytest.raises(DataValidationError, match="identically zero"):
        diagnose(G, np.zeros(50), y[:50], output_bound=NB)
    with pytest.raises(DataValidationError, match="at least 10"):
        diagnose(G, u[:5], y[:5], output_bound=NB)
    # typed errors are also ValueErrors
    with pytest.raises(ValueError):
        diagnose(G, u, y[:-1], output_bound=NB)


def test_bad_models(clean):
    u, y = clean
    with pytest.raises(ParameterValidationError, match="continuous-time.*sample_system"):
        diagnose(control.tf([1.0], [1.0, 1.0]), u, y, output_bound=NB)
    with pytest.raises(ParameterValidationError, match="unstable"):
        diagnose(control.tf([0.0, 1.0], [1.0, -1.5], True), u, y, output_bound=NB)
    with pytest.raises(ParameterValidationError, match="not supported.*TransferFunction"):
        diagnose("G", u, y, output_bound=NB)

    class WrongLength:
        def predict(self, u):
            return np.zeros(len(u) - 1)

    class Broken:
        def predict(self, u):
            raise RuntimeError("boom")

    with pytest.raises(DataValidationError, match="returned 299 samples for 300 inputs"):
        diagnose(WrongLength(), u, y, output_bound=NB)
    with pytest.raises(ParameterValidationError, match=r"model.predict\(u\) failed.*boom"):
        diagnose(Broken(), u, y, output_bound=NB)


def test_to_hammerstein_refuses_non_backlash_models():
    u, y = make_data("offset", 0.3, 0)
    rep = diagnose(G, u, y, output_bound=NB, candidates=["offset"])
    with pytest.raises(ParameterValidationError, match="without offset"):
        rep.refined_model.to_hammerstein()
    with pytest.raises(ParameterValidationError, match="has no backlash"):
        RefinedModel(A=A, B=B).to_hammerstein()


# --------------------------------------------------------------------------------------
# report: plot, summary, JSON
# --------------------------------------------------------------------------------------
def test_plot_summary_and_dict(tmp_path):
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    u, y = make_data("deadzone", 0.2, 0)
    rep = diagnose(G, u, y, output_bound=NB, candidates=["deadzone", "saturation"])
    assert isinstance(rep, DiagnosisReport)
    fig = rep.plot()
    assert isinstance(fig, Figure) and len(fig.axes) == 4
    plt.close(fig)
    out = rep.save(tmp_path / "diag.png")
    assert out == tmp_path / "diag.png" and out.stat().st_size > 10_000
    old = tmp_path / "old.png"
    with pytest.warns(DeprecationWarning, match=r"plot\(path\) is deprecated"):
        fig = rep.plot(old)  # the old form still draws and saves
    assert isinstance(fig, Figure) and old.stat().st_size > 10_000
    plt.close(fig)
    fig, axes = plt.subplots(4, 1)
    assert rep.plot(axes) is fig  # draws into given axes
    plt.close(fig)
    text = rep.summary()
    assert "deadzone" in text and "gap after" in text
    d = json.loads(json.dumps(rep.to_dict(), allow_nan=False))
    assert d["effect"] == "deadzone" and d["gap_after"] <= NB

    rep0 = diagnose(G, *make_data(None, 0.0, 0), output_bound=NB, candidates=["offset"])
    fig = rep0.plot(max_samples=100)
    assert isinstance(fig, Figure)
    plt.close(fig)


# --------------------------------------------------------------------------------------
# command line
# --------------------------------------------------------------------------------------
CLI_MODEL = ["--num", "0 0.2 0.1", "--den", "1 -1.2 0.5"]


def _write_csv(path, u, y, header="u,y"):
    lines = [header] if header else []
    lines += [f"{a:.17g},{b:.17g}" for a, b in zip(u, y, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_cli_names_effect_and_writes_json_and_plot(tmp_path, capsys):
    u, y = make_data("offset", 0.3, 0)
    csv = _write_csv(tmp_path / "data.csv", u, y)
    png = tmp_path / "fig.png"
    rc = diagnose_cli_main([csv, *CLI_MODEL, "--output-bound", "0.02",
                            "--candidates", "offset,delay", "--json", "--plot", str(png)])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["effect"] == "offset"
    assert out["gap_after"] <= 0.02 < out["gap_before"]
    assert png.stat().st_size > 10_000


def test_cli_text_output_headerless_and_named_columns(tmp_path, capsys):
    u, y = make_data("offset", 0.3, 0)
    csv = _write_csv(tmp_path / "plain.csv", u, y, header=None)
    rc = diagnose_cli_main([csv, *CLI_MODEL, "--output-bound", "0.02", "--candidates", "offset"])
    assert rc == 0
    assert "effect                   : offset" in capsys.readouterr().out
    # named columns in another order, plus an extra column
    path = tmp_path / "named.csv"
    rows = ["time,force,position"]
    rows += [f"{i},{a:.17g},{b:.17g}" for i, (a, b) in enumerate(zip(u, y, strict=True))]
    path.write_text("\n".join(rows) + "\n")
    uu, yy = read_io_csv(str(path), "force", "position")
    np.testing.assert_array_equal(uu, u)
    np.testing.assert_array_equal(yy, y)
    # the noise bound is too small: exit code 1 (inconsistent after)
    rc = diagnose_cli_main([str(path), *CLI_MODEL, "--output-bound", "0.005", "--u-col",
                            "force", "--y-col", "position", "--candidates", "offset"])
    assert rc == 1


def test_cli_missing_column(tmp_path, capsys):
    u, y = make_data(None, 0.0, 0)
    csv = _write_csv(tmp_path / "d.csv", u, y, header="u,output")
    rc = diagnose_cli_main([csv, *CLI_MODEL, "--output-bound", "0.02"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "column 'y'" in err and "['u', 'output']" in err and "--y-col" in err

    one = tmp_path / "one.csv"
    one.write_text("\n".join(f"{a:.17g}" for a in u) + "\n")
    assert diagnose_cli_main([str(one), *CLI_MODEL, "--output-bound", "0.02"]) == 2
    assert "y column (index 1) is missing: found 1 column(s)" in capsys.readouterr().err


def test_cli_bad_rows(tmp_path, capsys):
    u, y = make_data(None, 0.0, 0)
    lines = ["u,y"] + [f"{a:.17g},{b:.17g}" for a, b in zip(u, y, strict=True)]
    lines[4] = "0.5,abc"  # file line 5
    lines[9] = "0.25"  # file line 10: missing y
    lines[20] = "nan,0.1"  # file line 21
    path = tmp_path / "bad.csv"
    path.write_text("\n".join(lines) + "\n")
    rc = diagnose_cli_main([str(path), *CLI_MODEL, "--output-bound", "0.02"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "3 row(s)" in err
    assert "line 5: '0.5,abc'" in err and "line 10" in err and "line 21" in err
    with pytest.raises(DataValidationError, match="line 5"):
        read_io_csv(str(path))


def test_cli_other_errors(tmp_path, capsys):
    u, y = make_data(None, 0.0, 0)
    csv = _write_csv(tmp_path / "d.csv", u, y)
    assert diagnose_cli_main([str(tmp_path / "missing.csv"), *CLI_MODEL,
                              "--output-bound", "0.02"]) == 2
    assert "cannot read" in capsys.readouterr().err
    assert diagnose_cli_main([csv, "--num", "0 x", "--den", "1 -0.5",
                              "--output-bound", "0.02"]) == 2
    assert "--num must be numbers" in capsys.readouterr().err
    assert diagnose_cli_main([csv, "--num", "0 1", "--den", "1 -1.5",
                              "--output-bound", "0.02"]) == 2
    assert "unstable" in capsys.readouterr().err
    assert diagnose_cli_main([csv, *CLI_MODEL, "--output-bound", "-1"]) == 2
    assert "--output-bound" in capsys.readouterr().err
    assert diagnose_cli_main([csv, *CLI_MODEL, "--output-bound", "0.02",
                              "--candidates", "friction"]) == 2
    assert "unknown candidate" in capsys.readouterr().err
    assert diagnose_cli_main([csv, *CLI_MODEL]) == 2  # argparse: missing --output-bound
    assert "--output-bound" in capsys.readouterr().err
    empty = tmp_path / "empty.csv"
    empty.write_text("u,y\n")
    assert diagnose_cli_main([str(empty), *CLI_MODEL, "--output-bound", "0.02"]) == 2
    assert "no data rows" in capsys.readouterr().err


def test_errors_are_hammerbound_errors(clean):
    u, y = clean
    with pytest.raises(HammerboundError):
        diagnose(G, u, y, output_bound=0)
