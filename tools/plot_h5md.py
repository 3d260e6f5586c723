#!/usr/bin/python3
"""Plots a deli H5MD trajectory's observables against time, as PNG.

usage: tools/plot_h5md.py TRAJ.h5 [OUT.png]

Panels: energies (kinetic, potential, total, and the shadow energy when present), the
relative change of the total energy, temperature, pressure, and for constrained runs (GVI)
the constraint statistics: smallest gap and largest rod violation, and the events per
frame interval (reflections, landings, overlapping steps). Runs on Debian's Python
(/usr/bin/python3 with python3-h5py and python3-matplotlib)."""
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help") or len(sys.argv) > 3:
    print(__doc__)
    sys.exit(0 if len(sys.argv) >= 2 and sys.argv[1] in ("-h", "--help") else 2)
path = sys.argv[1]
out = sys.argv[2] if len(sys.argv) > 2 else path.rsplit(".", 1)[0] + ".png"
with h5py.File(path, "r") as f:
    if "observables" not in f or "total_energy" not in f["observables"]:
        sys.exit(f"{path}: no /observables/total_energy: not a deli H5MD trajectory")
    obs = {name: (f["observables"][name]["time"][:], f["observables"][name]["value"][:])
           for name in f["observables"]}
    creator = f["h5md/creator"].attrs["name"]

constrained = "min_gap" in obs
panels = ["energies", "energy change", "temperature", "pressure"]
if constrained:
    panels += ["constraint geometry", "constraint events"]
fig, axes = plt.subplots(len(panels), 1, figsize=(8, 2.5 * len(panels)), sharex=True)
for name in ["kinetic_energy", "potential_energy", "total_energy", "shadow_energy"]:
    if name in obs:
        axes[0].plot(*obs[name], label=name.replace("_", " "))
axes[0].set_ylabel("energy (epsilon)")
axes[0].legend(fontsize=8)
t, e = obs["total_energy"]
axes[1].plot(t, (e - e[0]) / abs(e[0]) if e[0] != 0 else e - e[0])
axes[1].set_ylabel("(E - E0) / |E0|")
axes[2].plot(*obs["temperature"])
axes[2].set_ylabel("temperature")
axes[3].plot(*obs["pressure"])
axes[3].set_ylabel("pressure")
if constrained:
    axes[4].plot(*obs["min_gap"], label="smallest gap")
    axes[4].plot(*obs["max_rod_violation"], label="largest rod violation (relative)")
    axes[4].set_ylabel("constraints")
    axes[4].legend(fontsize=8)
    for name in ["reflected", "landings", "penetrating_steps", "stalled_reflections",
                 "cycled_reflections"]:
        if name in obs:
            axes[5].plot(*obs[name], label=name.replace("_", " "))
    axes[5].set_ylabel("events per frame")
    axes[5].legend(fontsize=8)
axes[-1].set_xlabel("time (tau)")
fig.suptitle(f"{path} ({creator.decode() if isinstance(creator, bytes) else creator})", fontsize=9)
fig.tight_layout()
fig.savefig(out, dpi=100)
print(f"wrote {out}: {', '.join(panels)}")
