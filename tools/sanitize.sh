#!/usr/bin/env bash
# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer (g++), in build-asan/.
#   tools/sanitize.sh          configure if needed, build, run the tests
#   tools/sanitize.sh -R REGEX extra arguments go to ctest (a suite's name, or Suite[1-16])
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
# count); GCC does not include it in "undefined". -O2 was measured and is not worth it: it
# compiles 12-28 % slower (heavy files, back to back) and the slowest tests ran no faster
# (ShadowEnergy 217 s against 228 s, VelocityVerlet.LjLiquid 193 against 191, loaded machine):
# the sanitizers' checks, not the optimiser, set their pace.
flags="-O1 -g1 -fno-omit-frame-pointer -fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all"
# CMAKE_UNITY_BUILD: the libraries' files compiled in batches of 8, as the tests' are in every
# build: the engine's, forcefields', io's and the cross-check's 450 CPU s become 322 (from
# scratch, back to back, g++ 12). Results do not depend on it (no -ffast-math, contraction
# off: the same operations in the same order), and the plain build still compiles the
# engine and the force fields file by file, so a name clash between two of their files is
# still found there (io/, the cross-check and app/ are batched there too:
# DELI_UNITY_OUTER_LAYERS in CMakeLists.txt).
# -no-pie: each of the ~570 test processes otherwise applies about 600000 relative
# relocations to its own executable at start-up (the sanitizers' metadata is full of
# pointers; perf put half of a start-up's samples in the relocations and their page
# faults). Measured (`perf stat`, a test binary listing no test): 233-239 ms of CPU with PIE,
# 181-204 ms without. Run every time, so that an existing
# build-asan/ takes these settings too (a quick no-op when they have not changed).
# DELI_TEST_COMPILE_OPTIONS=-O0: the test files (never deli's libraries, which stay at -O1)
# compiled unoptimised: their code is mostly calls into deli and GoogleTest's assertions, and
# the optimiser's passes over the instrumented templates they instantiate (Eigen's, above all)
# were most of their compile time: the test binaries' translation units (and their
# precompiled header) took 346 CPU s at -O1, 216 at -O0 (g++ 12, each timed by a compiler
# launcher). Still instrumented. The cost: the linker keeps the first copy of an inline
# function it meets, the test files' (they come before the libraries), so deli's code calls
# unoptimised copies of the small templates it does not inline at -O1 (std::vector<Vec3>'s
# iterators and copies: 19 % of ContactTreatment's samples); still instrumented too.
# DELI_TEST_GROUPS: ctest runs the cases of a suite in groups of up to 16, one process each
# (cmake/test_groups.cmake), not one process per case: a process here costs about 0.2 s to
# start and leak-check at exit (10 ms in the plain build), which over ~600 cases was about a
# fifth of this pass's test time. Extra arguments to ctest (-R) match the groups' names
# (a suite's, or "Suite[1-16]").
# DELI_NATIVE=OFF: this pass is also CI's run of the suite on the portable build (the files
# the README's "Vector instructions" names, in their portable forms), so that the tests pass
# with the build machine's instruction set (the plain pass) and without it (here). A Release build of its
# own for that (tools/portable.sh) took 477 of CI's 1612 s on the 2-vCPU Intel Xeon machine
# (stop 75), and CI's budget is 20 minutes. The vector forms run in the plain pass, not under
# the sanitizers, which would not check their masked loads and gathers anyway (GCC 12: an
# eight-lane masked load and a gather reading past a block of five doubles went unreported,
# a plain eight-lane load was caught). The portable forms make the same numbers in the same
# order (README, "Vector instructions"), which Golden.* checks here against the same file as
# the plain pass.
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Sanitize -DCMAKE_UNITY_BUILD=ON -DDELI_TEST_GROUPS=16 \
  -DDELI_NATIVE=OFF -DDELI_TEST_COMPILE_OPTIONS=-O0 \
  -DCMAKE_CXX_FLAGS_SANITIZE="$flags" -DCMAKE_C_FLAGS_SANITIZE="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS_SANITIZE="-fsanitize=address,undefined -no-pie" >/dev/null
cmake --build build-asan -j "$jobs"

# Not run here: the tests that run no deli code, the layer probes (Layers.*: one #include
# compiled each, and a Python check of the sources) and the configure step of a fresh machine
# (Setup.*), which the plain pass (./setup.sh test) runs on the same sources.
skip="^(Layers|Setup)\\."
# The long statistical tests (1e4 to 1e6 steps of 864 to 4000 atoms, 8 to 15 times slower
# under the sanitizers: ShadowEnergy alone took 217 s, VelocityVerlet.LjLiquid 193 s, each
# Both/Thermostat 60-110 s) run here on a short prefix of their steps: they read
# DELI_SANITIZER_SHORT_RUNS through tests/support/short_runs.hpp, run the same code, and
# assert what a short run can (values finite, no overlap, bounds that hold over every prefix
# of the full run); their statistical assertions are the plain pass's, which runs them in
# full. The two-thread runs of the binary (ThreadsRun) are shortened the same way; the
# equation-of-state tool (two short runs) runs as it is.
export DELI_SANITIZER_SHORT_RUNS=1
# Every test runs here, the whole-system cross-checks included (every shipped input against
# OpenMM's reference and CPU platforms and LAMMPS, the 32000-atom ones too, every model) on
# the short trajectories DELI_SANITIZER_SHORT_RUNS asks for (2 and 10 steps), and the paper
# reproduction script on a tenth of --quick's steps. They became affordable when MPI stopped
# starting a daemon per process (io/crosscheck/single_process_mpi.hpp): Open MPI then loads
# few components and unloads none before the exit, so LSan's fast unwinder gives stacks that
# match lsan.supp, and the slow one (40 % of a 32000-atom cross-check, measured with perf)
# is no longer needed.
# (The two cross-checks of chains_4000_harmonic, which run here, once saw LeakSanitizer's
# tracer take a SIGSEGV at their exit leak check after both had passed, and not in 8 runs
# since: a known intermittent failure of the sanitizer runtime, google/sanitizers#1353.
# Should it recur, LSAN_OPTIONS=verbosity=1:log_threads=1 shows the thread. At stop 48 it
# became reproducible in OpenMMCpuPlatform.AgreesToSinglePrecision, which alone skips the exit
# check now: tests/crosscheck/validate_test.cpp.)

# allocator_may_return_null: an impossible size gets NULL, as from glibc. A damaged
# checkpoint (Checkpoint.EverySingleByteFlipIsRefusedOrHarmless) makes HDF5's metadata
# cache ask for a terabyte; HDF5 reports the NULL as an error and deli refuses the file,
# where ASan's allocator would abort. (A deli container still gets std::bad_alloc.)
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=0:check_initialization_order=1:allocator_may_return_null=1:suppressions=$here/asan.supp"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export LSAN_OPTIONS="suppressions=$here/lsan.supp:print_suppressions=0"
cd build-asan
ctest --output-on-failure -j "$jobs" -E "$skip" "$@"
