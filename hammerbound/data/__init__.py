"""Data: :class:`IOData` (samples with a sampling time, names and units), the one CSV
reader, and the one validation of signals, bounds and scalar settings."""

from .csv_reader import read_io_csv
from .iodata import IOData

__all__ = ["IOData", "read_io_csv"]
