/* span.c - stepping through the span of a run to its end, hit exactly: what
 * the driver (run.c) and the ensemble runner (ensemble.c) both do, so that a
 * trajectory of an ensemble ends where a single run of it ends. */
#include <math.h>
#include <string.h>

#include "hbvmrt_internal.h"

double hbvmrt_state_time(const hbvmrt_model *md, const void *x)
{
  double t;

  memcpy(&t, (const char *)x + md->off_t, sizeof t);
  return t;
}

double hbvmrt_span_end(const hbvmrt_opts *o)
{
  return o->h < 0 ? -o->T : o->T;
}

/* Step n of the N of a fixed-step run (1 <= n <= N) from the state x: h,
 * or, for the last step of a span (-T), the rest of the span, so that the
 * run ends on T exactly (-h 0.3 -T 100: 333 steps of 0.3 and one of 0.1). */
double hbvmrt_fixed_step(const hbvmrt_model *md, const hbvmrt_opts *o, long n, const void *x)
{
  return n == o->nsteps && o->to_T ? hbvmrt_span_end(o) - hbvmrt_state_time(md, x) : o->h;
}

/* One adaptive step (NAME_step_adaptive at tol) toward t_end from x, of at
 * most *h: a step that would pass t_end is shortened to end on it, and so is
 * one within 1e-12 of it, so that no sliver of a step is left. Returns the
 * step's code; on success *h is the next step the controller proposes (kept
 * as it was after the last step, whose size says nothing) and *at_end is 1
 * when x is now on t_end. */
int hbvmrt_adaptive_step(const hbvmrt_model *md, void *x, double *h, double t_end, double tol, const void *prm,
                         hbvmrt_stats *st, int *at_end)
{
  double rest = t_end - hbvmrt_state_time(md, x), hn = *h;
  int last = fabs(hn) >= fabs(rest) * (1 - 1e-12), code;

  memset(st, 0, sizeof *st);
  if (last)
    hn = rest;
  code = md->step_adaptive(x, &hn, tol, prm, st);
  *at_end = code == 0 && last && st->h == rest;
  if (code == 0 && !*at_end)
    *h = hn;
  return code;
}
