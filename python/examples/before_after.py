"""Before and after: a chamber run raw, compensated by the PX4-style cubic and by tcomp's model,
on a verification profile the models never saw, plotted with matplotlib.

    python python/examples/before_after.py [OUT.png]

1. simulate an IFOG whose bias hides a T·dT/dt (Shupe) term (training and verification runs);
2. fit the cubic baseline (`method="poly3"`) and the RBF model (T and its rate) on the
   training run, and diagnose the model there; when the diagnosis confirms a missing effect,
   refit with its expressions (as `tcomp fit --feature` would);
3. measure every model on the verification run and plot the raw error and the residuals
   against time, as 100 s means.
"""

import sys

import matplotlib

matplotlib.use("Agg")  # files only: runs without a display
import matplotlib.pyplot as plt
import numpy as np

import tcomp

out = sys.argv[1] if len(sys.argv) > 1 else "before_after.png"

sim = tcomp.simulate("ifog-shupe")
base = dict(target="gyro_dph", reference="ref_dph", signal="T=t_coil_c", sensor="ifog", axis="x", unit="deg/h")
cubic = tcomp.fit(sim.train, method="poly3", feature="T", **base)
model = tcomp.fit(sim.train, feature=["T", "rate(T)"], **base)
d = tcomp.diagnose(model, sim.train, sim.verify)
print("diagnosis:", d.verdict_text)
models = [("PX4-style cubic", cubic), ("tcomp, T and rate(T)", model)]
if d.verdict == "missing_effect":
    added = list(d.candidates.iloc[0]["expressions"])
    refit = tcomp.fit(sim.train, feature=["T", "rate(T)", *added], **base)
    models.append((f"tcomp, + {', '.join(added)}", refit))

t = sim.verify["time_s"].to_numpy()
error = (sim.verify["gyro_dph"] - sim.verify["ref_dph"]).to_numpy()
runs = [("raw error", error)] + [(label, m.evaluate(sim.verify).residual) for label, m in models]


def binned(x, width=100):
    n = len(x) // width
    return x[: n * width].reshape(n, width).mean(axis=1)


fig, ax = plt.subplots(figsize=(9, 4.5))
for label, series in runs:
    ax.plot(binned(t) / 3600, binned(series), label=f"{label} (std {np.std(binned(series)):.3g} deg/h)")
ax.set_xlabel("time on the verification profile (h)")
ax.set_ylabel("error, 100 s means (deg/h)")
ax.set_title("IFOG bias on a profile the models never saw")
ax.legend()
fig.tight_layout()
fig.savefig(out, dpi=120)
print(f"wrote {out}")
