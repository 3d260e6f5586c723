#!/usr/bin/env bash
# The two commands of the quick start, on Debian 12 as root:
#   ./setup.sh run [INPUT]   install what is missing, build (Release), run INPUT
#                            (no INPUT: the default input, inputs/lj_chains/rigid_slit.toml)
#   ./setup.sh test          install what is missing, build, run every test (ctest)
# Re-running with nothing changed skips apt and rebuilds nothing.
set -euo pipefail
cd "$(dirname "$0")"

action=${1:-}
case "$action" in
  run | test) shift ;;
  *)
    echo "usage: ./setup.sh run [INPUT] | ./setup.sh test" >&2
    exit 2
    ;;
esac

packages=(g++ make cmake pkg-config libeigen3-dev libhdf5-dev libgtest-dev libgmock-dev
  libtomlplusplus-dev libopenmm-dev libopenmm-plugins liblammps-dev)
# The trajectory tests read deli's H5MD files as a user would, with Debian's Python; CI
# (.ci/run) also builds the fuzz targets with clang's libFuzzer (tools/fuzz.sh).
[ "$action" = test ] && packages+=(python3-h5py python3-numpy python3-mdanalysis python3-matplotlib
  clang libclang-rt-14-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup: these Debian packages are missing and installing them needs root:" >&2
    echo "  apt-get install ${missing[*]}" >&2
    exit 1
  fi
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

jobs=$(nproc)
[ -f build/Makefile ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j "$jobs"

if [ "$action" = run ]; then
  exec build/deli run "$@"
fi
cd build
ctest --output-on-failure -j "$jobs"
