#!/bin/sh
# Is k = 2s + 12 (-k auto for a non-polynomial U or g) enough? For each
# non-polynomial model and s = 1..3, sweep h up to where the fixed point stops
# converging and record max |H - H0| over a fixed time, for that k and for
# smaller k, in units of the energy's ulp. Writes bench/results/kauto.csv.
set -eu
out=build/kauto
res=bench/results
mkdir -p "$out" "$res"
csv=$res/kauto.csv
echo "model,s,k,is_auto,h,steps,iters_per_step,max_dH,max_dH_ulps" > "$csv"
# model:T (time span) ; H0 scale for ulps is |H0|
for spec in kepler:62.83185307179586 satellites:10 pendulum_angle:20; do
  model=${spec%%:*}; T=${spec#*:}
  for s in 1 2 3; do
    auto=$((2 * s + 12))
    for k in $(printf '%s\n' "$s" $((2 * s)) 6 8 10 12 "$auto" | sort -nu); do
      # the rule is const's (poly's energy rescale holds H at any k)
      p="ka_${model}_k${k}s${s}const"
      [ -f "$out/$p" ] || {
        gen/hbvmgen --multiplier const -k "$k" -s "$s" -n "$p" -o "$out" "models/$model.ham"
        cc -O2 -std=c99 -DP="$p" -include "$out/$p.h" -I"$out" -o "$out/$p" "$out/$p.c" bench/lean/steps.c -lm
      }
      for n in 10 20 40 80 160 320 640 1280; do
        h=$(awk -v T="$T" -v n="$n" 'BEGIN { printf "%.17g", T / n }')
        r=$("$out/$p" "$n" "$h" energy 2>/dev/null) || continue
        H0=$(case $model in kepler) echo 0.5 ;; satellites) echo 0.1 ;; *) echo 1 ;; esac)
        echo "$model,$s,$k,$([ "$k" = "$auto" ] && echo 1 || echo 0),$h,$n,$(echo "$r" | cut -d' ' -f1),$(echo "$r" | cut -d' ' -f2),$(echo "$r" | awk -v H0="$H0" '{ printf "%.1f", $2 / (H0 * 2.220446049250313e-16) }')" >> "$csv"
      done
    done
  done
done
echo "kauto: wrote $csv"
