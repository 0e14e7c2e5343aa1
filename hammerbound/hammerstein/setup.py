"""What an identifier's fit starts from: its stage estimators (cloned and checked), the
record, the procedure it takes and the output bounds its guarantee rests on."""

from __future__ import annotations

import numpy as np
from sklearn.base import clone

from .._compat import is_given
from ..data.validation import as_signal, check_scale
from ..exceptions import DataValidationError, ParameterValidationError
from ..stage1.estimator import BacklashSetEstimator
from ..stage1.inner_signal import INNER_SIGNALS
from ..stage2.estimator import LinearEIVSetEstimator

PROCEDURES = ("auto", "two-stage", "one-record")

#: The unit-gain normalisation (22.8) and what it implies at rest, as every fit's
#: assumptions say it: the model has no output offset, so a sensor's offset is read as
#: a shift of the backlash lines (trial 17: 0.3 mm moved c_l from 0.40 to [0.548, 0.574]
#: and c_r from 0.30 to [0.150, 0.173], every status optimal).
GAIN_ASSUMPTION = ("linear block of unit steady-state gain (22.8), no output offset (at rest "
                   "y = x, the backlash output: subtract a sensor offset first)")


def _stage_estimator(value, cls, name, example):
    """A clone of the stage estimator ``value`` (an instance of ``cls``), or a typed error
    that says what to pass (a class, a string, another estimator)."""
    if isinstance(value, cls):
        return clone(value)
    if isinstance(value, type) and issubclass(value, cls):
        got = f"the class {cls.__name__} itself"
    elif isinstance(value, str):
        got = f"the string {value!r}"
    else:
        got = f"a {type(value).__name__}"
    raise ParameterValidationError(
        f"{name} must be a {cls.__name__} instance; got {got}. Pass e.g. {name}={example} "
        f"(its options, such as method=..., go to the {cls.__name__}).")


def _no_bound(est) -> bool:
    """Whether a stage estimator was given no output bound (under either name)."""
    return est.output_bound is None and not is_given(est.noise_bound)


def check_bounds(bl, lin, output_bound, steady):
    """Refuse, before any work, a missing output bound (the guarantee rests on it): the
    record's (stage-2 estimator or ``fit(output_bound=)``), and the steady-state one when
    steady-state data are given."""
    if steady and _no_bound(bl):
        raise ParameterValidationError(
            "HammersteinBacklashIdentifier: the stage-1 estimator has no output_bound. The "
            "steady-state data rest on the bound of their output errors, which has no "
            "default: pass backlash=BacklashSetEstimator(output_bound=0.05) (your sensor's "
            "error bound).")
    if output_bound is None and _no_bound(lin):
        raise ParameterValidationError(
            "HammersteinBacklashIdentifier: the stage-2 estimator has no output_bound. The "
            "record's output errors must be bounded (the guarantee rests on it; no "
            "default): pass linear=LinearEIVSetEstimator(na=2, nb=2, output_bound=0.05) (or "
            "fit(..., output_bound=...)).")


def checked_steady(bl, steady_state):
    """The steady-state points ``(u_ss, y_ss)`` of a one-record fit, checked as stage 1
    checks them (finite, equal lengths, no ``u = 0``, whose line is not known), or None.
    Unchecked, a NaN gave every backlash end ``[0, inf]`` without a word and unequal
    lengths an untyped error (review)."""
    if steady_state is None:
        return None
    from .two_stage import steady_pair

    us, ys, _ = bl._validate(*steady_pair(steady_state))
    return us, ys


def steady_bound(bl):
    """The stage-1 estimator's output bound (under its old name too, with a warning)."""
    from .._compat import renamed_value

    return renamed_value("BacklashSetEstimator", "output_bound", bl.output_bound,
                         "noise_bound", bl.noise_bound, stacklevel=5)


def _is_prbs(u, prbs_level) -> bool:
    """A two-level input ``+-u*`` (the chapter's stage-2 experiment)?"""
    if prbs_level is not None:
        return True
    levels = np.unique(u)
    return levels.size == 2 and bool(np.isclose(levels[0], -levels[1], rtol=1e-9, atol=0))


def stage_estimators(idf):
    """Clones of the two estimators, checked, the linear one at unit gain (22.8)."""
    if idf.inner_signal not in INNER_SIGNALS:
        raise ParameterValidationError(
            f"inner_signal must be one of {INNER_SIGNALS}; got {idf.inner_signal!r}.")
    if idf.procedure not in PROCEDURES:
        raise ParameterValidationError(
            f"procedure must be one of {PROCEDURES}; got {idf.procedure!r}.")
    bl = BacklashSetEstimator() if idf.backlash is None else _stage_estimator(
        idf.backlash, BacklashSetEstimator, "backlash",
        "BacklashSetEstimator(output_bound=0.05)")
    lin = LinearEIVSetEstimator() if idf.linear is None else _stage_estimator(
        idf.linear, LinearEIVSetEstimator, "linear",
        "LinearEIVSetEstimator(na=2, nb=2, output_bound=0.05)")
    g = lin.steady_state_gain
    if g is None:
        lin.set_params(steady_state_gain=1.0)  # (22.8), explicitly on the clone
    elif not (isinstance(g, (int, float, np.number)) and float(g) == 1.0):
        raise ParameterValidationError(
            f"the identifier normalises the linear block to unit steady-state gain (22.8) "
            f"and lets the backlash slopes carry the gain; got linear steady_state_gain="
            f"{g!r}. Use steady_state_gain=None (or 1.0) on the stage-2 estimator.")
    return bl, lin


def record_of(X, y):
    """The record ``(X, y)`` (arrays, or an IOData and None) as an IOData, checked."""
    from ..data.iodata import IOData, unpack

    X, y, data = unpack(X, y)
    u = as_signal("X (input)", X)
    yy = as_signal("y (output)", y)
    if u.shape != yy.shape:
        raise DataValidationError(
            f"X and y must have the same number of samples; got {u.size} and {yy.size}.")
    check_scale("HammersteinBacklashIdentifier.fit", {"X (input)": u, "y (output)": yy},
                hint=" (the slopes m_l, m_r and theta are unchanged; multiply the bounds "
                     "on c_l, c_r by s)")
    return IOData(u, yy) if data is None else data


def choose_procedure(idf, u, steady_state) -> str:
    """``"two-stage"`` or ``"one-record"``: what ``idf.procedure`` asks for, or, with
    ``"auto"``, two stages for steady-state data with a two-level PRBS record."""
    if idf.procedure == "two-stage":
        if steady_state is None:
            raise DataValidationError(
                "procedure='two-stage' needs the steady-state square-wave data: pass "
                "steady_state=(u_ss, y_ss) (or a dict {'u': ..., 'y': ...} / "
                "SteadyStateData), or use procedure='one-record' for one ordinary record.")
        return "two-stage"
    if idf.procedure == "one-record" or steady_state is None:
        return "one-record"
    if _is_prbs(u, idf.prbs_level):
        return "two-stage"
    import warnings

    from ..exceptions import DataWarning

    warnings.warn(
        f"steady-state data were given, but the record's input is not a two-level PRBS "
        f"+-u* ({_not_two_level(u)}), so the two-stage method of the chapter does not apply: "
        "the record is identified as one ordinary record, jointly with the steady-state "
        "points. Pass procedure='one-record' to say so (and silence this), or fix the "
        "record (swapped input and output columns?) and pass procedure='two-stage' to "
        "require the two experiments.", DataWarning, stacklevel=3)
    return "one-record"


def _not_two_level(u) -> str:
    """What keeps ``u`` from being a PRBS ``+-u*``: its first sample off the most common
    magnitude, or its two levels that are not opposite."""
    u = np.asarray(u, dtype=float)
    levels = np.unique(u)
    if levels.size == 1:
        return f"it is constant, u = {levels[0]:.6g}"
    if levels.size == 2:
        return f"its two levels {levels[0]:.6g} and {levels[1]:.6g} are not opposite"
    mags, counts = np.unique(np.abs(u), return_counts=True)
    star = mags[np.argmax(counts)]
    t = int(np.flatnonzero(~np.isclose(np.abs(u), star, rtol=1e-9, atol=0))[0])
    return (f"{levels.size} distinct values; u[{t}] = {u[t]:.6g}, where the most common "
            f"level is +-{star:.6g}")
