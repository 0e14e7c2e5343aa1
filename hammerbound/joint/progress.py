"""Progress of a one-record fit on stderr (``LinearEIVSetEstimator(progress=True)``,
``hammerbound identify --record ... --progress``). Stdout is never written.

What is shown is what is known: the partition of the backlash box goes generation by
generation, and how many parts a generation keeps is known only when it is done, so its
lines count parts (tightened, certified empty, kept); the leaves and the interval ends are
known in number, so they count to that number. On a terminal the counted stages are tqdm
bars; otherwise (a pipe, a file, a notebook) one plain line per event, without cursor
codes.
"""

from __future__ import annotations

import sys
import time

from ..terminal import is_terminal

__all__ = ["PROGRESS_EVERY", "RecordProgress"]

#: seconds between two progress lines of a stage's items when not on a terminal
PROGRESS_EVERY = 5.0


class RecordProgress:
    """Stage lines and counted bars on ``file`` (default ``sys.stderr``); silent when not
    ``enabled``."""

    def __init__(self, enabled: bool, file=None):
        self.enabled = bool(enabled)
        self.file = sys.stderr if file is None else file
        self.bars = self.enabled and is_terminal(self.file)
        self.t0 = time.perf_counter()
        self.bar = None
        self.name, self.total, self.count = "", 0, 0
        self.every, self.last, self.last_line = 0.0, True, self.t0

    def line(self, text: str) -> None:
        """One line: ``one-record: <text> [<seconds since the start> s]``."""
        if self.enabled:
            self.last_line = time.perf_counter()
            print(f"one-record: {text} [{self.last_line - self.t0:.1f} s]",
                  file=self.file, flush=True)

    def start(self, name: str, total: int, *, every: float = 0.0, last: bool = True) -> None:
        """A stage of ``total`` items (closing the previous one). In line mode an item's
        line is written only ``every`` seconds after the last line (the stage's last item
        always, unless not ``last``: a summary line follows then): a generation of the
        partition ran 91 s without a word, and 71 leaves cut by the deadline took 71 lines
        in the same instant (new-user trial 20)."""
        if not self.enabled:
            return
        self.close()
        self.name, self.total, self.count = name, int(total), 0
        self.every, self.last = float(every), bool(last)
        if self.bars:
            from tqdm.auto import tqdm

            self.bar = tqdm(total=self.total, desc=f"one-record: {name}", file=self.file,
                            leave=False, dynamic_ncols=True)

    def done(self, what: str = "") -> None:
        """One item of the stage is done (``what``: its outcome, shown in line mode)."""
        if not self.enabled:
            return
        self.count += 1
        if self.bar is not None:
            self.bar.update(1)
            return
        final = self.count >= self.total
        due = time.perf_counter() - self.last_line >= self.every
        if (final and self.last) or (due and not final):
            self.line(f"{self.name} {self.count}/{self.total}" + (f": {what}" if what else ""))

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
