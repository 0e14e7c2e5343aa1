"""The identifier's two-stage path (the chapter): stage 1 on steady-state data, the
hand-off of Result 1, stage 2 on the PRBS record."""

from __future__ import annotations

from dataclasses import dataclass

from ..exceptions import DataValidationError, EmptyFeasibleSetError, UnboundedSetError
from ..stage1.inner_signal import read_prbs_level

__all__ = ["TwoStageFit", "fit_two_stage", "steady_pair"]


def steady_pair(steady_state):
    """Accept SteadyStateData, a dict with 'u'/'y', or a pair (u, y)."""
    if hasattr(steady_state, "u") and hasattr(steady_state, "y"):
        return steady_state.u, steady_state.y
    if isinstance(steady_state, dict):
        try:
            return steady_state["u"], steady_state["y"]
        except KeyError as exc:
            raise DataValidationError(
                "steady_state dict must have keys 'u' and 'y'."
            ) from exc
    try:
        u, y = steady_state
    except (TypeError, ValueError) as exc:
        raise DataValidationError(
            "steady_state must be a pair (u_ss, y_ss), a dict with 'u' and 'y', or "
            "SteadyStateData."
        ) from exc
    return u, y


@dataclass(frozen=True)
class TwoStageFit:
    """The fitted stages and the hand-off between them."""

    backlash: object
    linear: object
    u_star: float
    inner: object
    record: object


def fit_two_stage(bl, lin, data, steady_state, *, prbs_level, inner_signal,
                  output_bound) -> TwoStageFit:
    """Stage 1 on ``steady_state``, Result 1 for ``u*``, stage 2 on the PRBS record
    ``data`` (an IOData); ``bl``/``lin`` are fitted in place (clones of the user's)."""
    u_ss, y_ss = steady_pair(steady_state)
    bl.fit(u_ss, y_ss)
    u_star = read_prbs_level(data.u, prbs_level)
    inner = bl.inner_signal_bounds(u_star)  # checks Result 1
    record = inner.stage2_record(data, inner_signal)
    try:
        lin.fit(record.data, input_bound=record.input_bound,
                input_groups=record.input_groups, output_bound=output_bound)
    except EmptyFeasibleSetError as exc:
        raise _in_two_stage_terms(exc, record.input_bound, u_star) from exc
    except UnboundedSetError as exc:
        raise UnboundedSetError(_procedure_words(str(exc))) from exc
    return TwoStageFit(bl, lin, u_star, inner, record)


def _procedure_words(text: str) -> str:
    """A stage-2 message without advice the two-stage procedure cannot take: its input
    error bound comes from stage 1 and its gain is fixed at 1 (22.8)."""
    text = text.replace("the input error bound (input_bound)",
                        "the inner-signal bound from stage 1")
    text = text.replace("; pass steady_state_gain=None for a plain EIV problem", "")
    return text.replace("enlarge theta_box or check the gain.",
                        "enlarge theta_box (the two-stage procedure fixes the gain at 1).")


def _in_two_stage_terms(exc, input_bound, u_star) -> EmptyFeasibleSetError:
    """Stage 2's empty verdict in the terms of the two-stage procedure: its input error
    bound is stage 1's inner-signal bound (not a parameter of the user's), the unit gain
    (22.8) is part of the procedure, and a stage-1 bound too tight (steady-state points not
    settled, or a steady-state output bound too small) empties stage 2 as surely as its
    own data."""
    from ..tables import bound_text

    text = _procedure_words(str(exc))
    if exc.first_index is None and "theta_box and the gain equality" in text:
        # the a priori box alone cannot meet the gain: no data, stage 1's or stage 2's, matter
        return EmptyFeasibleSetError(text, side=exc.side, first_index=None,
                                     relaxation=exc.relaxation)
    text += (f" In the two-stage procedure stage 2's input error bound is stage 1's "
             f"inner-signal bound |dx_t| <= {bound_text(input_bound)} at u* = {u_star:g}, "
             "computed from the "
             "steady-state points: if they had not settled (a transient left) or their "
             "output bound is too small, that bound is too tight and stage 2 is empty "
             "although its own record is fine: check the steady-state points as well as "
             "the PRBS record.")
    return EmptyFeasibleSetError(text, side=exc.side, first_index=exc.first_index,
                                 relaxation=exc.relaxation)
