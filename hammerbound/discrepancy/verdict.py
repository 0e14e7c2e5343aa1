"""The words of a diagnosis: its message (what is missing, or why nothing is named) and
the note on a fitted set's central model (split from :mod:`.diagnose`)."""

from __future__ import annotations

__all__ = ["CENTRAL_CHECK", "CENTRAL_NOTE", "diagnosis_message", "of_central_model"]


#: What a verdict against a fitted set's central model does not say (new-user trial 17: a
#: clean record of the true plant was "inconsistent" with the identifier's model at the
#: true bound, while the truth was inside every interval).
CENTRAL_NOTE = ("This tests the fitted set's central model (its A and backlash at the "
                "centres of their intervals{b}), not the whole set: other models of the set, "
                "the truth among them if the fit's assumptions hold, may explain the data. "
                "{check}")
#: the set's own check of new data, by the procedure that fitted it (recheck 49: a
#: two-stage fit's envelope refuses a record that is not a PRBS at +-u*)
CENTRAL_CHECK = {
    "one-record": "The set's own check of new data is its output envelope "
                  "(ident.output_envelope(u, y)).",
    "two-stage": "The set's own check is its output envelope, which takes a PRBS record at "
                 "+-u* (ident.output_envelope(u_prbs, y_prbs)); a record of another input "
                 "needs a one-record fit (procedure='one-record').",
}


def of_central_model(model, report, do_refit):
    """``report`` with :data:`CENTRAL_NOTE` after its message when ``model`` is a fitted
    set estimator (its ``system_`` is a centre, not an estimate to test) and the data
    were found inconsistent with it."""
    from dataclasses import replace

    if report.consistent_before or not hasattr(model, "bounds_") \
            or not hasattr(model, "system_"):
        return report
    check = CENTRAL_CHECK.get(getattr(model, "procedure_", None),
                              "Check the set itself on the data where it offers a check.")
    note = CENTRAL_NOTE.format(b=", B refitted" if do_refit else ", B as well", check=check)
    return replace(report, message=f"{report.message} {note}")


def _num(v):
    if isinstance(v, tuple):
        return "(" + ", ".join(f"{x:.4g}" for x in v) + ")"
    return f"{v:.4g}"


def diagnosis_message(bound, gap_before, consistent_before, chosen, added, fits, combos,
                      closest, removed, min_improvement, old, after_bound=None):
    """What the diagnosis found, in words: no missing effect, the effect(s) added, or why
    none of the candidates is named. ``bound`` judges the model before, ``after_bound`` the
    chosen one (each the output bound plus what an unknown backlash start can still do to
    that fit; default ``bound``)."""
    after_bound = bound if after_bound is None else after_bound
    if consistent_before:
        msg = (
            f"No missing effect: the model (after refitting its parameters) reproduces the "
            f"data within the output bound (gap {gap_before:.4g} <= {bound:.4g}), so the data "
            f"give no evidence for any candidate."
        )
        better = sorted((c for c in fits if c.minimax_error * min_improvement <= gap_before),
                        key=lambda c: c.minimax_error)
        if better:
            c = better[0]
            msg += (
                f" An effect whose size is below the output bound can neither be confirmed nor "
                f"excluded: e.g. {c.name} ({c.param_name} = {_num(c.value)}) would lower the "
                f"error to {c.minimax_error:.4g}, which is not required by the data."
            )
        return msg
    if chosen is not None:
        parts = [f"{e.name} ({e.param_label()} = {_num(v)}{e.value_note(chosen.model)})"
                 for e, (_, v) in zip(chosen.effects, chosen.model.effects, strict=True)]
        what = " + ".join(parts)
        if len(added) == 1 and not old:
            msg = (f"Missing effect: {what}; with it the data are consistent with the output "
                   f"bound (gap {gap_before:.4g} -> {chosen.error:.4g} <= {after_bound:.4g}).")
            others = [c for c in fits if c.consistent and c.name != added[0]]
            if others:
                msg += (" Also consistent, with a larger error or more parameters: "
                        + ", ".join(f"{c.name} ({c.minimax_error:.4g})" for c in others)
                        + "; the data do not exclude them.")
        else:
            msg = (f"Missing effects, fitted jointly: {what}; with them the data are "
                   f"consistent with the output bound (gap {gap_before:.4g} -> "
                   f"{chosen.error:.4g} <= {after_bound:.4g}).")
            if len(added) > 1:
                best = min(fits, key=lambda c: c.minimax_error)
                msg += (f" No single candidate is consistent (best: {best.name}, "
                        f"{best.minimax_error:.4g}).")
        return msg
    k = max((len(c.name.split("+")) for c in combos), default=1)
    tried = "single candidate" + (f" nor combination of up to {k} candidates (fitted "
                                  f"jointly)" if combos else "")
    msg = (f"None of the candidates explains the data: the model is inconsistent with the "
           f"data (gap {gap_before:.4g} > {bound:.4g}) and no {tried} makes it consistent.")
    if closest:
        msg += " Closest: " + "; ".join(
            f"{n} (error {e:.4g}, removes {100 * removed(e):.0f}% of the gap above the bound)"
            for n, e in closest) + "."
    else:
        msg += (f" No candidate shrinks the gap by the factor min_improvement = "
                f"{min_improvement:g}.")
    msg += (" Check the output bound; or the missing effect is not in the candidate "
            "library; or the model's fixed parts are off: refit='linear' refits only B (a "
            "black box's output gain) and the candidates' parameters, while A and the "
            "backlash stay as given (for an identifier, those of its central model).")
    return msg


