#!/usr/bin/env python3
"""Side by side: `tcomp fit` (bayes, 32 centers) against scikit-learn's KMeans + BayesianRidge
pipeline and its GaussianProcessRegressor, on the same simulated 6-hour 1 Hz RLG run (~22,000
rows), on one thread each. Issue 4's targets: tcomp >= 10x faster than KMeans + BayesianRidge at
equal or lower held-out residual, and within 10 % of the Gaussian process's held-out residual.

Usage, from the repository root:
    cargo run --release -p tcomp -- simulate --preset rlg --out /tmp/sim-rlg
    RAYON_NUM_THREADS=1 cargo run --release -p tcomp-train --example compare_rows -- /tmp/sim-rlg /tmp/cmp
    python3 scripts/sklearn_compare.py /tmp/cmp            # needs numpy, scikit-learn

Every fitter gets identical numbers: the four features (T = mean of three thermometers, rate(T),
two gradients) as the core's feature program computes them for every sample, and the error
gyro - reference, all written by the `compare_rows` example. Times are medians of repeated fits
from arrays in memory to fitted coefficients, with every library limited to one thread.
- "every sample": the pipeline as a scikit-learn user writes it, on all 22,000 rows.
- "tcomp's bins": the same pipeline on the 183 bin means (120 s) tcomp's `bayes` fits on.
- tcomp "to model": the feature program over all 22,000 rows, binning, and the evidence search
  over widths and length scales (27 evidence fits) — from arrays to coefficients, as the
  scikit-learn rows are timed. tcomp "whole fit": the `fit` call, which adds the blob and the
  training figures computed by running the decoded blob over the 22,000 rows.
Held-out figure: std of 100 s bin means of the residual on the verification profile.
"""
import json, os, sys, time
for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[v] = "1"
import numpy as np
from sklearn.cluster import KMeans
from sklearn.linear_model import BayesianRidge
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, WhiteKernel, ConstantKernel


def load(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def held_out(t, resid, s=100.0):
    k = np.floor((t - t[0]) / s).astype(int)
    step = np.median(np.diff(t))
    means = [resid[k == j].mean() for j in np.unique(k) if (k == j).sum() >= max(1, int(s / step * 0.5))]
    return float(np.std(means))


def kmeans_bayesridge(X, y):
    """The traditional pipeline: standardise, k-means centers, width d_max/sqrt(2M), BayesianRidge."""
    mu, sd = X.mean(0), X.std(0)
    Z = (X - mu) / sd
    c = KMeans(32, random_state=0).fit(Z).cluster_centers_
    dmax = max(np.linalg.norm(a - b) for a in c for b in c)
    s = dmax / np.sqrt(2 * len(c))
    phi = lambda X: np.exp(-((((X - mu) / sd)[:, None, :] - c[None]) ** 2).sum(-1) / (2 * s * s))
    br = BayesianRidge().fit(phi(X), y)
    return lambda X: br.predict(phi(X))


def gaussian_process(X, y):
    mu, sd = X.mean(0), X.std(0)
    kern = ConstantKernel() * RBF(np.ones(X.shape[1])) + WhiteKernel()
    gp = GaussianProcessRegressor(kern, normalize_y=True, random_state=0).fit((X - mu) / sd, y)
    return lambda X: gp.predict((X - mu) / sd)


def timed(fitter, X, y, reps):
    times, model = [], None
    for _ in range(reps):
        t0 = time.perf_counter()
        model = fitter(X, y)
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), model


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else "/tmp/cmp"
    tc = json.load(open(f"{d}/tcomp.json"))
    tr, ve, bi = load(f"{d}/train_rows.csv"), load(f"{d}/verify_rows.csv"), load(f"{d}/train_bins.csv")
    cols = ["f0", "f1", "f2", "f3"]
    Xtr = np.column_stack([tr[c] for c in cols]); ytr = tr["error"]
    Xve = np.column_stack([ve[c] for c in cols]); yve = ve["error"]
    Xb = np.column_stack([bi[c] for c in cols]); yb = bi["error"]
    raw = held_out(ve["time_s"], yve)
    rows = []
    for name, fitter, X, y, reps in [
        (f"KMeans+BayesianRidge, every sample ({len(ytr)} rows)", kmeans_bayesridge, Xtr, ytr, 5),
        (f"KMeans+BayesianRidge, tcomp's bins ({len(yb)} rows)", kmeans_bayesridge, Xb, yb, 11),
        (f"GaussianProcessRegressor, tcomp's bins ({len(yb)} rows)", gaussian_process, Xb, yb, 3),
    ]:
        t, model = timed(fitter, X, y, reps)
        rows.append({"method": name, "fit_s": t, "held_out": held_out(ve["time_s"], yve - model(Xve))})
    rows.append({"method": f"tcomp fit, bayes, 32 centers ({tc['rows']} rows -> {tc['bins']} bins)",
                 "fit_s": tc["fit_s"], "held_out": tc["held_out_100s_std"]})
    rows.append({"method": "  of which features + bins + evidence search",
                 "fit_s": tc["features_bins_search_s"], "held_out": tc["held_out_100s_std"]})
    print(f"verification run: raw error, std of 100 s bin means {raw:.5g} deg/h")
    # "to model": arrays in memory to fitted coefficients, what every scikit-learn row times;
    # "whole fit": tcomp's `fit` call, which also runs the decoded blob over the 22,000 training
    # rows for its training figures.
    core = tc["features_bins_search_s"]
    print(f"{'method':<58} {'fit s':>9} {'held-out':>10} {'/ tcomp to model':>17} {'/ tcomp whole fit':>18}")
    for r in rows:
        print(f"{r['method']:<58} {r['fit_s']:>9.4f} {r['held_out']:>10.5g} "
              f"{r['fit_s'] / core:>16.1f}x {r['fit_s'] / tc['fit_s']:>17.1f}x")
    gp = rows[2]["held_out"]
    print(f"tcomp held-out / Gaussian process held-out: {tc['held_out_100s_std'] / gp:.3f}")
    json.dump({"raw_held_out": raw, "rows": rows}, open(f"{d}/comparison.json", "w"), indent=1)


if __name__ == "__main__":
    main()
