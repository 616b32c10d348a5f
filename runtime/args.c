/* args.c - the standalone driver's options (docs/api.md, "The standalone driver").
 *
 *   NAME [-h STEP] [-T TIME | -N STEPS] [--every K] [--q0 a,b,..] [--p0 a,b,..]
 *        [--param name=value] [--project] [--csv FILE] [--tol TOL] [--dt DT]
 *        [--events FILE] [--stop-at NAME[:COUNT]] [--atol A] [--rtol R]
 *        [--tol-per time|run] [--hmax H] [--max-steps N] [--t0 T0]
 *        [--restart FILE[:ROW]] [--no-switch] [--quiet] [--help]
 *
 * Options are read left to right; a repeated option overrides the earlier one
 * (--param per name).  A value is the next argument, so `-h -0.01` works; it
 * may also be attached: `-h0.01`, `--every=10`.  Every value is checked here,
 * so the loop never meets a bad one: the first problem is reported as one line
 * `NAME: error: ...` on stderr and the driver exits with status 1. */
#define _XOPEN_SOURCE 700   /* realpath, stat */

#include <ctype.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "hbvmrt_internal.h"

typedef enum {
  OPT_STEP, OPT_TIME, OPT_STEPS, OPT_EVERY, OPT_Q0, OPT_P0, OPT_PARAM,
  OPT_CSV, OPT_QUIET, OPT_HELP, OPT_PROJECT, OPT_TOL, OPT_DT, OPT_EVENTS,
  OPT_STOP_AT, OPT_NO_SWITCH, OPT_HMAX, OPT_MAX_STEPS, OPT_ATOL, OPT_RTOL, OPT_TOL_PER,
  OPT_T0, OPT_RESTART
} OptId;

typedef struct {
  const char *name;
  OptId id;
  int takes_value;
} Option;

static const Option options[] = {
  {"-h", OPT_STEP, 1},      {"-T", OPT_TIME, 1},     {"-N", OPT_STEPS, 1},
  {"--every", OPT_EVERY, 1}, {"--q0", OPT_Q0, 1},    {"--p0", OPT_P0, 1},
  {"--param", OPT_PARAM, 1}, {"--csv", OPT_CSV, 1},  {"--quiet", OPT_QUIET, 0},
  {"--help", OPT_HELP, 0},   {"--project", OPT_PROJECT, 0},
  {"--tol", OPT_TOL, 1},      {"--dt", OPT_DT, 1},    {"--events", OPT_EVENTS, 1},
  {"--stop-at", OPT_STOP_AT, 1}, {"--no-switch", OPT_NO_SWITCH, 0},
  {"--hmax", OPT_HMAX, 1},    {"--max-steps", OPT_MAX_STEPS, 1},
  {"--atol", OPT_ATOL, 1},    {"--rtol", OPT_RTOL, 1}, {"--tol-per", OPT_TOL_PER, 1},
  {"--t0", OPT_T0, 1},        {"--restart", OPT_RESTART, 1},
};

/* What was seen on the way, for the checks that need all options. */
typedef struct {
  int have_T, have_N;
  double T;
  int have_atol, have_rtol;
} Seen;

void hbvmrt_error(const hbvmrt_model *md, const char *fmt, ...)
{
  va_list ap;

  fprintf(stderr, "%s: error: ", md->name);
  va_start(ap, fmt);
  vfprintf(stderr, fmt, ap);
  va_end(ap);
  fputc('\n', stderr);
}

/* Read a finite number at s (blanks before and after it allowed); returns
 * where the text after it starts, or NULL. */
static const char *scan_real(const char *s, double *v)
{
  char *end;

  *v = strtod(s, &end);
  if (end == s || !isfinite(*v))
    return NULL;
  while (isspace((unsigned char)*end))
    end++;
  return end;
}

/* a finite number that is all of s */
static int parse_real(const char *s, double *v)
{
  const char *end = scan_real(s, v);
  return end && *end == '\0' ? 0 : -1;
}

/* A whole number >= lo for -N and --every ("1e6" is fine, "1.5" is not). */
static int parse_count(const hbvmrt_model *md, const char *opt, const char *s,
                       long lo, long *n)
{
  double v;

  if (parse_real(s, &v) != 0 || v != floor(v)) {
    hbvmrt_error(md, "invalid value '%s' for %s (expected a whole number)",
                 s, opt);
    return -1;
  }
  if (v >= (double)LONG_MAX) {
    hbvmrt_error(md, "%s is too large (got %s)", opt, s);
    return -1;
  }
  if (v < (double)lo) {
    hbvmrt_error(md, "%s must be >= %ld (got %s)", opt, lo, s);
    return -1;
  }
  *n = (long)v;
  return 0;
}

static int parse_number(const hbvmrt_model *md, const char *opt, const char *s,
                        double *v)
{
  if (parse_real(s, v) == 0)
    return 0;
  hbvmrt_error(md, "invalid value '%s' for %s (expected a finite number)",
               s, opt);
  return -1;
}

/* A finite number > 0 for opt (--tol, --dt, --hmax, --atol, --rtol). */
static int parse_positive(const hbvmrt_model *md, const char *opt, const char *s, double *v)
{
  if (parse_number(md, opt, s, v) != 0)
    return -1;
  if (!(*v > 0)) {
    hbvmrt_error(md, "%s must be > 0 (got %s)", opt, s);
    return -1;
  }
  return 0;
}

/* --q0/--p0: exactly m comma-separated finite numbers into *out (allocated
 * on first use, overwritten when the option is repeated). */
static int parse_vector(const hbvmrt_model *md, const char *opt, const char *s,
                        double **out)
{
  const char *p = s;
  int n = 0;
  double v;

  if (!*out && !(*out = calloc((size_t)md->m + 1, sizeof **out))) {
    hbvmrt_error(md, "out of memory");
    return -1;
  }
  for (;;) {
    const char *end = scan_real(p, &v);
    if (!end || (*end != ',' && *end != '\0')) {
      hbvmrt_error(md, "invalid value '%s' for %s (expected %d finite "
                   "numbers separated by commas)", s, opt, md->m);
      return -1;
    }
    if (n < md->m)
      (*out)[n] = v;
    n++;
    if (*end == '\0')
      break;
    p = end + 1;
  }
  if (n != md->m) {
    hbvmrt_error(md, "%s needs %d value%s (m=%d), got %d", opt, md->m,
                 md->m == 1 ? "" : "s", md->m, n);
    return -1;
  }
  return 0;
}

/* The error for --param with a name the model does not have, listing the
 * names it has. */
static void unknown_param(const hbvmrt_model *md, const char *name, size_t len)
{
  int i;

  fprintf(stderr, "%s: error: unknown parameter '%.*s' ", md->name, (int)len,
          name);
  if (md->nparams == 0)
    fputs("(the model has no parameters)\n", stderr);
  for (i = 0; i < md->nparams; i++)
    fprintf(stderr, "%s%s", i ? ", " : "(parameters: ", md->params[i].name);
  if (md->nparams > 0)
    fputs(")\n", stderr);
}

/* --param name=value: the name must be one of the model's parameters. */
static int parse_param(const hbvmrt_model *md, const char *s, hbvmrt_opts *o)
{
  const char *eq = strchr(s, '=');
  size_t len;
  int i;

  if (!eq || eq == s) {
    hbvmrt_error(md, "invalid value '%s' for --param (expected name=value)", s);
    return -1;
  }
  len = (size_t)(eq - s);
  for (i = 0; i < md->nparams; i++) {
    const char *name = md->params[i].name;
    if (strlen(name) == len && strncmp(name, s, len) == 0)
      break;
  }
  if (i == md->nparams) {
    unknown_param(md, s, len);
    return -1;
  }
  if (parse_real(eq + 1, &o->param_val[i]) != 0) {
    hbvmrt_error(md, "invalid value '%s' for --param %s (expected a finite "
                 "number)", eq + 1, md->params[i].name);
    return -1;
  }
  o->param_set[i] = 1;
  return 0;
}

/* The option named by arg, with its attached value (`-h0.1`, `--every=3`)
 * in *val when there is one; NULL if arg names no option. */
static const Option *match(const char *arg, const char **val)
{
  size_t i;

  *val = NULL;
  for (i = 0; i < sizeof options / sizeof options[0]; i++) {
    const Option *op = &options[i];
    size_t n = strlen(op->name);
    if (strncmp(arg, op->name, n) != 0)
      continue;
    if (arg[n] == '\0')
      return op;
    if (op->name[1] == '-' && arg[n] == '=') {
      *val = arg + n + 1;
      return op;
    }
    if (op->name[1] != '-' && op->takes_value) {
      *val = arg + n;
      return op;
    }
  }
  return NULL;
}

/* Help's default of --q0 or --p0: all n values, or for a long vector (more
 * than HELP_VECTOR_MAX) the first few and a count, so that --help of a
 * chain of 1000 bodies stays a screen and not 40 KB of digits. */
#define HELP_VECTOR_MAX 12
#define HELP_VECTOR_HEAD 4
static void print_vector(FILE *out, const double *v, int n)
{
  int i, shown = n > HELP_VECTOR_MAX ? HELP_VECTOR_HEAD : n;

  if (!v) {
    fputs("model default", out);
    return;
  }
  for (i = 0; i < shown; i++)
    fprintf(out, "%s%.17g", i ? "," : "", v[i]);
  if (shown < n)
    fprintf(out, ",.. (the model's %d values)", n);
}

/* Usage, the model's sizes and its parameters with their defaults. */
static int print_help(const hbvmrt_model *md, FILE *out)
{
  void *prm = calloc(1, md->params_size + 1);
  int i;

  fprintf(out,
    "usage: %s [-h STEP] [-T TIME | -N STEPS] [--every K] [--q0 a,b,..]\n"
    "       %*s [--p0 a,b,..] [--param name=value] [--project] [--csv FILE]\n"
    "       %*s [--tol TOL] [--dt DT] [--events FILE] [--stop-at NAME[:COUNT]]\n"
    "       %*s [--atol A] [--rtol R] [--tol-per time|run] [--hmax H]\n"
    "       %*s [--max-steps N] [--t0 T0] [--restart FILE[:ROW]]\n"
    "       %*s [--no-switch] [--quiet]\n"
    "\n"
    "Integrates the model %s (m=%d coordinates, nu=%d constraints) with the\n"
    "HBVM(k=%d,s=%d) line integral method, N steps of the constant step h.\n"
    "\n"
    "  -h STEP            step size h, nonzero, negative to go back in time\n"
    "                     (default %g)\n"
    "  -T TIME            time span, TIME >= 0: N = ceil(TIME/|h|) steps, the\n"
    "                     last shortened to end at TIME exactly (default %g)\n"
    "  -N STEPS           number of steps N >= 0 instead of -T\n"
    "  --every K          a CSV row every K steps, K >= 1; t=0 and the last\n"
    "                     step are always written (default 1)\n"
    "  --q0 a,b,..        initial positions, %d values (default ",
    md->name, (int)strlen(md->name), "", (int)strlen(md->name), "", (int)strlen(md->name), "",
    (int)strlen(md->name), "", (int)strlen(md->name), "", md->name, md->m,
    md->nu, md->k,
    md->s, HBVMRT_DEFAULT_H, HBVMRT_DEFAULT_T, md->m);
  print_vector(out, md->q0, md->m);
  fprintf(out, ")\n  --p0 a,b,..        initial momenta, %d values (default ",
          md->m);
  print_vector(out, md->p0, md->m);
  fputs(")\n"
    "  --param name=value set a run-time parameter (repeatable)\n"
    "  --project          move q0 onto the constraints g = 0 and p0 onto the hidden\n"
    "                     constraints first, and report the change; without it,\n"
    "                     initial values off them (by more than 1e-10 relative)\n"
    "                     are refused\n"
    "  --csv FILE         write the rows t,x..,p_x..,lambda_1..,H,g_1..,hc_1.. to\n"
    "                     FILE ('-' for stdout); no CSV without it\n"
    "  --tol TOL          adaptive steps: each step's error estimate within\n"
    "                     0.01 TOL |h| (1 + max|q|), so that the error at T is\n"
    "                     about TOL T (1 + max|q|); -h is the first step, -T is\n"
    "                     hit exactly; --every K counts the steps taken;\n"
    "                     TOL >= 8 eps (1.8e-15 in double, 9.5e-7 in float:\n"
    "                     below it round-off outweighs the tolerance)\n"
    "  --atol A --rtol R  adaptive steps within 0.01 (A + R max|q|) |h| instead:\n"
    "                     absolute and relative (--tol TOL is --atol TOL\n"
    "                     --rtol TOL; --rtol alone sets A = R, --atol alone R = 0)\n"
    "  --tol-per time|run what the tolerance bounds: time (default), the error\n"
    "                     per unit time, so that the error at T is about\n"
    "                     TOL T (1 + max|q|); run, the error at T, about\n"
    "                     TOL (1 + max|q|) whatever T and its unit (TOL / T\n"
    "                     per unit time)\n"
    "  --hmax H           adaptive steps of at most H > 0 (no bound by default;\n"
    "                     a fixed -h above it is refused)\n"
    "  --max-steps N      stop after N steps (N >= 1) short of T: status 2\n"
    "  --t0 T0            the time of the initial state (default 0); the run\n"
    "                     goes to T0 + TIME\n"
    "  --restart FILE[:ROW]  start from row ROW (1 = t0's, default the last)\n"
    "                     of a CSV this driver wrote (--csv): its t, q and p\n"
    "                     (params as given; a later --t0, --q0, --p0 wins)\n"
    "  --dt DT            CSV rows at t = 0, DT, 2 DT, .. (DT > 0) whatever the\n"
    "                     steps are, each a step of the method from the start\n"
    "                     of the step containing it (as accurate as the steps),\n"
    "                     instead of a row per step (--every); at most 1e9 rows\n"
    "  --events FILE      write each event of the model when it occurs, as\n"
    "                     rows event,t,x..,p_x.. ('-' for stdout; not the\n"
    "                     --csv file), located to 1e-12 relative in t\n"
    "  --stop-at NAME[:COUNT]  end the run at the COUNT-th (default 1st)\n"
    "                     occurrence of the event NAME, its state the last\n"
    "                     state of the run\n"
    "  --no-switch        do not end steps where U or g is not smooth (a model\n"
    "                     with abs, sign, min, max, floor or mod: by default each\n"
    "                     step that crosses such a point is cut to end on it,\n"
    "                     located to 1e-12 relative in t, and the next starts\n"
    "                     afresh there; the summary counts them, switches=N)\n"
    "  --quiet            no progress line on a terminal\n"
    "  --ensemble FILE    many trajectories: FILE.csv has a header of columns\n"
    "                     (coordinates, p_ and a coordinate, params) and a row\n"
    "                     per trajectory; --csv gets a summary row for each,\n"
    "                     ending with its input columns (x(0), p_x(0), params)\n"
    "  --sweep NAME=A:B:N N trajectories, NAME (a column as above) from A to B;\n"
    "                     at most 1e7 trajectories, with --ensemble too\n"
    "  --threads N        threads for --ensemble/--sweep (OpenMP runtime only)\n"
    "  --help             this text\n", out);
  if (md->nparams > 0) {
    fputs("\nparameters (default):\n", out);
    if (prm && md->params_default)
      md->params_default(prm);
    for (i = 0; i < md->nparams; i++) {
      double v = 0;
      if (prm)
        memcpy(&v, (char *)prm + md->params[i].offset, sizeof v);
      fprintf(out, "  %s = %.17g\n", md->params[i].name, v);
    }
  }
  fputs("\nA step that fails is retried as two halves, down to h/256, on stderr\n"
    "(the first 10, then counted in one line).\n"
    "At the end, after a failed step or a write error too, one line on stderr:\n"
    "  steps=N iters_mean=X iters_max=Y max_dH=E max_g=E max_hc=E seconds=S\n"
    "  steps_rejected=R h_min=E h_max=E max_err_est=E H0=E max_dH_rel=E\n"
    "  max_defect=E defect_steps=N t=T status=WORD\n"
    "with the maxima of |H-H0|, |g_i| and |hc_i| over every step, the failed\n"
    "steps retried smaller, the smallest and largest |h| taken, the largest\n"
    "local error estimate of a step, H at t=0 and max_dH/|H0| (over |K0|+|U0|\n"
    "where H0 is round-off of it), the largest\n"
    "relative energy defect of a step and the steps where it is above\n"
    "sqrt(eps) (or --tol if larger), the time reached and how the run ended (ok, output_error,\n"
    "step_failed, event_nan, energy_defect, max_steps); a warning line before it when the\n"
    "error estimate is above 1e-3 (1 + max|q|) or steps were flagged.\n"
    "Exit status: 0 success, 1 bad arguments (inconsistent initial values\n"
    "included) or an output error, 2 a failed step or projection, or an\n"
    "event that is not a number, or --max-steps reached, 3 steps that did not\n"
    "conserve H. On a terminal a progress line: the share of the span done,\n"
    "steps per second, |H-H0| and the time left (ETA).\n", out);
  free(prm);
  if (fflush(out) != 0 || ferror(out)) {
    hbvmrt_error(md, "cannot write the help text");
    return -1;
  }
  return 0;
}

/* An option that needs what the driver may lack: -1 after saying so. */
static int needs(const hbvmrt_model *md, const char *opt, int have, const char *what)
{
  if (have)
    return 0;
  hbvmrt_error(md, "%s needs a model with %s and a driver from hbvmgen with them", opt, what);
  return -1;
}

/* --stop-at NAME[:COUNT]: an event of the model, COUNT >= 1 (default 1). */
static int parse_stop_at(const hbvmrt_model *md, const char *val, hbvmrt_opts *o)
{
  const char *colon = strchr(val, ':');
  size_t len = colon ? (size_t)(colon - val) : strlen(val);
  int i;

  if (needs(md, "--stop-at", md->nevents > 0, "events ('event NAME = ...' in the model)") != 0)
    return -1;
  o->stop_count = 1;
  if (colon && parse_count(md, "--stop-at", colon + 1, 1, &o->stop_count) != 0)
    return -1;
  for (i = 0; i < md->nevents; i++)
    if (strlen(md->event_names[i]) == len && !strncmp(md->event_names[i], val, len)) {
      o->stop_event = i;
      return 0;
    }
  fprintf(stderr, "%s: error: --stop-at: the model has no event '%.*s'; its events:", md->name, (int)len, val);
  for (i = 0; i < md->nevents; i++)
    fprintf(stderr, " %s", md->event_names[i]);
  fputc('\n', stderr);
  return -1;
}

/* The smallest --tol: 8 ulps of the solver's real type (1.8e-15 in double,
 * 9.5e-7 in float). Each step leaves a few ulps of round-off that no
 * estimate sees; below 8 ulps a tighter tol only takes more steps, each
 * adding its round-off, and the error at T grows (a float top: 2.4e-6 at
 * 1e-6, 5.7e-6 at 1e-7; a float four-bar and a double top alike, issue 31,
 * item 2). It also keeps the controller's tol |h| a normal number: a
 * subnormal tol (1e-310) made NAME_step_adaptive loop forever. */
#define HBVMRT_TOL_ULPS 8
static double min_tol(const hbvmrt_model *md)
{
  double eps = md->eps > 0 ? md->eps : DBL_EPSILON;
  return HBVMRT_TOL_ULPS * eps;
}

/* Store one option's value in o (or seen); -1 after reporting an error. */
static int apply(const hbvmrt_model *md, const Option *op, const char *val,
                 hbvmrt_opts *o, Seen *seen)
{
  switch (op->id) {
  case OPT_STEP:
    if (parse_number(md, op->name, val, &o->h) != 0)
      return -1;
    if (o->h == 0) {
      hbvmrt_error(md, "-h must be nonzero");
      return -1;
    }
    return 0;
  case OPT_TIME:
    if (parse_number(md, op->name, val, &seen->T) != 0)
      return -1;
    if (seen->T < 0) {
      hbvmrt_error(md, "-T must be >= 0 (got %s)", val);
      return -1;
    }
    seen->have_T = 1;
    return 0;
  case OPT_STEPS:
    seen->have_N = 1;
    return parse_count(md, op->name, val, 0, &o->nsteps);
  case OPT_EVERY:
    return parse_count(md, op->name, val, 1, &o->every);
  case OPT_Q0:
    return parse_vector(md, op->name, val, &o->q0);
  case OPT_P0:
    return parse_vector(md, op->name, val, &o->p0);
  case OPT_PARAM:
    return parse_param(md, val, o);
  case OPT_CSV:
    o->csv = val;
    return 0;
  case OPT_QUIET:
    o->quiet = 1;
    return 0;
  case OPT_NO_SWITCH:
    o->no_switch = 1;
    return 0;
  case OPT_PROJECT:
    o->project = 1;
    return 0;
  case OPT_TOL:
    if (parse_positive(md, op->name, val, &o->tol) != 0)
      return -1;
    if (o->tol < min_tol(md)) {
      hbvmrt_error(md, "--tol must be >= %.2g, 8 ulps of the solver's %s: below it the round-off of the steps "
                   "outweighs the tolerance, and a tighter one gives a larger error (got %s)", min_tol(md),
                   md->eps > 2 * DBL_EPSILON ? "float" : "double", val);
      return -1;
    }
    if (!md->step_adaptive) {
      hbvmrt_error(md, "--tol needs a driver generated with error control "
                   "(hbvmgen 0.1.0 or later, --main)");
      return -1;
    }
    return 0;
  case OPT_DT:
    if (parse_positive(md, op->name, val, &o->dt) != 0)
      return -1;
    return needs(md, op->name, md->dense != NULL, "dense output");
  case OPT_EVENTS:
    o->events = val;
    return needs(md, op->name, md->nevents > 0, "events ('event NAME = ...' in the model)");
  case OPT_STOP_AT:
    return parse_stop_at(md, val, o);
  case OPT_HMAX:
    return parse_positive(md, op->name, val, &o->hmax);
  case OPT_MAX_STEPS:
    return parse_count(md, op->name, val, 1, &o->max_steps);
  case OPT_ATOL:
  case OPT_RTOL:
    if (parse_positive(md, op->name, val, op->id == OPT_ATOL ? &o->atol : &o->rtol) != 0)
      return -1;
    if ((op->id == OPT_ATOL ? o->atol : o->rtol) < min_tol(md)) {
      hbvmrt_error(md, "%s must be >= %.2g, 8 ulps of the solver's %s (got %s)", op->name, min_tol(md),
                   md->eps > 2 * DBL_EPSILON ? "float" : "double", val);
      return -1;
    }
    *(op->id == OPT_ATOL ? &seen->have_atol : &seen->have_rtol) = 1;
    return needs(md, op->name, md->step_adaptive != NULL, "error control (hbvmgen 0.1.0 or later, --main)");
  case OPT_TOL_PER:
    if (strcmp(val, "time") != 0 && strcmp(val, "run") != 0) {
      hbvmrt_error(md, "--tol-per must be 'time' (the default: the tolerance per unit time) or 'run' (on the "
                   "error at T) (got '%s')", val);
      return -1;
    }
    o->tol_per_run = strcmp(val, "run") == 0;
    return 0;
  case OPT_T0:
    return parse_number(md, op->name, val, &o->t0);
  case OPT_RESTART:
    return hbvmrt_restart(md, val, o);
  case OPT_HELP:
    break;
  }
  return 0;
}

/* The tolerances once every option is read: --atol/--rtol against --tol
 * (--rtol alone: atol = rtol, as --tol; --atol alone: rtol = 0), divided by
 * the span under --tol-per run, each per unit time at least min_tol; -1
 * after reporting. */
static int finish_tol(const hbvmrt_model *md, hbvmrt_opts *o, const Seen *seen)
{
  double span = o->T;

  if ((seen->have_atol || seen->have_rtol) && o->tol > 0) {
    hbvmrt_error(md, "--tol or --atol/--rtol, not both (--tol TOL is --atol TOL --rtol TOL)");
    return -1;
  }
  if (seen->have_rtol && !seen->have_atol)
    o->atol = o->rtol;
  if (seen->have_atol || seen->have_rtol)
    o->tol = o->atol > o->rtol ? o->atol : o->rtol;  /* the nominal tol: adaptive steps */
  if (!o->tol_per_run || !(o->tol > 0))
    return 0;
  if (!(span > 0)) {
    hbvmrt_error(md, "--tol-per run needs a span -T > 0");
    return -1;
  }
  o->tol /= span;
  o->atol /= span;
  o->rtol /= span;
  if (o->tol < min_tol(md)) {
    hbvmrt_error(md, "--tol-per run: the tolerance over the span T = %g is %.2g per unit time, below %.2g, 8 ulps "
                 "of the solver's precision", span, o->tol, min_tol(md));
    return -1;
  }
  return 0;
}

/* The checks that need every option: -T against -N, N from the span, the
 * tolerances, --hmax against a fixed -h. */
static int finish(const hbvmrt_model *md, hbvmrt_opts *o, const Seen *seen)
{
  double T;

  if (seen->have_T && seen->have_N) {
    hbvmrt_error(md, "-T and -N cannot be used together");
    return -1;
  }
  if (seen->have_N && (o->tol > 0 || seen->have_atol || seen->have_rtol)) {
    hbvmrt_error(md, "--tol takes the span from -T, not -N");
    return -1;
  }
  if (o->hmax > 0 && !(o->tol > 0 || seen->have_atol || seen->have_rtol) && fabs(o->h) > o->hmax) {
    hbvmrt_error(md, "-h %g is above --hmax %g: a fixed step is -h (--hmax bounds adaptive steps)", o->h, o->hmax);
    return -1;
  }
  if (seen->have_N)
    return 0;
  T = seen->have_T ? seen->T : HBVMRT_DEFAULT_T;
  o->T = T;
  o->to_T = 1;
  /* a span T > 0 shorter than |h| is still one step (span.c) */
  o->nsteps = hbvmrt_span_steps(T, o->h);
  if (o->nsteps < 0) {
    hbvmrt_error(md, "too many steps: T/|h| = %g (at most 2^53)", T / fabs(o->h));
    return -1;
  }
  return finish_tol(md, o, seen);
}

/* Path resolved as far as it exists: its directory's real path, then its
 * last component ("F" in that directory); NULL when the directory has none. */
static char *resolved(const char *path)
{
  const char *slash = strrchr(path, '/');
  char *dir = slash ? malloc((size_t)(slash - path) + 2) : NULL, *real, *out = NULL;

  if (slash && !dir)
    return NULL;
  if (dir) {
    memcpy(dir, path, (size_t)(slash - path) + 1);
    dir[slash - path + 1] = '\0';
  }
  real = realpath(dir ? dir : ".", NULL);
  if (real && (out = malloc(strlen(real) + strlen(path) + 2)))
    sprintf(out, "%s/%s", real, slash ? slash + 1 : path);
  free(dir);
  free(real);
  return out;
}

/* Whether two output paths are one file that both would write: the same
 * text, both stdout ("-"), the same regular file when they exist (device
 * and inode: F, ./F, a link), the same directory and name when they do
 * not. Two devices (/dev/null twice) are not refused. */
static int same_output(const char *a, const char *b)
{
  struct stat sa, sb;
  char *ra, *rb;
  int same;

  if (!strcmp(a, b))
    return 1;
  if (!strcmp(a, "-") || !strcmp(b, "-"))
    return 0;
  if (stat(a, &sa) == 0 && stat(b, &sb) == 0)
    return S_ISREG(sa.st_mode) && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  ra = resolved(a);
  rb = resolved(b);
  same = ra && rb && !strcmp(ra, rb);
  free(ra);
  free(rb);
  return same;
}

/* --csv and --events: not the same file (they overwrote each other). */
static int check_outputs(const hbvmrt_model *md, const hbvmrt_opts *o)
{
  if (!o->csv || !o->events || !same_output(o->csv, o->events))
    return 0;
  hbvmrt_error(md, "--csv and --events name the same file ('%s', '%s'): give each its own", o->csv, o->events);
  return -1;
}

/* --dt against the span (-T, or N steps of h): at most HBVMRT_MAX_ROWS rows
 * (--dt 1e-300 ran forever); -1 after reporting. */
static int check_grid(const hbvmrt_model *md, const hbvmrt_opts *o)
{
  double span = o->to_T ? o->T : (double)o->nsteps * fabs(o->h);

  if (!(o->dt > 0) || span / o->dt <= HBVMRT_MAX_ROWS)
    return 0;
  hbvmrt_error(md, "--dt %g gives %.3g rows over the span %g: at most %.0e", o->dt, span / o->dt, span,
               HBVMRT_MAX_ROWS);
  return -1;
}

/* Parse argv into *o (which hbvmrt_opts_free releases in every case).
 * Returns HBVMRT_ARGS_RUN, HBVMRT_ARGS_DONE after --help, or
 * HBVMRT_ARGS_ERROR after printing the one-line error. */
int hbvmrt_parse_args(const hbvmrt_model *md, int argc, char **argv,
                      hbvmrt_opts *o)
{
  Seen seen = {0, 0, 0.0, 0, 0};
  size_t np = (size_t)(md->nparams > 0 ? md->nparams : 0) + 1;
  int i;

  memset(o, 0, sizeof *o);
  o->h = HBVMRT_DEFAULT_H;
  o->every = 1;
  o->stop_event = -1;
  o->param_val = calloc(np, sizeof *o->param_val);
  o->param_set = calloc(np, 1);
  if (!o->param_val || !o->param_set) {
    hbvmrt_error(md, "out of memory");
    return HBVMRT_ARGS_ERROR;
  }
  for (i = 1; i < argc; i++) {
    const char *arg = argv[i], *val;
    const Option *op = match(arg, &val);
    if (!op) {
      hbvmrt_error(md, "%s '%s' (try --help)", arg[0] == '-' && arg[1]
                   ? "unknown option" : "unexpected argument", arg);
      return HBVMRT_ARGS_ERROR;
    }
    if (op->id == OPT_HELP)
      return print_help(md, stdout) == 0 ? HBVMRT_ARGS_DONE
                                          : HBVMRT_ARGS_ERROR;
    if (op->takes_value && !val) {
      if (i + 1 >= argc) {
        hbvmrt_error(md, "option %s needs a value", op->name);
        return HBVMRT_ARGS_ERROR;
      }
      val = argv[++i];
    } else if (!op->takes_value && val) {
      hbvmrt_error(md, "option %s takes no value", op->name);
      return HBVMRT_ARGS_ERROR;
    }
    if (apply(md, op, val, o, &seen) != 0)
      return HBVMRT_ARGS_ERROR;
  }
  return finish(md, o, &seen) == 0 && check_grid(md, o) == 0 && check_outputs(md, o) == 0 ? HBVMRT_ARGS_RUN
                                                                                          : HBVMRT_ARGS_ERROR;
}

void hbvmrt_opts_free(hbvmrt_opts *o)
{
  free(o->q0);
  free(o->p0);
  free(o->param_val);
  free(o->param_set);
  memset(o, 0, sizeof *o);
}

/* Write the --param values into a params block already holding defaults. */
void hbvmrt_apply_params(const hbvmrt_model *md, const hbvmrt_opts *o,
                         void *prm)
{
  int i;

  for (i = 0; i < md->nparams; i++)
    if (o->param_set[i])
      memcpy((char *)prm + md->params[i].offset, &o->param_val[i],
             sizeof o->param_val[i]);
}
