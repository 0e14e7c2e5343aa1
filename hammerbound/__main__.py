"""``python -m hammerbound``: the command line (same as the ``hammerbound`` script)."""

import sys

from .app.cli import main

sys.exit(main())
