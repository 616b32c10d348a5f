#!/bin/sh
# bench/adaptive/rejections.sh - the tries NAME_step_adaptive rejects (issue
# 31, item 3: under 5% wanted), the table of docs/api.md, "Adaptive steps":
# per problem and tol 1e-6, 1e-8, 1e-10, 1e-12 the driver's steps and
# steps_rejected from -h 0.01, and the rejected share of the tries, with the
# generator of this tree. Problems: bench/adaptive/run.sh's (T = 10, chain8
# 5), Kepler e = 0.6 over ten periods at (11,6), (18,3), (4,4), the outer
# solar system over 20000 days at (16,2) and (11,6), a four-bar linkage
# (bench/adaptive/fourbar.ham) and a heavy top (tests/models/top.ham) at
# (3,3). TOLS="..." measures other tolerances. Into build/rejections.
set -eu
cd "$(dirname "$0")/../.."
B=build/rejections
GEN=gen/hbvmgen
[ -x "$GEN" ] || make --no-print-directory all
TOLS=${TOLS:-"1e-6 1e-8 1e-10 1e-12"}
mkdir -p "$B"
# name model k s T
while read -r n m k s T; do
  if [ -z "$(find "$B/$n" -newer "$GEN" 2>/dev/null)" ]; then # built by an older generator, or not at all
    "$GEN" --main -o "$B" -n "$n" -k "$k" -s "$s" "$m" 2>/dev/null
    cc -O2 -std=c99 -Iruntime -I"$B" "$B/$n.c" "$B/${n}_main.c" runtime/libhbvmrt.a -lm -o "$B/$n"
  fi
  for tol in $TOLS; do
    "$B/$n" -h 0.01 -T "$T" --tol "$tol" --every 100000000 --quiet 2>&1 >/dev/null |
      sed -n 's/.*steps=\([0-9]*\) .*steps_rejected=\([0-9]*\).*/\1 \2/p' |
      awk -v n="$n" -v tol="$tol" '{ printf "%-18s tol %-6s steps %6d rejected %5d  %5.1f%%\n", n, tol, $1, $2, 100 * $2 / ($1 + $2) }'
  done
done <<LIST
pendulum_k4s4 models/pendulum.ham 4 4 10
conical_k4s4 models/conical.ham 4 4 10
modified_k12s4 models/modified.ham 12 4 10
satellites_k4s4 models/satellites.ham 4 4 10
double_pendulum_k4s4 models/double_pendulum.ham 4 4 10
chain8_k4s4 models/chain8.ham 4 4 5
kepler_k11s6 models/kepler.ham 11 6 62.83185307179586
kepler_k18s3 models/kepler.ham 18 3 62.83185307179586
kepler_k4s4 models/kepler.ham 4 4 62.83185307179586
solar_k16s2 models/solar.ham 16 2 20000
solar_k11s6 models/solar.ham 11 6 20000
fourbar_k3s3 bench/adaptive/fourbar.ham 3 3 10
top_k3s3 tests/models/top.ham 3 3 10
LIST
