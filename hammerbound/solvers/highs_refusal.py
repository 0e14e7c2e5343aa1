"""What :class:`~.highs.HighsLP` does when HiGHS refuses an LP (stops with an error before a
result): the ladder of attempts (:data:`RECOVERY`), the test of a refusal and the text
that names it."""

from __future__ import annotations

import highspy

__all__ = ["HIGHS_DEFAULTS", "RECOVERY", "refusal_message", "refused"]

#: What :meth:`HighsLP.solve` tries, in order, after HiGHS stopped with an error before a
#: result: each attempt starts from scratch (the basis dropped), with the options shown
#: (the scaling stays on afterwards; the others are reset).
RECOVERY = (
    ("from scratch with scaling", {"simplex_scale_strategy": 2}),
    ("from scratch with the primal simplex", {"simplex_strategy": 4}),
    ("from scratch with the interior-point method", {"solver": "ipm"}),
)
#: HiGHS's defaults of the options :data:`RECOVERY` changes (restored after an attempt).
HIGHS_DEFAULTS = {"simplex_scale_strategy": 2, "simplex_strategy": 1, "solver": "choose"}

_REFUSED = frozenset(getattr(highspy.HighsModelStatus, n) for n in (
    "kNotset", "kLoadError", "kModelError", "kPresolveError", "kSolveError",
    "kPostsolveError"))


def refused(run, status) -> bool:
    """Whether a ``run()`` ended without any result: an error status, or a model status
    that says the solve did not get anywhere ("Not Set", "Solve error", ...)."""
    return run == highspy.HighsStatus.kError or status in _REFUSED


def _status_text(h, run, status) -> str:
    try:
        st = h.modelStatusToString(status)
    except Exception:  # pragma: no cover - depends on highspy version
        st = str(status)
    return f"run() returned {getattr(run, 'name', run)}, model status '{st}'"


def refusal_message(first: str, tried, defects: str = "") -> str:
    """What happened to an LP HiGHS refused on every attempt (for messages and errors)."""
    why = (f"the LP data are defective: {defects}" if defects else
           "the LP data are valid (bounds ordered, all values finite); with its log on, "
           "HiGHS names the reason, e.g. 'Dual simplex ratio test failed due to excessive "
           "dual values' on a near-singular basis")
    return (f"HiGHS stopped with an error before a result ({first}) on the first attempt "
            f"and again {', '.join(tried)}; {why}")
