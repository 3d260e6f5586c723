#!/usr/bin/env bash
# deli on two threads where other processes crowd the CPUs: an input alone, two runs of it at
# once, and one beside a CPU-bound process (`yes`), `ROUNDS` times each; prints the loop
# times. The team's waits turn `passive` for a second when a wait within a job outlasts 200 us
# while Linux's CPU pressure (/proc/pressure/cpu) shows threads waiting for a CPU
# (engine/core/thread_team.cpp): compare with DELI=<an older binary>.
#   bench/crowded.sh                                  the default input's first 4000 steps
#   ROUNDS=5 DELI=path/to/deli bench/crowded.sh input.toml:steps
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
deli=$(realpath "${DELI:-$top/build/deli}")
rounds=${ROUNDS:-3}
spec=${1:-$top/inputs/lj_chains/rigid_slit.toml:4000}
input=$(realpath "${spec%%:*}") steps=${spec##*:}
work=$(mktemp -d /tmp/deli-bench-crowded.XXXXXX)
trap 'rm -rf "$work"' EXIT
# The input with its data file made absolute, its step count, and no outputs.
awk -v dir="$(dirname "$input")" -v cap="$steps" '
  /^\[/ { section = $0 }
  section == "[output]" { next }
  /^data *=/ { sub(/"/, "\"" dir "/") }
  section == "[run]" && /^steps *=/ { $0 = "steps = " cap }
  { print }' "$input" > "$work/input.toml"
loop() { awk '/^loop time/ { printf "%s ", $3 }'; }
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg); $(nproc) cores; $deli"
for ((r = 0; r < rounds; ++r)); do
  alone=$(cd "$work" && "$deli" run input.toml --threads 2 | loop)
  pair=$(cd "$work" && { "$deli" run input.toml --threads 2 | loop & "$deli" run input.toml \
    --threads 2 | loop; wait; })
  yes > /dev/null &
  busy=$!
  beside=$(cd "$work" && "$deli" run input.toml --threads 2 | loop)
  kill "$busy"
  echo "round $r: alone ${alone}s; two at once ${pair}s; beside a busy process ${beside}s"
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
