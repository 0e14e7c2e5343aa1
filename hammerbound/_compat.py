"""Old module paths (before the layout of 0.2.0), kept importable with a DeprecationWarning.

``import hammerbound.eiv`` still works and gives :mod:`hammerbound.stage2.estimator`; the
old paths are removed in 0.3.0 (see CHANGELOG.md). The public top-level names
(``hammerbound.LinearEIVSetEstimator`` ...) are not affected.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings

REMOVAL = "0.3.0"
#: old module (under ``hammerbound.``) -> new module
MOVED = {
    "backlash": "stage1.estimator",
    "feasible_set": "stage1.feasible_set",
    "side_polygon": "stage1.side_polygon",
    "eiv": "stage2.estimator",
    "linear_model": "stage2.linear_model",
    "experiments": "systems.experiments",
    "iodata": "data.iodata",
    "io": "data.csv_reader",
    "validation": "data.validation",
    "chapter": "app.chapter",
    "cli": "app.cli",
    "cli_paths": "app.paths",
    "report": "app.report",
    "solvers.clarabel_picos": "solvers.clarabel",
}


class _MovedModule(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``hammerbound.<old>`` and hands out the module at its new path."""

    def __init__(self):
        self._specs = {}

    def find_spec(self, fullname, path=None, target=None):
        prefix = "hammerbound."
        if not fullname.startswith(prefix) or fullname[len(prefix):] not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec):
        new = "hammerbound." + MOVED[spec.name[len("hammerbound."):]]
        warnings.warn(f"{spec.name} is deprecated and will be removed in {REMOVAL}; import "
                      f"{new} (or the top-level hammerbound names) instead.",
                      DeprecationWarning, stacklevel=2)
        module = importlib.import_module(new)
        self._specs[spec.name] = module.__spec__
        return module

    def exec_module(self, module):
        # the module at the new path is already executed; the import system has just set
        # its __spec__ to the old path's: give it back its own (relative imports inside
        # functions read it)
        module.__spec__ = self._specs.pop(module.__spec__.name, module.__spec__)


def install() -> None:
    """Put the finder on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _MovedModule) for f in sys.meta_path):
        sys.meta_path.append(_MovedModule())


# ---------------------------------------------------------------------------------------
# renamed parameters (one name per concept, issue 27.3)
# ---------------------------------------------------------------------------------------
#: default of a deprecated constructor parameter (scikit-learn's convention)
DEPRECATED = "deprecated"


def warn_renamed(old: str, new: str, *, stacklevel: int = 2) -> None:
    """FutureWarning: ``old`` is deprecated, removed in :data:`REMOVAL`; use ``new``."""
    warnings.warn(f"{old} is deprecated and will be removed in {REMOVAL}; use {new} instead.",
                  FutureWarning, stacklevel=stacklevel + 1)


def is_given(value) -> bool:
    """Whether a deprecated parameter was set (its value is not the sentinel)."""
    return not (isinstance(value, str) and value == DEPRECATED)


def renamed_value(owner: str, new: str, new_value, old: str, old_value, *,
                  unset=None, stacklevel: int = 3):
    """The value of parameter ``new``, taking the deprecated ``old`` into account.

    ``old_value`` is the sentinel :data:`DEPRECATED` when not given; otherwise a
    FutureWarning names ``new``, and giving both raises ParameterValidationError.
    """
    if not is_given(old_value):
        return new_value
    warn_renamed(f"{owner}({old}=...)", f"{new}=...", stacklevel=stacklevel)
    if new_value is not unset:
        from .exceptions import ParameterValidationError

        raise ParameterValidationError(
            f"{owner} got both {old}= (deprecated) and {new}=; pass only {new}=.")
    return old_value
