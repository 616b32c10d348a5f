/* ensemble.c - many trajectories of one model: --ensemble FILE.csv or
 * --sweep NAME=A:B:N (docs/api.md, "Ensembles").
 *
 * Each trajectory is a row: initial values and params by column name over
 * the run's defaults (--q0, --p0, --param), the steps of a single run of the
 * driver (span.c: N steps of h, the last shortened to end on -T, or --tol's
 * adaptive steps to T), and one summary row (final state, max |H - H0|, |g|,
 * |hc|, iterations, status).
 * Trajectories are cut into chunks of consecutive rows: W of them when the
 * solver has a batch step (stepped together, one lane each), else
 * HBVMRT_SCALAR_CHUNK stepped one after another.  Chunks are handed out
 * dynamically: to the threads of an OpenMP build (libhbvmrt_omp.a, a
 * critical section around the counter) and, built with MPI
 * (libhbvmrt_mpi.a, make MPI=1), across ranks by an atomic fetch-and-add on
 * a counter in rank 0's memory.  Every trajectory's arithmetic is the same
 * whoever computes it (a lane of NAME_batch_step is bitwise NAME_step), so
 * the output does not depend on W, threads or ranks; rank 0 collects the
 * rows (a bitwise OR of the zero-initialised tables, each row written by
 * one rank only) and writes them in input order. */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "hbvmrt_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif
#ifdef HBVMRT_MPI
#include <mpi.h>
#include <stdint.h>
#endif

#define HBVMRT_SCALAR_CHUNK 4  /* trajectories per chunk without a batch step */

/* Where a column of the input goes. */
enum { COL_Q, COL_P, COL_PARAM };

typedef struct {
  const hbvmrt_model *md;
  const hbvmrt_batch *bt;      /* NULL: no batch step */
  hbvmrt_opts o;
  const char *file, *sweep;
  int threads;
  int ncol, *kind, *index;     /* per column: COL_*, coordinate or param */
  long nrow;
  double *val;                 /* nrow x ncol */
  int width;                   /* doubles per result row */
  double *res;                 /* nrow x width, see result() */
  long nchunk, chunk, next;
  int rank, nranks;
#ifdef HBVMRT_MPI
  MPI_Win win;
  long *counter;
#endif
} Ens;

/* What one thread works in. */
typedef struct {
  void *x, *prm, *b, *prms;    /* a state, a params block; a batch and W params */
  double *g, *hc;              /* nu * max(W, 1) each */
  double *H0, *Hb;
  int *code, *iters;
} Work;

/* The result row of trajectory i: status, steps, t, q, p, lambda, then from
 * R_H on H, max_dH, max_g, max_hc, iters_mean, iters_max, and, not written,
 * the running sum of the iterations and the number of failed steps retried
 * as halves. */
enum { R_H, R_DH, R_G, R_HC, R_MEAN, R_MAX, R_SUM, R_HALVED, R_COUNT };

static double *result(const Ens *e, long i)
{
  return e->res + i * e->width;
}

/* where the H column of a result row is */
static int at_H(const hbvmrt_model *md)
{
  return 3 + 2 * md->m + (md->nu > 0 ? md->nu : 0);
}

/* the doubles at byte offset off of a state block */
static double *field(const void *x, size_t off)
{
  return (double *)(void *)((char *)(size_t)x + off);
}

static void keep_max(double *max, double v)
{
  v = fabs(v);
  if (!(v <= *max) && !isnan(*max))
    *max = v;
}

/* ---- the options of the ensemble, and its input ---- */

/* Whether arg is the option name, alone or with an attached =VALUE. */
static int is_option(const char *arg, const char *name)
{
  size_t n = strlen(name);

  return !strncmp(arg, name, n) && (arg[n] == 0 || arg[n] == '=');
}

/* Whether argv asks for an ensemble: --ensemble or --sweep, as the option
 * itself (a prefix such as --sweep1 is the driver's unknown option, not an
 * ensemble without its input: found by tests/fuzz/fuzz_runtime.c). */
int hbvmrt_ensemble_wanted(int argc, char **argv)
{
  int i;

  for (i = 1; i < argc; i++)
    if (is_option(argv[i], "--ensemble") || is_option(argv[i], "--sweep"))
      return 1;
  return 0;
}

/* Take --ensemble, --sweep, --threads out of argv (into e), leaving the
 * driver's own options in *rest for hbvmrt_parse_args. Each takes its value
 * as the next argument or attached, --ensemble=F, as the driver's options. */
static int own_options(Ens *e, int argc, char **argv, char **rest, int *nrest)
{
  static const char *const own[] = {"--ensemble", "--sweep", "--threads"};
  int i, k;

  *nrest = 0;
  for (i = 0; i < argc; i++) {
    const char *a = argv[i], **to = NULL, *val = NULL;
    char *end;
    size_t n = 0;
    for (k = 0; i > 0 && k < 3; k++) {
      n = strlen(own[k]);
      if (!strncmp(a, own[k], n) && (a[n] == '\0' || a[n] == '='))
        break;
    }
    if (i == 0 || k == 3) {
      rest[(*nrest)++] = argv[i];
      continue;
    }
    if (a[n] == '=')
      val = a + n + 1;
    else if (i + 1 < argc)
      val = argv[++i];
    else {
      hbvmrt_error(e->md, "option %s needs a value", a);
      return -1;
    }
    if (k == 2) {
      long v = strtol(val, &end, 10);
      if (end == val || *end || v < 1 || v > 4096) {
        hbvmrt_error(e->md, "--threads needs a whole number from 1 to 4096, got '%s'", val);
        return -1;
      }
      e->threads = (int)v;
      continue;
    }
    to = k == 0 ? &e->file : &e->sweep;
    if (*to) {
      hbvmrt_error(e->md, "%s given twice", own[k]);
      return -1;
    }
    *to = val;
  }
  if (e->file && e->sweep) {
    hbvmrt_error(e->md, "--ensemble and --sweep cannot be used together");
    return -1;
  }
  return 0;
}

/* The column called name: a coordinate (x, x[3]), a param, or a momentum
 * (p_ and a coordinate), looked up by the exact name first, so that a param
 * p_x of a driver from before hbvmgen refused such names is that param, not
 * the momentum of x; -1 after an error naming it, after where (a place in
 * the file). */
static int column(Ens *e, int c, const char *name, size_t len, const char *where)
{
  const hbvmrt_model *md = e->md;
  int i;

  for (i = 0; i < md->m; i++)
    if (strlen(md->names[i]) == len && !strncmp(md->names[i], name, len)) {
      e->kind[c] = COL_Q, e->index[c] = i;
      return 0;
    }
  for (i = 0; i < md->nparams; i++)
    if (strlen(md->params[i].name) == len && !strncmp(md->params[i].name, name, len)) {
      e->kind[c] = COL_PARAM, e->index[c] = i;
      return 0;
    }
  for (i = 0; len > 2 && !strncmp(name, "p_", 2) && i < md->m; i++)
    if (strlen(md->names[i]) == len - 2 && !strncmp(md->names[i], name + 2, len - 2)) {
      e->kind[c] = COL_P, e->index[c] = i;
      return 0;
    }
  hbvmrt_error(md, "%sunknown column '%.*s' (a coordinate, p_ and a coordinate, or a parameter)", where, (int)len,
               name);
  return -1;
}

static int add_columns(Ens *e, int n)
{
  e->ncol = n;
  e->kind = calloc((size_t)n + 1, sizeof *e->kind);
  e->index = calloc((size_t)n + 1, sizeof *e->index);
  if (!e->kind || !e->index) {
    hbvmrt_error(e->md, "out of memory");
    return -1;
  }
  return 0;
}

/* --sweep NAME=A:B:N: N rows, NAME from A to B evenly (A alone for N = 1). */
static int read_sweep(Ens *e)
{
  const char *eq = strchr(e->sweep, '=');
  double a, b, n;
  char tail;
  long i;

  if (!eq || sscanf(eq + 1, "%lf:%lf:%lf%c", &a, &b, &n, &tail) != 3 || !isfinite(a) || !isfinite(b) ||
      n != floor(n) || n < 1) {
    hbvmrt_error(e->md, "invalid value '%s' for --sweep (expected NAME=A:B:N, N >= 1 whole)", e->sweep);
    return -1;
  }
  if (n > (double)HBVMRT_MAX_TRAJ) {
    hbvmrt_error(e->md, "--sweep: %.0f trajectories, at most %ld", n, HBVMRT_MAX_TRAJ);
    return -1;
  }
  if (add_columns(e, 1) || column(e, 0, e->sweep, (size_t)(eq - e->sweep), "--sweep: "))
    return -1;
  e->nrow = (long)n;
  if (!(e->val = calloc((size_t)e->nrow, sizeof *e->val))) {
    hbvmrt_error(e->md, "out of memory");
    return -1;
  }
  for (i = 0; i < e->nrow; i++)
    e->val[i] = e->nrow == 1 ? a : i == e->nrow - 1 ? b : a + (b - a) * (double)i / (double)(e->nrow - 1);
  return 0;
}

/* --ensemble FILE: a header of column names, then one row of numbers per
 * trajectory (table.c), each column one of column()'s. */
static int read_ensemble(Ens *e)
{
  hbvmrt_table tb;
  char where[512];
  int c, rc = -1;

  if (hbvmrt_table_read(e->md, e->file, HBVMRT_MAX_TRAJ, &tb) == 0 && add_columns(e, tb.ncol) == 0) {
    for (c = 0; c < tb.ncol; c++) {
      snprintf(where, sizeof where, "%s:%ld:%d: ", e->file, tb.header_line, tb.name_col[c]);
      if (column(e, c, tb.names[c], strlen(tb.names[c]), where) != 0)
        break;
    }
    rc = c == tb.ncol ? 0 : -1;
    e->nrow = tb.nrow;
    e->val = tb.val;
    tb.val = NULL;
  }
  hbvmrt_table_free(&tb);
  return rc;
}

/* ---- one trajectory's start and its result ---- */

/* Trajectory i's params block and initial state in w->x; its status (0, or
 * -1 off the constraints without --project, -2 projection failed). */
static int start(const Ens *e, long i, void *x, void *prm, double *g, double *hc)
{
  const hbvmrt_model *md = e->md;
  const double *row = e->val + i * e->ncol;
  double q[1024], p[1024], *qv = e->o.q0, *pv = e->o.p0, dq = 0, dp = 0;
  double tol = 64 * md->eps > HBVMRT_CONSISTENCY_TOL ? 64 * md->eps : HBVMRT_CONSISTENCY_TOL;
  int c, k, code, setq = 0, setp = 0;

  if (md->params_default)
    md->params_default(prm);
  hbvmrt_apply_params(md, &e->o, prm);
  for (c = 0; c < e->ncol; c++) {
    if (e->kind[c] == COL_PARAM)
      memcpy((char *)prm + md->params[e->index[c]].offset, &row[c], sizeof row[c]);
    setq |= e->kind[c] == COL_Q;
    setp |= e->kind[c] == COL_P;
  }
  md->init_params(x, qv, pv, prm);  /* the base values at the row's params */
  if (setq || setp) {
    memcpy(q, field(x, md->off_q), (size_t)md->m * sizeof *q);
    memcpy(p, field(x, md->off_p), (size_t)md->m * sizeof *p);
    for (c = 0; c < e->ncol; c++)
      if (e->kind[c] != COL_PARAM)
        (e->kind[c] == COL_Q ? q : p)[e->index[c]] = row[c];
    md->init_params(x, q, p, prm);
  }
  if (md->nu <= 0 || !md->project)
    return 0;
  {
    double qmax = 0, pmax = 0, gmax = 0, hmax = 0;
    char y[sizeof(double) * 4096];
    void *yb = md->state_size <= sizeof y ? y : malloc(md->state_size);
    if (!yb)
      return -2;
    for (k = 0; k < md->m; k++) {
      keep_max(&qmax, field(x, md->off_q)[k]);
      keep_max(&pmax, field(x, md->off_p)[k]);
    }
    memcpy(yb, x, md->state_size);
    code = md->project(yb, prm, &dq, &dp);
    md->constraints(x, prm, g);
    md->hidden(x, prm, hc);
    for (k = 0; k < md->nu; k++) {
      keep_max(&gmax, g[k]);
      keep_max(&hmax, hc[k]);
    }
    if (code != 0 && (e->o.project || !(gmax <= tol && hmax <= tol)))
      code = -2;
    else if (e->o.project)
      memcpy(x, yb, md->state_size), code = 0;
    else
      code = code == 0 && !(dq <= tol * qmax && dp <= tol * pmax) ? -1 : 0;
    if (yb != y)
      free(yb);
    return code;
  }
}

/* |H - H0|, |g|, |hc| of a state into the maxima of result r (g, hc: nu
 * values, stride apart). */
static void observe(const Ens *e, double *r, double H, double H0, const double *g, const double *hc, int stride)
{
  double *f = r + at_H(e->md);
  int a;

  keep_max(&f[R_DH], H - H0);
  for (a = 0; a < e->md->nu; a++) {
    keep_max(&f[R_G], g[a * stride]);
    keep_max(&f[R_HC], hc[a * stride]);
  }
}

/* One step's iterations into result r. */
static void count(const hbvmrt_model *md, double *r, long step, int iters)
{
  double *f = r + at_H(md);

  r[1] = (double)step;
  f[R_SUM] += iters;
  if (iters > f[R_MAX])
    f[R_MAX] = iters;
}

/* The final state x into result r (status and counters already there). */
static void finish(const Ens *e, double *r, const void *x, const void *prm)
{
  const hbvmrt_model *md = e->md;
  int m = md->m, nu = md->nu > 0 ? md->nu : 0;
  double *f = r + at_H(md);

  r[2] = *field(x, md->off_t);
  memcpy(r + 3, field(x, md->off_q), (size_t)m * sizeof *r);
  memcpy(r + 3 + m, field(x, md->off_p), (size_t)m * sizeof *r);
  memcpy(r + 3 + 2 * m, field(x, md->off_lambda), (size_t)nu * sizeof *r);
  f[R_H] = md->energy(x, prm);
  f[R_MEAN] = r[1] > 0 ? f[R_SUM] / r[1] : 0;
}

/* ---- running chunks ---- */

/* g and hc of the state x into w, when the model has constraints. */
static void constraints_of(const hbvmrt_model *md, Work *w, const void *x, const void *prm)
{
  if (md->nu > 0) {
    md->constraints(x, prm, w->g);
    md->hidden(x, prm, w->hc);
  }
}

/* One trajectory on the scalar path, for hbvmrt_advance's callback. */
typedef struct {
  const Ens *e;
  Work *w;                     /* its state in w->x */
  double *r, H0;               /* its result, its initial energy */
  const void *prm;
} Traj;

/* A step taken (a halved one counts as a step, as in a single run): into
 * the trajectory's counters and maxima. */
static int traj_taken(void *ctx, const hbvmrt_stats *st, double h)
{
  Traj *tr = ctx;
  const hbvmrt_model *md = tr->e->md;

  (void)h;
  count(md, tr->r, (long)tr->r[1] + 1, st->iters);
  constraints_of(md, tr->w, tr->w->x, tr->prm);
  observe(tr->e, tr->r, md->energy(tr->w->x, tr->prm), tr->H0, tr->w->g, tr->w->hc, 1);
  return 0;
}

/* A step of h that failed and is retried as halves (depth 0: the step of
 * the run's grid; deeper, its halves): counted in the trajectory's row for
 * the summary line, where a single run says it on stderr. */
static void traj_failed(void *ctx, double h, int code, int depth)
{
  Traj *tr = ctx;

  (void)h, (void)code;
  if (depth == 0)
    tr->r[at_H(tr->e->md) + R_HALVED] += 1;
}

/* A trajectory's steps from its state in w->x, as a single run of the
 * driver takes them: with --tol adaptive steps (NAME_step_adaptive, -h the
 * first) to T exactly; else steps `from`..N of h, the last shortened to end
 * on T with -T, a failed one retried as halves (hbvmrt_advance), after the
 * halves of the step fail_h that failed in a batch lane with fail_code
 * (when that is not 0). A step that fails even halved ends the trajectory,
 * its code the status. */
static void steps_scalar(Traj *tr, long from, double fail_h, int fail_code)
{
  const Ens *e = tr->e;
  const hbvmrt_model *md = e->md;
  void *x = tr->w->x;
  hbvmrt_steps cb = {NULL, traj_taken, traj_failed, NULL};
  double h = e->o.h;
  int code = 0, stopped, at_end = hbvmrt_state_time(md, x) == hbvmrt_span_end(&e->o);
  long k;

  cb.ctx = tr;
  if (e->o.tol > 0)
    while (code == 0 && !at_end) {
      hbvmrt_stats st;
      if ((code = hbvmrt_adaptive_step(md, &e->o, x, &h, tr->prm, &st, &at_end)) == 0)
        traj_taken(tr, &st, st.h);
    }
  else {
    if (fail_code != 0)
      code = hbvmrt_halve(md, x, tr->prm, fail_h, fail_code, 0, &cb, &stopped);
    for (k = from; code == 0 && k <= e->o.nsteps; k++)
      code = hbvmrt_advance(md, x, tr->prm, hbvmrt_fixed_step(md, &e->o, k, x), 0, &cb, &stopped);
  }
  if (code != 0)
    tr->r[0] = code;
  else
    hbvmrt_span_land(md, &e->o, x);
}

/* Trajectories [first, first + n) one after another. */
static void run_scalar(const Ens *e, Work *w, long first, long n)
{
  const hbvmrt_model *md = e->md;
  long i;

  for (i = first; i < first + n; i++) {
    double *r = result(e, i), H0;
    r[0] = start(e, i, w->x, w->prm, w->g, w->hc);
    H0 = md->energy(w->x, w->prm);
    if (r[0] == 0) {
      Traj tr = {e, w, r, H0, w->prm};
      constraints_of(md, w, w->x, w->prm);
      observe(e, r, H0, H0, w->g, w->hc, 1);
      steps_scalar(&tr, 1, 0, 0);
    }
    finish(e, r, w->x, w->prm);
  }
}

/* Trajectories [first, first + n), n <= W, in the lanes of one batch; the
 * lanes not used, not started or failed are idle. A lane whose step fails
 * leaves the batch and finishes on the scalar path (steps_scalar), from the
 * halves of that step on, as its single run would: the lane was left as it
 * was, and every lane is bitwise NAME_step. */
static void run_batch(const Ens *e, Work *w, long first, long n)
{
  const hbvmrt_model *md = e->md;
  int W = e->bt->w, l, live = 0, on[HBVMRT_MAX_LANES], failed[HBVMRT_MAX_LANES], done[HBVMRT_MAX_LANES];
  long k;

  for (l = 0; l < W; l++) {
    char *prm = (char *)w->prms + (size_t)l * md->params_size;
    long i = first + (l < n ? l : 0);
    int status = start(e, i, w->x, prm, w->g, w->hc);
    e->bt->set(w->b, l, w->x);
    w->H0[l] = md->energy(w->x, prm);
    if (l < n)
      result(e, i)[0] = status;
    on[l] = l < n && status == 0;
    done[l] = 0;
    e->bt->idle(w->b, l, !on[l]);
    live += on[l];
  }
  e->bt->observe(w->b, w->prms, w->Hb, w->g, w->hc);
  for (l = 0; l < n; l++)
    if (on[l])
      observe(e, result(e, first + l), w->Hb[l], w->H0[l], w->g + l, w->hc + l, W);
  for (k = 1; live > 0 && k <= e->o.nsteps; k++) {
    double h = e->o.h;
    if (k == e->o.nsteps && e->o.to_T) {  /* the last step ends on T: every live lane has the same t */
      for (l = 0; !on[l]; l++)
        ;
      e->bt->get(w->b, l, w->x);
      h = hbvmrt_fixed_step(md, &e->o, k, w->x);
    }
    e->bt->step(w->b, h, w->prms, w->code, w->iters);
    e->bt->observe(w->b, w->prms, w->Hb, w->g, w->hc);
    for (l = 0; l < n; l++) {
      failed[l] = on[l] && w->code[l] != 0;
      if (!on[l] || failed[l])
        continue;
      count(md, result(e, first + l), k, w->iters[l]);
      observe(e, result(e, first + l), w->Hb[l], w->H0[l], w->g + l, w->hc + l, W);
    }
    for (l = 0; l < n; l++)   /* after the lanes' g and hc above: the scalar path reuses them */
      if (failed[l]) {
        Traj tr = {e, w, result(e, first + l), w->H0[l], (char *)w->prms + (size_t)l * md->params_size};
        e->bt->idle(w->b, l, 1);
        on[l] = 0;
        live--;
        e->bt->get(w->b, l, w->x);
        steps_scalar(&tr, k + 1, h, w->code[l]);
        finish(e, tr.r, w->x, tr.prm);
        done[l] = 1;
      }
  }
  for (l = 0; l < n; l++) {
    char *prm = (char *)w->prms + (size_t)l * md->params_size;
    if (done[l])
      continue;  /* finished on the scalar path */
    e->bt->get(w->b, l, w->x);
    hbvmrt_span_land(md, &e->o, w->x);
    finish(e, result(e, first + l), w->x, prm);
  }
}

/* The next chunk to run, or -1: from the counter of this process, or of
 * rank 0 under MPI.  Called by one thread at a time. */
static long next_chunk(Ens *e)
{
  long c;

#ifdef HBVMRT_MPI
  long one = 1;
  MPI_Fetch_and_op(&one, &c, MPI_LONG, 0, 0, MPI_SUM, e->win);
  MPI_Win_flush(0, e->win);
#else
  c = e->next++;
#endif
  return c < e->nchunk ? c : -1;
}

static int work_alloc(const Ens *e, Work *w)
{
  const hbvmrt_model *md = e->md;
  size_t W = (size_t)(e->bt ? e->bt->w : 1), nu = (size_t)(md->nu > 0 ? md->nu : 0);

  memset(w, 0, sizeof *w);
  w->x = calloc(1, md->state_size + 1);
  w->prm = calloc(1, md->params_size + 1);
  w->prms = calloc(W, md->params_size + 1);
  w->b = calloc(1, (e->bt ? e->bt->size : 0) + 1);
  w->g = calloc(nu * W + 1, sizeof *w->g);
  w->hc = calloc(nu * W + 1, sizeof *w->hc);
  w->H0 = calloc(W, sizeof *w->H0);
  w->Hb = calloc(W, sizeof *w->Hb);
  w->code = calloc(W, sizeof *w->code);
  w->iters = calloc(W, sizeof *w->iters);
  return w->x && w->prm && w->prms && w->b && w->g && w->hc && w->H0 && w->Hb && w->code && w->iters ? 0 : -1;
}

static void work_free(Work *w)
{
  free(w->x), free(w->prm), free(w->prms), free(w->b), free(w->g), free(w->hc);
  free(w->H0), free(w->Hb), free(w->code), free(w->iters);
}

/* One thread: chunks until there are none; -1 when out of memory. */
static int worker(Ens *e)
{
  Work w;
  long c;
  int rc = work_alloc(e, &w);

  for (;;) {
#ifdef _OPENMP
#pragma omp critical(hbvmrt_next_chunk)
#endif
    c = rc == 0 ? next_chunk(e) : -1;
    if (c < 0)
      break;
    if (e->bt && !(e->o.tol > 0))  /* adaptive steps are each trajectory's own */
      run_batch(e, &w, c * e->chunk, e->nrow - c * e->chunk < e->chunk ? e->nrow - c * e->chunk : e->chunk);
    else
      run_scalar(e, &w, c * e->chunk, e->nrow - c * e->chunk < e->chunk ? e->nrow - c * e->chunk : e->chunk);
  }
  work_free(&w);
  return rc;
}

/* ---- output ---- */

/* The summary's name of input column c: a param by its name, the initial
 * value of a coordinate or momentum as x(0), p_x(0), apart from the final
 * x, p_x of the same row. */
static void input_name(const Ens *e, int c, FILE *f)
{
  const hbvmrt_model *md = e->md;

  if (e->kind[c] == COL_PARAM)
    fprintf(f, ",%s", md->params[e->index[c]].name);
  else
    fprintf(f, ",%s%s(0)", e->kind[c] == COL_P ? "p_" : "", md->names[e->index[c]]);
}

/* The summary CSV: a row per trajectory, its status, final state and
 * maxima, then the values of the input's columns (--ensemble) or the swept
 * one (--sweep), as given, so that a row says what it ran. */
static int write_results(const Ens *e, FILE *f)
{
  const hbvmrt_model *md = e->md;
  int m = md->m, nu = md->nu > 0 ? md->nu : 0, i;
  long t;

  fputs("traj,status,steps,t", f);
  for (i = 0; i < m; i++)
    fprintf(f, ",%s", md->names[i]);
  for (i = 0; i < m; i++)
    fprintf(f, ",p_%s", md->names[i]);
  for (i = 0; i < nu; i++)
    fprintf(f, ",lambda_%d", i + 1);
  fputs(",H,max_dH,max_g,max_hc,iters_mean,iters_max", f);
  for (i = 0; i < e->ncol; i++)
    input_name(e, i, f);
  fputc('\n', f);
  for (t = 0; t < e->nrow; t++) {
    const double *r = result(e, t);
    fprintf(f, "%ld,%d,%ld", t + 1, (int)r[0], (long)r[1]);
    for (i = 2; i < at_H(md) + R_SUM; i++)
      fprintf(f, ",%.17g", r[i]);
    for (i = 0; i < e->ncol; i++)
      fprintf(f, ",%.17g", e->val[t * e->ncol + i]);
    fputc('\n', f);
  }
  return ferror(f) ? -1 : 0;
}

static double now(void)
{
  struct timespec ts;

  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Run every chunk on this process's threads (and ranks); 0 or -1. */
static int run_all(Ens *e)
{
  int bad = 0;

#ifdef _OPENMP
  if (e->threads > 0)
    omp_set_num_threads(e->threads);
#pragma omp parallel reduction(| : bad)
  bad |= worker(e) != 0;
#else
  bad = worker(e) != 0;
#endif
#ifdef HBVMRT_MPI
  {                            /* each row was written by one rank: OR them */
    size_t n = (size_t)e->nrow * (size_t)e->width;
    MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
    MPI_Reduce(e->rank == 0 ? MPI_IN_PLACE : e->res, e->res, (int)n, MPI_UINT64_T, MPI_BOR, 0, MPI_COMM_WORLD);
  }
#endif
  return bad ? -1 : 0;
}

static int threads_used(const Ens *e)
{
#ifdef _OPENMP
  return e->threads > 0 ? e->threads : omp_get_max_threads();
#else
  (void)e;
  return 1;
#endif
}

/* The options (own_options, then the driver's: hbvmrt_parse_args) and the
 * input (--ensemble FILE or --sweep) into e, rest having room for argc
 * words: -1 when all is well, else the exit status (0 after --help, 1 after
 * an error). Nothing is run or written (tests/fuzz/fuzz_runtime.c calls it). */
static int prepare(Ens *e, int argc, char **argv, char **rest)
{
  const hbvmrt_model *md = e->md;
  int nrest, status;

  if (own_options(e, argc, argv, rest, &nrest) != 0)
    return 1;
  status = hbvmrt_parse_args(md, nrest, rest, &e->o);
  if (status != HBVMRT_ARGS_RUN)
    return status == HBVMRT_ARGS_DONE ? 0 : 1;
  if (e->o.dt > 0 || e->o.events || e->o.stop_event >= 0 || e->o.every != 1) {
    hbvmrt_error(md, "--%s writes rows along one run: not with --ensemble or --sweep, which write a summary row "
                 "per trajectory", e->o.dt > 0 ? "dt" : e->o.events ? "events" : e->o.stop_event >= 0 ? "stop-at" : "every");
    return 1;
  }
  if (e->o.t0 != 0 || e->o.max_steps > 0) {
    hbvmrt_error(md, "--%s is for one run: not with --ensemble or --sweep, whose trajectories start at t = 0",
                 e->o.t0 != 0 ? "t0 (or --restart)" : "max-steps");
    return 1;
  }
  if (!md->init_params || !md->names || md->m > 1024) {
    hbvmrt_error(md, "this driver cannot run ensembles (generated by an earlier hbvmgen, or m > 1024)");
    return 1;
  }
  return (e->file ? read_ensemble(e) : read_sweep(e)) != 0 ? 1 : -1;
}

/* What e holds (the parsed options, columns, rows, results). */
static void ens_free(Ens *e)
{
  hbvmrt_opts_free(&e->o);
  free(e->kind), free(e->index), free(e->val), free(e->res);
}

int hbvmrt_ensemble_main(const hbvmrt_model *md, const hbvmrt_batch *bt, int argc, char **argv)
{
  Ens e;
  char **rest = calloc((size_t)argc + 1, sizeof *rest);
  int status = 1, failed = 0;
  double t0;
  long i, halved = 0;

  memset(&e, 0, sizeof e);
  e.md = md;
  e.bt = bt;
  e.nranks = 1;
#ifdef HBVMRT_MPI
  {
    int provided;
    MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
    MPI_Comm_rank(MPI_COMM_WORLD, &e.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &e.nranks);
  }
#endif
  if (!rest || (status = prepare(&e, argc, argv, rest)) >= 0)
    goto out;
  status = 1;
  e.width = at_H(md) + R_COUNT;
  if (bt && (bt->w < 1 || bt->w > HBVMRT_MAX_LANES)) {
    hbvmrt_error(md, "a batch of %d lanes: the ensemble runner takes 1 to %d", bt->w, HBVMRT_MAX_LANES);
    goto out;
  }
  e.chunk = bt ? bt->w : HBVMRT_SCALAR_CHUNK;
  e.nchunk = (e.nrow + e.chunk - 1) / e.chunk;
  if (!(e.res = calloc((size_t)e.nrow * (size_t)e.width + 1, sizeof *e.res))) {
    hbvmrt_error(md, "out of memory");
    goto out;
  }
#ifdef HBVMRT_MPI
  MPI_Win_allocate(e.rank == 0 ? (MPI_Aint)sizeof(long) : 0, sizeof(long), MPI_INFO_NULL, MPI_COMM_WORLD, &e.counter,
                   &e.win);
  if (e.rank == 0)
    *e.counter = 0;
  MPI_Barrier(MPI_COMM_WORLD);
  MPI_Win_lock_all(0, e.win);
#endif
  t0 = now();
  if (run_all(&e) != 0) {
    hbvmrt_error(md, "out of memory");
    goto out;
  }
#ifdef HBVMRT_MPI
  MPI_Win_unlock_all(e.win);
  MPI_Win_free(&e.win);
#endif
  for (i = 0; i < e.nrow; i++) {
    failed += result(&e, i)[0] != 0;
    halved += result(&e, i)[at_H(md) + R_HALVED] > 0;
  }
  status = failed ? 2 : 0;
  if (e.rank == 0 && e.o.csv) {
    FILE *f = hbvmrt_out_open(e.o.csv);
    if (!f || write_results(&e, f) != 0 || (f != stdout ? fclose(f) : fflush(f)) != 0) {
      hbvmrt_error(md, "cannot write '%s': %s", e.o.csv, strerror(errno ? errno : EIO));
      status = 1;
    }
  }
  if (e.rank == 0) {
    fprintf(stderr, "trajectories=%ld ok=%ld failed=%d halved=%ld ", e.nrow, e.nrow - failed, failed, halved);
    if (e.o.tol > 0)
      fprintf(stderr, "tol=%g ", e.o.tol);
    else
      fprintf(stderr, "steps=%ld ", e.o.nsteps);
    fprintf(stderr, "W=%d threads=%d ranks=%d seconds=%.3g\n", bt && !(e.o.tol > 0) ? bt->w : 1, threads_used(&e),
            e.nranks, now() - t0);
  }
out:
  ens_free(&e);
  free(rest);
#ifdef HBVMRT_MPI
  MPI_Finalize();
#endif
  return status;
}
