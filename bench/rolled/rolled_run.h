/* rolled_run.h - the rolled solver B (B.h) from the model's initial state,
 * the run the IDA harnesses time (ida_chain.c, ida_cluster.c; ida_vs.h). */
#ifndef BENCH_ROLLED_RUN_H
#define BENCH_ROLLED_RUN_H

#include <string.h>

#include "B.h"

/* B from the model's initial state, n steps of h: (q, p) at the end; 0, or
 * 1 if a step failed. */
static int run_rolled(double h, long n, double *q, double *p)
{
  static B_state x;
  long k;
  int bad = 0;
  B_init(&x, NULL, NULL);
  for (k = 0; k < n; k++) bad |= B_step(&x, h, NULL, NULL);
  memcpy(q, x.q, sizeof x.q);
  memcpy(p, x.p, sizeof x.p);
  return bad != 0;
}

#endif
