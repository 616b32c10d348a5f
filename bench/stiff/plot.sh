#!/bin/sh
# bench/stiff/plot.sh RESULTS WORKDIR - stiff_wp_PROBLEM.png from
# RESULTS/stiff_work_precision.csv: CPU seconds against the slow motion's
# error at T, one line per method (and (k,s) for HBVM; Newton thick).
set -eu
. "$(dirname "$0")/../common.sh"
R=$1
W=$2
rm -rf "$W"
mkdir -p "$W"
term=$(png_terminal 1000,700)
# one WORKDIR/PROBLEM__SERIES.dat per line (err, seconds)
awk -F, -v w="$W" 'NR > 1 {
  key = $2 ($3 != "" ? "(" $3 "," $4 ")" : "")
  print $8, $7 > (w "/" $1 "__" key ".dat")
}' "$R/stiff_work_precision.csv"
for p in $(awk -F, 'NR > 1 { print $1 }' "$R/stiff_work_precision.csv" | uniq); do
  plots=""
  set -- "#7f7f7f" "#17becf" "#8c564b" "#ff7f0e" "#bcbd22" "#1f77b4" "#d62728" "#000000" "#9467bd" "#2ca02c"
  for f in "$W/${p}__"*.dat; do
    c=$1
    shift
    set -- "$@" "$c"
    t=${f##*__}
    t=${t%.dat}
    case $t in
    hbvm-newton* | hbvm-poly-newton*) style="lw 3 pt 7" ;;
    hbvm*) style="lw 1.5 pt 6 dt 2" ;;
    *) style="lw 1.5 pt 4" ;;
    esac
    plots="$plots${plots:+, }'$f' using 1:2 with linespoints $style lc rgb '$c' title '$t'"
  done
  gnuplot <<GP
set terminal $term
set output '$R/stiff_wp_$p.png'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'slow-motion error at T = 10 (max norm)'
set ylabel 'CPU seconds (median of timed repeats)'
set title '$p: work against the slow motion error (bench/stiff/run.sh)' noenhanced
set key outside right
set grid
plot $plots
GP
done
