# bench/stiff/pick.awk - the point of each method that reaches a slow error
# E at the least CPU time, for E = 1e-3 .. 1e-8, from a work_precision.csv
# (awk -F, -f bench/stiff/pick.awk FILE). A point reaches E when its error
# and the errors of every finer point of its line (smaller h, tighter
# tolerance: the rows after it) are <= E, so that a point whose error is
# small by a chance cancellation (the slow error is not monotone in h at
# h omega >> 1) does not count. HBVM lines of every (k, s) compete under
# their method. Output, space-separated, one row per (problem, E, method):
#   problem E method k s h seconds err err_H
BEGIN { ne = split("1e-3 1e-4 1e-5 1e-6 1e-7 1e-8", lev, " ") }
NR > 1 {
  line = $1 SUBSEP $2 SUBSEP $3 SUBSEP $4
  if (!(line in len)) lines[++nl] = line
  n = ++len[line]
  row[line, n] = $1 " " $2 " " ($3 == "" ? 0 : $3) " " ($4 == "" ? 0 : $4) " " $5
  sec[line, n] = $7 + 0
  err[line, n] = $8 + 0
  dH[line, n] = $9
}
END {
  for (l = 1; l <= nl; l++) {
    line = lines[l]
    worst = 0
    for (n = len[line]; n >= 1; n--) {
      if (err[line, n] > worst) worst = err[line, n]
      split(row[line, n], f, " ")
      for (e = 1; e <= ne; e++) if (worst <= lev[e] + 0) {
        key = f[1] SUBSEP lev[e] SUBSEP f[2]
        if (!(key in best) || sec[line, n] < best[key]) {
          best[key] = sec[line, n]
          out[key] = f[1] " " lev[e] " " f[2] " " f[3] " " f[4] " " f[5] " " sec[line, n] " " err[line, n] " " dH[line, n]
          if (!(key in seen)) { seen[key] = 1; keys[++nk] = key }
        }
      }
    }
  }
  for (i = 1; i <= nk; i++) print out[keys[i]]
}
