"""Shared helpers of the benchmark scripts: paths, timing, running one method, writing results."""

from __future__ import annotations

import csv
import json
import os
import platform
import sys
import threading
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results"
FIGURES = ROOT / "docs" / "figures"
REFERENCE = HERE / "reference" / "chapter22_tables.csv"

GAMMA_NAMES = ("ml", "cl", "mr", "cr")
THETA_NAMES = ("a1", "a2", "b1", "b2")

#: Method labels used throughout the suite -> keyword arguments of ``run_method``.
METHODS = {
    "lp": dict(method="lp"),
    "moment1": dict(method="moment", relaxation_order=1, solver="clarabel"),
    "moment1-cvxopt": dict(method="moment", relaxation_order=1, solver="cvxopt"),
    "moment2": dict(method="moment", relaxation_order=2, solver="clarabel"),
    "moment2-cvxopt": dict(method="moment", relaxation_order=2, solver="cvxopt"),
    "exact": dict(method="exact"),
    "lp-2level": dict(method="lp", inner_signal="two-level"),
    "moment1-2level": dict(method="moment", relaxation_order=1, inner_signal="two-level"),
    "exact-2level": dict(method="exact", inner_signal="two-level"),
}


class PeakRSS:
    """Peak resident memory (MB) of this process and its children, sampled in a thread."""

    def __init__(self, period=0.05):
        import psutil

        self.proc, self.period, self.peak = psutil.Process(), period, 0.0
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._run, daemon=True)

    def _rss(self):
        total = 0
        for p in [self.proc, *self.proc.children(recursive=True)]:
            try:
                total += p.memory_info().rss
            except Exception:  # noqa: BLE001 - a worker that just exited
                pass
        return total / 2**20

    def _run(self):
        while not self._stop.is_set():
            self.peak = max(self.peak, self._rss())
            time.sleep(self.period)

    def __enter__(self):
        self.base = self._rss()
        self._t.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._t.join()


def environment() -> dict:
    """Machine description stored next to every result (timings depend on it)."""
    import hammerbound

    try:
        load = os.getloadavg()
    except OSError:  # pragma: no cover
        load = (float("nan"),) * 3
    return {
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "cpu_count": os.cpu_count(),
        "loadavg_at_start": [round(v, 2) for v in load],
        "hammerbound": hammerbound.__version__,
        "numpy": np.__version__,
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
    }


def loadavg() -> float:
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:  # pragma: no cover
        return float("nan")


def chapter_stage2_problem(deta: float, N: int, inner: str):
    """The stage-2 EIV problem of the chapter example (seed 0) after stage 1 and the LP
    stage 2, with the inner signal ``inner`` ("independent" or "two-level")."""
    import hammerbound as hb

    ex = hb.chapter_example(deta, N=N, random_state=0)
    ident = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(deta), hb.LinearEIVSetEstimator(output_bound=deta, method="lp"),
        inner_signal=inner)
    ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    return ident.linear_.problem_


def run_method(example, label: str, *, n_jobs: int = 2, time_limit: float = 600.0,
               u=None, y=None, na: int = 2, nb: int = 2) -> dict:
    """Fit the two-stage identifier with the method ``label`` (a key of METHODS).

    Returns a flat dict: bounds, widths, times, iterations, statuses, coverage flags.
    Stage 1 is always the exact polygon method.
    """
    import hammerbound as hb

    opts = dict(METHODS[label])
    inner = opts.pop("inner_signal", "independent")
    bound = example.output_bound
    if opts["method"] == "lp":
        n_jobs = 1  # ~10 ms per LP: a process pool costs more than it saves
    lin = hb.LinearEIVSetEstimator(na=na, nb=nb, output_bound=bound, n_jobs=n_jobs,
                                   time_limit=time_limit, **opts)
    idf = hb.HammersteinBacklashIdentifier(backlash=hb.BacklashSetEstimator(bound), linear=lin,
                                           inner_signal=inner)
    u = example.prbs.u if u is None else u
    y = example.prbs.y if y is None else y
    t0 = time.perf_counter()
    idf.fit(u, y, steady_state=example.steady)
    wall = time.perf_counter() - t0
    infos = idf.linear_.bound_info_
    theta = np.asarray(example.theta_true, dtype=float)
    gamma = np.asarray(example.gamma_true, dtype=float)
    tb = idf.theta_bounds_
    gb = idf.gamma_bounds_
    iters = [i.iterations for i in infos if i.iterations is not None]
    nodes = [i.nodes for i in infos if i.nodes is not None]
    return {
        "method": label,
        "wall_s": wall,
        "bound_time_sum_s": float(sum(i.time for i in infos)),
        "bound_time_max_s": float(max(i.time for i in infos)),
        "iterations_sum": int(sum(iters)) if iters else None,
        "iterations_max": int(max(iters)) if iters else None,
        "nodes_sum": int(sum(nodes)) if nodes else None,
        "statuses": sorted({i.status for i in infos}),
        "all_certified": bool(all(i.certified for i in infos)),
        "theta_lower": tb[:, 0].tolist(),
        "theta_upper": tb[:, 1].tolist(),
        "theta_width": (tb[:, 1] - tb[:, 0]).tolist(),
        "gamma_lower": gb[:, 0].tolist(),
        "gamma_upper": gb[:, 1].tolist(),
        "theta_inside": bool(np.all((theta >= tb[:, 0]) & (theta <= tb[:, 1]))),
        "gamma_inside": bool(np.all((gamma >= gb[:, 0]) & (gamma <= gb[:, 1]))),
        "theta_true": theta.tolist(),
        "gamma_true": gamma.tolist(),
        "u_star": idf.u_star_,
        "x_hi": list(idf.inner_bounds_.x_hi),
        "x_lo": list(idf.inner_bounds_.x_lo),
        "box_limited": list(idf.linear_.box_limited_),
        "loadavg": loadavg(),
    }


def markdown_table(header, rows) -> str:
    """A Markdown table of ``rows`` (lists of cells) under ``header``."""
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def write_csv(rows: list[dict], path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    keys: list[str] = []
    for r in rows:
        for k in r:
            if k not in keys:
                keys.append(k)
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: _cell(r.get(k)) for k in keys})


def _cell(v):
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (list, tuple)):
        return ";".join(_cell(x) if isinstance(x, float) else str(x) for x in v)
    return "" if v is None else v


def write_json(obj, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as fh:
        json.dump(obj, fh, indent=1, default=_json_default)


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o))


def read_json(path: Path):
    with open(path) as fh:
        return json.load(fh)


def setup_matplotlib():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"figure.dpi": 110, "savefig.dpi": 110, "axes.grid": True,
                         "grid.alpha": 0.3, "font.size": 9})
    return plt


def log(msg: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", flush=True)
