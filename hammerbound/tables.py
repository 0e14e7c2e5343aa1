"""Named interval tables of fitted estimators: ``summary()`` text and ``to_frame()``.

:func:`interval_frame` returns a pandas DataFrame when pandas is importable, else a numpy
structured array with the same columns (``parameter, lower, centre, upper, half_width,
status``); :func:`interval_text` renders the same table as fixed-width text.
"""

from __future__ import annotations

import numpy as np

__all__ = ["assumptions_text", "bound_text", "dt_text", "interval_frame", "interval_records",
           "interval_text", "number_text", "outward_text", "poly_z", "rounded_text",
           "units_line"]

COLUMNS = ("parameter", "lower", "centre", "upper", "half_width", "status")


def bound_text(bound) -> str:
    """``"0.05"`` for a constant bound, ``"0.01..0.05 (per sample)"`` otherwise; each value
    with the digits it has (up to 10): a bound of 0.0200005 (a rounding allowance added to
    0.02) was shown as 0.02 (new-user trial 15)."""
    v = np.asarray(bound, dtype=float)
    lo, hi = float(np.min(v)), float(np.max(v))
    return number_text(lo) if lo == hi else f"{number_text(lo)}..{number_text(hi)} (per sample)"


def number_text(v: float) -> str:
    """``v`` in the fewest significant digits (4 to 10) that give it back exactly, else 10
    rounded down (``v`` is a bound: the one shown is never looser than the one used)."""
    for digits in (4, 6, 8):
        text = f"{v:.{digits}g}"
        if float(text) == v:
            return text
    return rounded_text(v, down=True, digits=10)


def rounded_text(v: float, down: bool, digits: int = 4) -> str:
    """``v`` in ``digits`` significant digits, rounded down (``down``) or up, never to the
    other side: an assumption shown rounded must be no weaker than the one used (an upper
    limit of an a priori box rounds down, the ends of a range it holds over round
    outward; review: ``m_l in [0, 102.5]`` was shown for a limit of 102.4967)."""
    return _directed_text(v, f"{digits}g", -1 if down else 1,
                          lambda x: 10.0 ** (np.floor(np.log10(abs(x))) - (digits - 1)))


def _directed_text(v: float, fmt: str, side: int, step) -> str:
    """``v`` in the format ``fmt``, to nearest (``side`` 0), else never on the other side
    of ``v`` than ``side``: the nearest text moved by one unit ``step(v)`` of the format's
    last digit when it fell on the wrong side, or ``v``'s own digits when that step
    rounds back past ``v``."""
    text = f"{v:.{fmt}}"
    if side == 0 or not np.isfinite(v) or float(text) == v or (float(text) > v) == (side > 0):
        return text
    text = f"{float(text) + side * step(v):.{fmt}}"
    if (float(text) - v) * side < 0:  # the rounding of the step itself: keep v exactly
        return repr(float(v))
    return text


def assumptions_text(items) -> str:
    """The assumptions a summary's intervals rest on: ``assumptions:`` and one ``  - item``
    line each (every summary lists them so, after its table:
    :meth:`~hammerbound.results.IntervalSet.summary`)."""
    return "assumptions:\n" + "\n".join(f"  - {a}" for a in items)


def units_line(units) -> str:
    """``"\nunits: m_l, m_r in mm/V; ..."`` from a record's ``(input, output)`` units, for
    a summary's head (empty when the record gives none; trial 17: with ``u [V]`` and
    ``y [mm]`` no parameter carried a unit)."""
    u, y = units
    if not (u or y):
        return ""
    u, y = u or "input unit", y or "output unit"
    return (f"\nunits: m_l, m_r in {y}/{u}; c_l, c_r in {u}; a_i, b_j none (unit gain: the "
            f"inner signal x is in {y})")


def dt_text(dt, unit: str = "") -> str:
    """A sampling time as the summaries print it: ``0.1 ms``, ``0.1`` (no unit known) or
    ``not given``."""
    return "not given" if dt is None else f"{dt:g} {unit}".strip()


def poly_z(coefs) -> str:
    """``[0.75, -0.28]`` -> ``"0.75 z - 0.28"`` (descending powers of z)."""
    c = np.trim_zeros(np.asarray(coefs, dtype=float), "f")
    if c.size == 0:
        return "0"
    terms = []
    for k, v in enumerate(c):
        p = c.size - 1 - k
        if v == 0:
            continue
        mag = abs(v)
        num = "" if (mag == 1 and p > 0) else f"{mag:.4g}"
        zp = "" if p == 0 else ("z" if p == 1 else f"z^{p}")
        term = " ".join(t for t in (num, zp) if t)
        sign = "-" if v < 0 else "+"
        terms.append(term if not terms and v > 0 else f"{sign} {term}" if terms
                     else f"-{term}")
    return " ".join(terms)


def interval_records(names, bounds, status=None) -> list[dict]:
    """One dict per parameter with the keys of :data:`COLUMNS`."""
    b = np.asarray(bounds, dtype=float).reshape(-1, 2)
    status = list(status) if status is not None else ["optimal"] * len(names)
    # an interval unbounded on a side ([0, inf], [-inf, inf]) has no centre: NaN ("-" in
    # the text, null in JSON; a half-open interval showed "inf", trial 9)
    return [{"parameter": str(n), "lower": float(lo),
             "centre": float(0.5 * lo + 0.5 * hi) if np.isfinite(lo) and np.isfinite(hi)
             else float("nan"), "upper": float(hi),
             "half_width": float(0.5 * hi - 0.5 * lo), "status": s}
            for n, (lo, hi), s in zip(names, b, status, strict=True)]


def interval_frame(names, bounds, status=None):
    """pandas DataFrame (if pandas is installed) or numpy structured array of the intervals."""
    recs = interval_records(names, bounds, status)
    try:
        import pandas as pd
    except ImportError:
        width = max([len(r["parameter"]) for r in recs] + [1])
        swidth = max([len(r["status"]) for r in recs] + [1])
        dtype = [("parameter", f"U{width}"), ("lower", float), ("centre", float),
                 ("upper", float), ("half_width", float), ("status", f"U{swidth}")]
        return np.array([tuple(r[c] for c in COLUMNS) for r in recs], dtype=dtype)
    return pd.DataFrame.from_records(recs, columns=list(COLUMNS))


def outward_text(v: float, fmt: str, side: int) -> str:
    """``v`` in ``fmt`` (``"4f"`` or ``"3e"``), rounded down (``side < 0``), up (``> 0``)
    or to nearest (0); infinite values as ``inf``/``-inf``."""
    decimals = int(fmt[:-1])
    if fmt.endswith("f"):
        return _directed_text(v, fmt, side, lambda x: 10.0 ** -decimals)
    return _directed_text(v, fmt, side,  # the last digit of the nearest text's mantissa
                          lambda x: 10.0 ** (int(f"{x:.{fmt}}".split("e")[1]) - decimals))


def interval_text(names, bounds, status=None, *, title=None, digits=4) -> str:
    """Fixed-width text table of the intervals (the ``summary()`` of estimators); the
    number columns widen to their longest entry (new-user trial 20: intervals 1e-7 wide,
    printed with 9 decimals, shifted the columns)."""
    recs = interval_records(names, bounds, status)
    w = max([len(r["parameter"]) for r in recs] + [9])
    cells = [_number_cells(r, digits) for r in recs]
    cw = max([digits + 7] + [len(c) for row in cells for c in row])
    lines = [] if title is None else [title]
    lines.append(f"{'parameter':<{w}} {'lower':>{cw}} {'centre':>{cw}} {'upper':>{cw}} "
                 f"{'half-width':>{cw}}  status")
    for r, row in zip(recs, cells, strict=True):
        nums = " ".join(f"{c:>{cw}}" for c in row)
        lines.append(f"{r['parameter']:<{w}} {nums}  {r['status']}")
    return "\n".join(lines)


def _number_cells(r, digits) -> list[str]:
    """Lower, centre, upper and half-width of one interval record as text."""
    # a row whose numbers are all below 0.01 (e.g. a slope in m3/s per %) in
    # scientific notation: fixed decimals would print it as 0.0000
    mag = max(abs(r["lower"]), abs(r["upper"]))
    fmt = f"{digits - 1}e" if np.isfinite(mag) and 0 < mag < 0.01 else f"{digits}f"
    hw = r["half_width"]
    if fmt.endswith("f") and np.isfinite(hw) and 0 < hw < 10.0 ** (1 - digits):
        # a narrow interval keeps two digits of its half-width (up to 10 decimals):
        # rounded outward to 4 decimals, a width of 3e-7 read 0.9999 .. 1.0001
        # (recheck 49)
        fmt = f"{max(digits, min(10, 1 - int(np.floor(np.log10(hw)))))}f"
    # an unbounded interval has no centre: "-", not "nan" or "inf"; the ends round
    # outward and the half-width up, so the printed interval holds the certified one
    # (to nearest, a lower end 0.24636 read 0.2464: a truth at 0.24638 looked outside)
    return ["-" if np.isnan(r[c]) else outward_text(r[c], fmt, side)
            for c, side in (("lower", -1), ("centre", 0), ("upper", 1), ("half_width", 1))]
