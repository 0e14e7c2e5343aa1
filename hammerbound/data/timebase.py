"""The time base of a record: which column is time, and its sampling time.

* :func:`find_time_column` recognises the usual names of a time column (``t``, ``time``,
  ``Time``, ``timestamp``, with or without a unit: ``t [s]``, ``time (ms)``, ``t_s``) and
  reads the unit from the name;
* :func:`uniform_step` checks that the column is uniformly sampled and returns its step
  to the precision the column supports: the mean step over the record, rounded to the
  shortest decimal within the rounding uncertainty of the time values (a column
  ``0, 0.01, 0.02, ...`` gives ``0.01``, not ``0.010000000000000009``).
"""

from __future__ import annotations

import re

import numpy as np

from ..exceptions import DataValidationError
from .validation import as_signal

__all__ = ["TIME_NAMES", "find_time_column", "name_and_unit", "name_with_unit", "time_seconds",
           "time_unit_of", "uniform_step"]

#: the start of an ISO 8601 date-time: a date ``YYYY-MM-DD``
_ISO_DATE = re.compile(r"^[-+]?\d{4,}-\d{2}-\d{2}")
#: base names recognised as a time column (case-insensitive)
TIME_NAMES = ("t", "time", "times", "timestamp", "zeit", "tiempo", "temps")
_UNIT = r"(?:\s*[\[(]\s*(?P<u1>[^\])]*?)\s*[\])]|[ _/](?P<u2>s|sec|secs|seconds|ms|us|min|h))?"
_TIME_RE = re.compile(r"^\s*(?P<base>" + "|".join(TIME_NAMES) + r")" + _UNIT + r"\s*$",
                      re.IGNORECASE)


# a unit in matching brackets after a space: "y [mm]", "u (V)"; not "x[1]", "y(t)" or
# "P [kPa)" (review 49: indices and arguments were read as units)
_NAME_UNIT_RE = re.compile(r"^\s*(?P<base>\S.*?)\s+(?:\[\s*(?P<u1>[^\[\]()]+?)\s*\]"
                           r"|\(\s*(?P<u2>[^\[\]()]+?)\s*\))\s*$")


def name_and_unit(name) -> tuple[str, str]:
    """A column name with a unit in brackets, ``"y [mm]"`` or ``"u (V)"``, as ``("y",
    "mm")``; ``("y", "")`` for a name without one (new-user trial 17: the units of
    ``u [V]`` and ``y [mm]`` were lost, and no parameter carried one)."""
    m = _NAME_UNIT_RE.match(str(name))
    unit = None if m is None else (m.group("u1") or m.group("u2"))
    # "x [1]" is an index, "y [mm] (filtered)" has two candidates: no unit read
    if m is None or unit.isdigit() or any(c in m.group("base") for c in "[]()"):
        return str(name).strip(), ""
    return m.group("base"), unit


def name_with_unit(name, unit) -> str:
    """``"y [mm]"`` (``name`` alone without a unit): how a signal is labelled and written,
    which :func:`name_and_unit` reads back."""
    return f"{name} [{unit}]" if unit else str(name)


def time_unit_of(name) -> str | None:
    """The unit in a time column's name (``"t [s]"`` -> ``"s"``, ``"t"`` -> ``""``), or
    None if the name is not a usual time-column name."""
    m = _TIME_RE.match(str(name))
    if m is None:
        return None
    return (m.group("u1") or m.group("u2") or "").strip()


def find_time_column(columns, exclude=(), where="the data", spell=None) -> str | None:
    """The one column of ``columns`` whose name is a usual time-column name (not one of
    ``exclude``), or None. Several candidates: a DataValidationError asking to choose
    (``spell``: how the message names the settings, keys ``t`` and ``no_t``, as
    :data:`hammerbound.data.csv_reader.PYTHON_NAMES`)."""
    spell = {"t": "t='<name>'", "no_t": "t=None", **(spell or {})}
    found = [c for c in columns if c not in exclude and time_unit_of(c) is not None]
    if len(found) > 1:
        raise DataValidationError(
            f"{where}: several columns look like a time base: {found}; pass {spell['t']} "
            f"for the one to use (or {spell['no_t']} to use none).")
    return found[0] if found else None


def time_seconds(texts, where, column, spell=None) -> tuple[np.ndarray, str | None]:
    """A time column's values from its text: numbers as they are (unit None: the
    column's name says it), or date-times in ISO 8601 form (``2024-03-05 08:00:00``, a
    historian's export; new-user trial 18) as seconds from the first one (unit ``"s"``).
    Anything else: a DataValidationError naming the value and how to read without it."""
    spell = {"no_t": "t=None", "dt": "dt=<sampling time>", **(spell or {})}
    try:
        return np.array([float(v) for v in texts]), None
    except ValueError:
        pass
    import warnings

    stamps = []
    for k, text in enumerate(texts):
        try:
            if not _ISO_DATE.match(text.strip()):  # "0" would be the year 0 (review 51)
                raise ValueError(text)
            with warnings.catch_warnings():  # numpy: "no explicit representation of
                warnings.simplefilter("ignore")  # timezones" (an offset: read as UTC)
                stamps.append(np.datetime64(text.strip().replace(" ", "T", 1), "ns"))
        except ValueError:
            raise DataValidationError(
                f"{where}: the time column {column!r} holds {text!r} (row {k + 1} of the "
                "data), neither a number nor a date-time in ISO 8601 form (e.g. "
                f"2024-03-05 08:00:00). Write it so, or pass {spell['no_t']} and "
                f"{spell['dt']} to read the record without it.") from None
    stamps = np.array(stamps)
    return (stamps - stamps[0]) / np.timedelta64(1, "s"), "s"


def _shortest_decimal(step, unc):
    """The decimal with the fewest digits within ``unc`` of ``step`` (else ``step``)."""
    for k in range(-int(np.floor(np.log10(step))) - 1, 18):
        cand = round(step, k) if k >= 0 else float(round(step, k))
        if cand > 0 and abs(cand - step) <= unc:
            return float(cand)
    return float(step)


def uniform_step(t, name="t") -> float:
    """The constant step of the time vector ``t`` (to the precision it supports), or a
    DataValidationError naming the first irregular sample."""
    t = as_signal(name, t)
    if t.size < 2:
        raise DataValidationError(f"the time column {name!r} needs at least two samples.")
    d = np.diff(t)
    step = float((t[-1] - t[0]) / (t.size - 1))
    if not step > 0 or np.any(d <= 0):
        raise DataValidationError(f"the time column {name!r} must increase.")
    eps = np.finfo(float).eps
    big = max(abs(float(t[0])), abs(float(t[-1])))  # the values' rounding (time stamps)
    bad = np.flatnonzero(np.abs(d - step) > 1e-6 * step + 4 * eps * big)
    if bad.size:
        # judged against the most common step: against the mean, one missing sample made
        # every step look wrong and the first was named (new-user trial 21)
        usual = float(np.median(d))
        off = np.flatnonzero(np.abs(d - usual) > 1e-6 * usual + 4 * eps * big)
        k = int(off[0]) if off.size else int(bad[0])
        ratio = d[k] / usual
        gap = (f" ({round(ratio) - 1} sample(s) missing there?)"
               if ratio > 1.5 and abs(ratio - round(ratio)) < 1e-3 else "")
        raise DataValidationError(
            f"the time column {name!r} is not uniformly sampled: {name}[{k + 1}] - "
            f"{name}[{k}] = {d[k]:g}, expected {usual:g} (the most common step){gap}. "
            "Resample the record (set-membership identification of a difference equation "
            "needs a constant sampling time).")
    # rounding of the two end values (and of the division), spread over the record; a
    # value read from text with few digits is exact to well within this
    unc = 4 * eps * big / (t.size - 1) + 4 * eps * step
    return _shortest_decimal(step, unc)
