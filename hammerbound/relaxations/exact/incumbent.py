"""The incumbent of one interval end of the exact method (:class:`IncumbentSearch`, mixed
into :class:`.search.EndSearch`): verified points found at the node LP points by the
primal heuristics -- the screen and line searches, an SLP walk, the completion of a node's
``a`` by its best ``b`` (no input errors), Gauss-Newton restoration where the relaxation is
exact. They only change how fast the gap closes: every point is verified by
:func:`.problem.check_theta`, and the lower bound never depends on them.
"""

from __future__ import annotations

import numpy as np

from .local import improve, restore_near

# after a line search that does not improve the incumbent, wait up to this many nodes
_MAX_SEARCH_GAP = 16
_MAX_SEARCH_GAP_WALKED = 1024
# nodes before the first completion of an LP point's a (an end that closes sooner pays none)
_FIRST_COMPLETE = 8
# Gauss-Newton restoration next to an LP point at which the relaxation is exact (every
# product violation below this, relative to max(1, |incumbent|)): once per this many nodes.
# Exact up to the node LP's own feasibility tolerance (HiGHS's 1e-7): with 1e-9 a record
# with every error at its bound (N = 60, na = 1, nb = 1, nk = 0) ran 3 ends into the node
# limit (LP points held their products to 7e-8); with 1e-6 every end closes at its root
# (0.5 s); the chapter's N = 300 problems give the same nodes and bounds either way
_EXACT_VIOLATION = 1e-6
_RESTORE_GAP = 64
# resolution of the SLP walk to a near-optimal incumbent (.local.improve): a fraction of
# the tolerance
_LOCAL_RES = 0.05


class IncumbentSearch:
    """The primal heuristics of :class:`.search.EndSearch` (which holds the state they
    use: ``pool``, ``k``, ``sense``, ``inc``, ``ub``, ``nodes``, the search schedules)."""

    def _try_incumbent(self, x, box, lb) -> bool:
        """Look for a better verified point at the node's LP point ``x``; True when the
        new incumbent closes the node."""
        th = np.clip(x[: self.problem.p], box[: self.problem.p, 0], box[: self.problem.p, 1])
        if self.val(th) >= self.ub - self.tol_eff:
            return False
        pt = self._heuristic_point(th, x, box)
        if pt is None or self.val(pt.theta) >= self.ub:
            return False
        self.inc, self.ub = pt, self.val(pt.theta)
        if self.interior is None:
            self.interior = pt.theta
        return self._closes(lb)

    def _heuristic_point(self, th, x, box):
        """The primal heuristic at an LP point: screen it, then line searches of ~10 LPs
        each, while they pay off (then backing off geometrically: the lower-bound proof
        needs no incumbent updates); an SLP walk from a better point; restoration where
        the relaxation is exact. Returns a verified point or None."""
        due = self.nodes - self.last_try >= self.try_gap
        pt = None
        if due:
            self.last_try = self.nodes
            pt = self.pool.add(th)
            if pt is None:
                pt = self._line_searches(th)
        if pt is None:
            pt = self._complete(th)
        if pt is not None and self.local and self.val(pt.theta) < self.ub - self.tol_eff:
            # another basin (or the first point): walk it down by SLP as well
            pt = self._walk(pt)
        if pt is None:
            pt = self._restore_at(th, x, box)
        if due:
            # useful: better by more than the searches' resolution
            useful = pt is not None and self.val(pt.theta) < self.ub - 0.25 * self.tol_eff
            self.try_gap = 1 if useful else min(2 * self.try_gap, self.max_gap)
        return pt

    def _complete(self, th):
        """Without input errors: ``th``'s ``a`` with the best ``b`` for it (one LP,
        :meth:`.points._Pool.complete`), on its own schedule: every node while it improves
        the incumbent, backing off geometrically (to :data:`_MAX_SEARCH_GAP`) while not.
        On a thin set the node LP's ``a`` lies in it where line searches never land
        (an output-error record, N = 120: a gap of 3e-3 left after 30 s without it)."""
        if self.nodes - self.last_complete < self.complete_gap:
            return None
        self.last_complete = self.nodes
        pt = self.pool.complete(th, self.k, self.sense)
        if pt is None and self.inc is not None:
            pt = self.pool.complete_line(self.inc.theta, th, self.k, self.sense,
                                         steps=8, resolution=0.25 * self.tol_eff)
        good = pt is not None and self.val(pt.theta) < self.ub - 0.25 * self.tol_eff
        self.complete_gap = 1 if good else min(2 * self.complete_gap, _MAX_SEARCH_GAP)
        return pt if good else None

    def _line_searches(self, th):
        """Line searches towards ``th``: a short segment from the incumbent (fine near the
        optimum), then from the interior point."""
        res = 0.25 * self.tol_eff
        pt = None
        if self.inc is not None:
            pt = self.pool.line_search(self.inc.theta, th, k=self.k, resolution=res)
            if pt is not None and self.val(pt.theta) >= self.ub:
                pt = None
        if pt is None and self.interior is not None:
            pt = self.pool.line_search(self.interior, th, k=self.k, resolution=res)
        return pt

    def _walk(self, pt):
        return improve(self.pool, pt, self.k, self.sense, self.box0,
                       _LOCAL_RES * self.tol_eff, stop_at=self.stop_at)

    def _restore_at(self, th, x, box):
        """Gauss-Newton next to an LP point at which the relaxation is exact but that is
        not verified (the set is thin there, see :func:`.local.restore_near`)."""
        if not self.local or self.nodes - self.last_restore < _RESTORE_GAP:
            return None
        exact = _EXACT_VIOLATION * max(1.0, abs(self.ub))
        if self.relax.violations(x, self.ks).max() > exact:
            return None
        self.last_restore = self.nodes
        pt = restore_near(self.pool, (th, *self.relax.split_eta_dx(x)),
                          box[: self.problem.p], 0.25 * self.tol_eff, stop_at=self.stop_at)
        if pt is not None and self.val(pt.theta) < self.ub - self.tol_eff:
            pt = self._walk(pt)
        return pt
