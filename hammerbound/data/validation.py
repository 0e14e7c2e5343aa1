"""One validation of signals, bounds and scalar settings for every entry point.

Every public entry point (the estimators, the identifier, the experiment generators,
the bound and scale checks of :func:`~hammerbound.discrepancy.diagnose`, and hence the
command line) validates its inputs here, so the same input gets the same answer
everywhere:

* **signals** (``u``, ``y``, ``X``): real numbers of shape ``(N,)`` or ``(N, 1)``;
  sparse, ragged, text, complex, empty and non-finite inputs are refused;
* **per-sample bounds** (output and input error bounds): a scalar, shape ``(N,)`` or
  ``(N, 1)``; booleans and text are refused (``True`` is not the number 1 here);
* **scalar settings** (a PRBS level, a margin, a steady-state gain): real numbers only;
  booleans and text, even numeric text such as ``"1.0"``, are refused;
* **scale**: the magnitudes the arithmetic can certify (:func:`check_scale`).

Each refusal is a typed error of :mod:`hammerbound.exceptions` whose message says what to
pass instead.
"""

from __future__ import annotations

import numbers

import numpy as np

from ..exceptions import DataScaleError, DataValidationError, ParameterValidationError

__all__ = [
    "SCALE_MAX",
    "SCALE_MIN",
    "SLOPE_MIN",
    "as_bound",
    "as_flag",
    "as_real",
    "as_signal",
    "as_theta",
    "check_excited",
    "check_scale",
]


def _describe(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _is_text(value) -> bool:
    return isinstance(value, (str, bytes, np.str_, np.bytes_))


def _is_bool(value) -> bool:
    return isinstance(value, (bool, np.bool_))


# ------------------------------------------------------------------------------ signals
def as_signal(name: str, v, *, error: type = DataValidationError) -> np.ndarray:
    """A 1-D float signal from a list/array of shape ``(N,)`` or ``(N, 1)``.

    Raises ``error`` (default :class:`DataValidationError`) for sparse, ragged, text,
    complex, multi-column, empty or non-finite input.
    """
    if hasattr(v, "toarray") or hasattr(v, "tocsr"):
        raise error(f"{name}: sparse input is not supported; pass a dense array.")
    try:
        arr = np.asarray(v)
    except (TypeError, ValueError) as exc:  # ragged nested sequences
        raise error(
            f"{name} must be a 1-D array of real numbers (shape (N,) or (N, 1)); got a "
            f"ragged or non-array value ({exc})."
        ) from exc
    if arr.dtype == object or np.iscomplexobj(arr) or not (
        np.issubdtype(arr.dtype, np.number) or arr.dtype == bool
    ):
        raise error(
            f"{name} must contain real numbers; got dtype {arr.dtype}. Convert text columns "
            "with np.asarray(..., dtype=float) and drop imaginary parts with np.real(...)."
        )
    arr = arr.astype(float)
    if arr.ndim == 2 and arr.shape[1] == 1:
        arr = arr[:, 0]
    if arr.ndim != 1:
        raise error(
            f"{name} must be a 1-D signal (shape (N,) or (N, 1)); got shape {arr.shape}."
        )
    if arr.size == 0:
        raise error(f"{name} is empty; pass at least one sample.")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise error(
            f"{name} contains NaN or infinity (first at sample {bad}). The samples are "
            "consecutive in time, so dropping one joins two parts of the record that are not: "
            "repair the value, or fit a stretch of consecutive finite samples (a slice such "
            "as u[:k], y[:k])."
        )
    return arr


# ------------------------------------------------------------------------------ bounds
def as_bound(name: str, value, n: int, *, allow_zero: bool = False,
             shape_error: type = DataValidationError,
             error: type = ParameterValidationError,
             sign_error: type | None = None) -> np.ndarray:
    """A scalar or per-sample bound as a float array of shape ``(n,)``.

    Accepts a real number, or an array of shape ``(n,)`` or ``(n, 1)``. Refuses ``None``,
    text (even numeric text), booleans, complex or non-finite values (``error``), a wrong
    length (``shape_error``), and values ``<= 0`` (``< 0`` with ``allow_zero``; raised as
    ``sign_error``, default ``error``).
    """
    sign_error = error if sign_error is None else sign_error
    what = f"a number or an array of {n} numbers (shape ({n},) or ({n}, 1))"
    if value is None or _is_text(value):
        hint = (f" - pass the number {value} (without quotes)" if _is_text(value)
                and _parses_as_float(value) else "")
        raise error(f"{name} must be {what}; got {_describe(value)}{hint}.")
    if _is_bool(value):
        raise error(f"{name} must be {what}; got the boolean {value!r} - pass a number such "
                    "as 0.05 (True is not taken as 1).")
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged
        raise error(f"{name} must be {what}; got {_describe(value)}.") from exc
    if raw.dtype == bool:
        raise error(f"{name} must be {what}; got an array of booleans - pass numbers.")
    if raw.dtype == object or np.iscomplexobj(raw) or not np.issubdtype(raw.dtype, np.number):
        raise error(f"{name} must be {what}; got {_describe(value)} (dtype {raw.dtype}).")
    arr = raw.astype(float)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    elif arr.ndim == 2 and arr.shape[1] == 1:
        arr = arr[:, 0]
    if arr.shape != (n,):
        raise shape_error(
            f"{name} must be a scalar or have one value per sample (shape ({n},) or "
            f"({n}, 1)); got shape {raw.shape}."
        )
    if not np.all(np.isfinite(arr)):
        raise error(f"{name} must be finite (no NaN or infinity).")
    if allow_zero:
        if np.any(arr < 0):
            raise sign_error(f"{name} must be finite and >= 0; got min {arr.min():g}.")
    elif np.any(arr <= 0):
        raise sign_error(
            f"{name} must be > 0 (a bounded-error method needs a positive error bound; a bound "
            f"of 0 makes the set degenerate - use the smallest bound you can guarantee); got "
            f"min {arr.min():g}."
        )
    return arr


def _parses_as_float(text) -> bool:
    try:
        float(text)
    except (TypeError, ValueError):
        return False
    return True


# ------------------------------------------------------------------------------ scalars
def as_real(name: str, value, *, positive: bool = False, nonzero: bool = False,
            lo: float | None = None, hi: float | None = None, or_none: bool = False,
            example: str = "0.5", want: str | None = None,
            error: type = ParameterValidationError) -> float | None:
    """A finite real number (``int``, ``float``, numpy scalar or 0-d array).

    Booleans and text are refused, numeric text (``"1.0"``) included: the message tells
    the user to pass the number itself. ``positive`` requires ``> 0``, ``nonzero`` ``!= 0``,
    ``lo``/``hi`` the open interval ``(lo, hi)``; ``or_none`` lets ``None`` through.
    ``want`` replaces the generated "must be ..." sentence.
    """
    if or_none and value is None:
        return None
    kind = "finite non-zero number" if nonzero else "finite number"
    rng = " > 0" if positive else ""
    if lo is not None and hi is not None:
        rng = f" in ({lo:g}, {hi:g})"
    if want is None:
        want = (f"{name} must be a {kind}{rng}{' or None' if or_none else ''}, e.g. "
                f"{name}={example}")
    if _is_text(value):
        hint = (f"; pass the number {value} (without quotes)" if _parses_as_float(value)
                else "")
        raise error(f"{want}; got the text {_describe(value)}{hint}.")
    if _is_bool(value):
        raise error(f"{want}; got the boolean {value!r} (True is not taken as 1).")
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype != bool:
        value = value[()]
    if not isinstance(value, numbers.Real) or _is_bool(value):
        raise error(f"{want}; got {_describe(value)} of type {type(value).__name__}.")
    v = float(value)
    bad = (not np.isfinite(v) or (positive and v <= 0) or (nonzero and v == 0)
           or (lo is not None and v <= lo) or (hi is not None and v >= hi))
    if bad:
        raise error(f"{want}; got {_describe(value)}.")
    return v


def discrete_dt(dt, default=None):
    """The sampling time of a discrete ``control.TransferFunction``: a finite number > 0,
    or python-control's ``True`` (discrete, sampling time not given). ``None`` takes
    ``default`` (the data's sampling time), else ``True``. ``0`` would make
    python-control build a *continuous-time* model from discrete coefficients, and
    negative or non-finite values mean nothing here: all are refused."""
    if dt is None:
        dt = default
    if dt is None or dt is True:
        return True
    return as_real("dt", dt, positive=True, example="0.1",
                   want="dt must be the sampling time (a finite number > 0) or True "
                        "(discrete, sampling time not given): the model is discrete-time "
                        "(dt=0 would mean continuous-time; for a continuous model convert "
                        "the discrete one with control.d2c(G, method='zoh'))")


def as_flag(name: str, value, *, error: type = ParameterValidationError) -> bool:
    """``True`` or ``False`` (Python or numpy booleans only; ``"no"``, 0 and 1 are refused)."""
    if not _is_bool(value):
        raise error(f"{name} must be True or False; got {_describe(value)}.")
    return bool(value)


def as_theta(theta, p: int, names, *, name: str = "theta",
             error: type = DataValidationError) -> np.ndarray:
    """A parameter vector of shape ``(p,)`` in the order ``names``, finite.

    Used by every ``contains``: a NaN parameter is refused rather than answered ``False``.
    """
    names = tuple(names)
    if _is_text(theta) or _is_bool(theta):
        th = None
    else:
        try:
            raw = np.asarray(theta)
            th = None if (raw.dtype == bool or raw.dtype == object or np.iscomplexobj(raw)
                          or not np.issubdtype(raw.dtype, np.number)) else raw.astype(float)
        except (TypeError, ValueError):
            th = None
    if th is None or th.shape != (p,):
        raise error(
            f"{name} must be {p} numbers of shape ({p},) in order {names}; got "
            f"{_describe(theta)}."
        )
    if not np.all(np.isfinite(th)):
        bad = [names[k] for k in np.flatnonzero(~np.isfinite(th))]
        raise error(
            f"{name} has a NaN or infinite value for {', '.join(bad)}; membership of a "
            f"non-finite parameter is undefined - pass finite numbers in order {names}."
        )
    return th


def check_excited(where: str, input_name: str, u, output_name: str, y) -> None:
    """Refuse an identically zero input or output record (the data carry no information).

    With ``y == 0`` exactly, every stable ``A(q^-1)`` in the a priori box explains the data
    (the "bounds" on ``a`` would be the prior, not a measurement) - and a record of exact
    zeros from a real sensor with bounded noise is, in practice, a wrong column or a
    disconnected sensor. With ``u == 0`` nothing about ``B`` can be learnt. Both are
    refused with a :class:`DataValidationError` rather than answered with a box.
    """
    if not np.any(np.asarray(u)):
        raise DataValidationError(
            f"{where}: the input {input_name} is identically zero, so the data carry no "
            "information about the dynamics; record data with an exciting input (e.g. a "
            "PRBS)."
        )
    if not np.any(np.asarray(y)):
        raise DataValidationError(
            f"{where}: the output {output_name} is identically zero while the input varies: "
            "the data carry no information about the dynamics (every stable A(q^-1) would "
            "be feasible, so the bounds would only repeat the a priori box). Check the "
            "output column and the sensor; pass the measured output."
        )


def warn_bound_covers_output(where: str, output_name: str, y, bound, *,
                             stacklevel: int = 4) -> None:
    """Warn (:class:`DataWarning`) when the output error bound of a one-record fit is at
    least half the output's range on every sample: a constant output then explains the
    record within the bound, and a backlash whose dead band spans the input's range gives
    one, with any linear block, so the record identifies nothing (the intervals stay
    guaranteed). Often the bound and the output are in different units.

    Only for the one-record identification: the linear block of stage 2 has no offset, so
    there a constant output does not explain every record."""
    y = np.asarray(y, dtype=float)
    half = 0.5 * float(np.max(y) - np.min(y)) if y.size else 0.0
    low = float(np.min(bound))
    if y.size and low >= half:
        import warnings

        from ..exceptions import DataWarning

        warnings.warn(
            f"{where}: the output error bound ({low:.4g}) is at least half the range of the "
            f"output {output_name} ({2 * half:.4g}), so a constant output explains the record "
            "within it (a dead band as wide as the input's range gives one) and the record "
            "identifies nothing; the intervals stay guaranteed. Check that the bound and the "
            "output are in the same units; if they are, the record is too small against its "
            "noise.", DataWarning, stacklevel=stacklevel)


# ------------------------------------------------------------------------------ scale
#: Smallest and largest magnitude ``max_t |s_t|`` of a signal the bounds are certified for.
SCALE_MIN = 1e-7
SCALE_MAX = 1e9
#: Smallest ratio ``max |y| / max |u|`` of stage-1 data (the order of the slopes ``m``).
SLOPE_MIN = 1e-9


def check_scale(where: str, signals: dict, bounds: dict | None = None, *,
                slope: tuple[str, str] | None = None, hint: str = "") -> None:
    """Refuse data whose magnitudes lie outside what the arithmetic can certify.

    Parameters
    ----------
    where : str
        The entry point, for the message (e.g. ``"BacklashSetEstimator.fit"``).
    signals : dict of name -> array
        Signals (``u``, ``y``, ``X``): each largest magnitude ``max_t |s_t|`` must lie in
        ``[SCALE_MIN, SCALE_MAX] = [1e-7, 1e9]`` (an identically zero signal is left to
        the caller, which knows whether it is an error).
    bounds : dict of name -> array, optional
        Per-sample bounds: their largest value must not exceed ``SCALE_MAX`` (a small
        bound is always sound: the tolerance policy only widens the set).
    slope : (str, str), optional
        Names ``(y, u)`` of two ``signals`` whose ratio ``max|y| / max|u|`` must be at
        least ``SLOPE_MIN = 1e-9`` (stage 1, where it is the order of the slopes ``m``).
    hint : str
        How to rescale for this entry point (appended to the message).

    Raises
    ------
    DataScaleError
        A :class:`DataValidationError` that gives the offending magnitude and how to
        rescale.

    Notes
    -----
    *Why a range at all.* The arithmetic is ordinary double precision, but the decisions
    around it are not scale-free. The LP solver (HiGHS) accepts constraint violations and
    reports dual bounds to an *absolute* tolerance of ``1e-7``; the half-plane
    intersection and the empty-set certificate of stage 1 use absolute terms of order
    ``1e-13`` next to the relative ``FEASIBILITY_RTOL = 1e-9`` of
    :mod:`hammerbound.tolerances`; and the a priori boxes (``|b_j| <= 1e4``, the big-M box
    ``1e6 max|y| / min|u|`` of stage 1) are fixed numbers. When the data's magnitudes are
    near or below those absolute tolerances, or products with the boxes exhaust the
    ``~16`` significant digits, the solvers stop resolving the error bound and the
    decisions "empty" / "unbounded" become statements about rounding, not about the data.

    *Measured* (chapter example, ``N = 60``, every signal and bound scaled by ``10^k``).
    Stage 1 returned the truth-containing set, identical relative widths, for data
    magnitudes ``2.5e-9 .. 2.5e13`` and declared consistent data empty for ``k <= -10``
    and ``k >= 14`` (so ``1e300`` and ``1e-300`` fail); with ``u`` and ``y`` scaled
    independently it failed at ``max|y| / max|u| = 1e-10`` in 2 of 3 cases (slopes
    ``m ~ 1e-10``), succeeded in all 14 cases tried at ``1e-9 .. 3e-9`` and was unaffected
    up to ``1e16``. The stage-2 LP bounds were identical to 3 digits for
    ``k`` in ``[-7, 9]`` (magnitudes ``2.5e-7 .. 2.5e9``), looser but still containing the
    truth at ``k = -8, 10, 12, 13``, and ``UnboundedSetError`` at ``k = -9`` and from
    ``k = 14``. At the edges
    ``1e-7`` and ``1e9`` the LP, moment and exact methods all returned intervals containing
    the truth (the exact method with a node/time limit is looser there than at ``1``:
    its branch-and-bound gaps close more slowly).

    *The range.* ``[1e-7, 1e9]`` for signal magnitudes (``SLOPE_MIN = 1e-9`` for stage 1)
    keeps a factor of at least 10 from every measured failure, contains the range
    ``1e-6 .. 1e6`` over which the extremal-noise tests run, and is far wider than any
    physical unit choice needs. Data outside it are refused with the fix: divide the
    signals *and* the error bounds by a common factor ``s`` (a power of ten) so that the
    largest magnitudes are near 1. In stage 1 the slopes are then unchanged and the
    dead-zone widths ``c_l``, ``c_r`` are divided by ``s`` (multiply them back); in stage 2
    scaling the input, the output and both bounds by the same factor leaves ``theta``
    unchanged. (Rescaling internally would be exact with powers of two, but it is not
    done: the fitted sets, witnesses and problems would have to be mapped back.)
    """
    found = []
    peaks = {}
    offending = []
    for name, v in signals.items():
        arr = np.asarray(v, dtype=float)
        big = float(np.max(np.abs(arr))) if arr.size else 0.0
        peaks[name] = big
        if big != 0.0 and np.isfinite(big) and not SCALE_MIN <= big <= SCALE_MAX:
            found.append(f"max |{name}| = {big:.3g}")
            offending.append(big)
    for name, v in (bounds or {}).items():
        arr = np.asarray(v, dtype=float)
        big = float(np.max(np.abs(arr))) if arr.size else 0.0
        if np.isfinite(big) and big > SCALE_MAX:
            found.append(f"max {name} = {big:.3g}")
    if found:
        factor = 10.0 ** round(float(np.log10(offending[0] if offending else SCALE_MAX)))
        raise DataScaleError(
            f"{where}: the data are outside the range of magnitudes [{SCALE_MIN:g}, "
            f"{SCALE_MAX:g}] for which the bounds can be certified ({'; '.join(found)}). "
            "Rescale: divide the signals and the error bounds by a common factor s (a "
            f"power of ten, here e.g. s = {factor:g}) so that their largest magnitudes are "
            f"near 1{hint}."
        )
    if slope is not None:
        num, den = slope
        if peaks.get(num, 0.0) > 0 and peaks.get(den, 0.0) > 0:
            ratio = peaks[num] / peaks[den]
            if ratio < SLOPE_MIN:
                raise DataScaleError(
                    f"{where}: max |{num}| / max |{den}| = {ratio:.3g} is below {SLOPE_MIN:g}, "
                    "so the slopes are too small to be certified in double precision. "
                    f"Rescale: multiply {num} and the error bound by a power of ten s (the "
                    f"slopes are multiplied by s; divide their bounds by s afterwards)."
                )
