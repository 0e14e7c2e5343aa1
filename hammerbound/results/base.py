"""The shape every result shares: ``summary()``, ``to_dict()``, ``plot(ax=None)``, ``save(path)``.

* ``summary()`` returns text for a person;
* ``to_dict()`` returns plain JSON-serialisable data (numbers, strings, lists; a
  non-finite number becomes ``None``);
* ``plot(ax=None, **kwargs)`` draws into ``ax`` (an Axes; for a figure of several panels a
  sequence of Axes) or into a new figure, and returns the **Axes** for a one-panel figure,
  the **Figure** for a figure of several panels;
* ``save(path, **kwargs)`` draws a new figure with ``plot(**kwargs)``, writes it to
  ``path`` (format from the suffix) and closes it.

Results are frozen: nothing changes a result after it is built.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .._compat import REMOVAL

__all__ = ["DeprecatedExtra", "Result", "jsonable", "warn_plot_path"]


def jsonable(obj):
    """``obj`` with arrays as lists, numpy scalars as Python numbers, NaN/inf as ``None``."""
    if isinstance(obj, Mapping):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if np.isfinite(obj) else None
    return obj


def _figure(drawn):
    """The Figure of what ``plot`` returned (an Axes or a Figure)."""
    return drawn if hasattr(drawn, "savefig") else drawn.figure


def _short(value) -> str:
    """A field's value in a result's repr: arrays by shape, other objects by type."""
    if isinstance(value, np.ndarray):
        return f"<array {value.shape}>" if value.size > 6 else repr(value.tolist())
    if value is None or isinstance(value, (bool, int, float, str, np.number)):
        return repr(value)
    if isinstance(value, tuple) and len(value) <= 6 and all(
            isinstance(v, (bool, int, float, str, np.number)) for v in value):
        return repr(value)
    return f"<{type(value).__name__}>"


class Result:
    """Mixin of the common result shape (see the module docstring)."""

    def __repr__(self) -> str:
        """One line: the class and its fields, arrays by shape (new-user trial 16: the
        dataclass repr of an UncertaintyWeight printed thousands of numbers)."""
        from dataclasses import fields, is_dataclass

        if not is_dataclass(self):
            return object.__repr__(self)
        shown = ", ".join(f"{f.name}={_short(getattr(self, f.name))}" for f in fields(self)
                          if f.repr)
        return f"{type(self).__name__}({shown})"

    def save(self, path, *, dpi: int = 110, **plot_kwargs) -> Path:
        """Draw :meth:`plot` ``(**plot_kwargs)`` in a new figure, write it to ``path``, close it.

        Returns
        -------
        pathlib.Path
            The path written.
        """
        import matplotlib.pyplot as plt

        fig = _figure(self.plot(**plot_kwargs))
        try:
            fig.savefig(path, dpi=dpi)
        finally:
            plt.close(fig)
        return Path(path)


def warn_plot_path(owner: str, stacklevel: int = 3) -> None:
    """DeprecationWarning for the old ``plot(path)``: use ``save(path)``."""
    warnings.warn(f"{owner}.plot(path) is deprecated and will be removed in {REMOVAL}: "
                  f"plot(ax=None) draws (and returns the figure), {owner}.save(path) writes "
                  "a file.", DeprecationWarning, stacklevel=stacklevel)


class DeprecatedExtra(Mapping):
    """The old string-keyed ``extra`` dict of a result, read-only, warning on every read.

    Each key maps to the typed attribute that replaces it (named in the warning).
    """

    def __init__(self, owner: str, values: dict, replacements: dict):
        self._owner = owner
        self._values = dict(values)
        self._replacements = dict(replacements)

    def _warn(self, key):
        new = self._replacements.get(key, "the typed attributes")
        warnings.warn(f"{self._owner}.extra[{key!r}] is deprecated and will be removed in "
                      f"{REMOVAL}; use {new} instead.", DeprecationWarning, stacklevel=3)

    def __getitem__(self, key):
        self._warn(key)
        return self._values[key]

    def get(self, key, default=None):
        self._warn(key)
        return self._values.get(key, default)

    def __contains__(self, key):
        return key in self._values

    def __iter__(self):
        return iter(self._values)

    def __len__(self):
        return len(self._values)

    def __repr__(self):
        return f"DeprecatedExtra({sorted(self._values)})"
