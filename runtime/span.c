/* span.c - stepping through the span of a run to its end, hit exactly, and
 * retrying a failed fixed step with halved steps: what the driver (run.c)
 * and the ensemble runner (ensemble.c) both do, so that a trajectory of an
 * ensemble ends where a single run of it ends. */
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

/* The halves of the fixed step h from x that failed with code at depth:
 * h / 2, then the rest to where h would have ended, each a step or, when it
 * fails too, halved again, HBVMRT_HALVINGS deep (h / 256). A failed step
 * leaves the state as it was, so each retry starts from the same point.
 * Returns 0, or the code of the last failed step; *stopped is set when
 * cb->taken asked to stop (the --stop-at event). */
int hbvmrt_halve(const hbvmrt_model *md, void *x, const void *prm, double h, int code, int depth,
                 const hbvmrt_steps *cb, int *stopped)
{
  double target = hbvmrt_state_time(md, x) + h;

  if (cb->failed)
    cb->failed(cb->ctx, h, code, depth);
  if (depth >= HBVMRT_HALVINGS)
    return code;
  if ((code = hbvmrt_advance(md, x, prm, h / 2, depth + 1, cb, stopped)) != 0 || *stopped)
    return code;
  return hbvmrt_advance(md, x, prm, target - hbvmrt_state_time(md, x), depth + 1, cb, stopped);
}

/* Advance x by the fixed step h: one step, or, when it fails, its halves
 * (hbvmrt_halve), so that the run keeps its grid of fixed steps. cb->before
 * runs before each try, cb->taken after each step taken. Returns 0, or the
 * code of the last failed step. */
int hbvmrt_advance(const hbvmrt_model *md, void *x, const void *prm, double h, int depth, const hbvmrt_steps *cb,
                   int *stopped)
{
  hbvmrt_stats st;
  int code;

  memset(&st, 0, sizeof st);
  *stopped = 0;
  if (cb->before)
    cb->before(cb->ctx);
  code = md->step(x, h, prm, &st);
  if (code == 0) {
    *stopped = cb->taken(cb->ctx, &st, h);
    return 0;
  }
  return hbvmrt_halve(md, x, prm, h, code, depth, cb, stopped);
}
