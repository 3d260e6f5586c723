#!/usr/bin/python3
"""Hard-sphere equation of state from deli at several time steps, extrapolated to h -> 0.

tools/eos.py INPUT [--timesteps 0.005,0.0025,0.00125] [--time 20] [--equilibrate 2]
                   [--block 1] [--seeds 1,2] [--contact paper|impact_time] [--order 1]
                   [--packing-fraction ETA] [--plot FILE] [--check PERCENT]

For each time step and seed the input is run with that step (and velocity seed, and
[integrator] contact), thermo rows every `--block` time units. Each row after
`--equilibrate` is one block: its compressibility factor Z = P V / (N kT) = 1 + W / (2 K)
(W the constraint virial averaged over the block, K the kinetic energy, kT = 2K / 3N) and
its collision rate per particle 2 * (contacts in the block) / (N * block). Error bars are
standard errors of the block means. Z(h) and the rate are then fitted by weighted least
squares to a polynomial in h (`--order`, 1 by default: c0 + c1 h; 0 the weighted mean, for
contact = impact_time on hard spheres alone, which has no step error; a quadratic term fitted
to noise-limited points moves c0 by more than it corrects), c0 the h -> 0 value, and compared with Carnahan-Starling, Z = (1 + e + e^2 - e^3) / (1 - e)^3,
and the rate Enskog's theory gives from that Z: 6 (Z - 1) sqrt(kT / (pi m)) / sigma.
The input must build an fcc lattice ([system.lattice]) of equal hard spheres
(hard_spheres = { diameter = ... }) with no pair force; packing fraction from its density,
or `--packing-fraction ETA` sets the lattice density to 6 ETA / (pi sigma^3).
"""
import argparse
import csv
import math
import os
import subprocess
import sys
import time
import tomllib

import numpy as np


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {v!r} as TOML")


def write_toml(table, path):
    with open(path, "w") as f:
        f.write(toml_dumps(table))


def base_with_density(base, density):
    """The input rewritten with its [system.lattice] density replaced (comments dropped)."""
    table = tomllib.loads(base)
    table["system"]["lattice"]["density"] = density
    return toml_dumps(table)


def toml_dumps(table):
    lines = []

    def section(name, t):
        scalars = {k: v for k, v in t.items() if not isinstance(v, dict)}
        if name:
            lines.append(f"[{name}]")
        lines.extend(f"{k} = {toml_value(v)}" for k, v in scalars.items())
        for k, v in t.items():
            if isinstance(v, dict):
                section(f"{name}.{k}" if name else k, v)

    section("", table)
    return "\n".join(lines) + "\n"


def carnahan_starling(eta):
    return (1 + eta + eta**2 - eta**3) / (1 - eta) ** 3


def fit(hs, values, errors, order):
    """Weighted least squares in powers of h; returns (coefficients, their covariance)."""
    hs, values, errors = map(np.asarray, (hs, values, errors))
    if len(hs) < order + 1:
        sys.exit(f"eos.py: a fit of order {order} needs at least {order + 1} time steps")
    a = np.vander(hs, order + 1, increasing=True) / errors[:, None]
    b = values / errors
    cov = np.linalg.inv(a.T @ a)
    coef = cov @ a.T @ b
    # Scale by the reduced chi^2 when the fit is worse than the error bars say.
    dof = len(hs) - order - 1
    if dof > 0:
        chi2 = float(np.sum((a @ coef - b) ** 2)) / dof
        cov = cov * max(1.0, chi2)
    return coef, cov


def run_one(args, base, h, seed, workdir):
    table = tomllib.loads(base)
    steps_per_block = max(1, round(args.block / h))
    blocks = math.ceil((args.equilibrate + args.time) / args.block)
    table["integrator"]["timestep"] = h
    if args.contact:
        table["integrator"]["contact"] = args.contact
    table.setdefault("velocities", {})["seed"] = seed
    table.setdefault("run", {})["steps"] = steps_per_block * blocks
    name = f"eos_h{h:g}_seed{seed}_{args.contact or 'input'}"
    thermo = os.path.join(workdir, name + ".thermo.csv")
    table["output"] = {"thermo": {"every": steps_per_block, "file": thermo}}
    path = os.path.join(workdir, name + ".toml")
    write_toml(table, path)
    start = time.time()
    done = subprocess.run([args.deli, "run", path], capture_output=True, text=True)
    wall = time.time() - start
    if done.returncode != 0:
        sys.exit(f"eos.py: {args.deli} run {path} failed ({done.returncode}): {done.stderr}")
    with open(thermo) as f:
        rows = list(csv.DictReader(f))
    return rows, wall, steps_per_block * h


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("input")
    parser.add_argument("--timesteps", default="0.005,0.0025,0.00125")
    parser.add_argument("--time", type=float, default=20.0, help="sampled time per run")
    parser.add_argument("--equilibrate", type=float, default=2.0, help="time left out first")
    parser.add_argument("--block", type=float, default=1.0, help="block length (time)")
    parser.add_argument("--seeds", default="1")
    parser.add_argument("--order", type=int, default=1, help="polynomial order of the fit in h")
    parser.add_argument("--contact", choices=["paper", "impact_time"], default=None)
    parser.add_argument("--deli", default=os.path.join(os.path.dirname(__file__), "..", "build", "deli"))
    parser.add_argument("--workdir", default=None, help="where inputs and thermo files go")
    parser.add_argument("--packing-fraction", type=float, default=None,
                        help="run at this packing fraction (sets the lattice density)")
    parser.add_argument("--plot", default=None, help="PNG of Z(h) and the rate")
    parser.add_argument("--check", type=float, default=None,
                        help="exit 1 unless Z(h -> 0) is within this many percent of "
                             "Carnahan-Starling")
    args = parser.parse_args()

    with open(args.input) as f:
        base = f.read()
    spec = tomllib.loads(base)
    try:
        lattice = spec["system"]["lattice"]
        density = float(lattice["density"])
        atoms = 4 * math.prod(lattice["cells"])
        sigma = float(spec["constraints"]["hard_spheres"]["diameter"])
    except KeyError as e:
        sys.exit(f"eos.py: {args.input} needs an fcc [system.lattice] and "
                 f"[constraints] hard_spheres = {{ diameter = ... }} (missing {e})")
    if args.packing_fraction is not None:
        if not 0 < args.packing_fraction < 0.74:
            sys.exit(f"eos.py: --packing-fraction {args.packing_fraction:g} is outside "
                     f"(0, 0.74), the fcc close packing")
        density = 6 * args.packing_fraction / (math.pi * sigma**3)
        lattice["density"] = density
        base = base_with_density(base, density)
    if lattice.get("type", "fcc") != "fcc":
        sys.exit(f"eos.py: {args.input}: only an fcc lattice is read (4 atoms per cell)")
    volume = atoms / density
    eta = math.pi / 6 * density * sigma**3
    workdir = args.workdir or f"/tmp/eos-{os.getpid()}"
    os.makedirs(workdir, exist_ok=True)
    hs = [float(x) for x in args.timesteps.split(",")]
    seeds = [int(x) for x in args.seeds.split(",")]

    results = []
    for h in hs:
        z_blocks, rate_blocks, kts, wall = [], [], [], 0.0
        for seed in seeds:
            rows, seconds, block = run_one(args, base, h, seed, workdir)
            wall += seconds
            for row in rows:
                if float(row["time"]) <= args.equilibrate + 1e-9:
                    continue
                kinetic = float(row["kinetic"])
                virial = 3 * volume * float(row["pressure"]) - 2 * kinetic
                z_blocks.append(1 + virial / (2 * kinetic))
                rate_blocks.append(2 * float(row["reflected"]) / (atoms * block))
                kts.append(2 * kinetic / (3 * atoms))
        z, rate = np.array(z_blocks), np.array(rate_blocks)
        results.append({
            "h": h, "z": z.mean(), "z_err": z.std(ddof=1) / math.sqrt(len(z)),
            "rate": rate.mean(), "rate_err": rate.std(ddof=1) / math.sqrt(len(rate)),
            "kT": float(np.mean(kts)), "blocks": len(z), "wall": wall,
            "speed": len(seeds) * (args.equilibrate + args.time) / wall,
        })

    zc, zcov = fit([r["h"] for r in results], [r["z"] for r in results],
                   [r["z_err"] for r in results], args.order)
    rc, rcov = fit([r["h"] for r in results], [r["rate"] for r in results],
                   [r["rate_err"] for r in results], args.order)
    z0, z0_err = zc[0], math.sqrt(zcov[0, 0])
    cs = carnahan_starling(eta)
    kt = np.mean([r["kT"] for r in results])
    enskog = 6 * (cs - 1) * math.sqrt(kt / math.pi) / sigma

    print(f"# {args.input}: N = {atoms}, packing fraction {eta:.4f}, contact = "
          f"{args.contact or 'as the input says'}, seeds {args.seeds}, "
          f"{args.time:g} time units per run after {args.equilibrate:g}, blocks of {args.block:g}")
    print(f"{'h':>9} {'blocks':>6} {'Z':>9} {'+-':>7} {'Z/Z0-1 %':>9} "
          f"{'rate':>8} {'+-':>6} {'wall s':>7} {'time/s':>7}")
    for r in results:
        print(f"{r['h']:9.6f} {r['blocks']:6d} {r['z']:9.5f} {r['z_err']:7.5f} "
              f"{100 * (r['z'] / z0 - 1):+9.3f} {r['rate']:8.4f} {r['rate_err']:6.4f} "
              f"{r['wall']:7.1f} {r['speed']:7.3f}")
    slope = ", ".join(f"c{k} = {c:.4g} +- {math.sqrt(zcov[k, k]):.2g}" for k, c in enumerate(zc))
    print(f"Z(h) fit: {slope}")
    print(f"Z(h -> 0) = {z0:.5f} +- {z0_err:.5f}; Carnahan-Starling {cs:.5f}; "
          f"difference {100 * (z0 / cs - 1):+.3f} % +- {100 * z0_err / cs:.3f} %")
    print(f"collision rate (h -> 0) = {rc[0]:.5f} +- {math.sqrt(rcov[0, 0]):.5f} per particle "
          f"per time; Enskog with Carnahan-Starling {enskog:.5f}")

    if args.check is not None and abs(z0 / cs - 1) * 100 > args.check:
        sys.exit(f"eos.py: Z(h -> 0) = {z0:.5f} is {100 * (z0 / cs - 1):+.3f} % from "
                 f"Carnahan-Starling's {cs:.5f}, beyond --check {args.check:g} %")

    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
        h = np.array([r["h"] for r in results])
        grid = np.linspace(0, h.max() * 1.05, 100)
        a1.errorbar(h, [r["z"] for r in results], [r["z_err"] for r in results], fmt="o",
                    label=f"deli ({args.contact or 'input'})")
        a1.plot(grid, np.polyval(zc[::-1], grid), "-", label="fit")
        a1.axhline(cs, color="k", ls="--", label="Carnahan-Starling")
        a1.set_xlabel("time step h")
        a1.set_ylabel("Z = PV/NkT")
        a1.legend()
        a2.errorbar(h, [r["rate"] for r in results], [r["rate_err"] for r in results], fmt="o")
        a2.plot(grid, np.polyval(rc[::-1], grid), "-")
        a2.axhline(enskog, color="k", ls="--", label="Enskog (CS)")
        a2.set_xlabel("time step h")
        a2.set_ylabel("collisions per particle per time")
        a2.legend()
        fig.suptitle(f"{os.path.basename(args.input)}: packing fraction {eta:.3f}, N = {atoms}")
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
        print(f"plot: {args.plot}")


if __name__ == "__main__":
    main()
