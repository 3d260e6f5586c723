#!/usr/bin/env bash
# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer (g++), in build-asan/.
#   tools/sanitize.sh          configure if needed, build, run the tests
#   tools/sanitize.sh -R REGEX extra arguments go to ctest (both passes)
# Any report stops the test that hit it (halt_on_error, -fno-sanitize-recover): a finding
# is a failing test, never a line in a log. OpenMM and LAMMPS (with OpenMPI) are
# uninstrumented Debian shared libraries; their leaks are suppressed by
# tools/sanitizers/lsan.supp, a heap overflow inside HDF5 by asan.supp, each entry scoped
# to a library and explained there. deli code is never exempt.
set -euo pipefail
cd "$(dirname "$0")/.."
here=$PWD/tools/sanitizers
jobs=${DELI_JOBS:-$(nproc)}

# -O1: the reports keep useful stacks; -g1: line numbers without full debug info (the link
# stays small). float-cast-overflow: a double out of range cast to an integer (a hostile
# count); GCC does not include it in "undefined".
flags="-O1 -g1 -fno-omit-frame-pointer -fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all"
if [ ! -f build-asan/Makefile ]; then
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Sanitize \
    -DCMAKE_CXX_FLAGS_SANITIZE="$flags" -DCMAKE_C_FLAGS_SANITIZE="$flags" \
    -DCMAKE_EXE_LINKER_FLAGS_SANITIZE="-fsanitize=address,undefined"
fi
cmake --build build-asan -j "$jobs"

# Left out, for CI time only (each costs minutes under ASan, and runs code the other tests
# run, for longer): the statistical and long-run tests, which average over 1e4-1e6 steps of
# a 4000-atom or 32000-atom system, and validation of the two 32000-atom and the
# chain-benchmark inputs. They run in the plain pass (./setup.sh test); run them here with
#   DELI_SANITIZE_ALL=1 tools/sanitize.sh
long="ShadowEnergy\.FluctuatesFarLessThanTheEnergy|VelocityVerlet\.LjLiquidEnergyBounded"
long+="|LangevinCrosscheck\.|Both/Thermostat\.|Pressure\.HardSphereFluid"
long+="|ValidatesAgainstOpenMMAndLammps/.*(32000|chain_benchmark)"
long+="|PaperExamples\.PogoStickBoundedTo1e5|GviFeasibility\.PogoStickShadowReflections"
long+="|Thermostatted/EveryIntegrator\.|PaperReproduction\."
# Left out because LeakSanitizer itself fails: after both tests on chains_4000_harmonic pass,
# its tracer takes a SIGSEGV at the exit leak check ("LeakSanitizer has encountered a fatal
# error"), only on this input (seen in the full run; not investigated yet).
long+="|ShippedInput\..*/lj_chains_chains_4000_harmonic_toml"
[ -n "${DELI_SANITIZE_ALL:-}" ] && long="^$"

# allocator_may_return_null: an impossible size gets NULL, as from glibc. A damaged
# checkpoint (Checkpoint.EverySingleByteFlipIsRefusedOrHarmless) makes HDF5's metadata
# cache ask for a terabyte; HDF5 reports the NULL as an error and deli refuses the file,
# where ASan's allocator would abort. (A deli container still gets std::bad_alloc.)
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=0:check_initialization_order=1:allocator_may_return_null=1:suppressions=$here/asan.supp"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export LSAN_OPTIONS="suppressions=$here/lsan.supp:print_suppressions=0"
# The tests that start OpenMM or LAMMPS (the cross-check binary, and `deli validate`
# through the command line) leak what those libraries keep to the end. LSan's fast
# unwinder stops at their uninstrumented frames, and OpenMPI's components are dlclosed
# before the leak check (their frames lose their names), so these tests unwind with the
# slow, complete unwinder: the suppressions then match the library frames. It costs about
# 1.7x on allocation-heavy code, so only there.
crosscheck="$(build-asan/tests/deli_crosscheck_tests --gtest_list_tests |
  awk '/^[^ ].*\.$/ {sub(/\.$/, ""); print $1}' | sort -u | paste -sd'|')"
crosscheck="^($crosscheck)\\."

cd build-asan
status=0
ctest --output-on-failure -j "$jobs" -E "$crosscheck|$long" "$@" || status=1
ASAN_OPTIONS="$ASAN_OPTIONS:fast_unwind_on_malloc=0" \
  ctest --output-on-failure -j "$jobs" -R "$crosscheck" -E "$long" "$@" || status=1
exit $status
