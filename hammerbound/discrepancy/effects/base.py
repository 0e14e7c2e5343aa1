"""The candidate-effect interface (see the package docstring of :mod:`.effects`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._compat import warn_renamed

__all__ = ["Context", "Effect", "Param"]


@dataclass(frozen=True)
class Param:
    """One searched (nonlinear) parameter of an effect.

    Attributes
    ----------
    name : str
        Short name shown in reports (``c``, ``w``, ``s``, ``d``, ``p``).
    lo, hi : float
        Search range (absolute units; use :class:`Context` to scale with the data).
    log : bool
        Grid spaced logarithmically (``lo > 0``).
    integer : bool
        Integer parameter: every integer in ``[lo, hi]`` is tried (exhaustive search).
    """

    name: str
    lo: float
    hi: float
    log: bool = False
    integer: bool = False

    def grid(self, size: int) -> np.ndarray:
        """Initial grid of ``size`` points (all integers for an integer parameter)."""
        if self.integer:
            return np.arange(int(round(self.lo)), int(round(self.hi)) + 1, dtype=float)
        if self.log:
            return np.geomspace(self.lo, self.hi, size)
        return np.linspace(self.lo, self.hi, size)


@dataclass(frozen=True)
class Context:
    """What an effect may use to set its search ranges.

    Attributes
    ----------
    u_max : float
        ``max |u|`` (scored samples and before).
    y_max : float
        ``max |y|``.
    n : int
        Number of samples.
    max_delay : int
        Largest extra delay the user allows.
    output_bound : float
    """

    u_max: float
    y_max: float
    n: int
    max_delay: int
    output_bound: float

    @property
    def noise_bound(self) -> float:
        """Deprecated name of :attr:`output_bound` (removed in 0.3.0)."""
        warn_renamed("Context.noise_bound", "Context.output_bound")
        return self.output_bound


class Effect:
    """Base class of a candidate effect: override only the hooks the effect uses.

    The model class after adding effects ``E1 .. Ek`` to a model ``G`` (input
    nonlinearity chain ``N0``, linear block ``B/A``, output offset) is::

        yhat = OUT( W * ([B/A] F(q^-1) IN_k(...IN_1(N0(u))) + sum_j coef_j col_j) )

    where ``IN_i`` are :meth:`transform_input`, ``F`` the product of the
    :meth:`series_filter` of every effect, ``col_j`` the :meth:`output_columns` (their
    coefficients are fitted by the linear program, like ``B``), ``W`` the product of the
    :meth:`output_gain` of every effect (time-varying gains, exact in the LP) and ``OUT`` the
    :meth:`transform_output` of every effect. The searched parameters ``theta`` (one
    value per :attr:`params` entry) are found by a grid search with local refinement
    (override :meth:`search_space` / :meth:`initial_grid` to change it).
    """

    #: Candidate name (registry key, shown in reports).
    name: str = ""
    #: Searched (nonlinear) parameters, see :meth:`search_space` (names only).
    param_names: tuple = ()
    #: Names of the parameters fitted as linear-program coefficients (:meth:`output_columns`).
    linear_names: tuple = ()
    #: One-line description (docs and summary).
    description: str = ""
    #: True when :meth:`transform_input` is used (input-side effect; hints use it).
    acts_on_input: bool = False
    #: Tried when ``diagnose(candidates=None)``; False: only when named (or ``"all"``).
    default: bool = True
    #: Candidates whose fitted parameters give this one starting points (:meth:`seeds`);
    #: a diagnosis fits those first when both are tried.
    seeded_by: tuple = ()
    #: True for a delay: after the fit the leading refitted coefficients of the numerator
    #: are pinned to zero one by one while the data stay consistent (the delay the data need).
    pins_leading: bool = False

    @property
    def n_params(self) -> int:
        """Number of parameters the effect adds to the model class."""
        return len(self.param_names) + len(self.linear_names)

    # ------------------------------------------------------------------ search
    def search_space(self, ctx: Context) -> tuple:
        """Search ranges of the searched parameters: a tuple of :class:`Param`."""
        return ()

    def seeds(self, fitted: dict) -> list:
        """Starting points (parameter tuples) from ``fitted``: the parameters found for
        the candidates of :attr:`seeded_by` that were fitted (name -> tuple)."""
        return []

    def initial_grid(self, ctx: Context, size: int) -> list:
        """Starting points of the search: a list of parameter tuples (default: the
        cartesian product of the :class:`Param` grids)."""
        import itertools

        grids = [p.grid(size) for p in self.search_space(ctx)]
        return [tuple(float(v) for v in pt) for pt in itertools.product(*grids)]

    # ------------------------------------------------------------------ model hooks
    def transform_input(self, x: np.ndarray, theta: tuple) -> np.ndarray:
        """Signal after the effect, for the signal ``x`` entering it (input side)."""
        return x

    def series_filter(self, theta: tuple):
        """``(num, den)`` in powers of ``q^-1`` put in series with the linear block, or None."""
        return None

    def output_columns(self, n: int, theta: tuple) -> np.ndarray | None:
        """``(n, len(linear_names))`` columns added to the output, or None."""
        return None

    def output_gain(self, n: int, theta: tuple) -> np.ndarray | None:
        """A time-varying gain ``w_t`` (shape ``(n,)``) multiplying the model output, or None.

        The fit multiplies the rows of its linear program by ``w``, so the refitted
        coefficients stay exact (a gain drift). An effect that defines it must also define
        :meth:`transform_output` as ``yhat * output_gain(yhat.size, theta)`` (used by
        :meth:`RefinedModel.predict`); output gains act before the other output maps.
        """
        return None

    def transform_output(self, yhat: np.ndarray, theta: tuple) -> np.ndarray:
        """Output after the effect (nonlinear sensor effects)."""
        return yhat

    def one_sided(self, y: np.ndarray, theta: tuple, output_bound: float) -> np.ndarray | None:
        """For output effects that clip: ``+1`` where only ``yhat_t >= y_t - e`` is required
        before :meth:`transform_output` (the clipped sample may be exceeded), ``-1`` where
        only ``yhat_t <= y_t + e``, ``0`` elsewhere; None: two-sided everywhere.
        ``output_bound`` is the bound ``Delta`` of the diagnosis (a clipped reading lies
        within it of the limit). The achieved error is always recomputed from the full
        model, so a wrong choice here can only make the fit worse, never the reported
        error wrong."""
        return None

    # ------------------------------------------------------------------ reporting
    def value(self, theta: tuple, coefs: tuple, model=None):
        """Value reported as ``CandidateFit.value`` (one number for one-parameter effects).

        ``model`` is the refined model (:class:`~hammerbound.discrepancy.RefinedModel`) the
        effect is part of, for values in the model's convention (the total delay, slopes
        scaled by the linear block's static gain); None when not known."""
        vals = tuple(theta) + tuple(coefs)
        return float(vals[0]) if len(vals) == 1 else vals

    def value_note(self, model=None) -> str:
        """Words after the fitted value in a verdict (e.g. what a delay's ``d`` counts in
        ``model``, the refined model)."""
        return ""

    def param_label(self) -> str:
        """Parameter name(s) shown in reports."""
        return ",".join((*self.param_names, *self.linear_names))

    def __repr__(self) -> str:
        return f"<effect {self.name}>"
