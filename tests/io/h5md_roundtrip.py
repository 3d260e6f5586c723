#!/usr/bin/python3
"""Reads a deli H5MD trajectory as a user would, with h5py and MDAnalysis, and checks it
against what deli held (expected.txt: per frame 'frame step time Lx Ly Lz', then one line
per atom 'x y z vx vy vz fx fy fz' at 17 digits) and the bonds of the LAMMPS data file.

usage: h5md_roundtrip.py TRAJ.h5 EXPECTED.txt TOPOLOGY.data"""
import sys
import warnings

import h5py
import numpy as np

warnings.filterwarnings("ignore")
import MDAnalysis as mda  # noqa: E402

traj, expected_path, topology = sys.argv[1:4]
frames = []
with open(expected_path) as f:
    lines = f.read().split("\n")
k = 0
while k < len(lines) and lines[k].strip():
    head = lines[k].split()
    n = int(head[0])
    step, time, box = int(head[1]), float(head[2]), [float(v) for v in head[3:6]]
    data = np.array([[float(v) for v in lines[k + 1 + a].split()] for a in range(n)])
    frames.append((step, time, box, data))
    k += n + 1

failures = []
with h5py.File(traj, "r") as f:
    # The layout H5MD 1.1 requires.
    for path in ["h5md", "h5md/author", "h5md/creator", "particles/all/position/value",
                 "particles/all/position/step", "particles/all/position/time",
                 "particles/all/box", "observables", "parameters"]:
        if path not in f:
            failures.append(f"missing {path}")
    if list(f["h5md"].attrs["version"]) != [1, 1]:
        failures.append("h5md version is not 1.1")
    if f["h5md/creator"].attrs["name"] != b"deli" and f["h5md/creator"].attrs["name"] != "deli":
        failures.append("creator is not deli")
    if int(f["particles/all/box"].attrs["dimension"]) != 3:
        failures.append("box dimension is not 3")
    position = f["particles/all/position/value"]
    velocity = f["particles/all/velocity/value"]
    if position.shape[0] != len(frames):
        failures.append(f"{position.shape[0]} frames in the file, {len(frames)} expected")
    for i, (step, time, box, data) in enumerate(frames):
        if f["particles/all/position/step"][i] != step:
            failures.append(f"frame {i}: step {f['particles/all/position/step'][i]} != {step}")
        if not np.array_equal(position[i], data[:, 0:3]):
            failures.append(f"frame {i}: positions differ from deli's (double precision)")
        if not np.array_equal(velocity[i], data[:, 3:6]):
            failures.append(f"frame {i}: velocities differ from deli's (double precision)")
        if not np.array_equal(f["particles/all/force/value"][i], data[:, 6:9]):
            failures.append(f"frame {i}: forces differ from deli's (double precision)")
        if not np.array_equal(np.diag(f["particles/all/box/edges/value"][i]), box):
            failures.append(f"frame {i}: box differs")

u = mda.Universe(topology, traj, format="H5MD", topology_format="DATA",
                 atom_style="id resid type x y z", convert_units=False)
if len(u.trajectory) != len(frames):
    failures.append(f"MDAnalysis sees {len(u.trajectory)} frames, {len(frames)} expected")
for i, ts in enumerate(u.trajectory):
    step, time, box, data = frames[i]
    # MDAnalysis holds coordinates in single precision: deli's values rounded to float32.
    if not np.array_equal(ts.positions, data[:, 0:3].astype(np.float32)):
        failures.append(f"MDAnalysis frame {i}: positions differ")
    if not np.array_equal(ts.velocities, data[:, 3:6].astype(np.float32)):
        failures.append(f"MDAnalysis frame {i}: velocities differ")
    if not np.array_equal(ts.forces, data[:, 6:9].astype(np.float32)):
        failures.append(f"MDAnalysis frame {i}: forces differ")
    if not np.array_equal(ts.dimensions[:3], np.array(box, dtype=np.float32)):
        failures.append(f"MDAnalysis frame {i}: box {ts.dimensions[:3]} != {box}")
    if abs(ts.time - time) > 1e-12 * max(1.0, abs(time)):
        failures.append(f"MDAnalysis frame {i}: time {ts.time} != {time}")
# /connectivity holds particle ids (H5MD 1.1: /particles/all has an id element).
# MDAnalysis 2.4 reads no topology from H5MD: its bonds are the data file's, by atom id.
with h5py.File(traj, "r") as f:
    bonds = f["connectivity/bonds"][:]
    if not np.array_equal(f["particles/all/id"][:], [a.id for a in u.atoms]):
        failures.append("/particles/all/id differs from the data file's atom ids")
mda_bonds = sorted(tuple(sorted(int(i) for i in b.atoms.ids)) for b in u.bonds)
deli_bonds = sorted(tuple(sorted(b)) for b in bonds.tolist())
if mda_bonds != deli_bonds:
    failures.append(f"bonds differ: MDAnalysis {len(mda_bonds)}, deli {len(deli_bonds)}")

for failure in failures:
    print("FAIL:", failure)
print(f"{len(frames)} frames, {u.atoms.n_atoms} atoms, {len(deli_bonds)} bonds: "
      + ("agree" if not failures else f"{len(failures)} failures"))
sys.exit(1 if failures else 0)
