/* clock.c - the core's clock while the benchmark runs, in GHz: a chain of
 * dependent integer adds (one cycle each on any x86-64 of the last decade)
 * timed in CPU time (not lost to other processes) over 2e8 adds, the median
 * of 9 runs. bench/step/run.sh turns the cycles of llvm-mca into ns with it.
 * x86-64 with gcc or clang only. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define RUNS 9
#define N 20000000L /* ten adds each */

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int main(void) {
  double ghz[RUNS];
  unsigned long x = 0;
  for (int r = 0; r < RUNS; r++) {
    double t = now();
    for (long i = 0; i < N; i++)
      __asm__ volatile("add $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\t"
                       "add $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0"
                       : "+r"(x));
    ghz[r] = 10.0 * N / (now() - t) * 1e-9;
  }
  qsort(ghz, RUNS, sizeof ghz[0], cmp);
  printf("%.3f\n", ghz[RUNS / 2]);
  return x == 0;
}
