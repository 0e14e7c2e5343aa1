"""Sparse moment (Lasserre) relaxations: the polynomial form and bases, the size guard and
the relaxation. Use :func:`hammerbound.relaxations.moment_bounds`."""

from .relaxation import moment_bounds

__all__ = ["moment_bounds"]
