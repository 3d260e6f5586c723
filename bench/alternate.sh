#!/usr/bin/env bash
# Two deli binaries on one input, alternated run by run (this machine's speed drifts by tens of
# percent between minutes: only runs side by side compare), and per binary the median and best
# of the loop time and of each phase of the timing table.
# Usage: bench/alternate.sh OLD NEW INPUT.toml [ROUNDS (default 5)], with THREADS=n (default 1).
# Runs from a scratch copy of the input's folder (its data files beside it). Not a test.
set -euo pipefail
old=$(realpath "$1") new=$(realpath "$2") input=$(realpath "$3")
rounds=${4:-5}
work=$(mktemp -d /tmp/deli-alternate.XXXXXX)
trap 'rm -rf "$work"' EXIT
cp "$(dirname "$input")"/*.data "$work"/ 2>/dev/null || true
cp "$input" "$work/input.toml"
# One line per run: binary, then "name=seconds" for the loop and each phase.
table() {
  awk -v who="$1" '
    /^loop time/ { line = who " loop=" $3 }
    /^phase/ { on = 1; next }
    on && NF >= 3 { name = $1; for (i = 2; i < NF - 1; ++i) name = name "_" $i; line = line " " name "=" $(NF - 1) }
    END { print line }'
}
# On one thread both binaries of a round run on the same core, the core moving round by round:
# this machine's two virtual cores ran one binary at 0.87-0.97 s and 1.25-1.34 s minutes
# apart, and unpinned, consecutive runs tended to land on alternate cores, so that one binary
# ran on the slow core far more often (bench/README.md, "Stop 41").
source "$(dirname "$0")/cores.sh"
runs=$(for ((k = 0; k < rounds; ++k)); do
  pin=()
  [[ ${THREADS:-1} == 1 && ${#cores[@]} -gt 1 ]] && command -v taskset > /dev/null &&
    pin=(taskset -c "${cores[k % ${#cores[@]}]}")
  for side in old new; do
    bin=$old
    [[ $side == new ]] && bin=$new
    (cd "$work" && "${pin[@]}" "$bin" run input.toml --threads "${THREADS:-1}") | table "$side"
  done
done)
for side in old new; do
  echo "$runs" | awk -v side="$side" '
    $1 == side { for (i = 2; i <= NF; ++i) { split($i, kv, "="); v[kv[1]] = v[kv[1]] " " kv[2]; if (!(kv[1] in seen)) { seen[kv[1]] = 1; order[++n] = kv[1] } } }
    END {
      printf "%s:", side
      for (k = 1; k <= n; ++k) {
        m = split(v[order[k]], x, " ")
        for (i = 1; i <= m; ++i) for (j = i + 1; j <= m; ++j) if (x[j] < x[i]) { t = x[i]; x[i] = x[j]; x[j] = t }
        printf " %s %s (best %s)", order[k], x[int((m + 1) / 2)], x[1]
      }
      printf "\n"
    }'
done
