"""Every ```python block in README.md and docs/*.md runs, and prints what the doc says.

Format: a ```python block may be followed (after at most one blank line) by a fenced block
with info string ``output`` holding the expected stdout of that block. Blocks of one file
share a namespace. The printed text is compared with the expected text token by token:
numbers with ``rtol = 1e-3`` and ``atol = 1e-6`` and at most 3 more significant digits
than the doc shows (a rounded doc may not hide a 17-digit float), other tokens exactly
(whitespace is not significant; ``0.8907...`` is a number of which the doc shows the first
digits), and ``...`` in the expected text matches any run of text (doctest ELLIPSIS).
A block that prints something but has no output block fails, as does an output block whose
python block prints nothing.

```console blocks are checked the same way: a line ``$ hammerbound ARGS`` runs the command
in-process; the lines up to the next ``$`` line are its expected stdout.
"""

from __future__ import annotations

import contextlib
import io
import re
import shlex
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

ROOT = Path(__file__).resolve().parents[2]
FILES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```[ \t]*$", re.S | re.M)
NUMBER = r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?"
# "0.8907..." in a doc: a number written with its first digits only (any digits follow)
TOKEN = re.compile(rf"{NUMBER}\.\.\.|\.\.\.|[A-Za-z_][A-Za-z_0-9]*|{NUMBER}|\S")
NUM_RE = re.compile(rf"{NUMBER}\Z")
RTOL, ATOL = 1e-3, 1e-6
#: how many more significant digits the program may print than the doc shows
MORE_DIGITS = 3
ELLIPSIS = "..."


def doc_blocks(text):
    """``[(kind, code, expected_or_None, line)]`` for the python and console blocks."""
    fences = [(m.group(1), m.group(2), m.start(), m.end()) for m in FENCE.finditer(text)]
    out = []
    for k, (info, body, start, end) in enumerate(fences):
        if info not in ("python", "console"):
            continue
        expected = None
        if k + 1 < len(fences) and fences[k + 1][0] == "output":
            gap = text[end:fences[k + 1][2]]
            if gap.count("\n") <= 2 and not gap.strip():
                expected = fences[k + 1][1]
        out.append((info, body, expected, text.count("\n", 0, start) + 1))
    return out


def _tokens(text):
    return TOKEN.findall(text)


def _digits(number: str) -> int:
    """Significant digits written in a number token (``-0.00123e5`` -> 3)."""
    mant = re.split(r"[eE]", number)[0].lstrip("+-").replace(".", "").lstrip("0")
    return max(len(mant), 1)


def _same(expected, actual) -> bool:
    if expected == actual:
        return True
    if expected.endswith(ELLIPSIS) and NUM_RE.match(expected[:-3]) and NUM_RE.match(actual):
        e, a = float(expected[:-3]), float(actual)
        return abs(a - e) <= ATOL + RTOL * abs(e)
    if NUM_RE.match(expected) and NUM_RE.match(actual):
        e, a = float(expected), float(actual)
        # a doc may round what is printed a little, not hide a 17-digit float behind 6
        return (abs(a - e) <= ATOL + RTOL * abs(e)
                and _digits(actual) <= _digits(expected) + MORE_DIGITS)
    return False


def output_matches(expected: str, actual: str) -> bool:
    """Token-wise match with numeric tolerance; ``...`` in ``expected`` matches any run."""
    exp, act = _tokens(expected), _tokens(actual)
    # dp[j] = exp[:i] matches act[:j]
    dp = [True] + [False] * len(act)
    for tok in exp:
        if tok == ELLIPSIS:
            new, seen = [], False
            for j in range(len(act) + 1):
                seen = seen or dp[j]
                new.append(seen)
        else:
            new = [False] + [dp[j] and _same(tok, act[j]) for j in range(len(act))]
        dp = new
    return dp[-1]


def test_matcher_numbers_words_and_ellipsis():
    assert output_matches("a1 in [-0.9217, -0.8830]", "a1 in [-0.921734, -0.882986]")
    assert not output_matches("a1 in [-0.9217, -0.8830]", "a1 in [-0.9317, -0.8830]")
    assert not output_matches("True", "False")
    assert not output_matches("b0", "b1")
    assert output_matches("x = ... done", "x = 1 2 3 anything done")
    assert output_matches("...", "")
    assert not output_matches("x = ... done", "x = 1 2 3")
    assert not output_matches("1 2", "1 2 3")            # extra output is not ignored
    assert output_matches("1e-7", "0")                    # atol
    assert output_matches("(100,)  34.9", "(100,) 34.91")
    # what the doc shows must be what the user sees, up to a little rounding
    assert not output_matches("(0.246585, 0.248042)", "(0.24658519569200837, 0.2480421)")
    assert output_matches("0.2466", "0.246585")
    assert output_matches("[-0.8907..., 1.2...]", "[-0.8907578120551644, 1.2000000001]")


def _run_console(body):
    """``[(command, expected, actual)]`` for the ``$ hammerbound ...`` lines of a block."""
    from hammerbound.app.cli import main

    runs, cmd, lines = [], None, []
    for line in body.splitlines() + ["$"]:
        if line.startswith("$"):
            if cmd is not None:
                buf = io.StringIO()
                with contextlib.redirect_stdout(buf):
                    rc = main(shlex.split(cmd)[1:])
                assert rc == 0, f"{cmd} exited with {rc}"
                runs.append((cmd, "\n".join(lines), buf.getvalue()))
            cmd, lines = line[1:].strip() or None, []
            if cmd is not None and not cmd.startswith("hammerbound "):
                cmd = None  # not ours (pip, git ...): not run
        else:
            lines.append(line)
    return runs


@pytest.mark.parametrize("path", [f for f in FILES if doc_blocks(f.read_text())],
                         ids=lambda p: p.name)
def test_doc_examples_print_what_they_say(path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "docs" / "figures").mkdir(parents=True)
    ns: dict = {"__name__": "__doc_example__"}
    for k, (kind, code, expected, line) in enumerate(doc_blocks(path.read_text())):
        where = f"{path.name}, block {k} (line {line})"
        if kind == "console":
            for cmd, exp, got in _run_console(code):
                if got.strip() or exp.strip():
                    assert output_matches(exp, got), (
                        f"{where}: `{cmd}` printed\n{got}\nbut the doc says\n{exp}")
            continue
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            exec(compile(code, f"{path.name}[block {k}]", "exec"), ns)  # noqa: S102
        got = buf.getvalue()
        if expected is None:
            assert not got.strip(), (
                f"{where} prints but has no ```output block after it; add one with:\n{got}")
        else:
            assert got.strip(), f"{where}: an ```output block follows but nothing is printed"
            assert output_matches(expected, got), (
                f"{where} printed\n{got}\nbut the doc's output block says\n{expected}")


def test_api_reference_is_current():
    import importlib.util

    spec = importlib.util.spec_from_file_location("gen_api", ROOT / "docs" / "gen_api.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    render = mod.render
    assert (ROOT / "docs" / "api.md").read_text() == render(), (
        "docs/api.md is stale: run `python docs/gen_api.py`")
