#!/bin/sh
# bench/mq/fourbar.sh - the four-bar linkage in its angles (M(q), two
# constraints) against its natural coordinates (constant M, three
# constraints), HBVM(s,s) for s = 2, 3, 4, fixed steps, at equal error
# (bench/mq/fourbar.c). Writes bench/results/mq_fourbar.csv. Run from the
# repository's root after `make all`: sh bench/mq/fourbar.sh
. bench/mq/solvers.sh
for s in 2 3 4; do
  for form in 0 1; do
    model=models/fourbar_angles.ham name=fba_s$s
    [ $form = 1 ] && model=bench/mq/fourbar_cartesian.ham name=fbn_s$s
    $G "$model" -k $s -s $s -n $name -o "$dir" >/dev/null
    echo "S($name, $form, $s)" >>"$dir/solvers.def"
    echo "#include \"$name.h\"" >>"$dir/solvers.h"
  done
done
srcs=$(solver_sources)
nice -n 5 gcc -std=c99 -Wall -Wextra -pedantic -O2 -I"$dir" -Ibench/mq -o "$dir/fourbar" bench/mq/fourbar.c $srcs \
  $(pkg-config --libs gsl) -lm
"$dir/fourbar" | tee bench/results/mq_fourbar.csv
