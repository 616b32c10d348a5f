#!/bin/sh
# Lean-code measurements (issue: skip what a model doesn't need):
#   bench/results/lean_instructions.csv  instructions per step (callgrind) per model
#   bench/results/lean_scaling.csv       chain of N pendula: generation time, code
#                                        size, cc -O2 time, instructions per step
# Usage: bench/lean/run.sh [TAG]   (TAG labels the rows, e.g. before/after)
set -eu
tag=${1:-current}
out=build/lean
res=bench/results
mkdir -p "$out" "$res"
gen=gen/hbvmgen
now() { date +%s.%N; }

# instructions per step of a solver: callgrind of STEPS+1 minus 1 step runs, so
# start-up and the first (cold) step do not count
instr_per_step() { # prefix dir steps h
  cc -O2 -std=c99 -DP="$1" -include "$2/$1.h" -I"$2" -o "$out/$1_steps" "$2/$1.c" bench/lean/steps.c -lm
  a=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$out/$1_steps" 1 "$4" 2>&1 | sed -n 's/.*Collected : //p')
  b=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$out/$1_steps" $(($3 + 1)) "$4" 2>&1 | sed -n 's/.*Collected : //p')
  it=$("$out/$1_steps" "$3" "$4" | cut -d' ' -f1)
  echo "$(( (b - a) / $3 )),$it"
}

# rows of an earlier run with the same tag are replaced
retag() { [ -f "$1" ] && grep -v "^$tag," "$1" > "$1.tmp" && mv "$1.tmp" "$1" || true; }

csv=$res/lean_instructions.csv
[ -f "$csv" ] || echo "tag,model,k,s,h,instructions_per_step,iters_per_step" > "$csv"
retag "$csv"
# model:k:s:h -- fixed (k, s) so that rows of different tags compare the same method
for spec in pendulum:2:2:0.05 conical:2:2:0.05 modified:6:2:0.05 satellites:6:2:0.1 kepler:6:2:0.03 \
            henon_heiles:3:2:0.1 chain8:2:2:0.01; do
  model=${spec%%:*}; rest=${spec#*:}; k=${rest%%:*}; rest=${rest#*:}; s=${rest%%:*}; h=${rest#*:}
  # the paper's method, as in the rows of earlier tags (the default is now poly)
  $gen --multiplier const -k "$k" -s "$s" -n "lean_$model" -o "$out" "models/$model.ham"
  echo "$tag,$model,$k,$s,$h,$(instr_per_step "lean_$model" "$out" 20 "$h")" >> "$csv"
done

csv=$res/lean_scaling.csv
[ -f "$csv" ] || echo "tag,N,m,nu,gen_seconds,c_bytes,cc_seconds,instructions_per_step,iters_per_step" > "$csv"
retag "$csv"
for N in ${LEAN_CHAIN:-8 32 128}; do
  sed "s/^N = 8$/N = $N/" models/chain8.ham > "$out/chain$N.ham"
  t0=$(now); $gen -s 2 -n "chain$N" -o "$out" "$out/chain$N.ham"; t1=$(now)
  cc -O2 -std=c99 -c -I"$out" -o "$out/chain$N.o" "$out/chain$N.c"; t2=$(now)
  ips=$(instr_per_step "chain$N" "$out" 10 0.01)
  echo "$tag,$N,$((2 * N)),$N,$(echo "$t1 - $t0" | bc),$(wc -c < "$out/chain$N.c"),$(echo "$t2 - $t1" | bc),$ips" >> "$csv"
done
echo "lean: wrote $res/lean_instructions.csv and $res/lean_scaling.csv"
