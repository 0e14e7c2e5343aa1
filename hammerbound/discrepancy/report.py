"""Results of the diagnosis: evidence per candidate, localisation, and the report."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .._compat import warn_renamed
from ..results import Result, jsonable, warn_plot_path

if TYPE_CHECKING:
    from .model import RefinedModel

__all__ = ["CandidateFit", "CombinationFit", "ConditionEvidence", "DiagnosisReport",
           "Disagreement"]


@dataclass(frozen=True)
class CandidateFit:
    """Evidence for one candidate effect.

    Attributes
    ----------
    name : str
        Candidate name (see :data:`CANDIDATES`).
    n_params : int
        Parameters the candidate adds to the model class.
    param_name : str
        Name of the added parameter (``c``, ``w``, ``s``, ``d``, ``o``, ``p``).
    value : float
        Fitted parameter value (the one with the smallest minimax error).
    minimax_error : float
        Achieved ``max_t |y_t - yhat_t|`` of the refitted augmented model: the smallest
        output bound under which the data are consistent with it (up to the search).
    lower_bound : float
        Rigorous lower bound of the minimax error *at* ``value`` (for ``offset`` and
        ``delay`` - searched exhaustively - a bound over the whole candidate class).
    consistent : bool
        ``minimax_error <= output_bound`` (every residual within the noise band, relaxed
        outward by the tolerance policy: ``1e-9 (|y_t| + |yhat_t| + output_bound)``).
    fraction_outside : float
        Fraction of samples whose residual exceeds the output bound after the refit.
    improvement : float
        ``gap_before / minimax_error`` (``> 1`` means the candidate shrinks the gap).
    exhaustive : bool
        True when the parameter was searched exhaustively (``offset``: LP; ``delay``:
        all integers up to ``max_delay``), so ``lower_bound`` covers the candidate class.
    n_evaluations : int
        Number of minimax LPs solved for this candidate.
    gap_fraction_removed : float
        ``(gap_before - minimax_error) / (gap_before - output_bound)`` clipped to [0, 1]:
        the share of the gap above the output bound that the candidate removes (0 when the
        model is already consistent).
    model : RefinedModel or None
        The model refitted with this candidate added (its parameters at ``value``). When no
        candidate alone explains the data, ``diagnose(report.candidate(name).model, ...)``
        continues from it, one effect at a time (``max_effects=1``).
    """

    name: str
    n_params: int
    param_name: str
    value: float
    minimax_error: float
    lower_bound: float
    consistent: bool
    fraction_outside: float
    improvement: float
    exhaustive: bool
    n_evaluations: int
    gap_fraction_removed: float = 0.0
    model: RefinedModel | None = field(default=None, repr=False, compare=False)


@dataclass(frozen=True)
class CombinationFit:
    """Evidence for a combination of effects fitted jointly (pairs, triples).

    Attributes
    ----------
    name : str
        The added effects joined by ``+`` (e.g. ``backlash+delay``).
    effects : tuple of str
        Every effect of the fitted class (effects already in a :class:`RefinedModel`
        first: they are refitted too).
    values : tuple
        Fitted parameter of each effect.
    minimax_error : float
        Achieved ``max_t |y_t - yhat_t|`` of the jointly refitted model.
    consistent : bool
    gap_fraction_removed : float
        ``(gap_before - minimax_error) / (gap_before - output_bound)`` clipped to [0, 1].
    n_evaluations : int
        Minimax LPs solved for this combination.
    seconds : float
        Time spent on it.
    """

    name: str
    effects: tuple
    values: tuple
    minimax_error: float
    consistent: bool
    gap_fraction_removed: float
    n_evaluations: int
    seconds: float


@dataclass(frozen=True)
class ConditionEvidence:
    """Where the out-of-band samples fall, for one operating condition.

    Attributes
    ----------
    name : str
        ``after_reversal``, ``after_input_change``, ``steady_state``,
        ``large_amplitude`` or ``small_amplitude``.
    share_of_samples : float
        Fraction of all (scored) samples in this condition.
    share_of_violations : float
        Fraction of the *largest* disagreements that are in this condition: samples whose
        least-squares-refit residual is outside the noise band and in the top 20% of the
        out-of-band magnitudes.
    enrichment : float
        ``share_of_violations / share_of_samples`` (``> 1``: over-represented; NaN when
        there are no violations or no samples in the condition).
    mean_abs_residual : float
        Mean ``|residual|`` in this condition (least-squares refit of the original model).
    """

    name: str
    share_of_samples: float
    share_of_violations: float
    enrichment: float
    mean_abs_residual: float


@dataclass(frozen=True)
class Disagreement:
    """Where and by how much the model disagrees with the data (step 1).

    Attributes
    ----------
    gap : float
        Smallest output bound making the data consistent with the original model class
        (minimax over the refittable parameters, see ``refit``).
    gap_lower : float
        Rigorous lower bound of ``gap`` (weak duality); ``gap_lower > output_bound``
        certifies that the model class is inconsistent with the data. The class is the
        model with its refitted coefficients free (``B`` or a black box's gain, the LP
        coefficients of added effects); the searched parameters of effects a previous
        diagnosis added stay at their fitted values (recheck 52).
    fraction_outside : float
        Fraction of samples whose minimax-refit residual exceeds the output bound (the
        minimax fit spreads the error evenly, so this is often close to 1 when
        ``gap > output_bound``).
    ls_fraction_outside : float
        Fraction of samples whose *least-squares* refit residual exceeds the output bound;
        these samples (``indices``) are used to locate the disagreement.
    nominal_gap : float
        ``max |y - model(u)|`` of the model as given (no refit).
    nominal_fraction_outside : float
        Same fraction for the model as given.
    indices : ndarray of int
        Samples outside the band after the least-squares refit.
    residual : ndarray
        Minimax-refit residual ``y - yhat``.
    ls_residual : ndarray
        Least-squares-refit residual (localisation residual).
    nominal_residual : ndarray
        Residual of the model as given.
    conditions : tuple of ConditionEvidence
        Distribution of the out-of-band samples over operating conditions.
    mean_shift : float
        Mean minimax-refit residual divided by ``gap`` (near +-1: a constant shift).
    direction_correlation : float
        Correlation of the residual of a least-squares refit (with a constant) with the
        model's linear response to the sign of the most recent input movement. A missing
        backlash drives it towards -1; wrong dynamics (delay, pole) also correlate
        moderately, so it is a hint, not a decision.
    best_lag : int
        Shift ``k`` (samples) maximising the correlation of ``y`` with the nominal
        prediction delayed by ``k`` (``> 0``: the data lag the model).
    hints : tuple of str
        Human-readable observations (heuristics; the decision is made in step 2).
    skip, skip_note : int, str
        Initial samples not scored, and why (:func:`~.diagnose`'s ``skip``; review 52:
        ``locate`` skipped samples without saying so).
    """

    gap: float
    gap_lower: float
    fraction_outside: float
    ls_fraction_outside: float
    nominal_gap: float
    nominal_fraction_outside: float
    indices: np.ndarray = field(repr=False)
    residual: np.ndarray = field(repr=False)
    ls_residual: np.ndarray = field(repr=False)
    nominal_residual: np.ndarray = field(repr=False)
    conditions: tuple = ()
    mean_shift: float = 0.0
    direction_correlation: float = 0.0
    best_lag: int = 0
    hints: tuple = ()
    skip: int = 0
    skip_note: str = ""


@dataclass(frozen=True, repr=False)
class DiagnosisReport(Result):
    """Result of :func:`diagnose`.

    Attributes
    ----------
    effect : str or None
        Name of the missing effect, or of the combination (``"backlash+delay"``), that
        makes the data consistent with the output bound; ``None`` when the model is
        already consistent, and when **none of the candidates explains the data** (then
        see ``closest``). Never the name of something that leaves the data inconsistent.
    effects_added : tuple of str
        The added effects (``effect`` split at ``+``; empty when ``effect`` is None).
    closest : tuple of str
        When nothing explains the data: the (at most two) candidates or combinations
        with the smallest error among those shrinking the gap by ``min_improvement``.
        Listed for information only; none of them is consistent.
    closest_gap_removed : tuple of float
        For each of ``closest``: the fraction of the gap above the output bound it
        removes, ``(gap_before - error) / (gap_before - output_bound)``.
    closest_minimax_error : tuple of float
        For each of ``closest``: its achieved minimax error.
    combinations : tuple of CombinationFit
        Evidence of the joint search (empty when a single candidate was consistent).
    search_seconds : float
        Wall time of the whole diagnosis (the search's cost).
    n_fits : int
        Minimax LPs solved.
    n_combinations : int
        Candidate classes (single effects and combinations) fitted.
    gap_before, gap_after : float
        Minimax error (smallest consistent output bound) of the original and refined
        model classes. ``gap_after == gap_before`` when ``effect is None``. When an
        effect is named, ``gap_after <= output_bound`` unless no candidate is consistent
        (then ``consistent_after`` is False and the message says so).
    output_bound : float
    consistent_before, consistent_after : bool
        ``gap <= output_bound`` before / after, up to the outward tolerance
        ``1e-9 (|y_t| + |yhat_t| + output_bound)`` per sample (hammerbound.tolerances).
    fraction_outside_before, fraction_outside_after : float
        Fraction of samples outside the noise band before / after (same tolerance).
    refined_model : RefinedModel
        The model with the effect added and refitted (the refitted original model when
        ``effect is None``).
    candidates : tuple of CandidateFit
        Evidence for every candidate that was tried (always all requested candidates,
        also when the original model is already consistent).
    disagreement : Disagreement
        Localisation of the disagreement (step 1).
    message : str
        One-paragraph conclusion.
    data : IOData or None
        The :class:`~hammerbound.IOData` passed to :func:`diagnose` (None for arrays): its
        signal names and units label the figure; its ``dt`` is ``refined_model.dt``.
    """

    effect: str | None
    gap_before: float
    gap_after: float
    output_bound: float
    consistent_before: bool
    consistent_after: bool
    fraction_outside_before: float
    fraction_outside_after: float
    refined_model: RefinedModel
    candidates: tuple
    disagreement: Disagreement
    message: str
    u: np.ndarray = field(repr=False, default=None)
    y: np.ndarray = field(repr=False, default=None)
    prediction_nominal: np.ndarray = field(repr=False, default=None)
    prediction_before: np.ndarray = field(repr=False, default=None)
    prediction_after: np.ndarray = field(repr=False, default=None)
    skip: int = 0
    skip_note: str = ""
    effects_added: tuple = ()
    closest: tuple = ()
    closest_gap_removed: tuple = ()
    closest_minimax_error: tuple = ()
    combinations: tuple = ()
    search_seconds: float = 0.0
    n_fits: int = 0
    n_combinations: int = 0
    data: object = field(repr=False, default=None)

    @property
    def noise_bound(self) -> float:
        """Deprecated name of :attr:`output_bound` (removed in 0.3.0)."""
        warn_renamed("DiagnosisReport.noise_bound", "DiagnosisReport.output_bound")
        return self.output_bound

    @property
    def effect_label(self) -> str:
        """``effect``, or "none of the candidates explains the data" / "none needed"."""
        if self.effect is not None:
            return self.effect
        if self.consistent_before:
            return "none (the model is consistent with the data)"
        return "none of the candidates explains the data"

    @property
    def gap_before_lower(self) -> float:
        """Certified lower bound of ``gap_before`` (see :attr:`Disagreement.gap_lower`)."""
        return self.disagreement.gap_lower

    @property
    def gap_reduction(self) -> float:
        """``gap_before / gap_after`` (1 when no effect was added)."""
        return self.gap_before / self.gap_after if self.gap_after > 0 else float("inf")

    def candidate(self, name: str) -> CandidateFit:
        """Evidence of candidate ``name``.

        Raises
        ------
        KeyError
            If the candidate was not tried.
        """
        for c in self.candidates:
            if c.name == name:
                return c
        raise KeyError(name)

    def summary(self) -> str:
        """Multi-line human-readable summary (gaps, locations, candidate table)."""
        d = self.disagreement
        lines = [
            f"output bound             : {self.output_bound:.6g}",
            f"scored samples           : {self._scored_text()}",
            f"nominal model max |error|: {d.nominal_gap:.6g} "
            f"({100 * d.nominal_fraction_outside:.1f}% of samples outside the band)",
            f"gap before (refit)       : {self.gap_before:.6g} "
            f"(certified >= {d.gap_lower:.6g}; "
            f"{100 * self.fraction_outside_before:.1f}% outside)",
            f"effect                   : {self.effect_label}",
            f"gap after                : {self.gap_after:.6g} "
            f"({100 * self.fraction_outside_after:.1f}% outside)",
        ]
        for name, frac, err in zip(self.closest, self.closest_gap_removed,
                                   self.closest_minimax_error, strict=True):
            lines.append(f"closest candidate        : {name} (error {err:.6g}, removes "
                         f"{100 * frac:.0f}% of the gap above the bound; not consistent)")
        lines.append(f"search cost              : {self.search_seconds:.2f} s, "
                     f"{self.n_fits} minimax fits, {self.n_combinations} classes")
        for h in d.hints:
            lines.append(f"  - {h}")
        if self.combinations:
            lines.append("combination (joint fit)         minimax err  consistent  gap removed")
            for c in self.combinations:
                lines.append(f"{c.name:<30} {c.minimax_error:>12.5g}  {str(c.consistent):>10}"
                             f" {100 * c.gap_fraction_removed:>11.0f}%")
        if self.candidates:
            # columns as wide as the longest name (asym_backlash, output_saturation, ...)
            wn = max(13, *(len(c.name) for c in self.candidates))
            wp = max(5, *(len(c.param_name) for c in self.candidates))
            wv = max(12, *(len(_val(c.value)) for c in self.candidates))
            lines.append(f"{'candidate':<{wn}} {'param':>{wp}} {'value':>{wv}}   minimax err  "
                         "consistent  improvement")
            for c in self.candidates:
                lines.append(
                    f"{c.name:<{wn}} {c.param_name:>{wp}} {_val(c.value):>{wv}} "
                    f"{c.minimax_error:>13.5g}  {str(c.consistent):>10} {c.improvement:>12.3g}"
                )
        lines.append(self.message)
        return "\n".join(lines)

    def _scored_text(self) -> str:
        """Which samples every error counts, and the initial state they rest on."""
        n = len(self.y) if self.y is not None else None
        which = (f"all{'' if n is None else f' {n}'}" if not self.skip
                 else f"{self.skip}..{'' if n is None else n - 1}")
        note = self.skip_note or (f"skip={self.skip}" if self.skip else "")
        if not note:
            return f"{which} (the model starts at rest, zero state)"
        return f"{which} (its linear block starts at rest, zero state; {note})"

    def to_dict(self) -> dict:
        """JSON-serialisable summary (no signals; NaN and inf become None)."""
        d = self.disagreement
        rm = self.refined_model
        return jsonable({
            "effect": self.effect,
            "effect_label": self.effect_label,
            "effects_added": list(self.effects_added),
            "closest": [{"name": n, "gap_fraction_removed": f, "minimax_error": e}
                        for n, f, e in zip(self.closest, self.closest_gap_removed,
                                           self.closest_minimax_error, strict=True)],
            "combinations": [c.__dict__ for c in self.combinations],
            "search_cost": {"seconds": self.search_seconds, "n_fits": self.n_fits,
                            "n_classes": self.n_combinations},
            "output_bound": self.output_bound,
            "skip": self.skip,
            "skip_note": self.skip_note,
            "gap_before": self.gap_before,
            "gap_before_certified_lower": d.gap_lower,
            "gap_after": self.gap_after,
            "consistent_before": self.consistent_before,
            "consistent_after": self.consistent_after,
            "fraction_outside_before": self.fraction_outside_before,
            "fraction_outside_after": self.fraction_outside_after,
            "nominal_gap": d.nominal_gap,
            "hints": list(d.hints),
            "conditions": [c.__dict__ for c in d.conditions],
            "candidates": [{k: v for k, v in c.__dict__.items() if k != "model"}
                           for c in self.candidates],
            "refined_model": {
                "effects": [list(e) for e in rm.effects],
                "A": None if rm.A is None else rm.A.tolist(),
                "B": None if rm.B is None else rm.B.tolist(),
                "offset": rm.offset,
                "gain": rm.gain,
                "dt": rm.dt,
                # the record's time unit ("" when the data did not say)
                "time_unit": getattr(self.data, "time_unit", "") or "",
            },
            "message": self.message,
        })

    def plot(self, ax=None, *, max_samples: int | None = None):
        """Figure: input, output and predictions, residuals with the noise band, candidates.

        Panels: (1) the input; (2) data, the model as given and the refined model;
        (3) the minimax residual before (original class, refitted) and after adding the
        effect, with the noise band ``+-output_bound`` - the gap is the largest excursion;
        (4) the minimax error of every candidate against the output bound and the gap
        before (log scale). :meth:`save` writes it to a file.

        Parameters
        ----------
        ax : sequence of 4 matplotlib Axes, optional
            The panels to draw into (default: a new figure). A path here is the
            deprecated ``plot(path)`` (removed in 0.3.0): the figure is drawn and saved
            there, as ``save(path)`` does.
        max_samples : int, optional
            Show only the first ``max_samples`` samples in the time panels (long records).

        Returns
        -------
        matplotlib.figure.Figure
        """
        import os

        from .plot import plot_report

        if isinstance(ax, (str, os.PathLike)):
            warn_plot_path("DiagnosisReport")
            fig = plot_report(self, None, max_samples=max_samples)
            fig.savefig(ax, dpi=110)
            return fig
        return plot_report(self, ax, max_samples=max_samples)


def _val(v) -> str:
    if isinstance(v, tuple):
        return ",".join(f"{x:.3g}" for x in v)
    return f"{v:.5g}"
