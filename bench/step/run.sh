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
#   chain, resource bound) of one sweep, both from llvm-mca: the current
#   step's iteration between markers (gcc -O2 -S), simulated 100 times, its
#   cycles per iteration (the loop-carried chain through gamma, in registers,
#   or the resources, whichever is longer) and its Block RThroughput; where
#   the sweep is too large to be inline (satellites) the sum over its parts
#   of the cycles of one run of each. Cycles become ns at the clock measured
#   by bench/step/clock.c. -> bench/results/step.csv
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

# mca FILE.c PREFIX: "cycles rthroughput" of one iteration of solver PREFIX's
# step: the loop of PREFIX_step_within from its head to its convergence test,
# between llvm-mca markers, simulated 100 times (the loop-carried chain or the
# resources, whichever is longer), plus, where the sweep is not inline, its
# functions (its parts), one run each (the loop only calls them)
cpu=$(llc --version 2>/dev/null | sed -n 's/.*Host CPU: *//p')
mca() {
  c=$1 P=$2
  awk -v P="$P" '
    $0 ~ "^static int " P "_step_within\\(" { step = 1 }
    step && $0 ~ "^  for \\(it = 1; it <= " P "_MAXITER; it\\+\\+\\) \\{$" { print; print "    __asm__ volatile(\"# LLVM-MCA-BEGIN sweep\");"; next }
    step && /^    \/\* otherwise progress is a new smallest increment/ { print "    __asm__ volatile(\"# LLVM-MCA-END sweep\");"; step = 0 }
    { print }' "$c" >"$B/mca.c"
  # gcc may duplicate the block of the end marker: llvm-mca takes the first
  gcc -std=gnu99 -O2 -S -I"$(dirname "$c")" -o "$B/mca.s" "$B/mca.c"
  awk '/LLVM-MCA-END/ { if (ends++) next } { print }' "$B/mca.s" >"$B/mca1.s"
  {
    llvm-mca -mcpu="$cpu" -iterations=100 "$B/mca1.s" 2>/dev/null |
      awk '/^Iterations:/ { it = $2 } /^Total Cycles:/ { c = $3 } /^Block RThroughput:/ { printf "%.1f %.1f\n", c / it, $3; exit }'
    if ! grep -q "the kernel sweep, inline" "$c"; then
      gcc -std=c99 -O2 -fno-inline -S -o "$B/sweep.s" "$c"
      for f in $(sed -En "s/^(${P}_sweep(_part[0-9]+)?(\.[a-z]+\.[0-9]+)?):$/\1/p" "$B/sweep.s"); do
        awk -v f="$f:" '$0 == f { on = 1; next } on && /\.cfi_endproc/ { exit } on && !/^\s*\./ { print }' "$B/sweep.s" >"$B/fn.s"
        llvm-mca -mcpu="$cpu" -iterations=1 "$B/fn.s" 2>/dev/null | awk '/^Total Cycles:/ { c = $3 } /^Block RThroughput:/ { print c, $3 }'
      done
    fi
  } | awk '{ c += $1; r += $2 } END { printf "%.1f %.1f\n", c, r }'
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
    set -- $(mca "$B/ab_$model/B.c" B)
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
