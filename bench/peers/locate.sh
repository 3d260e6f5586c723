# Sourced by the benchmark scripts (bench/constrained.sh, bench/threads.sh) with $top set to
# the source tree: sets $peers to the peers' driver (deli-peers), or to nothing when PEERS=0
# or when it cannot be built. PEERS_BIN=path picks another build of it.
peers=${PEERS_BIN:-$top/build/bench/peers/deli-peers}
[[ ${PEERS:-1} == 0 ]] && peers=
# Not part of the default build (a benchmark's driver): built on first use.
if [[ -n $peers && ! -x $peers && -z ${PEERS_BIN:-} && -f $top/build/CMakeCache.txt ]]; then
  cmake --build "$top/build" --target deli-peers >&2 || true
fi
if [[ -n $peers && ! -x $peers ]]; then
  echo "note: $peers not built (configure with -DDELI_CROSSCHECK=ON): deli alone" >&2
  peers=
fi
