"""Two deli H5MD trajectories hold the same frames, bit for bit.

usage: compare_h5md.py A.h5 B.h5 [MIN_FRAMES]

Every time series under /particles and /observables (step, time, value) must have the same
shape and the same bits in both files. Exit 1 naming the first difference.
"""
import sys

import h5py
import numpy as np


def series(f):
    found = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and name.split("/")[0] in ("particles", "observables"):
            found[name] = obj[()]

    f.visititems(visit)
    return found


def main():
    a_path, b_path = sys.argv[1], sys.argv[2]
    min_frames = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    with h5py.File(a_path, "r") as a, h5py.File(b_path, "r") as b:
        sa, sb = series(a), series(b)
        if sorted(sa) != sorted(sb):
            sys.exit(f"datasets differ: {sorted(set(sa) ^ set(sb))}")
        frames = a["particles/all/position/step"].shape[0]
        if frames < min_frames:
            sys.exit(f"{a_path}: {frames} frames, expected at least {min_frames}")
        for name in sorted(sa):
            x, y = sa[name], sb[name]
            if x.shape != y.shape:
                sys.exit(f"{name}: shape {x.shape} against {y.shape}")
            if x.dtype.kind == "f":
                same = np.array_equal(x.view(np.uint64 if x.itemsize == 8 else np.uint32),
                                      y.view(np.uint64 if y.itemsize == 8 else np.uint32))
            else:
                same = np.array_equal(x, y)
            if not same:
                where = np.argwhere(x != y)[0] if x.shape else ()
                sys.exit(f"{name}: differs first at {tuple(where)}")
        print(f"{len(sa)} datasets, {frames} frames, identical")


main()
