#!/bin/sh
# bench/mq/run.sh - the double pendulum in angles (M(q)) against GSL's rk8pd on
# the same ODE and against hbvmgen's Cartesian form (bench/mq/dpa_bench.c).
# Run from the repository's root after `make all`: sh bench/mq/run.sh
set -e
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
G=gen/hbvmgen
$G models/double_pendulum_angles.ham -s 3 -n dpa3 -o "$dir" >/dev/null
$G models/double_pendulum_angles.ham -s 4 -n dpa4 -o "$dir" >/dev/null
$G models/double_pendulum_angles.ham -s 4 -k 20 -n dpa4s -o "$dir" >/dev/null
$G models/double_pendulum.ham -s 4 -k 4 -n cart_k4s4 -o "$dir" >/dev/null
CFLAGS="-std=c99 -O2 -Wall -Wextra -pedantic"
cc $CFLAGS -I"$dir" -o "$dir/bench" bench/mq/dpa_bench.c "$dir"/dpa3.c "$dir"/dpa4.c \
  "$dir"/dpa4s.c "$dir"/cart_k4s4.c $(pkg-config --libs gsl) -lm
"$dir/bench"
