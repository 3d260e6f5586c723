#!/usr/bin/env bash
# deli on 1 and 2 threads (and, with DELI_OLD, an older binary on 1 thread), alternated
# in one run so that the ratios share the machine's load: the LJ liquid (4000 and 32000),
# the rigid-rod chain melt (GVI) and the hard-sphere fluid (GVI). Prints atom-steps/s per
# run and the ratios of the medians.
#   bench/threads.sh                       3 rounds, each input's own step count capped
#   ROUNDS=5 DELI_OLD=/tmp/deli-old bench/threads.sh [input.toml:steps ...]
# The peers (LAMMPS serial and 2 MPI ranks, OpenMM CPU on 1 and 2 threads) run in process
# from bench/peers (issue 10's driver).
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
deli=${DELI:-$top/build/deli}
old=${DELI_OLD:-}
rounds=${ROUNDS:-3}
# Threads waiting at a barrier sleep: on a shared machine a spinning thread takes the core
# its partner needs (a 4000-atom LJ run 30x slower, measured). OMP_WAIT_POLICY=active
# (libgomp spins a while first) suits a machine of one's own.
wait=${OMP_WAIT_POLICY:-passive}
# input:steps (shortened; throughput, not physics)
cases=(inputs/lj_liquid/lj_4000.toml:2000 inputs/lj_liquid/lj_32000.toml:300
       inputs/lj_chains/chains_4000_rigid.toml:300 inputs/hard_spheres/hs_4000.toml:1000)
[[ $# -gt 0 ]] && cases=("$@")
# Reads lines "old|new THREADS RATE...": medians and their ratios.
summarise=$(cat <<'PY'
import statistics, sys
median = {}
for line in sys.stdin:
    which, threads, *rates = line.split()
    key = f"{which} {threads}"
    median[key] = statistics.median(float(x) for x in rates)
    print(f"  {which} deli, {threads} thread(s): median {median[key]:.4g} atom-steps/s"
          f" (runs: {' '.join(rates)})")
ratio = f"  2 threads / 1 thread: {median['new 2'] / median['new 1']:.2f}x"
if "old 1" in median:
    ratio += f"; new / old on 1 thread: {median['new 1'] / median['old 1']:.3f}x"
print(ratio)
PY
)
work=$(mktemp -d /tmp/deli-bench-threads.XXXXXX)
trap 'rm -rf "$work"' EXIT
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg); $(nproc) cores; OMP_WAIT_POLICY=$wait"
for spec in "${cases[@]}"; do
  input=${spec%%:*} steps=${spec#*:}
  name=$(basename "$input" .toml)
  dir=$work/$name
  mkdir -p "$dir"
  cp "$top/$(dirname "$input")"/*.data "$dir"/ 2>/dev/null || true
  # The input without its outputs, at the capped step count.
  awk -v cap="$steps" '
    /^\[/ { section = $0 }
    section == "[output]" { next }
    section == "[run]" && /^steps *=/ { $0 = "steps = " cap }
    { print }' "$top/$input" > "$dir/input.toml"
  declare -A rate=()
  variants=("new 1" "new 2")
  [[ -n $old ]] && variants=("old 1" "${variants[@]}")
  for ((r = 0; r < rounds; ++r)); do
    for v in "${variants[@]}"; do
      read -r which threads <<< "$v"
      bin=$deli
      [[ $which == old ]] && bin=$old
      args=(--threads "$threads")
      [[ $which == old ]] && args=()
      line=$(cd "$dir" && OMP_WAIT_POLICY=$wait OMP_NUM_THREADS=$threads "$bin" run input.toml "${args[@]}" | grep "^loop time")
      value=$(echo "$line" | sed -E 's/.*: ([0-9.e+]+) atom-steps\/s.*/\1/')
      rate[$v]+="$value "
    done
  done
  summary=$(for v in "${variants[@]}"; do echo "$v ${rate[$v]}"; done |
    /usr/bin/python3 -c "$summarise")
  echo "$name ($steps steps):"
  echo "$summary"
  unset rate
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
