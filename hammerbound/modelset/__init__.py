"""From a parameter box to a guaranteed model set engineers can design with.

* :mod:`.sampling` - certified samples of the EIV set and of the backlash polygons;
* :mod:`.frequency` - guaranteed frequency-response envelope (exact zonotope value sets);
* :mod:`.uncertainty` - certified multiplicative / additive uncertainty weights;
* :mod:`.gain_plane` - bounds of the models on the gain plane (22.8), exact at steady state;
* :mod:`.compensation` - backlash inverse with a guaranteed residual error band;
* :mod:`.plots` - Bode envelope and compensation figures.

The estimators expose these as methods (``LinearEIVSetEstimator.sample``,
``.frequency_response_bounds``, ``.uncertainty_weight``, ``BacklashSetEstimator.sample``,
``.inverse``); see ``docs/robust-control.md``.
"""

from .compensation import BacklashCompensator, BacklashInverse
from .frequency import FrequencyEnvelope, denominators_stable
from .sampling import BacklashSamples, CertifiedSamples
from .uncertainty import UncertaintyWeight, WeightCertificate

__all__ = ["BacklashCompensator", "BacklashInverse", "BacklashSamples", "CertifiedSamples",
           "FrequencyEnvelope", "UncertaintyWeight", "WeightCertificate", "denominators_stable"]
