#!/usr/bin/env bash
# Whether two deli binaries give the same results bit for bit: runs a set of inputs
# (shortened) with each and compares their thermo CSVs (17 significant digits) byte for
# byte (when one binary has columns the other lacks: the shared columns, and it names the
# others). Usage: tools/same_results.sh DELI_A DELI_B [input.toml[:steps] ...]
# IGNORE="col1 col2" leaves those columns out of the comparison (a column a change means to
# alter). Default inputs: the default rigid slit, every paper input, the hard-sphere fluid
# and the rigid-rod chain melt.
set -uo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
a=$(realpath "$1") b=$(realpath "$2")
shift 2
cases=("$@")
if [[ ${#cases[@]} -eq 0 ]]; then
  cases=(inputs/lj_chains/rigid_slit.toml:1500 inputs/hard_spheres/hs_4000.toml:1000
         inputs/lj_chains/chains_4000_rigid.toml:300)
  for f in "$top"/inputs/paper/*.toml; do cases+=("inputs/paper/$(basename "$f"):20000"); done
fi
work=$(mktemp -d /tmp/deli-same-results.XXXXXX)
trap 'rm -rf "$work"' EXIT
status=0
for spec in "${cases[@]}"; do
  input=${spec%%:*}
  steps=${spec#"$input"}
  steps=${steps#:}
  name=$(basename "$input" .toml)
  for side in a b; do
    dir=$work/$side/$name
    mkdir -p "$dir"
    cp "$top/$(dirname "$input")"/*.data "$dir"/ 2>/dev/null || true
    # Keep the step count when the input asks for fewer; thermo to a known file.
    awk -v cap="$steps" '
      /^\[/ { section = $0 }
      section == "[run]" && /^steps *=/ && cap != "" { split($0, f, "="); if (f[2] + 0 > cap) $0 = "steps = " cap }
      section == "[output]" && /^thermo *=/ {
        if ($0 ~ /file *=/) sub(/file *= *"[^"]*"/, "file = \"thermo.csv\"")
        else sub(/} *$/, ", file = \"thermo.csv\" }")
        has_thermo = 1
      }
      { print }
      # No thermo table at all: one every 100 steps, so that there is something to compare.
      END { if (!has_thermo) print "[output.thermo]\nevery = 100\nfile = \"thermo.csv\"" }' "$top/$input" > "$dir/input.toml"
    deli=$a
    [[ $side == b ]] && deli=$b
    (cd "$dir" && "$deli" run input.toml > run.log 2>&1) || echo "$name: run $side failed"
  done
  if cmp -s "$work/a/$name/thermo.csv" "$work/b/$name/thermo.csv"; then
    echo "$name: identical ($(wc -l < "$work/a/$name/thermo.csv") thermo rows)"
  elif /usr/bin/python3 - "$work/a/$name/thermo.csv" "$work/b/$name/thermo.csv" "${IGNORE:-}" <<'PY'
# A binary that adds (or drops) statistics columns, or columns named in IGNORE (one that is
# meant to change): the other columns both have, byte for byte.
import csv, sys
a, b = (list(csv.reader(open(f))) for f in sys.argv[1:3])
ignored = set(sys.argv[3].replace(",", " ").split())
if not a or not b or len(a) != len(b):
    sys.exit(1)
shared = [c for c in a[0] if c in b[0] and c not in ignored]
ia, ib = [a[0].index(c) for c in shared], [b[0].index(c) for c in shared]
if any([ra[i] for i in ia] != [rb[i] for i in ib] for ra, rb in zip(a[1:], b[1:])):
    sys.exit(1)
only = sorted((set(a[0]) ^ set(b[0])) | (ignored & set(a[0]) & set(b[0])))
print(f"identical in the {len(shared)} shared columns; not compared: {', '.join(only)}", end="")
PY
  then
    echo " ($name, $(wc -l < "$work/a/$name/thermo.csv") thermo rows)"
  else
    echo "$name: DIFFERENT"
    status=1
  fi
done
exit $status
