"""Reading results and formatting numbers for docs/benchmarks.md (shared by the report's
modules: benchmarks/report.py and its sections)."""

from __future__ import annotations

import csv

import numpy as np

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

NOTES = C.HERE / "report_notes.md"


def _csv(name):
    p = C.RESULTS / name
    if not p.exists():
        return None
    with open(p) as fh:
        return list(csv.DictReader(fh))


def _json(name):
    p = C.RESULTS / name
    return C.read_json(p) if p.exists() else None


def _with_rows(name):
    """The results file ``name`` if it exists and has rows (else None: no section)."""
    j = _json(name)
    return j if j and j.get("rows") else None


def f(v, nd=4):
    if v is None or v == "":
        return "–"
    try:
        x = float(v)
    except (TypeError, ValueError):
        return str(v)
    if np.isnan(x):
        return "–"
    return f"{x:.{nd}f}"


def fs(v):
    """seconds"""
    if v is None or v == "":
        return "–"
    x = float(v)
    return f"{x:.3f}" if x < 1 else (f"{x:.2f}" if x < 10 else f"{x:.1f}")


table = C.markdown_table


def notes_section(key):
    """Text between '<!-- key -->' and the next '<!-- ' marker of report_notes.md."""
    if not NOTES.exists():
        return ""
    text = NOTES.read_text()
    marker = f"<!-- {key} -->"
    if marker not in text:
        return ""
    part = text.split(marker, 1)[1]
    return part.split("<!-- ", 1)[0].strip() + "\n"


def env_line(j):
    if not j or "environment" not in j:
        return ""
    e = j["environment"]
    return (f"_Run {e['date']}, Python {e['python']}, {e['cpu_count']} CPUs, load average at start "
            f"{e['loadavg_at_start'][0]} (shared machine)._")
