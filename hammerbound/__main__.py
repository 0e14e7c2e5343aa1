"""``python -m hammerbound``: the command line (same as the ``hammerbound`` script)."""

import sys

from .cli import main

sys.exit(main())
