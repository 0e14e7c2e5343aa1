"""Stage 1: guaranteed bounds on the backlash parameters (section 22.3).

:class:`BacklashSetEstimator` takes steady-state samples of square-wave experiments
(positive input -> right line, negative input -> left line) and computes the *exact*
feasible set of each side, its tight orthotope (22.22)-(22.24), and the exact bounds on
the inner PRBS levels (22.25)-(22.30).
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted

from .._compat import DEPRECATED, renamed_value
from ..data.gain_sign import negative_gain_hint, steady_slope
from ..data.validation import as_bound, as_flag, as_real, check_scale
from ..exceptions import (
    DataValidationError,
    EmptyFeasibleSetError,
    NotEnoughAmplitudesError,
    ParameterValidationError,
    ResultOneViolationError,
    UnboundedSetError,
)
from ..results import IntervalSet
from ..systems.models import GAMMA_NAMES
from .feasible_set import Edge, PolygonFeasibleSet
from .inner_signal import InnerSignalBounds
from .side_polygon import SideProblem
from .smallest_bound import smallest_bound_factor, smallest_bound_text

__all__ = ["BacklashSetEstimator", "InnerSignalBounds"]  # InnerSignalBounds: from .inner_signal

_SIDES = ("left", "right")


def _first_nonfinite_point(X, y) -> None:
    """Refuse a NaN or infinite steady-state point, naming it and the fix (the points are
    independent, unlike a record's samples: dropping one is safe). Only plain numeric
    arrays of one or two dimensions are checked here; anything else (strings, sparse,
    3-D) is left to scikit-learn's validation and its own message."""
    import scipy.sparse as sp

    for name, v in (("X (steady-state inputs)", X), ("y (steady-state outputs)", y)):
        if sp.issparse(v):
            continue
        try:
            a = np.asarray(v)
        except (TypeError, ValueError):
            continue
        if a.dtype.kind not in "fiu" or a.ndim not in (1, 2) or a.size == 0:
            continue
        bad = np.flatnonzero(~np.isfinite(a.reshape(a.shape[0], -1)).all(axis=1))
        if bad.size:
            raise DataValidationError(
                f"{name} contains NaN or infinity at point {int(bad[0])} ({bad.size} point(s) "
                "in all). The steady-state points are independent: drop those points from "
                "both X and y.")


class BacklashSetEstimator(RegressorMixin, BaseEstimator):
    """Guaranteed backlash parameter bounds from steady-state data (stage 1, section 22.3).

    Parameters
    ----------
    output_bound : float or array-like of shape (n_samples,), required
        Bound ``|eta| <= output_bound`` (``Delta eta``, 22.5) on the errors of the measured
        steady-state outputs; scalar or one per sample, > 0. The guarantee rests on it, so
        it has no default: ``None`` (the constructor default, for scikit-learn) makes
        :meth:`fit` raise :class:`~hammerbound.exceptions.ParameterValidationError`.
    method : {"polygon", "algorithm"}, default="polygon"
        ``"polygon"``: exact half-plane intersection in ``(m, beta = m c)`` coordinates,
        O(M log M). ``"algorithm"``: the chapter's Algorithm 22.1 (O(M^2)), same set.
    well_posed_on_data : bool, default=True
        Use the fact that the square-wave experiment itself drove the system up to
        ``+U_R`` and ``-U_L``: (22.1) can only have produced those data if it is well posed
        there, so every backlash that explains the data keeps a PRBS level
        ``u* <= min(U_R, U_L)`` before the crossing of its lines. Without it, Result 1 is
        checked against the crossing of *every* parameter in the feasible sets, which is
        far more conservative when ``m_l`` and ``m_r`` are uncertain (large noise).
    noise_bound : deprecated
        Old name of ``output_bound`` (removed in 0.3.0).

    Attributes
    ----------
    left_, right_ : PolygonFeasibleSet
        Exact feasible sets (22.13) and (22.12) with vertices, edges and orthotope.
    gamma_bounds_ : ndarray of shape (4, 2)
        Tight intervals (22.24) of ``[m_l, c_l, m_r, c_r]``.
    gamma_center_, gamma_radius_ : ndarray of shape (4,)
        Central estimate and uncertainty bound (22.23).
    intervals_ : IntervalSet
        The tight intervals (22.24) as an :class:`~hammerbound.results.IntervalSet` over
        ``("ml", "cl", "mr", "cr")``: table, ``contains``, ``to_dict``, ``plot``.
    crossed_on_data_ : float or None
        The input at which the steady-state points lie past the crossing of the lines of
        every feasible backlash (warned at the fit; they then do not show (22.1) well
        posed there), or None.
    output_bound_ : ndarray of shape (n_samples,)
        The output error bound of every steady-state sample the sets rest on.
    n_features_in_ : int
        Always 1.

    Notes
    -----
    ``X`` holds the steady-state input values, positive for the right line (22.9) and
    negative for the left line (22.10); ``y`` the measured steady-state outputs. The
    steady-state gain of the linear block is one (22.8).
    """

    def __init__(self, output_bound=None, *, method="polygon", well_posed_on_data=True,
                 noise_bound=DEPRECATED):
        self.output_bound = output_bound
        self.method = method
        self.well_posed_on_data = well_posed_on_data
        self.noise_bound = noise_bound

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.one_d_array = True
        return tags

    # ------------------------------------------------------------------ validation
    def _validate(self, X, y):
        if self.method not in ("polygon", "algorithm"):
            raise ParameterValidationError(
                f"method must be 'polygon' or 'algorithm'; got {self.method!r}."
            )
        as_flag("well_posed_on_data", self.well_posed_on_data)
        import scipy.sparse as sp
        from sklearn.utils.validation import validate_data

        if (not sp.issparse(X) and _is_complex(X)) or _is_complex(y):
            raise DataValidationError(
                "Complex data not supported: X (steady-state inputs) and y (outputs) must be "
                "real numbers; pass np.real(...) if the imaginary parts are zero."
            )
        if not sp.issparse(X) and np.ndim(X) == 1:
            X = np.reshape(np.asarray(X, dtype=object if _is_complex(X) else None), (-1, 1))
        _first_nonfinite_point(X, y)
        try:
            X, y = validate_data(self, X, y, dtype="numeric", y_numeric=True)
        except (TypeError, ValueError) as exc:  # re-raise as our typed error, message kept
            raise DataValidationError(
                f"{exc} (X: signed steady-state inputs of shape (n_samples,) or (n_samples, 1); "
                "y: outputs of shape (n_samples,))"
            ) from exc
        if X.shape[1] != 1:
            raise DataValidationError(
                f"X must have shape (n_samples,) or (n_samples, 1); got {X.shape}. "
                "Reshape your data with X.reshape(-1, 1)."
            )
        X = X[:, 0].astype(float)
        y = np.asarray(y, dtype=float)
        bound = renamed_value("BacklashSetEstimator", "output_bound", self.output_bound,
                              "noise_bound", self.noise_bound, stacklevel=4)
        if bound is None:
            raise ParameterValidationError(
                "BacklashSetEstimator: output_bound is not set. The backlash bounds rest on "
                "the bound |eta| <= output_bound of the steady-state output errors (22.5), "
                "so it has no default: pass BacklashSetEstimator(output_bound=0.05) (your "
                "sensor's error bound; the first argument).")
        deta = as_bound("output_bound", bound, X.shape[0],
                        shape_error=ParameterValidationError)
        if np.any(X == 0):
            raise DataValidationError(
                f"X[{int(np.flatnonzero(X == 0)[0])}] = 0: steady-state inputs must be non-zero "
                "(positive for the right line, negative for the left line)."
            )
        check_scale("BacklashSetEstimator.fit", {"y": y, "X": X}, {"output_bound": deta},
                    slope=("y", "X"),
                    hint=" (the slopes m are unchanged; multiply the bounds on c_l, c_r by s)")
        return X, y, deta

    # ------------------------------------------------------------------ fit
    def fit(self, X, y):
        """Compute the exact feasible sets of both sides.

        Parameters
        ----------
        X : array-like of shape (n_samples,) or (n_samples, 1)
            Signed steady-state inputs ``u_s``.
        y : array-like of shape (n_samples,)
            Measured steady-state outputs ``y_s``.

        Returns
        -------
        self
        """
        X, y, deta = self._validate(X, y)
        self.n_features_in_ = 1
        sets = {}
        for side in _SIDES:
            mask = X > 0 if side == "right" else X < 0
            idx = np.flatnonzero(mask)
            sets[side] = self._fit_side(side, X[idx], y[idx], deta[idx], idx)
        self.left_, self.right_ = sets["left"], sets["right"]
        self.output_bound_ = deta
        self.smallest_bound_factor_ = smallest_bound_factor(X, y, deta)
        self.input_range_ = (float(X.min()), float(X.max()))
        self.crossed_on_data_ = self._crossed_on_data()
        self.intervals_ = IntervalSet(GAMMA_NAMES, np.vstack(
            [self.left_.orthotope, self.right_.orthotope]), method=self.method)
        self.gamma_bounds_ = np.array(self.intervals_.bounds)
        self.gamma_center_ = self.intervals_.center
        self.gamma_radius_ = self.intervals_.radius
        return self

    def _crossed_on_data(self) -> float | None:
        """The input the steady-state points reached past the crossing of the two lines of
        *every* backlash that explains them (None when some feasible backlash is well
        posed at both tested amplitudes), with a :class:`DataWarning`. Such points do not
        show (22.1) well posed up to the amplitudes tested (new-user trial 19: square
        waves to +-3.5 of lines that cross at 1.95 got u* = 2.73 suggested, where the
        package's own simulator refuses the central backlash)."""
        lo, hi = self.input_range_
        past = [u for u in (hi, lo) if u != 0.0 and self.crossed_for_every(u)]
        if not past:
            return None
        import warnings

        from ..exceptions import DataWarning

        warnings.warn(
            f"the steady-state points reach u = {past[0]:.4g}, past the crossing of the two "
            "lines of every backlash that explains them (m_l (u + c_l) < m_r (u - c_r) "
            "there for all of them), where model (22.1) is not well posed: the plant's "
            "backlash does not act as (22.1) there. Each side's points still lie on one "
            "line, whose intervals hold; a PRBS level past the crossing takes its inner "
            "values on those lines (as the square waves showed them), which the two-stage "
            "assumptions then state. suggest_prbs_level() stays before the crossing, and "
            "the central model cannot be simulated past it.", DataWarning, stacklevel=3)
        return float(past[0])

    def _fit_side(self, side, u, y, deta, idx):
        sigma = -1.0 if side == "right" else 1.0
        if np.unique(u).size < 2:
            raise NotEnoughAmplitudesError(
                f"the {side} side has {np.unique(u).size} distinct input amplitude(s); the "
                "feasible set is unbounded with fewer than two (Remark 22.2). Add square waves "
                f"with at least two different {'positive' if side == 'right' else 'negative'} "
                f"amplitudes (the {side} line is seen at u "
                f"{'> 0' if side == 'right' else '< 0'})."
            )
        # the measured slabs relaxed outward by the tolerance policy, in centred and scaled
        # coordinates; "empty" only with an exact certificate (docs/tolerances.md)
        problem = SideProblem(side, u, y, deta, idx)
        res = problem.solve(self.method)
        if res is None:
            raise self._empty_error(side, problem)
        return _make_polygon_set(side, sigma, res.verts_mb, res.edge_cons, res.constraints,
                                 method=self.method, tolerance_factor=res.factor,
                                 max_tolerance=float(res.factor * problem.tol.max()))

    def _empty_error(self, side, problem):
        # the smallest prefix (in the caller's order) whose relaxed set is certified empty
        lo, hi = 1, problem.u.size - 1
        cert = problem.certificate()
        while lo < hi:
            mid = (lo + hi) // 2
            sel = slice(0, mid + 1)
            c = problem.certificate(sel) if problem.filtered_polygon(sel)[0] is None else None
            if c is not None:
                hi, cert = mid, c
            else:
                lo = mid + 1
        k = int(problem.idx[lo])
        which = ", ".join(cert[0]) if cert is not None else "?"
        return EmptyFeasibleSetError(
            f"no backlash parameters (m, c) > 0 explain the {side}-side steady-state data within "
            f"the output bound: the set becomes empty at measurement index {k} "
            f"(u = {problem.u[lo]:.4g}). Check that sample, output_bound (too small?), that "
            "the data are at steady state, that every amplitude takes the input past the "
            "dead band (a square wave inside it leaves the state where it was, off the "
            "lines: drop the smallest amplitudes) and that the input and output columns are "
            "not swapped. "
            f"(Certified in exact arithmetic by the constraints {which}, with the tolerance "
            "of docs/tolerances.md.)"
            + _sign_hint(problem.u, problem.y),
            side=side, first_index=k,
        )

    # ------------------------------------------------------------------ results
    @property
    def feasible_sets_(self) -> dict:
        check_is_fitted(self, "left_")
        return {"left": self.left_, "right": self.right_}

    def admissible_prbs_range(self) -> tuple[float, float]:
        """Open interval ``(u_lo, u_hi)`` of PRBS levels that satisfy Result 1 for *every*
        feasible backlash.

        ``u* > u_lo = max(c_l^max, c_r^max)`` puts both levels outside the dead zone, and
        ``u* < u_hi`` keeps both levels before the crossing of the two lines for every
        feasible parameter: ``|m_r - m_l| u* < m_l c_l + m_r c_r``, i.e.
        ``max_R (m_r u - b_r) + max_L (-m_l u - b_l) < 0`` and the mirrored condition; both
        maxima sit at vertices (linear in ``(m, beta)``), so the range is exact.
        With ``well_posed_on_data`` the upper end is at least ``min(U_R, U_L)``, the range
        over which the experiment showed each side's line (past the crossing of every
        feasible backlash, ``crossed_on_data_``, the fit warns: (22.1) is then not well
        posed there, and the levels rest on the lines the square waves showed).
        """
        return self._admissible(*self._limits())

    def _limits(self) -> tuple[float, float]:
        """``(u_lo, crossing)``: the dead zone's largest edge and :meth:`crossing_limit`
        (one search of the crossing for both)."""
        check_is_fitted(self, "left_")
        u_lo = max(self.left_.orthotope[1, 1], self.right_.orthotope[1, 1])
        return u_lo, float(self._geometric_prbs_range(u_lo)[1])

    def _tested(self) -> float:
        """The largest amplitude the steady-state data reached on both sides."""
        return float(min(-self.input_range_[0], self.input_range_[1]))

    def _admissible(self, u_lo, crossing) -> tuple[float, float]:
        """:meth:`admissible_prbs_range` from :meth:`_limits`."""
        u_data = self._tested() if self.well_posed_on_data else 0.0
        if u_data > crossing:
            # closed at u_data: the data show (22.1) well posed *at* +-U (strictly)
            return (u_lo, float(np.nextafter(u_data, np.inf)))
        return (u_lo, crossing)

    def crossed_for_every(self, u) -> bool:
        """Whether at input ``u`` the lines of *every* feasible backlash have crossed
        (``m_l (u + c_l) < m_r (u - c_r)`` for all: the minimum of ``R(u) - L(u)`` over the
        two polygons, at their vertices, is positive)."""
        check_is_fitted(self, "left_")
        L, R = self.left_.vertices_mb, self.right_.vertices_mb
        u = float(u)
        return bool(np.min(R[:, 0] * u - R[:, 1]) + np.min(-L[:, 0] * u - L[:, 1]) > 0.0)

    def crossing_limit(self) -> float:
        """The smallest PRBS level at which the two lines of some feasible backlash cross
        (``inf`` when none do): below it Result 1 holds for every feasible backlash on
        geometry alone, without ``well_posed_on_data``."""
        return self._limits()[1]

    def _geometric_prbs_range(self, u_lo):
        L, R = self.left_.vertices_mb, self.right_.vertices_mb

        def worst(u):
            f1 = np.max(R[:, 0] * u - R[:, 1]) + np.max(-L[:, 0] * u - L[:, 1])
            f2 = np.max(L[:, 0] * u - L[:, 1]) + np.max(-R[:, 0] * u - R[:, 1])
            return max(f1, f2)

        # worst(u) is convex piecewise linear with worst(0) < 0: find its root
        if worst(0.0) >= 0:
            return (u_lo, u_lo)
        hi = max(1.0, 2 * u_lo)
        while worst(hi) < 0 and hi < 1e12:
            hi *= 2
        if worst(hi) < 0:
            return (u_lo, np.inf)
        lo = 0.0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if worst(mid) < 0:
                lo = mid
            else:
                hi = mid
        return (u_lo, lo)

    def check_prbs_level(self, u_star: float) -> None:
        """Raise :class:`ResultOneViolationError` unless ``u*`` satisfies Result 1 for every
        feasible backlash (outside the dead zone, before the line crossing)."""
        u_star = as_real("u_star", u_star, positive=True, example="1.0")
        u_lo, u_hi = self.admissible_prbs_range()
        if u_star <= u_lo:
            raise ResultOneViolationError(
                f"u* = {u_star:g} is inside the dead zone: Result 1 needs u* > max(c_l^max, "
                f"c_r^max) = {u_lo:.6g}. Choose u* in ({u_lo:.6g}, {u_hi:.6g}), e.g. "
                "with suggest_prbs_level()."
            )
        if u_star >= u_hi:
            raise ResultOneViolationError(
                f"u* = {u_star:g} reaches the crossing of the backlash lines for some feasible "
                f"parameters (ill-posed (22.1), three inner levels instead of two). Choose u* "
                f"in ({u_lo:.6g}, {u_hi:.6g}), e.g. with suggest_prbs_level()."
            )

    def suggest_prbs_level(self, margin: float = 0.25) -> float:
        """A PRBS level inside the admissible range and the tested amplitudes:
        ``top - margin (top - u_lo)`` with ``top = min(u_hi, U)``, ``U`` the largest
        amplitude the steady-state data reached on both sides (the lines are known only
        where the experiment tested them: new-user trial 17 was suggested 9.64 V for a
        valve tested to +-5 V, from the lines' crossing); a
        :class:`~hammerbound.exceptions.DataWarning` when no admissible level lies within
        them (``U <= u_lo``: the level then extrapolates the lines). ``top`` is also kept
        below :meth:`crossing_limit` when that leaves room above ``u_lo``: a level past the
        crossing of some feasible backlash rests on ``well_posed_on_data``. With an unbounded range
        (``m_l == m_r`` can be excluded on neither side, and ``U`` does not cap it) it
        returns ``(1 + margin) * 10 * u_lo``.
        """
        margin = as_real("margin", margin, lo=0.0, hi=1.0, example="0.25")
        u_lo, crossing = self._limits()
        u_lo, u_hi = self._admissible(u_lo, crossing)
        if u_hi <= u_lo:
            raise ResultOneViolationError(
                "no PRBS level satisfies Result 1 for every feasible backlash: the dead zone "
                "and the line crossing overlap. Reduce the noise or add steady-state data."
            )
        tested = self._tested()
        top = min(u_hi, tested) if tested > u_lo else u_hi
        if u_lo < crossing < top:  # before every feasible crossing when there is room
            top = crossing  # (trial 19: past it the central model cannot be simulated)
        if tested <= u_lo:  # review 49: this fell back to the old rule without a word
            import warnings

            from ..exceptions import DataWarning

            warnings.warn(
                f"the steady-state data reach only |u| = {tested:.4g} on one side, not past "
                f"the dead band's largest edge {u_lo:.4g}: no admissible level lies within the "
                "tested amplitudes, and the one suggested extrapolates the backlash lines. "
                "Test larger amplitudes on both sides first.", DataWarning, stacklevel=2)
        if not np.isfinite(top):
            return float((1 + margin) * 10 * u_lo)
        return float(top - margin * (top - u_lo))

    def inner_signal_bounds(self, u_star: float) -> InnerSignalBounds:
        """Exact bounds (22.25)-(22.26) on the inner PRBS levels, after checking Result 1."""
        self.check_prbs_level(u_star)
        x_hi = self.right_.linear_range(u_star, -1.0)  # m_r u* - beta_r
        x_lo = self.left_.linear_range(-u_star, 1.0)  # -m_l u* + beta_l
        slope_max = float(max(self.left_.orthotope[0, 1], self.right_.orthotope[0, 1]))
        return InnerSignalBounds(float(u_star), x_hi, x_lo, slope_max)

    def inner_signal(self, u, u_star: float | None = None):
        """Central inner signal and radius ``(x^c, Delta x)`` for a PRBS ``u`` (22.31)-(22.33)."""
        check_is_fitted(self, "left_")
        u = np.ravel(np.asarray(u, dtype=float))
        if u_star is None:
            u_star = float(np.max(np.abs(u)))
        return self.inner_signal_bounds(u_star).transform(u)

    def predict(self, X):
        """Central steady-state output: ``m_r^c (u - c_r^c)`` for u > 0, ``m_l^c (u + c_l^c)`` else."""
        check_is_fitted(self, "left_")
        X = _column(X, "X")
        ml, cl, mr, cr = self.gamma_center_
        return np.where(X > 0, mr * (X - cr), ml * (X + cl))

    def to_frame(self):
        """The tight intervals of ``ml, cl, mr, cr`` as a table (pandas DataFrame when pandas
        is installed, else a numpy structured array): parameter, lower, centre, upper,
        half_width, status."""
        check_is_fitted(self, "left_")
        return self.intervals_.to_frame()

    def summary(self) -> str:
        """Text summary: the exact feasible sets and the tight intervals (22.24)."""
        check_is_fitted(self, "left_")
        from ..tables import bound_text

        head = (f"BacklashSetEstimator: exact feasible sets, left {len(self.left_.vertices)} "
                f"and right {len(self.right_.vertices)} vertices, inputs in "
                f"[{self.input_range_[0]:g}, {self.input_range_[1]:g}]")
        return self.intervals_.summary(title=head, assumptions=(
            f"output error bound |eta| <= {bound_text(self.output_bound_)}"
            + smallest_bound_text(self.smallest_bound_factor_, self.output_bound_),
            "the steady-state samples are settled (a transient left adds to their errors)",
            "unit steady-state gain of the linear block (22.8), no output offset (subtract "
            "a sensor offset first)"))

    # ------------------------------------------------------------------ model set (issue 16)
    def sample(self, n, random_state=None):
        """``n`` backlashes ``(m_l, c_l, m_r, c_r)`` from the exact feasible polygons.

        Uniform in ``(m, beta = m c)`` on each side (the sides are independent); each
        sample is checked against every half-plane of its polygon. Returns
        :class:`~hammerbound.modelset.BacklashSamples`.
        """
        check_is_fitted(self, "left_")
        from ..modelset.sampling import sample_backlash

        return sample_backlash(self.left_, self.right_, n, random_state=random_state)

    def inverse(self, v_range=None, x0=0.0):
        """Backlash-inverse compensator from the central estimate, with a guaranteed error.

        The classic right-inverse (rise: ``u = v/m_r + c_r``, fall: ``u = v/m_l - c_l``)
        plus :meth:`~hammerbound.modelset.BacklashInverse.error_bounds`, the band of the
        residual ``x - v`` valid for every backlash of the feasible set and every command
        sequence in ``v_range`` (default: the inner-signal range of the experiment).

        Raises
        ------
        IllPosedBacklashError
            The compensator would drive some feasible backlash past its line crossing.
        """
        check_is_fitted(self, "left_")
        from ..modelset.compensation import build_inverse

        return build_inverse(self, v_range=v_range, x0=x0)


def _sign_hint(u, y) -> str:
    """' ' + the hint of a reverse-acting plant when the side's outputs fall as its inputs
    rise (least-squares slope), else ''."""
    hint = negative_gain_hint(steady_slope(u, y), "steady-state slope (output against input)")
    return " " + hint if hint else ""


def _is_complex(X):
    try:
        return np.iscomplexobj(np.asarray(X))
    except (TypeError, ValueError):
        return False


def _column(X, name):
    try:
        X = np.asarray(X, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DataValidationError(f"{name} must be numeric.") from exc
    if X.ndim == 2 and X.shape[1] == 1:
        X = X[:, 0]
    if X.ndim != 1:
        raise DataValidationError(
            f"{name} must have shape (n_samples,) or (n_samples, 1); got {X.shape}. "
            "Reshape your data with X.reshape(-1, 1)."
        )
    if X.shape[0] == 0:
        raise DataValidationError(f"{name} is empty: pass the steady-state samples.")
    if not np.all(np.isfinite(X)):
        raise DataValidationError(
            f"{name} contains NaN or inf (first at index {int(np.flatnonzero(~np.isfinite(X))[0])})."
        )
    return X


def _counter_clockwise(verts, edge_cons):
    """The vertices counter-clockwise in ``(m, beta)`` with edge ``k`` from vertex ``k`` to
    ``k + 1``: the right side's polygon is computed in coordinates with ``-beta``, which
    reverses its orientation."""
    n = len(verts)
    x, y = verts[:, 0], verts[:, 1]
    if n < 3 or np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) >= 0:
        return verts, edge_cons
    return verts[::-1].copy(), [edge_cons[(n - 2 - j) % n] for j in range(n)]


def _make_polygon_set(side, sigma, verts_mb, edge_cons, cons, **fields) -> PolygonFeasibleSet:
    n = len(verts_mb)
    verts_mb, edge_cons = _counter_clockwise(np.asarray(verts_mb, dtype=float), list(edge_cons))
    edges = tuple(Edge(edge_cons[k], verts_mb[k], verts_mb[(k + 1) % n]) for k in range(n))
    m, beta = verts_mb[:, 0], verts_mb[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(m > 0, beta / m, np.inf)
    if not np.all(np.isfinite(c)):
        raise UnboundedSetError(
            f"the {side} feasible set touches m = 0, so c is unbounded; add square waves with "
            "larger amplitudes or reduce output_bound if justified."
        )
    orth = np.array([[m.min(), m.max()], [c.min(), c.max()]])
    names = ("ml", "cl") if side == "left" else ("mr", "cr")
    return PolygonFeasibleSet(
        param_names=names, orthotope=orth, exact=True, vertices=np.column_stack([m, c]),
        edges=edges, side=side, sigma=sigma, vertices_mb=np.asarray(verts_mb),
        constraints=tuple(k for k in cons if k.sign != "box"), **fields,
    )
