#!/bin/sh
# bench/run.sh - work-precision benchmarks of hbvmgen's solvers against the
# peers a user could pick instead (`make bench` runs it after `make all`).
#
#   1. generate HBVM(k,s) solvers with the current gen/hbvmgen into
#      build/bench/gen: for s = 1..3, k = s, the k of `-k auto` and the
#      paper's k
#   2. build the driver build/bench/bench (bench/bench.mk, -O2)
#   3. references at the final times (bench ref), and their accuracy
#   4. sweeps: every method on every problem it applies to
#   5. instruction counts of one step under callgrind (if time allows)
#   6. figures (bench/plot.sh) and the key figures (bench/summary.sh)
# Everything lands in bench/results/; see bench/README.md.
set -eu
cd "$(dirname "$0")/.."

B=build/bench
R=bench/results
GEN=gen/hbvmgen
BUDGET=${BENCH_BUDGET:-540} # seconds; callgrind is skipped past this
start=$(date +%s)
elapsed() { echo $(($(date +%s) - start)); }

PROBLEMS="pendulum conical modified satellites kepler chain8 double_pendulum"

# Step sizes FROM:TO:FACTOR (h = T/N, N from ceil(T/FROM) doubling), the
# error at which a line stops (the reference's accuracy), and the h of the
# callgrind count.
hrange() {
  case $1 in
  pendulum) echo 0.5:1e-5:2 ;;
  conical) echo 1:1e-4:2 ;;
  modified) echo 0.2:1e-5:2 ;;
  satellites) echo 2:1e-3:2 ;;
  kepler) echo 0.2:1e-4:2 ;;
  chain8) echo 0.02:1e-5:2 ;;
  double_pendulum) echo 0.2:1e-5:2 ;;
  esac
}
floor() {
  case $1 in
  kepler | conical) echo 1e-13 ;;
  *) echo 3e-13 ;;
  esac
}
count_h() {
  case $1 in
  satellites) echo 0.1 ;;
  conical) echo 0.1 ;;
  chain8) echo 0.001 ;;
  *) echo 0.01 ;;
  esac
}
IDA_TOLS=1e-3:1e-10:10
GSL_TOLS=1e-3:1e-14:10
GSL_PROBLEMS="pendulum conical kepler double_pendulum"

# The k that `hbvmgen -k auto` picks for model $1 at s = $2.
auto_k() {
  "$GEN" --check -s "$2" "models/$1.ham" | sed -n '1s/.* k=\([0-9]*\) s=.*/\1/p'
}

# The paper's k (section 6): modified k = 3s, satellites k = 6.
paper_k() {
  case $1 in
  modified) echo $((3 * $2)) ;;
  satellites) echo 6 ;;
  *) echo "$2" ;;
  esac
}

# "k s" pairs of a problem: (s,s), the auto k and the paper's k, s = 1..3.
configs() {
  for s in 1 2 3; do
    echo "$s $s"
    echo "$(auto_k "$1" "$s") $s"
    echo "$(paper_k "$1" "$s") $s"
  done | sort -n -k2 -k1 | uniq
}

mkdir -p "$B/gen" "$R"
# only this script's own results: bench/results also holds other benchmarks'
rm -f "$R/work_precision.csv" "$R/iterations.csv" "$R/overhead.csv" "$R/instructions.csv" "$R/reference.txt" \
  "$R/failures.txt" "$R/summary.txt" "$R/machine.txt" "$R"/wp_*.png "$R"/inv_*.png "$R/iterations.png"

# ---- the machine
{
  echo "date: $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "nproc: $(nproc)"
  echo "cpu: $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)"
  echo "compiler: $(${CC:-cc} --version | head -n 1)"
  echo "flags: -O2 (bench/bench.mk)"
  echo "gsl: $(pkg-config --modversion gsl)"
  echo "sundials: $(dpkg-query -W -f='${Version}' libsundials-dev 2>/dev/null || echo unknown)"
  echo "hbvmgen: $($GEN --version 2>&1 | head -n 1)"
  echo "load before (1, 5, 15 min): $(cut -d' ' -f1-3 /proc/loadavg)"
} >"$R/machine.txt"

# ---- 1. generate (the list of (k,s) is fixed here, once: gen/hbvmgen may
# be rebuilt by others while the sweeps run)
echo "== generating solvers into $B/gen ($(elapsed) s)"
for p in $PROBLEMS; do configs "$p" | sed "s/^/$p /"; done >"$B/configs.txt"
echo "-k auto at s=2: $(for p in $PROBLEMS; do printf '%s k=%s  ' "$p" "$(auto_k "$p" 2)"; done)" >>"$R/machine.txt"
solvers=""
while read -r p k s; do
  "$GEN" -k "$k" -s "$s" -n "${p}_k${k}s${s}" -o "$B/gen" "models/$p.ham"
  solvers="$solvers ${p}_k${k}s${s}"
done <"$B/configs.txt"
{
  echo "/* registry.c - written by bench/run.sh: the generated solvers of this build. */"
  echo "#include \"hbvm.h\""
  for n in $solvers; do echo "extern const GenSolver ${n}_bench;"; done
  echo "const GenSolver *const gen_solvers[] = {"
  for n in $solvers; do echo "  &${n}_bench,"; done
  echo "  0};"
} >"$B/gen/registry.c"

# ---- 2. build
echo "== building $B/bench ($(elapsed) s)"
make --no-print-directory -f bench/bench.mk -j2 B="$B" SOLVERS="$solvers" >"$B/build.log" 2>&1 ||
  { cat "$B/build.log"; exit 1; }
if grep -q 'warning:' "$B/build.log"; then grep 'warning:' "$B/build.log" >&2; fi

# ---- 3. references
echo "== references ($(elapsed) s)"
for p in $PROBLEMS; do
  "$B/bench" ref "$p" >"$B/ref_$p.txt"
  "$B/bench" refcheck "$p" >>"$R/reference.txt"
done

# ---- 4. sweeps
sweep() { # problem method range [options]
  _p=$1 _m=$2 _r=$3
  shift 3
  "$B/bench" sweep "$_p" "$_m" "$R" "$B/ref_$_p.txt" "$_r" --floor "$(floor "$_p")" "$@" 2>>"$R/failures.txt" ||
    echo "   ($_m on $_p: see $R/failures.txt)"
}
for p in $PROBLEMS; do
  echo "== $p ($(elapsed) s)"
  awk -v p="$p" '$1 == p { print $2, $3 }' "$B/configs.txt" >"$B/configs_$p.txt"
  while read -r k s; do
    for m in hbvm hbvm-generic; do
      sweep "$p" $m "$(hrange "$p")" -k "$k" -s "$s"
    done
  done <"$B/configs_$p.txt"
  sweep "$p" rattle "$(hrange "$p")"
  sweep "$p" ida $IDA_TOLS
  case " $GSL_PROBLEMS " in
  *" $p "*) for m in gsl-rk8pd gsl-rk4imp; do sweep "$p" $m $GSL_TOLS; done ;;
  esac
done

# ---- 5. instructions of one step (callgrind), s = 2 at the largest k
# generated (the auto k on every problem)
if [ "$(elapsed)" -lt "$BUDGET" ] && command -v valgrind >/dev/null; then
  echo "== callgrind ($(elapsed) s)"
  echo "problem,method,k,s,h,steps,iters_per_step,instr_per_step,instr_per_iter" >"$R/instructions.csv"
  for p in $PROBLEMS; do
    k=$(awk -v p="$p" '$1 == p && $3 == 2 { k = $2 } END { print k }' "$B/configs.txt")
    h=$(count_h "$p")
    for m in hbvm hbvm-generic; do
      out=$(valgrind --tool=callgrind --toggle-collect=count_steps --callgrind-out-file="$B/callgrind.out" \
        "$B/bench" count "$p" $m "$k" 2 "$h" 50 200 2>/dev/null) || { echo "   (callgrind $m on $p failed)"; continue; }
      ir=$(sed -n 's/^summary: *//p' "$B/callgrind.out")
      echo "$out $ir" | awk -v p="$p" -v m=$m -v k="$k" -v h="$h" \
        '{ printf "%s,%s,%s,2,%s,%d,%.3f,%.0f,%.1f\n", p, m, k, h, $1, $2 / $1, $3 / $1, $3 / $2 }' >>"$R/instructions.csv"
    done
  done
else
  echo "== callgrind skipped: $(elapsed) s used of the $BUDGET s budget"
fi

# ---- 6. figures and the key figures
echo "== figures ($(elapsed) s)"
bench/plot.sh "$R" "$B/plot"
bench/summary.sh "$R"

# ---- 7. the other measurements that live in make bench: long runs
# (Brouwer's law, issue 6), instructions per step and chain scaling of the
# generated code, the -k auto study for non-polynomial models
echo "== long runs ($(elapsed) s)"
RUNS=${LONGRUN_RUNS:-4} bench/longrun/run.sh || echo "bench: the long-run target was missed (bench/results/longrun.txt)"
echo "== lean-code measurements ($(elapsed) s)"
bench/lean/run.sh current
bench/batch/run.sh || echo "bench: the batch/ensemble benchmark failed"
bench/lean/kauto.sh

echo "load after (1, 5, 15 min): $(cut -d' ' -f1-3 /proc/loadavg)" >>"$R/machine.txt"
echo "bench/run.sh: $(elapsed) s" | tee -a "$R/machine.txt"
