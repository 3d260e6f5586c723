#!/usr/bin/env bash
# Where a run's threads spend their time, loop by loop: runs `deli run INPUT --threads N`
# with the thread team's profile on (DELI_TEAM_PROFILE, engine/core/team_profile.hpp) and
# prints, per parallel loop (each job function handed to the team), its calls and, in
# milliseconds over the step loop (not the set-up or the final output: the calling thread's
# columns add up to the run's loop time): the calling thread's own chunks, its waits for the
# workers after them, the slowest worker's chunks, and the calling thread's time alone before
# the loop since the team's previous job (serial work, while the workers wait). Loops whose own
# and worker times differ are unbalanced; a large serial time before a loop is serial work
# on the step's path. The results are the run's usual ones (the profile only reads clocks).
# usage: tools/team_profile.sh INPUT.toml [THREADS (default 2)] [ROWS (default 20)]
#   DELI=path/to/deli tools/team_profile.sh ...   another binary (default build/deli)
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
deli=${DELI:-$top/build/deli}
input=${1:?usage: tools/team_profile.sh INPUT.toml [THREADS] [ROWS]}
threads=${2:-2}
rows=${3:-20}
table=$(mktemp)
trap 'rm -f "$table"' EXIT
DELI_TEAM_PROFILE=$table "$deli" run "$input" --threads "$threads" | grep -E '^(loop time|[0-9]+ threads?)'
/usr/bin/python3 - "$table" "$rows" <<'PY'
import re, subprocess, sys
from collections import defaultdict

table, rows = sys.argv[1], int(sys.argv[2])
entries = []
for line in open(table):
    if line.startswith("#"):
        continue
    calls, own, wait, worker, serial, obj, offset = line.split()
    entries.append((int(calls), float(own), float(wait), float(worker), float(serial), obj, offset))
# Names for every offset, one addr2line per object file.
by_object = defaultdict(list)
for e in entries:
    by_object[e[5]].append(e[6])
names = {}
for obj, offsets in by_object.items():
    try:
        out = subprocess.run(["addr2line", "-f", "-C", "-e", obj, *offsets], capture_output=True,
                             text=True, check=True).stdout.split("\n")
        for k, offset in enumerate(offsets):
            names[(obj, offset)] = out[2 * k]
    except (OSError, subprocess.CalledProcessError):
        pass
wrappers = ("run_on_team", "for_each_chunk_then", "for_each_chunk", "for_each_range_then",
            "parallel_for", "ordered_max_then", "ordered_max", "ordered_sum", "filter_in_order",
            "copy_in_chunks")
def short(name):
    # run_on_team<for_each_chunk<Gvi::predict(...)::{lambda...}>...>: the loop's function,
    # with the helpers it went through.
    name = name.replace("deli::", "")
    through = []
    while True:
        m = re.match(r"(%s)<" % "|".join(wrappers), name)
        if not m:
            break
        if m.group(1) != "run_on_team":
            through.append(m.group(1))
        name = name[m.end():]
    name = re.split(r"[(]", name, maxsplit=1)[0]
    return name + (" [" + ", ".join(through) + "]" if through else "")
if not entries:
    sys.exit("no loop ran on the team (on one thread every loop runs on the calling thread)")
print(f"{'calls':>7} {'own ms':>9} {'wait ms':>9} {'worker ms':>9} {'serial ms':>9}  loop")
total = [0.0] * 4
for calls, own, wait, worker, serial, obj, offset in entries:
    total = [t + v for t, v in zip(total, (own, wait, worker, serial))]
for calls, own, wait, worker, serial, obj, offset in entries[:rows]:
    name = short(names.get((obj, offset), f"{obj} {offset}"))
    print(f"{calls:7d} {own:9.3f} {wait:9.3f} {worker:9.3f} {serial:9.3f}  {name[:100]}")
if len(entries) > rows:
    print(f"  ({len(entries) - rows} more loops)")
print(f"{'all':>7} {total[0]:9.3f} {total[1]:9.3f} {total[2]:9.3f} {total[3]:9.3f}")
PY
