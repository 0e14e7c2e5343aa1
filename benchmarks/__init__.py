"""Benchmark suite of hammerbound (not part of the installed package); see README.md."""
