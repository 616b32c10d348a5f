# bench/adaptive/rejections.awk - bench/results/rejections.csv as a table: a
# row per solver, the rejected share of the tries (%) per tol, and the
# largest; lines over 5% marked *. Run: awk -F, -f rejections.awk FILE.csv
NR == 1 { next }
{
  if (!($1 in seen)) { seen[$1] = 1; name[++nn] = $1 }
  if (!($2 in tseen)) { tseen[$2] = 1; tol[++nt] = $2 }
  pc[$1, $2] = $5; tries[$1, $2] = $3 + $4; rej[$1, $2] = $4
}
END {
  printf "%-18s", "rejected %"
  for (j = 1; j <= nt; j++) printf " %6s", tol[j]
  printf "    max (rejected/tries)\n"
  for (i = 1; i <= nn; i++) {
    n = name[i]; m = -1
    printf "%-18s", n
    for (j = 1; j <= nt; j++) {
      t = tol[j]
      printf " %5.1f%s", pc[n, t], (pc[n, t] > 5 ? "*" : " ")
      if (pc[n, t] > m) { m = pc[n, t]; mt = t }
    }
    printf "  %5.1f at %s (%d/%d)\n", m, mt, rej[n, mt], tries[n, mt]
  }
}
