#!/usr/bin/env python3
"""`tcomp eval` side by side with pandas (pyarrow engine) + numpy applying the same model.

Usage:
    scripts/eval_vs_pandas.py --model m.tcm --data big.csv [--tcomp target/release/tcomp]

The model is the simulated RLG's 32 x 4 one (`tcomp fit ... --signal 'T=mean(t_anode_c,
t_cathode_c, t_shell_c)' --feature T --feature 'rate(T)' --feature 't_anode_c - t_shell_c'
--feature 't_cathode_c - t_shell_c' --centers 32`, see BENCHMARKS.md). pandas cannot run the
feature program, so this script computes the same four features with numpy/scipy: the mean of the
thermometers, `rate` by the core's definition (two cascaded first-order lags with tau = w/2,
rate = 60 (L1 - L2)(e^(dt/tau) - 1)/dt, w = 60 s; `lfilter` on a uniformly sampled record), the two
gradients; then the Gaussian RBF with the blob's normalisation, ranges, centers, widths, weights
and linear term as `tcomp inspect --json` prints them (Gaussians see features clamped to the
trained range, the linear term to the range widened by one span, as the compensator does). It
checks that its residual std agrees with tcomp's to 1e-3 relative, then times both, each in its own
process, and prints wall time and peak RSS.
"""

import argparse
import json
import resource
import subprocess
import sys
import time

RLG_FEATURES = ["T", "rate(T)", "t_anode_c - t_shell_c", "t_cathode_c - t_shell_c"]
THERMOMETERS = ["t_anode_c", "t_cathode_c", "t_shell_c"]


def inspect(tcomp, model):
    out = subprocess.run(
        [tcomp, "inspect", model, "--json"], check=True, capture_output=True, text=True
    ).stdout
    return json.loads(out)


def pandas_eval(blob, data):
    """Read with pandas (pyarrow engine), apply the model with numpy; the residual std."""
    import numpy as np
    import pandas as pd
    from scipy.signal import lfilter

    exprs = [f["expr"] for f in blob["features"]]
    if exprs != RLG_FEATURES:
        sys.exit(f"this script computes the RLG features {RLG_FEATURES}, the model has {exprs}")
    cols = blob["columns"]
    time_col, target, reference = cols["time"], cols["target"], cols["reference"]
    use = [time_col, target, reference] + THERMOMETERS
    df = pd.read_csv(data, engine="pyarrow", usecols=use)
    t = df[time_col].to_numpy()
    dts = np.diff(t)
    dt = float(np.median(dts))
    if not np.allclose(dts, dt, rtol=1e-6, atol=1e-9):
        sys.exit("this script handles uniformly sampled records only (no gaps)")
    temp = (df["t_anode_c"].to_numpy() + df["t_cathode_c"].to_numpy() + df["t_shell_c"].to_numpy()) / 3.0
    tau = 60.0 / 2.0
    c = 1.0 - np.exp(-dt / tau)
    lag1, _ = lfilter([c], [1.0, -(1.0 - c)], temp, zi=[(1.0 - c) * temp[0]])
    lag2, _ = lfilter([c], [1.0, -(1.0 - c)], lag1, zi=[(1.0 - c) * lag1[0]])
    rate = 60.0 * (lag1 - lag2) * np.expm1(dt / tau) / dt
    x = np.stack(
        [
            temp,
            rate,
            df["t_anode_c"].to_numpy() - df["t_shell_c"].to_numpy(),
            df["t_cathode_c"].to_numpy() - df["t_shell_c"].to_numpy(),
        ],
        axis=1,
    )
    feats = blob["features"]
    lo = np.array([f["lo"] for f in feats])
    hi = np.array([f["hi"] for f in feats])
    span = hi - lo
    offset = np.array([f["offset"] for f in feats])
    scale = np.array([f["scale"] for f in feats])
    linear = np.array([f["linear"] for f in feats])
    zg = (np.clip(x, lo, hi) - offset) * scale
    zl = (np.clip(x, lo - span, hi + span) - offset) * scale
    centers = np.array([cj["center"] for cj in blob["centers"]])
    gamma = np.array([cj["gamma"] for cj in blob["centers"]])
    weight = np.array([cj["weight"] for cj in blob["centers"]])
    # ||z - c||^2 = ||z||^2 - 2 z.c + ||c||^2 as a (rows x centers) matrix, in chunks of 65,536
    # rows: one 2.2 M x 32 matrix and its temporaries cost gigabytes and 3x the time.
    cc = (centers * centers).sum(axis=1)[None, :]
    gaussian = np.empty(len(zg))
    chunk = 1 << 16
    for s in range(0, len(zg), chunk):
        z = zg[s : s + chunk]
        d2 = (z * z).sum(axis=1)[:, None] - 2.0 * (z @ centers.T) + cc
        gaussian[s : s + chunk] = np.exp(-d2 * gamma[None, :]) @ weight
    correction = blob["bias"] + zl @ linear + gaussian
    raw = df[target].to_numpy()
    ref = df[reference].to_numpy()
    residual = raw - correction - ref
    return float(np.std(residual)), len(df)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--data", required=True)
    ap.add_argument("--tcomp", default="target/release/tcomp")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each; the fastest is reported")
    ap.add_argument("--pandas-only", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    blob = inspect(a.tcomp, a.model)
    if a.pandas_only:
        t0 = time.perf_counter()
        std, rows = pandas_eval(blob, a.data)
        wall = time.perf_counter() - t0
        peak_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        print(json.dumps({"residual_std": std, "rows": rows, "wall_s": wall, "peak_kb": peak_kb}))
        return

    def timed(cmd):
        t0 = time.perf_counter()
        p = subprocess.run(
            ["/usr/bin/time", "-f", "%e %M"] + cmd, check=True, capture_output=True, text=True
        )
        wall = time.perf_counter() - t0
        peak_kb = int(p.stderr.strip().splitlines()[-1].split()[1])
        return p.stdout, wall, peak_kb

    pandas_cmd = [sys.executable, __file__, "--pandas-only", "--model", a.model, "--data", a.data, "--tcomp", a.tcomp]
    tcomp_cmd = [a.tcomp, "eval", "--model", a.model, "--data", a.data, "--json", "--quiet"]
    pd_runs, tc_runs = [], []
    for _ in range(max(1, a.repeat)):
        out, wall, peak = timed(pandas_cmd)
        pd_runs.append((wall, peak, json.loads(out)))
        out, wall, peak = timed(tcomp_cmd)
        tc_runs.append((wall, peak, json.loads(out)))
    pd_wall, pd_peak, pd_res = min(pd_runs, key=lambda r: r[0])
    pd_inner = min(r[2]["wall_s"] for r in pd_runs)
    tc_wall, tc_peak, tc_out = min(tc_runs, key=lambda r: r[0])
    tc_std = tc_out["residual_std"]
    rel = abs(pd_res["residual_std"] - tc_std) / abs(tc_std)
    print(f"rows                 {pd_res['rows']}")
    print(f"residual std         tcomp {tc_std:.6g}   pandas+numpy {pd_res['residual_std']:.6g}   relative difference {rel:.2e}")
    print(f"fastest of {max(1, a.repeat)} runs each, every run its own process:")
    print(f"pandas+numpy         {pd_wall:.2f} s wall, {pd_peak / 1024:.0f} MB peak RSS (read + model alone, imports and start-up excluded: {pd_inner:.2f} s)")
    print(f"tcomp eval           {tc_wall:.2f} s wall, {tc_peak / 1024:.1f} MB peak RSS")
    print(f"speed-up             {pd_wall / tc_wall:.2f}x whole processes, {pd_inner / tc_wall:.2f}x against pandas' read + model alone")
    if rel > 1e-3:
        sys.exit(f"the residual stds differ by {rel:.2e} relative (> 1e-3): not the same model")


if __name__ == "__main__":
    main()
