"""A LAMMPS data file (atom style atomic, with Velocities) with its atoms' indices shuffled:
atom k given the position and velocity of atom p(k), for a fixed random permutation p (seed 7).
The same configuration, as a liquid's indices are after long mixing.

usage: /usr/bin/python3 bench/shuffle_atoms.py IN.data OUT.data
"""
import random
import sys

lines = open(sys.argv[1]).read().split("\n")
a, v = lines.index("Atoms # atomic"), lines.index("Velocities")
atoms = [l for l in lines[a + 1:v] if l.strip()]
vel = [l for l in lines[v + 1:] if l.strip()]
p = list(range(len(atoms)))
random.Random(7).shuffle(p)
out = lines[:a + 1] + [""]
out += [" ".join([str(k + 1)] + atoms[p[k]].split()[1:]) for k in range(len(atoms))]
out += ["", "Velocities", ""]
out += [" ".join([str(k + 1)] + vel[p[k]].split()[1:]) for k in range(len(vel))]
open(sys.argv[2], "w").write("\n".join(out) + "\n")
