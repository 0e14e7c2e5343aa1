"""The parser of the ``hammerbound`` command and its entry point :func:`main`."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys

from ...exceptions import HammerboundError
from ..paths import FORCE_FLAG
from . import benchmark, demo, diagnose, eiv, identify
from .console import cli_warnings, print_error
from .options import UsageError

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="hammerbound",
        description="Guaranteed bounds on backlash-Hammerstein systems (set-membership).",
        epilog=f"Output files are checked before any work starts and never overwritten "
               f"unless {FORCE_FLAG} is given.")
    parser.add_argument("--version", action="version", version=f"hammerbound {_version()}")
    sub = parser.add_subparsers(dest="command", required=True)
    for module in (demo, identify, eiv, benchmark, diagnose):
        module.add_parser(sub)
    parser.with_output_bound = frozenset(
        name for name, p in sub.choices.items()
        if any("--output-bound" in a.option_strings for a in p._actions))
    return parser


def _version() -> str:
    from ... import __version__

    return __version__


#: flags a newcomer guesses for the output error bound (an argparse error about one of them
#: names ``--output-bound`` when the command has it)
_GUESSED = ("--noise", "--noise-bound", "--deta")


class _Parser(argparse.ArgumentParser):
    """An argument parser whose "unrecognized arguments" error names ``--output-bound`` for
    a guessed spelling of it (:data:`_GUESSED`), when the command has that flag."""

    with_output_bound: frozenset = frozenset()
    command: str | None = None

    def error(self, message):
        words = message.replace(",", " ").split()
        if (message.startswith("unrecognized arguments")
                and self.command in self.with_output_bound
                and any(w.split("=", 1)[0] in _GUESSED for w in words)):
            message += " (the bound on the output errors is --output-bound, e.g. " \
                       "--output-bound 0.05)"
        super().error(message)


def main(argv=None) -> int:
    """Run ``hammerbound ARGS``; returns the exit status (0 success, 1 a negative
    verdict, 2 invalid input or usage, 130 interrupted)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:2] == ["benchmark", "suite"]:
        return benchmark.run_suite(argv[2:])
    command = argv[0] if argv else None
    with cli_warnings(command or "hammerbound"):
        try:
            parser = build_parser()
            parser.command = command
            args = parser.parse_args(argv)
            return args.func(args)
        except BrokenPipeError:  # the reader of stdout left (e.g. `| head`): stop quietly
            with contextlib.suppress(OSError, ValueError):
                os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 1
        except UsageError as exc:
            print(f"hammerbound {command}: error: {exc}", file=sys.stderr)
            return 2
        except (HammerboundError, ValueError, TypeError, OSError) as exc:
            return print_error(command, exc)
        except KeyboardInterrupt:
            print(f"hammerbound {command}: interrupted", file=sys.stderr)
            return 130
