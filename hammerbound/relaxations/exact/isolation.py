"""The exact search in a worker process, where HiGHS can crash the process.

HiGHS 1.15-1.16 can end the whole Python process with a segmentation fault: when the basic
solution of a dual simplex run overflows (a warm start that is numerically singular for
the new box), its row choice (``HEkkDualRHS::chooseNormal``) calls itself without end. Its
code can only take that path with more than 500 primal infeasibilities in a sparse list
of at most a fifth of the rows, so models of fewer than :data:`CRASH_ROWS` rows are safe.
Seen only on output-error records (no input errors): N = 1000 and 3000, one crash in
about every second record, with scaled or unscaled LPs, devex or steepest edge; never on
records with input errors (hundreds of fits up to N = 10000). The reproducers are in
``benchmarks/output_error_lps.py`` and ``tests/relaxations/test_output_error_lps.py``.

Such searches (:func:`crash_prone`) run in one worker process (a loky executor of this
module, kept between fits): every step of :func:`.bnb.exact_bounds` that solves the
McCormick or the witness LPs of the full record (OBBT, the first verified points, each
interval end, the witnesses' polish). If the worker dies, :func:`run_isolated` raises
:class:`SolverCrashError` and :func:`.bnb.exact_bounds` keeps what the steps before it
certified (the LP bounds, the OBBT box, the verified witnesses unpolished), with status
``"limit"`` for the ends not searched to the end.
"""

from __future__ import annotations

import atexit
import re

from ..problem import EIVProblem

#: how every message about a dead worker of the search begins (:func:`crash_message`)
CRASH_TEXT = "the worker process of the exact search died"
#: rows of the full McCormick LP from which a HiGHS run can crash (see the module docstring)
CRASH_ROWS = 2500


class SolverCrashError(RuntimeError):
    """The worker process running the search died (HiGHS crashed in it)."""


def crash_prone(problem: EIVProblem) -> bool:
    """Whether the search of ``problem`` runs in a worker process: no input errors (the
    records on which HiGHS crashed) and a full McCormick LP of at least
    :data:`CRASH_ROWS` rows (the equations and 4 envelope rows per ``a_i eta`` product)."""
    if problem.has_input_errors:
        return False
    m = problem.equation_times.size
    return m * (1 + 4 * problem.na) >= CRASH_ROWS


_EXECUTOR = None


def run_isolated(fn, *args, **kwargs):
    """``fn(*args, **kwargs)`` in a worker process; :class:`SolverCrashError` if it dies.

    The worker (one, kept between calls, a new one after a crash) belongs to this module:
    joblib's reusable executor is left to joblib, which would not take one it did not make.
    """
    from joblib.externals.loky.process_executor import BrokenProcessPool

    global _EXECUTOR
    if _EXECUTOR is None:
        from joblib.externals.loky import ProcessPoolExecutor

        # no faulthandler dump of a crash (a traceback and 166 module names on the user's
        # stderr): the SolverCrashError's warning says what happened. loky enables the
        # handler in its workers unless this variable is set; empty, Python leaves it off
        _EXECUTOR = ProcessPoolExecutor(max_workers=1, env={"PYTHONFAULTHANDLER": ""})
    try:
        return _EXECUTOR.submit(fn, *args, **kwargs).result()
    except BrokenProcessPool as err:  # TerminatedWorkerError is one
        shutdown()
        raise SolverCrashError(crash_message(err)) from err
    except BaseException:
        # e.g. KeyboardInterrupt (a notebook's "interrupt kernel" reaches this process
        # only): the step must not go on in the worker, nor hold up the next call or exit
        shutdown(kill=True)
        raise


def crash_message(err) -> str:
    """What to tell the user when a worker process of the search died."""
    return (f"{CRASH_TEXT} ({why(err)}): HiGHS crashed in it "
            "(it can, on long output-error records: see hammerbound.relaxations.exact."
            "isolation), or the system ended it (e.g. out of memory)")


def shutdown(wait: bool = True, kill: bool = False):
    """Stop the worker process (a later :func:`run_isolated` starts a new one); ``kill``
    ends a step that is still running."""
    global _EXECUTOR
    if _EXECUTOR is not None:
        _EXECUTOR.shutdown(wait=wait, kill_workers=kill)
        _EXECUTOR = None


atexit.register(shutdown, wait=False, kill=True)


def why(err) -> str:
    """The exit codes loky names in ``err`` (e.g. ``SIGSEGV(-11)``), else its first line."""
    found = re.search(r"exit codes of the workers are \{(.*?)\}", str(err))
    return f"exit code {found.group(1)}" if found else str(err).strip().splitlines()[0]
