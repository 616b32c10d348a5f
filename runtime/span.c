/* span.c - stepping through the span of a run to its end, hit exactly, and
 * retrying a failed fixed step with halved steps: what the driver (run.c)
 * and the ensemble runner (ensemble.c) both do, so that a trajectory of an
 * ensemble ends where a single run of it ends. */
#include <float.h>
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
  return o->t0 + (o->h < 0 ? -o->T : o->T);
}

int hbvmrt_set_time(const hbvmrt_model *md, void *x, double t)
{
  if (md->set_time)
    md->set_time(x, t);
  else if (md->eps == DBL_EPSILON)  /* a double state: t is the double at off_t */
    memcpy((char *)x + md->off_t, &t, sizeof t);
  else
    return -1;
  return 0;
}

double hbvmrt_step_tol(const hbvmrt_model *md, const hbvmrt_opts *o, const void *x)
{
  double sc = 0, q;
  int i;

  if (!(o->atol > 0 || o->rtol > 0))
    return o->tol;
  for (i = 0; i < md->m; i++) {
    memcpy(&q, (const char *)x + md->off_q + (size_t)i * sizeof q, sizeof q);
    if (fabs(q) > sc)
      sc = fabs(q);
  }
  return (o->atol + o->rtol * sc) / (1 + sc);
}

/* The number N of steps of |h| over the span T: the least N with N |h| >= T
 * up to a sliver of 1e-9 |h| + 8 eps T, so that the last step, T - (N-1)
 * |h|, is neither 0 nor a sliver (-h 0.1 -T 1 is 10 steps, though 10 times
 * 0.1 is not 1 in binary). The 8 eps T is the rounding of T and of N times
 * h, which T/|h| = 26214403 in decimals leaves (-h 0.01 -T 262144.03: 2.4e-11
 * over 26214403 steps of the double 0.01). ceil(T/|h| - 1e-9) is the first
 * guess; it is corrected with the residual T - n |h| rounded once (fma),
 * since past 2^24 steps the quotient's own rounding exceeds the 1e-9 (that
 * run gave 26214404 steps, the last one 0). -1 from 2^53 steps on, where n
 * is no longer a double exactly. */
long hbvmrt_span_steps(double T, double h)
{
  double a = fabs(h), sliver = 1e-9 * a + 8 * DBL_EPSILON * T, n = ceil(T / a - 1e-9);

  if (!(T > 0))
    return 0;
  if (n < 1)
    n = 1;
  if (!(n < 9007199254740992.0))
    return -1;
  while (fma(-n, a, T) > sliver)
    n++;
  while (n > 1 && fma(-(n - 1), a, T) <= sliver)
    n--;
  return (long)n;
}

/* The state's t ends within a few ulps of the span's end T (its last step
 * T - t is added to t with the compensation the step carries, and halves
 * add theirs): it is set to T, which the run meant, so that the last row
 * and an ensemble's summary say T (7.6999999999999993 at -h 2.1 -T 7.7). */
void hbvmrt_span_land(const hbvmrt_model *md, const hbvmrt_opts *o, void *x)
{
  double end = hbvmrt_span_end(o), t = hbvmrt_state_time(md, x), eps = md->eps > 0 ? md->eps : DBL_EPSILON;

  if (o->to_T && t != end && fabs(t - end) <= 8 * eps * fabs(end))
    memcpy((char *)x + md->off_t, &end, sizeof end);
}

/* Step n of the N of a fixed-step run (1 <= n <= N) from the state x: h,
 * or, for the last step of a span (-T), the rest of the span, so that the
 * run ends on T exactly (-h 0.3 -T 100: 333 steps of 0.3 and one of 0.1). */
double hbvmrt_fixed_step(const hbvmrt_model *md, const hbvmrt_opts *o, long n, const void *x)
{
  return n == o->nsteps && o->to_T ? hbvmrt_span_end(o) - hbvmrt_state_time(md, x) : o->h;
}

/* One adaptive step (NAME_step_adaptive at hbvmrt_step_tol) toward the
 * span's end t_end from x, of at most *h and --hmax: a step that would pass
 * t_end is shortened to end on it, and so is one within 1e-12 of it, so that
 * no sliver of a step is left. Returns the step's code; on success *h is the
 * next step the controller proposes (kept as it was after the last step,
 * whose size says nothing) and *at_end is 1 when x is now on t_end. */
int hbvmrt_adaptive_step(const hbvmrt_model *md, const hbvmrt_opts *o, void *x, double *h, const void *prm,
                         hbvmrt_stats *st, int *at_end)
{
  double t_end = hbvmrt_span_end(o), rest = t_end - hbvmrt_state_time(md, x), hn;
  int last, code;

  if (o->hmax > 0 && fabs(*h) > o->hmax)
    *h = *h < 0 ? -o->hmax : o->hmax;
  hn = *h;
  last = fabs(hn) >= fabs(rest) * (1 - 1e-12);
  memset(st, 0, sizeof *st);
  if (last)
    hn = rest;
  code = md->step_adaptive(x, &hn, hbvmrt_step_tol(md, o, x), prm, st);
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
