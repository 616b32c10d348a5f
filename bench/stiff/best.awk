# bench/stiff/best.awk - from bench/stiff/pick.awk's rows (problem E method
# k s h seconds err err_H), the fastest row of each (problem, E, class),
# where a class joins the two multiplier families of one solver: newton =
# hbvm-newton (constant family) or hbvm-poly-newton, fixed = hbvm (the
# fixed-point step, constant family) or hbvm-poly; any other method is its
# own class. Prints the row with its class appended (a tenth field), so that
# "newton is 10x faster than the fastest fixed-point step" compares the
# fastest of either family on both sides (awk -f bench/stiff/best.awk).
{
  cls = $3 ~ /newton$/ ? "newton" : ($3 == "hbvm" || $3 == "hbvm-poly") ? "fixed" : $3
  key = $1 SUBSEP $2 SUBSEP cls
  if (!(key in best)) keys[++n] = key
  else if ($7 + 0 >= best[key] + 0) next
  best[key] = $7
  row[key] = $0 " " cls
}
END { for (i = 1; i <= n; i++) print row[keys[i]] }
