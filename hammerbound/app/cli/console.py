"""What the command line writes besides its results: progress lines, one-line warnings and
errors, in the command line's own terms (flags, not Python keywords; no source paths).

Library messages name the Python interface (``method='lp'``, ``total_time_limit``); the
command translates them with :func:`to_cli` (a table of the spellings that reach it).
"""

from __future__ import annotations

import contextlib
import re
import sys
import time
import warnings

__all__ = ["Progress", "cli_warnings", "one_line", "print_error", "to_cli"]

#: (pattern, replacement): Python spellings in library messages -> command-line spellings
_TERMS = [
    (r"LinearEIVSetEstimator\(na=(\d+), nb=(\d+), nk=(\d+)\)", r"--na \1 --nb \2 --nk \3"),
    (r"method='(\w+)'", r"--method \1"),
    (r"\brelaxation_order=(\d+)", r"--order \1"),
    (r"\brelaxation_order\b", "--order"),
    (r"\btotal_time_limit\b", "--total-time-limit"),
    (r"(?<![-\w])gamma_box\b", "--gamma-box"),
    (r"pass theta_box to LinearEIVSetEstimator to change", "--theta-box changes it"),
    (r"theta_box=\{('\w+': \([-+\d.e]+, [-+\d.e]+\)(, )?)+\}", lambda m: _box_flags(m[0])),
    (r"(?<![-\w])theta_box\b", "--theta-box"),
    (r"(?<![-\w])time_limit\b", "--time-limit"),
    (r"(?<![-\w])(na|nb|nk) must\b", r"--\1 must"),
    (r"must be None or a number", "must be a number"),
    (r"\bmax_nodes\b", "--max-nodes"),
    (r"\bn_jobs\b", "--n-jobs"),
    (r"pass steady_state_gain=None for a plain EIV problem",
     "omit --steady-state-gain for a plain EIV problem"),
    (r"\bsteady_state_gain=", "--steady-state-gain "),
    (r"\bsteady_state_gain\b", "--steady-state-gain"),
    (r"\boutput_bound=", "--output-bound "),
    (r"\boutput_bound\b", "--output-bound"),
    (r"\binput_bound=", "--input-bound "),
    (r"\binput_bound\b", "--input-bound"),
    # (the command line has no call that suggests u*: the range given is the advice)
    (r", e\.g\. with suggest_prbs_level\(\)", ""),
    # (the command line has no flag for the moment size budget)
    (r" \(\w*max_work; raise it to build anyway\)", ""),
    (r" \(\w*max_work=inf builds it anyway\)", ""),
    (r"\(bound_info_ gives each end's status(?: and certified gap)?\)",
     "(the status column gives each end's status; --json its details)"),
    (r"\(see assumptions_\)", "(see the assumptions printed)"),
    (r"\(in assumptions_\)", "(in the assumptions printed)"),  # trial 16
    (r"Pass prbs_level=u\* for a two-level signal with rounding noise\.",
     "Write a two-level PRBS as +-u* in the file (shift an offset or 0/1 signal); pass an "
     "ordinary record as --record DATA.csv."),
    (r"refit='linear' refits only B", "--refit linear refits only B"),
    (r"\(candidates='all' tries every", "(--candidates all tries every"),
    (r"the factor min_improvement = ", "the factor "),
    # diagnose's note on a fitted set (discrepancy.verdict.CENTRAL_CHECK)
    (r"\(ident\.output_envelope\((\w+), (\w+)\)\)", r"(in Python: ident.output_envelope(\1, \2))"),
    (r"needs a one-record fit \(procedure='one-record'\)",
     "needs a one-record fit (hammerbound identify --record DATA.csv)"),
    (r"use procedure='one-record' to identify both blocks from it",
     "pass it as --record DATA.csv (not --prbs) to identify both blocks from it"),
]


def to_cli(text: str) -> str:
    """A library message in command-line terms, on one line."""
    return cli_terms(one_line(text))


def cli_terms(text: str) -> str:
    """``text`` with the library's parameter names in command-line terms (layout kept)."""
    for pattern, repl in _TERMS:
        text = re.sub(pattern, repl, text)
    return text


def _box_flags(text: str) -> str:
    """``theta_box={'a1': (-3, 3), 'b1': (-10, 10)}`` as ``--theta-box a1=-3:3 --theta-box
    b1=-10:10``."""
    rows = re.findall(r"'(\w+)': \(([-+\d.e]+), ([-+\d.e]+)\)", text)
    return " ".join(f"--theta-box {name}={lo}:{hi}" for name, lo, hi in rows)


def one_line(text) -> str:
    """``text`` with every run of whitespace (newlines included) made one space."""
    return " ".join(str(text).split())


def print_error(command: str, exc: BaseException) -> int:
    """``hammerbound CMD: error: Type: message`` on stderr (one line); returns 2."""
    print(f"hammerbound {command}: error: {type(exc).__name__}: {to_cli(str(exc))}",
          file=sys.stderr)
    return 2


@contextlib.contextmanager
def cli_warnings(command: str):
    """Within the block, every warning is one stderr line ``hammerbound CMD: warning:
    Category: message`` in command-line terms, without the Python source line."""

    def show(message, category, filename, lineno, file=None, line=None):
        out = sys.stderr if file is None else file
        with contextlib.suppress(OSError, ValueError):
            print(f"hammerbound {command}: warning: {category.__name__}: "
                  f"{to_cli(str(message))}", file=out)

    with warnings.catch_warnings():
        warnings.showwarning = show
        yield


@contextlib.contextmanager
def recorded_warnings():
    """Within the block, every warning shown (by :func:`cli_warnings`' stderr line, as
    before) is also appended to the list yielded, as ``{"category", "message"}`` in
    command-line terms: the JSON output carries them (a script reading only stdout could
    not tell why an end was null, new-user trial 11)."""
    seen = []
    shown = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        seen.append({"category": category.__name__, "message": to_cli(str(message))})
        shown(message, category, filename, lineno, file, line)

    with warnings.catch_warnings():
        warnings.showwarning = show
        yield seen


class Progress:
    """Progress lines on stderr (stdout stays the program's tables or JSON)."""

    def __init__(self, enabled, prefix="hammerbound demo"):
        self.enabled = enabled
        self.prefix = prefix
        self.t0 = time.perf_counter()

    def elapsed(self):
        return time.perf_counter() - self.t0

    def __call__(self, msg):
        if self.enabled:
            print(f"{self.prefix}: {msg}", file=sys.stderr, flush=True)
