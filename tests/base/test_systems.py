import control
import numpy as np
import pytest
from scipy.signal import lfilter

from hammerbound.exceptions import DataValidationError, IllPosedBacklashError, ParameterValidationError
from hammerbound.systems.experiments import (
    CHAPTER_BACKLASH,
    chapter_system,
    prbs,
    prbs_experiment,
    square_wave_experiment,
)
from hammerbound.systems.models import Backlash, HammersteinSystem, as_polynomials, normalize_gain


def chapter_three_case(u, bl, x0=0.0):
    """(22.1)-(22.2) written exactly as in the chapter (reference implementation)."""
    x, out = x0, []
    for ut in u:
        zl = x / bl.ml - bl.cl
        zr = x / bl.mr + bl.cr
        assert zl < zr
        if ut <= zl:
            x = bl.ml * (ut + bl.cl)
        elif ut >= zr:
            x = bl.mr * (ut - bl.cr)
        out.append(x)
    return np.array(out)


def test_play_operator_matches_chapter_definition():
    rng = np.random.default_rng(1)
    u = np.cumsum(rng.normal(0, 0.3, 3000))
    u = 2.5 * u / np.max(np.abs(u))
    x = CHAPTER_BACKLASH.simulate(u, x0=0.1)
    np.testing.assert_allclose(x, chapter_three_case(u, CHAPTER_BACKLASH, 0.1), atol=1e-15)


def test_symmetric_unit_slope_matches_python_control():
    b = 0.6
    bl = Backlash(1.0, b / 2, 1.0, b / 2)
    rng = np.random.default_rng(2)
    u = np.cumsum(rng.normal(0, 0.2, 2000))
    nl = control.friction_backlash_nonlinearity(b)
    ref = np.array([nl(v) for v in u])
    np.testing.assert_allclose(bl.simulate(u), ref, atol=1e-12)


def test_crossing_detected():
    bl = CHAPTER_BACKLASH
    assert bl.crossing == pytest.approx(2.8414, abs=1e-4)
    with pytest.raises(IllPosedBacklashError, match="crossing"):
        bl.simulate([1.0, 3.0])
    # a PRBS level beyond the crossing would give a third inner level: refused
    with pytest.raises(IllPosedBacklashError):
        chapter_system().simulate(prbs(50, 4.0, random_state=0))
    # mirrored case m_l > m_r crosses on the negative side
    bl2 = Backlash(0.3, 0.05, 0.25, 0.05)
    assert bl2.crossing < 0
    with pytest.raises(IllPosedBacklashError):
        bl2.simulate([-5.0])


def test_prbs_inner_signal_has_two_levels():
    data = prbs_experiment(chapter_system(), 200, 1.0, 0.01, random_state=3)
    levels = np.unique(np.round(data.x, 12))
    np.testing.assert_allclose(sorted(levels), sorted(CHAPTER_BACKLASH.prbs_levels(1.0)), atol=1e-12)


def test_transfer_function_and_coefficients_agree():
    G = control.tf([2.15, -1.09], [1, -0.76, 0.82], True)
    A, B = as_polynomials(G)
    np.testing.assert_allclose(A, [1, -0.76, 0.82])
    np.testing.assert_allclose(B, [0, 2.15, -1.09])
    s1 = HammersteinSystem(CHAPTER_BACKLASH, G)
    s2 = chapter_system()
    u = prbs(100, 1.0, random_state=0)
    np.testing.assert_allclose(s1.simulate(u), s2.simulate(u))
    x = CHAPTER_BACKLASH.simulate(u)
    np.testing.assert_allclose(s2.simulate(u), lfilter([0, 2.15, -1.09], [1, -0.76, 0.82], x))
    tf = s2.to_transfer_function()
    np.testing.assert_allclose(as_polynomials(tf)[1], B)


def test_bad_linear_blocks():
    with pytest.raises(ParameterValidationError, match="discrete"):
        as_polynomials(control.tf([1], [1, 1]))
    with pytest.raises(ParameterValidationError, match="stable"):
        HammersteinSystem(CHAPTER_BACKLASH, ([1, -2.1, 1.2], [0, 1]))
    with pytest.raises(ParameterValidationError, match="finite"):
        as_polynomials(([1, np.nan], [1]))
    with pytest.raises(ParameterValidationError):
        Backlash(-1, 0.1, 1, 0.1)
    with pytest.raises(DataValidationError, match="NaN"):
        CHAPTER_BACKLASH.simulate([0.1, np.nan])


def test_normalize_gain_preserves_io_behaviour():
    A, B = [1, -0.5], [0, 2.0]
    bl = Backlash(1.0, 0.1, 1.2, 0.2)
    A2, B2, bl2 = normalize_gain(A, B, bl)
    assert np.sum(B2) / np.sum(A2) == pytest.approx(1.0)
    u = prbs(80, 1.0, random_state=1)
    y1 = HammersteinSystem(bl, (A, B)).simulate(u)
    y2 = HammersteinSystem(bl2, (A2, B2)).simulate(u)
    np.testing.assert_allclose(y1, y2, atol=1e-12)


def test_square_wave_steady_state_matches_static_lines():
    sys = chapter_system()
    d = square_wave_experiment(sys, np.linspace(0.3, 2.5, 10), 0.01, random_state=0)
    bl = sys.backlash
    static = np.where(d.u > 0, bl.right(d.u), bl.left(d.u))
    np.testing.assert_allclose(d.w, static, atol=1e-10)
    assert np.all(np.abs(d.y - d.w) <= 0.01)


def test_numpy_generator_and_seed_are_accepted_and_deterministic():
    from hammerbound import chapter_example

    a = chapter_example(0.05, N=40, random_state=np.random.default_rng(3))
    b = chapter_example(0.05, N=40, random_state=np.random.default_rng(3))
    c = chapter_example(0.05, N=40, random_state=4)
    np.testing.assert_array_equal(a.prbs.y, b.prbs.y)
    assert not np.array_equal(a.prbs.y, c.prbs.y)
