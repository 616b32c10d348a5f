#!/bin/sh
# Install the Debian packages hbvmgen needs, if any are missing.
#   scripts/deps.sh            build and test: bison flex libgsl-dev check libsubunit-dev pkg-config valgrind
#   scripts/deps.sh bench      also the benchmark peers, plotting, clang and llvm-mca
#   scripts/deps.sh embedded   also the ARM cross compiler for the embedded build check
#   scripts/deps.sh clang      also clang, the second compiler the generated C is checked with
#   scripts/deps.sh fuzz       also clang with libFuzzer
#   scripts/deps.sh mpi        also Open MPI (make MPI=1: ensembles across ranks)
# As root it runs apt-get install -y; otherwise it prints the exact line to run.
set -eu

pkgs="bison flex libgsl-dev check libsubunit-dev pkg-config valgrind gcc make"
for set in "$@"; do
  case "$set" in
    bench)    pkgs="$pkgs libsundials-dev gnuplot-nox clang llvm" ;;
    embedded) pkgs="$pkgs gcc-arm-none-eabi libnewlib-arm-none-eabi" ;;
    clang)    pkgs="$pkgs clang" ;;
    fuzz)     pkgs="$pkgs clang libclang-rt-14-dev" ;;
    mpi)      pkgs="$pkgs libopenmpi-dev openmpi-bin" ;;
    *) echo "deps.sh: unknown package set '$set' (bench, embedded, clang, fuzz, mpi)" >&2; exit 1 ;;
  esac
done

missing=""
for p in $pkgs; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  case "$status" in
    *"install ok installed"*) ;;
    *) missing="$missing $p" ;;
  esac
done
[ -z "$missing" ] && exit 0

if [ "$(id -u)" -eq 0 ]; then
  echo "deps.sh: installing$missing" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq >/dev/null
  # shellcheck disable=SC2086
  apt-get install -y -qq --no-install-recommends $missing >/dev/null
else
  echo "deps.sh: missing packages:$missing" >&2
  echo "run:  sudo apt-get install -y$missing" >&2
  exit 1
fi
