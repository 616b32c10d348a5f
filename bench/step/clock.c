/* clock.c - the core's clock while the benchmark runs, in GHz: a chain of
 * dependent integer adds (one cycle each on any x86-64 of the last decade)
 * timed in CPU time (not lost to other processes) over 2e8 adds, the median
 * of 9 runs. bench/step/run.sh turns the cycles of llvm-mca into ns with it.
 * x86-64 with gcc or clang only. */
#include <stdio.h>

#include "timing.h"

#define RUNS 9
#define N 20000000L /* ten adds each */

int main(void) {
  double ghz[RUNS];
  unsigned long x = 0;
  for (int r = 0; r < RUNS; r++) {
    double t = cpu_seconds();
    for (long i = 0; i < N; i++)
      __asm__ volatile("add $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\t"
                       "add $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0"
                       : "+r"(x));
    ghz[r] = 10.0 * N / (cpu_seconds() - t) * 1e-9;
  }
  printf("%.3f\n", median(ghz, RUNS));
  return x == 0;
}
