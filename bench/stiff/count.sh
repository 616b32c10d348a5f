#!/bin/sh
# bench/stiff/count.sh B R - callgrind instructions of the whole runs (every
# step, T = 10) of the fixed-step points in R/stiff_ab.csv (newton, the
# fixed-point step, RATTLE; IDA is not a fixed-step method), with the
# driver B/bench: R/stiff_instructions.csv. Skipped without valgrind.
set -eu
B=$1
R=$2
command -v valgrind >/dev/null || { echo "bench/stiff/count.sh: no valgrind, skipped"; exit 0; }
echo "E,problem,point,steps,instructions,ratio_to_newton" >"$R/stiff_instructions.csv"
# rows of stiff_ab.csv: E,problem,METHOD:K:S:X,rounds,median,ratio (newton first)
while IFS=, read -r e p point _; do
  [ "$e" = E ] && continue
  m=${point%%:*}
  case $m in ida) continue ;; esac
  rest=${point#*:}
  k=${rest%%:*}
  rest=${rest#*:}
  s=${rest%%:*}
  h=${rest#*:}
  n=$(awk -v h="$h" 'BEGIN { printf "%d", 10 / h + 0.5 }')
  valgrind --tool=callgrind --toggle-collect=count_steps --callgrind-out-file="$B/callgrind.out" \
    "$B/bench" count "$p" "$m" "$k" "$s" "$h" 0 "$n" >/dev/null 2>&1 || { echo "   (callgrind $point on $p failed)"; continue; }
  ir=$(sed -n 's/^summary: *//p' "$B/callgrind.out")
  case $m in *newton) base=$ir ;; esac # (newton's point is each E's first row)
  echo "$e,$p,$point,$n,$ir" | awk -F, -v b="$base" '{ printf "%s,%.3f\n", $0, $5 / b }' >>"$R/stiff_instructions.csv"
done <"$R/stiff_ab.csv"
