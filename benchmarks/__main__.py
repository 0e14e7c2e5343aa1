"""Command-line entry point of the benchmark suite.

    python -m benchmarks list
    python -m benchmarks stage1   [--quick] ...
    python -m benchmarks chapter  [--quick] ...
    python -m benchmarks methods  [--quick] [--part same|delta2|scaling|order] ...
    python -m benchmarks coverage [--quick] [--dask] ...
    python -m benchmarks moment2  [--N 10 20 50 100] [--full-N 10]
    python -m benchmarks default_method  # lp / moment / exact on the cases behind the default method
    python -m benchmarks weights                # certified uncertainty weights by order
    python -m benchmarks orders [--orders 2 3 4 5 6]  # LP time by model order, guard refusals
    python -m benchmarks lric                   # the LRIC exam record (../shared/data/lric/)
    python -m benchmarks units [--no-units]     # the same records in other units
    python -m benchmarks report                 # regenerate docs/benchmarks.md from results/
    python -m benchmarks all --quick            # every benchmark, then the report

Every sub-command forwards its remaining arguments to the script (``--help`` for each).
"""

from __future__ import annotations

import importlib
import sys

COMMANDS = {
    "stage1": "stage1_speed",
    "chapter": "chapter_tables",
    "methods": "methods",
    "moment2": "moment_order2",
    "default_method": "default_method",
    "coverage": "coverage",
    "weights": "weights",
    "orders": "lp_orders",
    "lric": "lric",
    "units": "units",
    "report": "report",
}


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help", "list"):
        print(__doc__)
        return 0
    cmd, rest = argv[0], argv[1:]
    if cmd == "all":
        for name in ("stage1", "chapter", "methods", "coverage"):
            importlib.import_module(f"benchmarks.{COMMANDS[name]}").main(rest)
        importlib.import_module("benchmarks.report").main([])
        return 0
    if cmd not in COMMANDS:
        print(f"unknown benchmark {cmd!r}; choose from {', '.join(COMMANDS)} or all", file=sys.stderr)
        return 2
    importlib.import_module(f"benchmarks.{COMMANDS[cmd]}").main(rest)
    return 0


if __name__ == "__main__":
    sys.exit(main())
