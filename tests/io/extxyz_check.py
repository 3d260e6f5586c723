#!/usr/bin/python3
"""Reads an extended XYZ file as its definition says (libAtoms/QUIP extended XYZ, as ASE's
ase.io.extxyz and OVITO's XYZ reader implement it) and checks every frame:

- line 1: the atom count; line 2: key=value pairs (values quoted with "..." when they
  hold spaces); `Properties` names the columns as name:type:count triples (types S, R, I,
  L), `Lattice` holds the 3 cell vectors (9 numbers, one vector after the other), `pbc`
  three T/F; then one line per atom with exactly the columns Properties names, each
  parsing as its type.
- ASE builds Atoms from `species`, which must be chemical symbols (ase.data's, 'X' for
  a dummy); ASE is not installed here, so the symbols are checked against the table.

Prints per frame 'frame K step S time T atoms N lattice a b c pbc TTF origin x y z' and
the first atom's columns, exit 1 naming what does not parse.

usage: extxyz_check.py FILE.xyz
"""
import re
import sys

ELEMENTS = set("""X H He Li Be B C N O F Ne Na Mg Al Si P S Cl Ar K Ca Sc Ti V Cr Mn Fe Co
Ni Cu Zn Ga Ge As Se Br Kr Rb Sr Y Zr Nb Mo Tc Ru Rh Pd Ag Cd In Sn Sb Te I Xe Cs Ba La Ce
Pr Nd Pm Sm Eu Gd Tb Dy Ho Er Tm Yb Lu Hf Ta W Re Os Ir Pt Au Hg Tl Pb Bi Po At Rn Fr Ra Ac
Th Pa U Np Pu Am Cm Bk Cf Es Fm Md No Lr Rf Db Sg Bh Hs Mt Ds Rg Cn Nh Fl Mc Lv Ts
Og""".split())

# ASE's key=value grammar: a key, '=', then a quoted value or one without spaces.
PAIR = re.compile(r'([A-Za-z_][A-Za-z0-9_-]*)\s*=\s*(?:"([^"]*)"|([^\s"]+))\s*')
PARSERS = {"R": float, "I": int, "S": str, "L": lambda v: {"T": True, "F": False}[v]}


def parse_comment(line):
    info, at = {}, 0
    line = line.strip()
    while at < len(line):
        match = PAIR.match(line, at)
        if not match:
            raise ValueError(f"not key=value at {line[at:at + 30]!r}")
        info[match.group(1)] = match.group(2) if match.group(2) is not None else match.group(3)
        at = match.end()
    return info


def main():
    lines = open(sys.argv[1]).read().split("\n")
    k, frame, problems = 0, 0, []
    while k < len(lines) and lines[k].strip():
        try:
            n = int(lines[k])
            info = parse_comment(lines[k + 1])
            fields = info["Properties"].split(":")
            if len(fields) % 3:
                raise ValueError("Properties is not name:type:count triples")
            columns = [(fields[c], fields[c + 1], int(fields[c + 2]))
                       for c in range(0, len(fields), 3)]
            if columns[0][0] != "species" or columns[1][:2] != ("pos", "R") or \
                    columns[1][2] != 3:
                raise ValueError("the columns do not begin species, pos:R:3")
            lattice = [float(v) for v in info["Lattice"].split()]
            if len(lattice) != 9:
                raise ValueError(f"Lattice holds {len(lattice)} numbers, not 9")
            pbc = info["pbc"].split()
            if len(pbc) != 3 or any(p not in ("T", "F") for p in pbc):
                raise ValueError(f"pbc {info['pbc']!r} is not three T/F")
            width = sum(c[2] for c in columns)
            first = None
            for a in range(n):
                values = lines[k + 2 + a].split()
                if len(values) != width:
                    raise ValueError(f"atom {a}: {len(values)} columns, Properties {width}")
                parsed, at = [], 0
                for name, kind, count in columns:
                    parsed += [PARSERS[kind](v) for v in values[at:at + count]]
                    at += count
                if parsed[0] not in ELEMENTS:
                    raise ValueError(f"atom {a}: species {parsed[0]!r} is not a chemical "
                                     "symbol (ASE refuses it)")
                if first is None:
                    first = values
            a, b, c = (lattice[0:3], lattice[3:6], lattice[6:9])
            print(f"frame {frame} step {info.get('Step')} time {info.get('Time')} atoms {n} "
                  f"lattice {a[0]:.6g} {b[1]:.6g} {c[2]:.6g} pbc {''.join(pbc)} "
                  f"origin {info.get('Origin')} columns {info['Properties']} "
                  f"first {' '.join(first or [])}")
        except (ValueError, KeyError, IndexError) as error:
            problems.append(f"frame {frame} (line {k + 1}): {error!r}")
            break
        k += n + 2
        frame += 1
    for p in problems:
        print("FAIL:", p)
    print(f"{frame} frames" + ("" if not problems else f", {len(problems)} problems"))
    sys.exit(1 if problems or frame == 0 else 0)


main()
