"""Solving the moment relaxation's objectives and certifying each end (worker side).

:func:`solve_group` solves several objectives on one conic data set (a joblib worker) and
certifies each from its dual (:func:`~hammerbound.solvers.conic.best_certificate`);
:func:`end_info` turns a solve into the reported interval end, labelled by where its value
comes from (the certificate, the LP bound or the a priori box).
"""

from __future__ import annotations

import numpy as np

from ...solvers.conic import EPS, ConicData, best_certificate
from ...status import BOX, INACCURATE, INFEASIBLE, LIMIT, OPTIMAL, RELAXATION
from ..result import BoundInfo, DualCertificate

__all__ = ["end_info", "solve_group"]


def solve_group(data: ConicData, xub, jobs, backend, solver_options: dict | None):
    """Worker: solve several objectives on one conic data set and certify each (``backend``
    is the registry's object, passed as it is: no lookup or licence check in a worker)."""
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
