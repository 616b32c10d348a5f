#!/bin/sh
# bench/batch/run.sh - hbvmgen --batch W against the scalar step, and the
# ensemble runner over threads and MPI ranks (part of make bench, ~3 min).
#
#   1. per model and W = 1, 2, 4, 8: one solver with --batch W, built with
#      FLAGS (default: gcc -O2 -march=native -fno-math-errno, AVX2 or wider; the
#      -std=c99 keeps -ffp-contract=off, so lanes stay bitwise NAME_step);
#      bench/batch/throughput.c times NAME_step and NAME_batch_step side by
#      side: ns per trajectory-step, medians of 9, and the ratio; W = 4 and 8
#      also with AVX2 alone ($AVX2: -fno-trapping-math lets gcc if-convert the lane
#      selects around a division or sqrt, which AVX-512's masks do without it;
#      bitwise the same states, bench/README.md)
#   2. NAME_batch_step_adaptive against NAME_step_adaptive per trajectory,
#      W = 4, over T = 10 at tol 1e-8 (bench/batch/adaptive.c)
#   3. a pendulum's driver (tests/models/mass_param.ham) with --batch 4 on a
#      --sweep of 4096 trajectories of 4000 steps,
#      1 and 2 threads (libhbvmrt_omp.a), 1 and 2 ranks (libhbvmrt_mpi.a,
#      when MPI is installed)
# Results: bench/results/batch.csv, batch_adaptive.csv, ensemble.csv; what they
# show: bench/README.md.
set -eu
cd "$(dirname "$0")/../.."
AVX2="-O2 -mavx2 -mfma -fno-math-errno -fno-trapping-math"
B=build/bench/batch
R=bench/results
CC=${CC:-gcc}
FLAGS=${FLAGS:--O2 -march=native -fno-math-errno}
mkdir -p "$B" "$R"

# model, -k -s, h (the issue's table; the double pendulum in angles, M(q): issue 28),
# steps per trajectory and repetition
problems="pendulum:2:2:0.025:4000 conical:2:2:0.0444:3000 kepler:16:2:0.031415926535897934:1500
satellites:6:2:0.05:400 chain8:2:2:0.005:400 double_pendulum_angles:2:2:0.05:2000"

[ "${1:-}" = ensemble ] && problems= # bench/batch/run.sh ensemble: the second part only
[ -n "$problems" ] && echo "model,k,s,W,compiler,flags,scalar_ns,batch_ns,ratio" > "$R/batch.csv"
for p in $problems; do
  IFS=: read -r model k s h n <<EOT
$p
EOT
  for W in 1 2 4 8; do
    name=${model}_b$W
    gen/hbvmgen -k "$k" -s "$s" --batch "$W" -n "$name" -o "$B" "models/$model.ham"
    for cc in $CC clang; do
      command -v "$cc" >/dev/null || continue
      # shellcheck disable=SC2086
      $cc -std=c99 $FLAGS -I"$B" -DP="$name" -DHDR="\"$name.h\"" "$B/$name.c" bench/batch/throughput.c -lm -o "$B/$name.$cc"
      line=$("$B/$name.$cc" "$h" "$n")
      echo "$model,$k,$s,$W,$cc,$FLAGS,$line" | tee -a "$R/batch.csv"
    done
    if [ "$W" -ge 4 ]; then # issue 14's target is for AVX2 (W = 4): without AVX-512's 32 registers and masks
      # shellcheck disable=SC2086
      $CC -std=c99 $AVX2 -I"$B" -DP="$name" -DHDR="\"$name.h\"" "$B/$name.c" bench/batch/throughput.c -lm -o "$B/$name.avx2"
      echo "$model,$k,$s,$W,$CC,$AVX2,$("$B/$name.avx2" "$h" "$n")" | tee -a "$R/batch.csv"
    fi
  done
done

# NAME_batch_step_adaptive (lanes sharing h) against NAME_step_adaptive per
# trajectory: W = 4, 8 close trajectories over T = 10 at tol 1e-8, with FLAGS
# and with AVX2 alone (bench/batch/adaptive.c)
if [ -n "$problems" ]; then
  echo "model,k,s,W,flags,scalar_ns_per_unit_t,batch_ns_per_unit_t,ratio,steps_scalar,steps_batch" >"$R/batch_adaptive.csv"
  for p in $problems; do
    IFS=: read -r model k s h n <<EOT
$p
EOT
    name=${model}_b4
    for fl in "$FLAGS" "$AVX2"; do
      # shellcheck disable=SC2086
      $CC -std=c99 $fl -I"$B" -DP="$name" -DHDR="\"$name.h\"" "$B/$name.c" bench/batch/adaptive.c -lm -o "$B/$name.adaptive"
      echo "$model,$k,$s,4,$fl,$("$B/$name.adaptive" 10 1e-8)" | tee -a "$R/batch_adaptive.csv"
    done
  done
fi

# ensemble scaling
gen/hbvmgen -k 2 -s 2 --batch 4 --main -n ens -o "$B" tests/models/mass_param.ham
$CC -std=c99 $FLAGS -fopenmp -Iruntime -I"$B" "$B/ens.c" "$B/ens_main.c" runtime/libhbvmrt_omp.a -lm -o "$B/ens"
mpi=0
if command -v mpicc >/dev/null && command -v mpirun >/dev/null; then
  mpicc -std=c99 $FLAGS -fopenmp -DHBVMRT_MPI -Iruntime -I"$B" "$B/ens.c" "$B/ens_main.c" runtime/*.c -lm -o "$B/ens_mpi"
  mpi=1
fi
args="--sweep m1=1:3:4096 -h 0.025 -N 4000"
echo "threads,ranks,seconds,trajectory_steps_per_second" > "$R/ensemble.csv"
run() { # threads ranks command...
  t=$1 r=$2
  shift 2
  best=
  for rep in 1 2 3; do
    sec=$("$@" $args --threads "$t" --csv "$B/ens_${t}_$r.csv" 2>&1 >/dev/null | sed -n 's/.*seconds=\([0-9.e+-]*\).*/\1/p')
    best=$(echo "$sec ${best:-$sec}" | awk '{print ($1 < $2) ? $1 : $2}')
  done
  echo "$t,$r,$best,$(echo "$best" | awk '{printf "%.3g", 4096 * 4000 / $1}')" | tee -a "$R/ensemble.csv"
}
run 1 1 "$B/ens"
run 2 1 "$B/ens"
if [ $mpi = 1 ]; then
  mpirun="mpirun --allow-run-as-root --oversubscribe"
  run 1 1 $mpirun -np 1 "$B/ens_mpi"
  run 1 2 $mpirun -np 2 "$B/ens_mpi"
fi
for f in "$B"/ens_*.csv; do
  cmp -s "$f" "$B/ens_1_1.csv" || { echo "bench/batch: $f differs from the 1-thread run" >&2; exit 1; }
done
echo "bench/batch: ensemble summaries identical over threads and ranks"
