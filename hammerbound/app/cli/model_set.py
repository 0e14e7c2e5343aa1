"""``--model-set FILE.json`` of ``identify`` and ``eiv``: the guaranteed model set of the
linear block for a robust-control design, written as one JSON file (the command line's
route to :mod:`hammerbound.modelset`; ``docs/robust-control.md`` shows the same in Python).

The file holds the parameter intervals and the assumptions they rest on, the Bode envelope
of every model in them
(:meth:`~hammerbound.LinearEIVSetEstimator.frequency_response_bounds`, at its listed
frequencies) and certified multiplicative and additive uncertainty weights around the
central model (:meth:`~hammerbound.LinearEIVSetEstimator.uncertainty_weight`, at every
frequency; ``null``, with its own reason in ``no_weight``, where none exists); with a
gain constraint (the
Hammerstein identifier's unit gain (22.8), or ``eiv --steady-state-gain``) the same again
on the gain plane, which every feasible model satisfies and the box alone does not
express. The path is checked before any work; an existing file is kept unless ``--force``
(also one made while the fit ran).
"""

from __future__ import annotations

import warnings

import numpy as np

from ...exceptions import HammerboundError, UnboundedSetError
from ..paths import check_output_file

__all__ = ["add_model_set_option", "check_model_set", "exit_status", "write_model_set"]

OPTION = "--model-set"
WHAT = ("every model B(q^-1)/A(q^-1) whose parameters lie in the intervals below, under the "
        "assumptions listed: the envelope bounds hold at its listed frequencies, the weights "
        "at every frequency")


def add_model_set_option(p) -> None:
    p.add_argument(OPTION, default=None, metavar="FILE.json",
                   help="also write the guaranteed model set of the linear block (Bode "
                        "envelope, certified multiplicative and additive uncertainty "
                        "weights; on the gain plane too when there is a gain constraint) "
                        "to this JSON file (exit status 1 if no file could be written, "
                        "e.g. an interval is infinite)")


def check_model_set(args):
    """The ``--model-set`` path checked before any work (None without the option)."""
    path = getattr(args, "model_set", None)
    if path is None:
        return None
    return check_output_file(path, force=args.force, option=OPTION)


def _sets(lin, on_gain_plane) -> dict:
    env = lin.frequency_response_bounds(on_gain_plane=on_gain_plane)
    weights, why = {}, {}
    for kind in ("multiplicative", "additive"):
        try:
            weights[kind] = lin.uncertainty_weight(kind, on_gain_plane=on_gain_plane).to_dict()
        except UnboundedSetError as exc:  # no finite weight of this kind: its own reason
            weights[kind], why[kind] = None, str(exc)
            plane = " on the gain plane" if on_gain_plane else ""
            warnings.warn(f"the model set's {kind} weight{plane} is null: {exc}",
                          UserWarning, stacklevel=2)  # said on stderr, not only in the file
    out = {"frequency_envelope": env.to_dict(), "uncertainty_weights": weights}
    if why:
        out["no_weight"] = why
    return out


def _document(lin, assumptions) -> dict:
    doc = {"what": WHAT, "parameters": list(lin.param_names_), "lower": lin.bounds_[:, 0],
           "upper": lin.bounds_[:, 1], "assumptions": list(assumptions),
           "box": _sets(lin, False)}
    if lin.steady_state_gain is not None:
        doc["gain_plane"] = {"steady_state_gain": float(lin.steady_state_gain),
                             **_sets(lin, True)}
    return doc


def exit_status(path, written) -> int:
    """The command's exit status: 1 when ``--model-set`` was asked for (``path``) and no
    file was written, else 0."""
    return 1 if path is not None and written is None else 0


def write_model_set(path, lin, assumptions, force=False) -> str | None:
    """Write the model set of the fitted linear block ``lin`` to ``path`` (the checked
    ``--model-set`` path, or None: nothing to write) and return it as text (the JSON
    output's ``"model_set"``); None, with a warning and no file, when an interval is
    infinite or the set cannot be computed or written (the identification's results are
    printed either way). Without ``force`` a file that appeared since the check is kept."""
    from .printing import json_text

    def fail(why):
        warnings.warn(f"no model set written to {path}: {why}", UserWarning, stacklevel=3)

    if path is None:
        return None

    if not np.all(np.isfinite(lin.bounds_)):
        return fail("an interval of the linear block is infinite (see the warnings before).")
    try:
        text = json_text(_document(lin, assumptions)) + "\n"
        with open(path, "w" if force else "x") as f:  # "w": through a link, mode kept
            f.write(text)
    except FileExistsError:
        return fail("the file appeared while the fit ran; pass --force to replace it.")
    except (HammerboundError, OSError) as exc:
        return fail(f"{type(exc).__name__}: {exc}")
    return str(path)
