"""Stage 2: guaranteed bounds on the linear block from errors-in-variables data.

:class:`LinearEIVSetEstimator` bounds the coefficients ``theta = (a_1..a_na, b_..)`` of
``A(q^-1) w_t = B(q^-1) x_t`` (22.3) from the central input ``x^c`` (the inner signal
delivered by stage 1, or a measured input) with ``|x_t - x^c_t| <= dx_t`` and the output
``y_t = w_t + eta_t`` with ``|eta_t| <= deta_t``: the feasible parameter set is (22.34)
and the parameter uncertainty intervals (PUIs) are (22.35)-(22.37).

Three methods, all *guaranteed* (every feasible ``theta`` lies inside every reported
interval):

``"lp"``
    The polytopic outer approximation of Cerone (1993) / Cerone & Regruto (2007): each
    equation is decoupled, ``|e_t(theta)| <= deta_t + sum |a_i| deta + sum |b_j| dx``, and
    split into sign orthants; one LP per parameter, sense and orthant (HiGHS), made
    rigorous by a dual bound. Fast and the most conservative.
``"moment"``
    The sparse Lasserre relaxation of order ``relaxation_order`` (chapter section 22.4),
    formulated in PICOS, solved by a swappable conic backend (Clarabel by default) and
    *certified* from the dual solution: an inaccurate solve gives a looser, never a
    tighter, bound. The a priori box on ``theta`` is the LP result.
``"exact"``
    Spatial branch-and-bound over ``theta`` with McCormick LP relaxations: the tight
    intervals (22.36)-(22.37) to within ``tol``, each end with a verified-feasible witness.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin

from .._compat import DEPRECATED, is_given, renamed_value
from ..data.validation import as_bound, as_signal, check_excited, check_scale
from ..exceptions import (
    DataValidationError,
    EmptyFeasibleSetError,
    ParameterValidationError,
    UnboundedSetError,
)
from ..modelset.estimator import ModelSetMixin
from ..relaxations.exact.limits import DEFAULT_TOTAL_TIME_LIMIT
from ..relaxations.moment.size import MOMENT_MAX_WORK
from ..relaxations.problem import EIVProblem
from ..stage1.feasible_set import FeasibleSet
from ..status import BOX
from .fitting import check_not_crossed, run_method, with_hints
from .linear_model import LinearModelMixin
from .orders import check_orders
from .params import METHODS, check_params

__all__ = ["LinearEIVSetEstimator", "METHODS"]


class LinearEIVSetEstimator(LinearModelMixin, ModelSetMixin, RegressorMixin, BaseEstimator):
    """Guaranteed parameter intervals of ``G(q^-1) = B/A`` from bounded-error EIV data.

    Parameters
    ----------
    na, nb : int, default 2
        Orders of ``A`` (``1 + a_1 q^-1 + ... + a_na q^-na``) and ``B`` (``nb``
        coefficients ``b_1 .. b_nb`` as in the chapter, plus ``b_0`` when ``nk = 0``).
    nk : int, default 1
        Input delay (first lag of ``B``, MATLAB's ``nk`` in ``[na nb nk]``): ``nk = 1`` is
        the chapter's ``B = b_1 q^-1 + ... + b_nb q^-nb``; ``nk = 0`` adds the direct term
        ``b_0``; ``nk > 1`` delays further, ``B = b_nk q^-nk + ... +
        b_{nk+nb-1} q^-(nk+nb-1)``. (MATLAB's ``[na nb nk]`` maps unchanged for
        ``nk >= 1``; MATLAB's ``nk = 0`` with ``nb`` coefficients is ``nb - 1`` here.)
    output_bound : float or array of shape (N,), required
        Bound ``|eta_t| <= output_bound`` on the output errors (``Delta eta``, 22.5), > 0.
        The guarantee rests on it, so it has no default: ``None`` (the constructor
        default, for scikit-learn) makes :meth:`fit` raise
        :class:`~hammerbound.exceptions.ParameterValidationError` unless ``fit`` gets
        ``output_bound=``. Too small a bound gives an empty set, too large a wide one.
    steady_state_gain : float or None, default None
        Imposes ``B(1) / A(1) = steady_state_gain`` (22.8) as a linear equality. ``None``
        (default): a plain EIV problem, no gain constraint. Inside
        :class:`HammersteinBacklashIdentifier` stage 2 always uses the normalisation
        ``steady_state_gain=1`` (22.8) that stage 1 assumes.
    method : {"exact", "lp", "moment"}, default "exact"
        See the module docstring. The default is chosen by measurement
        (``python -m benchmarks default_method``, ``docs/benchmarks.md``): over six
        representative records (the chapter example at N = 100 and 300, Delta eta = 0.05
        and 0.3; second-order and first-order EIV records of N = 150 with errors uniform
        and exactly at the bound) ``"exact"`` gave the tight intervals in 58 s in total
        (0.9-36 s per fit, faster than the moment method on 5 of 6), the order-1 moment
        relaxation intervals 1.06-10x wider in 74 s (2-31 s per fit), ``"lp"`` 2.2-13x
        wider in under 0.2 s per fit. ``"lp"`` is the fast screening choice; ``"moment"``
        (the chapter's relaxation) stays fully available.
    relaxation_order : int, default 1
        Order ``delta`` of the moment relaxation. The chapter uses 2; with the LP box as a
        priori box, order 1 is already close to the exact intervals at a fraction of the
        cost. Order 2 (term-sparse basis, ``relaxation_basis="sparse"``) equals the exact
        intervals within 1e-3 of their width on the chapter example (on other records up to
        5e-3 measured: Clarabel stops the order-2 solves "AlmostSolved" and the certificate
        pays for that) and takes minutes (357 s on 2 cores at N = 300, see
        ``docs/benchmarks.md``). The relaxation's time and
        memory are estimated before it is built: above ``relaxation_max_work`` (or the
        machine's memory) the fit raises
        :class:`~hammerbound.exceptions.RelaxationTooLargeError` (use ``"lp"`` or
        ``"exact"``), above an estimated minute it warns (module
        :mod:`hammerbound.relaxations.moment.size`).
    relaxation_max_work : float, default 3600
        Budget on the estimated seconds (one core) of building and solving the moment
        relaxation, checked before it is built (default
        :data:`~hammerbound.relaxations.moment.size.MOMENT_MAX_WORK`: sparse order 2 at
        N ~ 1800, full order 2 at N ~ 60, order 3 at N ~ 13; the memory check refuses
        sparse order 2 above N ~ 500 on 24 GB with 2 workers); ``float("inf")`` lifts the
        refusals. Raise it only when the estimated time and memory in the refusal are
        acceptable.
    relaxation_basis : {"sparse", "full"}, default "sparse"
        Monomial basis of the moment matrices (order >= 2; both coincide at order 1):
        ``"sparse"`` uses ``1, theta, e, theta e`` (the equations are bilinear in
        parameters x noise), ``"full"`` every monomial of degree <= ``relaxation_order``
        (at least as tight, ~50x slower: 404 s for N = 10). See
        :class:`~hammerbound.relaxations.moment.relaxation.MomentRelaxation`.
    solver : str, default "clarabel"
        Conic backend of the moment method, one of
        :func:`hammerbound.available_solvers` (``"clarabel"``, ``"cvxopt"``; ``"qics"``
        and ``"mosek"`` when installed, through PICOS; ``pip install 'hammerbound[solvers]'``
        adds CVXOPT and QICS). An unknown or unavailable
        name raises :class:`~hammerbound.exceptions.SolverNotAvailableError` at once,
        naming the available ones.
    solver_options : dict or None
        Native options of the backend (e.g. ``{"max_iter": 200}`` for Clarabel).
    theta_box : array of shape (p, 2), dict or None
        A priori box on ``theta``; default ``|a_i| <= binom(na, i)`` (every stable ``A``
        lies in it) and ``|b_j| <= 1e4``. A dict ``{name: (lower, upper)}`` replaces only
        the named rows of the default box, e.g. ``{"a1": (-3, 3)}`` for an unstable ``A``
        (command line: ``--theta-box a1=-3:3``). An "empty" verdict says whether a wider
        box would hold parameters (the default box may be what excludes the system).
    tol, max_nodes, time_limit : float, int, float
        Stopping rules of the exact method, per interval end (gap ``<= tol * max(1, |v|)``;
        for a ``b_j`` ``tol * max(G, |v|)``, ``G`` the power of two nearest the largest
        ``|b_j|`` of the LP bounds, 1 when that lies in ``[1/8, 8]``, from the input's
        magnitude when such a bound sits at the a priori box).
        An end stopped by ``max_nodes`` or ``time_limit`` reports the best certified outer
        bound found so far (never wider than the LP bound) with status ``"limit"``, and
        the fit warns (:class:`~hammerbound.exceptions.SearchLimitWarning`) naming the ends.
    total_time_limit : float or None, default 600
        Wall-time budget in seconds for the whole fit, shared by the ``2 p`` interval
        ends and the joblib workers (``time_limit`` is per end): the exact method's, and a
        one-record fit's with any method. It starts when :meth:`fit` is called; the
        polytopic LP always runs, the set-up (bound tightening, first feasible points:
        usually well under a second to a few seconds) while time is left, then each end
        searches for at most ``time_limit`` and its share of the time left (the time left
        divided by the rounds of ends still to run; time an end does not use goes to the
        ends after it); ends that find no time left report
        their LP/OBBT bound with status ``"limit"``. The result is always finite and
        guaranteed where the LP bound is, and the fit warns
        (:class:`~hammerbound.exceptions.SearchLimitWarning`) naming the ends it stopped.
        The default keeps a long record's exact fit from running for ``2 p x time_limit``
        (80 min for ``p = 4``) without a word; ``None``: no total budget. The LP method on
        the chapter's experiments takes seconds; the moment method is guarded by its size
        budget instead (see ``relaxation_order``).
    on_failure : {"box", "raise"}, default "raise"
        Moment method: when a bound cannot be certified, raise :class:`SolverError`
        (default) or report the LP bound for it (still guaranteed).
    n_jobs : int, default 1
        The ``2 p`` bound problems run in parallel (joblib).
    progress : bool, default False
        Progress on stderr (never stdout): the exact method's interval ends (bars on a
        terminal, lines otherwise), the moment relaxation's size and each solved bound.
    noise_bound, b0 : deprecated
        Old names of ``output_bound`` and of ``nk=0`` (removed in 0.3.0).

    Notes
    -----
    Every method starts from the polytopic LP over the ``2^p`` sign orthants of ``theta``
    (``p`` parameters), and the data must give enough equations to bound them: ``fit``
    refuses at once, before any LP, orders with ``p > 12`` or fewer equations than
    parameters (:mod:`hammerbound.stage2.orders`).

    Attributes
    ----------
    bounds_ : ndarray of shape (p, 2)
        Guaranteed parameter intervals, rows in :attr:`param_names_` order.
    center_, radius_ : ndarray of shape (p,)
        Central estimate ``theta^c`` and uncertainty ``Delta theta`` (22.23).
    coef_ : ndarray of shape (p,)
        Same as ``center_``.
    param_names_ : tuple of str
        ``("a1", ..., "b1", ...)``.
    feasible_set_ : FeasibleSet
        Outer-bounding orthotope; for ``method="lp"``, ``polytopes`` holds the orthant
        polytopes ``A theta <= b`` whose union contains the feasible set.
    bound_info_ : tuple of BoundInfo
        Per bound: status, objective, certificate, time, iterations (and witness/gap for
        the exact method).
    intervals_ : IntervalResult
        The one result behind the attributes above: an
        :class:`~hammerbound.results.IntervalSet` (names, bounds, a status per end --
        :data:`~hammerbound.status.BOX` for ``box_limited_`` --, ``infos``, ``center``,
        ``radius``, ``contains``, ``to_frame``, ``summary``, ``to_dict``, ``plot``) with
        the method's typed details (``lp``, ``polytopes``, ``inner``, ``details``).
    result_ : IntervalResult
        The same object as ``intervals_`` (its older name).
    problem_ : EIVProblem
        The problem (22.34) that was bounded.
    output_bound_ : ndarray of shape (N,)
        The output error bound of every sample the intervals rest on (the constructor's
        or the one given to ``fit``).
    box_limited_ : tuple of str
        Interval ends set by the a priori box rather than by the data (e.g. ``"a2 upper"``
        when only stability, A1, bounds ``a_2``). They are still guaranteed under A1.
    n_features_in_ : int
        Always 1.
    dt_ : float or None
        Sampling time of the fitted :class:`~hammerbound.IOData` (None: not given, e.g.
        arrays); the default of :meth:`to_transfer_function`, :meth:`frequency_response_bounds`
        and :meth:`uncertainty_weight`.
    signal_names_, signal_units_ : tuple of str
        ``(input, output)`` names and units of the fitted IOData (``("u", "y")``,
        ``("", "")`` for arrays); the names label the transfer function's signals, names
        and units the frequency plots.
    time_unit_ : str
        Unit of ``dt_`` (empty: seconds).

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.signal import lfilter
    >>> rng = np.random.default_rng(0)
    >>> x = np.where(rng.random(80) < 0.5, 1.0, -1.0)
    >>> y = lfilter([0, 0.5], [1, -0.5], x) + rng.uniform(-0.02, 0.02, 80)
    >>> est = LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="exact")
    >>> est.fit(x, y, input_bound=0.0).contains([-0.5, 0.5])
    True
    """

    def __init__(self, na=2, nb=2, *, nk=1, output_bound=None, steady_state_gain=None,
                 method="exact", relaxation_order=1, relaxation_basis="sparse",
                 relaxation_max_work=MOMENT_MAX_WORK, solver="clarabel", solver_options=None,
                 theta_box=None, tol=1e-4, max_nodes=20000, time_limit=600.0,
                 total_time_limit=DEFAULT_TOTAL_TIME_LIMIT, on_failure="raise", n_jobs=1,
                 progress=False,
                 noise_bound=DEPRECATED, b0=DEPRECATED):
        self.na = na
        self.nb = nb
        self.nk = nk
        self.output_bound = output_bound
        self.steady_state_gain = steady_state_gain
        self.method = method
        self.relaxation_order = relaxation_order
        self.relaxation_basis = relaxation_basis
        self.relaxation_max_work = relaxation_max_work
        self.solver = solver
        self.solver_options = solver_options
        self.theta_box = theta_box
        self.tol = tol
        self.max_nodes = max_nodes
        self.time_limit = time_limit
        self.total_time_limit = total_time_limit
        self.on_failure = on_failure
        self.n_jobs = n_jobs
        self.progress = progress
        self.noise_bound = noise_bound
        self.b0 = b0

    # ------------------------------------------------------------------ validation
    def _check_params(self):
        check_params(self)

    def _constructor_output_bound(self, stacklevel=6):
        """The constructor's ``output_bound`` (or the deprecated ``noise_bound``)."""
        return renamed_value("LinearEIVSetEstimator", "output_bound", self.output_bound,
                             "noise_bound", self.noise_bound, stacklevel=stacklevel)

    def _output_bound(self, n, output_bound=None):
        """``deta`` of shape (n,): the fit-time ``output_bound`` or the constructor's."""
        if output_bound is not None:
            return as_bound("output_bound", output_bound, n)
        bound = self._constructor_output_bound()
        if bound is None:
            raise ParameterValidationError(
                "LinearEIVSetEstimator: output_bound is not set. The guaranteed intervals "
                "rest on the bound |eta_t| <= output_bound of the output errors (22.5), so "
                "it has no default: pass LinearEIVSetEstimator(output_bound=0.05, ...) (your "
                "sensor's error bound) or fit(..., output_bound=...).")
        try:
            return as_bound("output_bound", bound, n)
        except DataValidationError as exc:
            raise DataValidationError(
                f"{exc} In cross-validation pass per-sample bounds to fit (output_bound=..., "
                "input_bound=...): scikit-learn splits fit arguments with the samples, not "
                "constructor parameters.") from None

    def _build_problem(self, X, y, input_bound, groups, output_bound=None):
        x = as_signal("X", X)
        yy = as_signal("y", y)
        if x.shape != yy.shape:
            raise DataValidationError(
                f"X and y must have the same number of samples; got {x.size} and {yy.size}."
            )
        n = x.size
        check_orders(self.na, self.nb, self._nk(), n)  # at once, before any LP
        deta = self._output_bound(n, output_bound)
        dx = as_bound("input_bound", input_bound, n, allow_zero=True)
        check_excited("LinearEIVSetEstimator.fit", "X", x, "y", yy)
        check_scale("LinearEIVSetEstimator.fit", {"X": x, "y": yy},
                    {"output_bound": deta, "input_bound": dx},
                    hint=" (scaling X, y and both bounds by the same factor leaves theta "
                         "unchanged)")
        return EIVProblem(yy, x, dx, deta, na=self.na, nb=self.nb, nk=self._nk(),
                          steady_state_gain=self.steady_state_gain, groups=groups,
                          theta_box=self.theta_box)

    def _nk(self) -> int:
        """The input delay ``nk`` (``0`` with the deprecated ``b0=True``)."""
        if is_given(self.b0) and self.b0:
            return 0
        return 1 if self.nk is None else int(self.nk)

    def _lags(self) -> np.ndarray:
        from ..relaxations.problem import b_lags_of

        return b_lags_of(self.nb, self._nk())

    # ------------------------------------------------------------------ fit
    def fit(self, X, y=None, input_bound=0.0, input_groups=None, *, output_bound=None,
            groups=None):
        """Bound the linear block from central input ``X`` and measured output ``y``.

        Parameters
        ----------
        X : array of shape (N,) or (N, 1), or IOData
            Central input ``x^c`` (e.g. the inner signal from stage 1), or an
            :class:`~hammerbound.IOData` holding input, output and sampling time (then
            ``y`` is None and ``dt`` flows into :meth:`to_transfer_function`).
        y : array of shape (N,) or None
            Measured output (None with an IOData).
        input_bound : float or array of shape (N,), default 0.0
            ``dx``: the true input is within ``x^c +- dx`` (22.31).
        input_groups : int array of shape (N,), optional
            Samples with the same label share *one* unknown input error (e.g. the two
            levels of a PRBS inner signal under Result 1: label ``u < 0``). Default:
            independent per-sample errors, as in the chapter.
        output_bound : float or array of shape (N,), optional
            Per-sample output error bound for this fit, overriding the constructor's
            ``output_bound``. Pass sample-aligned bounds here in cross-validation:
            scikit-learn splits fit arguments together with the samples.
        groups : deprecated
            Old name of ``input_groups`` (it collided with scikit-learn's CV ``groups``).

        Returns
        -------
        self

        Raises
        ------
        DataValidationError, ParameterValidationError
            Malformed data or settings; a non-contiguous subset of an IOData (KFold).
        EmptyFeasibleSetError
            No ``theta`` explains the data within the bounds (names the first equation and
            the active assumptions: orders, delay, gain constraint, bounds, box).
        UnboundedSetError
            The data do not bound some parameter inside ``theta_box`` (names the same).
        SolverError, SolverNotAvailableError, SolverOptionError
            Moment-method backend problems.
        RelaxationTooLargeError
            Moment method: the relaxation's estimated size exceeds its budget (checked
            before any work; use ``method="lp"`` or ``"exact"``).

        Warns
        -----
        SearchLimitWarning
            Exact method: some interval ends stopped at ``max_nodes``, ``time_limit`` or
            ``total_time_limit``; they are named, and their bounds are still guaranteed.
        """
        from ..data.iodata import unpack

        if groups is not None:
            import warnings

            warnings.warn("fit(groups=...) is deprecated: use input_groups=... (scikit-learn "
                          "reserves 'groups' for the CV splitter).", FutureWarning,
                          stacklevel=2)
            if input_groups is None:
                input_groups = groups
        groups = input_groups
        X, y, data = unpack(X, y)
        import time

        t_fit = time.time()
        self._check_params()
        deadline = None if self.total_time_limit is None else t_fit + float(self.total_time_limit)
        problem = self._build_problem(X, y, input_bound, groups, output_bound)
        try:
            res = run_method(self, problem, deadline)
        except (EmptyFeasibleSetError, UnboundedSetError) as exc:
            raise with_hints(exc, self, problem, data) from exc
        self.problem_ = problem
        self.result_ = res
        self.bounds_ = np.array(res.bounds, dtype=float)
        check_not_crossed(self, problem, self.bounds_)
        self.intervals_ = res
        self.center_ = res.center
        self.radius_ = res.radius
        self.coef_ = self.center_
        self.param_names_ = res.param_names
        self.bound_info_ = res.infos
        self.box_limited_ = res.ends_with(BOX)
        self.feasible_set_ = FeasibleSet(
            self.param_names_, res.bounds, exact=False, method=self.method,
            polytopes=tuple((q.A, q.b) for q in res.polytopes), inner=res.inner,
            intervals=res)
        self.n_features_in_ = 1
        self.dt_ = None if data is None else data.dt
        self.signal_names_ = ("u", "y") if data is None else (data.input_name,
                                                             data.output_name)
        self.signal_units_ = ("", "") if data is None else (data.input_unit, data.output_unit)
        self.time_unit_ = "" if data is None else data.time_unit
        self.n_samples_ = problem.N
        self.output_bound_ = problem.output_bound
        return self

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.one_d_array = True
        tags.target_tags.single_output = True
        return tags
