#!/bin/sh
# bench/rolled/run.sh - the rolled form (docs/rolled.md) on the chain of N
# pendula (models/chain8.ham with N replaced), s = 4, --multiplier const:
# per N the size of NAME.c, gcc -O2 compile time and the time per step of the
# straight-line form (--rolled off, up to N = $STRAIGHT_MAX) and of the rolled
# one (--rolled on), the two stepped alternately by bench/step/ab.c (medians
# of CPU time; with no straight-line form the rolled one is run against
# itself). Writes bench/results/rolled.csv.
# With MULT=poly the same for the poly family (straight-line up to N = 16,
# its straight-line C being about 5 times the const family's), into
# bench/results/rolled_poly.csv.
# Usage: bench/rolled/run.sh [N ...]   (default 8 16 32 64 128 256 512 1000)
set -eu
ns=${*:-8 16 32 64 128 256 512 1000}
mult=${MULT:-const}
case $mult in
  const) straight_max=${STRAIGHT_MAX:-128}; res=bench/results/rolled.csv ;;
  poly) straight_max=${STRAIGHT_MAX:-16}; res=bench/results/rolled_poly.csv ;;
  *) echo "rolled/run.sh: MULT is const or poly"; exit 1 ;;
esac
d=build/bench/rolled
mkdir -p "$d"
gen=gen/hbvmgen
now() { date +%s.%N; }
cc -std=c99 -O2 -c bench/timing.c -o "$d/timing.o"
echo "N,m,nu,straight_c_bytes,straight_cc_s,rolled_c_bytes,rolled_cc_s,straight_ns_step,rolled_ns_step,ratio,sweeps_straight,sweeps_rolled,bitwise" > "$res"
for N in $ns; do
  sed "s/^N = 8$/N = $N/" models/chain8.ham > "$d/chain$N.ham"
  # h: the step the chain's lean benchmark takes; 2000 / N steps (at least 10) a run
  nstep=$(( 2000 / N )); [ "$nstep" -ge 10 ] || nstep=10
  $gen --multiplier "$mult" -s 4 --rolled on -n B -o "$d" "$d/chain$N.ham"
  t0=$(now); cc -std=c99 -O2 -c "$d/B.c" -o "$d/B.o"; t1=$(now)
  rb=$(wc -c < "$d/B.c"); rcc=$(echo "$t1 - $t0" | bc)
  if [ "$N" -le "$straight_max" ]; then
    $gen --multiplier "$mult" -s 4 --rolled off -n A -o "$d" "$d/chain$N.ham"
    t0=$(now); cc -std=c99 -O2 -c "$d/A.c" -o "$d/A.o"; t1=$(now)
    sb=$(wc -c < "$d/A.c"); scc=$(echo "$t1 - $t0" | bc)
  else # the rolled solver against itself, as A
    sed 's/\bB_/A_/g; s/\bB\.h\b/A.h/; s/B_H\b/A_H/g' "$d/B.h" > "$d/A.h"
    sed 's/\bB_/A_/g; s/"B\.h"/"A.h"/' "$d/B.c" > "$d/A.c"
    cc -std=c99 -O2 -c "$d/A.c" -o "$d/A.o"
    sb=; scc=
  fi
  cc -std=c99 -O2 -I"$d" -Ibench -c bench/step/ab.c -o "$d/ab.o"
  cc -o "$d/ab" "$d/ab.o" "$d/timing.o" "$d/A.o" "$d/B.o" -lm
  row=$("$d/ab" 0.01 "$nstep")
  ta=$(echo "$row" | cut -d, -f1); tb=$(echo "$row" | cut -d, -f2); ratio=$(echo "$row" | cut -d, -f3)
  sa=$(echo "$row" | cut -d, -f4); sbw=$(echo "$row" | cut -d, -f5); bit=$(echo "$row" | cut -d, -f8)
  [ -n "$sb" ] || { ta=; ratio=; sa=; bit=; }
  echo "$N,$((2 * N)),$N,$sb,$scc,$rb,$rcc,$ta,$tb,$ratio,$sa,$sbw,$bit" >> "$res"
  tail -1 "$res"
done
echo "rolled: wrote $res"
