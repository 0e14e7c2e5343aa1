"""Model-discrepancy diagnosis: locate, name and add the effect a simulation model misses.

Workflow (see ``docs/discrepancy.md``)
-------------------------------------
1. **Locate.** The model is simulated on the measured input and compared with the data.
   The *gap* of a model class is the smallest output bound under which the data are
   consistent with it (a Chebyshev / minimax fit)::

       gap = min_theta max_{t >= skip} |y_t - yhat_t(theta)|

   where ``theta`` are the parameters the model is allowed to change ("parameter
   uncertainty": the numerator ``B`` of the linear block, or an output gain for a
   black-box model; see ``refit``). The data are consistent with the model class under
   the output bound ``Delta`` iff ``gap <= Delta`` - in floating point, iff every scored
   residual satisfies ``|y_t - yhat_t| <= Delta + 1e-9 (|y_t| + |yhat_t| + Delta)`` (the
   outward tolerance of :mod:`hammerbound.tolerances`; the same rule counts the samples
   "outside"). Samples whose best-fit residual lies outside that band are flagged and
   grouped by operating condition (after input reversals, after input changes, in steady
   state, at large / small amplitude), with constant-shift and lag indicators.
2. **Name.** Each candidate effect adds *one* parameter to the model class:

   ==============  ===========================================================  =====
   name            added block                                                  param
   ==============  ===========================================================  =====
   ``backlash``    play operator of half-width ``c`` (unit slopes) on the input  ``c``
   ``deadzone``    ``sign(u) max(|u| - w, 0)`` on the input                      ``w``
   ``saturation``  ``clip(u, -s, s)`` on the input                               ``s``
   ``delay``       ``q^-d`` (integer ``d >= 1``) extra input delay; reported:    ``d``
                   the total input delay of the refit (leading zeros of ``B``)
   ``offset``      constant ``o`` added to the output                            ``o``
   ``extra_pole``  ``(1 - p) / (1 - p q^-1)`` in series, ``-1 < p < 1``          ``p``
   ==============  ===========================================================  =====

   For every candidate the augmented class is refitted by minimax: for a fixed value
   of the nonlinear parameter the fit is a linear program in ``(B, offset)``; the
   nonlinear parameter is searched on a grid and refined locally (``delay`` is
   enumerated, ``offset`` is an LP variable). A candidate is *consistent* when its
   minimax error is ``<= Delta``. Every candidate is always refitted and reported.
   Selection: if the original class is consistent the answer is ``None`` (nothing is
   invented; effects below the noise level cannot be confirmed or excluded); otherwise,
   among consistent candidates the one with the fewest added parameters, then the
   smallest minimax error, wins; if none is consistent the candidate with the smallest
   error is named only if it shrinks the gap by ``min_improvement``
   (``consistent_after=False``), else ``None``.
3. **Add.** The chosen effect is inserted, the model refitted, and the report carries
   ``gap_before``, ``gap_after``, the :class:`RefinedModel` and :meth:`plot`.

Guarantees. Every reported minimax error is *achieved* by the returned parameters
(it is recomputed from the residual of the refined model), so "consistent" is a
certificate. ``report.gap_before_lower`` is a rigorous lower bound of the original
class's gap (weak duality, :mod:`hammerbound.solvers.safe_lp`) over a coefficient box
(each refitted column may contribute at most ``coef_box`` times the output scale): when
it exceeds ``Delta`` the model is *certified* inconsistent.
For grid-searched candidates, inconsistency is only established on the grid.
"""

from __future__ import annotations

from ..data.csv_reader import read_io_csv
from .diagnose import diagnose
from .effects import CANDIDATES, REGISTRY, Effect, default_candidates, register
from .locate import locate
from .model import RefinedModel, apply_effect
from .report import CandidateFit, ConditionEvidence, DiagnosisReport, Disagreement

__all__ = [
    "CANDIDATES",
    "REGISTRY",
    "CandidateFit",
    "ConditionEvidence",
    "Disagreement",
    "DiagnosisReport",
    "Effect",
    "RefinedModel",
    "apply_effect",
    "default_candidates",
    "diagnose",
    "locate",
    "read_io_csv",
    "register",
]

