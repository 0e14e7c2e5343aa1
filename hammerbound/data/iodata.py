"""Input/output data with a sampling time, names and units (in the spirit of MATLAB's iddata).

:class:`IOData` carries one SISO record ``(u, y)``, its sampling time ``dt`` and the names
and units of both signals. Every estimator's ``fit`` accepts it in place of ``(X, y)``;
``dt`` then flows into ``to_transfer_function()`` and the names into the reports. pandas is
optional: :meth:`IOData.from_frame` reads a DataFrame, :meth:`IOData.from_csv` a CSV file
with a header row.

Sampling time convention (python-control): ``dt=None`` means "discrete, sampling time not
given"; transfer functions built from such data get ``dt=True``.
"""

from __future__ import annotations

import numbers

import numpy as np

from ..exceptions import DataValidationError, DataWarning, ParameterValidationError
from .csv_reader import PYTHON_NAMES
from .timebase import find_time_column, name_and_unit, name_with_unit, time_unit_of, uniform_step
from .validation import as_signal

__all__ = ["IOData", "signal_label", "uniform_step"]


def signal_label(names, units) -> str:
    """``"force [N] -> position [mm]"``, or ``""`` for the defaults ``u -> y`` without units."""
    if tuple(names) == ("u", "y") and not any(units):
        return ""
    return " -> ".join(name_with_unit(n, un) for n, un in zip(names, units, strict=True))


def _check_dt(dt):
    if dt is None:
        return None
    if isinstance(dt, bool) or not isinstance(dt, numbers.Real) or not np.isfinite(dt) \
            or dt <= 0:
        raise ParameterValidationError(
            f"dt (sampling time) must be a finite number > 0 or None (not given); got {dt!r}.")
    return float(dt)


class IOData:
    """One SISO input/output record with sampling time, names and units.

    Parameters
    ----------
    u, y : array-like of shape (N,)
        Input and measured output, one value per sample.
    dt : float or None, default None
        Sampling time, in ``time_unit`` (seconds when that is empty). ``None``: not given
        (python-control's ``dt=True``; frequencies are then in rad/sample).
    input_name, output_name : str, default "u", "y"
    input_unit, output_unit : str, default ""
    t0 : float, default 0.0
        Time of the first sample.
    time_unit : str, default ""
        Unit of ``dt`` and ``t0`` (e.g. ``"ms"``; read from a time column named like
        ``"t [ms]"``); empty: seconds, python-control's convention (frequencies in rad/s).

    Attributes
    ----------
    N : int
    time : ndarray of shape (N,)
        ``t0 + k dt`` (``k`` when ``dt`` is None).
    sample_index : ndarray of shape (N,)
        Index of every sample in the original record; a subset taken by ``data[idx]``
        keeps it, so estimators can refuse non-contiguous subsets.

    Examples
    --------
    >>> import numpy as np
    >>> data = IOData(np.ones(5), np.zeros(5), dt=0.1, input_name="voltage", input_unit="V")
    >>> data
    IOData(N=5, dt=0.1, input='voltage' [V], output='y')
    >>> data[1:3].time
    array([0.1, 0.2])
    """

    def __init__(self, u, y, dt=None, *, input_name="u", output_name="y", input_unit="",
                 output_unit="", t0=0.0, sample_index=None, time_unit=""):
        self.u = as_signal("u", u)
        self.y = as_signal("y", y)
        if self.u.shape != self.y.shape:
            raise DataValidationError(
                f"u and y must have the same number of samples; got {self.u.size} and "
                f"{self.y.size}.")
        self.dt = _check_dt(dt)
        for k, v in (("input_name", input_name), ("output_name", output_name),
                     ("input_unit", input_unit), ("output_unit", output_unit),
                     ("time_unit", time_unit)):
            if not isinstance(v, str):
                raise ParameterValidationError(f"{k} must be a string; got {v!r}.")
        self.input_name, self.output_name = input_name, output_name
        self.input_unit, self.output_unit = input_unit, output_unit
        self.time_unit = time_unit
        if not (isinstance(t0, numbers.Real) and np.isfinite(t0)):
            raise ParameterValidationError(f"t0 must be a finite number; got {t0!r}.")
        self.t0 = float(t0)
        idx = np.arange(self.u.size) if sample_index is None else np.asarray(sample_index)
        if idx.shape != self.u.shape or not np.issubdtype(idx.dtype, np.integer):
            raise DataValidationError("sample_index must be N integers.")
        self.sample_index = idx

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_csv(cls, path, *, u="u", y="y", t="auto", dt=None, delimiter=",",
                 argument_names=None, **names) -> IOData:
        """Read the columns ``u`` and ``y`` (header names) of a CSV file.

        ``t`` names the time column; ``"auto"`` (default) takes the one column with a usual
        time name (``t``, ``time``, ``Time``, ``timestamp``..., also with a unit such as
        ``t [s]`` or ``time (ms)``, which sets ``time_unit``); ``None`` uses none. The time
        column must be uniformly sampled and gives ``dt`` (to the precision the column
        supports: ``0, 0.01, 0.02, ...`` gives 0.01) and ``t0``. If ``dt`` is also given,
        the two must agree, except for a column that counts samples (0, 1, 2, ...: steps of
        exactly 1), which is then read as sample numbers in units of ``dt``. With
        ``t="auto"``, no time column found, no ``dt`` and columns left unused, a
        :class:`~hammerbound.exceptions.DataWarning` names them. ``delimiter``: the field
        separator (default ``","``). ``argument_names``: how messages name these settings
        (default the keywords above; see
        :data:`hammerbound.data.csv_reader.PYTHON_NAMES`). Other keywords: the names and
        units of :class:`IOData` (names default to the column names; a name with a unit,
        ``u [V]``, gives name ``u`` and unit ``V``, and ``u="u"`` finds it when no column
        is named ``u`` alone: :meth:`to_csv` writes units so).
        """
        from .csv_reader import (
            _header_hint,
            _names,
            _separator_hint,
            column_with_unit,
            csv_header,
            read_columns,
        )
        from .timebase import time_seconds

        spell = _names(argument_names)
        header = csv_header(path, delimiter=delimiter)
        u, y = column_with_unit(header, u), column_with_unit(header, y)
        hint = _separator_hint(header, delimiter, spell) or _header_hint(header)
        t = cls._time_column(header, t, (u, y), str(path), dt, spell, hint)
        data = read_columns(path, [u, y] + ([t] if t else []), delimiter=delimiter,
                            argument_names=spell, text=t)
        tt, stamps = None, False
        if t:  # numbers, or date-times as seconds from the first (trial 18)
            tt, unit = time_seconds(data[t], str(path), t, spell)
            stamps = unit is not None
            if stamps:
                tt = _in_time_unit(tt, names)
        return cls._build(data[u], data[y], tt, t, dt, str(path), u, y, names, spell,
                          stamps=stamps)

    @classmethod
    def from_frame(cls, frame, *, u="u", y="y", t="auto", dt=None, **names) -> IOData:
        """Build from a pandas DataFrame (or any mapping of columns): columns ``u``, ``y``
        and a time column ``t`` (same rules as :meth:`from_csv`). Without a time column
        or ``dt``, a datetime (or timedelta) index of the frame is the time base, in
        seconds."""
        cols = [str(c) for c in frame]
        t = cls._time_column(cols, t, (str(u), str(y)), "the frame", dt, PYTHON_NAMES)
        try:
            uu, yy = np.asarray(frame[u], dtype=float), np.asarray(frame[y], dtype=float)
            tt, stamps = (None, False) if t is None else _column_seconds(frame[t], t, names)
        except KeyError as exc:
            raise DataValidationError(
                f"column {exc} not found; the frame has {list(frame)}.") from None
        if t is None and tt is None and dt is None:
            tt = _index_seconds(frame)  # a DatetimeIndex was ignored (dt None, trial 14)
            if tt is not None:
                t = "the frame's index"
                names.setdefault("time_unit", "s")
        elif t is None and tt is None:
            _check_index_dt(_index_seconds(frame), dt, names)
        return cls._build(uu, yy, tt, t, dt, "the frame", str(u), str(y), names,
                          stamps=stamps)

    @staticmethod
    def _time_column(columns, t, used, where, dt, spell, hint=""):
        """The time column's name (or None) for ``t`` = a name, None or "auto" (``hint``:
        a header that is one field names the separator it seems to use, trial 18)."""
        if t is None or t == "":
            return None
        if t != "auto":
            if str(t) not in columns:
                raise DataValidationError(
                    f"{where}: no time column {t!r}; the columns are {list(columns)}{hint}. "
                    f"Pass {spell['t']}, {spell['auto_t']} (recognise t, time, 't [s]'...) "
                    f"or {spell['no_t']} (none).")
            return t
        found = find_time_column(columns, exclude=used, where=where, spell=spell)
        unused = [c for c in columns if c not in used]
        if found is None and dt is None and unused and all(c in columns for c in used):
            import warnings

            warnings.warn(
                f"{where}: no time column recognised (looked for t, time, timestamp, also "
                f"with a unit as in 't [s]'), so the sampling time is not known and "
                f"frequencies will be in rad/sample; the columns {unused} are not used. Pass "
                f"{spell['t']} if one of them is the time, or {spell['dt']}, or "
                f"{spell['no_t']} to read without a time base.", DataWarning, stacklevel=3)
        return found

    @classmethod
    def _build(cls, u, y, tt, t, dt, where, uname, yname, names, spell=None, stamps=False):
        dt = _check_dt(dt)
        t0 = 0.0
        if tt is not None:
            step = uniform_step(tt, t)
            if dt is None or abs(step - dt) <= 1e-6 * dt:
                dt, t0 = step if dt is None else dt, float(tt[0])
                if time_unit_of(t):  # e.g. "t [ms]"
                    names.setdefault("time_unit", time_unit_of(t))
            elif step == 1.0 and np.all(tt == np.round(tt)) and not stamps:
                t0 = float(tt[0]) * dt           # a sample counter (never date-times)
            else:
                raise DataValidationError(
                    f"{where}: the time column {t!r} has step {step:g} but dt={dt:g} was "
                    f"given; drop one of them (or pass {(spell or PYTHON_NAMES)['no_t']} to "
                    "ignore the column).")
        read = [name_and_unit(c) for c in (uname, yname)]
        for which, column, (base, unit) in zip(("input", "output"), (uname, yname), read,
                                               strict=True):
            if unit and f"{which}_unit" not in names and read[0][0] != read[1][0]:
                # "y [mm]": name y, unit mm (not when both names would read the same)
                names[f"{which}_unit"] = unit
                names.setdefault(f"{which}_name", base)
            names.setdefault(f"{which}_name", column)
        return cls(u, y, dt, t0=t0, **names)

    # ------------------------------------------------------------------ views
    @property
    def N(self) -> int:  # noqa: N802 - system identification notation
        return int(self.u.size)

    @property
    def time(self) -> np.ndarray:
        step = 1.0 if self.dt is None else self.dt
        return self.t0 + step * (self.sample_index - self.sample_index[0]) if self.N else \
            np.zeros(0)

    @property
    def tf_dt(self):
        """``dt`` for ``control.tf``: the sampling time, or ``True`` when not given."""
        return True if self.dt is None else self.dt

    @property
    def shape(self) -> tuple:
        """``(N, 1)``: one input column, so that scikit-learn can index and split it."""
        return (self.N, 1)

    def __len__(self) -> int:
        return self.N

    def __getitem__(self, key) -> IOData:
        if isinstance(key, tuple):  # scikit-learn's _safe_indexing uses data[key, ...]
            if len(key) == 2 and key[1] is Ellipsis:
                key = key[0]
            else:
                raise DataValidationError("IOData supports data[rows] only.")
        if isinstance(key, numbers.Integral):
            key = [key]
        idx = np.arange(self.N)[key]
        if idx.size > 1 and np.any(np.diff(idx) != 1):
            k = int(np.flatnonzero(np.diff(idx) != 1)[0])
            raise DataValidationError(
                f"IOData can only be cut into consecutive samples (a jump from sample "
                f"{idx[k]} to {idx[k + 1]} was asked): identification data are a time series "
                "and the model relates consecutive samples. Cross-validate with "
                "sklearn.model_selection.TimeSeriesSplit (contiguous, forward folds), not "
                "KFold/ShuffleSplit.")
        return IOData(self.u[idx], self.y[idx], self.dt, input_name=self.input_name,
                      output_name=self.output_name, input_unit=self.input_unit,
                      output_unit=self.output_unit,
                      t0=float(self.time[idx[0]]) if idx.size else self.t0,
                      sample_index=self.sample_index[idx], time_unit=self.time_unit)

    def __array__(self, dtype=None, copy=None):
        # numpy (and every scikit-learn transformer, through check_array) would otherwise
        # recurse into __getitem__ and fail with "maximum number of dimension"
        raise DataValidationError(
            "an IOData is a record (input, output, sampling time, names), not a feature "
            "matrix: pass it straight to a hammerbound estimator, not through a scikit-learn "
            "transformer such as StandardScaler. The error bounds are in the units of the "
            "signals, so scaled data need scaled bounds: to scale, build IOData(u / su, "
            "y / sy) yourself and divide the output bound by sy and the input bound by su "
            "(the a_i do not change; a linear block's b_j scale by su / sy, while the "
            "Hammerstein identifier's unit-gain normalisation keeps the b_j and scales the "
            "backlash slopes by su / sy and its widths by 1 / su). Use data.u and data.y "
            "for the arrays.")

    def is_contiguous(self) -> bool:
        """Whether the samples are consecutive in the original record."""
        return bool(np.all(np.diff(self.sample_index) == 1))

    def to_frame(self):
        """A pandas DataFrame with columns time, input, output (pandas must be installed)."""
        import pandas as pd

        return pd.DataFrame({"t": self.time, self.input_name: self.u,
                             self.output_name: self.y})

    def to_csv(self, path) -> None:
        """Write the record as a CSV file with a header row: ``t`` (``t [unit]`` with a
        time unit; omitted when ``dt`` is not given), then the input and output columns
        under their names (``name [unit]`` with a unit), each value written so that
        :meth:`from_csv` reads it back exactly, names and units too."""
        cols = [self.u, self.y]
        header = [name_with_unit(self.input_name, self.input_unit),
                  name_with_unit(self.output_name, self.output_unit)]
        if self.dt is not None:
            cols.insert(0, self.time)
            header.insert(0, f"t [{self.time_unit}]" if self.time_unit else "t")
        if len(set(header)) < len(header) or any("," in h or '"' in h for h in header):
            raise ParameterValidationError(
                f"the column names {header} must be distinct and contain no comma or quote.")
        lines = [",".join(header)]
        for row in zip(*cols, strict=True):
            # the shortest text that reads back to the same float; the time to 12 digits
            vals = [repr(float(v)) for v in row]
            if self.dt is not None:
                vals[0] = f"{row[0]:.12g}"
            lines.append(",".join(vals))
        with open(path, "w", newline="") as fh:
            fh.write("\n".join(lines) + "\n")

    def __repr__(self) -> str:
        dt = "None (not given)" if self.dt is None else f"{self.dt:g}" + (
            f" {self.time_unit}" if self.time_unit else "")
        return (f"IOData(N={self.N}, dt={dt}, input={self.signal_text('input')}, "
                f"output={self.signal_text('output')})")

    def signal_text(self, which: str) -> str:
        """The ``"input"`` or ``"output"`` signal as messages quote it: ``'u' [V]``."""
        return name_with_unit(repr(getattr(self, f"{which}_name")),
                              getattr(self, f"{which}_unit"))


def _same_output(data, y) -> bool:
    """Whether ``y`` is the IOData's own output (same length and values)."""
    try:
        yy = np.asarray(y, dtype=float).ravel()
    except (TypeError, ValueError):
        return False
    return yy.shape == data.y.shape and bool(np.array_equal(yy, data.y, equal_nan=True))


def unpack(X, y, *, what="X", func="fit"):
    """``(u, y, data)`` from ``fit(X, y)`` or ``fit(IOData)``; ``data`` is the IOData or None.

    Raises DataValidationError for a non-contiguous IOData subset (e.g. a KFold training
    fold): a difference equation needs consecutive samples.
    """
    if isinstance(X, IOData):
        # y may repeat the IOData's own output: scikit-learn's scorers (scoring="r2", ...)
        # need y, e.g. cross_val_score(est, data, data.y, scoring="r2")
        if y is not None and not _same_output(X, y):
            raise DataValidationError(
                f"{what} is an IOData, which already holds the output: call {func}(data) "
                f"without y (or with y = {what}.y, as scikit-learn's scorers need).")
        if not X.is_contiguous():
            gaps = np.flatnonzero(np.diff(X.sample_index) != 1)
            k = int(gaps[0])
            raise DataValidationError(
                "the samples are not consecutive (a jump from sample "
                f"{X.sample_index[k]} to {X.sample_index[k + 1]}): identification data are "
                "a time series and the model relates consecutive samples. Cross-validate "
                "with sklearn.model_selection.TimeSeriesSplit (contiguous, forward folds), "
                "not KFold/ShuffleSplit.")
        return X.u, X.y, X
    if y is None:
        raise DataValidationError(
            f"{func} requires y to be passed, but the target y is None: pass the measured "
            f"output y, or an IOData (input, output, dt) as {what}.{_columns_hint(X, func)}")
    return X, y, None


def _columns_hint(X, func) -> str:
    """Advice when ``X`` holds several columns (new-user trial 9: a DataFrame of both the
    input and the output): how to pass them."""
    cols = getattr(X, "columns", None)
    ncol = len(cols) if cols is not None else (np.shape(X)[1] if np.ndim(X) == 2 else 0)
    if ncol < 2:
        return ""
    names = (f" ({', '.join(map(str, list(cols)[:4]))}{', ...' if ncol > 4 else ''})"
             if cols is not None else "")
    return (f" {func} got {ncol} columns{names}: the model has one input and one output. "
            "For a table holding both: IOData.from_frame(frame, u='<input column>', "
            f"y='<output column>'), or {func}(frame['<input column>'], "
            "frame['<output column>']).")


def _column_seconds(column, name, names):
    """A frame's time column as numbers, and whether it held date-times: date-times (or
    their ISO text) as seconds from the first and timedeltas as seconds, in the
    ``time_unit`` of ``names`` if one was given, else "s" (a datetime column was read as
    nanoseconds: dt = 1e7 for 10 s steps, trial 18's follow-up)."""
    from .timebase import time_seconds

    if hasattr(getattr(column, "dt", None), "to_timestamp"):  # periods: their start times
        column = column.dt.to_timestamp()  # (cast directly, they were cut to days)
    values = np.asarray(column)
    if values.dtype.kind not in "mMOSU":
        return np.asarray(values, dtype=float), False
    if values.dtype.kind == "M" or (values.dtype.kind == "O" and hasattr(column, "dt")):
        values = np.asarray(getattr(column, "dt", None).tz_convert(None)
                            if getattr(getattr(column, "dt", None), "tz", None) is not None
                            else column, dtype="datetime64[ns]")
        secs = ((values - values[0]) / np.timedelta64(1, "s")).astype(float)
    elif values.dtype.kind == "m":
        secs = (values / np.timedelta64(1, "s")).astype(float)
    else:
        secs, unit = time_seconds([str(v) for v in values], "the frame", name)
        if unit is None:
            return secs, False
    return _in_time_unit(secs, names), True


#: seconds per time unit a column of date-times can be given in
_SECONDS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "min": 60.0, "h": 3600.0}


def _in_time_unit(seconds, names):
    """Date-times (as ``seconds`` from the first) in the ``time_unit`` given in ``names``,
    or in seconds (then ``time_unit`` "s"); a unit they cannot be put in is refused
    (review 51: ``time_unit='min'`` was kept with dt in seconds)."""
    unit = names.get("time_unit")
    if not unit:
        names["time_unit"] = "s"
        return seconds
    if unit not in _SECONDS:
        raise DataValidationError(
            f"time_unit={unit!r} for a time column of date-times: give one of "
            f"{', '.join(_SECONDS)} (the date-times are converted to it), or none (s).")
    return seconds / _SECONDS[unit]


def _check_index_dt(seconds, dt, names) -> None:
    """A date-time index must agree with a ``dt`` given beside it (new-user trial 22: a gap
    in the index was ignored once ``dt`` was given)."""
    if seconds is None or dt is None or not float(dt) > 0 or len(seconds) < 2:
        return  # (dt itself is checked where it is used)
    from .timebase import uniform_step

    unit = names.setdefault("time_unit", "s")  # the unit the index was checked in
    step = uniform_step(_in_time_unit(seconds, dict(names)), "index")
    if abs(step - float(dt)) > 1e-6 * float(dt):
        raise DataValidationError(
            f"the frame's index steps by {step:g} {unit} but dt={dt:g} was given; drop dt "
            "(the index gives it), or pass frame.reset_index(drop=True) to ignore the index.")


def _index_seconds(frame):
    """The frame's datetime, period or timedelta index as seconds from its first entry, or None
    (no such index: a plain row number says nothing of the time)."""
    index = getattr(frame, "index", None)
    if hasattr(index, "to_timestamp") and hasattr(index, "freq"):  # a PeriodIndex
        index = index.to_timestamp()
    kind = getattr(getattr(index, "dtype", None), "kind", "")
    if kind not in "mM" or kind == "" or len(index) == 0:
        return None
    stamps = np.asarray(index)
    if stamps.dtype.kind not in "mM":  # e.g. a timezone-aware index: its UTC stamps
        stamps = np.asarray(index.tz_convert(None) if hasattr(index, "tz_convert") else index,
                            dtype="datetime64[ns]")
    return ((stamps - stamps[0]) / np.timedelta64(1, "s")).astype(float)
