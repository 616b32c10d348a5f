/* switch.c - the model's switching functions inside the driver's steps
 * (docs/api.md, "Kinks and jumps"; off with --no-switch).
 *
 * Where U or g is not smooth (abs, sign, min, max, floor, mod: hbvmgen
 * emits the arguments as NAME_switch), a step that crosses the point
 * integrates a function that is not smooth over the step: its error is of
 * low order whatever s is, the local error estimate, which assumes
 * smoothness, does not see it (issue 31: a polymer on a wall ended 1e4 to
 * 1e6 times above --tol), and where the force jumps the iteration of a step
 * across it may not converge at any h (a hard wall with the constant
 * multiplier stopped at its first contact). So each step ends on the first
 * such point inside it, and the next step starts afresh there
 * (NAME_restart: no warm start from the far side, the controller's history
 * forgotten); the rest of a fixed step follows.
 *
 * Each function keeps the side of its point it is on (for floor, its
 * integer cell): a value beyond it at a step's end is a crossing inside the
 * step. hbvmrt_switch_find searches the step [0, h] from its start x0 with
 * steps of the method of theta h: one that converges and crosses no point
 * is short of it (lower end), one that crosses a point or does not converge
 * is past it (upper end); Illinois regula falsi on the function crossed once
 * the upper end has values, halving before, until the bracket is below
 * HBVMRT_SWITCH_TOL (1 + |t|) in t. The state is then that of the upper end
 * (all its stages on the near side: a step of a smooth problem, whose force
 * at the end is the far side's, so that the next step's estimate is right),
 * and every function beyond its point there flips side. Adaptive steps
 * (hbvmrt_switch_adaptive) search before the step where the last step's
 * polynomials carried on predict a point inside it, and after a step that
 * crossed one or failed; a step to the point whose error estimate is above
 * the tolerance is undone for a step half as long. Two crossings of one
 * function inside one step cancel and are not seen. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmrt_internal.h"

#define HBVMRT_SWITCH_TOL 1e-13    /* the points are located to this relative in t (1 + |t|) */
#define SEARCH_ITERS 200           /* steps of one search at most */
#define NEAR_FACTOR 1e-6           /* a point found where no step converges: some function this much nearer
                                    * its point than at the start, else the failure is not a kink's */

int hbvmrt_switch_open(hbvmrt_switch *sw, const hbvmrt_model *md, const hbvmrt_switching *fn,
                       const hbvmrt_opts *o, const void *prm, const void *x)
{
  int n = fn ? fn->n + 1 : 1, i;

  memset(sw, 0, sizeof *sw);
  if (!fn || fn->n <= 0 || !fn->values || o->no_switch)
    return 0;
  sw->md = md;
  sw->fn = fn;
  sw->prm = prm;
  sw->v0 = calloc(2 * (size_t)n, sizeof *sw->v0);   /* (and the sides kept by find_within) */
  sw->v1 = calloc((size_t)n, sizeof *sw->v1);
  sw->side = calloc((size_t)n, sizeof *sw->side);
  for (i = 0; i < 4; i++)
    sw->z[i] = calloc(1, md->state_size + 1);
  if (!sw->v0 || !sw->v1 || !sw->side || !sw->z[0] || !sw->z[1] || !sw->z[2] || !sw->z[3]) {
    hbvmrt_error(md, "out of memory");
    return -1;
  }
  sw->fn->values(x, prm, sw->v1);
  for (i = 0; i < sw->fn->n; i++)
    sw->side[i] = sw->fn->kinds[i] == 1 ? floor(sw->v1[i]) : sw->v1[i] > 0 ? 1 : sw->v1[i] < 0 ? -1 : 0;
  return 0;
}

/* The value of function i relative to the point it would cross next from
 * its side: for a sign change the value itself, of the side's sign; for
 * floor the distance to the nearer end of its cell, positive inside. */
static double to_point(const hbvmrt_switch *sw, int i, double v)
{
  double s = sw->side[i];

  if (sw->fn->kinds[i] == 1)
    return v - s < s + 1 - v ? v - s : s + 1 - v;
  return s == 0 ? fabs(v) : s * v;
}

/* The first function (by index) whose value in v is beyond its point, -1 if
 * none; a function on its point at the start (side 0) takes the side of v. */
static int first_crossed(hbvmrt_switch *sw, const double *v)
{
  int i;

  for (i = 0; i < sw->fn->n; i++) {
    if (sw->fn->kinds[i] != 1 && sw->side[i] == 0)
      sw->side[i] = v[i] > 0 ? 1 : v[i] < 0 ? -1 : 0;
    if (to_point(sw, i, v[i]) < 0)
      return i;
  }
  return -1;
}

/* The point function i of value v (beyond it) crossed: *level, and *dir
 * 1 when it crossed downwards (its value above the level before), -1
 * upwards; for floor the end of its cell that v is past. */
static void crossing(const hbvmrt_switch *sw, int i, double v, double *level, double *dir)
{
  double s = sw->side[i];

  if (sw->fn->kinds[i] == 1) {
    *level = v >= s + 1 ? s + 1 : s;
    *dir = v >= s + 1 ? -1 : 1;
  } else {
    *level = 0;
    *dir = s;
  }
}

/* A step of theta h from x0 into z: 0 and the values in v, or its code. */
static int probe(hbvmrt_switch *sw, const void *x0, double h, double theta, void *z, double *v, hbvmrt_stats *st)
{
  const hbvmrt_model *md = sw->md;
  int code;

  memcpy(z, x0, md->state_size);
  memset(st, 0, sizeof *st);
  code = md->step(z, theta * h, sw->prm, st);
  if (code == 0)
    sw->fn->values(z, sw->prm, v);
  return code;
}

/* The function nearest its point at the state of values v1, if it is at
 * least NEAR_FACTOR nearer than at the start (values v0); -1 if none. */
static int nearest(const hbvmrt_switch *sw, const double *v0, const double *v1)
{
  int i, best = -1;

  for (i = 0; i < sw->fn->n; i++)
    if (fabs(to_point(sw, i, v1[i])) <= NEAR_FACTOR * fabs(to_point(sw, i, v0[i])) &&
        (best < 0 || fabs(to_point(sw, i, v1[i])) < fabs(to_point(sw, best, v1[best]))))
      best = i;
  return best;
}

/* Every function whose value in v is beyond its point takes the side of v
 * (for floor its cell), a point crossed. */
static void flip_crossed(hbvmrt_switch *sw, const double *v)
{
  int i;

  for (i = 0; i < sw->fn->n; i++)
    if (to_point(sw, i, v[i]) < 0) {
      sw->side[i] = sw->fn->kinds[i] == 1 ? floor(v[i]) : v[i] > 0 ? 1 : -1;
      sw->crossed++;
    }
}

/* The search ended on a point: x the state z, st its figures (a step of
 * h); the next step restarts. Returns 1. */
static int ended(hbvmrt_switch *sw, void *x, const void *z, const hbvmrt_stats *sz, double h, hbvmrt_stats *st)
{
  memcpy(x, z, sw->md->state_size);
  *st = *sz;
  st->h = h;
  sw->cut = 1;
  sw->pending = 1;
  return 1;
}

int hbvmrt_switch_find(hbvmrt_switch *sw, const void *x0, void *x, double h, double guess, hbvmrt_stats *st)
{
  const hbvmrt_model *md = sw->md;
  double t0 = hbvmrt_state_time(md, x0), tol = HBVMRT_SWITCH_TOL * (1 + fabs(t0)) / fabs(h);
  double lo = 0, hi = 1, flo = 0, fhi = 0, c = 1, level = 0, dir = 1;
  int target = -1, have_hi = 0, stuck = 0, it, code, first_code = 0, i;
  hbvmrt_stats s, slo, shi;
  void *zlo = sw->z[0], *zc = sw->z[1], *zhi = sw->z[2], *t;

  sw->cut = 0;
  memset(&slo, 0, sizeof slo);
  memcpy(zlo, x0, md->state_size);
  for (it = 0; it < SEARCH_ITERS && (it == 0 || hi - lo > tol); it++) {
    if (it > 0) {   /* Illinois on the target once both ends have values, else halves (first the guess) */
      c = have_hi ? (lo * fhi - hi * flo) / (fhi - flo) : it == 1 && guess > lo && guess < hi ? guess : 0.5 * (lo + hi);
      if (!(c > lo && c < hi))
        c = 0.5 * (lo + hi);
    }
    code = probe(sw, x0, h, c, zc, sw->v1, &s);
    i = code == 0 ? first_crossed(sw, sw->v1) : -1;
    if (it == 0 && code == 0 && i < 0) {
      memcpy(x, zc, md->state_size);   /* no point inside the step: it stands */
      *st = s;
      st->h = h;
      return 0;
    }
    if (it == 0)
      first_code = code;
    if (code != 0 || i >= 0) {   /* beyond the (first) point: the upper end */
      if (code == 0 && i != target) {   /* a new target: its gap at lo */
        target = i;
        stuck = 0;
        crossing(sw, i, sw->v1[i], &level, &dir);
        sw->fn->values(zlo, sw->prm, sw->v0);
        flo = dir * (sw->v0[i] - level);
      }
      hi = c;
      have_hi = code == 0;
      fhi = code == 0 ? dir * (sw->v1[i] - level) : 0;
      if (have_hi) {
        t = zhi, zhi = zc, zc = t;
        shi = s;
      }
      if (stuck == -1)
        flo /= 2;
      stuck = -1;
    } else {   /* short of every point: the lower end */
      lo = c;
      flo = target >= 0 ? dir * (sw->v1[target] - level) : 0;
      t = zlo, zlo = zc, zc = t;
      slo = s;
      if (stuck == 1)
        fhi /= 2;
      stuck = 1;
    }
  }
  if (have_hi && lo > 0) {   /* the state just past the point, whose force is that of the far side */
    sw->fn->values(zhi, sw->prm, sw->v1);
    flip_crossed(sw, sw->v1);
    return ended(sw, x, zhi, &shi, hi * h, st);
  }
  /* no step past the point converged: the state at lo, short of it by
   * less than tol, if some function is on its point there (at least
   * NEAR_FACTOR nearer than at x0) */
  sw->fn->values(zlo, sw->prm, sw->v1);
  sw->fn->values(x0, sw->prm, sw->v0);
  target = lo > 0 ? nearest(sw, sw->v0, sw->v1) : -1;
  if (target < 0)
    return first_code != 0 ? first_code : -1;
  if (sw->fn->kinds[target] == 1)   /* to the cell beyond the nearer end */
    sw->side[target] += sw->side[target] + 1 - sw->v1[target] < sw->v1[target] - sw->side[target] ? 1 : -1;
  else
    sw->side[target] = -sw->side[target];
  sw->crossed++;
  return ended(sw, x, zlo, &slo, lo * h, st);
}

int hbvmrt_switch_predicted(hbvmrt_switch *sw, const void *x, double h, double *guess)
{
  const hbvmrt_model *md = sw->md;
  double t = hbvmrt_state_time(md, x), hprev;
  int k;

  md->dense(x, 0, sw->z[2]);
  hprev = t - hbvmrt_state_time(md, sw->z[2]);
  if (!(hprev != 0 && isfinite(hprev)))
    return 0;
  for (k = 1; k <= 4; k++) {   /* the last step's polynomials carried on over the next */
    md->dense(x, 1 + 0.25 * k * h / hprev, sw->z[2]);
    sw->fn->values(sw->z[2], sw->prm, sw->v1);
    for (int i = 0; i < sw->fn->n; i++)
      if (to_point(sw, i, sw->v1[i]) < 0) {
        *guess = 0.25 * k;
        return 1;
      }
  }
  return 0;
}

/* The largest |q| of the state x. */
static double max_q(const hbvmrt_model *md, const void *x)
{
  const double *q = (const double *)(const void *)((const char *)x + md->off_q);
  double m = 0;
  int i;

  for (i = 0; i < md->m; i++)
    if (fabs(q[i]) > m)
      m = fabs(q[i]);
  return m;
}

/* hbvmrt_switch_find, undone (x, the sides as they were) when the step to
 * the point is not within the adaptive step's tolerance, 0.01 tol |h|
 * (1 + max|q|) (docs/api.md, --tol): 2 then, st->h the step to the point. */
static int find_within(hbvmrt_switch *sw, const void *x0, void *x, double h, double guess, double tol,
                       hbvmrt_stats *st)
{
  const hbvmrt_model *md = sw->md;
  long crossed = sw->crossed;
  int found;

  memcpy(sw->v0 + sw->fn->n + 1, sw->side, (size_t)sw->fn->n * sizeof *sw->side);
  found = hbvmrt_switch_find(sw, x0, x, h, guess, st);
  if (found != 1 || st->err_est <= 0.01 * tol * fabs(st->h) * (1 + max_q(md, x)))
    return found;
  memcpy(sw->side, sw->v0 + sw->fn->n + 1, (size_t)sw->fn->n * sizeof *sw->side);
  sw->crossed = crossed;
  sw->cut = sw->pending = 0;
  memcpy(x, x0, md->state_size);
  return 2;
}

int hbvmrt_switch_adaptive(hbvmrt_switch *sw, const hbvmrt_opts *o, const void *x0, void *x, double *h,
                           hbvmrt_stats *st, int *at_end)
{
  const hbvmrt_model *md = sw->md;
  double rest = hbvmrt_span_end(o) - hbvmrt_state_time(md, x0), tol = hbvmrt_step_tol(md, o, x0), guess;
  double hmax = o->hmax > 0 ? copysign(o->hmax, *h) : 0;   /* --hmax, then halves of a step too long */
  int code = 0, found, attempt;

  for (attempt = 0; attempt < 8; attempt++) {
    double hs = hmax != 0 && fabs(hmax) < fabs(*h) ? hmax : *h, H = fabs(hs) >= fabs(rest) * (1 - 1e-12) ? rest : hs;
    *at_end = 0;
    memcpy(x, x0, md->state_size);
    found = hbvmrt_switch_predicted(sw, x0, H, &guess) ? find_within(sw, x0, x, H, guess, tol, st) : -1;
    if (found == 0 || found < 0)
      memcpy(x, x0, md->state_size);   /* no point after all: the step with error control */
    if (found < 1 && (code = hbvmrt_adaptive_step(md, o, x, &hs, sw->prm, st, at_end)) == 0) {
      sw->fn->values(x, sw->prm, sw->v1);
      if (first_crossed(sw, sw->v1) < 0) {
        *h = hs;
        return 0;
      }
      memcpy(sw->z[3], x, md->state_size);   /* crossed: the step ends on the point instead */
      found = find_within(sw, x0, x, st->h, -1, tol, st);
      if (found < 0 || found == 0) {   /* (not located: the step across stands, the sides beyond it) */
        memcpy(x, sw->z[3], md->state_size);
        sw->fn->values(x, sw->prm, sw->v1);
        flip_crossed(sw, sw->v1);
        *h = hs;
        return 0;
      }
    } else if (found < 1) {
      found = find_within(sw, x0, x, H, -1, tol, st);   /* failed: at a point? */
    }
    if (found == 1)
      return 0;
    if (found != 2)
      return code != 0 ? code : -1;
    hmax = 0.5 * st->h;   /* the step to the point is too long: a step halfway first */
  }
  return code != 0 ? code : 1;
}

void hbvmrt_switch_before(hbvmrt_switch *sw, void *x)
{
  if (sw->md && sw->pending && sw->fn->restart)
    sw->fn->restart(x);
  sw->pending = 0;
}

void hbvmrt_switch_close(hbvmrt_switch *sw)
{
  int i;

  free(sw->v0);
  free(sw->v1);
  free(sw->side);
  for (i = 0; i < 4; i++)
    free(sw->z[i]);
  memset(sw, 0, sizeof *sw);
}
