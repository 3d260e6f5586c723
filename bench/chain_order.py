"""A LAMMPS data file ("Atoms # bond") with its molecules renumbered in the order of the box.

usage: /usr/bin/python3 bench/chain_order.py IN.data OUT.data [CELL]

Molecules (chains) are sorted by the cell of their centre (unwrapped with the image flags,
then wrapped): z band, then y band (CELL wide, default 2.8, the rigid melt's list reach), then
x; atoms and bonds are renumbered to match, each chain's beads kept consecutive in their old
order. The same system in another index order: for measuring what the order of chains costs
two threads whose chunks are chains by index and halves of the box (bench/README.md,
"Stop 48"). Not a test.
"""
import sys


def main():
    source, target = sys.argv[1], sys.argv[2]
    cell = float(sys.argv[3]) if len(sys.argv) > 3 else 2.8
    lines = open(source).read().split("\n")
    atoms_at = lines.index("Atoms # bond")
    velocities_at = lines.index("Velocities")
    bonds_at = lines.index("Bonds")
    lo, length = [0.0] * 3, [0.0] * 3
    for line in lines[:atoms_at]:
        words = line.split()
        for axis, name in enumerate(("xlo", "ylo", "zlo")):
            if len(words) == 4 and words[2] == name:
                lo[axis] = float(words[0])
                length[axis] = float(words[1]) - float(words[0])
    atoms = [line.split() for line in lines[atoms_at + 2 : velocities_at] if line.strip()]
    velocity = {line.split()[0]: line.split()[1:] for line in lines[velocities_at + 2 : bonds_at]
                if line.strip()}
    bonds = [line.split() for line in lines[bonds_at + 2 :] if line.strip()]
    chains = {}
    for atom in atoms:
        chains.setdefault(int(atom[1]), []).append(atom)

    def centre(chain):
        return [((sum(float(a[3 + k]) + length[k] * int(a[6 + k]) for a in chain) / len(chain)
                  - lo[k]) % length[k]) for k in range(3)]

    def key(molecule):
        c = centre(chains[molecule])
        return (int(c[2] / cell), int(c[1] / cell), c[0])

    new_id, atom_lines = {}, []
    for molecule, old in enumerate(sorted(chains, key=key), 1):
        for atom in sorted(chains[old], key=lambda a: int(a[0])):
            new_id[atom[0]] = str(len(new_id) + 1)
            atom_lines.append(" ".join([new_id[atom[0]], str(molecule)] + atom[2:]))
    old_id = {new: old for old, new in new_id.items()}
    velocity_lines = [" ".join([str(i)] + velocity[old_id[str(i)]])
                      for i in range(1, len(new_id) + 1)]
    bonds.sort(key=lambda b: (int(new_id[b[2]]), int(new_id[b[3]])))
    bond_lines = [f"{k} {b[1]} {new_id[b[2]]} {new_id[b[3]]}" for k, b in enumerate(bonds, 1)]
    text = lines[: atoms_at + 2] + atom_lines + ["", "Velocities", ""] + velocity_lines
    text += ["", "Bonds", ""] + bond_lines
    open(target, "w").write("\n".join(text) + "\n")
    print(f"{target}: {len(chains)} molecules, {len(new_id)} atoms, {len(bonds)} bonds")


main()
