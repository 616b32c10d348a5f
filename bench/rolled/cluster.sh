#!/bin/sh
# bench/rolled/cluster.sh - the cluster of N rigid diatomics with a pair
# potential (tests/models/cluster4.ham with N and its grid side L replaced),
# s = 2, default k (4), --multiplier const, h = 0.02 from the model's initial
# state: per N the size of NAME.c, gcc -O2 compile time (wall, while other
# jobs run) and the time per step of the straight-line form (--rolled off)
# and of the rolled one (--rolled on) where the generator rolls it, the two
# stepped alternately by bench/step/ab.c (medians of CPU time, their ratio);
# where it does not, the straight-line solver runs against itself and the
# rolled columns say why ("refused": not uniform in the index).
# Writes bench/results/rolled_cluster.csv.
# Usage: bench/rolled/cluster.sh [N ...]   (default 4 8 16 32)
set -eu
ns=${*:-4 8 16 32}
d=build/bench/rolled_cluster
res=bench/results/rolled_cluster.csv
mkdir -p "$d"
gen=gen/hbvmgen
now() { date +%s.%N; }
# as B's solver, A's (the straight-line one against itself)
as_a() {
  sed 's/\bB_/A_/g; s/\bB\.h\b/A.h/; s/B_H\b/A_H/g' "$d/B.h" > "$d/A.h"
  sed 's/\bB_/A_/g; s/"B\.h"/"A.h"/' "$d/B.c" > "$d/A.c"
}
cc -std=c99 -O2 -c bench/timing.c -o "$d/timing.o"
echo "N,m,nu,pairs,straight_c_bytes,straight_cc_s,rolled_c_bytes,rolled_cc_s,straight_ns_step,rolled_ns_step,ratio,sweeps_straight,sweeps_rolled,max_dH" > "$res"
for N in $ns; do
  L=1; while [ $((L * L * L)) -lt "$N" ]; do L=$((L + 1)); done
  sed "s/^N  = 4$/N  = $N/; s/^L  = 2$/L  = $L/" tests/models/cluster4.ham > "$d/cluster$N.ham"
  nstep=$(( 4000 / N )); [ "$nstep" -ge 20 ] || nstep=20
  $gen --multiplier const --rolled off -n B -o "$d" "$d/cluster$N.ham"
  t0=$(now); nice -n 5 cc -std=c99 -O2 -c "$d/B.c" -o "$d/B.o"; t1=$(now)
  sb=$(wc -c < "$d/B.c"); scc=$(echo "$t1 - $t0" | bc)
  as_a
  nice -n 5 cc -std=c99 -O2 -c "$d/A.c" -o "$d/A.o"
  # the rolled form as B; a refusal writes nothing, leaving B the straight-line solver
  if $gen --multiplier const --rolled on -n B -o "$d" "$d/cluster$N.ham" 2> "$d/why.txt"; then
    t0=$(now); nice -n 5 cc -std=c99 -O2 -c "$d/B.c" -o "$d/B.o"; t1=$(now)
    rb=$(wc -c < "$d/B.c"); rcc=$(echo "$t1 - $t0" | bc)
  else
    rb=refused; rcc=
  fi
  cc -std=c99 -O2 -I"$d" -Ibench -c bench/step/ab.c -o "$d/ab.o"
  cc -o "$d/ab" "$d/ab.o" "$d/timing.o" "$d/A.o" "$d/B.o" -lm
  row=$("$d/ab" 0.02 "$nstep")
  ta=$(echo "$row" | cut -d, -f1); tb=$(echo "$row" | cut -d, -f2); ratio=$(echo "$row" | cut -d, -f3)
  sa=$(echo "$row" | cut -d, -f4); sbw=$(echo "$row" | cut -d, -f5); dh=$(echo "$row" | cut -d, -f6)
  [ "$rb" != refused ] || { tb=; ratio=; sbw=; }
  echo "$N,$((6 * N)),$N,$((4 * N * (N - 1) / 2)),$sb,$scc,$rb,$rcc,$ta,$tb,$ratio,$sa,$sbw,$dh" >> "$res"
  tail -1 "$res"
done
echo "cluster: wrote $res"
