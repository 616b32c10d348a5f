#!/bin/sh
# bench/step/ab.sh - A/B of one model's step: ab.sh BASEGEN NEWGEN CC "FLAGS" MODEL K S H NSTEP [GENFLAGS]
# prints ab.c's CSV row (A = BASEGEN's solver, B = NEWGEN's).
set -eu
base=$1 new=$2 cc=$3 flags=$4 model=$5 k=$6 s=$7 h=$8 n=$9
shift 9
d=${ABDIR:-build/bench/step/ab}
mkdir -p "$d"
"$base" -k "$k" -s "$s" "$@" -n A -o "$d" "models/$model.ham"
"$new" -k "$k" -s "$s" "$@" -n B -o "$d" "models/$model.ham"
# shellcheck disable=SC2086
$cc -std=c99 $flags -I"$d" "$d/A.c" "$d/B.c" bench/step/ab.c -lm -o "$d/ab"
"$d/ab" "$h" "$n"
