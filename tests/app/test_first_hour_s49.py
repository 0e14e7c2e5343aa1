"""New-user trial 17 (a hydraulic valve positioner in a lab, both experiments, volts and
mm): what the fits assume about an output offset, and the command line's hints."""

from __future__ import annotations

import warnings

import numpy as np
from oracles import one_record

import hammerbound as hb


def _no_offset_said(assumptions) -> bool:
    return any("no output offset" in a and "subtract a sensor offset" in a
               for a in assumptions)


def test_both_procedures_say_the_model_has_no_output_offset():
    """Trial 17: a sensor offset of 0.3 mm moved both dead bands past the truth (every
    status optimal); nothing the fit printed said the model has no offset."""
    ex = hb.chapter_example(0.05, N=60)
    two = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05), hb.LinearEIVSetEstimator(output_bound=0.05, method="lp"),
    ).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    assert _no_offset_said(two.assumptions_) and "no output offset" in two.summary()
    u, y, _ = one_record(80, 0.02, "uniform", 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        one = hb.HammersteinBacklashIdentifier(
            linear=hb.LinearEIVSetEstimator(output_bound=0.02, na=2, nb=2, method="lp",
                                            total_time_limit=60),
            procedure="one-record").fit(u, y)
    assert _no_offset_said(one.assumptions_) and "no output offset" in one.summary()


def test_an_offset_is_what_moves_the_dead_bands():
    """Why the assumption is printed: the same steady states with 0.3 added to y give
    dead-band intervals that exclude the truth (the model has no term to carry it)."""
    rng = np.random.default_rng(0)
    a = np.linspace(0.8, 5.0, 10)
    u = np.r_[a, -a]
    y = np.where(u > 0, 2.1 * (u - 0.3), 2.0 * (u + 0.4)) + rng.uniform(-0.05, 0.05, u.size)
    clean = hb.BacklashSetEstimator(0.05).fit(u, y)
    shifted = hb.BacklashSetEstimator(0.05).fit(u, y + 0.3)
    cl, cr = clean.gamma_bounds_[1], clean.gamma_bounds_[3]
    assert cl[0] <= 0.4 <= cl[1] and cr[0] <= 0.3 <= cr[1]
    cl, cr = shifted.gamma_bounds_[1], shifted.gamma_bounds_[3]
    assert cl[0] > 0.4 and cr[1] < 0.3


def test_units_in_the_column_names_are_the_record_units(tmp_path):
    """Trial 17: ``u [V]`` and ``y [mm]`` kept their units inside the names, the units
    stayed empty and no parameter carried one."""
    from oracles import play
    from scipy.signal import lfilter

    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-3, 3, 20), 10)
    y = lfilter([0, 0.3], [1, -0.7], play(u, 2.0, 0.4, 2.1, 0.3)) + rng.uniform(-0.05, 0.05,
                                                                               u.size)
    path = tmp_path / "valve.csv"
    path.write_text("time [s],u [V],y (mm)\n" + "".join(
        f"{0.02 * k:.2f},{float(a)!r},{float(b)!r}\n" for k, (a, b) in enumerate(zip(u, y, strict=True))))
    data = hb.IOData.from_csv(path, u="u [V]", y="y (mm)")
    assert (data.input_name, data.input_unit) == ("u", "V")
    assert (data.output_name, data.output_unit) == ("y", "mm")
    given = hb.IOData.from_csv(path, u="u [V]", y="y (mm)", input_unit="volt")
    assert (given.input_name, given.input_unit) == ("u [V]", "volt")  # what is given wins
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idf = hb.HammersteinBacklashIdentifier(
            linear=hb.LinearEIVSetEstimator(output_bound=0.05, na=1, nb=1, method="lp",
                                            total_time_limit=60),
            procedure="one-record").fit(data)
    assert "units: m_l, m_r in mm/V; c_l, c_r in V" in idf.summary()
    plain = hb.IOData(u, y)
    assert (plain.input_unit, plain.output_unit) == ("", "")
