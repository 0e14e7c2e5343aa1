"""The ``hammerbound`` command line: one module per subcommand (:mod:`.demo`,
:mod:`.identify`, :mod:`.eiv`, :mod:`.benchmark`, :mod:`.diagnose`), the options they share
(:mod:`.options`), what they print alike (:mod:`.printing`) and how warnings, errors and
progress reach stderr (:mod:`.console`). The entry point is :func:`main`
(``hammerbound = "hammerbound.app.cli:main"``; also ``python -m hammerbound``)."""

from .diagnose import diagnose_cli_main
from .main import build_parser, main

__all__ = ["build_parser", "diagnose_cli_main", "main"]
