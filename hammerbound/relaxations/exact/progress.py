"""Progress of the exact method's interval ends on stderr (:class:`_GapBar`): a tqdm bar on
a terminal, plain lines otherwise. Stdout is never written."""

from __future__ import annotations

import time

import numpy as np

from ...terminal import is_terminal


class _GapBar:
    """Progress of one interval end: the fraction of its initial certified gap closed.

    The gap is "best verified value minus certified outer bound" (before a verified point
    exists, the width of the root box in ``theta_k`` stands for the value); the search is
    done when the gap is below ``tol``, so 100 % means done. On a terminal a tqdm bar whose
    postfix shows the gap, the nodes and the time left before the time limit stops the
    search; otherwise (a pipe, a file) plain lines without cursor codes: one every
    :data:`_LINE_EVERY` seconds and one when the end is done. The search gives its gaps in
    its own units (:mod:`..units`); ``unit`` converts them to the data's for display.
    """

    def __init__(self, label, position, gap0, stop_at, unit=1.0, t0=None):
        """``t0``: the :func:`time.perf_counter` time the end started (its first verified
        points and walk come before the bar; the times shown are the end's, as in
        ``bound_info_``: trial 13 saw 0.0 s on a line and 0.16 s in the report)."""
        import sys

        self.unit = float(unit)
        self.gap0 = max(float(gap0), 1e-300)
        self.stop_at = stop_at
        self.shown = 0.0
        self.label = label
        self.last = time.perf_counter()
        self.t0 = self.last if t0 is None else t0
        self.state = (0.0, float(gap0) * self.unit, 0)
        self.bar = None
        self.verified = True
        if is_terminal(sys.stderr):
            from tqdm.auto import tqdm

            self.bar = tqdm(total=100.0, position=position, leave=False, desc=label,
                            bar_format="{desc}: {percentage:3.0f}% of gap closed |{bar}| "
                                       "{elapsed} {postfix}")

    def update(self, gap, target, nodes, verified=True):
        """``gap``: value minus bound, or without a verified point (``verified`` False) the
        width of the box above the bound, which stands for it."""
        gap = max(float(gap), 0.0)
        done = 1.0 - max(gap - target, 0.0) / max(self.gap0 - target, 1e-300)
        pct = 100.0 * min(max(done, 0.0), 1.0)
        self.state = (pct, gap * self.unit, nodes)
        self.verified = bool(verified)
        if self.bar is None:
            if time.perf_counter() - self.last >= _LINE_EVERY:
                self._line("searching")
            return
        left = self.stop_at - time.perf_counter()
        gap_text = self._gap_text(gap * self.unit)
        self.bar.set_postfix_str(f"{gap_text}, {nodes} nodes, stops within {max(left, 0):.0f} s"
                                 if np.isfinite(left) else f"{gap_text}, {nodes} nodes",
                                 refresh=False)
        if pct > self.shown:
            self.bar.update(pct - self.shown)
            self.shown = pct
        else:
            self.bar.update(0)

    def _gap_text(self, gap) -> str:
        if self.verified:
            return f"gap {gap:.3g}"
        return f"no verified point yet (box width {gap:.3g} above the bound)"

    def _line(self, what):
        import sys

        pct, gap, nodes = self.state
        self.last = time.perf_counter()
        print(f"exact {self.label}: {what}, {pct:.0f}% of gap closed, {self._gap_text(gap)}, "
              f"{nodes} nodes, {self.last - self.t0:.1f} s", file=sys.stderr, flush=True)

    def close(self, outcome="finished"):
        """End the display; ``outcome`` says how the end's search ended ("finished" with
        its gap within the tolerance, or e.g. "stopped by the time limit (time_limit)"),
        shown in line mode."""
        if self.bar is None:
            self._line(outcome)
        else:
            self.bar.close()


#: seconds between progress lines of an interval end when stderr is not a terminal
_LINE_EVERY = 10.0


