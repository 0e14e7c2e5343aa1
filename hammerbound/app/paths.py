"""Output paths of the command line: checked before any work starts, never overwritten silently.

Every subcommand that writes files uses the same three helpers and the same flag:

- :func:`add_force_option` adds ``--force`` (overwrite existing outputs);
- :func:`check_output_file` / :func:`check_output_dir` run *before* the computation and
  raise :class:`~hammerbound.exceptions.OutputPathError` (missing or read-only parent
  directory, a directory or special file where a file goes, ...) or
  :class:`~hammerbound.exceptions.OutputExistsError` (the target exists and ``--force`` was
  not given), each with a one-line message that says what to do;
- :func:`write_output_text` writes the result at the end; without ``force`` it creates the
  file exclusively, so a file that appeared meanwhile is not clobbered either.

Example (a new subcommand)::

    p = sub.add_parser("mycmd")
    p.add_argument("--output")
    add_force_option(p)
    ...
    def cmd_mycmd(args):
        out = check_output_file(args.output, force=args.force, option="--output")
        ...  # the work
        write_output_text(out, text, force=args.force, option="--output")
"""

from __future__ import annotations

import os
import stat
import tempfile
from pathlib import Path

from ..exceptions import OutputExistsError, OutputPathError

__all__ = [
    "FORCE_FLAG",
    "add_force_option",
    "check_output_dir",
    "check_output_file",
    "write_output_text",
]

#: The one overwrite flag of every subcommand (as in ``cp -f``, ``ln -f``, ``git ... --force``).
FORCE_FLAG = "--force"


def add_force_option(parser, what="output files"):
    """Add ``--force`` (``dest="force"``) to an argparse parser."""
    parser.add_argument(FORCE_FLAG, action="store_true",
                        help=f"overwrite existing {what} (refused by default)")
    return parser


def _one_line(text) -> str:
    return " ".join(str(text).split())


def _where(option) -> str:
    return f"{option}: " if option else ""


def _probe_writable_dir(directory: Path, option) -> None:
    """Create and remove a temporary file in ``directory`` (the only reliable test: access()
    says yes to root on read-only or virtual file systems such as /proc)."""
    try:
        fd, name = tempfile.mkstemp(prefix=".hammerbound-write-test-", dir=directory)
    except OSError as exc:
        raise OutputPathError(
            f"{_where(option)}cannot create files in {directory} "
            f"({_one_line(exc.strerror or exc)}); choose a writable directory.",
            path=directory) from None
    os.close(fd)
    try:
        os.unlink(name)
    except OSError:  # pragma: no cover - created but not removable: leave it
        pass


def _check_parent(path: Path, option) -> None:
    parent = path.parent
    if not parent.exists():
        raise OutputPathError(
            f"{_where(option)}the directory {parent} does not exist; create it first or "
            "choose another path.", path=path)
    if not parent.is_dir():
        raise OutputPathError(
            f"{_where(option)}{parent} is not a directory; choose another path.", path=path)
    _probe_writable_dir(parent, option)


def _check_existing_file(path: Path, force, option, *, hint) -> None:
    """``path`` exists (or is a symbolic link): refuse unless it is a writable regular file
    and ``force`` is set."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise OutputPathError(
            f"{_where(option)}{path} is a symbolic link to a missing file; remove it or "
            "choose another name.", path=path) from None
    except OSError as exc:
        raise OutputPathError(f"{_where(option)}cannot use {path} "
                              f"({_one_line(exc.strerror or exc)}).", path=path) from None
    if stat.S_ISDIR(st.st_mode):
        raise OutputPathError(
            f"{_where(option)}{path} is a directory; give a file name such as "
            f"{path / 'results.json'}.", path=path)
    if not stat.S_ISREG(st.st_mode):
        raise OutputPathError(
            f"{_where(option)}{path} is not a regular file (a device, pipe or socket); "
            "choose a file name.", path=path)
    if not force:
        raise OutputExistsError(
            f"{_where(option)}{path} already exists; pass {FORCE_FLAG} to overwrite it, "
            f"or {hint}.", path=path)
    try:  # opening for update changes neither content nor modification time
        with open(path, "r+b"):
            pass
    except OSError as exc:
        raise OutputPathError(f"{_where(option)}cannot overwrite {path} "
                              f"({_one_line(exc.strerror or exc)}).", path=path) from None


def _as_path(path, option) -> Path:
    if path is None or str(path).strip() == "":
        raise OutputPathError(f"{_where(option)}empty output path; give a file name.",
                              path=path)
    return Path(os.fspath(path)).expanduser()


def check_output_file(path, *, force=False, option=None) -> Path:
    """Check that ``path`` can be written as a new (or, with ``force``, replaced) file.

    Parameters
    ----------
    path : str or Path
    force : bool, default False
        Allow replacing an existing regular file.
    option : str, optional
        Name of the command-line option, shown at the start of messages.

    Returns
    -------
    Path

    Raises
    ------
    OutputExistsError
        ``path`` exists and ``force`` is false.
    OutputPathError
        The parent directory is missing, not a directory or not writable; ``path`` is a
        directory, a special file or a dangling link; an existing file is not writable.
    """
    p = _as_path(path, option)
    if p.exists() or p.is_symlink():
        _check_existing_file(p, force, option, hint="choose another file name")
    _check_parent(p, option)
    return p


def check_output_dir(path, files, *, force=False, option=None,
                     hint="choose another directory", force_hint=None) -> Path:
    """Check that the files ``files`` can be written into directory ``path``.

    The directory may exist (it is then reused) or not (its parent must exist; it is
    created by the writer). Files of ``path`` not in ``files`` are never touched.

    Parameters
    ----------
    path : str or Path
    files : sequence of str
        Names of the files the writer creates inside ``path``.
    force : bool, default False
        Allow replacing those files when they exist.
    option : str, optional
        Name of the command-line option, shown at the start of messages.
    hint : str, optional
        The alternative to ``--force`` offered when a report exists.
    force_hint : str, optional
        How to ask for overwriting (default ``"pass --force"``; the Python API says
        ``"pass overwrite=True"``).

    Returns
    -------
    Path

    Raises
    ------
    OutputExistsError
        One of ``files`` exists in ``path`` and ``force`` is false.
    OutputPathError
        ``path`` is a file or special file; its parent is missing or not writable; one of
        ``files`` is a directory or special file.
    """
    p = _as_path(path, option)
    if p.is_symlink() and not p.exists():
        raise OutputPathError(f"{_where(option)}{p} is a symbolic link to a missing "
                              "directory; remove it or choose another name.", path=p)
    if not p.exists():
        _check_parent(p, option)
        return p
    if not p.is_dir():
        raise OutputPathError(
            f"{_where(option)}{p} exists and is not a directory; choose a directory name.",
            path=p)
    present = [f for f in files if (p / f).exists() or (p / f).is_symlink()]
    if present and not force:
        shown = ", ".join(present[:3]) + (" ..." if len(present) > 3 else "")
        raise OutputExistsError(
            f"{_where(option)}{p} already holds a report ({shown}); "
            f"{force_hint or 'pass ' + FORCE_FLAG} to overwrite it, or {hint}.", path=p)
    for f in present:
        _check_existing_file(p / f, True, option, hint="")
    _probe_writable_dir(p, option)
    return p


def write_output_text(path, text, *, force=False, option=None) -> Path:
    """Write ``text`` to ``path`` (checked earlier by :func:`check_output_file`).

    Without ``force`` the file is created exclusively: if it appeared since the check,
    :class:`OutputExistsError` is raised and the other file is left as it is.
    """
    p = Path(path)
    try:
        with open(p, "w" if force else "x", encoding="utf-8") as fh:
            fh.write(text)
    except FileExistsError:
        raise OutputExistsError(
            f"{_where(option)}{p} was created by someone else while this command ran; "
            f"it was left unchanged (pass {FORCE_FLAG} to overwrite it).", path=p) from None
    except OSError as exc:
        raise OutputPathError(f"{_where(option)}cannot write {p} "
                              f"({_one_line(exc.strerror or exc)}).", path=p) from None
    return p
