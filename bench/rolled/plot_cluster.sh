#!/bin/sh
# bench/rolled/plot_cluster.sh - bench/results/rolled_cluster.png from
# bench/results/rolled_cluster.csv and rolled_cluster_ida.csv
# (bench/rolled/cluster.sh): time per step against N, log-log, of the
# straight-line and rolled solvers (h = 0.02, stepped alternately) and of
# IDA (dense) at each tolerance.
set -e
csv=bench/results/rolled_cluster.csv
ida=bench/results/rolled_cluster_ida.csv
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
awk -F, 'NR > 1 && $9 != "" { print $1, $9 / 1000 }' "$csv" > "$dir/straight"
awk -F, 'NR > 1 { print $1, $10 / 1000 }' "$csv" > "$dir/rolled"
cmd="'$dir/straight' using 1:2 with linespoints title 'straight-line (--rolled off), h = 0.02', \\
  '$dir/rolled' using 1:2 with linespoints title 'rolled (--rolled on), h = 0.02'"
for tol in $(awk -F, 'NR > 1 && $2 == "ida_dense" { print $4 }' "$ida" | sort -u -g); do
  awk -F, -v tol="$tol" 'NR > 1 && $2 == "ida_dense" && $4 == tol { print $1, $6 / 1000 }' "$ida" > "$dir/ida$tol"
  cmd="$cmd, '$dir/ida$tol' using 1:2 with linespoints title 'IDA dense, tol $tol'"
done
gnuplot <<GP
set terminal pngcairo size 900,600 noenhanced
set output 'bench/results/rolled_cluster.png'
set logscale xy
set xlabel 'N (molecules; 6 N coordinates, N bonds)'
set ylabel 'microseconds of CPU per step (medians)'
set title 'cluster of N rigid diatomics, pair potential: time per step'
set key top left
plot $cmd
GP
