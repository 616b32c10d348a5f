#!/bin/sh
# bench/step/ab.sh - A/B of one model's step:
#   ab.sh GEN_A GEN_B CC "FLAGS" MODEL K S H NSTEP [GENFLAGS...]
# generates the solver with GEN_A as A and with GEN_B as B, builds them with
# CC FLAGS (B with $CC_B $FLAGS_B when set: compilers and flags side by side)
# and prints bench/step/ab.c's CSV row. LONG=1: one timed run (for drift),
# PSCALE: the initial momenta scaled, ABDIR: where to build.
set -eu
gen_a=$1 gen_b=$2 cc=$3 flags=$4 model=$5 k=$6 s=$7 h=$8 n=$9
shift 9
d=${ABDIR:-build/bench/step/ab}
mkdir -p "$d"
"$gen_a" -k "$k" -s "$s" "$@" -n A -o "$d" "models/$model.ham"
"$gen_b" -k "$k" -s "$s" "$@" -n B -o "$d" "models/$model.ham"
# shellcheck disable=SC2086
{
  $cc -std=c99 $flags -c "$d/A.c" -o "$d/A.o"
  ${CC_B:-$cc} -std=c99 ${FLAGS_B:-$flags} -c "$d/B.c" -o "$d/B.o"
  $cc -std=c99 -O2 -I"$d" -Ibench -c bench/step/ab.c -o "$d/ab.o"
  $cc -std=c99 -O2 -c bench/timing.c -o "$d/timing.o"
  $cc -o "$d/ab" "$d/ab.o" "$d/timing.o" "$d/A.o" "$d/B.o" -lm
}
"$d/ab" "$h" "$n" ${LONG:+long} ${PSCALE:-}
