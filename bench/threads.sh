#!/usr/bin/env bash
# deli on 1 and 2 threads (and, with DELI_OLD, an older binary on 1 thread) beside its peers,
# alternated in one run so that the ratios share the machine's load: the LJ liquid (4000 and
# 32000), the rigid-rod chain melt (GVI), the hard-sphere fluid (GVI, 4000 and 32000) and the
# default input (`deli run`: the rigid-rod slit, 1200 beads, GVI with contacts, walls and a
# Langevin start). Prints atom-steps/s per run, the medians, each engine's scaling and deli's
# ratio to each peer; each input's header, the cores' cache line round trip before its runs and
# after each round.
#   bench/threads.sh                       3 rounds, each input's own step count capped
#   ROUNDS=5 DELI_OLD=/tmp/deli-old bench/threads.sh [input.toml:steps ...]
#   THREADS="1 2 4" bench/threads.sh       other thread (and rank) counts
#   PEERS=0 bench/threads.sh               deli alone
#   CEILING=0 bench/threads.sh             without the machine's ceiling (below)
#   UNSPLIT=1 bench/threads.sh             also deli with [run] split_small_loops = false on
#                                          each count above 1 ("unsplit-deli": README, "Threads
#                                          and vector instructions"), its speed over deli's
#   UNBALANCED=1 bench/threads.sh          also deli with [run] balance_threads = false (equal
#                                          chunks, "unbalanced-deli"), its speed over deli's
# The peers run in process from bench/peers (deli-peers, built here on first use): OpenMM's
# CPU platform on the same thread counts (CCMA at 1e-4 for rods), LAMMPS on as many MPI ranks
# (mpirun -np N; with rods LAMMPS gets its own model: see deli-peers). The hard-sphere fluid
# has no peer (neither engine has hard spheres), nor has the default input.
# Every one-thread run (deli's, the old binary's, OpenMM's, serial LAMMPS') is pinned with
# taskset: a round's on one core, the next round's on the next; multi-thread runs are not.
# The machine's ceiling: two one-thread deli runs of the input at once, their rates summed,
# over one run alone (with the first two thread counts 1 and 2). No two-thread code can beat
# it; on a machine whose cores slow each other (shared caches, memory bandwidth, a host's
# other tenants) it is below 2.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
deli=${DELI:-$top/build/deli}
old=${DELI_OLD:-}
rounds=${ROUNDS:-3}
ceiling=${CEILING:-1}
unsplit=${UNSPLIT:-0}
unbalanced=${UNBALANCED:-0}
read -r -a counts <<< "${THREADS:-1 2}"
source "$top/bench/peers/locate.sh"
mpirun=${MPIRUN:-$(command -v mpirun || true)}
# The wait policy as a user gets it: deli's team's default (a waiting worker spins a few
# milliseconds, then sleeps; core/thread_team.hpp) unless OMP_WAIT_POLICY is set, which deli's
# team and the peers' OpenMP honour. On a machine shared with other work spinning threads take
# the core their partners need (a 4000-atom LJ run 30x slower, measured with libgomp's regions):
# run this on an idle machine, or set OMP_WAIT_POLICY=passive there. The load before and after
# is printed.
wait=${OMP_WAIT_POLICY:-}
source "$top/bench/cores.sh"
# input:steps (shortened; throughput, not physics)
cases=(inputs/lj_liquid/lj_4000.toml:2000 inputs/lj_liquid/lj_32000.toml:300
       inputs/lj_chains/chains_4000_rigid.toml:300 inputs/hard_spheres/hs_4000.toml:1000
       inputs/hard_spheres/hs_32000.toml:200 inputs/lj_chains/rigid_slit.toml:1500)
[[ $# -gt 0 ]] && cases=("$@")
# Reads lines "ENGINE THREADS RATE...": medians, scaling and deli's ratio to each peer.
summarise=$(cat <<'PY'
import statistics, sys
median, order = {}, []
for line in sys.stdin:
    engine, threads, *rates = line.split()
    if not rates:
        continue
    median[(engine, threads)] = statistics.median(float(x) for x in rates)
    order.append((engine, threads))
    print(f"  {engine}, {threads}: median {median[(engine, threads)]:.4g} atom-steps/s"
          f" (runs: {' '.join(rates)})")
counts = sorted({t for _, t in order}, key=int)
for engine in dict.fromkeys(e for e, _ in order):
    if engine in ("old-deli", "two-deli", "unsplit-deli", "unbalanced-deli"):
        continue
    base = median.get((engine, counts[0]))
    scaling = [f"{t}: {median[(engine, t)] / base:.2f}x" for t in counts[1:]
               if base and (engine, t) in median]
    if scaling:
        print(f"  {engine} scaling over {counts[0]}: {', '.join(scaling)}")
for t in counts:
    ratios = [f"{e} {median[('deli', t)] / median[(e, t)]:.2f}x" for e in ("openmm", "lammps")
              if ("deli", t) in median and (e, t) in median]
    if ratios:
        print(f"  deli / peer at {t}: {', '.join(ratios)}")
if ("two-deli", "1") in median and ("deli", "1") in median:
    print(f"  machine's ceiling (two one-thread runs at once / one alone): "
          f"{median[('two-deli', '1')] / median[('deli', '1')]:.2f}x")
for t in counts[1:]:
    if ("unsplit-deli", t) in median and ("deli", t) in median:
        scaling = (f", over deli on {counts[0]}: {median[('unsplit-deli', t)] / median[('deli', counts[0])]:.2f}x"
                   if ("deli", counts[0]) in median else "")
        print(f"  split_small_loops = false on {t}: {median[('unsplit-deli', t)] / median[('deli', t)]:.2f}x"
              f" deli's speed{scaling}")
for t in counts[1:]:
    if ("unbalanced-deli", t) in median and ("deli", t) in median:
        print(f"  balance_threads = false on {t}: "
              f"{median[('unbalanced-deli', t)] / median[('deli', t)]:.3f}x deli's speed")
if ("old-deli", counts[0]) in median and ("deli", counts[0]) in median:
    print(f"  new / old deli on {counts[0]}: "
          f"{median[('deli', counts[0])] / median[('old-deli', counts[0])]:.3f}x")
PY
)
work=$(mktemp -d /tmp/deli-bench-threads.XXXXXX)
trap 'rm -rf "$work"' EXIT
# The cores' distance: a cache line's round trip between two threads (deli-parallel-overhead,
# when built). On this project's 2-core VM it moved between about 170 and 510 ns as the host
# placed the two vCPUs, and the GVI inputs' scaling with it (bench/README.md, "Stop 38").
overhead=$top/build/bench/parallel_overhead/deli-parallel-overhead
round_trip() {
  [[ -x $overhead ]] || { echo "not measured (cmake --build build --target deli-parallel-overhead)"; return; }
  OMP_NUM_THREADS=2 "$overhead" --benchmark_filter=CacheLineRoundTrip 2>/dev/null |
    grep -oE 'per_round_trip=[0-9.]+[a-z]+' | cut -d= -f2
}
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg); $(nproc) cores; OMP_WAIT_POLICY=${wait:-unset (default)}"
echo "cache line round trip between two threads before: $(round_trip)"
echo "thread/rank counts: ${counts[*]}; peers: ${peers:-none}; mpirun: ${mpirun:-none}"
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
  if [[ $unsplit == 1 ]]; then
    sed 's/^\[run\]$/[run]\nsplit_small_loops = false/' "$dir/input.toml" > "$dir/input_unsplit.toml"
  fi
  if [[ $unbalanced == 1 ]]; then
    sed 's/^\[run\]$/[run]\nbalance_threads = false/' "$dir/input.toml" > "$dir/input_unbalanced.toml"
  fi
  declare -A rate=()
  variants=()
  [[ -n $old ]] && variants+=("old-deli ${counts[0]}")
  for t in "${counts[@]}"; do variants+=("deli $t"); done
  if [[ $unsplit == 1 ]]; then
    for t in "${counts[@]:1}"; do variants+=("unsplit-deli $t"); done
  fi
  if [[ $unbalanced == 1 ]]; then
    for t in "${counts[@]:1}"; do variants+=("unbalanced-deli $t"); done
  fi
  [[ $ceiling == 1 && ${counts[0]} == 1 && ${counts[1]:-} == 2 ]] && variants+=("two-deli 1")
  has_peers=
  if [[ -n $peers ]] && (cd "$dir" && "$peers" input.toml 1 openmm > /dev/null 2>&1); then
    has_peers=1
    for t in "${counts[@]}"; do variants+=("openmm $t"); done
    for t in "${counts[@]}"; do
      [[ $t == 1 || -n $mpirun ]] && variants+=("lammps $t")
    done
  fi
  trip_before=$(round_trip)
  trips=
  for ((r = 0; r < rounds; ++r)); do
    # The one-thread runs of a round share one core, the next round's the next core: the two
    # vCPUs of this project's machine have run at speeds 1.5x apart for minutes at a time
    # (bench/README.md, "Stop 41"), and unpinned consecutive runs tended to land on alternate
    # cores, so that which engine got the fast core decided the ratio.
    one=(taskset -c "${cores[r % ${#cores[@]}]}")
    for v in "${variants[@]}"; do
      read -r engine threads <<< "$v"
      pin=()
      [[ $threads == 1 && $engine != two-deli ]] && pin=("${one[@]}")
      case $engine in
        old-deli)
          line=$(cd "$dir" && "${pin[@]}" env ${wait:+OMP_WAIT_POLICY=$wait} OMP_NUM_THREADS=$threads "$old" run input.toml |
            grep "^loop time") ;;
        deli)
          line=$(cd "$dir" && "${pin[@]}" env ${wait:+OMP_WAIT_POLICY=$wait} OMP_NUM_THREADS=$threads "$deli" run input.toml \
            --threads "$threads" | grep "^loop time") ;;
        unsplit-deli)
          line=$(cd "$dir" && env ${wait:+OMP_WAIT_POLICY=$wait} OMP_NUM_THREADS=$threads "$deli" run \
            input_unsplit.toml --threads "$threads" | grep "^loop time") ;;
        unbalanced-deli)
          line=$(cd "$dir" && env ${wait:+OMP_WAIT_POLICY=$wait} OMP_NUM_THREADS=$threads "$deli" run \
            input_unbalanced.toml --threads "$threads" | grep "^loop time") ;;
        two-deli)
          # Both runs' rates summed, printed as one line for the parse below; one run a core.
          runs=$(cd "$dir" && {
            taskset -c "${cores[0]}" env ${wait:+OMP_WAIT_POLICY=$wait} OMP_NUM_THREADS=1 \
              "$deli" run input.toml --threads 1 | grep "^loop time" &
            taskset -c "${cores[1 % ${#cores[@]}]}" env ${wait:+OMP_WAIT_POLICY=$wait} \
              OMP_NUM_THREADS=1 "$deli" run input.toml --threads 1 | grep "^loop time"
            wait
          })
          line="$(echo "$runs" | grep -oE '[0-9.]+e[+-]?[0-9]+ atom-steps/s' |
            awk '{ sum += $1 } END { printf "%.4e atom-steps/s", sum }')" ;;
        openmm)
          line=$(cd "$dir" && "${pin[@]}" "$peers" input.toml "$steps" openmm 1e-4 "$threads") ||
            echo "note: OpenMM on $threads thread(s) failed on $name" >&2 ;;
        lammps)
          if [[ $threads == 1 ]]; then
            line=$(cd "$dir" && "${pin[@]}" env OMP_NUM_THREADS=1 "$peers" input.toml "$steps" lammps) ||
              echo "note: LAMMPS failed on $name" >&2
          else
            line=$(cd "$dir" && OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 \
              OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "$mpirun" -np "$threads" --oversubscribe \
              "$peers" input.toml "$steps" lammps) ||
              echo "note: LAMMPS on $threads MPI ranks failed on $name ($mpirun)" >&2
          fi ;;
      esac
      value=$(echo "$line" | grep -oE '[0-9.]+e[+-]?[0-9]+ atom-steps/s|atom-steps/s [0-9.e+-]+' |
        grep -oE '[0-9.]+(e[+-]?[0-9]+)?' | head -1 || true)
      rate[$v]+="$value "
    done
    trips+="$(round_trip) "
  done
  summary=$(for v in "${variants[@]}"; do echo "$v ${rate[$v]}"; done |
    /usr/bin/python3 -c "$summarise")
  # The cores' distance before the case's runs and after each round: a host that moves the
  # cores apart within a case (this project's VM: 100 <-> 400 ns every few minutes) changes
  # its ratios, and the rounds it moved them in show which runs to discount.
  echo "$name ($steps steps${has_peers:+; peers: OpenMM CPU, LAMMPS}; round trip $trip_before, then after each round: ${trips% }):"
  echo "$summary"
  unset rate
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "cache line round trip between two threads after: $(round_trip)"
