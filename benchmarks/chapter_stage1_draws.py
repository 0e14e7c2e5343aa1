"""Stage 1 over many noise draws: how often does our inner-signal radius reach the chapter's?

For each noise level and square-wave amplitude design, fit the exact stage 1 on ``--draws``
independent noise realisations (M = 50, uniform noise, the chapter's backlash) and compare
the inner-signal radius dx at u* = 1 with the radius implied by the chapter's Table 22.1
(:func:`hammerbound.app.chapter.chapter_inner_bounds`). Also records where seed 0 falls among the
draws (inner radius and transient SNR of the N = 100 PRBS).

    python benchmarks/chapter_stage1_draws.py --draws 100 --levels 0.05 0.3
    # -> results/chapter_stage1_draws.json
"""

from __future__ import annotations

import argparse

import numpy as np

try:
    from benchmarks import _common as C
except ImportError:  # run as a script
    import _common as C

import hammerbound as hb
from hammerbound.app.chapter import chapter_inner_bounds
from hammerbound.systems.experiments import CHAPTER_AMPLITUDES, CHAPTER_U_STAR, chapter_example

DESIGNS = {
    "ours [0.25, 2.5]": CHAPTER_AMPLITUDES,
    "near u* [0.25, 1.5]": np.linspace(0.25, 1.5, 50),
    "large [1.0, 2.8]": np.linspace(1.0, 2.8, 50),
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=100)
    ap.add_argument("--levels", type=float, nargs="+", default=[0.05, 0.3])
    args = ap.parse_args(argv)
    rows = []
    for lvl in args.levels:
        ch = chapter_inner_bounds(lvl, CHAPTER_U_STAR)
        snr = np.array([chapter_example(lvl, N=100, random_state=s).prbs.snr_db
                        for s in range(args.draws)])
        for name, amps in DESIGNS.items():
            dx = np.full((args.draws, 2), np.nan)
            for s in range(args.draws):
                ex = chapter_example(lvl, N=10, amplitudes=amps, random_state=s)
                bl = hb.BacklashSetEstimator(lvl).fit(ex.steady.u, ex.steady.y)
                dx[s] = bl.inner_signal_bounds(CHAPTER_U_STAR).radius
            reach = np.all(dx <= np.asarray(ch.radius), axis=1)
            row = {"delta_eta": lvl, "design": name, "amplitudes": [float(amps.min()),
                                                                    float(amps.max())],
                   "draws": args.draws,
                   "chapter_dx": list(ch.radius),
                   "dx_hi_median": float(np.median(dx[:, 0])),
                   "dx_lo_median": float(np.median(dx[:, 1])),
                   "dx_hi_p10": float(np.percentile(dx[:, 0], 10)),
                   "dx_lo_p10": float(np.percentile(dx[:, 1], 10)),
                   "dx_hi_min": float(dx[:, 0].min()), "dx_lo_min": float(dx[:, 1].min()),
                   "draws_reaching_chapter_dx": int(reach.sum()),
                   "seed0_dx": dx[0].tolist(),
                   "seed0_dx_lo_percentile": float(100 * np.mean(dx[:, 1] <= dx[0, 1])),
                   "seed0_dx_hi_percentile": float(100 * np.mean(dx[:, 0] <= dx[0, 0])),
                   "snr_median_db": float(np.median(snr)),
                   "seed0_snr_db": float(snr[0]),
                   "seed0_snr_percentile": float(100 * np.mean(snr <= snr[0]))}
            rows.append(row)
            C.log(f"deta={lvl} {name}: dx median ({row['dx_hi_median']:.5f}, "
                  f"{row['dx_lo_median']:.5f}) min ({row['dx_hi_min']:.5f}, "
                  f"{row['dx_lo_min']:.5f}) chapter ({ch.radius[0]:.5f}, {ch.radius[1]:.5f}); "
                  f"draws reaching the chapter's dx: {row['draws_reaching_chapter_dx']}/"
                  f"{args.draws}; seed 0 dx percentiles hi {row['seed0_dx_hi_percentile']:.0f} "
                  f"lo {row['seed0_dx_lo_percentile']:.0f}, SNR percentile "
                  f"{row['seed0_snr_percentile']:.0f}")
    C.write_json({"environment": C.environment(), "args": vars(args), "rows": rows},
                 C.RESULTS / "chapter_stage1_draws.json")


if __name__ == "__main__":
    main()
