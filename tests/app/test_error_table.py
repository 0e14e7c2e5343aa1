"""Every malformed input of tests/error_cases.py raises a typed, actionable error, and
docs/errors.md lists the real messages (regenerate with ``python docs/gen_errors.py``)."""

from __future__ import annotations

import importlib.util
import warnings
from pathlib import Path

import pytest
from error_cases import CASES, run_case

import hammerbound as hb

ROOT = Path(__file__).resolve().parents[2]
BUILTINS = (ValueError, TypeError, RuntimeError, AttributeError, LookupError, OSError)


def test_catalogue_is_large_and_ids_unique():
    assert len(CASES) >= 25
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids))
    # the categories are all represented
    areas = {c.area for c in CASES}
    assert {"stage 1", "stage 2", "identifier", "systems", "experiments", "io"} <= areas


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_raises_typed_actionable_error(case):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exc = run_case(case)
    assert exc is not None, f"{case.id}: {case.call} did not raise"
    # exactly the documented type, not a parent nor an accidental sibling
    assert type(exc) is case.expected, (
        f"{case.id}: expected {case.expected.__name__}, got {type(exc).__name__}: {exc}")
    # catchable through a built-in exception; hammerbound's own types through the base too
    assert isinstance(exc, BUILTINS)
    if case.expected.__module__.startswith("hammerbound"):
        assert isinstance(exc, hb.HammerboundError)
    msg = str(exc)
    assert len(msg) >= 20, f"{case.id}: message too short to be actionable: {msg!r}"
    assert case.hint.lower() in msg.lower(), (
        f"{case.id}: message does not say what to change ({case.hint!r} missing): {msg}")
    # no leaked internals in place of an explanation
    assert not msg.startswith(("float()", "could not convert", "operands could not"))


def _gen_module():
    spec = importlib.util.spec_from_file_location("gen_errors", ROOT / "docs" / "gen_errors.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_docs_errors_table_is_current():
    text = (ROOT / "docs" / "errors.md").read_text()
    assert text == _gen_module().render(), (
        "docs/errors.md is stale: run `python docs/gen_errors.py`")
    # one row per case, each with its exception name
    rows = [ln for ln in text.splitlines() if ln.startswith("| ") and ln[2:3].isdigit()]
    assert len(rows) == len(CASES)
    for case, row in zip(CASES, rows, strict=True):
        assert f"`{case.expected.__name__}`" in row
