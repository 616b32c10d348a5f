#!/bin/sh
# bench/rolled/cluster.sh - the rolled form (docs/rolled.md, "Pair sums") on
# the cluster of N rigid diatomics with a pair potential
# (tests/models/cluster4.ham with N and its grid side L replaced), s = 2,
# default k (4), --multiplier const, h = 0.02 from the model's initial state.
# Per N: the size of NAME.c and gcc -O2 compile time (CPU seconds, user +
# system of cc and its children, so that other jobs on the machine count
# little) of the straight-line form (--rolled off; compiled up to N =
# $STRAIGHT_MAX, beyond only its size) and of the rolled one (--rolled on),
# and their times per step, stepped alternately by bench/step/ab.c (medians
# of CPU time, their ratio rolled / straight). Without a straight-line
# solver the rolled one runs against itself. Writes
# bench/results/rolled_cluster.csv.
# Then, up to N = $IDA_MAX (default 64), the issue's peer: SUNDIALS IDA with
# a dense linear solver on the same model (bench/rolled/ida_cluster.c, the
# GGL form; every atom feels every other, so its Jacobian is dense), from
# the same initial state to T = 1, at tolerances 1e-6 and 1e-8 (IDA's
# dense Jacobian makes 1e-10 take minutes at N = 64), alternated with the
# rolled solver at h = 0.02 and 0.005 ($IDA_REPS times, default 3; medians
# of CPU time): time per step, per unit of
# simulated time and the error at T (bench/rolled/ida_vs.h). Writes
# bench/results/rolled_cluster_ida.csv, and bench/rolled/plot_cluster.sh
# plots both files into bench/results/rolled_cluster.png.
# Usage: bench/rolled/cluster.sh [N ...]   (default 4 8 16 32 64 128)
set -eu
ns=${*:-4 8 16 32 64 128}
straight_max=${STRAIGHT_MAX:-16}
ida_max=${IDA_MAX:-64}
ida_reps=${IDA_REPS:-3}
d=build/bench/rolled_cluster
res=bench/results/rolled_cluster.csv
ida_res=bench/results/rolled_cluster_ida.csv
mkdir -p "$d"
gen=gen/hbvmgen
CFLAGS="-std=c99 -O2 -Wall -Wextra -pedantic"
IDA_LIBS="-lsundials_ida -lsundials_sunlinsolband -lsundials_sunmatrixband -lsundials_sunlinsoldense -lsundials_sunmatrixdense -lsundials_nvecserial -lm"
# cc -std=c99 -O2 -c SRC -o OBJ, printing its CPU seconds
cc_time() {
  /usr/bin/time -f "%U %S" -o "$d/time.txt" nice -n 5 cc -std=c99 -O2 -c "$1" -o "$2"
  awk '{ print $1 + $2 }' "$d/time.txt"
}
# B's solver renamed A (the rolled solver against itself)
b_as_a() {
  sed 's/\bB_/A_/g; s/\bB\.h\b/A.h/; s/B_H\b/A_H/g' "$d/B.h" > "$d/A.h"
  sed 's/\bB_/A_/g; s/"B\.h"/"A.h"/' "$d/B.c" > "$d/A.c"
}
cc -std=c99 -O2 -c bench/timing.c -o "$d/timing.o"
for f in linalg ida_run; do cc $CFLAGS -c "bench/$f.c" -o "$d/$f.o"; done
cc $CFLAGS -Ibench -c bench/rolled/ida_vs.c -o "$d/ida_vs.o"
echo "N,method,T,h_or_tol,steps,ns_step,us_per_time,err" > "$ida_res"
echo "N,m,nu,pairs,straight_c_bytes,straight_cc_cpu_s,rolled_c_bytes,rolled_cc_cpu_s,straight_ns_step,rolled_ns_step,ratio,sweeps_straight,sweeps_rolled,max_dH_rolled" > "$res"
for N in $ns; do
  L=1; while [ $((L * L * L)) -lt "$N" ]; do L=$((L + 1)); done
  sed "s/^N  = 4$/N  = $N/; s/^L  = 2$/L  = $L/" tests/models/cluster4.ham > "$d/cluster$N.ham"
  nstep=$(( 4000 / N )); [ "$nstep" -ge 20 ] || nstep=20
  scc=
  if $gen --multiplier const --rolled off -n A -o "$d" "$d/cluster$N.ham" 2> "$d/straight.err"; then
    sb=$(wc -c < "$d/A.c")
  else # too large for the generator: only the rolled form
    sb=refused; rm -f "$d/A.c"
  fi
  if [ "$N" -le "$straight_max" ] && [ "$sb" != refused ]; then
    scc=$(cc_time "$d/A.c" "$d/A.o")
  fi
  $gen --multiplier const --rolled on -n B -o "$d" "$d/cluster$N.ham"
  rcc=$(cc_time "$d/B.c" "$d/B.o")
  rb=$(wc -c < "$d/B.c")
  if [ -z "$scc" ]; then b_as_a; cc -std=c99 -O2 -c "$d/A.c" -o "$d/A.o"; fi
  cc -std=c99 -O2 -I"$d" -Ibench -c bench/step/ab.c -o "$d/ab.o"
  cc -o "$d/ab" "$d/ab.o" "$d/timing.o" "$d/A.o" "$d/B.o" -lm
  row=$("$d/ab" 0.02 "$nstep")
  ta=$(echo "$row" | cut -d, -f1); tb=$(echo "$row" | cut -d, -f2); ratio=$(echo "$row" | cut -d, -f3)
  sa=$(echo "$row" | cut -d, -f4); sbw=$(echo "$row" | cut -d, -f5); dh=$(echo "$row" | cut -d, -f7)
  [ -n "$scc" ] || { ta=; ratio=; sa=; }
  echo "$N,$((6 * N)),$N,$((4 * N * (N - 1) / 2)),$sb,$scc,$rb,$rcc,$ta,$tb,$ratio,$sa,$sbw,$dh" >> "$res"
  tail -1 "$res"
  if [ "$N" -le "$ida_max" ]; then
    cc $CFLAGS -I"$d" -Ibench -c bench/rolled/ida_cluster.c -o "$d/ida_cluster.o"
    cc -o "$d/ida_cluster" "$d/ida_cluster.o" "$d/B.o" "$d/ida_vs.o" "$d/ida_run.o" "$d/timing.o" "$d/linalg.o" $IDA_LIBS
    "$d/ida_cluster" 1 0.02,0.005 "$ida_reps" 1e-6,1e-8 | tee -a "$ida_res"
  fi
done
echo "cluster: wrote $res and $ida_res"
bench/rolled/plot_cluster.sh || echo "cluster: no plot (gnuplot?)"
