#!/bin/sh
# bench/adaptive/summary.sh CSV - the figures of bench/adaptive/run.sh from
# its work_precision rows: per problem and line (method, k, s), the CPU
# seconds to reach err_q <= 1e-6, 1e-8, 1e-10, 1e-12 (log-log interpolation
# between the line's points; "-" not reached, "<=" its first point is
# already below), the ratios adaptive / fixed step and adaptive / rk8pd at
# each level, and per adaptive point: tol, error / tol, steps, max|H - H0|,
# max|g|.
set -eu
awk -F, '
  function lg(x) { return log(x) / log(10) }
  NR > 1 {
    key = $1 SUBSEP $2 ($3 != "" ? "(" $3 "," $4 ")" : "")
    if (!(key in n)) { order[++nk] = key }
    i = ++n[key]; err[key, i] = $8; sec[key, i] = $7
    if ($2 ~ /adaptive/)
      rows[$1] = rows[$1] sprintf("  %-28s tol %-7g error/tol %-8.3g steps %-6d max|H-H0| %-8.2g max|g| %s\n",
                                   $2 "(" $3 "," $4 ")", $5, $8 / $5, $6, $9, $10 == "" ? "-" : sprintf("%.2g", $10))
  }
  # seconds of line key at error level E (0 not reached; negative: upper bound)
  function at(key, E,   i, a, b) {
    if (n[key] && err[key, 1] <= E) return -sec[key, 1]
    for (i = 2; i <= n[key]; i++)
      if (err[key, i] <= E && err[key, i - 1] > E) {
        a = (lg(E) - lg(err[key, i - 1])) / (lg(err[key, i]) - lg(err[key, i - 1]))
        return 10 ^ (lg(sec[key, i - 1]) + a * (lg(sec[key, i]) - lg(sec[key, i - 1])))
      }
    return 0
  }
  function show(t) { return t == 0 ? "-" : t < 0 ? sprintf("<=%.3g", -t) : sprintf("%.3g", t) }
  END {
    split("1e-6 1e-8 1e-10 1e-12", lv, " ")
    print "CPU seconds to reach err_q <= level (median of 5 timed runs; adaptive = NAME_step_adaptive)"
    printf "%-16s %-28s", "problem", "line"; for (l = 1; l <= 4; l++) printf " %10s", lv[l]; printf "\n"
    for (j = 1; j <= nk; j++) {
      split(order[j], f, SUBSEP)
      if (f[1] != prev) { if (prev != "") printf "%s", rows[prev]; prev = f[1] }
      printf "%-16s %-28s", f[1], f[2]
      for (l = 1; l <= 4; l++) printf " %10s", show(at(order[j], lv[l] + 0))
      printf "\n"
      # adaptive against the fixed line of the same solver and against rk8pd
      if (f[2] ~ /adaptive/) {
        fx = f[1] SUBSEP f[2]; sub(/-adaptive/, "", fx); rk = f[1] SUBSEP "gsl-rk8pd"
        printf "%-16s %-28s", "", "  time / fixed step"
        for (l = 1; l <= 4; l++) { a = at(order[j], lv[l] + 0); b = at(fx, lv[l] + 0)
          printf " %10s", (a > 0 && b > 0 ? sprintf("%.3gx", a / b) : "-") }
        printf "\n"
        if (rk in n) {
          printf "%-16s %-28s", "", "  time / gsl-rk8pd"
          for (l = 1; l <= 4; l++) { a = at(order[j], lv[l] + 0); b = at(rk, lv[l] + 0)
            printf " %10s", (a > 0 && b > 0 ? sprintf("%.3gx", a / b) : "-") }
          printf "\n"
        }
      }
    }
    printf "%s", rows[prev]
  }' "$1"
