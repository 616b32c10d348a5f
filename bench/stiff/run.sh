#!/bin/sh
# bench/stiff/run.sh - the stiff benchmark (issue 27; `make bench-stiff`, and
# part of `make bench`): work against the slow motion's error on the stiff
# problems of bench/stiff.h, every method side by side in one run:
#   hbvm         the fixed-point step (--multiplier const), s = 2, 3, 4, 6 at -k auto
#   hbvm-newton  --iteration newton --multiplier const, the same (k, s): the
#                higher s (order 2s) for the long steps at tight errors, where
#                the sweeps need h omega < ~3 at any s
#   hbvm-poly-newton  --iteration newton in the default poly family (order 2s
#                in p too, p projected and rescaled), the same (k, s), on the
#                problems with constraints (the stiff bob, butane)
#   hbvm-poly    the poly family's fixed-point step there, so that the
#                fastest fixed-point step of either family is the baseline
#   rattle       RATTLE (Stormer-Verlet on the FPU chain)
#   ida          SUNDIALS IDA (BDF 1-5) on the GGL formulation
#   gsl-rk4imp, gsl-msbdf, gsl-bsimp   GSL's implicit steppers on the FPU
#                chain, y = (q, p) with the exact Jacobian
#   1. generates the solvers into build/bench-stiff/gen (fpu1000, stiff_bob6:
#      models/fpu.ham, models/stiff_bob.ham with omega = 1000, k = 1e6)
#   2. builds the driver there (bench/bench.mk)
#   3. references: the index-1 formulation, GSL rk8pd at 1e-15 (bench ref)
#   4. sweeps into build/bench-stiff/res; a fine scan of h omega with the
#      Newton step (the largest h omega that keeps the slow error <= 1e-3)
#      and the points of equal error compared timed again in alternation
#   5. bench/results/stiff_work_precision.csv, stiff_iterations.csv,
#      stiff_scan.csv, stiff_scan_iterations.csv, stiff_ab.csv,
#      stiff_instructions.csv (callgrind, bench/stiff/count.sh),
#      stiff_wp_P.png, stiff_summary.txt, stiff_machine.txt
# The error is the slow motion's (max norm at T = 10, bench/stiff.h): the
# fast phase is not resolved at h omega >> 1 by any long-step method.
# A partial run (the environment): STIFF_PROBLEMS (default all five),
# STIFF_S (the s of the HBVM lines, default "2 3 4 6"), STIFF_PEERS=0 (no
# RATTLE, IDA, GSL), STIFF_SCAN=0 (no scan of h omega), STIFF_AB_E (the
# errors of the alternated timings, default "1e-4 1e-6"), STIFF_OUT (the
# results' directory, default bench/results).
set -eu
cd "$(dirname "$0")/../.."
B=build/bench-stiff
R=${STIFF_OUT:-bench/results}
GEN=gen/hbvmgen
[ -x "$GEN" ] || make --no-print-directory all
start=$(date +%s)
elapsed() { echo $(($(date +%s) - start)); }

PROBLEMS=${STIFF_PROBLEMS:-fpu50 fpu1000 stiff_bob stiff_bob6 butane}
S_LIST=${STIFF_S:-2 3 4 6}
PEERS=${STIFF_PEERS:-1}
SCAN=${STIFF_SCAN:-1}

. bench/stiff/problems.sh
FLOOR=1e-10 # the slow error where a line stops (the references agree to 4e-11 or better: refcheck)
PEER_CAP=2  # CPU seconds of one RATTLE / IDA / GSL run (the HBVM lines: 0.25)
IDA_TOLS=1e-3:1e-11:10 # slow errors of 1e-8 and below by 1e-10 on every problem
GSL_TOLS=1e-3:1e-11:10

mkdir -p "$B/gen" "$B/models" "$B/res" "$B/scan" "$R"
rm -f "$B"/res/*.csv "$B"/res/failures.txt "$B"/scan/*.csv "$B"/scan/failures.txt

# ---- 1. generate: s = 2, 3, 4, 6 at -k auto, fixed point (forced: auto would pick Newton on these) and Newton
echo "== bench/stiff: generating ($(elapsed) s)"
: >"$B/configs.txt"
solvers=""
for p in $PROBLEMS; do
  model "$p"
  for s in $S_LIST; do
    generate "$p" "$s"
    solvers="$solvers $GENERATED"
    k=$GEN_K
    echo "$p $k $s" >>"$B/configs.txt"
  done
done
. bench/common.sh
# shellcheck disable=SC2086
write_registry bench/stiff/run.sh "$B/gen" $solvers

# ---- 2. build
echo "== bench/stiff: building ($(elapsed) s)"
make --no-print-directory -f bench/bench.mk -j2 B="$B" SOLVERS="$solvers" >"$B/build.log" 2>&1 ||
  { cat "$B/build.log"; exit 1; }
if grep -q 'warning:' "$B/build.log"; then grep 'warning:' "$B/build.log" >&2; fi

# ---- 3. references
echo "== bench/stiff: references ($(elapsed) s)"
: >"$B/reference.txt"
for p in $PROBLEMS; do
  "$B/bench" ref "$p" >"$B/ref_$p.txt"
  "$B/bench" refcheck "$p" >>"$B/reference.txt"
done

# ---- 4. sweeps, problem by problem, every method side by side
for p in $PROBLEMS; do
  echo "== bench/stiff: $p ($(elapsed) s)"
  while read -r q k s; do
    [ "$q" = "$p" ] || continue
    sweep "$B/res" "$p" hbvm-newton "$(newton_from "$p"):1e-6:2" -k "$k" -s "$s"
    ! has_constraints "$p" || sweep "$B/res" "$p" hbvm-poly-newton "$(newton_from "$p"):1e-6:2" -k "$k" -s "$s"
    sweep "$B/res" "$p" hbvm "$(fixed_from "$p"):1e-6:2" -k "$k" -s "$s" --cap $PEER_CAP
    ! has_constraints "$p" || sweep "$B/res" "$p" hbvm-poly "$(fixed_from "$p"):1e-6:2" -k "$k" -s "$s" --cap $PEER_CAP
  done <"$B/configs.txt"
  [ "$PEERS" = 1 ] || continue
  sweep "$B/res" "$p" rattle "$(fixed_from "$p"):2e-6:2" --cap $PEER_CAP
  sweep "$B/res" "$p" ida $IDA_TOLS --cap $PEER_CAP
  case $p in
  fpu*) for m in gsl-rk4imp gsl-msbdf gsl-bsimp; do sweep "$B/res" "$p" $m $GSL_TOLS --cap $PEER_CAP; done ;;
  esac
done
# the scan: h omega down from past the iteration's limit in steps of 1.15,
# s = 2, until h omega is about 5 (one timed repeat: the times are not used)
echo "== bench/stiff: scan of h omega ($(elapsed) s)"
for p in stiff_bob stiff_bob6 butane; do
  [ "$SCAN" = 1 ] && grep -q "^$p " "$B/configs.txt" || continue
  k=$(awk -v p="$p" '$1 == p && $3 == 2 { print $2 }' "$B/configs.txt")
  from=$(awk -v h="$(newton_from "$p")" 'BEGIN { print 1.6 * h }')
  to=$(awk -v h="$(newton_from "$p")" 'BEGIN { print h / 8 }')
  sweep "$B/scan" "$p" hbvm-newton "$from:$to:1.15" -k "$k" -s 2 --repeats 1 --min 0
done

# the points of equal error compared, timed again in alternation (bench ab):
# at E = 1e-4 and 1e-6 (STIFF_AB_E), newton's, the fixed-point step's (either family: best.awk),
# IDA's and RATTLE's points that reach E fastest (bench/stiff/pick.awk, as summary.sh's section 1)
echo "== bench/stiff: alternating runs ($(elapsed) s)"
: >"$B/res/ab.csv"
awk -F, -f bench/stiff/pick.awk "$B/res/work_precision.csv" | awk -f bench/stiff/best.awk >"$B/res/picks.txt"
for p in $PROBLEMS; do
  for e in ${STIFF_AB_E:-1e-4 1e-6}; do
    # shellcheck disable=SC2046
    set -- $(awk -v p="$p" -v e="$e" '$1 == p && $2 == e { spec[$10] = $3 ":" $4 ":" $5 ":" $6 }
      END { if ("newton" in spec) printf "%s %s %s %s", spec["newton"], spec["fixed"], spec["ida"], spec["rattle"] }' \
      "$B/res/picks.txt")
    [ $# -ge 2 ] || continue
    "$B/bench" ab "$p" 11 "$@" | sed "s/^/$e,/" >>"$B/res/ab.csv" || echo "   (bench ab on $p failed)"
  done
done

# ---- 5. results
echo "== bench/stiff: results ($(elapsed) s)"
cp "$B/res/work_precision.csv" "$R/stiff_work_precision.csv"
cp "$B/res/iterations.csv" "$R/stiff_iterations.csv"
if [ "$SCAN" = 1 ]; then
  cp "$B/scan/iterations.csv" "$R/stiff_scan_iterations.csv"
  cp "$B/scan/work_precision.csv" "$R/stiff_scan.csv"
else # (a partial run: summary.sh's section 4 left empty)
  : >"$R/stiff_scan_iterations.csv"
  : >"$R/stiff_scan.csv"
fi
{ echo "E,problem,point,rounds,median_seconds,ratio_to_newton"; cat "$B/res/ab.csv"; } >"$R/stiff_ab.csv"
bench/stiff/count.sh "$B" "$R"
cat "$B/res/failures.txt" "$B/scan/failures.txt" 2>/dev/null >"$R/stiff_failures.txt" || true
{
  echo "date: $(date -u '+%Y-%m-%d %H:%M UTC'), $(elapsed) s; $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)"
  echo "load (1, 5, 15 min) at the end: $(cut -d' ' -f1-3 /proc/loadavg)"
  cat "$B/reference.txt"
} >"$R/stiff_machine.txt"
bench/stiff/plot.sh "$R" "$B/plot"
bench/stiff/summary.sh "$R" >"$R/stiff_summary.txt"
echo "bench/stiff/run.sh: $(elapsed) s"
