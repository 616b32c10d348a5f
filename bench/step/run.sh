#!/bin/sh
# bench/step/run.sh - the scalar step against its bound, and compilers and
# flags side by side (part of make bench, ~5 min; bench/README.md says what
# the tables show).
#
#   bench/step/run.sh [table] [flags]     (both by default)
#
# table: on the five problems of issue 14, the default family, the step of
#   BASE (git revision, default fff6958: the step before the fused iteration
#   and the two-step warm start) against the current gen/hbvmgen, built with
#   gcc -O2 and timed side by side (bench/step/ab.c: medians of 41
#   alternations, in CPU time). The bound of a step is sweeps x max(dependency
#   chain, resource bound) of one sweep, both from llvm-mca over the current
#   step's iteration as it runs: the instructions callgrind counts once (or k
#   times) a sweep in the timed build (hot_bound below), simulated 100 times:
#   cycles per iteration (the loop-carried chain through gamma, in registers,
#   or the resources, whichever is longer) and Block RThroughput. Cycles
#   become ns at the clock measured by bench/step/clock.c.
#   -> bench/results/step.csv
# flags: the current step built by gcc and clang at -O2/-O3, gcc -O2 without
#   its SLP vectoriser, and with -march=native -fno-math-errno (and
#   -ffp-contract=fast), each against gcc
#   -O2 in one process: the time ratio, and whether the states after the run
#   are bitwise gcc -O2's. -> bench/results/flags.csv
set -eu
cd "$(dirname "$0")/../.."
B=build/bench/step
R=bench/results
BASE=${BASE:-fff6958}
mkdir -p "$B" "$R"
parts=${*:-table flags}

# model k s h steps (the h of issue 14's table; conical T/50, T = 2^(3/4) pi)
problems="pendulum:2:2:0.025:20000 conical:2:2:0.10567:15000 kepler:16:2:0.031415926535897934:5000
satellites:6:2:0.05:1500 chain8:2:2:0.005:2000"

# the generator of revision BASE, built once
base_gen() {
  if [ ! -x "$B/base/build/hbvmgen" ] || [ "$(cat "$B/base/REV" 2>/dev/null)" != "$BASE" ]; then
    rm -rf "$B/base"
    mkdir -p "$B/base"
    git archive "$BASE" | tar -x -C "$B/base"
    make -C "$B/base" --no-print-directory -s build/hbvmgen >/dev/null
    echo "$BASE" >"$B/base/REV"
  fi
  echo "$B/base/build/hbvmgen"
}

# hot_bound FILE.c PREFIX H NSTEP MODEL: "cycles rthroughput" of one iteration of
# solver PREFIX's step, from llvm-mca over the iteration's hot path: FILE.c
# built as timed (gcc -O2) and stepped NSTEP times by h without statistics
# (bench/step/hot.c) under callgrind, which counts each instruction; the
# iteration is the instructions of PREFIX_step_within and of the sweep's
# functions (PREFIX_sweep*, where the sweep is not inline) run at least 0.6x
# as often as the sweeps and at most as often, and those run an exact multiple
# k of the sweeps (an inner loop of the iteration: its block repeated k times),
# leaving out counts that are multiples of the steps (per-step loops); without
# its jumps, in address order, simulated 100 times (the loop-carried chain or
# the resources, whichever is longer). gcc lays blocks the fixed step never runs (the adaptive step's
# tests, the factor's refresh) between the iteration's own, which a region
# between markers would have counted (2026-11-26: 518 instead of 255
# instructions an iteration on the pendulum)
cpu=$(llc --version 2>/dev/null | sed -n 's/.*Host CPU: *//p')
hot_bound() {
  c=$1 P=$2 h=$3 n=$4 d=$B/hot_$5
  mkdir -p "$d"
  cp "$c" "$d/B.c"
  cp "$(dirname "$c")/$P.h" "$d/B.h"
  gcc -std=c99 -O2 -c "$d/B.c" -o "$d/B.o"
  gcc -std=c99 -O2 -I"$d" bench/step/hot.c "$d/B.o" -lm -o "$d/hot"
  sweeps=$("$d/hot" "$h" "$n" count)
  valgrind --tool=callgrind --callgrind-out-file="$d/cg" --dump-instr=yes --dump-line=no "$d/hot" "$h" "$n" 2>/dev/null
  awk -v P="$P" -f bench/step/counts.awk "$d/cg" |
    awk -v S="$sweeps" -v N="$n" -v P="$P" '($1 == P "_step_within" || index($1, P "_sweep") == 1) && $3 >= 0.6 * S {
      k = int($3 / S + 0.5)  # times an iteration: 1, or an inner loop of the iteration
      if ($3 <= S || ($3 == k * S && $3 % N != 0)) print $2, (k > 1 ? k : 1) }' >"$d/hot.list"
  objdump -d --no-show-raw-insn "$d/hot" |
    awk 'NR == FNR { times[$1] = $2; next }
      function flush(   j) { for (j = 0; j < k; j++) printf "%s", block; block = "" }
      /^ *[0-9a-f]+:\t/ { a = $1; sub(/:$/, "", a); sub(/^0+/, "", a)
        if (!(a in times)) next
        i = $0; sub(/^ *[0-9a-f]+:\t/, "", i); sub(/ *#.*$/, "", i)
        if (i ~ /^(j[a-z]*|call|ret|nop)/) next
        if (times[a] != k) { flush(); k = times[a] }
        block = block "\t" i "\n" }
      BEGIN { print "# LLVM-MCA-BEGIN hot" } END { flush(); print "# LLVM-MCA-END hot" }' "$d/hot.list" - >"$d/hot.s"
  llvm-mca -mcpu="$cpu" -iterations=100 "$d/hot.s" 2>/dev/null |
    awk '/^Iterations:/ { it = $2 } /^Total Cycles:/ { c = $3 } /^Block RThroughput:/ { printf "%.1f %.1f\n", c / it, $3; exit }'
}

if echo "$parts" | grep -q table; then
  gen_a=$(base_gen)
  gcc -O2 -std=c99 -Ibench bench/step/clock.c bench/timing.c -o "$B/clock" -lm
  ghz=$("$B/clock")
  echo "model,k,s,h,sweeps_base,sweeps_new,ns_base,ns_new,new_vs_base,sweep_cycles,sweep_rthroughput,ghz,bound_base_ns,bound_new_ns,ratio_base,ratio_new" >"$R/step.csv"
  for p in $problems; do
    IFS=: read -r model k s h n <<EOT
$p
EOT
    row=$(ABDIR="$B/ab_$model" bench/step/ab.sh "$gen_a" gen/hbvmgen gcc -O2 "$model" "$k" "$s" "$h" "$n")
    # shellcheck disable=SC2046 # two numbers, split on purpose
    set -- $(hot_bound "$B/ab_$model/B.c" B "$h" "$n" "$model")
    echo "$model,$k,$s,$h,$row,$1,$2,$ghz" | awk -F, -v OFS=, '{
      per = ($13 > $14 ? $13 : $14) / $15   # ns of one sweep at the bound
      bb = $8 * per; bn = $9 * per          # times the sweeps of each
      printf "%s,%s,%s,%s,%.3f,%.3f,%.1f,%.1f,%.3f,%s,%s,%s,%.1f,%.1f,%.2f,%.2f\n", $1, $2, $3, $4, $8, $9, $5, $6, $7, $13, $14, $15, bb, bn, $5 / bb, $6 / bn }' |
      tee -a "$R/step.csv"
  done
fi

if echo "$parts" | grep -q flags; then
  echo "model,compiler,flags,ns_gcc_O2,ns,ratio,bitwise_gcc_O2" >"$R/flags.csv"
  for p in $problems; do
    IFS=: read -r model k s h n <<EOT
$p
EOT
    for v in "gcc:-O3" "gcc:-O2 -fno-tree-slp-vectorize" "gcc:-O2 -march=native -fno-math-errno" \
      "gcc:-O3 -march=native -fno-math-errno" \
      "gcc:-O2 -march=native -fno-math-errno -ffp-contract=fast" "clang:-O2" "clang:-O3" \
      "clang:-O3 -march=native -fno-math-errno" "clang:-O3 -march=native -fno-math-errno -ffp-contract=off"; do
      cc=${v%%:*} fl=${v#*:}
      command -v "$cc" >/dev/null || continue
      row=$(CC_B=$cc FLAGS_B=$fl ABDIR="$B/fl_$model" bench/step/ab.sh gen/hbvmgen gen/hbvmgen gcc -O2 "$model" "$k" "$s" "$h" "$n")
      echo "$model,$cc,$fl,$row" | awk -F, -v OFS=, '{ print $1, $2, $3, $4, $5, $6, $11 }' | tee -a "$R/flags.csv"
    done
  done
fi
