"""The linear block's parameters ``theta = (a_1..a_na, b_j)``: the lags of the ``b_j``
(:func:`b_lags_of`), their names, and their a priori box: the default box
(``|a_i| <= binom(na, i)``, which holds every stable A, and ``|b_j| <= 1e4``), and a user's
box given whole or by named rows (:func:`resolve_theta_box`)."""

from __future__ import annotations

from math import comb

import numpy as np

from ..exceptions import ParameterValidationError

DEFAULT_B_BOUND = 1.0e4


def b_lags_of(nb: int, nk: int) -> np.ndarray:
    """Lags ``j`` of the coefficients ``b_j`` of ``B`` for orders ``nb`` and delay ``nk``.

    ``nk = 0``: ``0 .. nb`` (direct term plus the chapter's ``b_1 .. b_nb``); ``nk >= 1``:
    ``nk .. nk + nb - 1`` (``nb`` coefficients after a delay of ``nk`` samples).
    """
    nb, nk = int(nb), int(nk)
    return np.arange(nk, (nb + 1) if nk == 0 else (nk + nb))


def default_theta_box(na: int, nb: int, b0: bool, b_bound: float = DEFAULT_B_BOUND,
                      nk: int | None = None) -> np.ndarray:
    """A priori box: ``|a_i| <= binom(na, i)`` (stable A, A1) and ``|b_j| <= b_bound``."""
    rows = [(-comb(na, i), comb(na, i)) for i in range(1, na + 1)]
    nbp = b_lags_of(nb, (0 if b0 else 1) if nk is None else nk).size
    rows += [(-b_bound, b_bound)] * nbp
    return np.asarray(rows, dtype=float).reshape(-1, 2)


def theta_names(na: int, nb: int, nk: int) -> list[str]:
    """The parameter names ``a1 .. a_na, b_j`` (lags of :func:`b_lags_of`)."""
    return [f"a{i}" for i in range(1, na + 1)] + [f"b{j}" for j in b_lags_of(nb, nk)]


def resolve_theta_box(theta_box, na: int, nb: int, nk: int) -> np.ndarray:
    """The a priori box (p, 2) of ``theta_box``: None (the default box,
    :func:`default_theta_box`), an array (p, 2) in the order of :func:`theta_names`, or a
    dict ``{name: (lower, upper)}`` that replaces those rows of the default box (e.g.
    ``{"a1": (-3, 3)}`` for an unstable A). Raises ParameterValidationError naming the
    valid shapes and names."""
    names = theta_names(na, nb, nk)
    p = len(names)
    shape_msg = (f"theta_box must be a finite array of shape ({p}, 2) with lower <= upper "
                 f"(rows {', '.join(names)}), or a dict {{name: (lower, upper)}} of some of "
                 "them")
    box = default_theta_box(na, nb, nk == 0, nk=nk)
    if isinstance(theta_box, dict):
        unknown = [k for k in theta_box if k not in names]
        if unknown:
            raise ParameterValidationError(
                f"theta_box names unknown parameter(s) {unknown}; the parameters are "
                f"{', '.join(names)}.")
        for k, row in theta_box.items():
            try:
                if isinstance(row, (str, bytes)):
                    raise TypeError
                lo, hi = (float(v) for v in row)
            except (TypeError, ValueError):
                raise ParameterValidationError(
                    f"{shape_msg}; got {k}: {row!r} (give a pair (lower, upper)).") from None
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                raise ParameterValidationError(
                    f"theta_box row {k}: ({lo:g}, {hi:g}) needs finite ends with lower <= "
                    "upper.")
            box[names.index(k)] = lo, hi
    elif theta_box is not None:
        try:
            box = np.asarray(theta_box, dtype=float)
        except (TypeError, ValueError):
            box = np.full((0,), np.nan)  # reported below
    if box.shape != (p, 2) or not np.all(np.isfinite(box)) or np.any(box[:, 0] > box[:, 1]):
        raise ParameterValidationError(f"{shape_msg}.")
    return box


def given_rows(theta_box, na: int, nb: int, nk: int) -> np.ndarray:
    """Which rows of the a priori box the user gave (bool (p,)): none for None, all for an
    array, the named ones for a dict (:func:`resolve_theta_box`)."""
    names = theta_names(na, nb, nk)
    if theta_box is None:
        return np.zeros(len(names), dtype=bool)
    if isinstance(theta_box, dict):
        return np.array([n in theta_box for n in names], dtype=bool)
    return np.ones(len(names), dtype=bool)


def given_rows_text(theta_box, na: int, nb: int, nk: int) -> str:
    """The rows the user gave, as ``"a1 in [-3, 3], b2 in [-5, 5]"`` ('' for none)."""
    given = given_rows(theta_box, na, nb, nk)
    if not given.any():
        return ""
    box = resolve_theta_box(theta_box, na, nb, nk)
    return ", ".join(f"{n} in [{box[k, 0]:g}, {box[k, 1]:g}]"
                     for k, n in enumerate(theta_names(na, nb, nk)) if given[k])
