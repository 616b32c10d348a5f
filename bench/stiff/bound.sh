#!/bin/sh
# bench/stiff/bound.sh - where issue 27's target (newton >= 10x faster than
# the fastest fixed-point step of equal slow error) is reachable at all, for
# any solver of the step's equations:
#   1. every stiff problem's lines at s = 2..6 (-k auto): the fixed-point
#      step, Newton in the constant family and (with constraints) the poly
#      family, h halving (bench sweep, one repeat: errors only)
#   2. per problem and E = 1e-3..1e-8: each Newton line's largest h whose
#      error, and that of every finer point, is <= E (pick.awk's rule), the
#      method's own error whichever solver reached it; the fixed-point
#      lines' points likewise
#   3. callgrind: the fixed-point point's whole run (bench count), the
#      Newton point's whole run, and the fewest work a Newton step of that
#      line can do, one factorisation and two iterations
#      (bench/stiff/mincost.c, the step cut short), times T / h
#   4. the bound: fixed instructions / (T / h x that fewest work), the
#      most any solver of these equations can gain at E; the measured
#      ratio beside it. bench/results/stiff_bound.csv, stiff_bound.txt.
# STIFF_PROBLEMS, STIFF_S, STIFF_OUT as in run.sh. Runs in about 6 minutes
# alone, 19 at a load of 10 (2026-11-29).
set -eu
cd "$(dirname "$0")/../.."
B=build/bench-stiff-bound
R=${STIFF_OUT:-bench/results}
GEN=gen/hbvmgen
[ -x "$GEN" ] || make --no-print-directory all
command -v valgrind >/dev/null || { echo "bench/stiff/bound.sh: needs valgrind" >&2; exit 1; }
start=$(date +%s)
elapsed() { echo $(($(date +%s) - start)); }
PROBLEMS=${STIFF_PROBLEMS:-fpu50 fpu1000 stiff_bob stiff_bob6 butane}
S_LIST=${STIFF_S:-2 3 4 5 6}
# butane: s = 2, 3 only (its Newton solvers at s >= 4 are 1.6-8 MB of C, minutes
# of gcc each; its fixed-point step is the faster at every E already at s <= 3)
s_list() { case $1 in butane) echo "$S_LIST" | tr ' ' '\n' | awk '$1 <= 3' ;; *) echo "$S_LIST" ;; esac; }
FLOOR=1e-9 # the tightest E of the table is 1e-8
CFLAGS="-O2 -g -std=c99 -Wall -Wextra -pedantic"
. bench/stiff/problems.sh
. bench/common.sh

# STIFF_BOUND_TABLE=1: the table again from the last run's counts ($B/costs.txt) only
if [ "${STIFF_BOUND_TABLE:-0}" != 1 ]; then
mkdir -p "$B/gen" "$B/models" "$B/res" "$B/min" "$R"
rm -f "$B"/res/*.csv "$B"/res/failures.txt

echo "== bench/stiff/bound: generating ($(elapsed) s)"
: >"$B/configs.txt"
solvers=""
for p in $PROBLEMS; do
  model "$p"
  for s in $(s_list "$p"); do
    generate "$p" "$s"
    solvers="$solvers $GENERATED"
    echo "$p $GEN_K $s" >>"$B/configs.txt"
  done
done
# shellcheck disable=SC2086
write_registry bench/stiff/bound.sh "$B/gen" $solvers

echo "== bench/stiff/bound: building ($(elapsed) s)"
make --no-print-directory -f bench/bench.mk -j2 B="$B" SOLVERS="$solvers" >"$B/build.log" 2>&1 ||
  { cat "$B/build.log"; exit 1; }

echo "== bench/stiff/bound: references and lines ($(elapsed) s)"
for p in $PROBLEMS; do
  "$B/bench" ref "$p" >"$B/ref_$p.txt"
  while read -r q k s; do
    [ "$q" = "$p" ] || continue
    sweep "$B/res" "$p" hbvm-newton "$(newton_from "$p"):1e-6:2" -k "$k" -s "$s" --repeats 1 --min 0 --cap 0.5
    ! has_constraints "$p" ||
      sweep "$B/res" "$p" hbvm-poly-newton "$(newton_from "$p"):1e-6:2" -k "$k" -s "$s" --repeats 1 --min 0 --cap 0.5
    sweep "$B/res" "$p" hbvm "$(fixed_from "$p"):1e-6:2" -k "$k" -s "$s" --repeats 1 --min 0 --cap 0.5
  done <"$B/configs.txt"
done

# every line's point per E: its largest h whose error and that of every
# finer point are <= E (pick.awk's rule, each (method, k, s) on its own),
# as "problem E method k s h err seconds"
awk -F, 'BEGIN { ne = split("1e-3 1e-4 1e-5 1e-6 1e-7 1e-8", lev, " ") }
  NR > 1 { line = $1 " " $2 " " $3 " " $4; if (!(line in len)) lines[++nl] = line
    n = ++len[line]; h[line, n] = $5; sec[line, n] = $7; err[line, n] = $8 + 0 }
  END { for (l = 1; l <= nl; l++) { line = lines[l]; split(line, f, " ")
      for (e = 1; e <= ne; e++) { worst = 0; best = 0
        for (n = len[line]; n >= 1; n--) { if (err[line, n] > worst) worst = err[line, n]; if (worst <= lev[e] + 0) best = n }
        if (best) print f[1], lev[e], f[2], f[3], f[4], h[line, best], err[line, best], sec[line, best] } } }' \
  "$B/res/work_precision.csv" >"$B/points.txt"

# The instructions of a whole run (T = 10) at a point, cached:
# count METHOD PROBLEM K S H
count() {
  _c="$B/counts/$1_$2_$3_$4_$5"
  if [ ! -f "$_c" ]; then
    _n=$(awk -v h="$5" 'BEGIN { printf "%d", 10 / h + 0.5 }')
    if valgrind --tool=callgrind --toggle-collect=count_steps --callgrind-out-file="$B/callgrind.out" \
      "$B/bench" count "$2" "$1" "$3" "$4" "$5" 0 "$_n" >/dev/null 2>&1; then
      sed -n 's/^summary: *//p' "$B/callgrind.out" >"$_c"
    else echo NA >"$_c"; fi
  fi
  cat "$_c"
}
# The fewest work of one Newton step of solver NAME, cached: "C1 C2 FACTOR",
# the instructions of a step cut after one and two iterations (one
# factorisation each) and of the factorisation alone (mincost.c)
mincost() {
  [ ! -f "$B/min/$1.cost" ] || { cat "$B/min/$1.cost"; return; }
  for it in 1 2; do
    printf '#define %s_MAXITER %d\n#define %s_REUSE -1\n#define %s_REFRESH 1\n' "$1" $it "$1" "$1" >"$B/min/lim.h"
    # shellcheck disable=SC2086
    cc $CFLAGS -include "$B/min/lim.h" -I"$B/gen" -c -o "$B/min/$1_$it.o" "$B/gen/$1.c"
    # shellcheck disable=SC2086
    cc $CFLAGS -I"$B/gen" -DSOLVER="$1" "-DSOLVER_H=\"$1.h\"" -o "$B/min/$1_$it" bench/stiff/mincost.c \
      "$B/min/$1_$it.o" -lm
    _r=$("$B/min/$1_$it" 0.01)
    [ "$_r" = "1 $((it + 1)) 1" ] || { echo "bench/stiff/bound: $1 cut at $it: rc, iterations, factors $_r" >&2; exit 1; }
    valgrind --tool=callgrind --toggle-collect=one_step --callgrind-out-file="$B/min/cg.out" "$B/min/$1_$it" 0.01 \
      >/dev/null 2>&1
    printf '%s ' "$(sed -n 's/^summary: *//p' "$B/min/cg.out")" >>"$B/min/$1.part"
  done
  valgrind --tool=callgrind "--toggle-collect=*newton_factor_checked*" --callgrind-out-file="$B/min/cg.out" \
    "$B/min/$1_2" 0.01 >/dev/null 2>&1
  sed -n 's/^summary: *//p' "$B/min/cg.out" >>"$B/min/$1.part"
  mv "$B/min/$1.part" "$B/min/$1.cost"
  cat "$B/min/$1.cost"
}
solver_of() { # METHOD PROBLEM K S: the generated solver's name
  case $1 in hbvm) echo "${2}_k${3}s$4" ;; hbvm-newton) echo "${2}_k${3}s${4}newton" ;; *) echo "${2}_k${3}s${4}polynewton" ;; esac
}

echo "== bench/stiff/bound: the fewest work of a Newton step ($(elapsed) s)"
rm -rf "$B/counts" "$B"/min/*.cost "$B"/min/*.part
mkdir -p "$B/counts"
: >"$B/newton.txt" # problem E method k s h err seconds c1 c2 factor
while read -r p e m k s h err sec; do
  [ "$m" != hbvm ] || continue
  echo "$p $e $m $k $s $h $err $sec $(mincost "$(solver_of "$m" "$p" "$k" "$s")")" >>"$B/newton.txt"
done <"$B/points.txt"

# per problem and E: the Newton point of the fewest work (T / h x c2) and
# the fixed-point step's fastest point, "problem E N-method k s h err c1 c2
# factor F-method k s h err"
awk 'FNR == NR { key = $1 " " $2; mn = int(10 / $6 + 0.5) * $10
    if (!(key in nm) || mn < nm[key]) { nm[key] = mn; nrow[key] = $3 " " $4 " " $5 " " $6 " " $7 " " $9 " " $10 " " $11 }
    if (!(key in seen)) { seen[key] = 1; keys[++nk] = key }; next }
  $3 == "hbvm" { key = $1 " " $2; if (!(key in fs) || $8 < fs[key]) { fs[key] = $8; frow[key] = $3 " " $4 " " $5 " " $6 " " $7 }
    if (!(key in seen)) { seen[key] = 1; keys[++nk] = key } }
  END { for (i = 1; i <= nk; i++) { key = keys[i]
      print key, (key in nrow) ? nrow[key] : "- - - - - - - -", (key in frow) ? frow[key] : "- - - - -" } }' \
  "$B/newton.txt" "$B/points.txt" >"$B/chosen.txt"

echo "== bench/stiff/bound: callgrind of the whole runs ($(elapsed) s)"
: >"$B/costs.txt" # chosen.txt's row, then the instructions of the Newton and the fixed-point run
while read -r p e nm nk ns nh ne c1 c2 cf fm fk fs fh fe; do
  ni=NA fi=NA
  [ "$nm" = - ] || ni=$(count "$nm" "$p" "$nk" "$ns" "$nh")
  [ "$fm" = - ] || fi=$(count "$fm" "$p" "$fk" "$fs" "$fh")
  echo "$p $e $nm $nk $ns $nh $ne $c1 $c2 $cf $fm $fk $fs $fh $fe $ni $fi" >>"$B/costs.txt"
done <"$B/chosen.txt"
fi

echo "== bench/stiff/bound: results ($(elapsed) s)"
awk -v omegas="$STIFF_OMEGA" -v csv="$R/stiff_bound.csv" '
  BEGIN { n = split(omegas, o, " "); for (i = 1; i <= n; i++) { split(o[i], kv, "="); om[kv[1]] = kv[2] }
    print "problem,E,newton_point,h_omega,err,steps,c1,c2,factor,min_instructions,newton_instructions," \
      "fixed_point,fixed_h_omega,fixed_err,fixed_instructions,bound,bound_no_factor,measured" >csv
    printf "%-10s %-5s %-36s %-7s %-9s %-6s %-6s %-9s %-26s %-7s %-9s %-9s %6s %6s %8s\n", "problem", "E",
      "newton point", "h omega", "err", "c2", "factor", "min", "fixed point", "h omega", "fixed", "newton", "bound",
      "bound0", "measured" }
  { w = om[$1]
    if ($3 == "-" || $11 == "-") { printf "%-10s %-5s %s not reached\n", $1, $2, $3 == "-" ? "newton" : "fixed"; next }
    steps = int(10 / $6 + 0.5); mn = steps * $9; np = $3 ":" $4 ":" $5 ":" $6; fp = $11 ":" $12 ":" $13 ":" $14
    b = $17 == "NA" ? "NA" : sprintf("%.1f", $17 / mn); r = $16 == "NA" || $17 == "NA" ? "NA" : sprintf("%.1f", $17 / $16)
    b0 = $17 == "NA" ? "NA" : sprintf("%.1f", $17 / (steps * ($9 - $10)))
    printf "%-10s %-5s %-36s %-7.3g %-9.2e %-6d %-6d %-9.3g %-26s %-7.3g %-9.3g %-9.3g %6s %6s %8s\n", $1, $2, np, $6 * w,
      $7, $9, $10, mn, fp, $14 * w, $17, $16, b, b0, r
    printf "%s,%s,%s,%.4g,%s,%d,%s,%s,%s,%d,%s,%s,%.4g,%s,%s,%s,%s,%s\n", $1, $2, np, $6 * w, $7, steps, $8, $9, $10, mn,
      $16, fp, $14 * w, $15, $17, b, b0, r >>csv }
' "$B/costs.txt" >"$B/table.txt"
{
  echo "The most any solver of the step's equations can gain over the fixed-point step (bench/stiff/bound.sh,"
  echo "$(date -u '+%Y-%m-%d'); callgrind instructions of whole runs, T = 10). Per problem and slow error E: the Newton"
  echo "line (constant family hbvm-newton, poly family hbvm-poly-newton; s = ${S_LIST}, butane 2 3; -k auto) and point"
  echo "METHOD:K:S:H at its largest h whose slow error, and that of every finer point of the line (h halving),"
  echo "is <= E, the one whose fewest work is least: min = T/h steps x c2, c2 the instructions of one step cut"
  echo "after one factorisation (factor: its instructions) and two iterations (bench/stiff/mincost.c; the end of"
  echo "an accepted step not counted, so min is low and the bound high). fixed: the fixed-point step's fastest point"
  echo "of E (any s; CPU seconds of one run) and its instructions. bound = fixed / min: what the fastest possible"
  echo "solver of these equations gains with a factorisation a step; bound0 = fixed / (T/h x (c2 - factor)): with"
  echo "the factor kept across steps (as NAME_REUSE does at a fixed h), the most any solver can gain; measured ="
  echo "fixed / newton, the Newton step of today at the same point (it keeps its factor: above bound on butane)."
  echo "c2 includes NAME_anderson's two calls (on the bob 5994 against 5290 for the plain update: about 12%)."
  echo "h omega lies on a grid of factor 2: the largest h of error <= E may be up to 2x longer, and the bounds up"
  echo "to 2x higher. fixed-point lines: s = 2..6 as Newton's."
  echo
  cat "$B/table.txt"
} >"$R/stiff_bound.txt"
cat "$R/stiff_bound.txt"
echo "bench/stiff/bound.sh: $(elapsed) s"
