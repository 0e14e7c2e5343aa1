"""Solving the moment relaxation's objectives and certifying each end (worker side).

:func:`solve_group` solves several objectives on one conic data set (a joblib worker) and
certifies each from its dual (:func:`~hammerbound.solvers.conic.best_certificate`);
:func:`end_info` turns a solve into the reported interval end, labelled by where its value
comes from (the certificate, the LP bound or the a priori box). :func:`solve_all` runs
the objectives (in worker processes), :func:`ends` gathers the interval ends, and
:class:`Lines` tells the progress on stderr.
"""

from __future__ import annotations

import time

import numpy as np

from ...exceptions import SolverError
from ...solvers.conic import EPS, ConicData, best_certificate
from ...status import BOX, FAILED, INACCURATE, INFEASIBLE, LIMIT, OPTIMAL, RELAXATION
from ..result import BoundInfo, DualCertificate

__all__ = ["Lines", "end_info", "ends", "solve_all", "solve_group"]


def solve_group(data: ConicData, xub, jobs, backend, solver_options: dict | None,
                on_done=None):
    """Worker: solve several objectives on one conic data set and certify each (``backend``
    is the registry's object, passed as it is: no lookup or licence check in a worker).
    ``on_done(job)`` (in-process runs) is called after each objective."""
    out = []
    try:
        inst = backend.conic(data, solver_options)
    except Exception as exc:  # noqa: BLE001 - reported per bound below
        return [(j, None, None, f"{type(exc).__name__}: {exc}") for j in jobs]
    for jid, q, q0 in jobs:
        try:
            sol = inst.solve(q, q0)
        except Exception as exc:  # noqa: BLE001
            out.append((jid, None, None, f"{type(exc).__name__}: {exc}"))
            continue
        # the dual, its least-squares repair and alternating cone projections are all dual
        # vectors: the best of their rigorous bounds is kept
        vb = None if sol.z is None else best_certificate(data, q, sol.z, xub, q0)
        out.append((jid, sol, vb, ""))
        if on_done is not None:
            on_done(jid)
    return out


def end_info(name, sense, sol, vb, err, solver, known, a_priori) -> BoundInfo:
    """One end of a moment interval, labelled by where its value comes from.

    ``known`` = (lower, upper) certified outer bounds already known for the parameter (the
    polytopic LP bound, within the a priori box); ``a_priori`` its a priori box
    (``problem.theta_box``). The end is the moment certificate when it is tighter than
    ``known`` (status of the solve: ``OPTIMAL``, else ``INACCURATE`` / ``LIMIT``: the bound
    comes from the dual), else the known end: ``BOX`` when that end is the a priori box
    itself, ``RELAXATION`` (the LP bound) otherwise. Never wider than ``known``.
    """
    lo, hi = known
    certified = vb is not None and bool(np.isfinite(vb.bound))
    val = np.nan
    if certified:
        # vb.bound <= min of (+-theta_k); add a rounding margin for the sign flip
        lb = vb.bound - 2 * EPS * abs(vb.bound)
        val = lb if sense == "min" else -lb
    tighter = certified and (val > lo if sense == "min" else val < hi)
    if tighter:
        bnd = float(val)
        status = sol.status if sol.status in (OPTIMAL, LIMIT, INFEASIBLE) else INACCURATE
    else:
        bnd = float(lo if sense == "min" else hi)
        w = max(1.0, a_priori[1] - a_priori[0])
        at_box = (bnd <= a_priori[0] + 1e-9 * w) if sense == "min" else (
            bnd >= a_priori[1] - 1e-9 * w)
        status = BOX if at_box else RELAXATION
    sv = np.nan
    if sol is not None and np.isfinite(sol.primal_value):
        sv = sol.primal_value if sense == "min" else -sol.primal_value
    cert = None
    if vb is not None:
        cert = DualCertificate(vb.dual_value if sense == "min" else -vb.dual_value,
                               vb.psd_correction, vb.residual_correction, vb.cone_correction)
    msg = err if sol is None else f"{solver}: {sol.native_status}" + (f"; {err}" if err else "")
    if not tighter:
        why = ("its certificate" + (f" ({val:.6g})" if certified else "") + " is not tighter"
               if certified else "no certificate")
        msg += (f"; {why}: the {'a priori box' if status == BOX else 'LP bound'} end "
                "is reported")
    return BoundInfo(
        param=name, sense=sense, bound=bnd, solver_value=float(sv), status=status,
        certified=certified, time=float(sol.time) if sol is not None else 0.0,
        iterations=None if sol is None else sol.iterations, message=msg, certificate=cert)


class Lines:
    """Progress lines of :func:`moment_bounds` on stderr (nothing unless ``on``)."""

    def __init__(self, on, t0, objs, names):
        self.on, self.t0, self.objs, self.names, self.n = on, t0, objs, names, 0

    def __call__(self, text):
        if self.on:
            import sys

            print(f"moment: {text}", file=sys.stderr, flush=True)

    def done(self, jid):
        self.n += 1
        k, sense = self.objs[jid][:2]
        self(f"{self.names[k]} {sense} solved ({self.n} of {len(self.objs)}), "
             f"{time.perf_counter() - self.t0:.1f} s")


def solve_all(relax, objs, backend, opts, n_jobs, on_done=None):
    """The ``2 p`` conic solves (in ``n_jobs`` worker processes), in the order of
    ``objs``: ``(job, solution, verified bound, error)``; ``on_done(job)`` after each
    (with workers: for each of a worker's jobs when the worker ends)."""
    jobs = [(i, q, q0) for i, (_, _, q, q0) in enumerate(objs)]
    data = relax.data.strip_picos()
    if n_jobs > 1 and backend.name == "clarabel" and "max_threads" not in opts:
        # one thread per worker process: measured faster than 2 x 2 threads on 2 cores
        opts = {**opts, "max_threads": 1}
    if n_jobs == 1:
        results = solve_group(data, relax.xub, jobs, backend, opts, on_done)
    else:
        from joblib import Parallel, delayed

        groups = [jobs[i::n_jobs] for i in range(n_jobs)]
        results = []
        for part in Parallel(n_jobs=n_jobs, return_as="generator_unordered")(
                delayed(solve_group)(data, relax.xub, g, backend, opts) for g in groups):
            results += part
            for r in part:
                if on_done is not None:
                    on_done(r[0])
    return sorted(results, key=lambda r: r[0])


def ends(problem, box, objs, results, fallback, solver, on_failure):
    """The bounds (p, 2) and :class:`BoundInfo` of every end: its certificate when tighter
    than ``fallback``, else the fallback end (or :class:`SolverError` with
    ``on_failure="raise"`` when no certificate could be computed)."""
    names = problem.param_names
    bounds = box.copy()
    infos = []
    for (jid, sol, vb, err), (k, sense, _q, _q0) in zip(results, objs, strict=True):
        assert jid == len(infos)
        if (vb is None or not np.isfinite(vb.bound)) and on_failure == "raise":
            status = FAILED if sol is None else sol.status
            raise SolverError(
                f"{solver}: could not certify the {sense} of {names[k]} "
                f"(status {status}{': ' + err if err else ''}); try another solver, "
                "tighter tolerances or on_failure='box'."
            )
        info = end_info(names[k], sense, sol, vb, err, solver,
                        (max(box[k, 0], fallback[k, 0]), min(box[k, 1], fallback[k, 1])),
                        problem.theta_box[k])
        infos.append(info)
        bounds[k, 0 if sense == "min" else 1] = info.bound
    return bounds, infos
