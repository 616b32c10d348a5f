/* hot.c - NSTEP steps of solver B from its model's initial values, as
 * bench/step/ab.c times them (no statistics); with a third argument the
 * same steps with statistics, printing the sweeps they took. The first is
 * the run whose per-instruction counts (callgrind) pick the iteration's hot
 * path for llvm-mca (bench/step/run.sh). */
#include <stdio.h>
#include <stdlib.h>

#include "B.h"

int main(int argc, char **argv) {
  double h = argc > 1 ? atof(argv[1]) : 0.01;
  long n, nstep = argc > 2 ? atol(argv[2]) : 1000, sweeps = 0;
  B_state x;
  B_stats st;
  B_init(&x, NULL, NULL);
  for (n = 0; n < nstep; n++) {
    if (B_step(&x, h, NULL, argc > 3 ? &st : NULL)) return 1;
    if (argc > 3) sweeps += st.iters;
  }
  if (argc > 3) printf("%ld\n", sweeps);
  return 0;
}
