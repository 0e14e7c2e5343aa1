"""Generate docs/api.md from the docstrings of the public API: ``python docs/gen_api.py``."""

from __future__ import annotations

import inspect
from pathlib import Path

MODULES = [
    ("hammerbound", None),
    ("hammerbound.systems.experiments", None),
    ("hammerbound.stage2.orders", ["check_orders", "largest_order"]),
    ("hammerbound.relaxations.lp", ["lp_bounds"]),
    ("hammerbound.relaxations.moment.relaxation", ["moment_bounds", "MomentRelaxation"]),
    ("hammerbound.relaxations.exact.bnb", ["exact_bounds", "SearchOptions"]),
    ("hammerbound.results", ["IntervalSet", "BoundInfo", "OutputEnvelope", "Result"]),
    ("hammerbound.modelset", ["FrequencyEnvelope", "UncertaintyWeight", "WeightCertificate",
                              "CertifiedSamples", "BacklashSamples", "BacklashInverse",
                              "BacklashCompensator"]),
    ("hammerbound.status", None),
    ("hammerbound.relaxations.result", ["IntervalResult", "Polytope", "LPDetails",
                                        "MomentDetails", "ExactDetails"]),
    ("hammerbound.solvers", ["available_solvers", "get_solver"]),
    ("hammerbound.discrepancy", ["diagnose", "locate", "DiagnosisReport", "RefinedModel"]),
    ("hammerbound.app.report", ["write_report", "IdentificationReport"]),
    ("hammerbound.plotting", None),
]

PUBLIC_METHODS = ("fit", "predict", "score", "contains", "transform", "inner_signal",
                  "inner_signal_bounds", "admissible_prbs_range", "check_prbs_level",
                  "suggest_prbs_level", "to_transfer_function", "one_step_envelope",
                  "output_envelope", "simulate", "plot", "linear_range", "boundary_mc",
                  "summary", "to_dict", "to_frame", "save", "write", "to_transfer_functions",
                  "frequency_response_bounds", "uncertainty_weight", "sample",
                  "denominators_stable", "theta_of", "method_label", "from_csv", "to_csv",
                  "inverse", "compensate", "compensator", "error_bounds", "step", "refine")


def _own_method(cls, name):
    """The method ``name`` of ``cls`` defined in hammerbound (on the class or a base class
    of the package, not scikit-learn's), or None."""
    for base in cls.__mro__:
        meth = base.__dict__.get(name)
        if meth is not None:
            if isinstance(meth, (classmethod, staticmethod)):
                meth = getattr(cls, name)
            ok = callable(meth) and base.__module__.startswith("hammerbound")
            return meth if ok else None
    return None


def _sig(obj) -> str:
    try:
        return str(inspect.signature(obj))
    except (TypeError, ValueError):
        return "(...)"


def _doc(obj) -> str:
    return inspect.cleandoc(obj.__doc__ or "(undocumented)")


def render() -> str:
    import importlib

    out = ["# API reference", "",
           "Generated from the docstrings by `python docs/gen_api.py`; do not edit by hand.", ""]
    for modname, names in MODULES:
        mod = importlib.import_module(modname)
        if names is None:
            names = [n for n in getattr(mod, "__all__", []) if not n.startswith("__")]
        out += [f"## `{modname}`", ""]
        for name in names:
            obj = getattr(mod, name)
            if inspect.isclass(obj) and issubclass(obj, BaseException):
                out += [f"### `{name}`", "", f"Exception, bases: "
                        f"{', '.join(b.__name__ for b in obj.__mro__[1:-2])}.", "",
                        _doc(obj).split("\n\n")[0], ""]
                continue
            if inspect.isclass(obj) or inspect.isfunction(obj):
                kind = "class" if inspect.isclass(obj) else "def"
                out += [f"### `{name}`", "", "```text", f"{kind} {name}{_sig(obj)}", "```", "",
                        _doc(obj), ""]
                if inspect.isclass(obj):
                    for m in PUBLIC_METHODS:
                        meth = _own_method(obj, m)
                        if meth is not None:
                            out += [f"#### `{name}.{m}{_sig(meth)}`", "", _doc(meth), ""]
            else:
                out += [f"### `{name}`", "", f"`{obj!r}`"[:200], ""]
    return "\n".join(out).rstrip() + "\n"


if __name__ == "__main__":
    path = Path(__file__).with_name("api.md")
    path.write_text(render())
    print(f"wrote {path}")
