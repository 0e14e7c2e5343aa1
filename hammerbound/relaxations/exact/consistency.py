"""Is the EIV set (22.34) empty? A certificate either way, or "undecided" at a limit.

Order selection needs this decision, not the intervals: an order whose feasible set is
empty on the record is *falsified* (no model of that order explains the data within the
bounds), whatever its fit on part of the record scores. The polytopic LP decides
"empty" only for part of the inconsistent problems (its set is a strict outer
approximation); the exact method's machinery decides the rest:

* **consistent**: a verified-feasible point (:func:`.problem.check_theta` accepted it;
  the witness is returned);
* **empty**: the polytopic LP, the McCormick relaxation at the root (OBBT) or every leaf of
  a branch-and-bound tree is certified infeasible (the same certificates on which
  :func:`.bnb.exact_bounds` raises :class:`~hammerbound.exceptions.EmptyFeasibleSetError`;
  infeasibility is decided with the LPs' feasibility tolerance pointing outward, so a
  set that is empty only within the tolerances is not called empty);
* **undecided**: neither within ``time_limit`` or ``max_nodes`` (never counted as empty).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ...exceptions import EmptyFeasibleSetError
from ..lp import lp_bounds
from ..problem import EIVProblem
from .bnb import verified_points
from .local import restore
from .obbt import _obbt
from .points import _Pool
from .search import search_end

__all__ = ["Consistency", "consistency"]

STATUSES = ("consistent", "empty", "undecided")


@dataclass(frozen=True)
class Consistency:
    """The decision of :func:`consistency`.

    ``status`` is ``"consistent"``, ``"empty"`` or ``"undecided"``; ``by`` names the
    certificate (``"witness"``, ``"lp"``, ``"relaxation"``, ``"branch-and-bound"``) or
    ``"limit"``; ``witness`` is the verified theta of a consistent set; ``nodes`` and
    ``time`` (s) the cost.
    """

    status: str
    by: str
    witness: np.ndarray | None
    nodes: int
    time: float
    message: str

    @property
    def empty(self) -> bool:
        return self.status == "empty"


def consistency(problem: EIVProblem, *, time_limit: float = 60.0,
                max_nodes: int = 20000) -> Consistency:
    """Decide whether some theta explains the data of ``problem`` within its bounds.

    Runs the polytopic LP, Gauss-Newton steps from the least-squares equation-error
    estimate (a verified point in a few LPs for most consistent sets), then OBBT on the
    McCormick relaxation, the search for a first verified point of the exact method and,
    if still undecided, one branch-and-bound tree
    (on ``min theta_1``) that stops at its first verified point or when every leaf is
    certified infeasible. ``time_limit`` (s) and ``max_nodes`` bound the work; what is not
    decided by then is ``"undecided"``.
    """
    t0 = time.perf_counter()
    deadline = time.time() + float(time_limit)

    def done(status, by, witness=None, nodes=0, message=""):
        return Consistency(status, by, witness, nodes, time.perf_counter() - t0, message)

    try:
        lp = lp_bounds(problem, check_box=False)
    except EmptyFeasibleSetError as exc:
        return done("empty", "lp", message=str(exc))
    pool = _Pool(problem)
    phi, yt = problem.regressors()
    theta_ls = np.clip(np.linalg.lstsq(phi, -yt, rcond=None)[0], lp.bounds[:, 0],
                       lp.bounds[:, 1])
    # a shortcut only: at most 2 s (a tenth of the budget when that is shorter)
    pt = pool.add(theta_ls) or restore(
        pool, [(theta_ls, np.zeros(problem.N), np.zeros(problem.n_groups))], lp.bounds,
        stop_at=time.perf_counter() + min(0.1 * float(time_limit), 2.0))
    if pt is not None:
        return done("consistent", "witness", pt.theta.copy(),
                    message="a point verified feasible by check_theta")
    try:
        box, roots, thetas, _ = _obbt(problem, lp.bounds, deadline=deadline)
    except EmptyFeasibleSetError as exc:
        return done("empty", "relaxation", message=str(exc))
    pts = verified_points(problem, box, roots, thetas, deadline=deadline)
    if pts:
        return done("consistent", "witness", pts[0].theta.copy(),
                    message="a point verified feasible by check_theta")
    left = deadline - time.time()
    if left <= 0:
        return done("undecided", "limit", message=f"time limit ({time_limit:g} s) reached")
    # a tolerance this large ends the tree at its first verified point
    out = search_end(problem, box, 0, 1.0, [], roots.get((0, 1.0)), tol=1e12,
                     max_nodes=max_nodes, time_limit=left, progress=False, position=0,
                     deadline=deadline)
    if out.bound == np.inf:
        return done("empty", "branch-and-bound", nodes=out.nodes,
                    message="every node of the McCormick relaxation certified infeasible")
    if out.witness is not None:
        return done("consistent", "witness", out.witness.theta.copy(), out.nodes,
                    "a point verified feasible by check_theta")
    return done("undecided", "limit", nodes=out.nodes, message=out.message)
