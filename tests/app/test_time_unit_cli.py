"""The time unit of a CSV's time column goes with every dt the command line and the
summaries print (new-user trial: a ``time (ms)`` column gave ``dt = 100`` without its
unit, read by python-control as seconds)."""

from __future__ import annotations

import json

import numpy as np
from oracles import play
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.app.cli import main


def _csv(tmp_path):
    """Own simulation of 0.5 q^-1 / (1 - 0.5 q^-1), sampled every 100 ms."""
    rng = np.random.default_rng(0)
    x = np.repeat(rng.uniform(-1, 1, 15), 4)
    y = lfilter([0.0, 0.5], [1.0, -0.5], x) + rng.uniform(-0.02, 0.02, x.size)
    path = tmp_path / "ms.csv"
    path.write_text("time (ms),u,y\n" + "".join(
        f"{100 * i},{a:.17g},{b:.17g}\n" for i, (a, b) in enumerate(zip(x, y, strict=True))))
    return path


ARGS = ["--na", "1", "--nb", "1", "--output-bound", "0.02", "--method", "lp"]


def test_the_text_says_the_unit(tmp_path, capsys):
    assert main(["eiv", str(_csv(tmp_path)), *ARGS]) == 0
    out = capsys.readouterr().out
    assert "N = 60, dt = 100 ms, input 'u'" in out
    assert "nk=1, N = 60, dt = 100 ms, no gain constraint" in out
    assert out.rstrip().endswith("dt = 100 ms")  # the central model's line


def test_the_json_says_the_unit(tmp_path, capsys):
    assert main(["eiv", str(_csv(tmp_path)), *ARGS, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["data"]["dt"] == 100 and out["data"]["time_unit"] == "ms"
    assert out["transfer_function"]["dt"] == 100
    assert out["transfer_function"]["time_unit"] == "ms"


def test_the_identifier_summary_says_the_unit(tmp_path):
    data = hb.IOData.from_csv(_csv(tmp_path))
    assert data.time_unit == "ms"
    rng = np.random.default_rng(1)
    u = np.repeat(rng.uniform(-2, 2, 12), 5)
    y = lfilter([0.0, 0.5], [1.0, -0.5], play(u, 1.0, 0.1, 1.0, 0.1))
    rec = hb.IOData(u, y + rng.uniform(-0.01, 0.01, u.size), dt=100, time_unit="ms")
    est = hb.HammersteinBacklashIdentifier(linear=hb.LinearEIVSetEstimator(
        na=1, nb=1, output_bound=0.01, method="lp"), procedure="one-record").fit(rec)
    assert "N = 60, dt = 100 ms" in est.summary().splitlines()[0]
