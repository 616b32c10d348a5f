/* clock.c - the core's clock while the benchmark runs, in GHz: a chain of
 * dependent integer multiplies (3 cycles each on every x86-64 since Sandy
 * Bridge and Zen) timed in CPU time (not lost to other processes) over 2e8
 * of them, the median of 9 runs. bench/step/run.sh turns the cycles of
 * llvm-mca into ns with it. A chain of `add $1` is no clock: Golden Cove
 * (Sapphire Rapids) folds immediate adds at rename, 6 and more a cycle, and
 * gave 16.6 "GHz" on a 3.4 GHz core. x86-64 with gcc or clang only. */
#include <stdio.h>

#include "timing.h"

#define RUNS 9
#define N 20000000L /* ten multiplies each */

int main(void) {
  double ghz[RUNS];
  unsigned long x = 1;
  for (int r = 0; r < RUNS; r++) {
    double t = cpu_seconds();
    for (long i = 0; i < N; i++)
      __asm__ volatile("imul $3, %0, %0\n\timul $3, %0, %0\n\timul $3, %0, %0\n\timul $3, %0, %0\n\t"
                       "imul $3, %0, %0\n\timul $3, %0, %0\n\timul $3, %0, %0\n\timul $3, %0, %0\n\t"
                       "imul $3, %0, %0\n\timul $3, %0, %0"
                       : "+r"(x));
    ghz[r] = 3 * 10.0 * N / (cpu_seconds() - t) * 1e-9;
  }
  printf("%.3f\n", median(ghz, RUNS));
  return x == 0;
}
