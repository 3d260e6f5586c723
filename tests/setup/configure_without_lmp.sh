#!/usr/bin/env bash
# A fresh Debian 12 machine has liblammps-dev (which setup.sh installs) but not the
# lammps package, so no /usr/bin/lmp; Debian's LAMMPS CMake config refers to that file.
# Configure deli in a scratch build folder as that machine would see it: where lmp is
# installed, hide it inside a private mount namespace (an overlay whiteout on /usr/bin).
# Exit 77 (ctest: skipped) with the reason where that cannot be done.
set -euo pipefail
src=$(cd "$(dirname "$0")/../.." && pwd)
scratch=$(mktemp -d /tmp/deli-configure-without-lmp.XXXXXX)
trap 'rm -rf "$scratch"' EXIT

configure='cmake -S "$0" -B "$1/build" -DDELI_BUILD_TESTS=OFF > "$1/configure.log" 2>&1'
if [ ! -e /usr/bin/lmp ]; then
  echo "/usr/bin/lmp is absent here: configuring as is"
  sh -c "$configure" "$src" "$scratch" || { cat "$scratch/configure.log"; exit 1; }
else
  if [ "$(id -u)" -ne 0 ] || ! command -v unshare > /dev/null; then
    echo "skipped: /usr/bin/lmp is installed and hiding it needs root and unshare"
    exit 77
  fi
  hide='mount -t tmpfs none "$1/ns" && mkdir "$1/ns/upper" "$1/ns/work" &&
        mknod "$1/ns/upper/lmp" c 0 0 &&
        mount -t overlay overlay -o "lowerdir=/usr/bin,upperdir=$1/ns/upper,workdir=$1/ns/work" /usr/bin'
  mkdir "$scratch/ns"
  if ! unshare -m sh -c "$hide && test ! -e /usr/bin/lmp" sh "$scratch"; then
    echo "skipped: this machine does not allow a private overlay mount to hide /usr/bin/lmp"
    exit 77
  fi
  echo "/usr/bin/lmp hidden in a private mount namespace"
  unshare -m sh -c "$hide && $configure" "$src" "$scratch" ||
    { cat "$scratch/configure.log"; exit 1; }
fi
grep "deli: LAMMPS" "$scratch/configure.log"
echo "configured without /usr/bin/lmp"
