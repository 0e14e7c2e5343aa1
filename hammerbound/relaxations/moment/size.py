"""Size of a sparse moment relaxation, estimated *before* it is built (memory/time guard).

The relaxation is built in PICOS (coefficients passed directly as sparse matrices, so the
build is about linear in the record length N) and solved by an interior-point method whose
cost per iteration is the sparse factorisation of its rows plus the dense Hessian blocks of
the PSD cones: a block of side ``s`` has ``t = s (s + 1) / 2`` rows and costs about ``t^3``
per factorisation. :func:`estimate_moment_relaxation` counts the cliques, conic rows,
moment variables and PSD blocks from the problem's structure (cheap: no polynomial is
formed) and turns them into an estimate of the time (one core: the build and the ``2 p``
solves) and memory (one process); :func:`check_moment_budget` refuses
(:class:`~hammerbound.exceptions.RelaxationTooLargeError`) or warns against the budgets
below. The cost model is calibrated on the chapter example (``na = nb = 2``, idle machine,
``docs/benchmarks.md``): order 1 at N = 300 took 14 s, the term-sparse order 2 at N = 300
(24 x 24 moment matrices, ``t = 300``) 632 s of one core (357 s on 2) and 4.1 GB with 2
workers; it overestimates the full order-2 basis (45 x 45, ``t = 1035``; N = 10: 110 s of
one core, estimated 507 s). The memory of the PICOS build grows with ``rows x moments``.

Default budgets (constants; a call changes them through its options, never by patching
the module: ``LinearEIVSetEstimator(relaxation_max_work=...)``,
``moment_bounds(..., max_work=..., warn_work=...)``; ``float("inf")`` lifts the refusal):

``MOMENT_WARN_WORK = 60``
    estimated seconds (one core) above which a :class:`RuntimeWarning` says the relaxation
    will take minutes (with ``na = nb = 2``: order 1 at N ~ 830, sparse order 2 at
    N ~ 30, the full order-2 basis at any N).
``MOMENT_MAX_WORK = 3600``
    estimated seconds (one core) above which the moment method refuses (sparse order 2 at
    N ~ 1800, the full order-2 basis at N ~ 60, order 3 at N ~ 13). A relaxation whose
    estimated memory (counted once per worker process) exceeds the machine's is refused
    as well: on 24 GB with 2 workers that is sparse order 2 above N ~ 500 and order 1
    above N ~ 3500. Use
    ``method="lp"`` (seconds) or ``method="exact"`` (tight, with ``total_time_limit``)
    instead.
"""

from __future__ import annotations

import itertools
import numbers
import os
import warnings
from dataclasses import dataclass
from math import comb

import numpy as np

from ...exceptions import ParameterValidationError, RelaxationTooLargeError
from ..problem import EIVProblem

__all__ = ["MOMENT_MAX_WORK", "MOMENT_WARN_WORK", "MomentSize", "check_moment_budget",
           "check_work", "estimate_moment_relaxation", "solve_processes"]

#: Estimated seconds (one core) above which building the relaxation is refused.
MOMENT_MAX_WORK = 3600.0
#: Estimated seconds (one core) above which a warning says it will take minutes.
MOMENT_WARN_WORK = 60.0
# cost model, calibrated on the chapter example on an idle machine (issue 28): build ~ per
# conic row; solve ~ 2 p objectives x ~30 iterations x (a sparse factorisation ~ per conic
# row + the dense PSD blocks ~ sum of t^3, t = svec rows). Seconds per iteration measured:
# order 1 at N = 300 / 1000 (14,311 / 47,911 rows) 0.067 / 0.24; sparse order 2 at N = 100
# / 300 (sum t^3 = 2.65e9 / 8.05e9) 0.66 / 2.38; the full order-2 basis at N = 10 (8.88e9)
# 0.86 in 16 iterations per solve: the model overestimates it 4.6x in all (its few large
# blocks cost less per t^3).
_SEC_PER_ROW = 2.0e-4
_SEC_PER_ROW_ITER = 5.0e-6
_SEC_PER_PSD_FLOP = 2.3e-10
_ITERATIONS = 30
# memory of one process: the PICOS build grows with rows x moments (order 1 at N = 1000,
# 8.1e8: 880 MB over the process's base; sparse order 2 at N = 300, 3.4e9: 4.1 GB for the
# process and 2 workers; order 2 at N = 2000 without input errors, 2.6e10: past 13 GB and
# still building when stopped), the solver with the rows and the PSD blocks
_BYTES_PER_ENTRY = 1.2  # x rows x moments: the PICOS build
_BYTES_PER_ROW = 1.8e4  # conic data and the sparse KKT factors
_BYTES_PER_PSD = 32.0  # x sum t^2: the dense KKT blocks and their factors
# enumerate monomials to count the moments exactly up to this many tuples
_MAX_ENUMERATE = 2_000_000


@dataclass(frozen=True)
class MomentSize:
    """Estimated size of a sparse moment relaxation (see :func:`estimate_moment_relaxation`).

    Attributes
    ----------
    order : int
    n_cliques : int
        Distinct cliques (one moment matrix each).
    clique_vars : int
        Largest number of variables in a clique.
    psd_side : int
        Side of the largest moment matrix, ``binom(clique_vars + order, order)``.
    n_rows : int
        Conic rows (symmetric-vectorised PSD blocks, localizing and equality rows).
    n_moments : int
        Moment variables (exact when ``moments_exact``, else an upper bound).
    moments_exact : bool
    est_seconds, est_bytes : float
        Rough time (build and the ``2 p`` conic solves, one core) and memory (one process).
    psd_work : float
        ``sum t^3`` over the PSD blocks (``t = s (s + 1) / 2`` for side ``s``): the cost
        of one interior-point factorisation.
    basis : str
    """

    order: int
    n_cliques: int
    clique_vars: int
    psd_side: int
    n_rows: int
    n_moments: int
    moments_exact: bool
    est_seconds: float
    est_bytes: float
    psd_work: float = 0.0
    basis: str = "sparse"

    @property
    def work(self) -> float:
        """The measure the budgets apply to: :attr:`est_seconds`."""
        return self.est_seconds

    def describe(self) -> str:
        """One sentence with the sizes and the rough build cost (used in messages)."""
        b = f" ({self.basis} basis)" if self.order >= 2 else ""
        return (f"order {self.order}{b}: {self.n_cliques} cliques of up to {self.clique_vars} "
                f"variables (moment matrices {self.psd_side} x {self.psd_side}), "
                f"{self.n_rows} conic rows, {'' if self.moments_exact else '<= '}"
                f"{self.n_moments} moments; building and solving it would take "
                f"about {self.est_seconds:.0f} s (one core) and "
                f"{self.est_bytes / 2**20:.0f} MB (one process)")


def _clique_sets(problem: EIVProblem, theta_box) -> tuple[int, int, list]:
    """``(q, n_extra, [(variables, n_equations)])`` as :class:`.moment._ScaledPOP` builds them."""
    box = problem.theta_box if theta_box is None else np.asarray(theta_box, dtype=float)
    half = 0.5 * (box[:, 1] - box[:, 0])
    fixed = half <= 0
    g = problem.gain_row()
    elim = None
    if g is not None and np.any(np.abs(g[0]) * half > 0):
        elim = int(np.argmax(np.abs(g[0]) * half))
    q = sum(1 for k in range(problem.p) if k != elim and not fixed[k])
    n = problem.N
    eta = problem.eta_index() + q  # variable ids: theta 0..q-1, eta q.., dx q+N..
    dxi = problem.dx_index()
    dx_ok = problem.dx_group[dxi] > 0
    dxv = np.where(dx_ok, dxi + q + n, -1)
    counts: dict = {}
    base = tuple(range(q))
    for e in range(eta.shape[0]):
        key = base + tuple(sorted(set(eta[e].tolist()) | {v for v in dxv[e].tolist() if v >= 0}))
        counts[key] = counts.get(key, 0) + 1
    return q, (1 if elim is not None else 0), list(counts.items())


def _t3(side: int) -> float:
    """Factorisation cost ``t^3`` of a PSD block of ``side`` (``t`` svec rows); 0 for
    scalars."""
    if side <= 1:
        return 0.0
    return float(side * (side + 1) // 2) ** 3


def _seconds(rows: int, psd: float, p: int) -> float:
    return _SEC_PER_ROW * rows + 2 * p * _ITERATIONS * (_SEC_PER_ROW_ITER * rows
                                                         + _SEC_PER_PSD_FLOP * psd)


def _bytes(rows: int, moments: int, psd: float) -> float:
    # sum t^2 >= (sum t^3)^(2/3) / n_blocks^(1/3); blocks of one size dominate: use the sum
    # of t^2 of the same blocks, recovered as psd^(2/3) times a safety factor of 4
    solve = _BYTES_PER_ROW * rows + 4.0 * _BYTES_PER_PSD * psd ** (2.0 / 3.0)
    return max(_BYTES_PER_ENTRY * float(rows) * float(moments), solve)


def _sparse_counts(q: int, n_extra: int, cliques, d: int):
    """Rows and moments of ``basis="sparse"`` (see :func:`.moment._clique_constraints`),
    counted in closed form (no monomial is formed, so refusing is immediate at any order).

    Every clique holds all ``q`` theta variables and its ``m`` noise variables. Its basis
    (:func:`.basis._sparse_basis`, order ``d >= 2``) is ``theta^a`` with ``|a| <= d - 1``
    and ``theta^a e`` with ``|a| <= d - 1``: side ``s = (1 + m) C(q + d - 1, d - 1)``; each
    noise box ``1 - e^2`` is localized on the ``C(q + d - 1, d - 1)`` pure-theta monomials,
    each equation multiplied by the ``(1 + m) C(q + 2d - 3, 2d - 3)`` monomials ``theta^a``,
    ``theta^a e`` with ``|a| <= 2d - 3`` (products that stay inside the matrix). The
    products of two basis monomials are ``theta^a``, ``theta^a e`` and ``theta^a e e'``
    with ``|a| <= 2d - 2``: over all cliques, ``P - 1 + P (n_e + n_ee)`` moments with
    ``P = C(q + 2d - 2, 2d - 2)``, ``n_e`` distinct noise variables and ``n_ee`` distinct
    pairs ``e <= e'`` that share a clique.
    """
    theta_basis = comb(q + d - 1, d - 1)
    # localizers of 1 - e^2: the pure-theta monomials of degree <= d - 1; equality
    # multipliers: theta^a and theta^a e with |a| <= 2d - 3
    lb = theta_basis
    mult = comb(q + 2 * d - 3, 2 * d - 3)
    rows = q + n_extra  # scalar theta boxes, once
    psd = 0.0
    noise, pairs = set(), set()
    side_max = 0
    for cv, nh in cliques:
        nv = sorted(v for v in cv if v >= q)
        s = (1 + len(nv)) * theta_basis
        side_max = max(side_max, s)
        rows += s * (s + 1) // 2 + nh * (1 + len(nv)) * mult  # moment matrix; h x mult.
        psd += _t3(s)
        noise.update(nv)
        pairs.update(itertools.combinations_with_replacement(nv, 2))
    rows += len(noise) * (lb * (lb + 1) // 2)
    psd += len(noise) * _t3(lb)
    p_theta = comb(q + 2 * d - 2, 2 * d - 2)
    moments = p_theta - 1 + p_theta * (len(noise) + len(pairs))
    return rows, moments, side_max, psd


def estimate_moment_relaxation(problem: EIVProblem, order: int, theta_box=None,
                               basis: str = "sparse") -> MomentSize:
    """Estimate the size of :class:`.moment.MomentRelaxation` without building it.

    The rows are counted exactly (PSD blocks in symmetric vectorisation); the moments are
    counted exactly by enumerating the cliques' monomials when that is cheap (up to
    ``2e6`` monomials), else bounded from above. ``basis``: as in
    :class:`.moment.MomentRelaxation` (``"sparse"`` and ``"full"`` coincide at order 1).
    """
    d = int(order)
    q, n_extra, cliques = _clique_sets(problem, theta_box)
    if not cliques:
        cliques = [(tuple(range(q)), 0)]
    if basis == "sparse" and d >= 2 and any(nh for _, nh in cliques):
        rows, moments, side, psd = _sparse_counts(q, n_extra, cliques, d)
        nv_max = max(len(cv) for cv, _ in cliques)
        return MomentSize(order=d, n_cliques=len(cliques), clique_vars=nv_max,
                          psd_side=side, n_rows=int(rows), n_moments=int(moments),
                          moments_exact=True,
                          est_seconds=_seconds(rows, psd, problem.p),
                          est_bytes=_bytes(rows, moments, psd), psd_work=psd, basis="sparse")
    rows = 0
    nv_max = 0
    psd = 0.0
    if d == 1:  # scalar localizers (1 - v^2 >= 0, the extra box): identical ones once
        rows += len(set().union(*[set(cv) for cv, _ in cliques])) + n_extra
    for cv, nh in cliques:
        nv = len(cv)
        nv_max = max(nv_max, nv)
        s = comb(nv + d, d)
        sl = comb(nv + d - 1, d - 1)
        rows += s * (s + 1) // 2
        if d > 1:
            rows += (nv + n_extra) * sl * (sl + 1) // 2
            psd += (nv + n_extra) * _t3(sl)
        psd += _t3(s)
        rows += nh * comb(nv + 2 * d - 2, 2 * d - 2)
    per = comb(nv_max + 2 * d, 2 * d)
    exact = len(cliques) * per <= _MAX_ENUMERATE
    if exact:
        seen = set()
        for cv, _ in cliques:
            for deg in range(1, 2 * d + 1):
                seen.update(itertools.combinations_with_replacement(cv, deg))
        moments = len(seen)
    else:
        theta_only = comb(q + 2 * d, 2 * d)
        moments = len(cliques) * (per - theta_only) + theta_only - 1
    return MomentSize(order=d, n_cliques=len(cliques), clique_vars=nv_max,
                      psd_side=comb(nv_max + d, d), n_rows=int(rows), n_moments=int(moments),
                      moments_exact=exact,
                      est_seconds=_seconds(rows, psd, problem.p),
                      est_bytes=_bytes(rows, moments, psd), psd_work=psd,
                      basis="full" if d >= 2 else "sparse")


def check_work(name: str, value, default: float = MOMENT_MAX_WORK) -> float:
    """A size budget (estimated seconds of one core): a number > 0 (``inf`` allowed), else
    :class:`~hammerbound.exceptions.ParameterValidationError` naming the option."""
    if isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)) \
            and value > 0:  # (NaN fails "> 0")
        return float(value)
    raise ParameterValidationError(
        f"{name} must be a number > 0 (a budget on the estimated seconds, one core, of "
        f"building and solving the moment relaxation, default {default:g}; float('inf') "
        f"lifts it); got {value!r}.")


def solve_processes(n_jobs, p: int) -> int:
    """Worker processes :func:`.relaxation.moment_bounds` solves its ``2 p`` objectives on
    (each holds a copy of the relaxation): ``n_jobs``, at least one, at most one per
    objective."""
    return max(1, min(int(n_jobs), 2 * p))


def check_moment_budget(size: MomentSize, max_work: float | None = None,
                        warn_work: float | None = None, *, option: str = "max_work",
                        processes: int = 1, stacklevel: int = 3) -> None:
    """Refuse or warn when a relaxation of ``size`` exceeds the budgets.

    ``option`` is the name of the caller's option that sets ``max_work`` (the refusal names
    it, so a user knows what to raise); ``processes`` hold a copy each (the memory check).
    ``max_work=inf`` skips both refusals.

    Raises
    ------
    RelaxationTooLargeError
        ``size.work > max_work`` (default :data:`MOMENT_MAX_WORK`), or an estimated
        memory above the machine's (:func:`physical_memory`).
    """
    max_work = MOMENT_MAX_WORK if max_work is None else max_work
    warn_work = MOMENT_WARN_WORK if warn_work is None else warn_work
    alternatives = ("Use method='lp' (polytopic outer bounds, seconds) or method='exact' "
                    "(tight bounds; bound its time with total_time_limit), a shorter record, "
                    "or a lower relaxation_order.")
    ram = physical_memory()
    need = size.est_bytes * max(1, int(processes))
    # the memory first: a time budget raised would not make it fit (seen: N = 2000, 9 %
    # over the time budget and 14x the machine's memory, refused naming only the time)
    if ram is not None and need > ram and max_work != float("inf"):
        on = f" in each of {int(processes)} processes" if processes > 1 else ""
        over = (f" (and above the time budget of {max_work:g} s)"
                if size.work > max_work else "")
        raise RelaxationTooLargeError(
            f"the moment relaxation is too large: {size.describe()}{on}, more than this "
            f"machine's {ram / 2**20:.0f} MB of memory{over} ({option}=inf builds it "
            "anyway). " + alternatives)
    if size.work > max_work:
        raise RelaxationTooLargeError(
            f"the moment relaxation is too large: {size.describe()}, above the budget of "
            f"{max_work:g} s ({option}; raise it to build anyway). " + alternatives)
    if size.work > warn_work:
        warnings.warn(
            f"large moment relaxation: {size.describe()}. method='lp' or method='exact' "
            "(with total_time_limit) may be faster.", RuntimeWarning, stacklevel=stacklevel)


#: Memory limits of a container (cgroup v2, then v1), read by :func:`physical_memory`.
CGROUP_LIMITS = ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes")


def physical_memory() -> float | None:
    """Bytes of memory this process may use: the machine's physical memory, or a smaller
    memory limit of its container (:data:`CGROUP_LIMITS`); None where neither is known."""
    try:
        ram = float(os.sysconf("SC_PAGE_SIZE")) * float(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        ram = None
    for path in CGROUP_LIMITS:
        try:
            with open(path) as fh:
                text = fh.read().strip()
        except OSError:
            continue
        if text.isdigit() and 0 < int(text) < (ram if ram is not None else float("inf")):
            ram = float(text)
    return ram
