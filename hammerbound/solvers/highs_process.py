"""HiGHS in this process: a silent banner, quiet instances, time limits of runs, deadlines.

Clean stdout: highspy's C++ code prints its banner ("Running HiGHS ... Copyright ...") to
file descriptor 1 when the *first* ``Highs`` object of a process is constructed, before any
option can be set, so neither ``output_flag=False`` nor :func:`contextlib.redirect_stdout`
stops it. This module constructs that first object at import time with descriptor 1
pointed at ``os.devnull`` (:func:`silence_highs_banner`); every later ``Highs()`` in the
process, ours or not, prints nothing. Use :func:`new_highs` to create a quiet instance.
(scipy's ``linprog(method="highs")`` uses scipy's own HiGHS build, which prints nothing.)
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time

import highspy

#: Longest one ``run()`` of a HiGHS instance may take in hammerbound (s) when its caller
#: asks for no shorter limit (:func:`limit_run`). A run stopped there keeps the bound its
#: duals certify (maybe none), and every caller then keeps the bound it already had. Seen
#: in worker processes: one stage-2 screening LP (the witness search of a valve loop, with
#: a 3 s budget) and one one-record relaxation LP ran for 14-15 min; both kinds normally
#: take well under a second.
RUN_TIME_LIMIT = 120.0

_BANNER_LOCK = threading.Lock()
_BANNER_DONE = False


def _flush_c_stdio():
    """Flush the C library's stdio buffers (text the C++ code wrote but did not flush)."""
    try:
        import ctypes

        ctypes.CDLL(None).fflush(None)
    except Exception:  # pragma: no cover - no C runtime reachable this way (e.g. Windows)
        pass


@contextlib.contextmanager
def stdout_fd_to_devnull():
    """Point file descriptor 1 at ``os.devnull`` inside the block (C-level output included).

    Python's own ``sys.stdout`` is flushed first so that nothing already printed is lost;
    if descriptor 1 is not open, the block runs unchanged.
    """
    with contextlib.suppress(Exception):
        sys.stdout.flush()
    try:
        saved = os.dup(1)
    except OSError:  # no descriptor 1 (e.g. closed by the caller): nothing to protect
        yield
        return
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(null, 1)
        finally:
            os.close(null)
        yield
    finally:
        _flush_c_stdio()
        os.dup2(saved, 1)
        os.close(saved)


def silence_highs_banner() -> None:
    """Let HiGHS print its once-per-process banner into ``os.devnull`` (idempotent).

    Called when this module is imported, so any ``highspy.Highs()`` created afterwards in
    the process (including by code that does not use :func:`new_highs`) is silent.
    """
    global _BANNER_DONE
    if _BANNER_DONE:
        return
    with _BANNER_LOCK:
        if _BANNER_DONE:
            return
        with stdout_fd_to_devnull():
            h = highspy.Highs()
            h.setOptionValue("output_flag", False)
            del h
        _BANNER_DONE = True


def new_highs(options=None):
    """A ``highspy.Highs`` instance that prints nothing (banner silenced, ``output_flag`` off).

    The option ``threads`` is never set here, on purpose: HiGHS keeps *one* thread
    scheduler per process, sized by the first ``run()``, and a later ``run()`` whose
    ``threads`` option is non-zero and different fails without solving ("the scheduler has
    already been initialized to use 2 threads"). With the default (0) our LPs run whatever
    HiGHS user came first in the process, and never break a later one.

    Parameters
    ----------
    options : dict, optional
        HiGHS options (name -> value) set after ``output_flag=False``.

    Raises
    ------
    ValueError
        HiGHS rejected an option.
    """
    silence_highs_banner()
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    for name, value in (options or {}).items():
        if h.setOptionValue(name, value) != highspy.HighsStatus.kOk:
            raise ValueError(f"HiGHS rejected option {name}={value!r}")
    return h


silence_highs_banner()


def past(deadline) -> bool:
    """Whether the :func:`time.time` stamp ``deadline`` (None: no deadline) has passed."""
    return deadline is not None and time.time() > deadline


def seconds_left(cap, deadline=None) -> float:
    """Seconds a solve may take: ``cap``, or less when ``deadline`` (a :func:`time.time`
    stamp) comes first; at least 1 ms (a limit of 0 would be read as none)."""
    left = float(cap) if deadline is None else min(float(cap), float(deadline) - time.time())
    return max(left, 1e-3)


def wall_stamp(stop_at):
    """The :func:`time.time` stamp of a :func:`time.perf_counter` instant (None: None)."""
    return None if stop_at is None else time.time() + (stop_at - time.perf_counter())


def _run_cap(seconds=None) -> float:
    """A run's own limit: ``seconds``, at most :data:`RUN_TIME_LIMIT` (None: that)."""
    return RUN_TIME_LIMIT if seconds is None else min(float(seconds), RUN_TIME_LIMIT)


def limit_run(h, seconds=None, deadline=None) -> float:
    """Let the next ``run()`` of the HiGHS instance ``h`` stop after ``seconds`` (default
    and most :data:`RUN_TIME_LIMIT`) or at ``deadline`` (a :func:`time.time` stamp),
    whichever comes first; returns the seconds allowed.

    HiGHS compares its ``time_limit`` option with the run time accumulated over *all* runs
    of the instance, so a plain ``time_limit`` on a persistent instance caps the sum of its
    solves; the limit is set relative to :meth:`getRunTime` instead. The option is
    reserved for this function: :class:`HighsLP` refuses it among its options.
    """
    left = seconds_left(_run_cap(seconds), deadline)
    h.setOptionValue("time_limit", float(h.getRunTime() + left))
    return left
