/* events.c - the model's events inside the driver's steps (--events,
 * --stop-at).
 *
 * After every step from x0 to x the event functions are compared at both
 * ends: an event whose sign changes (in its direction: rising from < 0 to
 * >= 0, falling from > 0 to <= 0, or either) occurred inside the step; a
 * value exactly 0 at the start is not a change, so an event is found once,
 * and one exactly 0 at the end is found there (theta = 1), either way.
 * An event whose value is not a number has no sign to compare: the run
 * stops there with an error rather than miss a crossing next to it.
 * Two changes inside one step cancel and are not seen: the step must be
 * shorter than the time between two occurrences.
 *
 * Each occurrence is located in two stages.
 *   1. On the dense output (NAME_dense, order s+1): the Illinois variant of
 *      regula falsi on theta in [0, 1] until the bracket is below
 *      HBVMRT_EVENT_TOL relative in t (1e-12 asked, 1e-13 kept).
 *   2. The dense output's own error (order s+1) would then limit the time
 *      to about its local error, far above the method's accuracy at the
 *      step points (order 2s). So the root is polished with real steps of
 *      the method: from a copy of x0, a step of theta h, Newton's iteration
 *      on theta with the slope from the dense output, until the correction
 *      is below HBVMRT_EVENT_TOL. The event's state is that step's result,
 *      exactly a state of the method, which --stop-at continues from.
 * The rows are written in time order, several per step when several events
 * occurred in it. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmrt_internal.h"

/* The roots are located to this relative in t (1 + |t|). */
#define HBVMRT_EVENT_TOL 1e-13
#define POLISH_ITERS 6     /* Newton steps of the polish at most */

/* Whether v0 -> v1 is a sign change that counts in direction dir. */
static int crossed(int dir, double v0, double v1)
{
  int up = v0 < 0 && v1 >= 0, down = v0 > 0 && v1 <= 0;
  return dir > 0 ? up : dir < 0 ? down : up || down;
}

/* Event i on the dense output of the last step of x, at theta. */
static double dense_value(hbvmrt_events *ev, const void *x, double theta, int i)
{
  ev->md->dense(x, theta, ev->y);
  ev->md->events(ev->y, ev->prm, ev->vt);
  return ev->vt[i];
}

/* Stage 1: theta of the root of event i on the dense output of the step h
 * (x its end), bracketed by fa = value at 0 (never 0) and fb = value at 1:
 * 1 when fb is 0, so that below both ends have a sign, opposite ones. */
static double locate(hbvmrt_events *ev, const void *x, double h, int i, double fa, double fb)
{
  double a = 0, b = 1, tol = HBVMRT_EVENT_TOL * (1 + fabs(hbvmrt_state_time(ev->md, x))) / fabs(h);
  int side = 0, it;

  if (fb == 0)
    return 1;
  for (it = 0; it < 200 && b - a > tol; it++) {
    double c = (a * fb - b * fa) / (fb - fa), fc;
    if (!(c > a && c < b))
      c = 0.5 * (a + b);
    fc = dense_value(ev, x, c, i);
    if (fc == 0)
      return c;
    if ((fc > 0) == (fb > 0)) {   /* the root is in [a, c] */
      b = c;
      fb = fc;
      if (side == -1)
        fa /= 2;
      side = -1;
    } else {
      a = c;
      fa = fc;
      if (side == 1)
        fb /= 2;
      side = 1;
    }
  }
  return fa == fb ? 0.5 * (a + b) : (a * fb - b * fa) / (fb - fa);
}

int hbvmrt_state_within(const hbvmrt_model *md, const void *prm, const void *x0, const void *x, double theta,
                        double hsub, void *z)
{
  hbvmrt_stats st;

  memcpy(z, x0, md->state_size);
  if (theta > 0 && hsub != 0 && md->step(z, hsub, prm, &st) == 0)
    return 0;
  md->dense(x, theta < 0 ? 0 : theta, z);
  return 1;
}

/* Stage 2: the state at event i into ev->z, by steps of theta h from x0
 * (Newton on theta, the slope from the dense output of x); the dense
 * output at theta when a step fails. */
static void polish(hbvmrt_events *ev, const void *x0, const void *x, double h, int i, double theta)
{
  const hbvmrt_model *md = ev->md;
  double d = 1e-6, lo = theta - d < 0 ? 0 : theta - d, hi = theta + d > 1 ? 1 : theta + d;
  double slope = (dense_value(ev, x, hi, i) - dense_value(ev, x, lo, i)) / (hi - lo);
  double tol = HBVMRT_EVENT_TOL * (1 + fabs(hbvmrt_state_time(md, x))) / fabs(h);
  int k;

  for (k = 0; k < POLISH_ITERS; k++) {
    double f, dtheta;
    if (!(slope != 0 && isfinite(slope)))
      break;
    if (hbvmrt_state_within(md, ev->prm, x0, x, theta, theta * h, ev->z) != 0)
      return; /* the dense output at theta: no step of the method reaches it */
    md->events(ev->z, ev->prm, ev->vt);
    f = ev->vt[i];
    dtheta = -f / slope;
    if (fabs(dtheta) <= tol || !isfinite(dtheta) || k == POLISH_ITERS - 1)
      return;
    theta += dtheta;
    if (theta < 0)
      theta = 0;
    if (theta > 1)
      theta = 1;
  }
  md->dense(x, theta, ev->z);
}

/* The first event whose value in v is not a number, reported as at the
 * state x (after, when given, the value v0 it had at x0); -1 if none. */
static int not_a_number(const hbvmrt_events *ev, const double *v, const void *x, const double *v0, const void *x0)
{
  const hbvmrt_model *md = ev->md;
  int i;

  for (i = 0; i < md->nevents; i++)
    if (isnan(v[i])) {
      fprintf(stderr, "%s: error: event '%s' is not a number at t=%.15g", md->name, md->event_names[i],
              hbvmrt_state_time(md, x));
      if (v0)
        fprintf(stderr, " (%.3g at t=%.15g)", v0[i], hbvmrt_state_time(md, x0));
      fputs(": its sign changes cannot be found\n", stderr);
      return i;
    }
  return -1;
}

int hbvmrt_events_open(hbvmrt_events *ev, const hbvmrt_model *md, const hbvmrt_opts *o, const void *prm,
                       const void *x)
{
  size_t n = (size_t)md->nevents + 1;

  memset(ev, 0, sizeof *ev);
  if (!o->events && o->stop_event < 0)
    return 0;
  ev->md = md;
  ev->prm = prm;
  ev->stop_event = o->stop_event;
  ev->stop_count = o->stop_count;
  ev->v0 = calloc(n, sizeof *ev->v0);
  ev->v1 = calloc(n, sizeof *ev->v1);
  ev->vt = calloc(n, sizeof *ev->vt);
  ev->count = calloc(n, sizeof *ev->count);
  ev->found = calloc(n, sizeof *ev->found);
  ev->theta = calloc(n, sizeof *ev->theta);
  ev->y = calloc(1, md->state_size + 1);
  ev->z = calloc(1, md->state_size + 1);
  if (!ev->v0 || !ev->v1 || !ev->vt || !ev->count || !ev->found || !ev->theta || !ev->y || !ev->z) {
    hbvmrt_error(md, "out of memory");
    return -1;
  }
  md->events(x, prm, ev->v0);
  if (not_a_number(ev, ev->v0, x, NULL, NULL) >= 0)
    return -1;
  if (!o->events)
    return 0;
  ev->path = o->events;
  ev->f = hbvmrt_out_open(o->events);
  if (!ev->f) {
    hbvmrt_error(md, "cannot open '%s': %s", o->events, strerror(errno));
    return -1;
  }
  if (hbvmrt_csv_event_header(ev->f, md) != 0)
    ev->ferr = errno ? errno : EIO;
  return 0;
}

/* The events found in the step, by theta (insertion sort: few per step). */
static void sort_found(hbvmrt_events *ev, int n)
{
  int a, b;

  for (a = 1; a < n; a++)
    for (b = a; b > 0 && ev->theta[ev->found[b]] < ev->theta[ev->found[b - 1]]; b--) {
      int t = ev->found[b];
      ev->found[b] = ev->found[b - 1];
      ev->found[b - 1] = t;
    }
}

int hbvmrt_events_step(hbvmrt_events *ev, const void *x0, void *x, double h)
{
  const hbvmrt_model *md = ev->md;
  int i, n = 0, k;

  if (!md)
    return 0;
  md->events(x, ev->prm, ev->v1);
  if (not_a_number(ev, ev->v1, x, ev->v0, x0) >= 0)
    return 2;
  for (i = 0; i < md->nevents; i++)
    if (crossed(md->event_dirs[i], ev->v0[i], ev->v1[i])) {
      ev->theta[i] = locate(ev, x, h, i, ev->v0[i], ev->v1[i]);
      ev->found[n++] = i;
    }
  sort_found(ev, n);
  for (k = 0; k < n; k++) {
    i = ev->found[k];
    polish(ev, x0, x, h, i, ev->theta[i]);
    ev->count[i]++;
    if (ev->f && !ev->ferr && hbvmrt_csv_event_row(ev->f, md, md->event_names[i], ev->z) != 0)
      ev->ferr = errno ? errno : EIO;
    if (i == ev->stop_event && ev->count[i] == ev->stop_count) {
      memcpy(x, ev->z, md->state_size);
      md->events(x, ev->prm, ev->v0);
      return 1;
    }
  }
  memcpy(ev->v0, ev->v1, (size_t)md->nevents * sizeof *ev->v0);
  return ev->ferr ? -1 : 0;
}

int hbvmrt_events_close(hbvmrt_events *ev)
{
  int err = ev->f ? hbvmrt_out_close(ev->f, ev->ferr) : 0;

  if (err)
    hbvmrt_error(ev->md, "cannot write '%s': %s", strcmp(ev->path, "-") == 0 ? "standard output" : ev->path,
                 strerror(err));
  free(ev->v0);
  free(ev->v1);
  free(ev->vt);
  free(ev->count);
  free(ev->found);
  free(ev->theta);
  free(ev->y);
  free(ev->z);
  memset(ev, 0, sizeof *ev);
  return err ? -1 : 0;
}
