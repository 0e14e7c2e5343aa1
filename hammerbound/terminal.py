"""Whether progress goes to a terminal (bars with cursor codes) or elsewhere (plain lines)."""

from __future__ import annotations

import sys

__all__ = ["is_terminal"]


def is_terminal(file=None) -> bool:
    """True if ``file`` (default ``sys.stderr``) is an interactive terminal; a pipe, a
    file, a notebook's stream or an object without ``isatty`` is not."""
    isatty = getattr(sys.stderr if file is None else file, "isatty", None)
    return callable(isatty) and bool(isatty())
