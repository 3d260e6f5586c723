#!/usr/bin/env bash
# Cache order ([neighbor] cell_order): CPU seconds of deli on one thread with the option
# off and on, alternated in one run, the particles themselves never sorted (sort_every = 0;
# bench/sort_every.sh measures that), on the LJ liquid 4000 and 32000 as built (fcc lattice
# order: neighbours are near in index already) and with the atoms' indices shuffled (a
# liquid after long mixing: neighbours anywhere in memory). Prints each run's user CPU
# seconds and the medians' ratios.
#   bench/cell_order.sh              3 rounds
#   ROUNDS=5 DELI=path/to/deli bench/cell_order.sh
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
deli=$(realpath "${DELI:-$top/build/deli}")
rounds=${ROUNDS:-3}
# Reads "ORDER OFF_TIMES | ON_TIMES": medians and their ratio.
summarise=$(cat <<'PY'
import statistics, sys
order, rest = sys.stdin.read().split(" ", 1)
off, on = ([float(x) for x in part.split()] for part in rest.split("|"))
m_off, m_on = statistics.median(off), statistics.median(on)
print(f"  {order}: cell_order off {m_off:.2f} s (runs {' '.join(map(str, off))}),"
      f" on {m_on:.2f} s (runs {' '.join(map(str, on))}); on/off {m_on / m_off:.3f}")
PY
)
work=$(mktemp -d /tmp/deli-bench-cell-order.XXXXXX)
trap 'rm -rf "$work"' EXIT
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg); $(nproc) cores"
for spec in lj_4000:1000 lj_32000:150; do
  name=${spec%%:*} steps=${spec#*:}
  # The data file as built, and with atom k given the position and velocity of atom p(k)
  # for a fixed random permutation p (the same liquid, its indices scrambled).
  cp "$top/inputs/lj_liquid/$name.data" "$work/${name}_lattice.data"
  /usr/bin/python3 "$top/bench/shuffle_atoms.py" "$work/${name}_lattice.data" \
    "$work/${name}_shuffled.data"
  for order in lattice shuffled; do
    for option in false true; do
      awk -v data="${name}_$order.data" -v cap="$steps" -v option="$option" '
        /^\[/ { section = $0 }
        section == "[output]" { next }
        /^data *=/ { $0 = "data = \"" data "\"" }
        section == "[neighbor]" && /^skin/ { $0 = $0 "\ncell_order = " option "\nsort_every = 0" }
        section == "[run]" && /^steps *=/ { $0 = "steps = " cap }
        { print }' "$top/inputs/lj_liquid/$name.toml" > "$work/${name}_${order}_$option.toml"
    done
  done
  declare -A cpu=()
  for ((r = 0; r < rounds; ++r)); do
    for order in lattice shuffled; do
      for option in false true; do
        t=$(cd "$work" && { OMP_NUM_THREADS=1 /usr/bin/time -f %U "$deli" run \
              "${name}_${order}_$option.toml" > /dev/null; } 2>&1 | tail -1)
        cpu[$order $option]+="$t "
      done
    done
  done
  echo "$name ($steps steps, 1 thread; user CPU seconds, including reading the input):"
  for order in lattice shuffled; do
    echo "$order ${cpu[$order false]}| ${cpu[$order true]}" | /usr/bin/python3 -c "$summarise"
  done
  unset cpu
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
