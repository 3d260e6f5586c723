#!/bin/bash
# Energy trend against fluctuation of contact = "impact_time" (and "paper") on the paper's LJ
# beads and LJ chain in a sphere (hard cores 0.6 = LJ sigma, on LJ's steep wall; README,
# "Contact treatment"): h 0.0025, 0.005, 0.01; 5 starts (SEEDS="0 1 2 3 4": the data file's velocities, then
# temperature 0.13 with seeds 1000 + SEED); TIME time units each, thermo every 0.5.
# Usage: bench/contact_energy/run.sh [OUTDIR]   (variants: VARIANTS="old new paper", where
# `old` runs the binary OLD and `new`/`paper`/`remainder` the binary NEW; `remainder`: impact_time
# with shadow_remainder_steps = ${REMAINDER_STEPS:-10}; STEP_THERMO=1 writes thermo
# every step, for attribute.py); then
# /usr/bin/python3 bench/contact_energy/analyse.py OUTDIR
HERE=$(cd "$(dirname "$0")" && pwd)
OLD=${OLD:-}; NEW=${NEW:-$HERE/../../build/deli}; D=${1:-/tmp/contact_energy}; T=${TIME:-1000}
mkdir -p "$D"
cmds=$D/commands.txt; : > "$cmds"
for sys in ${SYSTEMS:-beads chain}; do for h in ${HS:-0.0025 0.005 0.01}; do for seed in ${SEEDS:-0 1 2 3 4}; do for v in ${VARIANTS:-new}; do
  n=${sys}_${v}_${h}_s${seed}; steps=$(/usr/bin/python3 -c "print(round($T/$h))"); every=$(/usr/bin/python3 -c "print(round(0.5/$h))")
  [ -n "${STEP_THERMO:-}" ] && every=1
  contact=impact_time; [ "$v" = paper ] && contact=paper
  bin=$NEW; [ "$v" = old ] && bin=$OLD
  {
    echo "[system]"; echo "data = \"$HERE/$sys.data\""; echo 'boundary = "fff"'
    [ "$seed" != 0 ] && { echo "[velocities]"; echo "temperature = 0.13"; echo "seed = $((1000 + seed))"; }
    if [ "$sys" = chain ]; then
      echo '[forcefield.special_bonds]'; echo 'lj = [1.0, 1.0, 1.0]'; echo '[constraints]'
      echo 'rods = [{ atoms = [1, 2], length = 1.0 },{ atoms = [2, 3], length = 1.0 },{ atoms = [3, 4], length = 1.0 },{ atoms = [4, 5], length = 1.0 },{ atoms = [5, 6], length = 1.0 }]'
    else
      echo '[constraints]'
    fi
    echo 'hard_spheres = { diameter = 0.6 }'
    echo 'walls = [{ type = "inside_sphere", radius = 5.0 }]'
    echo '[forcefield.pair]'; echo 'style = "lj/cut"'; echo 'cutoff = 3.0'
    echo 'coeffs = [{ types = [1, 1], epsilon = 1.0, sigma = 0.6 }]'
    echo "[integrator]"; echo 'type = "gvi"'; echo "timestep = $h"; echo "contact = \"$contact\""
    [ "$v" = remainder ] && echo "shadow_remainder_steps = ${REMAINDER_STEPS:-10}"
    echo "[run]"; echo "steps = $steps"; echo "[output]"; echo "thermo = { every = $every, file = \"$D/$n.csv\" }"
  } > "$D/$n.toml"
  echo "cd $D && OMP_NUM_THREADS=1 nice -n 19 $bin run $n.toml > $n.log 2>&1" >> "$cmds"
done; done; done; done
xargs -P2 -I{} bash -c "{}" < "$cmds"
