"""Progress of a diagnosis on stderr (``diagnose(..., progress=True)``, ``--progress``).

What is shown is what is known: the stage of the search, the model classes (single
candidates, combinations) fitted in it out of those planned, the class being fitted now
and the minimax LPs solved so far. The number of LPs a class needs is not known in
advance (grid searches refine until they converge), so LPs are counted, not predicted;
the screening of combinations stops at the first consistent one, so its bar may end early
(it says so). On a terminal each stage is a tqdm bar; when stderr is not a terminal (a
pipe, a file, a notebook) plain lines are written instead - one per fitted class and a
heartbeat line during long fits - without cursor codes. Nothing goes to stdout.
"""

from __future__ import annotations

import sys
import time

from ..terminal import is_terminal

__all__ = ["SearchProgress"]

#: Seconds between heartbeat lines during a long fit (line mode).
HEARTBEAT = 10.0


class SearchProgress:
    """Stage bars (terminal) or lines (otherwise) on ``file`` (default ``sys.stderr``)."""

    def __init__(self, enabled: bool, file=None):
        self.enabled = bool(enabled)
        self.file = sys.stderr if file is None else file
        self.bars = self.enabled and is_terminal(self.file)
        self.t0 = time.perf_counter()
        self.n_lps = 0
        self.bar = None
        self.stage_name, self.total, self.count, self.current = "", 0, 0, ""
        self.last_line = self.t0

    # ------------------------------------------------------------------ stages
    def stage(self, name: str, total: int) -> None:
        """Start a stage of ``total`` model classes (closing the previous one)."""
        if not self.enabled:
            return
        self.close()
        self.stage_name, self.total, self.count, self.current = name, int(total), 0, ""
        if self.bars:
            from tqdm.auto import tqdm

            self.bar = tqdm(total=self.total, desc=f"diagnose: {name}", file=self.file,
                            leave=False, unit="class", dynamic_ncols=True)

    def start(self, name: str) -> None:
        """The class ``name`` is being fitted now."""
        if not self.enabled:
            return
        self.current = name
        self._postfix()

    def lp(self) -> None:
        """One minimax LP solved."""
        if not self.enabled:
            return
        self.n_lps += 1
        if self.bar is not None:
            self._postfix()
        elif time.perf_counter() - self.last_line >= HEARTBEAT:
            self._line(f"{self.stage_name}: fitting {self.current} ...")

    def done(self, name: str, error: float, consistent: bool) -> None:
        """The class ``name`` was fitted: minimax ``error``, ``consistent`` or not."""
        if not self.enabled:
            return
        self.count += 1
        verdict = "consistent" if consistent else "not consistent"
        if self.bar is not None:
            self.bar.update(1)
            self._postfix()
            self.bar.refresh()  # every finished class is drawn, however fast it was
        else:
            self._line(f"{self.stage_name} {self.count}/{self.total}: {name}: error "
                       f"{error:.4g} ({verdict})")

    def end_early(self, why: str) -> None:
        """The stage stops before its planned total (e.g. a consistent pair was found)."""
        if not self.enabled or self.count >= self.total:
            return
        if self.bar is not None:
            self.bar.set_description_str(f"diagnose: {self.stage_name} (stopped: {why})")
        else:
            self._line(f"{self.stage_name}: stopped after {self.count}/{self.total}: {why}")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    # ------------------------------------------------------------------ output
    def _postfix(self) -> None:
        if self.bar is not None:
            self.bar.set_postfix_str(f"{self.current}, {self.n_lps} LPs", refresh=False)
            self.bar.update(0)

    def _line(self, text: str) -> None:
        now = time.perf_counter()
        self.last_line = now
        print(f"diagnose: {text} [{self.n_lps} LPs, {now - self.t0:.1f} s]",
              file=self.file, flush=True)
