"""Changes one value of a deli checkpoint and recomputes that dataset's checksum, so that the
file is intact as far as checksums go: what is left to refuse it is the range checks.

usage: forge_checkpoint.py FILE DATASET INDEX VALUE
(INDEX into the flattened dataset; VALUE a Python literal such as nan, -5, 1e300.)
"""
import sys

import h5py
import numpy as np


def fnv1a64(data: bytes) -> int:
    h = 0xCBF29CE484222325
    for b in data:
        h ^= b
        h = (h * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


path, name, index, value = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
with h5py.File(path, "r+") as f:
    data = f[name][()]
    flat = np.array(data).reshape(-1)
    flat[index] = float(value) if flat.dtype.kind == "f" else int(float(value))
    f[name][()] = flat.reshape(np.shape(data))
    native = flat.astype(flat.dtype.newbyteorder("="))
    f[name].attrs["fnv1a64"] = np.uint64(fnv1a64(native.tobytes()))
