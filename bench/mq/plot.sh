#!/bin/sh
# bench/mq/plot.sh - bench/results/mq_wp_P.png from bench/results/mq_wp.csv
# (bench/mq/wp.sh): CPU seconds against the error at T of the gcc -O2 build,
# rk8pd and the hbvm lines named below (dpc_, sphc_, armc_: the Cartesian forms), timed
# points only, in the order of the sweep (tol or N).
set -e
csv=bench/results/mq_wp.csv
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
# plot PROBLEM LINE... (a LINE is method:mode)
plot() {
  pb=$1
  shift
  cmd=""
  for line in "$@"; do
    m=${line%%:*} mode=${line#*:}
    awk -F, -v pb="$pb" -v m="$m" -v mode="$mode" \
      '$1 == "gcc-O2" && $2 == pb && $3 == m && $5 == mode && $12 > 0 { print $10, $12 }' \
      "$csv" >"$dir/$m.$mode"
    cmd="$cmd${cmd:+, }'$dir/$m.$mode' using 1:2 with linespoints title '$m $mode'"
  done
  gnuplot <<GP
set terminal pngcairo size 900,600 noenhanced
set output 'bench/results/mq_wp_$pb.png'
set logscale xy
set xlabel 'max error of (q, p) at T = 10'
set ylabel 'CPU seconds (median of 7, gcc -O2)'
set title '$pb: hbvmgen against GSL rk8pd on the same ODE'
set key top right
plot $cmd
GP
}
plot pendulum_angle gsl-rk8pd:adaptive pa_ks_s6:adaptive pa_ks_s6:fixed pa_ks_s4:adaptive \
  pa_kauto_s6:adaptive pa_kauto_s4:adaptive pa_quad_s6:adaptive pa_quad_s4:adaptive
plot double_pendulum_angles gsl-rk8pd:adaptive dpa_ks_s6:fixed dpa_ks_s6:adaptive dpa_ks_s7:fixed \
  dpa_ks_s4:fixed dpa_ks_s4:adaptive dpc_ks_s6:fixed dpc_ks_s4:fixed
plot spherical_pendulum gsl-rk8pd:adaptive sph_kauto_s6:fixed sph_kauto_s6:adaptive sph_kauto_s5:fixed \
  sph_kauto_s4:fixed sph_kauto_s4:adaptive sphc_ks_s5:fixed sphc_ks_s5:adaptive
plot arm3 gsl-rk8pd:adaptive arm_kauto_s6:fixed arm_kauto_s6:adaptive arm_kauto_s5:fixed \
  arm_kauto_s4:fixed arm_kauto_s4:adaptive armc_ks_s6:fixed armc_ks_s5:fixed armc_ks_s5:adaptive
