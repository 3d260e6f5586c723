#!/usr/bin/env bash
# Throughput of deli and LAMMPS (serial) on the same LJ liquid inputs, one after the other.
# Needs Debian's lammps package for `lmp`. Usage: bench/lj_liquid.sh [4000|32000 ...]
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
deli=${DELI:-$top/build/deli}
cd "$top/inputs/lj_liquid"
for n in "${@:-4000 32000}"; do
  for size in $n; do
    deli_line=$("$deli" run "lj_$size.toml" | grep "^loop time")
    lmp -in "in.lj_$size" -log "/tmp/deli-bench-lmp-$size.log" > /dev/null
    loop=$(grep "Loop time" "/tmp/deli-bench-lmp-$size.log")
    read -r seconds steps atoms <<< "$(echo "$loop" | awk '{print $4, $9, $12}')"
    echo "lj_$size deli:   $deli_line"
    echo "lj_$size lammps: $loop: $(awk -v s="$seconds" -v n="$steps" -v a="$atoms" 'BEGIN{printf "%.4g atom-steps/s", n*a/s}')"
  done
done
