"""A trajectory left by a run killed with SIGKILL opens and holds every flushed frame.

usage: killed_run_check.py TRAJECTORY.h5 THERMO.csv EVERY TOPOLOGY.data

The thermo CSV is flushed row by row, each row after its step's frame was flushed: so every
complete row's step must be a frame in the file. The file must open in h5py and in
MDAnalysis, its frames at consecutive multiples of EVERY, every position finite.
"""
import sys

import h5py
import numpy as np


def main():
    path, csv_path, every, topology = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
    with open(csv_path, "rb") as f:
        text = f.read().decode()
    complete = text[: text.rfind("\n") + 1].splitlines()[1:]
    rows = [int(line.split(",")[0]) for line in complete]
    with h5py.File(path, "r") as f:
        position = f["particles/all/position"]
        steps = position["step"][()]
        values = position["value"][()]
        frames = len(steps)
        if not np.array_equal(steps, every * np.arange(frames)):
            sys.exit(f"frame steps are not 0, {every}, ...: {steps[:10]}")
        if not np.isfinite(values).all():
            sys.exit("non-finite positions in a frame")
        for name in f["observables"]:
            n = f["observables"][name]["value"].shape[0]
            if n < frames:
                sys.exit(f"observable {name}: {n} entries for {frames} frames")
    missing = sorted(set(rows) - set(steps.tolist()))
    if missing:
        sys.exit(f"thermo rows at steps {missing[:5]} have no frame in the trajectory")
    if frames < 2:
        sys.exit(f"only {frames} frames: the run was killed too early to test anything")
    import MDAnalysis as mda

    u = mda.Universe(topology, path, format="H5MD", topology_format="DATA",
                     atom_style="id resid type x y z", convert_units=False)
    if len(u.trajectory) < len(rows):
        sys.exit(f"MDAnalysis sees {len(u.trajectory)} frames, thermo has {len(rows)} rows")
    u.trajectory[len(u.trajectory) - 1]
    print(f"killed run: {frames} frames readable, {len(rows)} complete thermo rows, last step "
          f"{steps[-1]}")


main()
