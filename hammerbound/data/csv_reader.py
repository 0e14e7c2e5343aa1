"""Reading experiment data from CSV files, with errors that say what to fix."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np

from ..exceptions import DataValidationError
from .timebase import name_and_unit

__all__ = ["PYTHON_NAMES", "csv_header", "load_chapter_tables",
           "read_columns", "read_io_csv"]

#: How the messages of the readers name their settings (the interface in use): the
#: Python keywords by default; the command line passes its flags instead (``{"u":
#: "--u-col NAME", ...}``). Keys: ``u``, ``y`` (the column names), ``t`` (the time
#: column), ``no_t`` (no time column), ``auto_t`` (find it by name), ``dt``, ``delimiter``.
PYTHON_NAMES = {"u": "u='<name>'", "y": "y='<name>'", "t": "t='<name>'", "no_t": "t=None",
                "auto_t": "t='auto'", "dt": "dt=<sampling time>",
                "delimiter": "delimiter=';'"}


def _names(argument_names, **python):
    """The spellings of the settings in messages: ``argument_names`` over ``python``
    over :data:`PYTHON_NAMES`."""
    return {**PYTHON_NAMES, **python, **(argument_names or {})}


def read_columns(path, columns, *, delimiter=",", argument_names=None, text=None
                 ) -> dict[str, np.ndarray]:
    """Read named numeric columns from a CSV file with a header row.

    Parameters
    ----------
    path : str or Path
    columns : sequence of str
        Header names to read.
    delimiter : str, default ","
        Field separator (e.g. ``";"``, ``"\\t"``).
    argument_names : dict, optional
        How messages name the settings (see :data:`PYTHON_NAMES`).
    text : str, optional
        One of ``columns`` read as text, not parsed (a time column of date-times:
        :func:`~.timebase.time_seconds`).

    Returns
    -------
    dict name -> float ndarray (the ``text`` column: a list of str)

    Raises
    ------
    DataValidationError
        Missing file, missing header or column, non-numeric or non-finite value (the
        message names the row and column), empty file.
    """
    try:
        cols = None if isinstance(columns, (str, bytes)) else list(columns)
    except TypeError:
        cols = None
    if not cols or not all(isinstance(c, str) for c in cols):
        raise DataValidationError(
            f"columns must be a non-empty list of header names such as ['u', 'y']; got "
            f"{columns!r}."
        )
    columns = cols
    path = Path(path)
    _check_file(path)
    names = _names(argument_names, u="columns=[...]", y="columns=[...]")
    try:
        return _read_columns(path, columns, _delimiter(delimiter, names), names, text)
    except UnicodeDecodeError as exc:
        raise DataValidationError(
            f"{path}: not a UTF-8 text CSV file ({exc.reason} at byte {exc.start}); save it "
            "as plain UTF-8 CSV."
        ) from None


#: spellings of a tab that a shell passes as text
_TAB = ("\\t", "tab", "TAB", "\\\\t")


def _check_file(path: Path) -> None:
    if path.is_dir():
        raise DataValidationError(f"{path} is a directory, not a CSV file; give the file.")
    if not path.is_file():
        raise DataValidationError(f"{path}: no such file; check the path.")


def _separator_hint(header, delimiter, names) -> str:
    """A hint when the header is one field: the separator it seems to use."""
    if len(header) > 1:
        return ""
    seen = [c for c in (";", "\t", "|", ",") if c != delimiter and c in header[0]]
    if not seen:
        return (f" (one column only: if the fields are separated by another character, "
                f"pass {names['delimiter']})")
    spelled = "tab" if seen[0] == "\t" and names["delimiter"].startswith("--") else \
        repr(seen[0])
    flag = names["delimiter"].replace("';'", spelled)
    return f" (one column only: the header seems separated by {spelled}; pass {flag})"


def _header_hint(header) -> str:
    """A hint when the first row is numbers: the file has no header row."""
    try:
        [float(h) for h in header]
    except ValueError:
        return ""
    return (" (the first row is numbers: the file seems to have no header row; add one "
            "naming the columns, e.g. 'u,y' or 't,u,y')")


#: what a gap in a record asks of the user (a nan or an empty cell)
_GAP_ADVICE = ("cannot be dropped silently (the model needs consecutive samples): split the "
               "record at the gap and fit the longest part, or fill the value if you know it.")


def _not_a_number(path, lineno, column, text) -> str:
    msg = f"{path}, line {lineno}, column {column!r}: {text!r} is not a number."
    if not text.strip():  # an empty cell: a gap, like a nan (recheck 49)
        msg += f" An empty cell is a gap, which {_GAP_ADVICE}"
    if re.fullmatch(r"\s*[-+]?\d*,\d+([eE][-+]?\d+)?\s*", text):
        msg += (" Decimal commas are not read: save the file with decimal points (e.g. "
                "from a spreadsheet with an English number format).")
    return msg


def _named_width(header) -> int:
    """The header's columns up to its last non-empty name (``u,y,`` from a spreadsheet has
    two: a value under the unnamed third column is a shifted one, review 49)."""
    names = [h.strip() for h in header]
    while names and not names[-1]:
        names.pop()
    return len(names)


def _usual_width(rows) -> int:
    """The most common number of fields (trailing empty ones dropped) of headerless rows:
    a first row with a decimal comma must not set the width the others are checked
    against (review 49)."""
    widths = [_named_width(r) for _, r in rows]
    return max(set(widths), key=widths.count) if widths else 0


def _check_width(path, lineno, row, width, delimiter) -> None:
    """A row with more (non-empty) fields than the header has its values shifted into
    other columns: a decimal comma in a comma-separated file (``2.38,3.5,8,827`` read
    3.5 and 8.0, new-user trial 17) or a stray separator. Refused, never read."""
    if len(row) > width and any(f.strip() for f in row[width:]):
        sep = "a tab" if delimiter == "\t" else repr(delimiter)
        raise DataValidationError(
            f"{path}, line {lineno}: the row has {len(row)} fields but the header (or first "
            f"row) has {width}, so its values would land in the wrong columns: "
            f"{delimiter.join(row)!r}. A decimal comma in a file separated by {sep}, or a "
            "stray separator? Fix the row (decimal points, e.g. 8.827 not 8,827), or pass "
            "the file's own delimiter.")


_INTEGER = re.compile(r"\s*[-+]?\d+")
_DIGITS = re.compile(r"\d+(?:[eE][-+]?\d+)?\s*")


def _check_rows(path, rows, width, read, delimiter) -> None:
    """Every check of shifted values on the rows ``(lineno, row)``: more fields than
    ``width`` (:func:`_check_width`) and a decimal comma into a usually empty column
    (:func:`_check_shifts`; ``read``: the indices of the columns read)."""
    for lineno, row in rows:
        _check_width(path, lineno, row, width, delimiter)
    _check_shifts(path, rows, read, delimiter)


def _check_shifts(path, rows, read, delimiter) -> None:
    """A decimal comma can also shift values into a *named* column that is usually empty
    (``u,y,note``: ``2,38,3.5`` reads y = 38, recheck 49). Refused: a row of a
    comma-separated file with more non-empty fields than most rows, where at or before a
    column that is read (``read``: their indices) an integer stands in a column whose
    values are mostly not integers and a field of digits follows it. (A file of integer
    counts with a sometimes-filled flag column is read as it is.)"""
    if delimiter != "," or not rows:
        return
    counts = [sum(1 for f in r if f.strip()) for _, r in rows]
    usual = max(set(counts), key=counts.count)
    last = max(read)
    typical = [r for (_, r), c in zip(rows, counts, strict=True) if c == usual]

    def decimal(j):  # the column's values are mostly not integers
        vals = [r[j] for r in typical if j < len(r) and r[j].strip()]
        return sum(not _INTEGER.fullmatch(v) for v in vals) > len(vals) / 2

    for (lineno, row), count in zip(rows, counts, strict=True):
        if count <= usual:
            continue
        for i in range(min(last, len(row) - 2) + 1):
            if _INTEGER.fullmatch(row[i]) and _DIGITS.fullmatch(row[i + 1]) \
                    and decimal(i) and _numbers_when_joined(row, i, read):
                raise DataValidationError(
                    f"{path}, line {lineno}: the row has {count} values where most rows "
                    f"have {usual}, and {row[i]!r} followed by {row[i + 1]!r} looks like "
                    f"one number with a decimal comma ({row[i]},{row[i + 1]}), which "
                    f"would put values into the wrong columns: {','.join(row)!r}. Save "
                    "the file with decimal points (e.g. from a spreadsheet with an "
                    "English number format); if the row is right as it is, write its "
                    "integers with a decimal point (e.g. 2.0).")


def _numbers_when_joined(row, i, read) -> bool:
    """Whether the columns read are numbers once fields ``i`` and ``i + 1`` are joined by a
    decimal point: a decimal comma would have split them so (review 51: a row whose note
    is text, ``2,40,3.5,calibrated`` under ``t,u,y,note``, is a row of integers and a
    note, not a shifted one)."""
    joined = [*row[:i], f"{row[i].strip()}.{row[i + 1].strip()}", *row[i + 2:]]
    try:
        return all(j < len(joined) and float(joined[j]) == float(joined[j]) for j in read)
    except ValueError:
        return False


def _delimiter(delimiter, names) -> str:
    if isinstance(delimiter, str) and delimiter in _TAB:
        return "\t"
    if not isinstance(delimiter, str) or len(delimiter) != 1:
        raise DataValidationError(
            f"the delimiter must be one character (a comma, a semicolon, a tab...), e.g. "
            f"{names['delimiter']}; got {delimiter!r}.")
    return delimiter


def csv_header(path, *, delimiter=",") -> list[str]:
    """The header row (column names) of a CSV file."""
    path = Path(path)
    _check_file(path)
    delimiter = _delimiter(delimiter, PYTHON_NAMES)
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:
            row = next(csv.reader(fh, delimiter=delimiter), None)
    except UnicodeDecodeError as exc:
        raise DataValidationError(
            f"{path}: not a UTF-8 text CSV file ({exc.reason} at byte {exc.start}); save it "
            "as plain UTF-8 CSV.") from None
    if row is None:
        raise DataValidationError(f"{path}: the file is empty; expected a header row.")
    return [h.strip() for h in row]


def __getattr__(name):
    if name == "example_data_path":
        raise AttributeError(
            "hammerbound.data.csv_reader.example_data_path was removed: hammerbound ships no "
            "third-party data. For an example CSV file, write a simulated record with "
            "hammerbound.eiv_example().data.to_csv('eiv_example.csv').")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def column_with_unit(header, name):
    """The column ``name`` of ``header``, or the one column ``name [unit]`` when no column
    is called ``name`` alone (review 49: a record written with its units was not found
    again by its names; the command line's ``--u-col u`` finds ``u [V]`` in every file)."""
    if name is None or name in header:
        return name
    found = [h for h, (base, unit) in zip(header, map(name_and_unit, header), strict=True)
             if base == str(name) and unit]
    return found[0] if len(found) == 1 else name


def _read_columns(path, columns, delimiter, names, text=None):
    with path.open(newline="", encoding="utf-8-sig") as fh:
        reader = csv.reader(fh, delimiter=delimiter)
        try:
            header = [h.strip() for h in next(reader)]
        except StopIteration:
            raise DataValidationError(f"{path}: the file is empty; expected a header row "
                                      f"with columns {list(columns)}.") from None
        actual = {c: column_with_unit(header, c) for c in columns}
        missing = [c for c in columns if actual[c] not in header]
        if missing:
            how = sorted({names["u"], names["y"]})
            other = _separator_hint(header, delimiter, names) or _header_hint(header)
            raise DataValidationError(
                f"{path}: missing column(s) {missing}; the header has {header}{other}. "
                f"Rename the columns or pass the right names ({', '.join(how)})."
            )
        idx = [header.index(actual[c]) for c in columns]
        width = _named_width(header)
        rows = [(lineno, row) for lineno, row in enumerate(reader, start=2)
                if row and any(f.strip() for f in row)]
        _check_rows(path, rows, width, idx, delimiter)
        out = {c: [] for c in columns}
        for lineno, row in rows:
            for c, i in zip(columns, idx, strict=True):
                if i >= len(row):
                    raise DataValidationError(
                        f"{path}, line {lineno}: the row has {len(row)} field(s), column "
                        f"{c!r} is missing."
                    )
                if c == text:
                    out[c].append(row[i])
                    continue
                try:
                    v = float(row[i])
                except ValueError:
                    raise DataValidationError(_not_a_number(path, lineno, c, row[i])) \
                        from None
                if not np.isfinite(v):
                    raise DataValidationError(
                        f"{path}, line {lineno}, column {c!r}: {row[i]!r} is not finite. "
                        f"A gap in a record {_GAP_ADVICE}"
                    )
                out[c].append(v)
    if not out[columns[0]]:
        raise DataValidationError(f"{path}: no data rows after the header.")
    return {c: v if c == text else np.asarray(v, dtype=float) for c, v in out.items()}


def load_chapter_tables(path=None) -> list[dict]:
    """Rows of the chapter's Tables 22.1-22.3 (CSV with columns table, N, delta_eta,
    snr_db, param, true, lower, center, upper, half_width)."""
    if path is None:
        for cand in (Path(__file__).resolve().parent / "chapter22_tables.csv",):
            if cand.is_file():
                path = cand
                break
        else:
            return []
    with Path(path).open(newline="") as fh:
        return list(csv.DictReader(fh))


def _column_index(spec, header, ncols, which, default, path, names, delimiter=","):
    """Position of column ``spec`` (a header name or a 0-based index)."""
    spec = str(spec).strip()
    cols = None if header is None else [h.strip() for h in header]
    if cols is not None and spec.lower() in [c.lower() for c in cols]:
        j = [c.lower() for c in cols].index(spec.lower())
    elif spec.isdigit():
        j = int(spec)
    elif cols is None and spec == which:
        j = default
    elif cols is None:
        raise DataValidationError(
            f"{path} has no header line, so the {which} column cannot be found by the name "
            f"{spec!r}; add a header (e.g. 'u,y') or give a 0-based column index."
        )
    else:
        raise DataValidationError(
            f"column {spec!r} (the {which} column) not found in the header of {path}; columns "
            f"are {cols}{_separator_hint(cols, delimiter, names)}. Rename it or pass "
            f"{names[which]}."
        )
    if j >= ncols:
        found = f"{ncols} column(s)" + ("" if cols is None else f" {cols}")
        hint = "" if ncols > 1 else f" If the fields are separated by another character, pass " \
            f"{names['delimiter']}."
        raise DataValidationError(
            f"{path} needs an input and an output column (u,y) but the {which} column "
            f"(index {j}) is missing: found {found}.{hint}"
        )
    return j


def read_io_csv(path, u_column="u", y_column="y", delimiter=",", *, argument_names=None):
    """Read an input/output record from a CSV file.

    The file may start with a header line naming the columns (then ``u_column`` and
    ``y_column`` are looked up by name, case-insensitively); without a header the
    columns are taken by 0-based index (default: the first two columns are ``u, y``).
    Blank lines and lines starting with ``#`` are ignored. ``argument_names``: how
    messages name the settings (see :data:`PYTHON_NAMES`).

    Returns
    -------
    u, y : ndarray

    Raises
    ------
    DataValidationError
        Unreadable file, missing column, non-numeric or incomplete rows (the message lists
        the offending line numbers), fewer than two columns.
    """
    names = _names(argument_names, u="u_column='<name or index>'",
                   y="y_column='<name or index>'")
    delimiter = _delimiter(delimiter, names)
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            rows = [(i + 1, r) for i, r in enumerate(csv.reader(fh, delimiter=delimiter))]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise DataValidationError(f"cannot read {path}: {exc}") from exc
    rows = [(ln, r) for ln, r in rows
            if r and any(f.strip() for f in r) and not r[0].lstrip().startswith("#")]
    if not rows:
        raise DataValidationError(f"{path} contains no data rows.")

    def numeric(field):
        try:
            float(field)
            return True
        except ValueError:
            return False

    header = None
    if not all(numeric(f) for f in rows[0][1]):
        header, rows = rows[0][1], rows[1:]
    ncols = len(header) if header is not None else len(rows[0][1])
    width = _named_width(header) if header is not None else _usual_width(rows)
    ju = _column_index(u_column, header, ncols, "u", 0, path, names, delimiter)
    jy = _column_index(y_column, header, ncols, "y", 1, path, names, delimiter)
    if ju == jy:
        raise DataValidationError(
            f"the u and y columns of {path} are the same column (index {ju}); pass "
            f"{names['u']} and {names['y']}."
        )
    if not rows:
        raise DataValidationError(f"{path} has a header but no data rows.")
    _check_rows(path, rows, width, (ju, jy), delimiter)
    u, y, bad = [], [], []
    for ln, r in rows:
        try:
            uv, yv = float(r[ju]), float(r[jy])
        except (IndexError, ValueError):
            bad.append((ln, delimiter.join(r)))
            continue
        if not (np.isfinite(uv) and np.isfinite(yv)):
            bad.append((ln, delimiter.join(r)))
            continue
        u.append(uv)
        y.append(yv)
    if bad:
        shown = "; ".join(f"line {ln}: {text!r}" for ln, text in bad[:5])
        more = f" (and {len(bad) - 5} more)" if len(bad) > 5 else ""
        raise DataValidationError(
            f"{path}: {len(bad)} row(s) without two finite numbers in the u and y columns - "
            f"{shown}{more}. Fix or remove them (keep u and y aligned)."
        )
    return np.array(u), np.array(y)
