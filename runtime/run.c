/* run.c - hbvmrt_run: the standalone driver's loop (docs/api.md, "The standalone driver").
 *
 * After the options (args.c) it allocates the state and params blocks, fills
 * the params with the defaults and the --param values, initialises the state
 * and takes N steps of the constant step h, the last one shortened to end
 * on -T exactly.  A step that fails is retried as two halves (each of which
 * may be halved again, HBVMRT_HALVINGS deep), said once on stderr.  After
 * t=0 and after every step it evaluates H, g and the hidden constraints hc,
 * so the maxima in the summary are over every step, not just the rows
 * written (every K-th step, t=0 and the last step).  A step that fails even
 * halved stops the loop: the state it left is the last good one, written as
 * the final row, and the exit status is 2.
 *
 * With --dt the rows are those of the grid t = k DT instead, from the dense
 * output of the step that contains each (grid_rows); with --events or
 * --stop-at each step is searched for events (events.c), which needs the
 * state before the step (x0), and --stop-at ends the loop at the state of
 * its event.
 *
 * Exit status: 0 success, 1 bad arguments or an output error (the CSV could
 * not be opened or written: an incomplete file is never silent; this wins over
 * a failed step), 2 a failed step, an event that is not a number or
 * --max-steps reached short of T, 3 steps
 * whose relative energy defect (hbvmrt_stats.defect) is above sqrt(eps):
 * the run ended, but H was not conserved.  Every run that started ends with
 * the summary line (summary), after warnings on the largest local error
 * estimate and on those steps; per-step messages stop at HBVMRT_MAX_SAID. */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "hbvmrt_internal.h"

/* One run: the blocks, scratch for g and hc, and the running figures. */
typedef struct {
  const hbvmrt_model *md;
  const hbvmrt_opts *o;
  void *x, *prm;
  double *g, *hc;             /* nu values each (one spare) */
  double H0, H;               /* energy at t=0 and now */
  double scale0;              /* |K| + |U| at t=0: the energy's size where H0 is round-off */
  double max_dh, max_g, max_hc;
  double iters_sum;
  int iters_max;
  long steps;                 /* steps taken successfully */
  long rejected;              /* steps tried and failed (then retried smaller) */
  double h_min, h_max;        /* of the steps taken, in |h| */
  int fail_code;              /* the failed step's code, or 0 */
  FILE *csv;                  /* NULL: no CSV */
  int csv_errno;              /* errno of the first failed write, or 0 */
  void *x0, *y;               /* the state before the step, a dense state (--dt, events) */
  long grid_k;                /* --dt: the next row is at t = grid_k DT */
  double grid_t;              /* ... and the last one was at t = grid_t */
  hbvmrt_events ev;           /* --events, --stop-at */
  const hbvmrt_switching *swfn; /* the model's switching functions, or NULL */
  hbvmrt_switch sw;           /* steps ended on the switching points (switch.c) */
  int stopped;                /* the --stop-at event ended the run */
  int event_nan;              /* ... or an event that is not a number, reported */
  double max_err_est;         /* the largest local error estimate of a step */
  double max_q;               /* max |q| over the steps, the scale of max_err_est */
  double max_defect;          /* the largest relative energy defect of a step */
  long defect_steps;          /* steps whose defect is far above round-off */
  int max_steps_hit;          /* --max-steps ended the run short of T */
  long newton_steps;          /* steps that took simplified Newton ... */
  long newton, factors, jacobians; /* ... its iterations, factorisations, J evaluations */
  long said;                  /* per-step messages written on stderr ... */
  long unsaid;                /* ... and suppressed past HBVMRT_MAX_SAID */
} Run;

/* The progress line: drawn only on a terminal, after a second, at most ten
 * times a second; the clock is read every `stride` steps, a stride that
 * adapts so that it is read every 10 to 50 ms whatever a step costs. */
typedef struct {
  int on;
  double start, last_check, last_draw;
  long stride, next;          /* read the clock again at step `next` */
  int width;                  /* of the line drawn, 0 if none */
} Progress;

/* Wall-clock seconds (CLOCK_MONOTONIC): the summary's `seconds` is the wall
 * time of the loop, CSV writing included, since that is what the user waits
 * for and what the progress line's steps per second mean. */
static double now(void)
{
  struct timespec ts;

  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The time of the run's state (its rounded value). */
static double state_t(const Run *r)
{
  return hbvmrt_state_time(r->md, r->x);
}

/* max = max(max, |v|), except that a NaN, once seen, stays */
static void keep_max(double *max, double v)
{
  v = fabs(v);
  if (!(v <= *max) && !isnan(*max))
    *max = v;
}

/* H, g and hc of the current state, into the running maxima. */
static void observe(Run *r)
{
  const hbvmrt_model *md = r->md;
  int i;

  r->H = md->energy(r->x, r->prm);
  keep_max(&r->max_dh, r->H - r->H0);
  if (md->nu <= 0)
    return;
  md->constraints(r->x, r->prm, r->g);
  md->hidden(r->x, r->prm, r->hc);
  for (i = 0; i < md->nu; i++) {
    keep_max(&r->max_g, r->g[i]);
    keep_max(&r->max_hc, r->hc[i]);
  }
}

/* max |v[i]| over n doubles at byte offset off of the state x */
static double max_abs(const void *x, size_t off, int n)
{
  const double *v = (const double *)(const void *)((const char *)x + off);
  double m = 0;
  int i;

  for (i = 0; i < n; i++)
    keep_max(&m, v[i]);
  return m;
}

/* The initial state against the constraints (drivers that can project): a
 * copy is projected, and a change of q or p beyond HBVMRT_CONSISTENCY_TOL
 * relative (64 ulps in float) is refused, naming the sizes, unless
 * --project was given; then the projected state is kept and the change
 * reported.  Returns 0, or the exit status after reporting. */
static int check_initial(Run *r)
{
  const hbvmrt_model *md = r->md;
  double dq = 0, dp = 0, gmax = 0, hmax = 0, tol = HBVMRT_CONSISTENCY_TOL;
  double qmax = max_abs(r->x, md->off_q, md->m), pmax = max_abs(r->x, md->off_p, md->m);
  void *y;
  int i, code, status = 0;

  if (md->nu <= 0 || !md->project)
    return 0;
  if (64 * md->eps > tol)
    tol = 64 * md->eps;
  if (!(y = malloc(md->state_size + 1))) {
    hbvmrt_error(md, "out of memory");
    return 1;
  }
  memcpy(y, r->x, md->state_size);
  code = md->project(y, r->prm, &dq, &dp);
  md->constraints(r->x, r->prm, r->g);
  md->hidden(r->x, r->prm, r->hc);
  for (i = 0; i < md->nu; i++) {
    keep_max(&gmax, r->g[i]);
    keep_max(&hmax, r->hc[i]);
  }
  if (code != 0 && (r->o->project || !(gmax <= tol && hmax <= tol))) {
    hbvmrt_error(md, "cannot project the initial values onto the constraints "
                 "(max|g(q0)| = %.3e, max|hidden(q0, p0)| = %.3e): %s", gmax,
                 hmax, md->strerror ? md->strerror(code) : "failed");
    status = 2;
  } else if (r->o->project) {
    memcpy(r->x, y, md->state_size);
    fprintf(stderr, "%s: projected the initial values onto the constraints: "
            "max|g(q0)| = %.3e, max|hidden(q0, p0)| = %.3e; q moved by %.3e, "
            "p by %.3e\n", md->name, gmax, hmax, dq, dp);
  } else if (code == 0 && !(dq <= tol * qmax && dp <= tol * pmax)) {
    hbvmrt_error(md, "the initial values are off the constraints: max|g(q0)| "
                 "= %.3e, max|hidden(q0, p0)| = %.3e (q would move by %.3e, "
                 "p by %.3e, more than %.0e relative); give consistent "
                 "--q0/--p0, or pass --project to move them onto the "
                 "constraints", gmax, hmax, dq, dp, tol);
    status = 1;
  }
  free(y);
  return status;
}

/* |K| + |U| of the state x whose energy is H: U from a state initialised at
 * x's q with p = 0 (K = p' M(q)^-1 p / 2 vanishes there; through init, as a
 * float driver's energy reads its own state, not the double q and p the
 * runtime sees), K = H - U; the size the summary's max_dH_rel is taken
 * against where H0 is round-off (summary). 0 where that state cannot be made. */
static double energy_scale(const hbvmrt_model *md, const void *x, const void *prm, double H)
{
  void *y = calloc(1, md->state_size + 1);
  double *zero = calloc((size_t)md->m + 1, sizeof *zero), U;
  const double *q = (const double *)(const void *)((const char *)x + md->off_q);

  if (!y || !zero) {
    free(y);
    free(zero);
    return 0;
  }
  if (md->init_params)
    md->init_params(y, q, zero, prm);
  else
    md->init(y, q, zero);
  U = md->energy(y, prm);
  free(y);
  free(zero);
  return fabs(H - U) + fabs(U);
}

/* Allocate the blocks, set the params and the initial state (docs/api.md:
 * NULL q0/p0 means the model defaults, at the run's params when the driver
 * can say so), checked against the constraints.  The exit status after
 * reporting, or 0. */
static int setup(Run *r, const hbvmrt_model *md, const hbvmrt_switching *sw, const hbvmrt_opts *o)
{
  const double *q0 = o->q0, *p0 = o->p0;
  size_t nu = (size_t)(md->nu > 0 ? md->nu : 0);
  int status;

  memset(r, 0, sizeof *r);
  r->grid_k = 1;              /* the row at t = 0 is the first */
  r->md = md;
  r->swfn = sw;
  r->o = o;
  r->x = calloc(1, md->state_size + 1);
  r->prm = calloc(1, md->params_size + 1);
  r->g = calloc(nu + 1, sizeof *r->g);
  r->hc = calloc(nu + 1, sizeof *r->hc);
  if (o->dt > 0 || o->events || o->stop_event >= 0 || (sw && sw->n > 0 && !o->no_switch)) {
    r->x0 = calloc(1, md->state_size + 1);
    r->y = calloc(1, md->state_size + 1);
    if (!r->x0 || !r->y) {
      hbvmrt_error(md, "out of memory");
      return 1;
    }
  }
  if (!r->x || !r->prm || !r->g || !r->hc) {
    hbvmrt_error(md, "out of memory");
    return 1;
  }
  if (md->params_default)
    md->params_default(r->prm);
  hbvmrt_apply_params(md, o, r->prm);
  if (md->init_params) {
    md->init_params(r->x, q0, p0, r->prm);
  } else {
    if (q0 || p0) {
      q0 = q0 ? q0 : md->q0;
      p0 = p0 ? p0 : md->p0;
    }
    md->init(r->x, q0, p0);
  }
  if (o->t0 != 0 && hbvmrt_set_time(md, r->x, o->t0) != 0) {
    hbvmrt_error(md, "--t0: this float driver cannot set the time of its state (generated before --t0): "
                 "generate it again");
    return 1;
  }
  status = check_initial(r);
  r->H0 = md->energy(r->x, r->prm);
  r->scale0 = energy_scale(md, r->x, r->prm, r->H0);
  return status;
}

static void teardown(Run *r)
{
  free(r->x);
  free(r->prm);
  free(r->g);
  free(r->hc);
  free(r->x0);
  free(r->y);
}

static const char *csv_name(const Run *r)
{
  return strcmp(r->o->csv, "-") == 0 ? "standard output" : r->o->csv;
}

/* Open --csv FILE (stdout for "-") and write the header; -1 after
 * reporting.  Nothing is opened before the options are known to be good. */
static int open_csv(Run *r)
{
  const char *path = r->o->csv;

  if (!path)
    return 0;
  r->csv = hbvmrt_out_open(path);
  if (!r->csv) {
    hbvmrt_error(r->md, "cannot open '%s': %s", path, strerror(errno));
    return -1;
  }
  if (hbvmrt_csv_header(r->csv, r->md) != 0)
    r->csv_errno = errno ? errno : EIO;
  return 0;
}

/* The current state as a CSV row; -1 (errno kept) once writing failed. */
static int write_row(Run *r)
{
  if (!r->csv)
    return 0;
  if (r->csv_errno == 0 &&
      hbvmrt_csv_row(r->csv, r->md, r->x, r->H, r->g, r->hc) != 0)
    r->csv_errno = errno ? errno : EIO;
  return r->csv_errno ? -1 : 0;
}

/* Close (or for stdout, flush) the CSV; -1 after reporting a write error,
 * whether it happened now or during the loop. */
static int close_csv(Run *r)
{
  int err;

  if (!r->csv)
    return 0;
  err = hbvmrt_out_close(r->csv, r->csv_errno);
  r->csv = NULL;
  if (!err)
    return 0;
  hbvmrt_error(r->md, "cannot write '%s': %s", csv_name(r), strerror(err));
  return -1;
}

static void progress_start(Progress *pg, const Run *r)
{
  int csv_on_tty = r->o->csv && strcmp(r->o->csv, "-") == 0 &&
                   isatty(fileno(stdout));

  memset(pg, 0, sizeof *pg);
  pg->on = !r->o->quiet && !csv_on_tty && isatty(fileno(stderr));
  pg->start = pg->last_check = pg->last_draw = now();
  pg->stride = pg->next = 1;
}

/* At step n: adapt the stride, and redraw when a second has gone by since
 * the start and a tenth since the last drawing. */
static void progress_tick(Progress *pg, const Run *r, long n)
{
  double t = now(), since = t - pg->last_check;
  double done = (double)n / (double)r->o->nsteps;
  char line[192], eta[32];
  int len;

  if (since < 0.01 && pg->stride < (1L << 20))
    pg->stride *= 2;
  else if (since > 0.05 && pg->stride > 1)
    pg->stride /= 2;
  pg->last_check = t;
  pg->next = n + pg->stride;
  if (t - pg->start < 1.0 || t - pg->last_draw < 0.1)
    return;
  pg->last_draw = t;
  if (r->o->tol > 0 && r->o->T > 0)   /* adaptive: the share of the span */
    done = fabs(state_t(r) - r->o->t0) / r->o->T;
  hbvmrt_eta(t - pg->start, done, eta, sizeof eta);
  len = snprintf(line, sizeof line, "%s: %5.1f%%  %.0f steps/s  |H-H0|=%.2e  %s",
                 r->md->name, 100.0 * done,
                 (double)n / (t - pg->start), fabs(r->H - r->H0), eta);
  if (len > (int)sizeof line - 1)
    len = (int)sizeof line - 1;
  fprintf(stderr, "\r%-*s", pg->width, line);
  if (len > pg->width)
    pg->width = len;
}

void hbvmrt_eta(double elapsed, double done, char *buf, size_t n)
{
  double left = elapsed * (1 - done) / done;

  if (!(done > 0 && done <= 1 && left < 1e8)) {
    if (n)
      buf[0] = '\0';
    return;
  }
  if (left < 60)
    snprintf(buf, n, "ETA %.0fs", left);
  else if (left < 3600)
    snprintf(buf, n, "ETA %.0fm%02.0fs", floor(left / 60), floor(fmod(left, 60)));
  else
    snprintf(buf, n, "ETA %.0fh%02.0fm", floor(left / 3600), floor(fmod(left, 3600) / 60));
}

static void progress_clear(Progress *pg)
{
  if (pg->width > 0)
    fprintf(stderr, "\r%*s\r", pg->width, "");
  pg->width = 0;
}

/* A row per step, unless --dt writes the rows on its grid. */
static int step_row(Run *r)
{
  return r->o->dt > 0 ? 0 : write_row(r);
}

/* --dt: the rows of the grid t = k DT (k = grid_k, ...) inside the step just
 * taken, from r->x0 to r->x; the time written is the grid's (a point within
 * round-off past the step's end is its end). A row inside the step is a step
 * of the method from r->x0 to it, as accurate as the run's steps (the dense
 * output alone is of order S+1: on Kepler at --tol 1e-10 it was 1e-5 off,
 * the rows now 1e-9); the dense output only where that step fails. */
static void grid_rows(Run *r)
{
  const hbvmrt_model *md = r->md;
  double t0 = hbvmrt_state_time(md, r->x0), t1 = state_t(r), dt = r->o->dt;
  int i;

  for (;;) {
    double dir = t1 < t0 ? -1 : 1, tk = r->o->t0 + dir * (double)r->grid_k * dt, theta, H;
    if ((tk - t1) * dir > 1e-12 * (fabs(t1) + dt) || t1 == t0)
      return;
    theta = (tk - t0) / (t1 - t0);
    if (theta >= 1)
      memcpy(r->y, r->x, md->state_size);
    else
      hbvmrt_state_within(md, r->prm, r->x0, r->x, theta, tk - t0, r->y);
    memcpy((char *)r->y + md->off_t, &tk, sizeof tk);
    H = md->energy(r->y, r->prm);
    for (i = 0; i < md->nu; i++)
      r->g[i] = r->hc[i] = 0;
    if (md->nu > 0) {
      md->constraints(r->y, r->prm, r->g);
      md->hidden(r->y, r->prm, r->hc);
    }
    if (r->csv && r->csv_errno == 0 && hbvmrt_csv_row(r->csv, md, r->y, H, r->g, r->hc) != 0)
      r->csv_errno = errno ? errno : EIO;
    r->grid_t = tk;
    r->grid_k++;
  }
}

/* The state of the --stop-at event as the last row: with --dt too (its
 * grid ended at the row before the event), unless the grid's last row is
 * the event's t within the grid's round-off. */
static int stop_row(Run *r)
{
  double t = state_t(r);

  if (r->o->dt > 0 && fabs(t - r->grid_t) <= 1e-12 * (fabs(t) + r->o->dt))
    return 0;
  return write_row(r);
}

/* Before a step: a fresh start after a switching point (switch.c), and the
 * state it starts from, when events, --dt or the switching need it. */
static void before_step(Run *r)
{
  hbvmrt_switch_before(&r->sw, r->x);
  if (r->x0)
    memcpy(r->x0, r->x, r->md->state_size);
}

/* The relative energy defect (hbvmrt_stats.defect) above which a step is
 * flagged: sqrt(eps) of the solver's real type, half the digits of H lost in
 * one step, or under --tol the tolerance, if larger (the adaptive step's
 * estimate holds the defect within it: Kepler at k = s = 2, --tol 1e-4,
 * keeps 2e-7, well within what was asked).  A step that resolves H keeps it
 * to a few ulps (Kepler, k = 16: 4e-16 up to h = 0.5; float: 2e-7); one
 * whose quadrature does not loses far more (h = 1: 1e-7, h = 300: 0.3). */
static double defect_limit(const Run *r)
{
  double lim = sqrt(r->md->eps > 0 ? r->md->eps : 2.220446049250313e-16);

  return r->o->tol > lim ? r->o->tol : lim;
}

/* A per-step message on stderr (printf-like): the first HBVMRT_MAX_SAID of
 * the run are written, the rest counted (said at the end, say_suppressed),
 * so that a run of a million retried steps does not write a million lines. */
static void say(Run *r, const char *fmt, ...) HBVMRT_PRINTF(2, 3);
static void say(Run *r, const char *fmt, ...)
{
  va_list ap;

  if (r->said >= HBVMRT_MAX_SAID) {
    r->unsaid++;
    return;
  }
  r->said++;
  va_start(ap, fmt);
  vfprintf(stderr, fmt, ap);
  va_end(ap);
}

static void say_suppressed(const Run *r)
{
  if (r->unsaid > 0)
    fprintf(stderr, "%s: %ld more such messages not shown (at most %d are)\n", r->md->name, r->unsaid,
            HBVMRT_MAX_SAID);
}

/* A step of size h was taken: its figures into the run's, its events (the
 * --stop-at event moves the state back to it), its rows of the --dt grid. */
static void taken(Run *r, const hbvmrt_stats *st, double h)
{
  r->steps++;
  r->iters_sum += st->iters;
  r->newton_steps += st->newton > 0;
  r->newton += st->newton;
  r->factors += st->factors;
  r->jacobians += st->jacobians;
  if (st->iters > r->iters_max)
    r->iters_max = st->iters;
  if (r->steps == 1 || fabs(h) < r->h_min)
    r->h_min = fabs(h);
  if (fabs(h) > r->h_max)
    r->h_max = fabs(h);
  keep_max(&r->max_err_est, st->err_est);
  keep_max(&r->max_q, max_abs(r->x, r->md->off_q, r->md->m));
  keep_max(&r->max_defect, st->defect);
  if (!(st->defect <= defect_limit(r)))
    r->defect_steps++;
  if (r->ev.md) {
    int found = hbvmrt_events_step(&r->ev, r->x0, r->x, h);
    r->event_nan = found == 2;
    r->stopped = found == 1 || found == 2;
  }
  observe(r);
  if (r->o->dt > 0)
    grid_rows(r);
}

/* hbvmrt_advance's callbacks for the run: the state before each try, each
 * step taken into the run's figures (stop at the --stop-at event), each
 * failed try counted, the first retry of a fixed step said on stderr. */
static void on_before(void *ctx)
{
  before_step(ctx);
}

static int on_taken(void *ctx, const hbvmrt_stats *st, double h)
{
  Run *r = ctx;

  taken(r, st, h);
  return r->stopped;
}

static void on_failed(void *ctx, double h, int code, int depth)
{
  Run *r = ctx;

  r->rejected++;
  if (depth == 0)
    say(r, "%s: step h=%.6g failed at t=%.15g (%s): retrying with halved steps\n", r->md->name, h, state_t(r),
        r->md->strerror ? r->md->strerror(code) : "failed");
}

/* Advance the state by h (hbvmrt_advance: one step, or, when it fails, its
 * halves; a step cut on a switching point is followed by the rest of h, so
 * that the run keeps its grid; after HBVMRT_MAX_CUTS cuts in one step, a
 * chattering contact, the rest goes across them).  Returns 0, or the code of the last failed
 * step. */
static int advance(Run *r, double h)
{
  hbvmrt_steps cb = {on_before, on_taken, on_failed, NULL};
  double target = state_t(r) + h;
  int stopped, cuts = 0;

  cb.ctx = r;
  while (r->sw.md && cuts++ < HBVMRT_MAX_CUTS) {   /* steps that end on the switching points (switch.c) */
    hbvmrt_stats st;
    double rest = target - state_t(r);
    int found;
    before_step(r);
    found = hbvmrt_switch_find(&r->sw, r->x0, r->x, rest, -1, &st);
    h = rest;
    if (found != 0 && found != 1)   /* a failure not at a point: halves, as without */
      break;
    taken(r, &st, st.h);
    if (found == 0 || r->stopped)
      return 0;
    h = target - state_t(r);
  }
  return hbvmrt_advance(r->md, r->x, r->prm, h, 0, &cb, &stopped);
}

/* --max-steps: n steps taken and the span not done: the run stops there
 * (status 2, max_steps), its state written as the last row (unless the
 * --every K of the loop just wrote it). */
static int max_steps_reached(Run *r, long n, long K)
{
  if (!(r->o->max_steps > 0 && n >= r->o->max_steps))
    return 0;
  r->max_steps_hit = 1;
  if (n % K != 0)
    step_row(r);
  return 1;
}

/* --tol: adaptive steps from h until -T, hit exactly (hbvmrt_adaptive_step).
 * Rows at t=0, every K steps taken and at T; stops at the first failed step
 * (its code in r->fail_code). */
static void loop_adaptive(Run *r, Progress *pg)
{
  long n = 0, K = r->o->every;
  double h = r->o->h, t_end = hbvmrt_span_end(r->o);

  observe(r);
  if (write_row(r) != 0)
    return;
  while (state_t(r) != t_end) {
    hbvmrt_stats st;
    int at_end, code;

    if (max_steps_reached(r, n, K))
      return;
    before_step(r);
    if (r->sw.md)   /* steps that end on the switching points (switch.c) */
      code = hbvmrt_switch_adaptive(&r->sw, r->o, r->x0, r->x, &h, &st, &at_end);
    else
      code = hbvmrt_adaptive_step(r->md, r->o, r->x, &h, r->prm, &st, &at_end);
    r->rejected += st.rejected;
    if (code != 0) {
      r->fail_code = code;
      if (n % K != 0)
        step_row(r);
      return;
    }
    n++;
    taken(r, &st, st.h);
    if (r->stopped || at_end) {   /* at the event, or on T */
      hbvmrt_span_land(r->md, r->o, r->x);
      if (r->stopped)
        stop_row(r);
      else
        step_row(r);
      return;
    }
    if (n % K == 0 && step_row(r) != 0)
      return;
    if (pg->on && n >= pg->next)
      progress_tick(pg, r, n);
  }
  step_row(r);
}

/* Rows at t=0, every K steps and at the last step taken; stops at the
 * first step that fails even halved (code in r->fail_code) or failed
 * write.  With a span (-T) the last step is shortened to end on it. */
static void loop(Run *r, Progress *pg)
{
  long n, N = r->o->nsteps, K = r->o->every;

  observe(r);
  if (write_row(r) != 0)
    return;
  for (n = 1; n <= N; n++) {
    int code;
    if (max_steps_reached(r, n - 1, K))
      return;
    code = advance(r, hbvmrt_fixed_step(r->md, r->o, n, r->x));
    if (code != 0) {
      r->fail_code = code;
      if ((n - 1) % K != 0)
        step_row(r);           /* the state the failed step left */
      return;
    }
    if (r->stopped) {          /* at the --stop-at event */
      stop_row(r);
      return;
    }
    if (n == N)
      hbvmrt_span_land(r->md, r->o, r->x);
    if ((n % K == 0 || n == N) && step_row(r) != 0)
      return;
    if (pg->on && n >= pg->next)
      progress_tick(pg, r, n);
  }
}

/* `NAME: error: step failed at t=T: REASON`, T the time of the state the
 * failed step left alone. */
static void report_failure(const Run *r)
{
  const hbvmrt_model *md = r->md;
  const char *why = md->strerror ? md->strerror(r->fail_code) : NULL;

  fprintf(stderr, "%s: error: step failed at t=%.15g: ", md->name, state_t(r));
  if (why)
    fprintf(stderr, "%s\n", why);
  else
    fprintf(stderr, "code %d\n", r->fail_code);
}

/* The largest local error estimate against the state: above
 * HBVMRT_ERR_EST_WARN (1 + max|q|), said in one line.  The steps are then too
 * long for the motion, whatever H and g say: the method conserves them at any
 * h (a four-bar at h = 0.2 ended 1.76 off with H and g at 1e-14). */
static void warn_err_est(const Run *r)
{
  double limit = HBVMRT_ERR_EST_WARN * (1 + r->max_q);

  if (r->max_err_est > limit)
    fprintf(stderr, "%s: warning: the largest local error estimate of a step, %.3e, is above %g (1 + max|q|) = "
            "%.3e: the steps are too long for the motion, and the result may be far off even where H and g are "
            "kept; take a smaller -h, or --tol\n", r->md->name, r->max_err_est, HBVMRT_ERR_EST_WARN, limit);
}

/* Steps flagged for their energy defect (defect_limit), said in one line. */
static void warn_defect(const Run *r)
{
  if (r->defect_steps > 0)
    fprintf(stderr, "%s: warning: %ld step%s did not conserve H: relative energy defect up to %.3e, above %.1e "
            "(the k = %d nodes do not resolve H at this h); take a smaller %s (exit status 3)\n",
            r->md->name, r->defect_steps, r->defect_steps == 1 ? "" : "s", r->max_defect, defect_limit(r),
            r->md->k, r->o->tol > 0 ? "--tol" : "-h");
}

/* Which solver ran, for the summary: fixed (no step took Newton), newton
 * (every step did), fixed+newton (under --iteration auto, some steps did). */
static const char *solver_ran(const Run *r)
{
  if (r->newton_steps == 0)
    return "fixed";
  return r->newton_steps == r->steps ? "newton" : "fixed+newton";
}

/* The summary line (docs/api.md, "The standalone driver"); without constraints max_g
 * and max_hc are kept, as a plain 0, so every run's line has the same
 * fields.  max_dH_rel is max_dH / |H0|, or over |K0| + |U0| where H0 is
 * within 64 ulps of that (0 when max_dH is 0); solver says
 * which iteration ran, and where Newton did, its counts follow; status says
 * how the run ended, t where. */
static void summary(const Run *r, double seconds, const char *status)
{
  double mean = r->steps > 0 ? r->iters_sum / (double)r->steps : 0.0;
  double eps = r->md->eps > 0 ? r->md->eps : DBL_EPSILON;
  /* against |H0|, or |K0| + |U0| where H0 is round-off of it (64 ulps): a bound
   * motion's H0 can be 0, or 3e-17 (the satellites), and max_dH over that said 5 or inf */
  double den = fabs(r->H0) > 64 * eps * r->scale0 ? fabs(r->H0) : r->scale0;
  double rel = r->max_dh == 0 ? 0 : r->max_dh / den;

  fprintf(stderr, "steps=%ld iters_mean=%.3g iters_max=%d max_dH=%.3e ",
          r->steps, mean, r->iters_max, r->max_dh);
  if (r->md->nu > 0)
    fprintf(stderr, "max_g=%.3e max_hc=%.3e", r->max_g, r->max_hc);
  else
    fputs("max_g=0 max_hc=0", stderr);
  fprintf(stderr, " seconds=%.3g steps_rejected=%ld h_min=%.3e h_max=%.3e",
          seconds, r->rejected, r->h_min, r->h_max);
  fprintf(stderr, " max_err_est=%.3e H0=%.17g max_dH_rel=%.3e max_defect=%.3e defect_steps=%ld",
          r->max_err_est, r->H0, rel, r->max_defect, r->defect_steps);
  if (r->swfn && r->swfn->n > 0)   /* a model that is not smooth: the switching points crossed */
    fprintf(stderr, " switches=%ld", r->sw.crossed);
  fprintf(stderr, " solver=%s", solver_ran(r));
  if (r->newton_steps > 0)
    fprintf(stderr, " newton_steps=%ld newton_iters=%ld factors=%ld jacobians=%ld", r->newton_steps, r->newton,
            r->factors, r->jacobians);
  fprintf(stderr, " t=%.15g status=%s\n", state_t(r), status);
}

/* The loop and everything reported after it; returns the exit status:
 * 1 an output error, 2 a failed step or an event not a number, 3 steps that
 * did not conserve H, else 0.  Every run that started ends with the summary
 * line, its status one of ok, output_error, step_failed, event_nan,
 * max_steps, energy_defect (the first that applies). */
static int simulate(Run *r)
{
  Progress pg;
  double seconds;
  int out_failed, status;
  static const char *const word[] = {"ok", "output_error", "step_failed", "energy_defect"};

  progress_start(&pg, r);
  if (r->o->tol > 0)
    loop_adaptive(r, &pg);
  else
    loop(r, &pg);
  seconds = now() - pg.start;
  progress_clear(&pg);
  say_suppressed(r);
  if (r->fail_code != 0)
    report_failure(r);
  if (r->max_steps_hit)
    fprintf(stderr, "%s: error: --max-steps %ld reached at t=%.15g, short of the span's end %.15g\n", r->md->name,
            r->o->max_steps, state_t(r), hbvmrt_span_end(r->o));
  out_failed = close_csv(r) != 0;
  if (r->ev.md && hbvmrt_events_close(&r->ev) != 0)
    out_failed = 1;
  warn_err_est(r);
  warn_defect(r);
  status = out_failed ? 1 : r->fail_code != 0 || r->event_nan || r->max_steps_hit ? 2 : r->defect_steps > 0 ? 3 : 0;
  summary(r, seconds, status == 2 && r->fail_code == 0 ? (r->max_steps_hit ? "max_steps" : "event_nan") : word[status]);
  return status;
}

/* The standalone driver's one run (driver.c sends it every run that is not an
 * ensemble): see hbvmrt.h and the comment at the top. */
int hbvmrt_run(const hbvmrt_model *model, const hbvmrt_switching *sw, int argc, char **argv)
{
  hbvmrt_opts o;
  Run r;
  int status;

  status = hbvmrt_parse_args(model, argc, argv, &o);
  if (status != HBVMRT_ARGS_RUN) {
    hbvmrt_opts_free(&o);
    return status == HBVMRT_ARGS_DONE ? 0 : 1;
  }
  status = setup(&r, model, sw, &o);
  if (status == 0)
    status = open_csv(&r) == 0 && hbvmrt_events_open(&r.ev, model, &o, r.prm, r.x) == 0 &&
                     hbvmrt_switch_open(&r.sw, model, sw, &o, r.prm, r.x) == 0
                 ? simulate(&r)
                 : 1;
  if (r.ev.md && status == 1)
    hbvmrt_events_close(&r.ev);
  hbvmrt_switch_close(&r.sw);
  teardown(&r);
  hbvmrt_opts_free(&o);
  return status;
}
