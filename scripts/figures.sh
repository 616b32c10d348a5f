#!/bin/sh
# make figures: redraw the paper's figures fig1-fig3 as PNG files in docs/.
#   fig1  conical pendulum, HBVM(2,2), h = T/100, 100 periods: solution error
#   fig2  the same run: multiplier, Hamiltonian, constraint, hidden-constraint errors
#   fig3  tethered satellites, HBVM(6,2), h = 0.1, 10^4 steps: hidden constraints,
#         Hamiltonian and the three constraints
set -eu
out=build/figures
mkdir -p "$out" docs
cc="${CC:-cc} -O2 -std=c99 -Iruntime -I$out"
build() { # model k s
  gen/hbvmgen -k "$2" -s "$3" -n "$1" --main -o "$out" "models/$1.ham"
  $cc -o "$out/$1" "$out/$1.c" "$out/$1_main.c" runtime/libhbvmrt.a -lm
}
build conical 2 2
build satellites 6 2
T=$(awk 'BEGIN { printf "%.17g", 2^0.75 * 3.14159265358979323846 }')
h=$(awk -v T="$T" 'BEGIN { printf "%.17g", T / 100 }')
"$out/conical" -h "$h" -N 10000 --every 10 --quiet --csv "$out/conical.csv" 2>/dev/null
"$out/satellites" -h 0.1 -N 10000 --every 10 --quiet --csv "$out/satellites.csv" 2>/dev/null

H0c=$(awk -F, 'NR == 2 { print $9 }' "$out/conical.csv")
H0s=$(awk -F, 'NR == 2 { print $23 }' "$out/satellites.csv")

gnuplot <<GP
set datafile separator ","
set terminal pngcairo size 900,560 font "sans,11"
r = 2**-0.5; w = 2**0.25; T = $T
max(a, b) = a > b ? a : b
err(t, x, y, z, px, py, pz) = max(max(max(abs(x - r*cos(w*t)), abs(y - r*sin(w*t))), max(abs(z + r), abs(px + r*w*sin(w*t)))), max(abs(py - r*w*cos(w*t)), abs(pz)))
set grid
set key top left
set output "docs/fig1.png"
set title "Conical pendulum, HBVM(2,2), h = T/100: solution error (max norm) grows linearly"
set xlabel "t / T (periods)"
set ylabel "max |(q,p) - exact|"
plot "$out/conical.csv" skip 1 using (\$1/T):(err(\$1,\$2,\$3,\$4,\$5,\$6,\$7)) with lines lw 2 title "HBVM(2,2)"
set output "docs/fig2.png"
set title "Conical pendulum, HBVM(2,2), h = T/100: invariants and multiplier"
set ylabel "error"
set logscale y
set format y "10^{%L}"
set yrange [1e-17:1e-10]
plot "$out/conical.csv" skip 1 using (\$1/T):(abs(\$8 - 2**-0.5) + 1e-18) with lines dt 2 lw 2 title "|lambda - 2^{-1/2}|", \
     "" skip 1 using (\$1/T):(abs(\$11) + 1e-18) with lines dt 4 lw 2 title "hidden constraint", \
     "" skip 1 using (\$1/T):(abs(\$9 - $H0c) + 1e-18) with lines dt 1 lw 2 title "|H - H_0|", \
     "" skip 1 using (\$1/T):(abs(\$10) + 1e-18) with lines dt 3 lw 2 title "|g|"
set output "docs/fig3.png"
set terminal pngcairo size 900,1100 font "sans,10"
set multiplot layout 5,1 title "Tethered satellites, HBVM(6,2), h = 0.1, 10^4 steps"
unset title
set xlabel ""
set yrange [*:*]
set logscale y
set ylabel "||hidden||"
plot "$out/satellites.csv" skip 1 using 1:(sqrt(\$27**2 + \$28**2 + \$29**2) + 1e-18) with lines notitle
set ylabel "|H - H_0|"
plot "" skip 1 using 1:(abs(\$23 - $H0s) + 1e-18) with lines notitle
set ylabel "|g_1|"
plot "" skip 1 using 1:(abs(\$24) + 1e-18) with lines notitle
set ylabel "|g_2|"
plot "" skip 1 using 1:(abs(\$25) + 1e-18) with lines notitle
set ylabel "|g_3|"
set xlabel "t"
plot "" skip 1 using 1:(abs(\$26) + 1e-18) with lines notitle
unset multiplot
GP
echo "figures: docs/fig1.png docs/fig2.png docs/fig3.png"
