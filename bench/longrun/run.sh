#!/bin/sh
# Long runs: Brouwer's law for the generated solvers (not part of make check).
#   bench/longrun/run.sh [--quick]
# Generates HBVM(k,s) for models/kepler.ham (s=2, -k auto: k=16, h = 2 pi/200)
# and models/pendulum.ham (s=2, -k auto: k=2, h = 0.1), --multiplier const, each
# with compensated summation, with --plain-sum, and compensated with --wide-step
# (the sweep in long double), the pendulum with --multiplier poly, and bench/longrun/oscillator.ham (two harmonic oscillators,
# s=2, k=2, h = 0.1) compensated with and without --wide-step; runs each RUNS=8 times from initial values
# perturbed by a relative 1e-12 for STEPS=10^7 steps (bench/longrun/longrun.c)
# and writes
#   bench/results/longrun.csv  solver,n,t,rms_dH,max_dH,rms_g,max_g on a
#                              log-spaced grid of step numbers
#   bench/results/longrun.txt  per solver: max |H-H0| to 10^6 and 10^7 steps,
#                              the log-log slopes of the RMS errors, the target
#   bench/results/longrun.png  RMS |H-H0| and |g| against t (gnuplot)
# --quick: 10^5 steps, 2 runs, results in build/longrun/quick/ (a smoke test).
# About 6 minutes on one core. Exit status 0; 3 when the target (Kepler,
# compensated, max |H-H0| <= 5e-13 over 10^6 steps) is missed; 1 on errors.
set -eu
cd "$(dirname "$0")/../.."
STEPS=10000000
RUNS=${RUNS:-8}
TARGET=5e-13
B=build/longrun
R=bench/results
if [ "${1:-}" = "--quick" ]; then STEPS=100000; RUNS=2; R=$B/quick; fi
mkdir -p "$B" "$R"

[ -x gen/hbvmgen ] || make --no-print-directory gen/hbvmgen >/dev/null
# the paper's method (--multiplier const; the default is poly for s >= 2 with
# constraints), and the pendulum once more with poly, whose energy rescale
# holds H at each step
for model in kepler pendulum; do
  gen/hbvmgen -s 2 -k auto --multiplier const -n "${model}_comp" -o "$B" "models/$model.ham"
  gen/hbvmgen -s 2 -k auto --multiplier const --plain-sum -n "${model}_plain" -o "$B" "models/$model.ham"
  gen/hbvmgen -s 2 -k auto --multiplier const --wide-step -n "${model}_wide" -o "$B" "models/$model.ham"
done
gen/hbvmgen -s 2 -k auto --multiplier poly -n pendulum_poly -o "$B" models/pendulum.ham
gen/hbvmgen -s 2 -k auto -n oscillator_comp -o "$B" bench/longrun/oscillator.ham
gen/hbvmgen -s 2 -k auto --wide-step -n oscillator_wide -o "$B" bench/longrun/oscillator.ham
${CC:-cc} -O2 -std=c99 -Wall -Wextra -pedantic -I"$B" -o "$B/longrun" bench/longrun/longrun.c \
  "$B/kepler_comp.c" "$B/kepler_plain.c" "$B/kepler_wide.c" "$B/pendulum_comp.c" "$B/pendulum_plain.c" "$B/pendulum_wide.c" \
  "$B/pendulum_poly.c" "$B/oscillator_comp.c" "$B/oscillator_wide.c" -lm

# results are written in $B and copied to $R at the end
KEPLER_H=$(awk 'BEGIN { printf "%.17g", 8 * atan2(1, 1) / 200 }')
echo "solver,n,t,rms_dH,max_dH,rms_g,max_g" > "$B/longrun.csv"
: > "$B/summary"
for sv in kepler_comp kepler_plain kepler_wide pendulum_comp pendulum_plain pendulum_wide pendulum_poly oscillator_comp oscillator_wide; do
  case "$sv" in kepler*) h=$KEPLER_H ;; *) h=0.1 ;; esac
  "$B/longrun" "$sv" "$h" "$STEPS" "$RUNS" >> "$B/longrun.csv" 2>> "$B/summary"
done

# the target: Kepler, compensated, the running max |H-H0| at 10^6 steps (or at the end of a --quick run)
mid=$((STEPS < 1000000 ? STEPS : 1000000))
worst=$(awk -F, -v n="$mid" '$1 == "kepler_comp" && $2 == n { print $5 }' "$B/longrun.csv")
[ -n "$worst" ] || { echo "longrun: no Kepler result at $mid steps" >&2; exit 1; }
verdict=$(awk -v w="$worst" -v t="$TARGET" 'BEGIN { print (w + 0 <= t + 0) ? "met" : "MISSED" }')
{
  echo "# bench/longrun/run.sh: $RUNS runs of $STEPS steps per solver, initial values perturbed by 1e-12"
  echo "# HBVM(k,s) with s=2, -k auto; Kepler e=0.6 at h = 2 pi/200, pendulum and oscillator at h = 0.1"
  echo "# --multiplier const; _comp: compensated (Kahan) summation of q, p, t; _plain: --plain-sum; _wide: compensated, --wide-step"
  echo "# pendulum_poly: --multiplier poly (order 4, p projected and rescaled to H0 each step), compensated"
  echo "# slope: least squares of log(RMS over the runs) against log(t), from 10^3 steps on"
  cat "$B/summary"
  echo "target: Kepler, compensated, max |H-H0| over $mid steps = $worst <= $TARGET: $verdict"
} > "$B/longrun.txt"
mkdir -p "$R"
cp "$B/longrun.csv" "$B/longrun.txt" "$R/"
cat "$R/longrun.txt"

if command -v gnuplot >/dev/null 2>&1; then
  gnuplot <<GP
set terminal pngcairo size 1100,480 font ",10"
set output "$B/longrun.png"
set datafile separator ","
set logscale xy
set format y "%.0e"
set key top left
set grid
set multiplot layout 1,2 title "Brouwer's law: RMS over $RUNS runs, initial values perturbed by 1e-12 (HBVM, s = 2, -k auto)"
set xlabel "steps"
set ylabel "RMS |H - H0|"
set title "energy error"
plot "$B/longrun.csv" using (strcol(1) eq "kepler_comp" ? \$2 : NaN):4 with lines lw 2 title "Kepler, compensated", \
     "" using (strcol(1) eq "kepler_plain" ? \$2 : NaN):4 with lines lw 2 title "Kepler, plain sum", \
     "" using (strcol(1) eq "pendulum_comp" ? \$2 : NaN):4 with lines lw 2 title "pendulum, compensated", \
     "" using (strcol(1) eq "pendulum_plain" ? \$2 : NaN):4 with lines lw 2 title "pendulum, plain sum", \
     "" using (strcol(1) eq "kepler_wide" ? \$2 : NaN):4 with lines lw 2 title "Kepler, compensated, wide step", \
     "" using (strcol(1) eq "pendulum_wide" ? \$2 : NaN):4 with lines lw 2 title "pendulum, compensated, wide step", \
     "" using (strcol(1) eq "pendulum_poly" ? \$2 : NaN):4 with lines lw 2 title "pendulum, poly (rescaled to H0)", \
     "" using (strcol(1) eq "oscillator_comp" ? \$2 : NaN):4 with lines lw 1 dt 4 title "oscillator, compensated", \
     "" using (strcol(1) eq "oscillator_wide" ? \$2 : NaN):4 with lines lw 1 dt 5 title "oscillator, compensated, wide step", \
     [1000:$STEPS] 2e-16 * sqrt(x) with lines dt 2 lc "black" title "slope 1/2", \
     [1000:$STEPS] 5e-19 * x with lines dt 3 lc "black" title "slope 1"
set ylabel "RMS |g(q)|"
set title "constraint residual (pendulum)"
plot "$B/longrun.csv" using (strcol(1) eq "pendulum_comp" ? \$2 : NaN):6 with lines lw 2 lc 3 title "pendulum, compensated", \
     "" using (strcol(1) eq "pendulum_plain" ? \$2 : NaN):6 with lines lw 2 lc 4 title "pendulum, plain sum", \
     "" using (strcol(1) eq "pendulum_wide" ? \$2 : NaN):6 with lines lw 2 lc 6 title "pendulum, compensated, wide step", \
     "" using (strcol(1) eq "pendulum_poly" ? \$2 : NaN):6 with lines lw 2 lc 7 title "pendulum, poly", \
     [1000:$STEPS] 2e-16 * sqrt(x) with lines dt 2 lc "black" title "slope 1/2"
unset multiplot
GP
  cp "$B/longrun.png" "$R/"
  echo "longrun: wrote $R/longrun.csv, $R/longrun.txt, $R/longrun.png"
else
  echo "longrun: gnuplot not found (scripts/deps.sh bench): no plot; wrote $R/longrun.csv, $R/longrun.txt"
fi
[ "$verdict" = met ] || exit 3
