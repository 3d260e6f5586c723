#!/usr/bin/env bash
# The build without the build machine's instruction set (`-DDELI_NATIVE=OFF`: the pair
# kernels, the rod chains' passes, the list build's candidate test, GVI's particle passes and
# the Langevin draws in their portable x86-64 forms, build-portable/) and the whole suite on it, as the README's
# test command runs it: the tests pass with DELI_NATIVE on and off. By hand: CI runs the
# suite on a portable build in its sanitizer pass (tools/sanitize.sh), not here.
#   tools/portable.sh            DELI_JOBS=N for N parallel compiles and tests (default: nproc)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${DELI_JOBS:-$(nproc)}
cmake -S . -B build-portable -DCMAKE_BUILD_TYPE=Release -DDELI_NATIVE=OFF > /dev/null
cmake --build build-portable -j "$jobs"
cd build-portable
ctest --output-on-failure -j "$jobs"
