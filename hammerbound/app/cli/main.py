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
    parser = argparse.ArgumentParser(
        prog="hammerbound",
        description="Guaranteed bounds on backlash-Hammerstein systems (set-membership).",
        epilog=f"Output files are checked before any work starts and never overwritten "
               f"unless {FORCE_FLAG} is given.")
    parser.add_argument("--version", action="version", version=f"hammerbound {_version()}")
    sub = parser.add_subparsers(dest="command", required=True)
    for module in (demo, identify, eiv, benchmark, diagnose):
        module.add_parser(sub)
    return parser


def _version() -> str:
    from ... import __version__

    return __version__


#: flags a newcomer guesses for an option the command spells otherwise
_GUESSED = {"--noise": "--output-bound", "--noise-bound": "--output-bound",
            "--deta": "--output-bound"}


def _guessed_flag(argv) -> str | None:
    """A usage error for a guessed flag in ``argv`` (say which flag is meant), or None."""
    for a in argv:
        flag = a.split("=", 1)[0]
        if flag in _GUESSED:
            return (f"unrecognized argument {flag}: the bound on the output errors is "
                    f"{_GUESSED[flag]} (e.g. {_GUESSED[flag]} 0.05)")
    return None


def main(argv=None) -> int:
    """Run ``hammerbound ARGS``; returns the exit status (0 success, 1 a negative
    verdict, 2 invalid input or usage, 130 interrupted)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:2] == ["benchmark", "suite"]:
        return benchmark.run_suite(argv[2:])
    command = argv[0] if argv else None
    guessed = _guessed_flag(argv)
    if guessed is not None:
        print(f"hammerbound {command}: error: {guessed}", file=sys.stderr)
        return 2
    with cli_warnings(command or "hammerbound"):
        try:
            args = build_parser().parse_args(argv)
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
