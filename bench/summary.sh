#!/bin/sh
# bench/summary.sh RESULTS - the key figures of a run, from its CSVs, into
# RESULTS/summary.txt:
#   1. generated vs generic HBVM: CPU time ratio at equal (k, s, h)
#   2. CPU time to reach err_q <= 1e-6, 1e-8, 1e-10 for each method (HBVM:
#      its best (k,s)), log-log interpolated between the two sweep points
#      around the level; the winner, and HBVM's factor against the best peer
#   3. the overhead ratio and the instruction counts
set -eu
R=$1
{
  echo "== 1. generated (hbvm) vs generic (hbvm-generic): CPU time ratio at equal (k,s,h)"
  echo "problem      (k,s)     points  median   min     max"
  awk -F, 'NR > 1 && ($2 == "hbvm" || $2 == "hbvm-generic") {
      key = $1 " " $3 " " $4 " " $5
      if ($2 == "hbvm") t[key] = $7; else g[key] = $7
    }
    END {
      for (key in t) if (key in g) {
        split(key, f, " "); ks = f[1] " (" f[2] "," f[3] ")"
        r = g[key] / t[key]; n[ks]++; v[ks, n[ks]] = r
        np[f[1]]++; vp[f[1], np[f[1]]] = r
      }
      for (ks in n) print ks, n[ks], stats(v, ks, n[ks])
      for (p in np) print p, "(all)", np[p], stats(vp, p, np[p])
    }
    function stats(a, k, m,    i, j, x, lo, hi) {
      for (i = 1; i <= m; i++) for (j = i + 1; j <= m; j++)
        if (a[k, j] < a[k, i]) { x = a[k, i]; a[k, i] = a[k, j]; a[k, j] = x }
      return sprintf("%.2f %.2f %.2f", m % 2 ? a[k, (m + 1) / 2] : (a[k, m / 2] + a[k, m / 2 + 1]) / 2, a[k, 1], a[k, m])
    }' "$R/work_precision.csv" | sort -k1,1 -k2,2 | awk '{ printf "%-12s %-9s %6d  %6.2f  %6.2f  %6.2f\n", $1, $2, $3, $4, $5, $6 }'
  awk -F, 'FNR == 1 { f++ } f == 1 && FNR > 1 && ($2 == "hbvm" || $2 == "hbvm-generic") { e[$1 "," $3 "," $4 "," $5, $2] = $8 }
    f == 2 && FNR > 1 { it[$1 "," $3 "," $4 "," $5, $2] = $7 }
    END {
      for (k in e) { split(k, a, SUBSEP); if (a[2] != "hbvm" || !((a[1], "hbvm-generic") in e)) continue
        n++; r = e[k] - e[a[1], "hbvm-generic"]; r = (r < 0 ? -r : r) / e[k]
        if (e[k] > 1e-6) { nb++; if (r < 1e-3) same++; if (r > worst) worst = r }
        d = it[k] - it[a[1], "hbvm-generic"]; d = (d < 0 ? -d : d) / it[k]; if (d > itworst) itworst = d
        if (d <= 0.02) sameit++ }
      printf "same algorithm: %d rows at equal (k,s,h); mean iterations within 2%% in %d (largest difference %.1f%%); err_q within 0.1%% in %d of the %d rows with err_q > 1e-6 (largest relative difference %.1e; below, amplified round-off differs)\n", n, sameit, 100 * itworst, same, nb, worst
    }' "$R/work_precision.csv" "$R/iterations.csv"
  echo
  echo "== 2. CPU seconds to reach err_q <= level (interpolated; '-' = not reached)"
  awk -F, 'NR > 1 {
      line = $1 SUBSEP $2 SUBSEP ($3 != "" ? "(" $3 "," $4 ")" : "")
      if (!(line in seen)) { seen[line] = 1; lines[++nl] = line }
      n[line]++; e[line, n[line]] = $8; t[line, n[line]] = $7
      if (!($1 in isp)) { isp[$1] = 1; probs[++npr] = $1 }
    }
    END {
      split("1e-6 1e-8 1e-10", lev, " ")
      for (i = 1; i <= nl; i++) for (L = 1; L <= 3; L++) {
        split(lines[i], f, SUBSEP); x = reach(lines[i], lev[L] + 0)
        if (x < 0) continue
        k = f[1] SUBSEP f[2] SUBSEP L
        if (!(k in best) || x < best[k]) { best[k] = x; cfg[k] = f[3] }
        if (!((f[1] SUBSEP L) in methods)) methods[f[1] SUBSEP L] = ""
        if (index(methods[f[1] SUBSEP L], " " f[2] " ") == 0) methods[f[1] SUBSEP L] = methods[f[1] SUBSEP L] " " f[2] " "
      }
      for (P = 1; P <= npr; P++) {
        p = probs[P]
        for (L = 1; L <= 3; L++) {
          printf "%-11s %-6s", p, lev[L]
          win = ""; peer = ""
          nm = split(methods[p SUBSEP L], ms, " ")
          for (j = 1; j <= nm; j++) {
            m = ms[j]; k = p SUBSEP m SUBSEP L
            printf "  %s%s %.3g", m, cfg[k], best[k]
            if (win == "" || best[k] < best[p SUBSEP win SUBSEP L]) win = m
            if (m != "hbvm" && m != "hbvm-generic" && (peer == "" || best[k] < best[p SUBSEP peer SUBSEP L])) peer = m
          }
          if (nm == 0) printf "  (no method reached it)"
          else {
            printf "\n%-18s winner: %s", "", win
            hk = p SUBSEP "hbvm" SUBSEP L; pk = p SUBSEP peer SUBSEP L
            if ((hk in best) && peer != "")
              printf "; best peer %s; hbvm %s %.2fx", peer, best[hk] <= best[pk] ? "faster by" : "slower by",
                best[hk] <= best[pk] ? best[pk] / best[hk] : best[hk] / best[pk]
            else if (peer != "") printf "; hbvm did not reach it"
          }
          printf "\n"
        }
      }
    }
    function reach(l, E,    i) {
      for (i = 1; i <= n[l]; i++) if (e[l, i] <= E) {
        if (i == 1 || e[l, i - 1] <= E || e[l, i] == e[l, i - 1]) return t[l, i]
        return exp(log(t[l, i - 1]) + (log(E) - log(e[l, i - 1])) * (log(t[l, i]) - log(t[l, i - 1])) / (log(e[l, i]) - log(e[l, i - 1])))
      }
      return -1
    }' "$R/work_precision.csv"
  echo
  echo "== 3. overhead ratio step_ns / (iters * k * grad_ns), generated solvers: median over h"
  awk -F, 'NR > 1 { key = $1 " (" $2 "," $3 ")"; n[key]++; v[key, n[key]] = $8; g[key] = $7; st[key, n[key]] = $6 / $5 }
    END { for (k in n) { m = n[k]
      for (i = 1; i <= m; i++) for (j = i + 1; j <= m; j++) if (v[k, j] < v[k, i]) { x = v[k, i]; v[k, i] = v[k, j]; v[k, j] = x }
      printf "%-22s ratio %6.2f (min %.2f, max %.2f)  grad+jac %.1f ns\n", k, m % 2 ? v[k, (m + 1) / 2] : (v[k, m / 2] + v[k, m / 2 + 1]) / 2, v[k, 1], v[k, m], g[k] } }' \
    "$R/overhead.csv" | sort
  if [ -s "$R/instructions.csv" ]; then
    echo
    echo "== 4. instructions per step and per iteration (callgrind)"
    awk -F, 'NR > 1 { printf "%-11s %-13s (%s,%s) h=%-6s iters/step %.2f  instr/step %9.0f  instr/iter %8.1f\n", $1, $2, $3, $4, $5, $7, $8, $9
      if ($2 == "hbvm") h[$1] = $8; else if ($1 in h) printf "%-11s generic/generated instructions: %.2f\n", $1, $8 / h[$1] }' "$R/instructions.csv"
  fi
} >"$R/summary.txt"
