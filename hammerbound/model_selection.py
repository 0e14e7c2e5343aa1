"""Order selection that never picks a falsified order.

Cross-validation alone cannot select the order of a set-membership model. A training fold
holds fewer equations than the record, so an order that the whole record falsifies (no
model of that order explains the data within the bounds) may still be consistent on every
fold and score well on the held-out segments; and the LP method does not detect every
inconsistent order. :class:`OrderSelectionCV` therefore first decides, on the *whole*
record, which orders are falsified -- their feasible set certified empty by the exact
method's machinery (:func:`hammerbound.relaxations.consistency`) -- and discards them.
Among the others it picks, by default, the most parsimonious structure -- the fewest
parameters, then the lowest model order (the simplest model class that explains the data
within the bounds), then the best mean cross-validation score -- or, with
``rule="score"``, the best mean score.
"""

from __future__ import annotations

import numbers
import warnings

import numpy as np
from sklearn.base import BaseEstimator, clone
from sklearn.model_selection import ParameterGrid, TimeSeriesSplit, cross_val_score
from sklearn.utils.validation import check_is_fitted

from .exceptions import (
    EmptyFeasibleSetError,
    ParameterValidationError,
    SearchLimitWarning,
    UnboundedSetError,
)
from .relaxations import consistency
from .relaxations.problem import b_lags_of

__all__ = ["OrderSelectionCV"]

RULES = ("parsimonious", "score")


def _linear_part(est):
    """The fitted stage-2 estimator inside ``est`` (itself or an identifier's ``linear_``)."""
    if hasattr(est, "problem_"):
        return est
    lin = getattr(est, "linear_", None)
    if lin is not None and hasattr(lin, "problem_"):
        return lin
    raise ParameterValidationError(
        f"OrderSelectionCV selects the order of a LinearEIVSetEstimator or of the linear "
        f"block of a HammersteinBacklashIdentifier; got {type(est).__name__}.")


def _structure_size(est) -> tuple[int, int]:
    """``(number of parameters, model order)`` of ``est``'s (linear) structure: ``na`` plus
    the number of ``b`` coefficients, and ``n = max(na, last input lag)`` (the number of
    states of a minimal realisation of ``B/A``)."""
    p = est.get_params()
    pre = "" if "na" in p else "linear__"
    if pre + "na" not in p:
        if "linear" in p:  # an identifier with the default (None) stage 2
            raise ParameterValidationError(
                "OrderSelectionCV varies the orders of the identifier's stage 2: pass it "
                "explicitly, HammersteinBacklashIdentifier(linear=LinearEIVSetEstimator(...)).")
        _linear_part(est)  # raises: not a stage-2 estimator nor an identifier
    nk = p[pre + "nk"]
    nk = (0 if p[pre + "b0"] else 1) if nk is None else int(nk)
    na, lags = int(p[pre + "na"]), b_lags_of(int(p[pre + "nb"]), nk)
    return na + int(lags.size), max(na, int(lags[-1]) if lags.size else 0)


class OrderSelectionCV(BaseEstimator):
    """Select model orders: discard the falsified ones on the whole record, then choose.

    Parameters
    ----------
    estimator : LinearEIVSetEstimator or HammersteinBacklashIdentifier
        The model; any method (``"lp"`` is the fastest). It is fitted once per candidate
        on the whole record (that fit is kept as :attr:`best_estimator_`) and once per
        cross-validation fold.
    param_grid : dict or list of dicts
        The candidate orders, as for :class:`~sklearn.model_selection.GridSearchCV`:
        ``{"na": [1, 2, 3], "nb": [1, 2]}``, or ``{"linear__na": [1, 2, 3]}`` for an
        identifier (``nk`` may be part of the grid).
    cv : int, cross-validation generator or None, default None
        Splitter of the (time-series) record; ``None``: ``TimeSeriesSplit(n_splits=3)``,
        an int ``k``: ``TimeSeriesSplit(n_splits=k)``. Use forward splits: the model
        relates consecutive samples.
    rule : {"parsimonious", "score"}, default "parsimonious"
        Among the orders not certified inconsistent: ``"parsimonious"`` takes the fewest
        parameters; among equally many, the lowest model order ``n = max(na, nk + nb -
        1)`` (``na=2, nb=2`` before ``na=3, nb=1``), then a certified-consistent order
        before an undecided one, then the best mean CV score. ``"score"`` takes the best
        mean CV score (ties: the fewest parameters, the lowest order).
    time_limit : float, default 60
        Seconds per candidate for deciding whether its feasible set is empty; a candidate
        left undecided is kept (it is not certified inconsistent) and marked
        ``"undecided"``.
    n_jobs : int or None
        Passed to :func:`~sklearn.model_selection.cross_val_score`.

    Attributes
    ----------
    best_estimator_ : estimator
        The selected order, fitted on the whole record with ``estimator``'s settings.
    best_params_ : dict
    best_index_ : int
        Index of the selected candidate in ``cv_results_``.
    best_score_ : float
        Its mean cross-validation score.
    consistency_ : list
        Per candidate: the :class:`~hammerbound.relaxations.Consistency` decision, or
        None when the whole-record fit itself raised (``"empty"`` from the fit's own
        certificate, ``"unbounded"`` when the data do not bound that order's parameters).
    cv_results_ : dict of arrays
        ``params``, ``param_<name>``, ``n_parameters``, ``model_order``, ``consistency`` (``"consistent"``,
        ``"empty"``, ``"undecided"`` or ``"unbounded"``), ``certified_by``,
        ``split<k>_test_score``, ``mean_test_score``, ``std_test_score`` (NaN for the
        discarded candidates, which are not cross-validated) and ``rank_selection``
        (1 = selected; the discarded candidates rank last).
    n_splits_ : int

    Raises
    ------
    EmptyFeasibleSetError
        From :meth:`fit`, when every candidate is certified inconsistent or unbounded:
        the message lists them (question the bounds or widen the grid).

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.signal import lfilter
    >>> import hammerbound as hb
    >>> rng = np.random.default_rng(0)
    >>> x = np.repeat(rng.uniform(-1, 1, 50), 3)
    >>> y = lfilter([0, 1.0, 0.5], [1, -1.5, 0.7], x) + rng.uniform(-0.02, 0.02, 150)
    >>> sel = hb.OrderSelectionCV(hb.LinearEIVSetEstimator(output_bound=0.02, method="lp"),
    ...                           {"na": [1, 2, 3], "nb": [1, 2]}).fit(x, y)
    >>> sel.best_params_
    {'na': 2, 'nb': 2}
    """

    def __init__(self, estimator, param_grid, *, cv=None, rule="parsimonious",
                 time_limit=60.0, n_jobs=None):
        self.estimator = estimator
        self.param_grid = param_grid
        self.cv = cv
        self.rule = rule
        self.time_limit = time_limit
        self.n_jobs = n_jobs

    def _check_params(self):
        if self.rule not in RULES:
            raise ParameterValidationError(f"rule must be one of {RULES}; got {self.rule!r}.")
        tl = self.time_limit
        if not isinstance(tl, numbers.Real) or isinstance(tl, bool) or not tl > 0:
            raise ParameterValidationError(
                f"time_limit must be a number of seconds > 0; got {tl!r}.")
        cv = self.cv
        if cv is None:
            return TimeSeriesSplit(n_splits=3)
        if isinstance(cv, numbers.Integral) and not isinstance(cv, bool):
            return TimeSeriesSplit(n_splits=int(cv))
        return cv

    def _decide(self, est, X, y, fit_params):
        """Fit ``est`` on the whole record and decide its consistency.

        Returns ``(status, certified_by, decision, fitted or None)``.
        """
        try:
            est.fit(X, y, **fit_params)
        except EmptyFeasibleSetError:
            return "empty", "fit", None, None
        except UnboundedSetError:
            return "unbounded", "fit", None, None
        if getattr(est, "procedure_", None) == "one-record":
            # its ends' points are verified members of the joint set; with none (the
            # relaxation's bounds only) nothing is certified either way (new-user trial
            # 22: the stage-2 consistency test was run on the joint problem and crashed)
            if any(getattr(i, "point", None) is not None for i in est.one_record_.result.infos):
                return "consistent", "witness", None, est
            return "undecided", "fit", None, est
        lin = _linear_part(est)
        wit = [i.witness for i in lin.bound_info_ if getattr(i, "witness", None) is not None]
        if wit:  # an exact fit: its witnesses are verified points
            return "consistent", "witness", None, est
        dec = consistency(lin.problem_, time_limit=float(self.time_limit))
        return dec.status, dec.by, dec, est

    def fit(self, X, y=None, **fit_params):
        """Decide every candidate on the whole record, cross-validate the others, select.

        ``X, y`` (or an :class:`~hammerbound.IOData` as ``X``) and ``fit_params`` (e.g.
        ``input_bound=``, ``steady_state=``) are passed to every fit; sample-aligned fit
        parameters are split with the folds.
        """
        cv = self._check_params()
        _structure_size(self.estimator)  # a stage-2 estimator or an identifier with one
        cands = list(ParameterGrid(self.param_grid))
        if not cands:
            raise ParameterValidationError("param_grid holds no candidate.")
        rows, fitted, decisions = [], [], []
        for params in cands:
            est = clone(self.estimator).set_params(**params)
            n_par, n_order = _structure_size(est)
            status, by, dec, est = self._decide(est, X, y, fit_params)
            rows.append({"status": status, "by": by, "n_par": n_par, "order": n_order,
                         "scores": None})
            fitted.append(est)
            decisions.append(dec)
        keep = [k for k, r in enumerate(rows) if r["status"] in ("consistent", "undecided")]
        if not keep:
            listing = "; ".join(f"{_label(p)}: {r['status']} ({r['by']})"
                                for p, r in zip(cands, rows, strict=True))
            raise EmptyFeasibleSetError(
                "no candidate order explains the data within the bounds (" + listing + "). "
                "Check the error bounds (output_bound, input_bound) or widen the grid.",
                first_index=None)
        n_splits = None
        with warnings.catch_warnings():
            # a short fold may not bound a high order: scored -inf, reported in cv_results_
            warnings.filterwarnings("ignore", message=".*fits failed.*")
            for k in keep:
                est = clone(self.estimator).set_params(**cands[k])
                s = cross_val_score(est, X, y, cv=cv, n_jobs=self.n_jobs, params=fit_params,
                                    error_score=-np.inf)
                rows[k]["scores"] = s
                n_splits = s.size
        order = self._ranking(keep, rows)
        best = order[0]
        if rows[best]["status"] == "undecided":
            why = (f"within time_limit={self.time_limit:g} s (lower orders were certified "
                   "inconsistent); raise time_limit to decide it" if rows[best]["by"] != "fit"
                   else "by its one-record fit, whose relaxation gives no verified point; "
                   "method='exact' certifies it by its ends' points")  # recheck 52b
            warnings.warn(
                f"the selected order {_label(cands[best])} is neither certified consistent "
                f"nor certified inconsistent {why}.", SearchLimitWarning, stacklevel=2)
        self.cv_results_ = self._results(cands, rows, order, n_splits)
        self.consistency_ = decisions
        self.n_splits_ = n_splits
        self.best_index_ = best
        self.best_params_ = dict(cands[best])
        self.best_estimator_ = fitted[best]
        self.best_score_ = float(np.mean(rows[best]["scores"]))
        return self

    def _ranking(self, keep, rows):
        def key(k):
            score = float(np.mean(rows[k]["scores"]))
            simple = (rows[k]["n_par"], rows[k]["order"])
            if self.rule == "parsimonious":
                return *simple, rows[k]["status"] != "consistent", -score
            return -score, *simple

        rest = [k for k in range(len(rows)) if k not in keep]
        return sorted(keep, key=key) + rest

    @staticmethod
    def _results(cands, rows, order, n_splits):
        n = len(cands)
        res = {"params": cands}
        for name in sorted({key for p in cands for key in p}):
            res[f"param_{name}"] = np.array([p.get(name) for p in cands], dtype=object)
        res["n_parameters"] = np.array([r["n_par"] for r in rows])
        res["model_order"] = np.array([r["order"] for r in rows])
        res["consistency"] = np.array([r["status"] for r in rows], dtype=object)
        res["certified_by"] = np.array([r["by"] for r in rows], dtype=object)
        scores = np.full((n, n_splits), np.nan)
        for k, r in enumerate(rows):
            if r["scores"] is not None:
                scores[k] = r["scores"]
        for i in range(n_splits):
            res[f"split{i}_test_score"] = scores[:, i]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # -inf - -inf in std
            res["mean_test_score"] = scores.mean(axis=1)
            res["std_test_score"] = scores.std(axis=1)
        rank = np.empty(n, dtype=int)
        rank[np.asarray(order)] = np.arange(1, n + 1)
        res["rank_selection"] = rank
        return res

    # ------------------------------------------------------------------ delegation
    def predict(self, X):
        """``best_estimator_.predict(X)``."""
        check_is_fitted(self, "best_estimator_")
        return self.best_estimator_.predict(X)

    def score(self, X, y=None, **kwargs):
        """``best_estimator_.score(X, y)``."""
        check_is_fitted(self, "best_estimator_")
        return self.best_estimator_.score(X, y, **kwargs)

    def summary(self) -> str:
        """One line per candidate: order, parameters, consistency, mean CV score, choice."""
        check_is_fitted(self, "best_estimator_")
        r = self.cv_results_
        lines = [f"{'candidate':<22} {'params':>6}  {'consistency':<27} {'mean CV score':>13}"]
        for k, p in enumerate(r["params"]):
            n_par = r["n_parameters"][k]
            state = f"{r['consistency'][k]} ({r['certified_by'][k]})"
            m = r["mean_test_score"][k]
            lines.append(f"{_label(p):<22} {n_par:>6}  {state:<27} "
                         f"{'-' if np.isnan(m) else f'{m:.4f}':>13}"
                         + ("  <- selected" if k == self.best_index_ else ""))
        return "\n".join(lines)


def _label(params) -> str:
    return " ".join(f"{k.split('__')[-1]}={v}" for k, v in sorted(params.items()))
