# ratios.awk - from bench/results/mq_wp.csv (bench/mq/wp.c), the CPU seconds of
# each line at err 1e-10 and 1e-12, interpolated log-log between the two timed
# points of the line that bracket the level (the first such pair in the order
# of the sweep), and their ratio to gsl-rk8pd's in the same build; per build,
# problem and level the fastest hbvm line first. Usage: awk -F, -f ratios.awk CSV
NR == 1 { next }
{
  key = $1 "," $2 "," $3 "," $4 "," $5 "," $6 "," $7
  if (!(key in seen)) { seen[key] = 1; keys[++nk] = key }
  if ($12 > 0) { n = ++np[key]; e[key, n] = $10 + 0; t[key, n] = $12 + 0; st[key, n] = $9 + 0 }
}
function at(key, E,    i, a, b, f) {
  for (i = 1; i < np[key]; i++) {
    a = e[key, i]; b = e[key, i + 1]
    if (a >= E && b <= E && a > b) {
      f = log(E / a) / log(b / a)
      steps_at = st[key, i] + f * (st[key, i + 1] - st[key, i])
      return exp(log(t[key, i]) + f * (log(t[key, i + 1]) - log(t[key, i])))
    }
  }
  return -1
}
END {
  split("1e-10 1e-12", levels, " ")
  for (j = 1; j <= nk; j++) {
    split(keys[j], f, ",")
    for (l = 1; l <= 2; l++) {
      E = levels[l] + 0
      x = at(keys[j], E)
      if (x < 0) continue
      g = f[1] SUBSEP f[2] SUBSEP l
      if (f[3] == "gsl-rk8pd") rk[g] = x
      else { nl[g]++; line[g, nl[g]] = keys[j]; tl[g, nl[g]] = x; sl[g, nl[g]] = steps_at }
      if (f[3] == "gsl-rk8pd") rks[g] = steps_at
      grp[g] = 1
    }
  }
  printf "%-16s %-22s %-6s %-24s %-11s %-8s %4s %2s %7s %10s %6s\n", "build", "problem", "err", "method", "variant", "mode", "k", "s", "steps", "seconds", "ratio"
  np_ = split("pendulum_angle double_pendulum_angles spherical_pendulum arm3", problems, " ")
  for (b = 1; b <= 2; b++) for (p = 1; p <= np_; p++) for (l = 1; l <= 2; l++) {
    bn = b == 1 ? "gcc-O2" : "clang-O3-native"
    pn = problems[p]
    g = bn SUBSEP pn SUBSEP l
    if (!(g in grp)) continue
    printf "%-16s %-22s %-6s %-24s %-11s %-8s %4s %2s %7.0f %10.3e %6s\n", bn, pn, levels[l], "gsl-rk8pd", "", "adaptive", "", "", rks[g], rk[g], "1.00"
    # selection sort of the hbvm lines by time
    n = nl[g]
    for (i = 1; i <= n; i++) idx[i] = i
    for (i = 1; i <= n; i++) for (q = i + 1; q <= n; q++) if (tl[g, idx[q]] < tl[g, idx[i]]) { z = idx[i]; idx[i] = idx[q]; idx[q] = z }
    for (i = 1; i <= n; i++) {
      split(line[g, idx[i]], f, ",")
      printf "%-16s %-22s %-6s %-24s %-11s %-8s %4s %2s %7.0f %10.3e %6.2f\n", bn, pn, levels[l], f[3], f[4], f[5], f[6], f[7], sl[g, idx[i]], tl[g, idx[i]], (rk[g] > 0 ? tl[g, idx[i]] / rk[g] : -1)
    }
  }
}
