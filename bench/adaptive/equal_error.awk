# bench/adaptive/equal_error.awk - the tries at equal error of two runs of
# bench/adaptive/rejections.sh (its CSV: name,tol,steps,rejected,percent,error):
# per solver, the after file's tries over the before file's at the after run's
# error, the before line interpolated log-log between the two neighbouring
# errors, the median over tol 1e-12..1e-6 and over 1e-6..1e-4 (1.000 = the same
# work; errors below 1e-13 are left out, round-off); and the lines over 5%
# rejected in each, with the worst after. Run:
#   awk -F, -f bench/adaptive/equal_error.awk BEFORE.csv AFTER.csv
FNR == 1 { f++; next }
{
  if (f == 2 && !($1 in seen)) { seen[$1] = 1; name[++nn] = $1 }
  k = ++np[f, $1]; tol[f, $1, k] = $2 + 0; tries[f, $1, k] = $3 + $4; err[f, $1, k] = $6 + 0
  if ($5 > 5) { over[f]++; if (f == 2 && $5 > worst) { worst = $5; wl = $1 " at " $2 " (" $4 "/" $3 + $4 ")" } }
}
# the before line's tries at error e: log-log between the two points around e
function before_tries(n, e,    i, j, m, ex, tx, t, a) {
  m = np[1, n]
  for (i = 1; i <= m; i++) { ex[i] = err[1, n, i]; tx[i] = tries[1, n, i] }
  for (i = 2; i <= m; i++)  # sorted by error
    for (j = i; j > 1 && ex[j] < ex[j - 1]; j--) {
      t = ex[j]; ex[j] = ex[j - 1]; ex[j - 1] = t; t = tx[j]; tx[j] = tx[j - 1]; tx[j - 1] = t
    }
  for (i = 1; i < m; i++)
    if (ex[i] > 0 && ex[i] <= e && e <= ex[i + 1] && ex[i + 1] > ex[i]) {
      a = (log(e) - log(ex[i])) / (log(ex[i + 1]) - log(ex[i]))
      return exp(log(tx[i]) + a * (log(tx[i + 1]) - log(tx[i])))
    }
  return 0
}
function median(v, m,    i, j, t) {
  for (i = 2; i <= m; i++)
    for (j = i; j > 1 && v[j] < v[j - 1]; j--) { t = v[j]; v[j] = v[j - 1]; v[j - 1] = t }
  return m % 2 ? v[(m + 1) / 2] : (v[m / 2] + v[m / 2 + 1]) / 2
}
# the median ratio of solver n over after-run tolerances lo..hi, "-" without any
function ratio(n, lo, hi,    i, m, b, v) {
  m = 0
  for (i = 1; i <= np[2, n]; i++)
    if (tol[2, n, i] >= lo * 0.999 && tol[2, n, i] <= hi * 1.001 && err[2, n, i] > 1e-13 &&
        (b = before_tries(n, err[2, n, i])) > 0)
      v[++m] = tries[2, n, i] / b
  return m ? sprintf("%.3f (%d)", median(v, m), m) : "-"
}
END {
  printf "%-22s %-18s %-18s\n", "after / before", "tol 1e-12..1e-6", "tol 1e-6..1e-4"
  for (i = 1; i <= nn; i++) printf "%-22s %-18s %-18s\n", name[i], ratio(name[i], 1e-12, 1e-6), ratio(name[i], 1e-6, 1e-4)
  printf "lines over 5%% rejected: before %d, after %d; the worst after: %s\n", over[1], over[2], wl ? wl " " worst "%" : "none"
}
