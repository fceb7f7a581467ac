#!/usr/bin/env python3
"""Side-by-side fit time and held-out residual: `tcomp fit` (bayes, 32 centers) vs scikit-learn's
KMeans + BayesianRidge pipeline and GaussianProcessRegressor, on the same simulated 6-hour 1 Hz RLG
run (~22,000 rows). Held-out figure: std of 100 s bin means of the residual on the verification run.

Usage (from the repository root, after `cargo build --release -p tcomp`):
    tcomp simulate --preset rlg --out /tmp/sim-rlg
    python3 scripts/sklearn_compare.py /tmp/sim-rlg [path/to/tcomp]
Needs numpy, pandas, scikit-learn. scikit-learn models get the same features the core computes
(T, rate(T) with the core's cascaded-lag definition, the two gradients), as 30 s bin means for
training, and the same single-thread budget (OMP/MKL threads = 1).
"""
import json, os, subprocess, sys, time
os.environ.setdefault("OMP_NUM_THREADS", "1")
import numpy as np, pandas as pd
from sklearn.cluster import KMeans
from sklearn.linear_model import BayesianRidge
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, WhiteKernel, ConstantKernel

def rate(x, dt=1.0, w=60.0):
    tau = w / 2; d = np.exp(-dt / tau); gain = 60 * (np.exp(dt / tau) - 1) / dt
    # the core's definition: two cascaded lags, tau = w/2, scaled to units per minute
    l1 = np.empty_like(x); l2 = np.empty_like(x); l1[0] = l2[0] = x[0]; c = 1 - d
    for i in range(1, len(x)):
        l1[i] = l1[i-1] + c * (x[i] - l1[i-1]); l2[i] = l2[i-1] + c * (l1[i] - l2[i-1])
    return gain * (l1 - l2)

def features(df):
    T = (df.t_anode_c + df.t_cathode_c + df.t_shell_c).values / 3
    return np.column_stack([T, rate(T), (df.t_anode_c - df.t_shell_c).values, (df.t_cathode_c - df.t_shell_c).values])

def bins(t, v, s):
    k = np.floor((t - t[0]) / s).astype(int)
    return np.array([v[k == j].mean(axis=0) for j in np.unique(k)])

def main():
    d = sys.argv[1]; tcomp = sys.argv[2] if len(sys.argv) > 2 else "target/release/tcomp"
    tr = pd.read_csv(f"{d}/train.csv"); ve = pd.read_csv(f"{d}/verify.csv")
    Xtr, Xve = features(tr), features(ve)
    ytr = (tr.gyro_dph - tr.ref_dph).values; yve = (ve.gyro_dph - ve.ref_dph).values
    Xb, yb = bins(tr.time_s.values, Xtr, 30.0), bins(tr.time_s.values, ytr, 30.0)
    mu, sd = Xb.mean(0), Xb.std(0)
    z = lambda X: (X - mu) / sd
    held = lambda pred: bins(ve.time_s.values, yve - pred, 100.0).std()
    rows = []
    t0 = time.perf_counter()
    km = KMeans(32, n_init=10, random_state=0).fit(z(Xb))
    c = km.cluster_centers_; dmax = max(np.linalg.norm(a - b) for a in c for b in c); s = dmax / np.sqrt(64)
    phi = lambda X: np.exp(-((z(X)[:, None, :] - c[None]) ** 2).sum(-1) / (2 * s * s))
    br = BayesianRidge().fit(phi(Xb), yb)
    rows.append(("sklearn KMeans+BayesianRidge", time.perf_counter() - t0, held(br.predict(phi(Xve)))))
    t0 = time.perf_counter()
    gp = GaussianProcessRegressor(ConstantKernel() * RBF(np.ones(4)) + WhiteKernel(), normalize_y=True).fit(z(Xb), yb)
    rows.append(("sklearn GaussianProcessRegressor", time.perf_counter() - t0, held(gp.predict(z(Xve)))))
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    args = [tcomp, "fit", "--data", f"{d}/train.csv", "--reference", "ref_dph", "--target", "gyro_dph",
            "--signal", "T=mean(t_anode_c, t_cathode_c, t_shell_c)", "--feature", "T", "--feature", "rate(T)",
            "--feature", "t_anode_c - t_shell_c", "--feature", "t_cathode_c - t_shell_c",
            "--average", "30", "--centers", "32", "--out", "/tmp/cmp.tcm", "--quiet"]
    t0 = time.perf_counter(); subprocess.run(args, check=True, env=env, capture_output=True)
    ft = time.perf_counter() - t0
    ev = json.loads(subprocess.run([tcomp, "eval", "--model", "/tmp/cmp.tcm", "--data", f"{d}/verify.csv", "--json", "--quiet"],
                                   check=True, capture_output=True).stdout)
    rows.append(("tcomp fit --method bayes (incl. CSV load)", ft, ev["binned"]["residual_std"]))
    print(f"{'method':<42} {'fit s':>8} {'held-out 100 s std':>20}")
    for n, t, r in rows:
        print(f"{n:<42} {t:>8.3f} {r:>20.5g}")

if __name__ == "__main__":
    main()
