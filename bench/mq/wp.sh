#!/bin/sh
# bench/mq/wp.sh - work-precision of hbvmgen in minimal coordinates against
# GSL's rk8pd on the same ODE (bench/mq/wp.c): the pendulum in its angle and
# the double pendulum in angles, s = 2..6 at k = s and at the generator's k
# (-k auto: s for both, the end of the step rescaling p to keep H), the
# pendulum also at its old default (--energy quadrature: k = 2s+12, no
# rescale; with -k s the step keeps the plain quadrature), the double pendulum also at
# s = 7, 8 and (11,6), fixed and adaptive, one line with --stage-loop, and its
# Cartesian form (models/double_pendulum.ham, k = s = 4..6, variant cartesian,
# its state mapped to the angles); the spherical pendulum in its angles and the
# 3-link arm in its joint angles at s = 2..6, -k auto, the spherical
# pendulum's Cartesian form (models/conical.ham started on the spherical
# pendulum's state, k = s = 4..6, variant cartesian) and the arm's
# (bench/mq/arm3_cartesian.ham: its joint points, constant M, three rods;
# k = s = 4..6, variant cartesian, mapped to the joint angles), each built by
# gcc -O2 and by clang -O3 -march=native -fno-math-errno -ffp-contract=off
# (docs/api.md, "Flags that are safe"). Writes bench/results/mq_wp.csv and
# bench/results/mq_ratios.txt (bench/mq/ratios.awk), and with gnuplot the
# figures bench/results/mq_wp_*.png (bench/mq/plot.sh). Run from the repository's
# root after `make all`: sh bench/mq/wp.sh
. bench/mq/solvers.sh
# gen MODEL PROBLEM(0 pendulum angle, 1 double pendulum angles, 2 spherical
# pendulum angles, 3 arm joint angles) NAME K S VARIANT [options]; MODEL is
# models/MODEL.ham, or a path without .ham when it has a slash
gen() {
  model=$1 pb=$2 name=$3 k=$4 s=$5 var=$6
  shift 6
  case $model in */*) ;; *) model=models/$model ;; esac
  $G "$model.ham" -k "$k" -s "$s" -n "$name" -o "$dir" "$@" >/dev/null
  [ "$k" = auto ] && k=$(sed -n 's/.*_K \([0-9]*\).*/\1/p' "$dir/$name.h" | head -n 1)
  echo "S($name, $pb, ${k:-0}, $s, \"$var\")" >>"$dir/solvers.def"
  echo "#include \"$name.h\"" >>"$dir/solvers.h"
}
for s in 2 3 4 5 6; do
  gen pendulum_angle 0 pa_ks_s$s "$s" "$s" ""
  gen pendulum_angle 0 pa_kauto_s$s auto "$s" ""
  gen pendulum_angle 0 pa_quad_s$s auto "$s" "" --energy quadrature
done
for s in 3 4 5 6 7 8; do
  gen double_pendulum_angles 1 dpa_ks_s$s "$s" "$s" ""
done
gen double_pendulum_angles 1 dpa_kauto_s4 auto 4 ""
gen double_pendulum_angles 1 dpa_kauto_s6 auto 6 ""
gen double_pendulum_angles 1 dpa_k11_s6 11 6 ""
gen double_pendulum_angles 1 dpa_ks_s4_loop 4 4 "stage-loop" --stage-loop 1
for s in 4 5 6; do  # the Cartesian form (two constraints, the poly family), in the angles' group
  gen double_pendulum 1 dpc_ks_s$s "$s" "$s" "cartesian"
done
for s in 2 3 4 5 6; do  # -k auto: k = s, the step rescaling p to keep H
  gen spherical_pendulum 2 sph_kauto_s$s auto "$s" ""
  gen arm3 3 arm_kauto_s$s auto "$s" ""
done
for s in 4 5 6; do  # the spherical pendulum's Cartesian form (one constraint), started on its state
  gen conical 2 sphc_ks_s$s "$s" "$s" "cartesian"
done
for s in 4 5 6; do  # the arm's Cartesian form (three constraints), started on its state
  gen bench/mq/arm3_cartesian 3 armc_ks_s$s "$s" "$s" "cartesian"
done
W="-std=c99 -Wall -Wextra -pedantic"
srcs=$(solver_sources)
nice -n 5 gcc $W -O2 -DBUILD='"gcc-O2"' -I"$dir" -o "$dir/wp_gcc" bench/mq/wp.c $srcs $(pkg-config --libs gsl) -lm
nice -n 5 clang $W -O3 -march=native -fno-math-errno -ffp-contract=off -DBUILD='"clang-O3-native"' -I"$dir" \
  -o "$dir/wp_clang" bench/mq/wp.c $srcs $(pkg-config --libs gsl) -lm
out=bench/results/mq_wp.csv
"$dir/wp_gcc" >"$out"
"$dir/wp_clang" | tail -n +2 >>"$out"
awk -F, -f bench/mq/ratios.awk "$out" >bench/results/mq_ratios.txt
cat bench/results/mq_ratios.txt
if command -v gnuplot >/dev/null; then sh bench/mq/plot.sh; fi
