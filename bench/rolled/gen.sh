#!/bin/sh
# bench/rolled/gen.sh - the generator's own cost on the rolled form
# (docs/rolled.md, "The generator's time and memory"): the chain of N
# pendula (models/chain8.ham with N replaced), s = 4, --multiplier const,
# --rolled on; per N the generator's CPU time (user + system, the median of
# 3 runs), its peak resident memory (GNU time's %M) and the size of NAME.c.
# Writes bench/results/rolled_gen.csv. Needs /usr/bin/time (GNU time).
# Usage: bench/rolled/gen.sh [N ...]   (default 250 500 1000 2000 4000)
set -eu
ns=${*:-250 500 1000 2000 4000}
d=build/bench/rolled
res=bench/results/rolled_gen.csv
gen=gen/hbvmgen
mkdir -p "$d"
[ -x /usr/bin/time ] || { echo "rolled/gen.sh: needs /usr/bin/time (GNU time)"; exit 1; }
echo "N,m,nu,gen_cpu_s,gen_max_rss_kb,c_bytes" > "$res"
for N in $ns; do
  sed "s/^N = 8$/N = $N/" models/chain8.ham > "$d/gchain$N.ham"
  runs=
  for rep in 1 2 3; do
    /usr/bin/time -f "%U %S %M" -o "$d/gen.time" $gen --multiplier const -s 4 --rolled on -n G -o "$d" "$d/gchain$N.ham"
    runs="$runs$(awk '{printf "%.3f %d\n", $1 + $2, $3}' "$d/gen.time")
"
  done
  cpu=$(printf '%s' "$runs" | sort -n | sed -n 2p | cut -d' ' -f1)
  rss=$(printf '%s' "$runs" | sort -n -k2 | sed -n 3p | cut -d' ' -f2)
  echo "$N,$((2 * N)),$N,$cpu,$rss,$(wc -c < "$d/G.c")" >> "$res"
  tail -1 "$res"
done
echo "rolled: wrote $res"
