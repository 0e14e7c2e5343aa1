"""A persistent HiGHS LP with *guaranteed* bounds (row-bound form of :mod:`.safe_lp`).

The LP is ``min c'z  s.t.  rl <= A z <= ru,  l <= z <= u`` with every column boxed
(finite ``l, u``). The model is kept inside one :class:`highspy.Highs` object so that a
branch-and-bound can change bounds, costs and a few coefficients and re-solve from the
previous basis (warm start) instead of rebuilding the LP.

Rigour (Neumaier & Shcherbina, 2004; same argument as :func:`.safe_lp.dual_bound`): for
*any* row multipliers ``y``, with ``y+ = max(y, 0)`` paired with finite ``rl`` and
``y- = min(y, 0)`` paired with finite ``ru``, and ``r = c - A'(y+ + y-)``::

    min c'z  >=  y+'rl + y-'ru + sum_j min(r_j l_j, r_j u_j),

evaluated in floating point and lowered by a rounding margin. With ``c = 0`` a positive
value of the right-hand side is a Farkas certificate of infeasibility; HiGHS's dual ray
is tried for that, and :func:`.safe_lp.certify_infeasible` (phase 1) is the fallback.

HiGHS instances are created quiet and their runs time-limited by :mod:`.highs_process`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import highspy
import numpy as np
import scipy.sparse as sp

from ..status import FAILED, INFEASIBLE, OPTIMAL
from .highs_process import RUN_TIME_LIMIT, _run_cap, limit_run, new_highs, past, seconds_left
from .highs_refusal import HIGHS_DEFAULTS, RECOVERY, _status_text, refusal_message, refused
from .safe_lp import certify_infeasible, row_dual_bound

#: LP status (not an interval-end status): the dual simplex proved the value exceeds the
#: requested objective bound (the reported bound is rigorous).
CUTOFF = "cutoff"

INF = highspy.kHighsInf

def _joined(*notes) -> str:
    """Non-empty notes joined by "; "."""
    return "; ".join(n for n in notes if n)


def basis_arrays(basis):
    """A HiGHS basis (:meth:`HighsLP.snapshot`) as the ``(col_status, row_status)`` int8
    arrays of :meth:`HighsLP.get_basis` and :meth:`HighsLP.set_basis`."""
    return (np.fromiter((int(v) for v in basis.col_status), np.int8),
            np.fromiter((int(v) for v in basis.row_status), np.int8))


@dataclass
class LPSolve:
    """Outcome of :meth:`HighsLP.solve`.

    Attributes
    ----------
    status : {OPTIMAL, INFEASIBLE, CUTOFF, FAILED}
        Constants of :mod:`hammerbound.status` (and :data:`CUTOFF`).
        ``"infeasible"`` only with a certificate; ``"cutoff"`` means the dual simplex
        proved the value exceeds the requested objective bound (``bound`` is rigorous).
    bound : float
        Rigorous lower bound of the LP minimum (``+inf`` if certified infeasible).
    value : float
        HiGHS objective value (not guaranteed), NaN if none.
    x : ndarray or None, shape (n,)
        Primal point (``None`` unless optimal).
    iterations : int
    reduced : ndarray or None, shape (n,)
        Reduced costs behind ``bound`` (see :func:`row_dual_bound`), when optimal.
    note : str
        Empty, or what happened when HiGHS first refused the LP (see
        :meth:`HighsLP.solve`): how it was solved after all, or why it was not.
    refused : bool
        HiGHS refused the LP on every attempt of :data:`RECOVERY` (status ``"failed"``,
        bound ``-inf``).
    """

    status: str
    bound: float
    value: float
    x: np.ndarray | None
    iterations: int = 0
    reduced: np.ndarray | None = None
    note: str = ""
    refused: bool = False


class HighsLP:
    """Persistent LP ``min c'z, rl <= A z <= ru, lb <= z <= ub`` on one HiGHS instance.

    Parameters
    ----------
    A : scipy.sparse matrix, shape (m, n)
    rl, ru : ndarray, shape (m,)
    lb, ub : ndarray, shape (n,)
        Finite column bounds (required for the rigorous bound).
    c : ndarray, shape (n,), optional
    options : dict, optional
        Extra HiGHS options (name -> value), e.g. simplex pricing for repeated warm starts.
        Not ``time_limit``: use ``run_limit`` and ``deadline``.
    run_limit : float, optional
        Seconds one solve may take (default and at most :data:`RUN_TIME_LIMIT`); a solve
        stopped there returns status ``"failed"`` with the bound its duals certify.
    deadline : float, optional
        :func:`time.time` stamp at which every solve stops (same outcome). Both are
        attributes and may be changed between solves.

    Raises
    ------
    ValueError
        ``options`` holds ``time_limit``, or HiGHS rejected an option.
    """

    def __init__(self, A, rl, ru, lb, ub, c=None, options=None, *, run_limit=None,
                 deadline=None):
        if "time_limit" in (options or {}):
            raise ValueError("HighsLP: pass run_limit= (seconds per solve) or deadline= "
                             "(time.time() stamp) instead of the HiGHS option time_limit, "
                             "which counts the time of all solves of the instance")
        self.run_limit, self.deadline = run_limit, deadline
        self._stop = None  # time.time() stamp at which the current solve() stops
        A = sp.csc_matrix(A, dtype=float)
        A.sort_indices()
        self.A = A
        m, n = A.shape
        self.rl = np.asarray(rl, dtype=float).copy()
        self.ru = np.asarray(ru, dtype=float).copy()
        self.lb = np.asarray(lb, dtype=float).copy()
        self.ub = np.asarray(ub, dtype=float).copy()
        self.c = np.zeros(n) if c is None else np.asarray(c, dtype=float).copy()
        h = new_highs(options)
        self._options = dict(options or {})
        # unscaled solves are faster on well-scaled data, but if the certified bound then
        # trails HiGHS's own value, the duals are inaccurate: scaling goes back on for good
        self._unscaled = (options or {}).get("simplex_scale_strategy") == 0
        self.rescaled = False
        lp = highspy.HighsLp()
        lp.num_col_ = n
        lp.num_row_ = m
        lp.col_cost_ = self.c
        lp.col_lower_ = self.lb
        lp.col_upper_ = self.ub
        lp.row_lower_ = np.where(np.isfinite(self.rl), self.rl, -INF)
        lp.row_upper_ = np.where(np.isfinite(self.ru), self.ru, INF)
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = A.indptr.astype(np.int32)
        lp.a_matrix_.index_ = A.indices.astype(np.int32)
        lp.a_matrix_.value_ = A.data
        h.passModel(lp)
        self.h = h
        self._cutoff = None

    # ---- modification ---------------------------------------------------------------
    def set_cost(self, c):
        c = np.asarray(c, dtype=float)
        idx = np.flatnonzero(c != self.c)
        if idx.size:
            self.h.changeColsCost(idx.size, idx.astype(np.int32), c[idx])
            self.c = c.copy()

    def set_col_bounds(self, idx, lo, hi):
        idx = np.asarray(idx, dtype=np.int32)
        if idx.size == 0:
            return
        self.lb[idx] = lo
        self.ub[idx] = hi
        self.h.changeColsBounds(idx.size, idx, self.lb[idx], self.ub[idx])

    def set_row_bounds(self, idx, lo, hi):
        idx = np.asarray(idx, dtype=np.int32)
        if idx.size == 0:
            return
        self.rl[idx] = lo
        self.ru[idx] = hi
        rl = np.where(np.isfinite(self.rl[idx]), self.rl[idx], -INF)
        ru = np.where(np.isfinite(self.ru[idx]), self.ru[idx], INF)
        self.h.changeRowsBounds(idx.size, idx, rl, ru)

    def data_positions(self, rows, cols) -> np.ndarray:
        """Positions in ``A.data`` of the existing entries ``(rows[k], cols[k])``."""
        A = self.A
        rows = np.asarray(rows, dtype=np.int64)
        cols = np.asarray(cols, dtype=np.int64)
        m = np.int64(A.shape[0])
        # CSC with sorted indices: the keys col * m + row of the entries are increasing
        keys = np.repeat(np.arange(A.shape[1], dtype=np.int64), np.diff(A.indptr)) * m \
            + A.indices.astype(np.int64)
        want = cols * m + rows
        pos = np.searchsorted(keys, want)
        bad = (pos >= keys.size) | (keys[np.minimum(pos, keys.size - 1)] != want)
        if np.any(bad):
            k = int(np.flatnonzero(bad)[0])
            raise KeyError(f"no structural entry at ({rows[k]}, {cols[k]})")
        return pos

    def add_cols(self, lo, hi):
        """Append empty columns with bounds ``lo, hi`` and zero cost (the basis is kept)."""
        lo = np.asarray(lo, dtype=float)
        hi = np.asarray(hi, dtype=float)
        k = lo.size
        if k == 0:
            return
        self.h.addCols(k, np.zeros(k), lo, hi, 0, np.zeros(k, dtype=np.int32),
                       np.zeros(0, dtype=np.int32), np.zeros(0))
        self.A = sp.hstack([self.A, sp.csc_matrix((self.A.shape[0], k))], format="csc")
        self.lb = np.concatenate([self.lb, lo])
        self.ub = np.concatenate([self.ub, hi])
        self.c = np.concatenate([self.c, np.zeros(k)])

    def add_rows(self, rl, ru, block):
        """Append rows ``rl <= block z <= ru`` (``block`` sparse, shape (k, n); basis kept)."""
        block = sp.csr_matrix(block, dtype=float)
        k = block.shape[0]
        if k == 0:
            return
        block.sort_indices()
        rl = np.asarray(rl, dtype=float)
        ru = np.asarray(ru, dtype=float)
        self.h.addRows(k, np.where(np.isfinite(rl), rl, -INF), np.where(np.isfinite(ru), ru, INF),
                       block.nnz, block.indptr.astype(np.int32), block.indices.astype(np.int32),
                       block.data)
        # through CSR (vstack of CSR concatenates the arrays): explicit zeros (coefficients
        # that set_box may have set to 0) stay structural entries
        A = sp.vstack([self.A.tocsr(), block], format="csr").tocsc()
        A.sort_indices()
        self.A = A
        self.rl = np.concatenate([self.rl, rl])
        self.ru = np.concatenate([self.ru, ru])

    def set_coeffs(self, rows, cols, pos, vals):
        """Change existing coefficients (``pos`` from :meth:`data_positions`)."""
        vals = np.asarray(vals, dtype=float)
        changed = np.flatnonzero(self.A.data[pos] != vals)
        if changed.size == 0:
            return
        ch = self.h.changeCoeff
        # one HiGHS call per entry (highspy has no batch call): plain lists keep it cheap
        for r, c, v in zip(np.asarray(rows)[changed].tolist(), np.asarray(cols)[changed].tolist(),
                           vals[changed].tolist(), strict=True):
            ch(r, c, v)
        self.A.data[pos[changed]] = vals[changed]

    def set_cutoff(self, value):
        """Let the dual simplex stop once the objective provably exceeds ``value``."""
        v = INF if value is None or not np.isfinite(value) else float(value)
        if v != self._cutoff:
            self.h.setOptionValue("objective_bound", v)
            self._cutoff = v

    # ---- basis transfer (warm start across processes) ----------------------------------
    def get_basis(self):
        """Current simplex basis as ``(col_status (n,), row_status (m,))`` int8 arrays, or None."""
        b = self.h.getBasis()
        return basis_arrays(b) if b.valid else None

    def snapshot(self):
        """The current simplex basis as a HiGHS object (a cheap copy, for warm starts in
        this process; :meth:`get_basis` gives a picklable one), or None."""
        b = self.h.getBasis()
        return b if b.valid else None

    def restore(self, snapshot) -> bool:
        """Warm start from a :meth:`snapshot` of the same model structure."""
        return snapshot is not None and self.h.setBasis(snapshot) == highspy.HighsStatus.kOk

    def set_basis(self, basis) -> bool:
        """Warm start from a basis returned by :meth:`get_basis` (same model structure)."""
        if basis is None:
            return False
        st = highspy.HighsBasisStatus
        b = highspy.HighsBasis()
        b.col_status = [st(int(v)) for v in basis[0]]
        b.row_status = [st(int(v)) for v in basis[1]]
        b.valid = True
        return self.h.setBasis(b) == highspy.HighsStatus.kOk

    # ---- solve ----------------------------------------------------------------------
    def bound_from(self, y) -> float:
        return row_dual_bound(self.c, self.A, self.rl, self.ru, self.lb, self.ub, y)

    def _certify_infeasible(self) -> bool:
        h = self.h
        zero = np.zeros_like(self.c)
        # the ray may take a solve of its own (after presolve), and so may the fallback:
        # what is left of the solve's time, at least 1 s (not certified: not infeasible)
        left = max(1.0, (self._stop or np.inf) - time.time())
        try:
            limit_run(h, seconds=left)
            out = h.getDualRay()
            has, ray = (out[1], out[2]) if len(out) == 3 else (out[0], out[1])
        except Exception:  # pragma: no cover - depends on highspy version
            has, ray = False, None
        if has and ray is not None:
            ray = np.asarray(ray, dtype=float)
            for s in (1.0, -1.0):
                if row_dual_bound(zero, self.A, self.rl, self.ru, self.lb, self.ub, s * ray) > 0:
                    return True
        # fallback: phase-1 LP of safe_lp (rows split into <= and == parts)
        A = self.A.tocsr()
        eq = np.isfinite(self.rl) & np.isfinite(self.ru) & (self.rl == self.ru)
        up = np.isfinite(self.ru) & ~eq
        lo = np.isfinite(self.rl) & ~eq
        A_ub = sp.vstack([A[up], -A[lo]]).tocsr()
        b_ub = np.concatenate([self.ru[up], -self.rl[lo]])
        return certify_infeasible(A_ub, b_ub, A[eq], self.rl[eq], self.lb, self.ub,
                                  time_limit=min(left, RUN_TIME_LIMIT))

    def _run_highs(self):
        """One ``run()`` of HiGHS, stopped at :attr:`run_limit` or :attr:`deadline`
        (:func:`limit_run`): ``(run status, model status)`` (a seam for tests)."""
        limit_run(self.h, deadline=self._stop)
        run = self.h.run()
        return run, self.h.getModelStatus()

    def _run(self):
        """``run()``, and when HiGHS stops with an error before a result, the recovery
        ladder of :data:`RECOVERY` (see :func:`refused`). Returns ``(model status, note)``;
        the status is None when every attempt was refused, ``note`` says what happened."""
        run, st = self._run_highs()
        if not refused(run, st):
            return st, ""
        first = _status_text(self.h, run, st)
        tried = []
        for label, opts in RECOVERY:
            self.h.clearSolver()  # drop the basis: the next run starts from scratch
            for name, value in opts.items():
                self.h.setOptionValue(name, value)
            try:
                run, st = self._run_highs()
            finally:
                for name in opts:
                    if name != "simplex_scale_strategy":
                        self.h.setOptionValue(name, self._options.get(name, HIGHS_DEFAULTS[name]))
            if "simplex_scale_strategy" in opts and self._unscaled:
                self._unscaled, self.rescaled = False, True  # scaling stays on for good
            tried.append(label)
            if not refused(run, st):
                how = (f"solved {label}" if st == highspy.HighsModelStatus.kOptimal else
                       f"re-run {label}, which ended with model status "
                       f"'{self.h.modelStatusToString(st)}'")
                return st, f"HiGHS stopped with an error before a result ({first}); {how}"
        self.h.clearSolver()
        return None, refusal_message(first, tried, self.defects())

    def defects(self) -> str:
        """What makes the LP data invalid ("" if nothing): crossed bounds, NaN values."""
        out = []
        for what, lo, hi in (("row", self.rl, self.ru), ("column", self.lb, self.ub)):
            bad = np.flatnonzero(lo > hi)
            if bad.size:
                out.append(f"{bad.size} {what} bound(s) crossed (first: {what} {bad[0]}, "
                           f"{float(lo[bad[0]]):.17g} > {float(hi[bad[0]]):.17g})")
            if np.isnan(lo).any() or np.isnan(hi).any():
                out.append(f"NaN {what} bounds")
        if not np.all(np.isfinite(self.A.data)) or not np.all(np.isfinite(self.c)):
            out.append("non-finite matrix or cost values")
        return "; ".join(out)

    def solve(self, *, primal=False) -> LPSolve:
        """Solve from the current basis and return a rigorous bound (see module docstring).

        ``primal=True`` runs the primal simplex, for a re-solve after a change of the cost
        only: the last optimal basis stays primal feasible (measured on the one-record
        relaxation at N = 300: OBBT's second solve of a row about 1.6x faster than with
        the default dual simplex).

        An LP that HiGHS refuses (``run()`` returns an error before any result, e.g. its
        dual ratio test fails on a near-singular warm-start basis) is re-solved from
        scratch, with the primal simplex and with the interior-point method
        (:data:`RECOVERY`); if every attempt is refused the result is ``"failed"`` with
        bound ``-inf`` and ``refused=True`` -- the caller keeps the bound it already has
        (a branch-and-bound node its parent's, OBBT its box) -- and ``note`` says why.
        """
        # one stop for the whole solve: the recovery ladder's re-runs and the re-solves
        # below (:meth:`_solve_once`) included
        self._stop = time.time() + seconds_left(_run_cap(self.run_limit), self.deadline)
        return self._solve_once(primal)

    @property
    def stop(self) -> float | None:
        """:func:`time.time` stamp at which the last :meth:`solve` stopped or stops (its
        :attr:`run_limit` or :attr:`deadline`); None before the first solve. A caller that
        solves again as part of the same task passes it on as the :attr:`deadline`."""
        return self._stop

    def _solve_once(self, primal, retry=True) -> LPSolve:
        """One solve before :attr:`_stop` (set by :meth:`solve`); ``retry``: a run that
        ends with model status "Unknown" is solved again (:meth:`_after_unknown`)."""
        h = self.h
        if np.any(self.lb > self.ub):
            return LPSolve(INFEASIBLE, np.inf, np.nan, None, 0)
        if primal:
            h.setOptionValue("simplex_strategy", 4)
        try:
            st, note = self._run()
        finally:
            if primal:
                h.setOptionValue("simplex_strategy", self._options.get(
                    "simplex_strategy", HIGHS_DEFAULTS["simplex_strategy"]))
        it = int(h.getInfo().simplex_iteration_count)
        if st is None:
            return LPSolve(FAILED, -np.inf, np.nan, None, it, note=note, refused=True)
        if retry and st == highspy.HighsModelStatus.kUnknown:
            return self._after_unknown(primal, it, note)
        res = self._result(st, it)
        res.note = note
        return res

    def _after_unknown(self, primal, it, note) -> LPSolve:
        """A run that ended with model status "Unknown", solved once more from scratch by
        the other simplex while time is left, before the same stop. Seen on the
        one-record relaxation: primal re-solves at N = 300, Delta eta = 0.3 (1 to 3 of about
        1000, with either dual pricing; the dual simplex from that basis ends the same way
        at once), and a cold dual solve in 1 of 10465 LPs of an N = 300 fit whose every
        end then said "limit"."""
        kind, other = ("primal", "dual") if primal else ("dual", "primal")
        what = f"the {kind} simplex ended with model status 'Unknown'"
        if past(self.deadline) or past(self._stop):
            res = self._result(highspy.HighsModelStatus.kUnknown, it)
            res.note = _joined(note, f"{what}; no time left to solve it again")
            return res
        self.h.clearSolver()
        res = self._solve_once(not primal, retry=False)
        res.iterations += it
        res.note = _joined(note, f"{what}; re-solved from scratch with the {other} simplex",
                           res.note)
        return res

    def _result(self, st, it) -> LPSolve:
        """The :class:`LPSolve` of a run that ended with model status ``st``."""
        h = self.h
        MS = highspy.HighsModelStatus
        if st == MS.kOptimal:
            sol = h.getSolution()
            y = np.asarray(sol.row_dual)
            x = np.asarray(sol.col_value)
            val = float(h.getInfo().objective_function_value)
            bound, r = row_dual_bound(self.c, self.A, self.rl, self.ru, self.lb, self.ub, y,
                                      with_reduced=True)
            if self._unscaled and not val - bound <= 1e-5 * (1.0 + abs(val)):
                self._unscaled, self.rescaled = False, True
                h.setOptionValue("simplex_scale_strategy", 2)  # HiGHS's default
                return self._solve_once(False)
            return LPSolve(OPTIMAL, bound, val, x, it, r)
        if st == MS.kObjectiveBound:
            sol = h.getSolution()
            y = np.asarray(sol.row_dual)
            b = self.bound_from(y) if sol.dual_valid else -np.inf
            return LPSolve(CUTOFF, b, np.nan, None, it)
        if st == MS.kInfeasible:
            if self._certify_infeasible():
                return LPSolve(INFEASIBLE, np.inf, np.nan, None, it)
            return LPSolve(FAILED, -np.inf, np.nan, None, it)
        # anything else: whatever duals exist still give a valid (maybe weak) bound
        try:
            sol = h.getSolution()
            b = self.bound_from(np.asarray(sol.row_dual)) if sol.dual_valid else -np.inf
        except Exception:  # pragma: no cover
            b = -np.inf
        return LPSolve(FAILED, b, np.nan, None, it)
