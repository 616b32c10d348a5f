#!/bin/sh
# bench/stiff/summary.sh RESULTS - the key figures of the stiff benchmark
# from RESULTS/stiff_work_precision.csv, stiff_iterations.csv,
# stiff_scan.csv and stiff_scan_iterations.csv (bench/stiff/run.sh), to stdout.
set -eu
R=$1
. "$(dirname "$0")/problems.sh"
OMEGA=$STIFF_OMEGA

echo "Stiff benchmark (bench/stiff/run.sh; stiff_machine.txt). Error: the slow motion's at T = 10 (bench/stiff.h:"
echo "FPU x0 and its momenta, the bob's centre of mass, butane's dihedral), max norm, against the index-1"
echo "formulation by GSL rk8pd at 1e-15. Seconds: CPU, median of 5 timed repeats of the whole run, all lines in"
echo "one run. newton = hbvmgen --iteration newton, fixed = the fixed-point step (--iteration fixed), each the"
echo "faster of the constant family (hbvm-newton, hbvm) and, on the problems with constraints, the poly family"
echo "(hbvm-poly-newton, hbvm-poly: marked p) at each E (bench/stiff/best.awk)."
echo

echo "1. CPU seconds to reach a slow error <= E: each method's fastest point whose error, and that of every"
echo "   finer point of its line, is <= E (bench/stiff/pick.awk; HBVM: every s of the run (2, 3, 4, 6 unless"
echo "   STIFF_S says otherwise) at -k auto, the fastest taken, shown as (k,s) [h omega]; - = not reached)."
echo "   Ratios: fixed, ida and rattle over newton (> 1: newton faster)."
awk -F, -f bench/stiff/pick.awk "$R/stiff_work_precision.csv" | awk -f bench/stiff/best.awk | awk -v omegas="$OMEGA" '
  BEGIN { n = split(omegas, o, " "); for (i = 1; i <= n; i++) { split(o[i], kv, "="); om[kv[1]] = kv[2] }
          ne = split("1e-3 1e-4 1e-5 1e-6 1e-7 1e-8", lev, " ")
          nm = split("newton fixed rattle ida gsl-rk4imp gsl-msbdf gsl-bsimp", meth, " ") }
  {
    if (!($1 in seen)) { seen[$1] = 1; probs[++np] = $1 }
    key = $1 SUBSEP $2 SUBSEP $10
    best[key] = $7; hw[key] = $6 * om[$1]; ks[key] = "(" $4 "," $5 ")" ($3 ~ /^hbvm-poly/ ? "p" : ""); dH[key] = $9
  }
  END {
    printf "%-10s %-5s %-24s %-24s %-9s %-9s %-9s %-9s %-9s %8s %8s %8s\n", "problem", "E", "newton [h omega]", \
      "fixed [h omega]", "rattle", "ida", "rk4imp", "msbdf", "bsimp", "fix/new", "ida/new", "rat/new"
    for (p = 1; p <= np; p++) for (e = 1; e <= ne; e++) {
      line = sprintf("%-10s %-5s", probs[p], lev[e])
      for (m = 1; m <= nm; m++) {
        key = probs[p] SUBSEP lev[e] SUBSEP meth[m]
        if (m <= 2) cell = (key in best) ? sprintf("%.2e%s [%.3g]", best[key], ks[key], hw[key]) : "-"
        else cell = (key in best) ? sprintf("%.2e", best[key]) : "-"
        line = line sprintf(m <= 2 ? " %-24s" : " %-9s", cell)
      }
      kn = probs[p] SUBSEP lev[e] SUBSEP "newton"
      kf = probs[p] SUBSEP lev[e] SUBSEP "fixed"
      ki = probs[p] SUBSEP lev[e] SUBSEP "ida"
      kr = probs[p] SUBSEP lev[e] SUBSEP "rattle"
      line = line sprintf(" %8s %8s %8s", (kn in best && kf in best) ? sprintf("%.1f", best[kf] / best[kn]) : "-", \
                                          (kn in best && ki in best) ? sprintf("%.1f", best[ki] / best[kn]) : "-", \
                                          (kn in best && kr in best) ? sprintf("%.1f", best[kr] / best[kn]) : "-")
      print line
    }
    print ""
    print "2. max |H - H0| over the run at those points (E = 1e-4 and 1e-6): newton, fixed, ida, rattle"
    for (p = 1; p <= np; p++) for (e = 2; e <= 4; e += 2) {
      line = sprintf("%-10s %-5s", probs[p], lev[e])
      for (m = 1; m <= 4; m++) {
        key = probs[p] SUBSEP lev[e] SUBSEP meth[m]
        line = line sprintf(" %-8s %-10s", meth[m], (key in dH) ? dH[key] : "-")
      }
      print line
    }
  }'
echo

echo "3. Newton iterations per step, mean (max), against h omega (stiff_iterations.csv, s = 2); the"
echo "   fixed-point step's sweeps per step where it converges"
awk -F, -v omegas="$OMEGA" '
  BEGIN { n = split(omegas, o, " "); for (i = 1; i <= n; i++) { split(o[i], kv, "="); om[kv[1]] = kv[2] } }
  NR > 1 && $4 == 2 {
    k = $1 " " $2
    if (!(k in seen)) { seen[k] = 1; keys[++nk] = k; row[k] = sprintf("%-10s %-11s", $1, $2) }
    row[k] = row[k] sprintf(" %.3g:%.1f(%d)", $5 * om[$1], $7, $8)
  }
  END { for (i = 1; i <= nk; i++) print row[keys[i]] }' "$R/stiff_iterations.csv"
echo

echo "4. The scan (Newton, s = 2, h omega in steps of 1.15; T = 10): the largest h omega whose slow error is"
echo "   <= 1e-3 with every step converged; the shortest that failed (a step did not converge) or lost the"
echo "   accuracy; and the longest below which every scanned h omega is accurate"
{
  echo "failed runs (header)"
  grep -h 'hbvm-newton k=[0-9]* s=2 .*run failed' "$R/stiff_failures.txt" |
    awk '{ sub(/^h=/, "", $6); print "FAIL," $2 ",hbvm-newton,,2," $6 ",,,nan,," }'
} >"$R/.scanfail.tmp"
awk -F, -v omegas="$OMEGA" '
  BEGIN { n = split(omegas, o, " "); for (i = 1; i <= n; i++) { split(o[i], kv, "="); om[kv[1]] = kv[2] } }
  FNR == 1 { f++; next }
  f == 1 { it[$1 SUBSEP $5] = sprintf("%.1f (%d)", $7, $8); next }
  f == 2 && !($1 in om) { next }
  f == 3 { $1 = $2; bad_at($1, $6 * om[$1], "failed"); next }
  {
    w = $5 * om[$1]
    if (!($1 in seen)) { seen[$1] = 1; probs[++np] = $1 }
    if ($8 + 0 <= 1e-3) { okw[$1, ++nok[$1]] = w; okh[$1, nok[$1]] = $5; oke[$1, nok[$1]] = $8 }
    else bad_at($1, w, sprintf("error %.2e", $8))
  }
  function bad_at(p, w, why) { if (!(p in bad) || w < bad[p]) { bad[p] = w; badwhy[p] = why } }
  END {
    for (p = 1; p <= np; p++) {
      q = probs[p]; best = -1; robust = -1
      for (i = 1; i <= nok[q]; i++) {
        if (okw[q, i] > best) { best = okw[q, i]; bi = i }
        if ((!(q in bad) || okw[q, i] < bad[q]) && okw[q, i] > robust) { robust = okw[q, i]; ri = i }
      }
      printf "%-10s largest %.3g (h %.3g, error %.2e, %s iterations)", q, best, okh[q, bi], oke[q, bi], it[q SUBSEP okh[q, bi]]
      if (q in bad) printf "; shortest bad %.3g (%s)", bad[q], badwhy[q]
      printf "; accurate below %.3g (error %.2e, %s iterations)\n", robust, oke[q, ri], it[q SUBSEP okh[q, ri]]
    }
  }' "$R/stiff_scan_iterations.csv" "$R/stiff_scan.csv" "$R/.scanfail.tmp"
rm -f "$R/.scanfail.tmp"
echo

echo "5. Section 1's points at E = 1e-4 and 1e-6 (newton, fixed, ida, rattle) timed again in alternation (bench ab, 11 rounds,"
echo "   medians; stiff_ab.csv): newton's time, and each other point's time over newton's"
awk -F, 'NR > 1 {
    k = $2 " " $1
    if (!(k in row)) { keys[++n] = k; row[k] = sprintf("%-10s E %-5s newton %s %.3g s", $2, $1, $3, $5); next }
    row[k] = row[k] sprintf("; %s %.3g s = %.1fx", $3, $5, $6)
  }
  END { for (i = 1; i <= n; i++) print row[keys[i]] }' "$R/stiff_ab.csv"
echo

echo "6. The fixed-step points of section 5 under callgrind: instructions of all the run's steps"
echo "   (bench/stiff/count.sh, stiff_instructions.csv), and their ratio to newton's"
[ -f "$R/stiff_instructions.csv" ] && awk -F, 'NR > 1 {
    k = $2 " " $1
    if (!(k in row)) { keys[++n] = k; row[k] = sprintf("%-10s E %-5s newton %s %.3g M", $2, $1, $3, $5 / 1e6); next }
    row[k] = row[k] sprintf("; %s %.3g M = %.2fx", $3, $5 / 1e6, $6)
  }
  END { for (i = 1; i <= n; i++) print row[keys[i]] }' "$R/stiff_instructions.csv"
