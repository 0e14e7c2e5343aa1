"""Model orders the data and the methods can support, checked before any work (issue 29.4).

Every stage-2 method starts from the polytopic LP of :mod:`hammerbound.relaxations.lp`,
which solves ``2p + 1`` LPs in each of the ``2^p`` sign orthants of ``theta`` (``p``
parameters): its cost doubles with every parameter (``python -m benchmarks.lp_orders``:
seconds up to ``p = 8``, minutes at ``p = 12``, hours beyond). And the data must give at
least one equation per parameter: with fewer equations than parameters some direction of
``theta`` is not bounded by the data (only by the a priori box). So
:func:`check_orders` refuses, at once, ``p >`` :data:`MAX_PARAMETERS` and records too
short for the orders, and says which orders would work.
"""

from __future__ import annotations

from ..exceptions import DataValidationError, ParameterValidationError
from ..relaxations.problem import b_lags_of

__all__ = ["EQUATIONS_PER_PARAMETER", "MAX_PARAMETERS", "check_orders", "largest_order",
           "model_size"]

#: Most parameters ``p = na + len(B)`` a fit accepts (``2^12 = 4096`` LP orthants).
MAX_PARAMETERS = 12
#: Fewest equations (samples after the first ``n0 = max(na, last input lag)``) per parameter.
EQUATIONS_PER_PARAMETER = 1


def model_size(na: int, nb: int, nk: int) -> tuple[int, int]:
    """``(p, n0)``: number of parameters and first equation time."""
    lags = b_lags_of(nb, nk)
    return na + lags.size, max(na, int(lags[-1]))


def _supported(na: int, nb: int, nk: int, n_samples: int) -> bool:
    p, n0 = model_size(na, nb, nk)
    return p <= MAX_PARAMETERS and n_samples - n0 >= EQUATIONS_PER_PARAMETER * p


def largest_order(nk: int, n_samples: int) -> int:
    """The largest ``k`` with ``na = nb = k`` (delay ``nk``) supported by ``n_samples``
    samples; 0 when even ``k = 1`` is not."""
    k = 0
    while _supported(k + 1, k + 1, nk, n_samples):
        k += 1
    return k


def _what_works(nk: int, n_samples: int) -> str:
    k = largest_order(nk, n_samples)
    if k == 0:
        return f"no order works with N = {n_samples} samples"
    return f"with N = {n_samples} samples, orders up to na = nb = {k} work"


def check_orders(na: int, nb: int, nk: int, n_samples: int, *,
                 owner: str = "LinearEIVSetEstimator") -> None:
    """Refuse orders the methods or the data cannot support, before any LP is built.

    Raises
    ------
    ParameterValidationError
        More than :data:`MAX_PARAMETERS` parameters.
    DataValidationError
        Fewer equations than parameters.
    """
    p, n0 = model_size(na, nb, nk)
    orders = f"{owner}(na={na}, nb={nb}, nk={nk})"
    if p > MAX_PARAMETERS:
        raise ParameterValidationError(
            f"{orders} has p = {p} parameters, more than the {MAX_PARAMETERS} the methods "
            f"support: every method starts from the polytopic LP over the 2^p sign orthants "
            f"of theta (2^{p} = {2.0 ** p:.3g} here, {2 * p + 1} LPs each; p = 12 already "
            f"takes minutes). Use lower orders: {_what_works(nk, n_samples)}.")
    n_eq = n_samples - n0
    need = EQUATIONS_PER_PARAMETER * p
    if n_eq < need:
        raise DataValidationError(
            f"{orders} has p = {p} parameters, which need at least {need} equations (one "
            f"per parameter, or the data cannot bound them all), but N = {n_samples} samples give "
            f"{max(n_eq, 0)} (one per sample from t = n0 = {n0}). Use a longer record "
            f"(N >= {n0 + need}) or lower orders ({_what_works(nk, n_samples)}).")
