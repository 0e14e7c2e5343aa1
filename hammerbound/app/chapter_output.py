"""How the chapter's reproduction is shown: the records as tables beside the chapter's, as
JSON, and stdout kept for the JSON document (:mod:`.chapter` computes the records)."""

from __future__ import annotations

import contextlib
import json
import os
import sys

import numpy as np

from ..systems.experiments import CHAPTER_U_STAR

__all__ = ["format_records", "records_json", "stdout_to_stderr", "write_records"]


# --------------------------------------------------------------------------- printing
def _f(v, w=8, d=4):
    return " " * (w - 1) + "-" if v is None else f"{v:{w}.{d}f}"


def format_records(records, file=None) -> None:
    """Print the records as tables: ours (median seed) beside the chapter's, ratio."""
    file = sys.stdout if file is None else file
    groups = []
    for r in records:
        key = (r["table"], r["N"])
        if key not in groups:
            groups.append(key)
    for table, n in groups:
        rows = [r for r in records if (r["table"], r["N"]) == (table, n)]
        r0 = rows[0]
        if table == "22.1":
            title = ("Table 22.1 - backlash parameters (our exact stage 1) and inner-signal "
                     f"levels for u* = {rows[-1].get('u_star', CHAPTER_U_STAR):g}")
        else:
            name = f"({table})" if table.startswith("N=") else table
            title = (f"Table {name} - linear block, N = {n}, method {r0['method']}, "
                     f"stage 1: {r0['stage1']}")
        print(f"\n{title}", file=file)
        print(f"  ours: interval of the median seed, median half-width (min-max) over "
              f"{len(r0['seeds'])} seed(s); chapter in [ ]; ratio = our median half-width / "
              "chapter's; * = truth inside for every seed (! = not)", file=file)
        for deta in dict.fromkeys(r["delta_eta"] for r in rows):
            sub = [r for r in rows if r["delta_eta"] == deta]
            snr = sub[0].get("snr_db")
            snr_t = "" if not snr else f"  (SNR median {np.median(snr):.1f} dB" + (
                f", chapter {sub[0]['chapter_snr_db']:g} dB)" if sub[0].get("chapter_snr_db")
                is not None else ")")
            print(f"  delta_eta = {deta:g}{snr_t}", file=file)
            for r in sub:
                ch = "" if r["chapter_lower"] is None else (
                    f"  [{r['chapter_lower']:.4f} {r['chapter_upper']:.4f} "
                    f"({r['chapter_half_width']:.4f})]")
                ratio = "" if r["ratio"] is None else f"  ratio {r['ratio']:5.2f}"
                print(f"    {r['param']:7s} true {_f(r['true'])}  ours {_f(r['lower'])} "
                      f"{_f(r['upper'])} ({r['median_half_width']:.4f}, "
                      f"{r['half_width_min']:.4f}-{r['half_width_max']:.4f})"
                      f"{'*' if all(r['inside']) else '! NOT INSIDE'}{ch}{ratio}", file=file)


# --------------------------------------------------------------------------- output
@contextlib.contextmanager
def stdout_to_stderr():
    """Send everything written to stdout -- Python's and the C libraries' (file descriptor
    1, e.g. a solver banner) -- to stderr while the block runs, so that stdout can carry
    only a JSON document afterwards."""
    sys.stdout.flush()
    try:
        fd = sys.__stdout__.fileno() if sys.__stdout__ is not None else 1
        saved = os.dup(fd)
    except (OSError, ValueError, AttributeError):  # no real stdout (embedded interpreter)
        fd = saved = None
    old = sys.stdout
    if saved is not None:
        os.dup2(sys.__stderr__.fileno() if sys.__stderr__ is not None else 2, fd)
    sys.stdout = sys.stderr
    try:
        yield
    finally:
        sys.stdout = old
        if saved is not None:
            os.dup2(saved, fd)
            os.close(saved)


def records_json(records) -> str:
    """The records as a JSON list (one object per table row)."""
    return json.dumps(records, indent=1, default=_json_default)


def write_records(records, path, *, file=None) -> None:
    """Write the records as a JSON list to ``path`` (``"-"``: to ``file``, default stdout)."""
    text = records_json(records)
    if str(path) == "-":
        out = sys.stdout if file is None else file
        out.write(text + "\n")
        out.flush()
    else:
        from pathlib import Path

        Path(path).write_text(text + "\n")


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
