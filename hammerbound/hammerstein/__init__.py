"""The identifier of the whole backlash-Hammerstein system (stage 1 and stage 2 composed)."""

from .identifier import HammersteinBacklashIdentifier

__all__ = ["HammersteinBacklashIdentifier"]
