"""Step 2 and 3: name the missing effect(s) and add them (:func:`diagnose`)."""

from __future__ import annotations

import numpy as np

from . import effects as _effects
from .checks import candidate_names, int_param, positive, validate
from .effects import CANDIDATES, Context
from .fitting import design, outside, rebuild
from .locate import locate_design
from .report import CandidateFit, DiagnosisReport
from .search import Problem, fit_combination

__all__ = ["diagnose"]


def diagnose(
    model,
    u,
    y,
    noise_bound: float,
    *,
    candidates=None,
    refit: str = "linear",
    skip: int = 0,
    max_delay: int = 10,
    grid_size: int = 24,
    window: int = 5,
    coef_box: float = 1e3,
    min_improvement: float = 1.1,
) -> DiagnosisReport:
    """Locate, name and add the effect a simulation model is missing.

    Parameters
    ----------
    model : control.TransferFunction, HammersteinSystem, RefinedModel or object
        A *discrete-time*, stable SISO transfer function (powers of ``q^-1`` as in
        :func:`hammerbound.systems.as_polynomials`), a Hammerstein system, a model
        returned by a previous :func:`diagnose` (to look for a second effect), or any
        object with ``.predict(u) -> y`` (a black box).
    u, y : array_like
        Measured input and output, same length; the data are assumed to start from rest
        (zero initial state) unless the first ``skip`` samples are excluded.
    noise_bound : float
        Known bound ``|eta_t| <= noise_bound`` of the output error (22.5).
    candidates : sequence of str, optional
        Names from :data:`CANDIDATES` to try (default: :func:`default_candidates`, the
        one-parameter effects; ``"all"``: every registered candidate, including the
        slower several-parameter ones ``polynomial``, ``asym_backlash``, ``relay``,
        ``output_saturation``, ``drift``).
    refit : {"linear", "none"}
        ``"linear"`` (default): the model's parameter uncertainty is the numerator ``B``
        of its linear block (leading zeros kept, ``A`` fixed) - or an output gain for a
        black-box model - refitted by minimax with and without each candidate.
        ``"none"``: the model is taken as exact; only the candidate's parameter (and the
        offset for ``offset``) is fitted.
    skip : int
        Number of initial samples excluded from every error (unknown initial state).
    max_delay : int
        Largest extra delay tried by ``delay`` (and lag examined in step 1).
    grid_size : int
        Grid points of the 1-D search for ``backlash``, ``deadzone``, ``saturation`` and
        ``extra_pole`` before local refinement.
    window : int
        Samples after an input change / reversal counted as "after" it (step 1).
    coef_box : float
        Coefficient box (relative to the output scale) for the certified lower bounds.
    min_improvement : float
        When *no* candidate is consistent, the best one is named only if it shrinks the
        gap by at least this factor (``gap_before / gap_after >= min_improvement``);
        otherwise ``effect`` is None. Guards against naming an effect for a noise bound
        that is simply too small.

    Returns
    -------
    DiagnosisReport

    Raises
    ------
    DataValidationError
        NaN/inf in ``u`` or ``y``, mismatched lengths, too few samples, a black-box model
        returning the wrong number of samples.
    ParameterValidationError
        Non-positive noise bound, unknown candidate, continuous-time or unstable
        transfer function, unsupported model type.

    Examples
    --------
    >>> import control, numpy as np
    >>> from hammerbound.discrepancy import diagnose
    >>> G = control.tf([0, 0.5], [1, -0.5], True)
    >>> u = np.repeat(np.random.default_rng(0).uniform(-1, 1, 40), 8)
    >>> y = control.forced_response(G, U=u).outputs + 0.3
    >>> diagnose(G, u, y, noise_bound=0.01).effect
    'offset'
    """
    s, u, y, nb, do_refit, skip = validate(model, u, y, noise_bound, refit, skip)
    names = candidate_names(candidates)
    max_delay = int_param("max_delay", max_delay, 1)
    max_delay = min(max_delay, u.size - skip - 2)
    grid_size = int_param("grid_size", grid_size, 3)
    window = int_param("window", window, 1)
    coef_box = positive("coef_box", coef_box)
    min_improvement = positive("min_improvement", min_improvement, 1.0, strict=False)

    origin = s if s.origin is None else s.origin
    existing = tuple((_effects.get(n), tuple(th)) for n, th, _ in s.effect_params) \
        if s.origin is not None else ()
    ctx = Context(u_max=float(np.max(np.abs(u))), y_max=float(np.max(np.abs(y))),
                  n=int(u.size), max_delay=max_delay, noise_bound=nb)
    pb = Problem(origin, u, y, nb, do_refit, skip, coef_box, grid_size, ctx)
    old = tuple(e for e, _ in existing)
    if existing:
        before = fit_combination(pb, old, starts=[tuple(th for _, th in existing)])
        d_before, combo_before = before.design, tuple(zip(old, before.thetas, strict=True))
    else:
        combo_before = ()
        d_before = design(origin, u, do_refit, (), y)
    disagreement, base_fit, nominal = locate_design(
        s, d_before, u, y, nb, skip, window, max_delay, coef_box
    )
    gap_before = base_fit.error
    consistent_before = not np.any(outside(y, base_fit.prediction, nb, skip))
    base_model = rebuild(origin, do_refit, combo_before, d_before, base_fit)
    frac_before = disagreement.fraction_outside

    def frac(pred):
        return float(np.mean(outside(y, pred, nb, skip)[skip:]))

    # step 2: refit every candidate (also when the model is already consistent, so that
    # the report always carries the evidence for each of them)
    fits = []
    cand_models = {}
    have = {e.name for e in old}
    for name in names:
        if name in have:
            continue
        e = _effects.get(name)
        cf = fit_combination(pb, (*old, e))
        theta = cf.thetas[-1]
        coefs = tuple(float(v) for v in cf.fit.z[cf.design.slices[-1]])
        err = cf.error
        cand_models[name] = (cf.model, cf.prediction)
        fits.append(
            CandidateFit(
                name=name,
                n_params=CANDIDATES[name],
                param_name=e.param_label(),
                value=e.value(theta, coefs),
                minimax_error=err,
                lower_bound=cf.lower,
                consistent=not np.any(outside(y, cf.prediction, nb, skip)),
                fraction_outside=frac(cf.prediction),
                improvement=gap_before / err if err > 0 else float("inf"),
                exhaustive=cf.exhaustive,
                n_evaluations=cf.n_evaluations,
            )
        )
    pred_before = base_fit.prediction
    effect = None
    if consistent_before:
        msg = (
            f"No missing effect: the model (after refitting its parameters) reproduces the "
            f"data within the noise bound (gap {gap_before:.4g} <= {nb:.4g}), so the data "
            f"give no evidence for any candidate."
        )
        better = sorted((c for c in fits if c.minimax_error * min_improvement <= gap_before),
                        key=lambda c: c.minimax_error)
        if better:
            c = better[0]
            msg += (
                f" An effect whose size is below the noise bound can neither be confirmed nor "
                f"excluded: e.g. {c.name} ({c.param_name} = {_num(c.value)}) would lower the "
                f"error to {c.minimax_error:.4g}, which is not required by the data."
            )
    else:
        ok = sorted((c for c in fits if c.consistent),
                    key=lambda c: (c.n_params, c.minimax_error))
        if ok:
            best = ok[0]
            effect = best.name
            msg = (
                f"Missing effect: {best.name} ({best.param_name} = {_num(best.value)}); with it "
                f"the data are consistent with the noise bound (gap {gap_before:.4g} -> "
                f"{best.minimax_error:.4g} <= {nb:.4g})."
            )
            if len(ok) > 1:
                others = ", ".join(f"{c.name} ({c.minimax_error:.4g})" for c in ok[1:])
                msg += (
                    f" Also consistent, with a larger error or more parameters: {others}; "
                    f"the data do not exclude them."
                )
        elif fits:
            best = min(fits, key=lambda c: c.minimax_error)
            if best.minimax_error * min_improvement <= gap_before:
                effect = best.name
                msg = (
                    f"No single candidate makes the data consistent with the noise bound "
                    f"{nb:.4g}; the best is {best.name} ({best.param_name} = "
                    f"{_num(best.value)}), gap {gap_before:.4g} -> {best.minimax_error:.4g}. "
                    f"Either the noise bound is too small or something else (or a "
                    f"combination) is missing - run diagnose on report.refined_model to look "
                    f"for a second effect."
                )
            else:
                msg = (
                    f"The model is inconsistent with the data (gap {gap_before:.4g} > "
                    f"{nb:.4g}) but no candidate shrinks the gap by the factor "
                    f"min_improvement = {min_improvement:g} (best: {best.name}, "
                    f"{best.minimax_error:.4g}). Check the noise bound, or the missing effect "
                    f"is not in the candidate library."
                )
    if effect is None:
        refined, pred_after, gap_after = base_model, pred_before, gap_before
    else:
        refined, pred_after = cand_models[effect]
        gap_after = best.minimax_error
    return DiagnosisReport(
        effect=effect,
        gap_before=gap_before,
        gap_after=gap_after,
        noise_bound=nb,
        consistent_before=consistent_before,
        consistent_after=not np.any(outside(y, pred_after, nb, skip)),
        fraction_outside_before=frac_before,
        fraction_outside_after=frac(pred_after),
        refined_model=refined,
        candidates=tuple(fits),
        disagreement=disagreement,
        message=msg,
        u=u,
        y=y,
        prediction_nominal=nominal,
        prediction_before=pred_before,
        prediction_after=pred_after,
        skip=skip,
    )


def _num(v):
    if isinstance(v, tuple):
        return "(" + ", ".join(f"{x:.4g}" for x in v) + ")"
    return f"{v:.4g}"
