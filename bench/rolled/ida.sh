#!/bin/sh
# bench/rolled/ida.sh - the peer of the rolled form: SUNDIALS IDA
# with a banded linear solver (bench/rolled/ida_chain.c) on the chain of N
# pendula of bench/rolled/run.sh (s = 4, --multiplier const, --rolled on),
# T = 1 from the model's initial state: the rolled solver at h = 0.01,
# 0.0025 and 0.0005, IDA at tolerances 1e-6, 1e-8, 1e-10, alternated 11 times in one
# process (medians of CPU time): time per step, per unit of simulated time
# and the error at T. Writes bench/results/rolled_ida.csv.
# Usage: bench/rolled/ida.sh [N ...]   (default 8 32 128 1000)
set -eu
ns=${*:-8 32 128 1000}
d=build/bench/rolled_ida
res=bench/results/rolled_ida.csv
mkdir -p "$d"
CFLAGS="-std=c99 -O2 -Wall -Wextra -pedantic"
LIBS="-lsundials_ida -lsundials_sunlinsolband -lsundials_sunmatrixband -lsundials_sunlinsoldense -lsundials_sunmatrixdense -lsundials_nvecserial -lm"
for f in timing linalg ida_run; do cc $CFLAGS -c "bench/$f.c" -o "$d/$f.o"; done
cc $CFLAGS -Ibench -c bench/rolled/ida_vs.c -o "$d/ida_vs.o"
echo "N,method,T,h_or_tol,steps,ns_step,us_per_time,err" > "$res"
for N in $ns; do
  sed "s/^N = 8$/N = $N/" models/chain8.ham > "$d/chain$N.ham"
  gen/hbvmgen --multiplier const -s 4 --rolled on -n B -o "$d" "$d/chain$N.ham"
  cc $CFLAGS -c "$d/B.c" -o "$d/B.o"
  cc $CFLAGS -I"$d" -Ibench -c bench/rolled/ida_chain.c -o "$d/ida_chain.o"
  cc -o "$d/ida_chain" "$d/ida_chain.o" "$d/B.o" "$d/ida_vs.o" "$d/ida_run.o" "$d/timing.o" "$d/linalg.o" $LIBS
  "$d/ida_chain" 1 0.01,0.0025,0.0005 11 1e-6,1e-8,1e-10 | tee -a "$res"
done
echo "rolled/ida: wrote $res"
