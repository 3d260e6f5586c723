#!/usr/bin/env bash
# Throughput of deli on the constrained benchmarks, one after the other, with the loop's
# timing breakdown: the default input (rigid-rod slit, 1200 beads, GVI with shadow-H
# reflections and contacts), the 4000-bead LJ chain melt with harmonic bonds (velocity
# Verlet) and with rigid rods (GVI), and the hard-sphere fluid (eta 0.30, N 4000, GVI).
# Usage: bench/constrained.sh [slit|harmonic|rigid|spheres ...] (default: all), with
# STEPS=n to override every input's step count (DELI=path picks the binary).
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
deli=${DELI:-$top/build/deli}
work=$(mktemp -d /tmp/deli-bench-constrained.XXXXXX)
trap 'rm -rf "$work"' EXIT
declare -A inputs=(
  [slit]=inputs/lj_chains/rigid_slit.toml
  [harmonic]=inputs/lj_chains/chains_4000_harmonic.toml
  [rigid]=inputs/lj_chains/chains_4000_rigid.toml
  [spheres]=inputs/hard_spheres/hs_4000.toml
)
for name in ${@:-slit harmonic rigid spheres}; do
  input=$top/${inputs[$name]:?unknown benchmark $name}
  # Run from a copy beside its data file, so the thermo CSV lands in the scratch folder.
  dir=$work/$name
  mkdir -p "$dir"
  cp "$(dirname "$input")"/*.data "$dir"/ 2>/dev/null || true
  if [[ -n ${STEPS:-} ]]; then
    sed "s/^steps = .*/steps = $STEPS/" "$input" > "$dir/input.toml"
  else
    cp "$input" "$dir/input.toml"
  fi
  echo "== $name: ${inputs[$name]}${STEPS:+ ($STEPS steps)}"
  (cd "$dir" && "$deli" run input.toml | sed -n '/^loop time/,$p')
done
