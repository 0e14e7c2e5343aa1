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

Such searches (:func:`crash_prone`) run in one worker process (joblib's loky executor,
reused between fits). If the worker dies, :func:`run_isolated` raises
:class:`SolverCrashError` and :func:`.bnb.exact_bounds` reports the LP method's bounds,
which stay guaranteed, with status ``"limit"``.
"""

from __future__ import annotations

import re

import numpy as np

from ..problem import EIVProblem

#: rows of the full McCormick LP from which a HiGHS run can crash (see the module docstring)
CRASH_ROWS = 2500


class SolverCrashError(RuntimeError):
    """The worker process running the search died (HiGHS crashed in it)."""


def crash_prone(problem: EIVProblem) -> bool:
    """Whether the search of ``problem`` runs in a worker process: no input errors (the
    records on which HiGHS crashed) and a full McCormick LP of at least
    :data:`CRASH_ROWS` rows (the equations and 4 envelope rows per ``a_i eta`` product)."""
    if np.any(problem.dx_group > 0):
        return False
    m = problem.equation_times.size
    return m * (1 + 4 * problem.na) >= CRASH_ROWS


def run_isolated(fn, *args, **kwargs):
    """``fn(*args, **kwargs)`` in a worker process; :class:`SolverCrashError` if it dies."""
    from joblib.externals.loky import get_reusable_executor
    from joblib.externals.loky.process_executor import BrokenProcessPool

    executor = get_reusable_executor(max_workers=1)
    try:
        return executor.submit(fn, *args, **kwargs).result()
    except BrokenProcessPool as err:  # TerminatedWorkerError is one
        raise SolverCrashError(f"the worker process of the exact search died ({_why(err)}); "
                               "HiGHS can crash the process on long output-error records "
                               "(see hammerbound.relaxations.exact.isolation)") from err


def _why(err) -> str:
    """The exit codes loky names in ``err`` (e.g. ``SIGSEGV(-11)``), else its first line."""
    found = re.search(r"exit codes of the workers are \{(.*?)\}", str(err))
    return f"exit code {found.group(1)}" if found else str(err).strip().splitlines()[0]
