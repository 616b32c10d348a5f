/* lanes.h - what the batch benchmarks (throughput.c, adaptive.c) share: the
 * solver's names from -DP=prefix (F(_step) is prefix_step), NT trajectories
 * and their initial values, timed REPS times, the clock and the comparison
 * for the medians. */
#ifndef BENCH_BATCH_LANES_H
#define BENCH_BATCH_LANES_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include HDR

#define CAT2(a, b) a##b
#define CAT(a, b) CAT2(a, b)
#define F(name) CAT(P, name)
#define NT 8
#define REPS 9

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The NT trajectories: the model's initial values, momenta scaled by
 * 1 + j / 1000 for trajectory j (close ones, as a narrow sweep). */
static void initial_states(F(_state) *s0) {
  int j, l;
  for (j = 0; j < NT; j++) {
    F(_init)(&s0[j], NULL, NULL);
    for (l = 0; l < F(_M); l++) s0[j].p[l] *= 1 + j / 1000.0;
  }
}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

#endif
