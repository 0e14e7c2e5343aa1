"""``--model-set FILE.json`` of ``identify`` and ``eiv``: the guaranteed model set of the
linear block for a robust-control design, written as one JSON file (the command line's
route to :mod:`hammerbound.modelset`; ``docs/robust-control.md`` shows the same in Python).

The file holds the parameter intervals, the Bode envelope of every model in them
(:meth:`~hammerbound.LinearEIVSetEstimator.frequency_response_bounds`) and certified
multiplicative and additive uncertainty weights around the central model
(:meth:`~hammerbound.LinearEIVSetEstimator.uncertainty_weight`); with a gain constraint
(the Hammerstein identifier's unit gain (22.8), or ``eiv --steady-state-gain``) the same
again on the gain plane, which every feasible model satisfies and the box alone does not
express. The path is checked before any work; an existing file is kept unless
``--force``.
"""

from __future__ import annotations

import warnings

import numpy as np

from ...exceptions import UnboundedSetError
from ..paths import check_output_file

__all__ = ["add_model_set_option", "check_model_set", "write_model_set"]

OPTION = "--model-set"


def add_model_set_option(p) -> None:
    p.add_argument(OPTION, default=None, metavar="FILE.json",
                   help="also write the guaranteed model set of the linear block (Bode "
                        "envelope, certified multiplicative and additive uncertainty "
                        "weights; on the gain plane too when there is a gain constraint) "
                        "to this JSON file (exit status 1 if an interval is infinite: no "
                        "model set then)")


def check_model_set(args):
    """The ``--model-set`` path checked before any work (None without the option)."""
    path = getattr(args, "model_set", None)
    if path is None:
        return None
    return check_output_file(path, force=args.force, option=OPTION)


def _sets(lin, on_gain_plane) -> dict:
    env = lin.frequency_response_bounds(on_gain_plane=on_gain_plane)
    weights = {kind: lin.uncertainty_weight(kind, on_gain_plane=on_gain_plane).to_dict()
               for kind in ("multiplicative", "additive")}
    return {"frequency_envelope": env.to_dict(), "uncertainty_weights": weights}


def write_model_set(path, lin) -> bool:
    """Write the model set of the fitted linear block ``lin`` to ``path``; False, with a
    warning (and no file), when an interval is infinite or no finite weight exists."""
    from .printing import json_text

    if not np.all(np.isfinite(lin.bounds_)):
        warnings.warn(f"no model set written to {path}: an interval of the linear block is "
                      "infinite (see the warnings before).", UserWarning, stacklevel=2)
        return False
    try:
        doc = {"what": "every model B(q^-1)/A(q^-1) whose parameters lie in the intervals "
                       "below; the envelope and the weights hold for all of them",
               "parameters": list(lin.param_names_), "lower": lin.bounds_[:, 0],
               "upper": lin.bounds_[:, 1], "box": _sets(lin, False)}
        if lin.steady_state_gain is not None:
            doc["gain_plane"] = {"steady_state_gain": float(lin.steady_state_gain),
                                 **_sets(lin, True)}
    except UnboundedSetError as exc:
        warnings.warn(f"no model set written to {path}: {exc}", UserWarning, stacklevel=2)
        return False
    path.write_text(json_text(doc) + "\n")
    return True
