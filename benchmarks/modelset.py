"""Issue 16 "done when": the model set on the chapter example and on the LRIC EIV data.

    python -m benchmarks.modelset            # full: chapter N = 300 (exact), 1000 samples
    python -m benchmarks.modelset --quick    # N = 100, 100 samples

For each data set: fit (exact method), draw certified samples and re-verify every one
with an independent LP (scipy linprog, equality form), build the frequency envelope at
512 frequencies and check it contains the response of all 2^p orthotope vertices and of
every sample, measure its width against the range over the vertices plus 1e5 random
orthotope points and against the range of the samples, fit and check the multiplicative
and additive weights; for the backlash, draw samples from the exact polygons and check
the compensator's error band on a dense command sequence. Timings of every feature.
Writes benchmarks/results/modelset.json and docs/figures/robust_*.png.
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
FIGURES = HERE.parent / "docs" / "figures"
# third-party record, read in place from ../shared/data/ beside the repository (not shipped)
LRIC = HERE.parent.parent / "shared" / "data" / "lric" / "eiv_first_order_2017.csv"


def own_feasible(theta, y, x, dx, deta, na, b_lags, tol=1e-8):
    """Independent feasibility LP at fixed theta (per-sample input errors), sparse."""
    import scipy.sparse as sp
    from scipy.optimize import linprog

    n = y.size
    a, b = theta[:na], theta[na:]
    n0 = max(na, max(b_lags))
    t = np.arange(n0, n)
    m = t.size
    rows, cols, vals = [np.arange(m)], [t], [np.ones(m)]
    rhs = y[t].copy()
    for i in range(1, na + 1):
        rows.append(np.arange(m))
        cols.append(t - i)
        vals.append(np.full(m, a[i - 1]))
        rhs += a[i - 1] * y[t - i]
    for k, j in enumerate(b_lags):
        rows.append(np.arange(m))
        cols.append(n + t - j)
        vals.append(np.full(m, -b[k]))
        rhs -= b[k] * x[t - j]
    M = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(m, 2 * n))
    A_eq = sp.hstack([M, -sp.eye(m), sp.eye(m)]).tocsr()
    c = np.concatenate([np.zeros(2 * n), np.ones(2 * m)])
    lb = np.concatenate([-np.broadcast_to(deta, n), -np.broadcast_to(dx, n), np.zeros(2 * m)])
    ub = np.concatenate([np.broadcast_to(deta, n), np.broadcast_to(dx, n), np.full(2 * m, np.inf)])
    res = linprog(c, A_eq=A_eq, b_eq=rhs, bounds=np.column_stack([lb, ub]), method="highs")
    return res.status == 0 and res.fun <= tol * (1 + np.max(np.abs(y)))


def responses(th, w, na, b_lags, dt):
    th = np.atleast_2d(th)
    za = np.exp(-1j * np.outer(w * dt, np.arange(1, na + 1)))
    zb = np.exp(-1j * np.outer(w * dt, b_lags))
    return (th[:, na:] @ zb.T) / (1 + th[:, :na] @ za.T)


def timed(f, repeat=1):
    ts, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        ts.append(time.perf_counter() - t0)
    return out, float(np.median(ts))


def linear_block(name, est, y, x, dx, dt, n_samples, rng):
    lags = est._b_lags()
    na = est.na
    rep = {"name": name, "p": int(est.bounds_.shape[0]), "bounds": est.bounds_.tolist()}
    S, rep["t_sample"] = timed(lambda: est.sample(n_samples, random_state=0))
    rep["n_samples"] = len(S)
    rep["sample_lps"] = S.n_lp
    ok, rep["t_own_lp_verify"] = timed(
        lambda: [own_feasible(th, y, x, dx, est.output_bound, na, lags) for th in S.theta])
    rep["samples_verified_by_own_lp"] = int(np.sum(ok))
    nyq = np.pi / dt
    w = np.logspace(np.log10(1e-3 * nyq), np.log10(nyq), 512)
    env, rep["t_envelope_512"] = timed(lambda: est.frequency_response_bounds(w, dt=dt), repeat=20)
    V = np.array(list(itertools.product(*est.bounds_)))
    Rn = rng.uniform(est.bounds_[:, 0], est.bounds_[:, 1], (100_000, len(est.bounds_)))
    GV = responses(V, w, na, lags, dt)
    GS = responses(S.theta, w, na, lags, dt)
    rep["envelope_contains_vertices"] = bool(env.contains(GV).all())
    rep["envelope_contains_samples"] = bool(env.contains(GS).all())
    mags = [np.abs(GV)]
    rel = [np.angle(GV / env.central)]
    for chunk in np.array_split(Rn, 10):
        G = responses(chunk, w, na, lags, dt)
        rep.setdefault("envelope_contains_random", True)
        rep["envelope_contains_random"] &= bool(env.contains(G).all())
        mags.append(np.abs(G))
        rel.append(np.angle(G / env.central))
    mags = np.vstack(mags)
    rel = np.vstack(rel)
    width = env.mag_upper - env.mag_lower
    r_box = width / np.ptp(mags, axis=0)
    r_smp = width / np.ptp(np.abs(GS), axis=0)
    rep["mag_width_ratio_to_box_points"] = {"max": float(r_box.max()), "median": float(np.median(r_box))}
    rep["mag_width_ratio_to_samples"] = {"max": float(r_smp.max()), "median": float(np.median(r_smp))}
    pw = env.phase_upper - env.phase_lower
    pr = np.ptp(rel, axis=0)
    sel = pr > 1e-9
    rep["phase_width_ratio_to_box_points"] = {"max": float(np.nanmax((pw / pr)[sel])),
                                              "median": float(np.nanmedian((pw / pr)[sel]))}
    rep["phase_bounded_everywhere"] = bool(env.phase_bounded.all())
    if est.steady_state_gain is not None:
        envg, rep["t_envelope_512_on_gain_plane"] = timed(
            lambda: est.frequency_response_bounds(w, dt=dt, on_gain_plane=True), repeat=3)
        rep["gain_plane_envelope_contains_samples"] = bool(envg.contains(GS).all())
        rg = (envg.mag_upper - envg.mag_lower) / np.ptp(np.abs(GS), axis=0)
        rep["gain_plane_mag_width_ratio_to_samples"] = {
            "max": float(rg.max()), "median": float(np.median(rg)),
            "median_above_0.1_nyquist": float(np.median(rg[w >= 0.1 * nyq]))}
        rep["mag_width_ratio_to_samples"]["median_above_0.1_nyquist"] = float(
            np.median(r_smp[w >= 0.1 * nyq]))
    wd = np.linspace(0, nyq, 4096)
    GVd = responses(V, wd, na, lags, dt)
    GSd = responses(S.theta, wd, na, lags, dt)
    G0d = responses(est.center_, wd, na, lags, dt)[0]
    for kind in ("multiplicative", "additive"):
        uw, t = timed(lambda kind=kind: est.uncertainty_weight(kind, dt=dt))
        Wd = np.abs(uw.W(np.exp(1j * wd * dt)))
        dev = (lambda G: np.abs(G / G0d - 1)) if kind == "multiplicative" else (lambda G: np.abs(G - G0d))
        rep[f"weight_{kind}"] = {
            "t_fit_and_certify": t, "certified": uw.certificate.holds,
            "certificate_min_ratio": uw.certificate.min_ratio,
            "bounds_vertices": bool(np.all(dev(GVd) <= Wd)),
            "bounds_samples": bool(np.all(dev(GSd) <= Wd)),
            "median_W_over_max_seen_deviation": float(np.median(
                Wd / np.maximum(np.max(dev(np.vstack([GVd, GSd])), axis=0), 1e-300))),
            "W": str(uw.W).split("\n", 4)[-1].strip(),
        }
        if est.steady_state_gain is None:
            continue
        # the weight on the gain plane: around its own central model, |W(1)| against the box's
        up, t = timed(lambda kind=kind: est.uncertainty_weight(kind, dt=dt, on_gain_plane=True))
        Wp = np.abs(up.W(np.exp(1j * wd * dt)))
        G0p = responses(est.theta_of(up.central), wd, na, lags, dt)[0]
        devp = np.abs(GSd / G0p - 1) if kind == "multiplicative" else np.abs(GSd - G0p)
        rep[f"weight_{kind}_on_gain_plane"] = {
            "t_fit_and_certify": t, "certified": up.certificate.holds,
            "bounds_samples": bool(np.all(devp <= Wp)),
            "W_at_0": float(Wp[0]), "box_W_at_0": float(Wd[0]),
            "median_W_over_max_seen_deviation": float(np.median(
                Wp / np.maximum(np.max(devp, axis=0), 1e-300))),
        }
    return rep, env, S


def main(argv=None):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import hammerbound as hb
    from benchmarks._common import environment

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--samples", type=int, default=None)
    args = ap.parse_args(argv)
    N = 100 if args.quick else 300
    ns = args.samples or (100 if args.quick else 1000)
    rng = np.random.default_rng(0)
    out = {"environment": environment(), "N": N, "n_samples": ns, "blocks": []}
    # ---------------------------------------------------------------- chapter example
    ex = hb.chapter_example(0.05, N=N, random_state=0)
    idf = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05), hb.LinearEIVSetEstimator(output_bound=0.05, method="exact"))
    _, t_fit = timed(lambda: idf.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady))
    rep, env, S = linear_block("chapter", idf.linear_, ex.prbs.y, idf.xc_, idf.dx_, 1.0, ns, rng)
    rep["t_fit"] = t_fit
    out["blocks"].append(rep)
    fig = env.plot(samples=responses(S.theta[:200], env.omega, 2, [1, 2], 1.0))
    fig.savefig(FIGURES / "robust_bode_envelope.png", dpi=110)
    plt.close(fig)
    # backlash
    bl = idf.backlash_
    B, t_bs = timed(lambda: bl.sample(ns, random_state=1))
    inv, t_inv = timed(lambda: bl.inverse())
    lo_v, hi_v = inv.v_range
    steps = rng.normal(0, 0.01 * (hi_v - lo_v), 20000)
    steps[rng.random(steps.size) < 0.1] = 0.0
    v = np.clip(np.cumsum(steps), lo_v, hi_v)
    v = np.concatenate([np.linspace(0, hi_v, 500), np.linspace(hi_v, lo_v, 1000), v])
    u, t_comp = timed(lambda: inv.compensate(v))
    lo, hi = inv.error_bounds(v)
    worst_out, worst_abs = 0.0, 0.0
    uu = u.tolist()
    for g in B.gamma:
        ml, cl, mr, cr = g
        x, xs = 0.0, np.empty(v.size)
        for t, ut in enumerate(uu):
            x = min(max(x, mr * (ut - cr)), ml * (ut + cl))
            xs[t] = x
        e = xs - v
        worst_out = max(worst_out, float(np.max(np.maximum(e - hi, lo - e))))
        worst_abs = max(worst_abs, float(np.max(np.abs(e))))
    out["backlash"] = {
        "t_sample": t_bs, "n_samples": len(B), "t_inverse": t_inv, "t_compensate": t_comp,
        "n_commands": int(v.size), "v_range": list(inv.v_range),
        "bound_holds_for_all_samples": worst_out <= 0.0,
        "max_excess_over_band": worst_out, "max_abs_error_seen": worst_abs,
        "max_guaranteed_bound": float(np.max(inv.error_bound(v))),
    }
    fig = inv.plot(samples=B.gamma[:30])
    fig.savefig(FIGURES / "robust_backlash_inverse.png", dpi=110)
    plt.close(fig)
    # ---------------------------------------------------------------- LRIC data
    if LRIC.exists():
        d = np.loadtxt(LRIC, delimiter=",", skiprows=1)
        u_l, y_l = d[:, 1], d[:, 2]
        est = hb.LinearEIVSetEstimator(1, 1, nk=0, output_bound=0.05, steady_state_gain=None,
                                       method="exact")
        _, t_fit = timed(lambda: est.fit(u_l, y_l, input_bound=0.05))
        rep, _, _ = linear_block("lric", est, y_l, u_l, 0.05, 0.1, ns, rng)
        rep["t_fit"] = t_fit
        out["blocks"].append(rep)
    RESULTS.mkdir(exist_ok=True)
    name = "modelset_quick.json" if args.quick else "modelset.json"
    (RESULTS / name).write_text(json.dumps(out, indent=1))
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
