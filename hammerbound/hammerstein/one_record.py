"""The identifier's one-record path: both blocks from one ordinary record (:mod:`~hammerbound.joint`).

:func:`fit_one_record` takes the settings of the identifier's stage-2 estimator (orders,
delay, output bound, method, limits, jobs), the record, an optional a priori backlash box
and optional steady-state points, and returns a :class:`OneRecordFit`: the certified
intervals, the statuses, the assumptions they rest on and what the record does not
identify (reported as infinite ends with a :class:`~hammerbound.exceptions.NotIdentifiedWarning`,
never as a finite bound that only an assumption holds up, unless the user gave that
assumption).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, replace
from functools import partial

import numpy as np

from ..data.validation import warn_bound_covers_output
from ..exceptions import (
    DataValidationError,
    EmptyFeasibleSetError,
    NotIdentifiedWarning,
    ParameterValidationError,
    SearchLimitWarning,
)
from ..joint import (
    ASSUMED_LIMIT_RTOL,
    GAMMA_NAMES,
    LIMIT_RTOL,
    GammaPrior,
    RecordProblem,
    at_prior_limit,
    default_gamma_box,
    record_bounds,
    record_box,
    unidentified,
)
from ..joint.relaxation import gain_tolerance
from ..relaxations.problem import (
    b_lags_of,
    given_rows,
    given_rows_text,
    resolve_theta_box,
    theta_names,
)
from ..status import BOX, INACCURATE, NOT_IDENTIFIED, RELAXATION
from ..tables import bound_text, rounded_text
from .default_box import search_default_box
from .empty_bound import with_smallest_bound
from .record_checks import (
    record_a1_of,
    warn_dead_band_covers_record,
    warn_gain_sign,
    warn_inputs_off_zero,
    with_gain_sign,
)
from .setup import GAIN_ASSUMPTION

__all__ = ["OneRecordFit", "fit_one_record"]


@dataclass(frozen=True)
class OneRecordFit:
    """What the one-record path found (see the module docstring)."""

    problem: RecordProblem
    result: object
    prior: GammaPrior
    theta_bounds: np.ndarray
    gamma_bounds: np.ndarray
    statuses: tuple
    assumptions: tuple
    unidentified: tuple
    seconds: float


def _gamma_prior(gamma_box, u, y, deta) -> GammaPrior:
    if gamma_box is None:
        return GammaPrior(default_gamma_box(u, y, deta), user_given=False)
    g = np.asarray(gamma_box, dtype=float)
    if g.shape != (4, 2) or not np.all(np.isfinite(g)) or np.any(g[:, 0] > g[:, 1]) \
            or np.any(g[:, 0] < 0):
        raise ParameterValidationError(
            "gamma_box must be a finite (4, 2) array of [lower, upper] rows for m_l, c_l, "
            "m_r, c_r with 0 <= lower <= upper, e.g. [[0, 1], [0, 0.5], [0, 1], [0, 0.5]].")
    return GammaPrior(g, user_given=True)


def _problem(lin, data, prior, steady, steady_bound, output_bound):
    nk = lin._nk()
    na, nb = int(lin.na), int(lin.nb)
    deta = np.broadcast_to(np.asarray(output_bound, dtype=float), data.y.shape)
    theta_box = None if lin.theta_box is None else resolve_theta_box(lin.theta_box, na, nb, nk)
    box = record_box(na, b_lags_of(nb, nk).size, data.u, prior.box, theta_box)
    st = None
    if steady is not None:
        us, ys = (np.asarray(v, dtype=float).ravel() for v in steady)
        st = (us, ys, np.broadcast_to(np.asarray(steady_bound, float), us.shape).copy())
    return RecordProblem(data.u, data.y, deta, na, nb, nk, box, st)


def _box_words(theta_box, na, nb, nk) -> str:
    """The a priori box of A in the assumptions: stable A (default rows), the user's."""
    given = given_rows(theta_box, na, nb, nk)
    if not given.any():
        return ", stable A (|a_i| <= binom(na, i))"
    default_a = not given[:na].all()
    return (f"; a priori box {given_rows_text(theta_box, na, nb, nk)} (theta_box)"
            + (", stable A (|a_i| <= binom(na, i)) for the other a_i" if default_a else ""))


def _assumptions(problem, prior, lin, steady, found=()) -> tuple:
    deta = np.asarray(problem.deta, dtype=float)
    every = " on every sample" if np.all(deta == deta.flat[0]) else ""
    out = [f"output errors |eta_t| <= {bound_text(deta)}{every}",  # (per sample: review)
           "the input is known exactly",
           GAIN_ASSUMPTION
           + _box_words(lin.theta_box, problem.na, problem.nb, problem.nk),
           prior.describe(reached=sorted({n for n, _ in found})),
           f"the backlash lines do not cross over the record's inputs "
           f"[{rounded_text(float(np.min(problem.u)), down=True)}, "
           f"{rounded_text(float(np.max(problem.u)), down=False)}] "
           "(m_l (u + c_l) >= m_r (u - c_r): a well-posed backlash)"]
    given = given_rows(lin.theta_box, problem.na, problem.nb, problem.nk)
    if not given[problem.na:].all():
        names = theta_names(problem.na, problem.nb, problem.nk)
        rest = [n for n, g in zip(names, given, strict=True) if n[0] == "b" and not g]
        which = "" if given[problem.na:].sum() == 0 else f" for {', '.join(rest)}"
        out.append(f"|b_j| <= 1e4{which} (default theta box; pass theta_box to "
                   "LinearEIVSetEstimator to change)")
    if steady is not None:
        out.append("steady-state points: u > 0 on the right line, u < 0 on the left (the "
                   "last move before each hold went the same way), settled: a transient left "
                   "counts against the steady-state output bound")
    return tuple(out)


def _check_length(lin, n_samples, prior, steady):
    """Refuse, before any work, a record with fewer equations (one per sample from ``n0``,
    one per steady-state point) than unknowns (the linear block's ``p``, and the backlash
    parameters the a priori box leaves free: 4 unless a gamma_box fixes some)."""
    from ..stage2.orders import model_size

    nk = lin._nk()
    p, n0 = model_size(lin.na, lin.nb, nk)
    n_steady = 0 if steady is None else np.size(steady[0])
    free = int(np.sum(prior.box[:, 1] > prior.box[:, 0]))
    n_eq = max(n_samples - n0, 0) + n_steady
    if n_eq < p + free:
        fixed = "" if free == 4 else f", {4 - free} fixed by the gamma_box"
        points = f" and {n_steady} steady-state points" if n_steady else ""
        raise DataValidationError(
            f"a one-record fit with na={lin.na}, nb={lin.nb}, nk={nk} has {p + free} "
            f"unknowns ({p} of the linear block, {free} of the backlash{fixed}), which need "
            f"at least {p + free} equations, but N = {n_samples} samples{points} give "
            f"{n_eq} (one per sample from t = {n0}{', one per point' if n_steady else ''}). "
            f"Use a longer record (N >= {n0 + p + free - n_steady}) or lower orders.")


def _warn_stopped(infos, named, method="exact"):
    """Warn, naming them, about the interval ends a limit stopped (status "limit") that the
    not-identified warning does not already name (``named``: backlash parameters). The
    per-end limits are named only for the exact method (the LP method has none)."""
    ends = [f"{i.param} {i.end}" for i in infos
            if i.status == "limit" and i.param not in named]
    if ends:
        more = ("total_time_limit (or time_limit / max_nodes)" if method == "exact"
                else "total_time_limit")
        warnings.warn(
            f"the search stopped early for {len(ends)} of {len(infos)} interval ends "
            f"({', '.join(ends)}): their bounds are guaranteed outer bounds but may be "
            f"looser than the record allows; raise {more} for tighter ones (bound_info_ "
            "gives each end's status).",
            # warn -> here -> fit_one_record -> _fit_one_record -> fit -> the caller
            SearchLimitWarning, stacklevel=5)


def _warn_inaccurate(infos, lps_stopped) -> None:
    """A SearchLimitWarning naming the finite ends of status INACCURATE: some relaxation
    LPs ended before optimality, so those bounds (certified from the LPs' duals) may be
    looser than the relaxation gives (review: they had no warning of their own)."""
    ends = [f"{i.param} {i.end}" for i in infos
            if i.status == INACCURATE and np.isfinite(i.bound)]
    if ends:
        warnings.warn(
            f"{lps_stopped} relaxation LP(s) ended before optimality (their own time limit, "
            f"at most hammerbound.joint.relaxation.LP_TIME_LIMIT s, or HiGHS could not "
            f"solve them): the bounds of {', '.join(ends)} are certified from those LPs' "
            "duals and may be looser than the relaxation allows. Rescaling the data or a "
            "narrower gamma_box may help.", SearchLimitWarning,
            # warn -> here -> fit_one_record -> _fit_one_record -> fit -> the caller
            stacklevel=5)


#: causes of :func:`~hammerbound.joint.prior.unidentified` that are the record's own
_RECORD_CAUSES = ("the input never reverses", "the record does not excite")


def _lead(stopped_by_time, causes=()) -> str:
    """How a not-identified warning begins: with the time limit when it stopped the
    search (new-user trial 9 read "the record does not bound" as the record's fault),
    with the record only when every cause is the record's (trial 16: "the record does
    not bound cl, cr" where a gamma_box bounded them from the same record: the
    relaxation over the default box was too weak)."""
    if stopped_by_time:
        return "within the time limit the search did not bound"
    if causes and all(c.startswith(_RECORD_CAUSES) for c in causes):
        return "the record does not bound"
    return "the search did not bound"


def _report_unidentified(problem, bounds, prior, stopped_by_time=False, lps_stopped=0,
                         method="exact", pace=(0, 0.0)):
    """Ends stuck at an assumed limit become infinite, with a warning naming the cause."""
    p = problem.p
    gb = bounds[p: p + 4].copy()
    found = unidentified(problem.u, GAMMA_NAMES, gb, prior.box, prior.assumed(),
                         stopped_by_time=stopped_by_time, lps_stopped=lps_stopped,
                         method=method,
                         rtol=LIMIT_RTOL if prior.user_given else ASSUMED_LIMIT_RTOL)
    if not found:
        return gb, ()
    for name, _cause in found:
        i = GAMMA_NAMES.index(name)
        if not prior.user_given:
            gb[i, 1] = np.inf
    names = ", ".join(sorted({n for n, _ in found}))
    causes = "; ".join(sorted({c for _, c in found}))
    what = ("reported as infinite (not identified)" if not prior.user_given
            else "limited only by the gamma_box you gave")
    rests = ("" if prior.user_given else
             "The other intervals rest on the default backlash box (in assumptions_): a "
             "slope or dead band beyond it (e.g. a state that starts on a line far from "
             "the record's inputs) could lie outside them. ")
    # an input that never reverses is the cause whatever the time (recheck 52b)
    timed = stopped_by_time and not all(c.startswith(_RECORD_CAUSES) for _, c in found)
    lead = _lead(timed, [c for _, c in found])
    warnings.warn(f"{lead} {names}: {causes}. Those ends are {what}. "
                  + rests + _scale_hint(problem, bounds, {n for n, _ in found}, timed)
                  + _advice(timed, lps_stopped, prior.user_given, pace),
                  # warn -> here -> fit_one_record -> _fit_one_record -> fit -> the caller
                  NotIdentifiedWarning, stacklevel=5)
    return gb, tuple(found)


def _scale_hint(problem, bounds, names, stopped_by_time=False) -> str:
    """A sentence when backlash slopes are not bounded and the a_i intervals *found* let
    ``A(1) = 1 + sum a_i`` reach 0: the unit-gain normalisation (22.8) then leaves the scale
    between the slopes and ``B`` free (new-user trial 11: a plant with A(1) = 0.15 bounded
    nothing; with the a_i boxed so that A(1) >= 0.05 its backlash was bounded in 34 s).
    When the time limit stopped the search or an a_i end is still at its a priori limit,
    those intervals say nothing of the plant (review): the record's least-squares A(1)
    may be named instead (:func:`_slow_plant_hint`)."""
    if not names & {"ml", "mr"} or problem.na == 0:
        return ""
    a = bounds[: problem.na]
    if stopped_by_time or any(at_prior_limit(a[i, j], problem.box, i, j)
                              for i in range(problem.na) for j in (0, 1)):
        return _slow_plant_hint(problem)
    low = 1.0 + float(np.sum(a[:, 0]))
    if not low <= 0.0:
        return ""
    return (f"The a_i intervals found let A(1) = 1 + a_1 + ... + a_na reach 0 (down to "
            f"{low:.3g}), so the unit-gain normalisation (22.8) does not fix the scale "
            "between the backlash slopes and B: a likely reason the slopes are not bounded "
            "(a plant whose A(1) is small, e.g. slow or lightly damped). A theta_box on "
            "the a_i from what you know of the plant (keeping A(1) > 0) or a gamma_box "
            "bounding m_l, m_r fixes it. ")


#: below this, the record's least-squares A(1) suggests a slow plant (trial 18: 0.06 and
#: 0.2 bounded nothing in 300 s; trial 11: 0.15; the chapter's plant: 1.06)
SLOW_A1 = 0.25


def _slow_plant_hint(problem) -> str:
    """When the search's own a_i intervals say nothing (stopped, or at their a priori
    limits): a sentence if the record's least-squares fit has a small A(1), a *possible*
    reason (new-user trial 18: second-order plants with A(1) = 0.06 and 0.2 bounded
    nothing, and the warning blamed only the time limit)."""
    a1 = record_a1_of(problem)
    if not a1 < SLOW_A1:
        return ""
    return (f"The record's least-squares fit has A(1) = 1 + a_1 + ... + a_na = {a1:.2g} (a "
            "slow or lightly damped plant?): the unit-gain normalisation (22.8) then fixes "
            "the scale between the backlash slopes and B only weakly, a possible reason the "
            "slopes are not bounded. A theta_box on the a_i from what you know of the plant "
            "(keeping A(1) well above 0) or a gamma_box bounding m_l, m_r helps. ")


def _not_identified_infos(infos, theta_bounds, gamma_bounds) -> tuple:
    """The ends' infos (theta's then the backlash's, min and max per parameter) with those
    reported as infinite said so: bound +-inf, status NOT_IDENTIFIED (their search stopped
    at an assumed limit; ``bound_info_`` and ``bounds_`` then agree)."""
    b = np.vstack([theta_bounds, gamma_bounds])
    out = []
    for i, info in enumerate(infos):
        k, e = divmod(i, 2)
        if np.isinf(b[k, e]):
            info = replace(info, bound=float(b[k, e]), status=NOT_IDENTIFIED)
        elif b[k, e] != info.bound:  # tightened by the gain equality (gain_tightened)
            # an end so moved is no longer the a priori box's (review)
            info = replace(info, bound=float(b[k, e]),
                           status=RELAXATION if info.status == BOX else info.status)
        out.append(info)
    return tuple(out)


def gain_tightened(problem, theta_bounds) -> np.ndarray:
    """``theta_bounds`` intersected with what the gain equality (22.8)
    ``sum_j b_j = g (1 + sum_i a_i)`` gives each ``b_j`` from the other intervals (interval
    arithmetic, widened by the relaxation's outward tolerance of that row). A search that
    a limit stopped can leave a ``b_j`` at its default box while the ``a_i`` are bounded:
    with one ``b`` it is then ``g (1 + sum_i a_i)`` itself (new-user trial 14: ``b1`` was
    reported infinite beside a bounded ``a1``)."""
    tb = np.array(theta_bounds, dtype=float)
    na, p, g = problem.na, problem.p, float(problem.gain)
    if g <= 0 or not np.all(np.isfinite(tb[:na])):
        return tb
    tol = gain_tolerance(g, problem.box[:p])  # the relaxation's row, over the a priori box
    lo = g * (1.0 + tb[:na, 0].sum())
    hi = g * (1.0 + tb[:na, 1].sum())
    for j in range(na, p):
        others = np.delete(tb[na:], j - na, axis=0)
        if not np.all(np.isfinite(others)):
            continue
        jlo = lo - others[:, 1].sum() - tol
        jhi = hi - others[:, 0].sum() + tol
        jlo, jhi = np.nextafter(jlo, -np.inf), np.nextafter(jhi, np.inf)
        new = [max(tb[j, 0], jlo), min(tb[j, 1], jhi)]
        if new[0] <= new[1]:  # (an empty meet would be rounding: keep the search's)
            tb[j] = new
    return tb


def _unbounded_b(problem, theta_bounds, lin, stopped_by_time=False):
    """``b_j`` ends at the *default* box ``|b_j| <= 1e4`` (an arbitrary assumption, not
    the record's answer) become infinite, with a warning naming them; rows of a
    ``theta_box`` the user gave keep their ends (the user's prior, status "box")."""
    tb = np.array(theta_bounds, dtype=float)
    given = given_rows(lin.theta_box, problem.na, problem.nb, problem.nk)
    names = problem.names
    hit = []
    for k in range(problem.na, problem.p):
        for j in (0, 1):
            if not given[k] and at_prior_limit(tb[k, j], problem.box, k, j,
                                               ASSUMED_LIMIT_RTOL):
                tb[k, j] = -np.inf if j == 0 else np.inf
                hit.append(names[k])
    hit = tuple(dict.fromkeys(hit))  # b_j once even when both its ends are at the box
    if not hit:
        return tb, ()
    which = ", ".join(hit)
    more = "give more time (total_time_limit), or " if stopped_by_time else ""
    warnings.warn(
        f"{_lead(stopped_by_time)} {which}: it reached the default box "
        "|b_j| <= 1e4, an assumption and not the record's answer, so those ends are "
        "reported as infinite (and there is no central model). The other intervals hold "
        f"under that box (see assumptions_). To bound them, {more}use a record that moves "
        "the input more often, or lower na, nb if the plant may be of lower order (a "
        "pole of the model cancelling a zero leaves its b_j free), or pass a theta_box "
        "from what you know of the gain.",
        # warn -> here -> fit_one_record -> _fit_one_record -> fit -> the caller
        NotIdentifiedWarning, stacklevel=5)
    return tb, hit


def _advice(stopped_by_time, lps_stopped, box_given=False, pace=(0, 0.0)) -> str:
    """What to do about backlash ends the record did not bound, for the cause
    :func:`~hammerbound.joint.unidentified` names: more time when the time limit stopped
    the search (with the leaves' pace when it cut some short: ``pace = (cut, mean
    seconds)``); another record when no limit did (the input is then a cause it names);
    a (narrower) gamma_box."""
    fixes = []
    if stopped_by_time:  # (LPs stopped at their own cap: the cause says what helps)
        cut, sec = pace
        more = (f"; the limit cut {cut} leaf box(es) of the partition short, and those "
                f"tightened before it took about {sec:.2g} s each on this machine (more "
                "time may also split the partition further)" if cut else "")
        fixes.append(f"give more time (total_time_limit{more})")
    elif not lps_stopped:
        fixes.append("use a record whose input reverses by more than the dead band")
    fixes.append("narrow the gamma_box if what you know of the actuator allows it"
                 if box_given else "give a gamma_box")
    text = ", or ".join(fixes) + "."
    return text[0].upper() + text[1:]


def _at_assumed_limit(problem, prior):
    """Skip the search of a backlash end already at (within :data:`ASSUMED_LIMIT_RTOL`
    of) a default (assumed) a priori limit after OBBT: a search could only move it within
    that band, and such an end is reported as not identified (infinite) anyway. With a box
    the user gave, every end is searched."""
    if prior.user_given:
        return None
    p, assumed = problem.p, prior.assumed()

    def skip(k, sense, bound):
        i, j = k - p, (0 if sense > 0 else 1)
        if not 0 <= i < 4 or not assumed[i, j]:
            return False
        return at_prior_limit(bound, prior.box, i, j, ASSUMED_LIMIT_RTOL)

    return skip


def fit_one_record(lin, data, *, gamma_box=None, steady=None, steady_bound=None,
                   output_bound=None) -> OneRecordFit:
    """Certified intervals of both blocks from the record ``data`` (an IOData)."""
    t0 = time.perf_counter()
    lin._check_params()  # tol, limits, orders (a negative total_time_limit ran, trial 11)
    if lin.method not in ("exact", "lp"):
        raise ParameterValidationError(
            f"the one-record identification supports method='exact' (tight intervals) or "
            f"'lp' (the relaxation's bounds); got method={lin.method!r} on the stage-2 "
            "estimator.")
    ob = lin._output_bound(data.N, output_bound)
    prior = _gamma_prior(gamma_box, data.u, data.y, ob)
    _check_length(lin, data.N, prior, steady)
    warn_bound_covers_output("HammersteinBacklashIdentifier.fit", data.output_name or "y",
                             data.y, ob, stacklevel=5)
    warn_inputs_off_zero(data.u, data.input_name or "u")
    deadline = None if lin.total_time_limit is None else time.time() + float(lin.total_time_limit)
    try:
        prior, problem, res = search_default_box(
            partial(_search, lin, data, steady=steady, steady_bound=steady_bound, ob=ob,
                    deadline=deadline), prior, deadline, bool(lin.progress))
    except EmptyFeasibleSetError as exc:
        raise with_smallest_bound(
            exc, partial(_scaled_problem, lin, data, prior, steady, steady_bound, ob), ob,
            prior, lin, time.perf_counter() - t0) from exc
    warn_gain_sign(problem, res)
    d = res.details
    gb, found = _report_unidentified(problem, res.bounds, prior,
                                     d is not None and d.stopped_by_time,
                                     0 if d is None else d.lps_stopped, lin.method,
                                     (0, 0.0) if d is None else (d.leaves_cut,
                                                                 d.leaf_seconds))
    tb, b_found = _unbounded_b(problem, gain_tightened(problem, res.bounds[: problem.p]), lin,
                               d is not None and d.stopped_by_time)
    _warn_stopped(res.infos, {name for name, _ in found} | set(b_found), lin.method)
    warn_dead_band_covers_record(problem.u, gb)
    res = replace(res, infos=_not_identified_infos(res.infos, tb, gb))
    _warn_inaccurate(res.infos, 0 if d is None else d.lps_stopped)
    statuses = tuple(i.status for i in res.infos)
    return OneRecordFit(problem, res, prior, tb, gb, statuses,
                        _assumptions(problem, prior, lin, steady, found), found,
                        time.perf_counter() - t0)


def _scaled_problem(lin, data, prior, steady, steady_bound, ob, factor):
    """The record's problem with its output bound multiplied by ``factor``."""
    return _problem(lin, data, prior, steady, steady_bound, ob * factor)


def _search(lin, data, prior, *, steady, steady_bound, ob, deadline):
    """The problem under ``prior`` and its :func:`~hammerbound.joint.record_bounds`."""
    problem = _problem(lin, data, prior, steady, steady_bound, ob)
    try:
        res = record_bounds(problem, method=lin.method, tol=float(lin.tol),
                            max_nodes=int(lin.max_nodes), time_limit=lin.time_limit,
                            deadline=deadline, n_jobs=lin.n_jobs,
                            skip=_at_assumed_limit(problem, prior),
                            progress=bool(lin.progress))
    except EmptyFeasibleSetError as exc:
        raise with_gain_sign(exc, problem) from exc
    return problem, res


def in_param_order(infos, p):
    """The one-record ends (theta's, then the backlash's; each witness the search's vector
    ``[theta, gamma, z0]``) with witnesses in the order of the parameters they are shown
    with, and ``inner`` (the end's parameter at its witness) filled in (new-user trial 9:
    the witness did not follow ``param_names_``, and ``inner`` was None).

    Returns ``((identifier_theta_ends, linear_view_theta_ends), backlash_ends)``: the
    identifier's witnesses are ``[m_l, c_l, m_r, c_r, theta]`` (its ``param_names_``), the
    linear view's ``theta`` (as :class:`~hammerbound.LinearEIVSetEstimator`'s). The full
    joint witness, with the initial backlash state ``z0``, stays in ``point``."""
    def with_witness(info, vector, k):
        if info.point is None:
            return info
        vector = np.asarray(vector, dtype=float)
        return replace(info, witness=vector, inner=float(vector[k]))

    def joint(info):
        return None if info.point is None else np.concatenate([info.point.gamma,
                                                               info.point.theta])

    theta_ends, gamma_ends = infos[: 2 * p], infos[2 * p:]
    ident = tuple(with_witness(i, joint(i), 4 + j // 2) for j, i in enumerate(theta_ends))
    view = tuple(with_witness(i, None if i.point is None else i.point.theta, j // 2)
                 for j, i in enumerate(theta_ends))
    gamma = tuple(with_witness(i, joint(i), j // 2) for j, i in enumerate(gamma_ends))
    return (ident, view), gamma
