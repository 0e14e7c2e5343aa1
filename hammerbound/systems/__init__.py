"""The systems: the backlash (22.1)-(22.2), the Hammerstein system (22.3)-(22.4), their
simulation, and the chapter's experiments (square waves, PRBS, bounded noise)."""

from .experiments import (
    ChapterExample,
    EIVExample,
    PRBSData,
    SteadyStateData,
    chapter_example,
    chapter_system,
    eiv_example,
    prbs,
    prbs_experiment,
    snr_db,
    square_wave_experiment,
    uniform_noise,
)
from .models import (
    GAMMA_NAMES,
    Backlash,
    HammersteinSystem,
    as_polynomials,
    normalize_gain,
    simulate_backlash,
    steady_state_gain,
)
from .records import INPUTS, OrdinaryRecord, ordinary_record, random_steps

__all__ = [
    "GAMMA_NAMES",
    "INPUTS",
    "OrdinaryRecord",
    "ordinary_record",
    "random_steps",
    "Backlash",
    "ChapterExample",
    "EIVExample",
    "HammersteinSystem",
    "PRBSData",
    "SteadyStateData",
    "as_polynomials",
    "chapter_example",
    "chapter_system",
    "eiv_example",
    "normalize_gain",
    "prbs",
    "prbs_experiment",
    "simulate_backlash",
    "snr_db",
    "square_wave_experiment",
    "steady_state_gain",
    "uniform_noise",
]
