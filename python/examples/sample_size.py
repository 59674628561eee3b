"""The paper's experiment: validation error against the number of training samples, for each
constraint set, into a pandas DataFrame and a matplotlib plot (the Cheetah-3-like leg, the CI
scenario: 4 seeds here).

usage: python python/examples/sample_size.py [OUT_DIR]   (from the repository root)
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import physid  # noqa: E402

e = physid.experiment("scenarios/ci.toml", seeds=4)
summary = e.summary()
print(summary.pivot(index="n_s", columns="constraints", values="val_rms_median")[e.constraints].round(3))
fig, ax = plt.subplots()
for name, rows in summary.groupby("constraints"):
    ax.loglog(rows["n_s"], rows["val_rms_median"], marker="o", label=name)
ax.set(xlabel="training samples n_s", ylabel="median validation RMS (N m)")
ax.legend()
fig.savefig(f"{sys.argv[1] if len(sys.argv) > 1 else '.'}/sample_size.png", dpi=100)
