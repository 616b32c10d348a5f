/* sweep.h - one work-precision line: a method on a problem over a range of
 * step sizes (fixed-step methods) or tolerances (adaptive ones). */
#ifndef BENCH_SWEEP_H
#define BENCH_SWEEP_H

#include <stdio.h>

#include "bench.h"

typedef struct {
  const Problem *pb;
  const MethodDef *md;
  int k, s;                           /* HBVM only */
  double qref[BENCH_MAXM], pref[BENCH_MAXM]; /* the reference at T */
  double T;
  double from, to, factor; /* h (or tol) from `from` down to `to`, divided by factor */
  double cap;              /* stop refining once one run takes longer (CPU seconds) */
  double floor;            /* stop refining once err_q is below */
  int keep_going;          /* no stop at an error grown 4x (the stiff lines: not round-off there) */
  double min_seconds;      /* of one timed repeat */
  int repeats;             /* timed repeats; the median is reported */
  FILE *wp, *iters, *overhead; /* work_precision.csv, iterations.csv, overhead.csv */
} Sweep;

/* The CSV headers, written when a file is empty. */
extern const char *const sweep_wp_header, *const sweep_iters_header, *const sweep_overhead_header;

/* Run the sweep, appending a row per point. 0, -1 if the method does not
 * apply to the problem (nothing written), -2 if no point succeeded. */
int sweep_run(const Sweep *sw);

/* CPU nanoseconds of one evaluation of grad U and of grad g (problems.c):
 * the unit of the overhead ratio. */
double gradient_ns(const Problem *pb, double min_seconds, int repeats);

#endif
