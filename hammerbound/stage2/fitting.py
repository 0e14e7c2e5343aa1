"""Stage 2's fit from a built problem to bounds: the method's run, what a bound at the a
priori box means, and the messages that name the assumptions behind a refusal.

Used by :class:`~.estimator.LinearEIVSetEstimator` (``est``: the estimator, read only).
"""

from __future__ import annotations

import numpy as np

from ..exceptions import EmptyFeasibleSetError, UnboundedSetError
from ..relaxations.problem import given_rows, given_rows_text, theta_names
from ..tables import bound_text


def run_method(est, problem, deadline):
    """The interval result of ``est.method`` on ``problem`` (stopping at ``deadline``, a
    :func:`time.time` stamp, or None); a ``b_j`` at the default box raises
    :class:`UnboundedSetError`, the exact method's stopped ends warn."""
    from ..relaxations.lp import lp_bounds

    if est.method == "lp":
        res = lp_bounds(problem, n_jobs=est.n_jobs, check_box=False)
        check_box(est, problem, res)
        return res
    if est.method == "exact":
        from ..relaxations.exact.bnb import exact_bounds

        res = exact_bounds(problem, tol=est.tol, max_nodes=est.max_nodes,
                           time_limit=est.time_limit, n_jobs=est.n_jobs,
                           progress=est.progress, check_box=False, deadline=deadline)
        check_box(est, problem, res)
        warn_limits(res)
        return res
    return _moment(est, problem)


def _moment(est, problem):
    """The moment method, after its size guard (solver and options were checked before)."""
    from ..relaxations.lp import lp_bounds
    from ..relaxations.moment.relaxation import moment_bounds
    from ..relaxations.moment.size import (
        check_moment_budget,
        estimate_moment_relaxation,
        solve_processes,
    )

    # memory/time guard before any work (refuses with the estimate, or warns)
    check_moment_budget(estimate_moment_relaxation(
        problem, est.relaxation_order, basis=est.relaxation_basis),
        max_work=float(est.relaxation_max_work), option="relaxation_max_work",
        processes=solve_processes(est.n_jobs, problem.p),
        stacklevel=5)  # warn -> here -> run_method -> fit -> the caller
    lp = lp_bounds(problem, n_jobs=est.n_jobs, check_box=False)
    check_box(est, problem, lp)
    # the LP bounds are the a priori box and the fallback; kept as res.lp
    return moment_bounds(problem, order=est.relaxation_order, solver=est.solver,
                         solver_options=est.solver_options, n_jobs=est.n_jobs,
                         on_failure=est.on_failure, max_work=float("inf"),
                         basis=est.relaxation_basis, lp=lp, progress=est.progress)


def with_hints(exc, est, problem, data):
    """``exc`` (empty or unbounded set) again, its message naming the assumptions, a badly
    scaled record and, for samples that are not an IOData, cross-validation cuts."""
    wider = smallest = ""
    if isinstance(exc, EmptyFeasibleSetError):
        from .smallest_bound import LazyText, smallest_output_factor, smallest_output_text

        # computed when the message is shown: a verdict caught and dropped costs nothing
        smallest = LazyText(lambda: smallest_output_text(problem,
                                                         smallest_output_factor(problem)))
        wider = widened_box_hint(problem, exc.relaxation)
    parts = [wider, smallest, box_hint(est, problem), assumptions(est, problem)]
    kw = {"side": exc.side, "first_index": exc.first_index, "relaxation": exc.relaxation} \
        if isinstance(exc, EmptyFeasibleSetError) else {}
    if isinstance(exc, EmptyFeasibleSetError) and data is None:
        parts.append("If these samples were cut by a cross-validation splitter (e.g. "
                     "KFold), they are not consecutive: use TimeSeriesSplit, or pass "
                     "IOData, which refuses such cuts.")
    first = str(exc)

    def text():
        return " ".join(h for h in (first, *map(str, parts)) if h)

    return type(exc)(LazyText(text) if isinstance(exc, EmptyFeasibleSetError) else text(),
                     **kw)


#: How much wider the a priori box is made (about its centre) to tell whether it, and not
#: the data, excludes every parameter vector: the rows of A, of B.
WIDER_A, WIDER_B = 10.0, 1e3


def _widened(box, factor):
    """``box`` (p, 2) made ``factor`` (p,) times wider about its centre."""
    mid, half = box.mean(axis=1), 0.5 * (box[:, 1] - box[:, 0]) * factor
    return np.column_stack([mid - half, mid + half])


def widened_box_hint(problem, relaxation: str | None = None) -> str:
    """Whether the LP outer set is still empty in a box that holds the a priori box and the
    default one, each :data:`WIDER_A` times wider in ``a`` and :data:`WIDER_B` times in
    ``b`` (about its centre): if not, the box may be what excludes the system. A hint, not
    a certificate: the LP set is an outer set. Nothing when the LP set is not empty in the
    box itself (a tighter relaxation found the set empty). ``relaxation``: the
    :attr:`~hammerbound.exceptions.EmptyFeasibleSetError.relaxation` of the verdict (None:
    the LP is solved to learn whether its set is empty)."""
    from ..exceptions import SolverError
    from ..relaxations.lp import lp_bounds
    from ..relaxations.theta_box import default_theta_box

    if relaxation is None:
        try:
            lp_bounds(problem, check_box=False)
        except EmptyFeasibleSetError:
            relaxation = "lp"
        except SolverError:
            return ""
    if relaxation != "lp":  # a tighter relaxation than the LP found it empty: the LP
        return ""  # cannot tell more
    factor = np.where(np.arange(problem.p) < problem.na, WIDER_A, WIDER_B)
    mine = _widened(problem.theta_box, factor)
    default = _widened(default_theta_box(problem.na, problem.nb, problem.nk == 0,
                                         nk=problem.nk), factor)
    wider = np.column_stack([np.minimum(mine[:, 0], default[:, 0]),
                             np.maximum(mine[:, 1], default[:, 1])])
    what = (f"a box that holds the a priori box and the default one, {WIDER_A:g}x wider in "
            f"a and {WIDER_B:g}x wider in b")
    try:
        wide = lp_bounds(problem.with_theta_box(wider), check_box=False).bounds
    except EmptyFeasibleSetError:
        return f"The LP outer set is empty also in {what}: the box is not what empties it."
    except SolverError:
        return ""
    return (f"In {what}, the LP outer set is not empty: the a priori box may be what "
            "excludes the system (the default box holds only stable A's and |b_j| <= 1e4; "
            f"a box you gave may miss the system). {_rows_hint(problem, wide)}")


def _rows_hint(problem, wide) -> str:
    """Which rows of the a priori box the LP set in the wider box leaves (``wide``: its
    intervals), and an example ``theta_box`` of those rows (symmetric, a power of ten)."""
    box, names = problem.theta_box, problem.param_names
    outside = (wide[:, 0] < box[:, 0]) | (wide[:, 1] > box[:, 1])
    disjoint = (wide[:, 1] < box[:, 0]) | (wide[:, 0] > box[:, 1])
    rows = np.flatnonzero(disjoint if disjoint.any() else outside)
    if rows.size == 0:  # pragma: no cover - a set inside the box would not be empty there
        return "Pass a wider theta_box if your knowledge allows it."
    where = ", ".join(f"{names[k]} in [{wide[k, 0]:.4g}, {wide[k, 1]:.4g}]" for k in rows)
    ends = [10.0 ** np.ceil(np.log10(max(np.abs(wide[k]).max(), 1e-300)) + 1e-12)
            for k in rows]
    example = ", ".join(f"'{names[k]}': ({-e:g}, {e:g})" for k, e in zip(rows, ends,
                                                                      strict=True))
    return (f"There the LP set has {where}, beyond the a priori box ("
            + ", ".join(f"{names[k]} in [{box[k, 0]:.3g}, {box[k, 1]:.3g}]" for k in rows)
            + "). Pass a theta_box with the values your knowledge allows for these rows "
            f"(keeping any rows you gave for the others), e.g. theta_box={{{example}}}.")


def check_not_crossed(est, problem, bounds):
    """Refuse bounds whose ends cross. Both ends are certified outer bounds (lower <= min,
    max <= upper over the set, relaxed outward by the tolerance policy): if they cross, no
    parameter vector is feasible, beyond the tolerance."""
    if not np.all(np.isfinite(bounds)):  # pragma: no cover - every method clips
        from ..exceptions import SolverError

        raise SolverError(f"internal error: non-finite bounds {bounds.tolist()}; "
                          "please report it.")
    crossed = np.flatnonzero(bounds[:, 0] > bounds[:, 1])
    if crossed.size:
        k = int(crossed[0])
        name = problem.param_names[k]
        raise EmptyFeasibleSetError(
            f"no parameters explain the data within the bounds: the certified bounds on "
            f"{name} cross ({bounds[k, 0]:.6g} > {bounds[k, 1]:.6g}). "
            f"{assumptions(est, problem)}", relaxation=est.method)


def assumption_list(est, problem) -> list[str]:
    """The assumptions that shaped the feasible set, one phrase each."""
    g = est.steady_state_gain
    gain = ("no steady-state gain constraint" if g is None else
            f"steady-state gain constraint B(1)/A(1) = {g:g} (22.8)")
    box = box_text(est.theta_box, problem.na, problem.nb, problem.nk)
    dx = bound_text(problem.input_bound)
    shared = ("" if problem.n_groups == problem.N else
              f", shared by {problem.n_groups} sample groups")
    exact = " (exact input)" if not np.any(problem.input_bound) else ""
    return [f"output error bound |eta_t| <= {bound_text(problem.output_bound)}",
            f"input error bound |dx_t| <= {dx}{exact}{shared}", gain, box]

def assumptions(est, problem) -> str:
    """One sentence naming every assumption that shaped the feasible set."""
    lags = problem.b_lags
    b_terms = " + ".join(f"b{j}" + (f" q^-{j}" if j else "") for j in lags)
    a_terms = "".join(f" + a{i} q^-{i}" for i in range(1, problem.na + 1))
    items = assumption_list(est, problem)
    if est.steady_state_gain is not None:
        items[2] = items[2][:-1] + "; pass steady_state_gain=None for a plain EIV problem)"
    return (f"Active assumptions: orders na={problem.na}, nb={problem.nb}, "
            f"nk={problem.nk} (A = 1{a_terms}, B = {b_terms}); " + "; ".join(items) + ".")


def box_text(theta_box, na, nb, nk) -> str:
    """The a priori box as an assumption: the default one, the user's, or the user's rows
    (a dict, :func:`~hammerbound.relaxations.problem.resolve_theta_box`) and the default
    for the others."""
    default = "|a_i| <= binom(na, i) (stable A), |b_j| <= 1e4"
    if theta_box is None or (isinstance(theta_box, dict) and not theta_box):
        return f"default a priori box {default}"
    if not isinstance(theta_box, dict):
        return "user theta_box"
    rows = given_rows_text(theta_box, na, nb, nk)
    rest = [n for n in theta_names(na, nb, nk) if n not in theta_box]
    if not rest:
        return f"a priori box {rows} (theta_box)"
    parts = [text for text, pre in (("|a_i| <= binom(na, i) (stable A)", "a"),
                                    ("|b_j| <= 1e4", "b"))
             if any(n.startswith(pre) for n in rest)]
    return (f"a priori box {rows} (theta_box); default box for {', '.join(rest)} "
            f"({', '.join(parts)})")


def box_hint(est, problem) -> str:
    """A hint for badly scaled data, whose true b_j may lie outside the default box."""
    given = given_rows(est.theta_box, problem.na, problem.nb, problem.nk)
    if given[problem.na:].all():
        return ""
    sx = float(np.max(np.abs(problem.x))) or 1.0
    sy = float(np.max(np.abs(problem.y))) or 1.0
    if 1e-3 <= sy / sx <= 1e3:
        return ""
    return (f"The data are badly scaled (max |x| = {sx:.3g}, max |y| = {sy:.3g}): the "
            "b_j may lie outside the default box |b_j| <= 1e4 or be lost to the solver "
            "tolerances. Rescale x and y to similar magnitudes (and steady_state_gain "
            "accordingly) or pass a theta_box.")


def check_box(est, problem, res):
    """Decide what a bound that coincides with the a priori box means.

    The default box on ``a`` (``|a_i| <= binom(na, i)``) contains every *stable* ``A``
    (assumption A1), so a bound set by it is still guaranteed under A1; the result
    gives it the status :data:`~hammerbound.status.BOX`. The same holds for a
    user-supplied ``theta_box``
    (the user's prior). The default box on ``b`` (``|b_j| <= 1e4``) is arbitrary:
    touching it means the data do not bound that coefficient, which is an error.
    """
    from ..relaxations.lp import box_limit_message, box_limited_ends

    ends = box_limited_ends(res.bounds, problem.theta_box, problem.param_names)
    given = given_rows(est.theta_box, problem.na, problem.nb, problem.nk)
    bad = [lab for k, lab in ends if k >= problem.na and not given[k]]
    if bad:
        stopped = [f"{i.param} {i.end}" for i in res.infos if i.status == "limit"]
        raise UnboundedSetError(box_limit_message(
            bad, stopped, where="below the default box |b_j| <= 1e4",
            advice="a smaller output_bound if justified, or a theta_box with prior "
                   "knowledge"))


def warn_limits(res, stacklevel=4):
    """Warn, naming the interval ends, when a search stopped at a node/time limit."""
    import warnings

    from ..exceptions import SearchLimitWarning
    from ..relaxations.exact.isolation import CRASH_TEXT

    ends = [f"{i.param} {i.end}" for i in res.infos if i.status == "limit"]
    died = [f"{i.param} {i.end}" for i in res.infos
            if i.status == "limit" and CRASH_TEXT in (i.message or "")]
    if ends:
        why = (f" ({', '.join(died)}: the worker process of the search died, see the "
               "warning before; more time does not help there)" if died else "")
        warnings.warn(
            f"the exact search stopped early for {len(ends)} of {len(res.infos)} interval "
            f"ends ({', '.join(ends)}): their bounds are guaranteed outer bounds (never "
            "wider than the LP bound) but may be looser than the exact ones; raise "
            "time_limit / total_time_limit / max_nodes for tighter ones (bound_info_ "
            f"gives each end's status and certified gap){why}.", SearchLimitWarning,
            stacklevel=stacklevel)
