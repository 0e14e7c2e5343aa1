"""Stage 2 (section 22.4): the linear block from errors-in-variables data, and the fitted
linear model (interval table, transfer function, predictions)."""

from .estimator import METHODS, LinearEIVSetEstimator

__all__ = ["LinearEIVSetEstimator", "METHODS"]
