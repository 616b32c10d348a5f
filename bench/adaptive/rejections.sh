#!/bin/sh
# bench/adaptive/rejections.sh - the tries NAME_step_adaptive rejects (issue
# 31, item 3: under 5% wanted), the table of docs/api.md, "Adaptive steps":
# per problem and tol 1e-6, 1e-8, 1e-10, 1e-12 the driver's steps and
# steps_rejected from -h 0.01, and the rejected share of the tries, with the
# generator of this tree. Problems: bench/adaptive/run.sh's (T = 10, chain8
# 5), Kepler e = 0.6 over ten periods at (11,6), (18,3), (4,4), the outer
# solar system over 20000 days at (16,2) and (11,6), a four-bar linkage
# (bench/adaptive/fourbar.ham) and a heavy top (tests/models/top.ham) at
# (3,3); the double pendulum in angles (M(q), bench/mq's adaptive lines: k = s
# at s = 3..8 and (11,6)) and the pendulum in its angle (k = s, s = 2..6, and
# (18,3)) to T = 10, and the stiff FPU chain (4,2). TOLS="..." measures other
# tolerances (default 1e-4 .. 1e-12, half a decade apart); GEN=... another
# generator (into build/rejections-NAME, NAME its directory's name). Prints a
# line per run and writes bench/results/rejections.csv (OUT=... another file)
# and, with bench/adaptive/rejections.awk, bench/results/rejections.txt. The
# CSV's error is the run's at T (max over q and p) against the same solver at
# tol 1e-14, for bench/adaptive/equal_error.awk (two such files: the tries at
# equal error).
set -eu
cd "$(dirname "$0")/../.."
GEN=${GEN:-gen/hbvmgen}
B=build/rejections
[ "$GEN" = gen/hbvmgen ] || B=build/rejections-$(basename "$(dirname "$GEN")")
OUT=${OUT:-bench/results/rejections.csv}
[ -x "$GEN" ] || make --no-print-directory all
TOLS=${TOLS:-"1e-4 3e-5 1e-5 3e-6 1e-6 3e-7 1e-7 3e-8 1e-8 3e-9 1e-9 3e-10 1e-10 3e-11 1e-11 3e-12 1e-12"}
mkdir -p "$B"
echo "name,tol,steps,rejected,percent,error" >"$OUT"
ROW=$B/row.csv
# the q and p of the last row of the driver's CSV (not t, lambda, H, g, hc), a line
last_qp() {
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) keep[i] = $i !~ /^(t|H|lambda_.*|g_.*|hc_.*)$/; next }
    { last = $0 } END { n = split(last, v, ","); s = ""; for (i = 1; i <= n; i++) if (keep[i]) s = s " " v[i]; print s }' "$1"
}
# name model k s T
while read -r n m k s T; do
  if [ -z "$(find "$B/$n" -newer "$GEN" 2>/dev/null)" ]; then # built by an older generator, or not at all
    "$GEN" --main -o "$B" -n "$n" -k "$k" -s "$s" "$m" 2>/dev/null
    cc -O2 -std=c99 -Iruntime -I"$B" "$B/$n.c" "$B/${n}_main.c" runtime/libhbvmrt.a -lm -o "$B/$n"
  fi
  "$B/$n" -h 0.01 -T "$T" --tol 1e-14 --every 100000000 --quiet --csv "$ROW" 2>/dev/null || : >"$ROW"
  ref=$(last_qp "$ROW")
  for tol in $TOLS; do
    sum=$("$B/$n" -h 0.01 -T "$T" --tol "$tol" --every 100000000 --quiet --csv "$ROW" 2>&1 >/dev/null)
    echo "$sum" | sed -n 's/.*steps=\([0-9]*\) .*steps_rejected=\([0-9]*\).*/\1 \2/p' |
      awk -v n="$n" -v tol="$tol" -v out="$OUT" -v ref="$ref" -v row="$(last_qp "$ROW")" '{
        e = 0; nr = split(ref, a, " "); split(row, b, " ")
        for (i = 1; i <= nr; i++) if ((d = a[i] - b[i]) * (d < 0 ? -1 : 1) > e) e = d < 0 ? -d : d
        printf "%-18s tol %-6s steps %6d rejected %5d  %5.1f%%  error %.3g\n", n, tol, $1, $2, 100 * $2 / ($1 + $2), e
        printf "%s,%s,%d,%d,%.2f,%.6g\n", n, tol, $1, $2, 100 * $2 / ($1 + $2), e >>out }'
  done
done <<LIST
pendulum_k4s4 models/pendulum.ham 4 4 10
conical_k4s4 models/conical.ham 4 4 10
modified_k12s4 models/modified.ham 12 4 10
satellites_k4s4 models/satellites.ham 4 4 10
double_pendulum_k4s4 models/double_pendulum.ham 4 4 10
chain8_k4s4 models/chain8.ham 4 4 5
kepler_k11s6 models/kepler.ham 11 6 62.83185307179586
kepler_k18s3 models/kepler.ham 18 3 62.83185307179586
kepler_k4s4 models/kepler.ham 4 4 62.83185307179586
solar_k16s2 models/solar.ham 16 2 20000
solar_k11s6 models/solar.ham 11 6 20000
fourbar_k3s3 bench/adaptive/fourbar.ham 3 3 10
top_k3s3 tests/models/top.ham 3 3 10
fpu_k4s2 models/fpu.ham 4 2 10
dpa_k3s3 models/double_pendulum_angles.ham 3 3 10
dpa_k4s4 models/double_pendulum_angles.ham 4 4 10
dpa_k5s5 models/double_pendulum_angles.ham 5 5 10
dpa_k6s6 models/double_pendulum_angles.ham 6 6 10
dpa_k7s7 models/double_pendulum_angles.ham 7 7 10
dpa_k8s8 models/double_pendulum_angles.ham 8 8 10
dpa_k11s6 models/double_pendulum_angles.ham 11 6 10
pa_k2s2 models/pendulum_angle.ham 2 2 10
pa_k3s3 models/pendulum_angle.ham 3 3 10
pa_k4s4 models/pendulum_angle.ham 4 4 10
pa_k6s6 models/pendulum_angle.ham 6 6 10
pa_k18s3 models/pendulum_angle.ham 18 3 10
LIST
awk -F, -f bench/adaptive/rejections.awk "$OUT" >"${OUT%.csv}.txt"
