"""Result objects shared by every layer: one interval-set type for every box
(:class:`IntervalSet`, with :class:`BoundInfo` per end), the one-step output band
(:class:`OutputEnvelope`) and the common ``summary``/``to_dict``/``plot(ax=None)``/``save``
shape (:class:`Result`). Statuses of interval ends: :mod:`hammerbound.status`."""

from .base import DeprecatedExtra, Result, jsonable, warn_plot_path
from .envelope import OutputEnvelope
from .intervals import BoundInfo, DualCertificate, IntervalSet, VerifiedPoint, outward_margin

__all__ = [
    "BoundInfo",
    "DeprecatedExtra",
    "DualCertificate",
    "IntervalSet",
    "OutputEnvelope",
    "Result",
    "VerifiedPoint",
    "jsonable",
    "outward_margin",
    "warn_plot_path",
]
