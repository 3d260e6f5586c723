#!/usr/bin/env bash
# Particles sorted in space ([neighbor] sort_every): deli's loop time with sorting off
# (sort_every = 0) and on (every 1000 steps, the default, and at the start), alternated in
# one run, on one thread (pinned to CPU 0) and on two: the hard-sphere fluids hs_4000 and
# hs_32000 and the LJ liquid 32000 from their lattice order (neighbours near in index
# already) and with their atoms' indices shuffled (the same fluid after long mixing, as
# bench/cell_order.sh shuffles them); the rigid chain melt (chains_4000_rigid) and the
# default input (rigid_slit, 11000 steps) as their data files list them (chain by chain).
# Prints the medians of each and on/off.
#   bench/sort_every.sh              3 rounds
#   ROUNDS=5 DELI=path/to/deli bench/sort_every.sh
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
deli=$(realpath "${DELI:-$top/build/deli}")
rounds=${ROUNDS:-3}
work=$(mktemp -d /tmp/deli-bench-sort-every.XXXXXX)
trap 'rm -rf "$work"' EXIT
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg); $(nproc) cores"
cases=()
for spec in hard_spheres/hs_4000:3000 hard_spheres/hs_32000:300 lj_liquid/lj_32000:150 \
  lj_chains/chains_4000_rigid:1000 lj_chains/rigid_slit:11000; do
  source=${spec%%:*} steps=${spec#*:} name=$(basename "${spec%%:*}")
  orders=(lattice shuffled)
  # The lattice's data file (the hard spheres' is written from their [system.lattice]).
  if [[ $name == hs_* ]]; then
    (cd "$work" && "$deli" write-data "$top/inputs/$source.toml" "${name}_lattice.data" > /dev/null)
  elif [[ $name == lj_* ]]; then
    cp "$top/inputs/$source.data" "$work/${name}_lattice.data"
  else
    orders=(as_built)
    data=$(awk -F'"' '/^data *=/ { print $2 }' "$top/inputs/$source.toml")
    cp "$top/inputs/lj_chains/$data" "$work/${name}_as_built.data"
  fi
  [[ ${orders[0]} == lattice ]] &&
    /usr/bin/python3 "$top/bench/shuffle_atoms.py" "$work/${name}_lattice.data" \
      "$work/${name}_shuffled.data"
  for order in "${orders[@]}"; do
    for every in 0 1000; do
      awk -v data="${name}_$order.data" -v cap="$steps" -v every="$every" '
        /^\[/ { section = $0 }
        section == "[output]" || section == "[velocities]" { next }
        section == "[system.lattice]" || /^\[system.lattice\]/ { next }
        section == "[system]" && /^\[system\]/ { print; print "data = \"" data "\""; next }
        section == "[system]" && /^data *=/ { next }
        section == "[neighbor]" && /^skin/ { $0 = $0 "\nsort_every = " every }
        section == "[run]" && /^steps *=/ { $0 = "steps = " cap }
        { print }' "$top/inputs/$source.toml" > "$work/${name}_${order}_$every.toml"
    done
    cases+=("${name}_$order")
  done
done
declare -A loop=()
for ((r = 0; r < rounds; ++r)); do
  for c in "${cases[@]}"; do
    for every in 0 1000; do
      for threads in 1 2; do
        pin=()
        [[ $threads == 1 ]] && pin=(taskset -c 0)
        t=$(cd "$work" && "${pin[@]}" "$deli" run "${c}_$every.toml" --threads "$threads" |
              awk '/^loop time/ { print $3 }')
        loop[$c $every $threads]+="$t "
      done
    done
  done
done
echo "loop seconds, medians of $rounds (runs); sort_every 0 | 1000, on/off:"
for c in "${cases[@]}"; do
  for threads in 1 2; do
    echo "$c ${threads}t ${loop[$c 0 $threads]}| ${loop[$c 1000 $threads]}" | /usr/bin/python3 -c '
import statistics, sys
name, threads, rest = sys.stdin.read().split(" ", 2)
off, on = ([float(x) for x in part.split()] for part in rest.split("|"))
m_off, m_on = statistics.median(off), statistics.median(on)
print(f"  {name:18s} {threads}: off {m_off:.3f} ({min(off):.3f}-{max(off):.3f}), "
      f"on {m_on:.3f} ({min(on):.3f}-{max(on):.3f}); on/off {m_on / m_off:.3f}")'
  done
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
