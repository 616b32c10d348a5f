/* ab.c - two builds of one solver side by side: NAME_step of solver A and of
 * solver B (bench/step/run.sh generates both from one model, A with the
 * baseline generator, B with the current one, with -n A / -n B).
 *
 * One trajectory from the model's initial values, NSTEP steps of h: A and B
 * alternate REPS times (so a shared core's load hits both alike), timed in
 * the process's CPU time (time lost to other processes does not count); printed as
 * one CSV row: the medians in ns per step, their ratio B/A, sweeps per step
 * of each, max |H - H0| over the run of each, and whether the final states
 * are bitwise equal (1) or not (0). Exits 1 if a step fails. A third argument
 * times one run instead of REPS (for the drift of long runs). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "A.h"
#include "B.h"
#include "timing.h"

#define REPS 41

/* One solver's run: timed (ns per step) or counting sweeps and the drift. */
#define RUN(P, ns, sweeps, drift)                                                   \
  do {                                                                              \
    P##_state x;                                                                    \
    P##_stats st;                                                                   \
    long n, it = 0;                                                                 \
    double H0, d = 0, t;                                                            \
    P##_init(&x, NULL, NULL);                                                       \
    for (n = 0; n < P##_M; n++) x.p[n] *= pscale;                                   \
    H0 = P##_energy(&x, NULL);                                                      \
    t = cpu_seconds();                                                                      \
    for (n = 0; n < nstep && count == 0; n++) bad |= P##_step(&x, h, NULL, NULL);   \
    ns = (cpu_seconds() - t) / (double)nstep * 1e9 + 0 * dummy;                             \
    for (n = 0; n < nstep && count; n++) {                                          \
      bad |= P##_step(&x, h, NULL, &st);                                            \
      it += st.iters;                                                               \
      if (fabs(P##_energy(&x, NULL) - H0) > d) d = fabs(P##_energy(&x, NULL) - H0); \
    }                                                                               \
    sweeps = (double)it / (double)nstep;                                            \
    drift = d;                                                                      \
    memcpy(q, x.q, sizeof x.q);                                                     \
    memcpy(p, x.p, sizeof x.p);                                                     \
  } while (0)

int main(int argc, char **argv) {
  double h = argc > 1 ? atof(argv[1]) : 0.01, ta[REPS], tb[REPS], sa = 0, sb = 0, da = 0, db = 0, dummy = 0;
  long nstep = argc > 2 ? atol(argv[2]) : 1000;
  double qa[A_M], pa[A_M], qb[B_M], pb[B_M], pscale = argc > 4 ? atof(argv[4]) : 1;
  int r, bad = 0, count, reps = argc > 3 ? 1 : REPS; /* a third argument: one timed run (long runs) */
  for (r = 0, count = 0; r < reps; r++) {
    double *q = qa, *p = pa;
    RUN(A, ta[r], dummy, dummy);
    q = qb, p = pb;
    RUN(B, tb[r], dummy, dummy);
  }
  count = 1;
  {
    double *q = qa, *p = pa;
    RUN(A, dummy, sa, da);
    q = qb, p = pb;
    RUN(B, dummy, sb, db);
  }
  double ma = median(ta, reps), mb = median(tb, reps);
  printf("%.1f,%.1f,%.3f,%.3f,%.3f,%.3g,%.3g,%d\n", ma, mb, mb / ma, sa, sb, da,
         db, !memcmp(qa, qb, sizeof qa) && !memcmp(pa, pb, sizeof pa));
  if (bad) fprintf(stderr, "ab: a step failed\n");
  return bad != 0;
}
