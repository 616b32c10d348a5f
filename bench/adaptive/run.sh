#!/bin/sh
# bench/adaptive/run.sh - NAME_step_adaptive against the best fixed step and
# GSL's rk8pd, side by side in one run (issue 11), without the rest of
# `make bench`:
#   1. generates the solvers of CONFIGS into build/bench-adaptive/gen
#      (models/P.ham, or bench/adaptive/P.ham for the eccentric Kepler
#      orbits e = 0.9 and e = 0.99)
#   2. builds the benchmark driver there (bench/bench.mk)
#   3. sweeps, per problem: the adaptive line (tolerances 1e-4 .. 1e-13) and
#      the fixed-step line of the same solver; rk8pd where GSL has the
#      problem in minimal coordinates
#   4. writes bench/results/adaptive.csv (the rows of work_precision.csv),
#      bench/results/adaptive.txt (bench/adaptive/summary.sh), and redraws
#      bench/results/wp_P.png and inv_P.png with the adaptive line added to
#      the lines of the last `make bench` (bench/results/work_precision.csv)
set -eu
cd "$(dirname "$0")/../.."
B=build/bench-adaptive
R=bench/results
GEN=gen/hbvmgen
[ -x "$GEN" ] || make --no-print-directory all

# problem k s family: the best (k, s) of the fixed-step benchmark
# (bench/results/summary.txt, section 2): poly(4,4) at the auto k on the
# constrained problems. On Kepler the fastest adaptive line that keeps H at
# round-off at tol <= 1e-7, (11,6) (measured against (4,4)..(8,8), (8,5),
# (10,5), (9,6)..(12,6), (10,7)..(14,7), (12,8), (14,8): bench/README.md), and
# s = 3 at the k of -k auto (18: H at round-off at every converging h).
# ADAPTIVE_CONFIGS="..." runs other lines (into build/bench-adaptive/res only:
# bench/results and the figures are left alone).
CONFIGS=${ADAPTIVE_CONFIGS:-"pendulum 4 4 poly
conical 4 4 poly
modified 12 4 poly
satellites 4 4 poly
double_pendulum 4 4 poly
chain8 4 4 poly
kepler 11 6 const
kepler 18 3 const
kepler09 11 6 const
kepler09 18 3 const
kepler099 11 6 const
kepler099 18 3 const"}

. bench/common.sh
# the fixed steps start 4x coarser than make bench's for order 8 (as its
# poly_range); Kepler's at make bench's h, down to 1e-5 for e = 0.99
hrange4() {
  case $1 in
  kepler*) echo 0.2:1e-5:2 ;;
  *) hrange "$1" | awk -F: '{ printf "%.10g:%s:%s\n", 4 * $1, $2, $3 }' ;;
  esac
}
model() { if [ -f "models/$1.ham" ]; then echo "models/$1.ham"; else echo "bench/adaptive/$1.ham"; fi; }
name() { if [ "$4" = poly ]; then echo "${1}_k${2}s${3}poly"; else echo "${1}_k${2}s${3}"; fi; }

mkdir -p "$B/gen" "$B/res"
rm -f "$B/res"/*
solvers=""
echo "$CONFIGS" | {
  while read -r p k s f; do
    n=$(name "$p" "$k" "$s" "$f")
    "$GEN" --multiplier "$f" -k "$k" -s "$s" -n "$n" -o "$B/gen" "$(model "$p")"
    solvers="$solvers $n"
  done
  echo "$solvers" >"$B/solvers.txt"
}
solvers=$(cat "$B/solvers.txt")
# shellcheck disable=SC2086
write_registry bench/adaptive/run.sh "$B/gen" $solvers
make --no-print-directory -f bench/bench.mk -j2 B="$B" SOLVERS="$solvers" >"$B/build.log" 2>&1 ||
  { cat "$B/build.log"; exit 1; }

sweep() { # problem method range [options]
  _p=$1 _m=$2 _r=$3
  shift 3
  "$B/bench" sweep "$_p" "$_m" "$B/res" "$B/ref_$_p.txt" "$_r" --floor "$(floor "$_p")" "$@" 2>>"$B/res/failures.txt" ||
    echo "   ($_m on $_p: see $B/res/failures.txt)"
}
for p in $(echo "$CONFIGS" | cut -d' ' -f1 | uniq); do
  echo "== $p"
  "$B/bench" ref "$p" >"$B/ref_$p.txt"
  echo "$CONFIGS" | awk -v p="$p" '$1 == p { print $2, $3, $4 }' >"$B/configs_$p.txt"
  while read -r k s f; do
    if [ "$f" = poly ]; then fixed=hbvm-poly adaptive=hbvm-poly-adaptive; else fixed=hbvm adaptive=hbvm-adaptive; fi
    sweep "$p" $adaptive 1e-4:1e-13:10 -k "$k" -s "$s"
    sweep "$p" $fixed "$(hrange4 "$p")" -k "$k" -s "$s"
  done <"$B/configs_$p.txt"
  case $p in pendulum | conical | kepler* | double_pendulum) sweep "$p" gsl-rk8pd 1e-3:1e-14:10 ;; esac
done

if [ -n "${ADAPTIVE_CONFIGS:-}" ]; then # other lines: a summary, bench/results untouched
  bench/adaptive/summary.sh "$B/res/work_precision.csv"
  exit 0
fi
cp "$B/res/work_precision.csv" "$R/adaptive.csv"
bench/adaptive/summary.sh "$R/adaptive.csv" | tee "$R/adaptive.txt"
# the figures: the last make bench's lines plus these (adaptive lines and
# the new problems)
mkdir -p "$B/plot/r"
{
  cat "$R/work_precision.csv"
  awk -F, 'NR > 1 && ($2 ~ /adaptive/ || $1 ~ /^kepler0/)' "$R/adaptive.csv"
} >"$B/plot/r/work_precision.csv"
cp "$R/iterations.csv" "$B/plot/r/iterations.csv"
bench/plot.sh "$B/plot/r" "$B/plot/w"
cp "$B/plot/r"/wp_*.png "$B/plot/r"/inv_*.png "$R/"
