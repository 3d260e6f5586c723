#!/usr/bin/python3
"""Energy fluctuation and drift per atom from a deli thermo CSV.

usage: bench/energy_drift.py THERMO.csv ATOMS [SKIP_TIME]
Prints the largest |E(t) - E(t0)| / N and the least-squares slope of E / N against t
(per atom per tau), from time SKIP_TIME on (default 0)."""
import csv
import sys

path, atoms = sys.argv[1], float(sys.argv[2])
skip = float(sys.argv[3]) if len(sys.argv) > 3 else 0.0
rows = [(float(r["time"]), float(r["total"]) / atoms) for r in csv.DictReader(open(path))]
rows = [(t, e) for t, e in rows if t >= skip]
t0, e0 = rows[0]
n = len(rows)
st = sum(t for t, _ in rows)
se = sum(e for _, e in rows)
stt = sum(t * t for t, _ in rows)
ste = sum(t * e for t, e in rows)
slope = (n * ste - st * se) / (n * stt - st * st)
print(f"samples {n}, t = {t0:g} .. {rows[-1][0]:g}")
print(f"max |E - E0| / N = {max(abs(e - e0) for _, e in rows):.3e}")
print(f"drift = {slope:.3e} per atom per tau")
