/* check_runtime.c - the standalone driver's runtime (runtime/libhbvmrt.a).
 *
 * Two hand-written fake models stand in for generated code:
 *   osc   m=1 nu=0, the harmonic oscillator H = (q^2 + p^2)/2 stepped by the
 *         exact rotation, so q(t) = cos t, p(t) = -sin t from (1, 0);
 *   ring  m=2 nu=1, a free particle on the unit circle, H = k |p|^2 / 2 with
 *         the run-time parameter k, stepped by the exact rotation by k L h
 *         (L = q1 p2 - q2 p1); lambda = k |p|^2, g = |q|^2 - 1, hc = 2 q.p.
 * Each test calls hbvmrt_main with an argv built from a string, stdout and
 * stderr captured in temporary files, and checks the exit status, the CSV and
 * the summary line. */
#define _XOPEN_SOURCE 700         /* mkstemp, dup2, posix_openpt */

#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "hbvmrt.h"
#include "hbvmrt_internal.h"       /* hbvmrt_span_steps */
#include "kepler_k16s2.h"          /* a generated solver, for the energy defect */

#define HALVINGS 8              /* HBVMRT_HALVINGS of runtime/hbvmrt_internal.h */

/* --- osc: m=1, nu=0, no parameters ------------------------------------- */

typedef struct {
  double t, q[1], p[1], lambda[1];
  long n;                       /* steps taken */
} OscState;

static const double osc_q0[1] = {1.0}, osc_p0[1] = {0.0};

static void osc_init(void *x, const double *q0, const double *p0)
{
  OscState *s = x;

  memset(s, 0, sizeof *s);
  s->q[0] = q0 ? q0[0] : osc_q0[0];
  s->p[0] = p0 ? p0[0] : osc_p0[0];
}

static void osc_params_default(void *prm)
{
  (void)prm;
}

/* exact rotation; iters = 1 + n%3, so 2,3,1,2,3,1,... */
static int osc_step(void *x, double h, const void *prm, hbvmrt_stats *st)
{
  OscState *s = x;
  double c = cos(h), sn = sin(h), q = s->q[0], p = s->p[0];

  (void)prm;
  s->q[0] = c * q + sn * p;
  s->p[0] = -sn * q + c * p;
  s->t += h;
  s->n++;
  if (st) {
    st->iters = 1 + (int)(s->n % 3);
    st->increment = 0;
  }
  return 0;
}

/* as osc_step, but the sixth step fails and leaves the state alone */
static int osc_step_fail(void *x, double h, const void *prm, hbvmrt_stats *st)
{
  if (((OscState *)x)->n == 5)
    return 7;
  return osc_step(x, h, prm, st);
}

/* as osc_step, taking a millisecond: 1500 steps run 1.5 s */
static int osc_step_slow(void *x, double h, const void *prm, hbvmrt_stats *st)
{
  struct timespec ms = {0, 1000000};

  nanosleep(&ms, NULL);
  return osc_step(x, h, prm, st);
}

/* as osc_step, but every step longer than 0.06 fails */
static int osc_step_short(void *x, double h, const void *prm, hbvmrt_stats *st)
{
  if (fabs(h) > 0.06)
    return 7;
  return osc_step(x, h, prm, st);
}

/* as osc_step, reporting a local error estimate of 0.5 on the third step
 * (1e-6 on the others) and a relative energy defect of 0.3 on the fifth
 * (0 on the others) */
static int osc_step_estimated(void *x, double h, const void *prm, hbvmrt_stats *st)
{
  int rc = osc_step(x, h, prm, st);
  long n = ((OscState *)x)->n;

  st->err_est = n == 3 ? 0.5 : 1e-6;
  st->defect = n == 5 ? 0.3 : 0;
  return rc;
}

/* an adaptive step of osc (the step proposed kept), each with a relative
 * energy defect of 1e-6 */
static int osc_step_adaptive(void *x, double *h, double tol, const void *prm, hbvmrt_stats *st)
{
  int rc = osc_step(x, *h, prm, st);

  (void)tol;
  st->h = *h;
  st->defect = 1e-6;
  return rc;
}

static const char *osc_strerror(int code)
{
  return code == 7 ? "did not converge" : "unknown";
}

static double osc_energy(const void *x, const void *prm)
{
  const OscState *s = x;

  (void)prm;
  return 0.5 * (s->q[0] * s->q[0] + s->p[0] * s->p[0]);
}

static const hbvmrt_model osc = {
  "osc", 1, 0, 2, 2,
  sizeof(OscState), 0,
  offsetof(OscState, t), offsetof(OscState, q), offsetof(OscState, p),
  offsetof(OscState, lambda),
  0, NULL,
  osc_q0, osc_p0,
  osc_init, osc_params_default, osc_step, osc_strerror, osc_energy,
  NULL, NULL,                   /* nu = 0: never called */
  NULL,                         /* no names: the numbered CSV header */
  NULL, NULL, 0,                /* as a driver of hbvmgen 0.1: no projection */
  NULL,                         /* nor error control */
  NULL, 0, NULL, NULL, NULL,    /* nor dense output and events */
  NULL                          /* nor a time of its own (--t0: written at off_t) */
};

/* --- kepler_k16s2: the generated solver of models/kepler.ham (k = 16) ---- */

static void kep_init(void *x, const double *q0, const double *p0) { kepler_k16s2_init(x, q0, p0); }
static void kep_params_default(void *prm) { kepler_k16s2_params_default(prm); }
static double kep_energy(const void *x, const void *prm) { return kepler_k16s2_energy(x, prm); }

/* emit_main.c's adapter of NAME_step */
static int kep_step(void *x, double h, const void *prm, hbvmrt_stats *st)
{
  kepler_k16s2_stats s;
  int rc = kepler_k16s2_step(x, h, prm, &s);

  st->iters = s.iters;
  st->increment = s.increment;
  st->err_est = s.err_est;
  st->defect = s.defect;
  return rc;
}

static const hbvmrt_model kepler = {
  "kepler", kepler_k16s2_M, 0, kepler_k16s2_K, kepler_k16s2_S,
  sizeof(kepler_k16s2_state), sizeof(kepler_k16s2_params),
  offsetof(kepler_k16s2_state, t), offsetof(kepler_k16s2_state, q), offsetof(kepler_k16s2_state, p),
  offsetof(kepler_k16s2_state, lambda),
  0, NULL, NULL, NULL,
  kep_init, kep_params_default, kep_step, kepler_k16s2_strerror, kep_energy,
  NULL, NULL, NULL, NULL, NULL, DBL_EPSILON,
  NULL, NULL, 0, NULL, NULL, NULL, NULL
};

/* --- ring: m=2, nu=1, parameter k ---------------------------------------- */

typedef struct {
  double t, q[2], p[2], lambda[1];
} RingState;

typedef struct {
  double k;
} RingParams;

static const hbvmrt_param ring_params[] = {{"k", offsetof(RingParams, k)}};
static const double ring_q0[2] = {1.0, 0.0}, ring_p0[2] = {0.0, 1.0};

static double ring_k(const void *prm)
{
  return prm ? ((const RingParams *)prm)->k : 1.0;
}

static void ring_init(void *x, const double *q0, const double *p0)
{
  RingState *s = x;

  memset(s, 0, sizeof *s);
  memcpy(s->q, q0 ? q0 : ring_q0, sizeof s->q);
  memcpy(s->p, p0 ? p0 : ring_p0, sizeof s->p);
  s->lambda[0] = s->p[0] * s->p[0] + s->p[1] * s->p[1];
}

static void ring_params_default(void *prm)
{
  ((RingParams *)prm)->k = 1.0;
}

static void rotate(double *v, double c, double sn)
{
  double a = v[0], b = v[1];

  v[0] = c * a - sn * b;
  v[1] = sn * a + c * b;
}

static int ring_step(void *x, double h, const void *prm, hbvmrt_stats *st)
{
  RingState *s = x;
  double k = ring_k(prm), L = s->q[0] * s->p[1] - s->q[1] * s->p[0];
  double c = cos(k * L * h), sn = sin(k * L * h);

  rotate(s->q, c, sn);
  rotate(s->p, c, sn);
  s->lambda[0] = k * (s->p[0] * s->p[0] + s->p[1] * s->p[1]);
  s->t += h;
  if (st)
    st->iters = 4;
  return 0;
}

static const char *ring_strerror(int code)
{
  (void)code;
  return "unknown";
}

static double ring_energy(const void *x, const void *prm)
{
  const RingState *s = x;

  return 0.5 * ring_k(prm) * (s->p[0] * s->p[0] + s->p[1] * s->p[1]);
}

static void ring_constraints(const void *x, const void *prm, double *g)
{
  const RingState *s = x;

  (void)prm;
  g[0] = s->q[0] * s->q[0] + s->q[1] * s->q[1] - 1.0;
}

static void ring_hidden(const void *x, const void *prm, double *gp)
{
  const RingState *s = x;

  (void)prm;
  gp[0] = 2.0 * (s->q[0] * s->p[0] + s->q[1] * s->p[1]);
}

static const hbvmrt_model ring = {
  "ring", 2, 1, 3, 2,
  sizeof(RingState), sizeof(RingParams),
  offsetof(RingState, t), offsetof(RingState, q), offsetof(RingState, p),
  offsetof(RingState, lambda),
  1, ring_params,
  ring_q0, ring_p0,
  ring_init, ring_params_default, ring_step, ring_strerror, ring_energy,
  ring_constraints, ring_hidden,
  NULL,
  NULL, NULL, 0,
  NULL,
  NULL, 0, NULL, NULL, NULL, NULL
};

/* ring with the fields of hbvmgen 0.2 drivers: init at the run's params
 * and the projection onto |q| = 1, q.p = 0 (code 3 at q = 0). */
static void ringp_init_params(void *x, const double *q0, const double *p0, const void *prm)
{
  (void)prm;
  ring_init(x, q0, p0);
}

static int ringp_project(void *x, const void *prm, double *dq, double *dp)
{
  RingState *s = x;
  double r = hypot(s->q[0], s->q[1]), q[2], qp;
  int i;

  (void)prm;
  if (r == 0)
    return 3;
  q[0] = s->q[0] / r;
  q[1] = s->q[1] / r;
  qp = q[0] * s->p[0] + q[1] * s->p[1];
  *dq = *dp = 0;
  for (i = 0; i < 2; i++) {
    *dq = fmax(*dq, fabs(q[i] - s->q[i]));
    *dp = fmax(*dp, fabs(qp * q[i]));
    s->q[i] = q[i];
    s->p[i] -= qp * q[i];
  }
  return 0;
}

/* ring as a driver with those fields */
static hbvmrt_model ring_projecting(void)
{
  hbvmrt_model md = ring;

  md.name = "ringp";
  md.init_params = ringp_init_params;
  md.project = ringp_project;
  md.eps = 2.220446049250313e-16;
  return md;
}

/* --- running the driver ---------------------------------------------------- */

/* What one hbvmrt_main call left behind. */
typedef struct {
  int status;
  char *out, *err, *csv;        /* stdout, stderr, the --csv @ file */
} Result;

static char *slurp(const char *path)
{
  FILE *f = fopen(path, "rb");
  char *buf;
  long n;

  ck_assert_ptr_nonnull(f);
  fseek(f, 0, SEEK_END);
  n = ftell(f);
  rewind(f);
  buf = calloc(1, (size_t)n + 1);
  ck_assert_ptr_nonnull(buf);
  ck_assert_int_eq(fread(buf, 1, (size_t)n, f), n);
  fclose(f);
  return buf;
}

static void temp_path(char *path)
{
  int fd;

  strcpy(path, "/tmp/check_runtime_XXXXXX");
  fd = mkstemp(path);
  ck_assert_int_ge(fd, 0);
  close(fd);
}

/* Point fd (1 or 2) at path; returns a copy of the old fd to restore. */
static int redirect(int fd, const char *path)
{
  FILE *f = fopen(path, "w");
  int saved = dup(fd);

  ck_assert_ptr_nonnull(f);
  ck_assert_int_ge(saved, 0);
  ck_assert_int_ge(dup2(fileno(f), fd), 0);
  fclose(f);
  return saved;
}

static void restore(int fd, int saved)
{
  ck_assert_int_ge(dup2(saved, fd), 0);
  close(saved);
}

/* A pseudo-terminal for stderr: returns the master's fd and the slave's in
 * *slave, or -1 where there is none. */
static int open_tty(int *slave)
{
  int master = posix_openpt(O_RDWR | O_NOCTTY);

  if (master < 0)
    return -1;
  if (grantpt(master) != 0 || unlockpt(master) != 0 ||
      (*slave = open(ptsname(master), O_RDWR | O_NOCTTY)) < 0) {
    close(master);
    return -1;
  }
  return master;
}

/* All the master has until the slave side is closed. */
static char *drain_tty(int master)
{
  size_t len = 0, cap = 4096;
  char *buf = malloc(cap);
  ssize_t n;

  ck_assert_ptr_nonnull(buf);
  while ((n = read(master, buf + len, cap - len - 1)) > 0 ||
         (n < 0 && errno == EINTR)) {
    len += n > 0 ? (size_t)n : 0;
    if (cap - len < 2) {
      buf = realloc(buf, cap *= 2);
      ck_assert_ptr_nonnull(buf);
    }
  }
  buf[len] = '\0';
  close(master);
  return buf;
}

/* Run model md with the options in cmd (split at blanks; an argument ending
 * in "@" has it replaced by a temporary CSV file), capturing stdout, and
 * stderr in a file or, with tty, on a pseudo-terminal (in which case the
 * caller must have checked that open_tty works). */
static Result run_on(const hbvmrt_model *md, const char *cmd, int tty)
{
  char csv[64], out[64], err[64], buf[512], args[32][96], *argv[32], *tok;
  int argc = 0, save_out, save_err, master = -1, slave = -1;
  Result r;

  temp_path(csv);
  temp_path(out);
  temp_path(err);
  ck_assert_uint_lt(strlen(cmd), sizeof buf);
  strcpy(buf, cmd);
  argv[argc++] = (char *)md->name;
  for (tok = strtok(buf, " "); tok; tok = strtok(NULL, " ")) {
    size_t n = strlen(tok);
    ck_assert_int_lt(argc, 31);
    if (tok[n - 1] == '@') {
      snprintf(args[argc], sizeof args[argc], "%.*s%s", (int)n - 1, tok, csv);
      tok = args[argc];
    }
    argv[argc++] = tok;
  }
  argv[argc] = NULL;

  fflush(stdout);
  fflush(stderr);
  save_out = redirect(1, out);
  if (tty) {
    master = open_tty(&slave);
    ck_assert_int_ge(master, 0);
    save_err = dup(2);
    ck_assert_int_ge(dup2(slave, 2), 0);
    close(slave);
  } else {
    save_err = redirect(2, err);
  }
  r.status = hbvmrt_main(md, argc, argv);
  fflush(stdout);
  fflush(stderr);
  restore(1, save_out);
  restore(2, save_err);

  r.out = slurp(out);
  r.err = tty ? drain_tty(master) : slurp(err);
  r.csv = slurp(csv);
  unlink(csv);
  unlink(out);
  unlink(err);
  return r;
}

static Result run(const hbvmrt_model *md, const char *cmd)
{
  return run_on(md, cmd, 0);
}

static void done(Result *r)
{
  free(r->out);
  free(r->err);
  free(r->csv);
}

static int count_lines(const char *s)
{
  int n = 0;

  for (; *s; s++)
    n += *s == '\n';
  return n;
}

/* Value in data row `row` (0 = first after the header), column `col`. */
static double cell(const char *csv, int row, int col)
{
  const char *p = csv;
  char *end;
  double v;
  int i;

  for (i = 0; i <= row; i++) {
    p = strchr(p, '\n');
    ck_assert_msg(p != NULL, "no row %d", row);
    p++;
  }
  for (i = 0; i < col; i++) {
    p = strpbrk(p, ",\n");
    ck_assert_msg(p && *p == ',', "no column %d in row %d", col, row);
    p++;
  }
  v = strtod(p, &end);
  ck_assert_msg(end != p && (*end == ',' || *end == '\n'),
                "bad value in row %d column %d", row, col);
  return v;
}

/* The summary line's fields. */
typedef struct {
  long steps;
  double iters_mean;
  int iters_max;
  double max_dH, max_g, max_hc, seconds;
  long rejected;
  double h_min, h_max;
} Summary;

static Summary summary_of(const char *err)
{
  const char *p = strstr(err, "steps=");
  Summary s;

  ck_assert_msg(p != NULL, "no summary in: %s", err);
  ck_assert_msg(p == err || p[-1] == '\n', "summary not at a line start");
  ck_assert_int_eq(sscanf(p, "steps=%ld iters_mean=%lf iters_max=%d "
                          "max_dH=%lf max_g=%lf max_hc=%lf seconds=%lf "
                          "steps_rejected=%ld h_min=%lf h_max=%lf",
                          &s.steps, &s.iters_mean, &s.iters_max, &s.max_dH,
                          &s.max_g, &s.max_hc, &s.seconds, &s.rejected,
                          &s.h_min, &s.h_max), 10);
  ck_assert_ptr_eq(strchr(p, '\n'), p + strlen(p) - 1);
  return s;
}

/* The summary line's field NAME= (after the fixed ones above) as a number. */
static double summary_field(const char *err, const char *name)
{
  const char *p = strstr(err, "steps=");
  char key[64], *end;
  double v;

  ck_assert_ptr_nonnull(p);
  snprintf(key, sizeof key, " %s=", name);
  p = strstr(p, key);
  ck_assert_msg(p != NULL, "no %s in the summary: %s", name, err);
  v = strtod(p + strlen(key), &end);
  ck_assert_msg(end != p + strlen(key) && (*end == ' ' || *end == '\n'), "bad %s in: %s", name, err);
  return v;
}

/* Whether the summary line says status=WORD. */
static int summary_status(const char *err, const char *word)
{
  const char *p = strstr(err, " status=");
  size_t n = strlen(word);

  return p && strncmp(p + 8, word, n) == 0 && p[8 + n] == '\n';
}

/* --- tests ----------------------------------------------------------------- */

START_TEST(header_nu0)
{
  Result r = run(&osc, "-N 1 --csv @");

  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(strncmp(r.csv, "t,q1,p1,H\n", 10), 0);
  done(&r);
}
END_TEST

START_TEST(header_nu1)
{
  Result r = run(&ring, "-N 1 --csv @");

  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(strncmp(r.csv, "t,q1,q2,p1,p2,lam1,H,g1,hc1\n", 28), 0);
  done(&r);
}
END_TEST

/* with the model's coordinate names, as generated drivers give them */
START_TEST(header_names)
{
  static const char *const names[] = {"x", "r[2]"};
  static const char want[] = "t,x,r[2],p_x,p_r[2],lambda_1,H,g_1,hc_1\n0,1,0,";
  hbvmrt_model named = ring;
  Result r;

  named.names = names;
  r = run(&named, "-N 1 --csv @");
  ck_assert_int_eq(r.status, 0);
  ck_assert_msg(strncmp(r.csv, want, strlen(want)) == 0, "header and first row: %.60s", r.csv);
  done(&r);
}
END_TEST

/* rows for -N/--every: t=0, every K-th step, and the last step */
static const struct {
  const char *cmd;
  int rows;
  double last_t;
} row_cases[] = {
  {"-h 0.1 -N 10 --csv @", 11, 1.0},
  {"-h 0.1 -N 10 --every 3 --csv @", 5, 1.0},
  {"-h 0.1 -N 9 --every 3 --csv @", 4, 0.9},
  {"-h 0.1 -N 10 --every 10 --csv @", 2, 1.0},
  {"-h 0.1 -N 10 --every 20 --csv @", 2, 1.0},
  {"-h 0.1 -N 1 --every 100 --csv @", 2, 0.1},
  {"-h 0.1 -N 0 --csv @", 1, 0.0},
  {"-h 0.1 -N 0 --every 5 --csv @", 1, 0.0},
  {"-h 0.1 -T 1 --csv @", 11, 1.0},
  {"-h 0.3 -T 1 --csv @", 5, 1.0},   /* the last step shortened to 0.1 */
  {"-h 0.1 -T 0.3 --csv @", 4, 0.3},
  {"-h -0.1 -T 1 --csv @", 11, -1.0},
  {"-T 0 --csv @", 1, 0.0},
  {"--csv @", 1001, 10.0},      /* defaults h = 0.01, T = 10 */
  {"-N10 --every=5 -h0.1 --csv=@", 3, 1.0},
};

START_TEST(rows)
{
  Result r = run(&osc, row_cases[_i].cmd);

  ck_assert_msg(r.status == 0, "%s: status %d, %s", row_cases[_i].cmd,
                r.status, r.err);
  ck_assert_int_eq(count_lines(r.csv), 1 + row_cases[_i].rows);
  ck_assert_double_eq(cell(r.csv, 0, 0), 0.0);
  ck_assert_double_eq_tol(cell(r.csv, row_cases[_i].rows - 1, 0),
                          row_cases[_i].last_t, 1e-12);
  done(&r);
}
END_TEST

START_TEST(values_read_back)
{
  Result r = run(&osc, "-h 0.1 -N 20 --every 4 --csv @");
  int i;

  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(count_lines(r.csv), 1 + 6);
  for (i = 0; i < 6; i++) {
    double t = cell(r.csv, i, 0);
    ck_assert_double_eq_tol(t, 0.4 * i, 1e-12);
    ck_assert_double_eq_tol(cell(r.csv, i, 1), cos(t), 1e-12);
    ck_assert_double_eq_tol(cell(r.csv, i, 2), -sin(t), 1e-12);
    ck_assert_double_eq_tol(cell(r.csv, i, 3), 0.5, 1e-14);
  }
  done(&r);
}
END_TEST

/* %.17g: the t=0 row holds exactly the initial values given */
START_TEST(values_exact)
{
  Result r = run(&osc, "-N 0 --q0 0.1 --p0 -0.30000000000000004 --csv @");

  ck_assert_int_eq(r.status, 0);
  ck_assert_double_eq(cell(r.csv, 0, 1), 0.1);
  ck_assert_double_eq(cell(r.csv, 0, 2), -0.30000000000000004);
  done(&r);
}
END_TEST

START_TEST(summary_nu0)
{
  Result r = run(&osc, "-h 0.1 -N 10");
  Summary s = summary_of(r.err);

  ck_assert_int_eq(r.status, 0);
  ck_assert_str_eq(r.out, "");
  ck_assert_int_eq(count_lines(r.err), 1);
  ck_assert_int_eq(s.steps, 10);
  ck_assert_double_eq(s.iters_mean, 2.0);     /* 2,3,1,2,3,1,2,3,1,2 */
  ck_assert_int_eq(s.iters_max, 3);
  ck_assert_double_le(s.max_dH, 1e-14);
  ck_assert_ptr_nonnull(strstr(r.err, " max_g=0 max_hc=0 "));
  ck_assert_double_ge(s.seconds, 0.0);
  done(&r);
}
END_TEST

/* the maxima of |g| and |hc|, with q0 off the constraint */
START_TEST(summary_nu1)
{
  Result r = run(&ring, "-h 0.1 -N 7 --q0 0,-2 --p0 0.5,0.25");
  Summary s = summary_of(r.err);

  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(s.steps, 7);
  ck_assert_double_eq(s.iters_mean, 4.0);
  ck_assert_int_eq(s.iters_max, 4);
  ck_assert_double_eq(s.max_g, 3.0);          /* |q|^2 - 1 on radius 2 */
  ck_assert_double_eq(s.max_hc, 1.0);         /* |2 q.p| */
  ck_assert_double_le(s.max_dH, 1e-14);
  done(&r);
}
END_TEST

/* osc whose energy is off by 0.25 after step 3 only */
static double osc_energy_spike(const void *x, const void *prm)
{
  return osc_energy(x, prm) + (((const OscState *)x)->n == 3 ? 0.25 : 0.0);
}

/* the maxima cover every step, not only the rows written */
START_TEST(summary_every_step)
{
  hbvmrt_model spiky = osc;
  Result r;

  spiky.energy = osc_energy_spike;
  r = run(&spiky, "-h 0.1 -N 7 --every 5 --csv @");
  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(count_lines(r.csv), 1 + 3);              /* 0 5 7 */
  ck_assert_double_eq_tol(summary_of(r.err).max_dH, 0.25, 1e-14);
  done(&r);
}
END_TEST

START_TEST(ring_default_run)
{
  Result r = run(&ring, "-h 0.25 -N 4 --csv @");
  int i;

  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(count_lines(r.csv), 1 + 5);
  for (i = 0; i < 5; i++) {
    double t = cell(r.csv, i, 0);
    ck_assert_double_eq_tol(cell(r.csv, i, 1), cos(t), 1e-12);
    ck_assert_double_eq_tol(cell(r.csv, i, 2), sin(t), 1e-12);
    ck_assert_double_eq_tol(cell(r.csv, i, 5), 1.0, 1e-12);   /* lam1 */
    ck_assert_double_eq_tol(cell(r.csv, i, 6), 0.5, 1e-12);   /* H */
    ck_assert_double_eq_tol(cell(r.csv, i, 7), 0.0, 1e-12);   /* g1 */
    ck_assert_double_eq_tol(cell(r.csv, i, 8), 0.0, 1e-12);   /* hc1 */
  }
  done(&r);
}
END_TEST

START_TEST(param_changes_model)
{
  Result r = run(&ring, "-h 0.25 -N 4 --param k=2 --csv @");
  double t;

  ck_assert_int_eq(r.status, 0);
  ck_assert_double_eq_tol(cell(r.csv, 0, 6), 1.0, 1e-15);     /* H = k/2 */
  ck_assert_double_eq_tol(cell(r.csv, 4, 5), 2.0, 1e-12);     /* lam1 = k */
  t = cell(r.csv, 4, 0);
  ck_assert_double_eq_tol(cell(r.csv, 4, 1), cos(2 * t), 1e-12);
  ck_assert_double_eq_tol(cell(r.csv, 4, 2), sin(2 * t), 1e-12);
  done(&r);
}
END_TEST

START_TEST(param_last_wins)
{
  Result r = run(&ring, "-N 0 --param k=2 --param=k=3 --csv @");

  ck_assert_int_eq(r.status, 0);
  ck_assert_double_eq_tol(cell(r.csv, 0, 6), 1.5, 1e-15);
  done(&r);
}
END_TEST

/* only --q0: p0 is the model default, and the other way round */
START_TEST(q0_alone)
{
  Result r = run(&ring, "-N 0 --q0 0,1 --csv @");

  ck_assert_int_eq(r.status, 0);
  ck_assert_double_eq(cell(r.csv, 0, 1), 0.0);
  ck_assert_double_eq(cell(r.csv, 0, 2), 1.0);
  ck_assert_double_eq(cell(r.csv, 0, 3), 0.0);
  ck_assert_double_eq(cell(r.csv, 0, 4), 1.0);
  ck_assert_double_eq(cell(r.csv, 0, 8), 2.0);                /* hc = 2 q.p */
  done(&r);
  r = run(&ring, "-N 0 --p0 3,-4 --csv @");
  ck_assert_int_eq(r.status, 0);
  ck_assert_double_eq(cell(r.csv, 0, 1), 1.0);
  ck_assert_double_eq(cell(r.csv, 0, 2), 0.0);
  ck_assert_double_eq(cell(r.csv, 0, 3), 3.0);
  ck_assert_double_eq(cell(r.csv, 0, 4), -4.0);
  ck_assert_double_eq(cell(r.csv, 0, 6), 12.5);
  done(&r);
}
END_TEST

START_TEST(csv_to_stdout)
{
  Result r = run(&osc, "-h 0.1 -N 3 --csv -");

  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(strncmp(r.out, "t,q1,p1,H\n0,1,0,0.5\n", 20), 0);
  ck_assert_int_eq(count_lines(r.out), 5);
  ck_assert_int_eq(count_lines(r.err), 1);
  done(&r);
}
END_TEST

START_TEST(no_csv)
{
  Result r = run(&osc, "-N 5 --quiet");

  ck_assert_int_eq(r.status, 0);
  ck_assert_str_eq(r.out, "");
  ck_assert_str_eq(r.csv, "");
  done(&r);
}
END_TEST

/* as osc_step, a solver of --iteration auto: Newton (4 iterations, one
 * factorisation) in the steps after the second */
static int osc_step_newton(void *x, double h, const void *prm, hbvmrt_stats *st)
{
  int rc = osc_step(x, h, prm, st);

  if (st && ((OscState *)x)->n > 2) {
    st->newton = 4;
    st->factors = st->jacobians = 1;
  }
  return rc;
}

/* The summary says which solver ran (issue 27): fixed where no step took
 * Newton, with no counts; fixed+newton when some did (--iteration auto),
 * with the counts summed. */
START_TEST(summary_solver)
{
  hbvmrt_model aut = osc;
  Result r = run(&osc, "-h 0.1 -N 4");

  ck_assert_ptr_nonnull(strstr(r.err, " solver=fixed t="));
  done(&r);
  aut.step = osc_step_newton;
  r = run(&aut, "-h 0.1 -N 2");
  ck_assert_ptr_nonnull(strstr(r.err, " solver=fixed t="));
  done(&r);
  r = run(&aut, "-h 0.1 -N 5");
  ck_assert_ptr_nonnull(strstr(r.err, " solver=fixed+newton newton_steps=3 newton_iters=12 factors=3 jacobians=3 t="));
  done(&r);
}
END_TEST

/* The summary tells the truth (issue 31 item 4): the largest local error
 * estimate, H0 and the relative energy error, where and how the run ended;
 * an estimate above 1e-3 (1 + max|q|) is warned about; a step whose energy
 * defect is far above round-off (0.3 > sqrt(eps)) is flagged, warned about,
 * exit status 3. */
START_TEST(summary_truth)
{
  hbvmrt_model est = osc;
  Result r = run(&osc, "-h 0.1 -N 4");

  ck_assert_int_eq(r.status, 0);
  ck_assert_double_eq(summary_field(r.err, "max_err_est"), 0);
  ck_assert_double_eq(summary_field(r.err, "H0"), 0.5);
  ck_assert_double_eq_tol(summary_field(r.err, "max_dH_rel"), summary_of(r.err).max_dH / 0.5,
                          1e-3 * summary_of(r.err).max_dH / 0.5);
  ck_assert_double_eq(summary_field(r.err, "defect_steps"), 0);
  ck_assert_double_eq_tol(summary_field(r.err, "t"), 0.4, 1e-15);
  ck_assert(summary_status(r.err, "ok"));
  ck_assert_int_eq(count_lines(r.err), 1);
  done(&r);
  est.step = osc_step_estimated;
  r = run(&est, "-h 0.1 -N 4");   /* the estimate of step 3, no defect yet */
  ck_assert_int_eq(r.status, 0);
  ck_assert_double_eq(summary_field(r.err, "max_err_est"), 0.5);
  ck_assert_ptr_nonnull(strstr(r.err, "osc: warning: the largest local error estimate of a step, 5.000e-01, is "
                               "above 0.001 (1 + max|q|)"));
  ck_assert(summary_status(r.err, "ok"));
  ck_assert_int_eq(count_lines(r.err), 2);
  done(&r);
  r = run(&est, "-h 0.1 -N 6");   /* and the defect of step 5 */
  ck_assert_int_eq(r.status, 3);
  ck_assert_double_eq(summary_field(r.err, "max_defect"), 0.3);
  ck_assert_double_eq(summary_field(r.err, "defect_steps"), 1);
  ck_assert_ptr_nonnull(strstr(r.err, "osc: warning: 1 step did not conserve H: relative energy defect up to "
                               "3.000e-01"));
  ck_assert(summary_status(r.err, "energy_defect"));
  ck_assert_int_eq(count_lines(r.err), 3);
  done(&r);
  /* under --tol the defect is flagged above the tolerance only: the step's
   * estimate holds it within tol */
  est.step_adaptive = osc_step_adaptive;
  r = run(&est, "--tol 1e-4 -h 0.1 -T 1");
  ck_assert_int_eq(r.status, 0);
  ck_assert_double_eq(summary_field(r.err, "max_defect"), 1e-6);
  ck_assert(summary_status(r.err, "ok"));
  done(&r);
  r = run(&est, "--tol 1e-8 -h 0.1 -T 1");
  ck_assert_int_eq(r.status, 3);
  ck_assert_double_eq(summary_field(r.err, "defect_steps"), 10);
  ck_assert_ptr_nonnull(strstr(r.err, "take a smaller --tol (exit status 3)"));
  done(&r);
}
END_TEST

/* osc's energy less 1/2: H0 = 0 exactly from q = 0, p = 1 (K0 = 1/2, U0 = -1/2) */
static double osc_energy_shifted(const void *x, const void *prm)
{
  return osc_energy(x, prm) - 0.5;
}

/* max_dH_rel where H0 is round-off: over |K0| + |U0| (1 here), where max_dH / |H0|
 * said inf (H0 = 0; the satellites' H0 = 3e-17 gave 5). Forty rotations leave
 * max_dH at round-off, not 0. */
START_TEST(summary_relative_to_energy_size)
{
  hbvmrt_model zero = osc;
  Result r;

  zero.energy = osc_energy_shifted;
  r = run(&zero, "-h 0.1 -N 40 --q0 0 --p0 1");
  ck_assert_int_eq(r.status, 0);
  ck_assert_double_eq(summary_field(r.err, "H0"), 0);
  ck_assert_double_gt(summary_of(r.err).max_dH, 0);
  ck_assert_double_eq_tol(summary_field(r.err, "max_dH_rel"), summary_of(r.err).max_dH,
                          1e-3 * summary_of(r.err).max_dH);
  done(&r);
}
END_TEST

/* Issue 30 item 5: Kepler (k = 16) at h = 300 converged to steps whose
 * quadrature does not resolve H, |H - H0| = 1.456, and exited 0. Its steps'
 * energy defect (NAME_stats.defect) now flags the run: exit status 3. At
 * h = 0.1 every step keeps H to round-off (max_defect 4e-16 measured; at
 * most 16 ulps allowed), exit 0. */
START_TEST(kepler_energy_defect)
{
  Result r = run(&kepler, "-h 300 -T 3000");

  ck_assert_int_eq(r.status, 3);
  ck_assert(summary_status(r.err, "energy_defect"));
  ck_assert_double_gt(summary_field(r.err, "max_dH_rel"), 1);
  ck_assert_double_gt(summary_field(r.err, "max_defect"), 0.1);
  ck_assert_double_eq(summary_field(r.err, "H0"), -0.5);
  ck_assert_ptr_nonnull(strstr(r.err, "kepler: warning: 1 step did not conserve H"));
  done(&r);
  r = run(&kepler, "-h 0.1 -T 100");
  ck_assert_int_eq(r.status, 0);
  ck_assert(summary_status(r.err, "ok"));
  ck_assert_double_le(summary_field(r.err, "max_defect"), 16 * DBL_EPSILON);
  ck_assert_double_le(summary_field(r.err, "max_err_est"), 1e-3);
  ck_assert_int_eq(count_lines(r.err), 1);
  done(&r);
}
END_TEST

/* Per-step messages stop at 10, then one line counts the rest: every step
 * of 0.1 fails and is retried (one line each: 100 before). */
START_TEST(messages_rate_limited)
{
  hbvmrt_model shortish = osc;
  Result r;

  shortish.step = osc_step_short;
  r = run(&shortish, "-h 0.1 -N 100");
  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(summary_of(r.err).rejected, 100);
  ck_assert_ptr_nonnull(strstr(r.err, "osc: 90 more such messages not shown (at most 10 are)\n"));
  ck_assert_int_eq(count_lines(r.err), 10 + 1 + 1);
  done(&r);
}
END_TEST

START_TEST(step_failure)
{
  const char *want =
    "osc: step h=0.1 failed at t=0.5 (did not converge): retrying with "
    "halved steps\nosc: error: step failed at t=0.5: did not converge\n"
    "steps=5 ";
  hbvmrt_model failing = osc;
  Result r;

  failing.step = osc_step_fail;
  r = run(&failing, "-h 0.1 -N 10 --csv @");
  ck_assert_int_eq(r.status, 2);
  ck_assert_int_eq(count_lines(r.csv), 1 + 6);                /* t=0..0.5 */
  ck_assert_double_eq_tol(cell(r.csv, 5, 0), 0.5, 1e-12);
  ck_assert_int_eq(strncmp(r.err, want, strlen(want)), 0);
  ck_assert_int_eq(summary_of(r.err).steps, 5);
  ck_assert_int_eq(summary_of(r.err).rejected, 1 + HALVINGS);
  ck_assert_int_eq(count_lines(r.err), 3);
  ck_assert(summary_status(r.err, "step_failed"));
  ck_assert_double_eq_tol(summary_field(r.err, "t"), 0.5, 1e-15);
  done(&r);
}
END_TEST

/* a fixed step that fails is retried in halves, on the same grid: the rows
 * stay at multiples of h, the summary counts the failures and the sizes */
START_TEST(step_retried)
{
  hbvmrt_model shortish = osc;
  Result r;
  Summary s;

  shortish.step = osc_step_short;
  r = run(&shortish, "-h 0.1 -N 3 --csv @");
  s = summary_of(r.err);
  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(count_lines(r.csv), 1 + 4);
  ck_assert_double_eq_tol(cell(r.csv, 3, 0), 0.3, 1e-15);
  ck_assert_double_eq_tol(cell(r.csv, 3, 1), cos(0.3), 1e-14);
  ck_assert_int_eq(s.steps, 6);
  ck_assert_int_eq(s.rejected, 3);
  ck_assert_double_eq_tol(s.h_min, 0.05, 1e-15);
  ck_assert_double_eq_tol(s.h_max, 0.05, 1e-15);
  ck_assert_int_eq(count_lines(r.err), 3 + 1);
  ck_assert_ptr_nonnull(strstr(r.err, "osc: step h=0.1 failed at t=0.2 (did "
                               "not converge): retrying with halved steps\n"));
  done(&r);
}
END_TEST

/* The number of steps of a span, hbvmrt_span_steps(T, h): the least N with
 * N |h| >= T up to a sliver s = 1e-9 |h| + 8 eps T (round-off of T and N h),
 * so that the last step, T - (N-1) |h|, is neither 0 nor a sliver (s < last
 * <= |h| + s), also past 2^24 steps, where ceil(T/|h| - 1e-9) counted one
 * step too many (-h 0.01 -T 262144.03: 26214404, the last step 0 after
 * 26214403). */
START_TEST(span_steps)
{
  static const struct {
    double T, h;
    long n;
  } known[] = {{262144.03, 0.01, 26214403}, {1, 0.3, 4}, {1, 0.1, 10}, {10, 0.01, 1000}, {100, 0.3, 334},
               {0, 0.1, 0}, {0.05, 0.1, 1}, {1, -0.1, 10}, {1e-300, 1, 1}, {7.7, 2.1, 4}};
  unsigned long seed = 12345;
  int i;

  for (i = 0; i < (int)(sizeof known / sizeof known[0]); i++)
    ck_assert_msg(hbvmrt_span_steps(known[i].T, known[i].h) == known[i].n, "T=%.17g h=%g: %ld steps, not %ld",
                  known[i].T, known[i].h, hbvmrt_span_steps(known[i].T, known[i].h), known[i].n);
  ck_assert_int_eq(hbvmrt_span_steps(1e300, 1e-300), -1);       /* too many to count */
  for (i = 0; i < 200000; i++) {           /* T = k h + a rest of decimals, up to 2^40 steps */
    double h, T, last, sliver;
    long n;
    seed = seed * 6364136223846793005UL + 1442695040888963407UL;
    h = (double)(1 + (seed >> 40) % 999) / 1000.0;
    T = ldexp((double)((seed >> 20) % 1000000) / 1e6 + 1, (int)(seed % 40)) * h + (double)((seed >> 8) % 100) / 100.0;
    n = hbvmrt_span_steps(T, h);
    last = fma(-(double)(n - 1), h, T);
    sliver = 1e-9 * h + 8 * DBL_EPSILON * T;
    ck_assert_msg(n >= 1 && last > sliver && last <= h + sliver, "T=%.17g h=%.17g: %ld steps, the last %g", T, h, n,
                  last);
  }
}
END_TEST

/* -T is hit exactly: the last step is shortened (0.3, 0.3, 0.3, 0.1) */
START_TEST(span_hit_exactly)
{
  Result r = run(&osc, "-h 0.3 -T 1 --csv @");
  Summary s = summary_of(r.err);

  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(count_lines(r.csv), 1 + 5);
  ck_assert_double_eq_tol(cell(r.csv, 4, 0), 1.0, 1e-15);
  ck_assert_double_eq_tol(cell(r.csv, 4, 1), cos(1.0), 1e-14);
  ck_assert_int_eq(s.steps, 4);
  ck_assert_double_eq_tol(s.h_min, 0.1, 1e-14);
  ck_assert_double_eq_tol(s.h_max, 0.3, 1e-15);
  done(&r);
  r = run(&osc, "-h -0.3 -T 1 --csv @");                  /* backwards */
  ck_assert_int_eq(r.status, 0);
  ck_assert_double_eq_tol(cell(r.csv, 4, 0), -1.0, 1e-15);
  done(&r);
  r = run(&osc, "-h 0.3 -N 4 --csv @");                   /* -N: N steps of h */
  ck_assert_double_eq_tol(cell(r.csv, 4, 0), 1.2, 1e-15);
  done(&r);
}
END_TEST

/* the state the failed step left is the last row, even between K's */
START_TEST(step_failure_every)
{
  hbvmrt_model failing = osc;
  Result r;

  failing.step = osc_step_fail;
  r = run(&failing, "-h 0.1 -N 10 --every 2 --csv @");
  ck_assert_int_eq(r.status, 2);
  ck_assert_int_eq(count_lines(r.csv), 1 + 4);                /* 0 2 4 5 */
  ck_assert_double_eq_tol(cell(r.csv, 3, 0), 0.5, 1e-12);
  ck_assert_double_eq_tol(cell(r.csv, 2, 0), 0.4, 1e-12);
  done(&r);
}
END_TEST

/* bad arguments: one line `NAME: error: ...`, status 1, no CSV written */
static const struct {
  const hbvmrt_model *md;
  const char *cmd;
} bad_cases[] = {
  {&osc, "-h 0 --csv @"},
  {&osc, "-h abc --csv @"},
  {&osc, "-h 0.1x --csv @"},
  {&osc, "-h inf --csv @"},
  {&osc, "-h nan --csv @"},
  {&osc, "-h 1e999 --csv @"},
  {&osc, "--csv @ -h"},
  {&osc, "-N -1 --csv @"},
  {&osc, "-N 1.5 --csv @"},
  {&osc, "-N ten --csv @"},
  {&osc, "-N 1e30 --csv @"},
  {&osc, "-T -1 --csv @"},
  {&osc, "-T nan --csv @"},
  {&osc, "-T 1 -N 5 --csv @"},
  {&osc, "-N 5 -T 1 --csv @"},
  {&osc, "-T 1e300 -h 1e-300 --csv @"},
  {&osc, "--every 0 --csv @"},
  {&osc, "--every -3 --csv @"},
  {&osc, "--q0 1,2 --csv @"},
  {&osc, "--p0 1, --csv @"},
  {&osc, "--p0 , --csv @"},
  {&ring, "--q0 1 --csv @"},
  {&ring, "--q0 1,2,3 --csv @"},
  {&ring, "--p0 1;2 --csv @"},
  {&ring, "--p0 1,,2 --csv @"},
  {&ring, "--q0 1,nan --csv @"},
  {&ring, "--param nope=1 --csv @"},
  {&ring, "--param k --csv @"},
  {&ring, "--param =1 --csv @"},
  {&ring, "--param k=two --csv @"},
  {&ring, "--param k=inf --csv @"},
  {&ring, "--param kk=1 --csv @"},
  {&osc, "--param k=1 --csv @"},
  {&osc, "--bogus --csv @"},
  {&osc, "--every5 --csv @"},
  {&osc, "--quiet=1 --csv @"},
  {&osc, "stray --csv @"},
  {&osc, "- --csv @"},
  {&osc, "-x 1 --csv @"},
  {&osc, "--csv /nonexistent-dir/x.csv"},
  {&osc, "--tol 1e-8 --csv @"},           /* no step_adaptive: an old driver */
};

START_TEST(bad_args)
{
  Result r = run(bad_cases[_i].md, bad_cases[_i].cmd);
  char prefix[32];

  snprintf(prefix, sizeof prefix, "%s: error: ", bad_cases[_i].md->name);
  ck_assert_msg(r.status == 1, "'%s': status %d", bad_cases[_i].cmd,
                r.status);
  ck_assert_msg(strncmp(r.err, prefix, strlen(prefix)) == 0 &&
                count_lines(r.err) == 1 && r.err[strlen(r.err) - 1] == '\n',
                "'%s': stderr is '%s'", bad_cases[_i].cmd, r.err);
  ck_assert_str_eq(r.out, "");
  ck_assert_str_eq(r.csv, "");
  done(&r);
}
END_TEST

START_TEST(disk_full)
{
  Result r;

  if (access("/dev/full", W_OK) != 0)
    return;                     /* not on this system */
  r = run(&osc, "-h 0.1 -N 10 --csv /dev/full");
  ck_assert_int_eq(r.status, 1);
  ck_assert_ptr_nonnull(strstr(r.err, "osc: error: cannot write '/dev/full'"));
  ck_assert_int_eq(summary_of(r.err).steps, 10);
  done(&r);
  /* large enough to fail inside the loop, not only at fclose */
  r = run(&osc, "-h 0.1 -N 100000 --csv /dev/full");
  ck_assert_int_eq(r.status, 1);
  ck_assert_int_eq(count_lines(r.err), 2);
  ck_assert_int_lt(summary_of(r.err).steps, 100000);
  ck_assert(summary_status(r.err, "output_error"));
  done(&r);
}
END_TEST

/* Past the file size limit (ulimit -f) a write fails as on a full disk:
 * reported, exit status 1, where the driver died of SIGXFSZ (status 153 in
 * a shell), without a word. Run in a child, whose limit is 8 KiB. */
START_TEST(file_size_limit)
{
  static const char *const outs[] = {"--csv @", "--csv - --quiet"};
  char cmd[128];
  Result r;
  pid_t pid;
  int status, fd;

  snprintf(cmd, sizeof cmd, "-h 0.01 -N 10000 %s", outs[_i]);
  fflush(stdout);
  fflush(stderr);
  pid = fork();
  ck_assert_int_ge(pid, 0);
  if (pid == 0) {
    struct rlimit lim = {8192, 8192};
    setrlimit(RLIMIT_FSIZE, &lim);
    r = run(&osc, cmd);
    fd = open("/tmp/check_runtime_fsize", O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd >= 0) {
      ssize_t n = write(fd, r.err, strlen(r.err) < 4000 ? strlen(r.err) : 4000);
      (void)n;
      close(fd);
    }
    _exit(r.status);
  }
  ck_assert_int_eq(waitpid(pid, &status, 0), pid);
  ck_assert_msg(WIFEXITED(status), "the driver died of signal %d", WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  ck_assert_int_eq(WEXITSTATUS(status), 1);
  r.err = slurp("/tmp/check_runtime_fsize");
  unlink("/tmp/check_runtime_fsize");
  ck_assert_msg(strstr(r.err, "osc: error: cannot write '") && strstr(r.err, strerror(EFBIG)), "%s", r.err);
  free(r.err);
}
END_TEST

/* Initial values off the constraints: refused (status 1, the sizes named)
 * by a driver that can project, run as they are by an older one, projected
 * with --project (reported, g and hc zero at t = 0); a projection that fails
 * is status 2; values off by round-off only run unchanged. */
START_TEST(inconsistent_start)
{
  const hbvmrt_model ringp = ring_projecting();
  Result r = run(&ringp, "--q0 1.1,0 --p0 0.5,1 -N 2 --csv @");
  ck_assert_int_eq(r.status, 1);
  ck_assert_msg(strstr(r.err, "ringp: error: the initial values are off the constraints: max|g(q0)| = 2.100e-01, "
                              "max|hidden(q0, p0)| = 1.100e+00") && strstr(r.err, "--project"), "%s", r.err);
  ck_assert_str_eq(r.csv, "");
  done(&r);
  r = run(&ring, "--q0 1.1,0 -N 2");
  ck_assert_int_eq(r.status, 0);
  done(&r);
  r = run(&ringp, "--q0 1.1,0 --p0 0.5,1 -N 2 --project --csv @");
  ck_assert_int_eq(r.status, 0);
  ck_assert_msg(strstr(r.err, "ringp: projected the initial values onto the constraints: max|g(q0)| = 2.100e-01, "
                              "max|hidden(q0, p0)| = 1.100e+00; q moved by 1.000e-01, p by 5.000e-01\n"), "%s", r.err);
  ck_assert(cell(r.csv, 0, 1) == 1 && cell(r.csv, 0, 3) == 0 && cell(r.csv, 0, 7) == 0 && cell(r.csv, 0, 8) == 0);
  done(&r);
  r = run(&ringp, "--q0 0,0 -N 2 --project");
  ck_assert_int_eq(r.status, 2);
  ck_assert_msg(strstr(r.err, "ringp: error: cannot project the initial values onto the constraints"), "%s", r.err);
  done(&r);
  r = run(&ringp, "--q0 0.6,0.8 --p0 -0.8,0.6 -N 2 --csv @");
  ck_assert_int_eq(r.status, 0);
  ck_assert(cell(r.csv, 0, 1) == 0.6 && cell(r.csv, 0, 4) == 0.6);
  done(&r);
}
END_TEST

/* An ensemble's column is looked up by its exact name first: a param p_x
 * (which a driver from before hbvmgen refused the name may have) is that
 * param, where --sweep p_x set the momentum of x (so the start, off the
 * constraint q.p = 0, was refused: status -1). Here it is ring's k = 2, the
 * rate of the rotation: x = cos 0.2 after a step of 0.1. */
static const hbvmrt_param px_param[] = {{"p_x", offsetof(RingParams, k)}};
static const char *const ring_names[] = {"x", "y"};

START_TEST(column_exact_name)
{
  hbvmrt_model md = ring_projecting();
  Result r;

  md.names = ring_names;
  md.params = px_param;
  r = run(&md, "--sweep p_x=2:2:1 -h 0.1 -N 1 --csv @");
  ck_assert_msg(r.status == 0, "status %d: %s", r.status, r.err);
  ck_assert_int_eq(strncmp(r.csv, "traj,status,steps,t,x,y,p_x,p_y,", 32), 0);
  ck_assert_double_eq(cell(r.csv, 0, 1), 0);
  ck_assert_double_eq_tol(cell(r.csv, 0, 4), cos(0.2), 1e-15);
  done(&r);
}
END_TEST

START_TEST(help)
{
  Result r = run(&ring, "--help");

  ck_assert_int_eq(r.status, 0);
  ck_assert_str_eq(r.err, "");
  ck_assert_int_eq(strncmp(r.out, "usage: ring ", 12), 0);
  ck_assert_ptr_nonnull(strstr(r.out, "-h STEP"));
  ck_assert_ptr_nonnull(strstr(r.out, "-T TIME"));
  ck_assert_ptr_nonnull(strstr(r.out, "-N STEPS"));
  ck_assert_ptr_nonnull(strstr(r.out, "--every K"));
  ck_assert_ptr_nonnull(strstr(r.out, "--param name=value"));
  ck_assert_ptr_nonnull(strstr(r.out, "--csv FILE"));
  ck_assert_ptr_nonnull(strstr(r.out, "--quiet"));
  ck_assert_ptr_nonnull(strstr(r.out, "m=2 "));
  ck_assert_ptr_nonnull(strstr(r.out, "nu=1 "));
  ck_assert_ptr_nonnull(strstr(r.out, "k=3,s=2"));
  ck_assert_ptr_nonnull(strstr(r.out, "end at TIME exactly"));
  ck_assert_ptr_nonnull(strstr(r.out, "--tol TOL"));
  ck_assert_ptr_nonnull(strstr(r.out, "  k = 1\n"));
  ck_assert_ptr_nonnull(strstr(r.out, "default 1,0)"));     /* q0 */
  done(&r);
  r = run(&osc, "-N 3 --help --csv @");                      /* no run */
  ck_assert_int_eq(r.status, 0);
  ck_assert_str_eq(r.csv, "");
  ck_assert_ptr_null(strstr(r.out, "parameters"));
  done(&r);
}
END_TEST

/* A long q0 and p0 (m = 20 here; 1000 on a chain of 500 pairs, 40 KB of
 * digits before) are shown by their first values and a count. Fails on a
 * driver that prints them whole. */
START_TEST(help_long_vectors)
{
  static const double v[20] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20};
  hbvmrt_model md = ring;
  Result r;

  md.m = 20;
  md.q0 = md.p0 = v;
  r = run(&md, "--help");
  ck_assert_int_eq(r.status, 0);
  ck_assert_ptr_nonnull(strstr(r.out, "initial positions, 20 values (default 1,2,3,4,.. (the model's 20 values))"));
  ck_assert_ptr_nonnull(strstr(r.out, "initial momenta, 20 values (default 1,2,3,4,.. (the model's 20 values))"));
  ck_assert_ptr_null(strstr(r.out, ",5,"));
  done(&r);
}
END_TEST

/* A run of 1.5 s with stderr on a file: no progress line, the summary */
START_TEST(no_progress_off_terminal)
{
  hbvmrt_model slow = osc;
  Result r;

  slow.step = osc_step_slow;
  r = run(&slow, "-N 1500");
  ck_assert_int_eq(r.status, 0);
  ck_assert_ptr_null(strchr(r.err, '\r'));
  ck_assert_int_eq(count_lines(r.err), 1);
  ck_assert_int_eq(summary_of(r.err).steps, 1500);
  done(&r);
}
END_TEST

/* The same on a terminal: progress lines (\r, percent, steps/s, |H-H0|),
 * cleared before the summary; none with --quiet. */
START_TEST(progress_on_terminal)
{
  hbvmrt_model slow = osc;
  int slave, master = open_tty(&slave);
  const char *last;
  Result r;

  if (master < 0)
    return;                     /* no pseudo-terminals here */
  close(master);
  close(slave);
  slow.step = osc_step_slow;
  r = run_on(&slow, "-N 1500", 1);
  ck_assert_int_eq(r.status, 0);
  ck_assert_msg(strstr(r.err, "\rosc: ") != NULL, "no progress: %s", r.err);
  ck_assert_ptr_nonnull(strstr(r.err, "% "));
  ck_assert_ptr_nonnull(strstr(r.err, " steps/s "));
  ck_assert_ptr_nonnull(strstr(r.err, "|H-H0|="));
  /* the clearing, \r blanks \r, then the summary (its \n is \r\n here) */
  last = strstr(r.err, "steps=1500 ");
  ck_assert_ptr_nonnull(last);
  ck_assert_int_eq(*--last, '\r');
  while (last > r.err && last[-1] == ' ')
    last--;
  ck_assert_int_eq(last[-1], '\r');
  ck_assert_ptr_null(strchr(strstr(r.err, "steps="), '%'));
  done(&r);

  r = run_on(&slow, "-N 1500 --quiet", 1);
  ck_assert_int_eq(r.status, 0);
  ck_assert_int_eq(strncmp(r.err, "steps=1500 ", 11), 0);
  ck_assert_int_eq(count_lines(r.err), 1);
  done(&r);
}
END_TEST

Suite *runtime_suite(void)
{
  Suite *s = suite_create("runtime");
  TCase *csv = tcase_create("csv");
  TCase *args = tcase_create("args");
  TCase *run_ = tcase_create("run");

  tcase_add_test(csv, header_nu0);
  tcase_add_test(csv, header_nu1);
  tcase_add_test(csv, header_names);
  tcase_add_loop_test(csv, rows, 0,
                      (int)(sizeof row_cases / sizeof row_cases[0]));
  tcase_add_test(csv, values_read_back);
  tcase_add_test(csv, values_exact);
  tcase_add_test(csv, csv_to_stdout);
  tcase_add_test(csv, no_csv);
  tcase_add_test(csv, disk_full);
  tcase_add_loop_test(csv, file_size_limit, 0, 2);
  suite_add_tcase(s, csv);

  tcase_add_loop_test(args, bad_args, 0,
                      (int)(sizeof bad_cases / sizeof bad_cases[0]));
  tcase_add_test(args, param_changes_model);
  tcase_add_test(args, param_last_wins);
  tcase_add_test(args, q0_alone);
  tcase_add_test(args, help);
  tcase_add_test(args, help_long_vectors);
  tcase_add_test(args, column_exact_name);
  suite_add_tcase(s, args);

  tcase_add_test(run_, summary_nu0);
  tcase_add_test(run_, summary_nu1);
  tcase_add_test(run_, summary_every_step);
  tcase_add_test(run_, ring_default_run);
  tcase_add_test(run_, inconsistent_start);
  tcase_add_test(run_, summary_truth);
  tcase_add_test(run_, summary_relative_to_energy_size);
  tcase_add_test(run_, summary_solver);
  tcase_add_test(run_, kepler_energy_defect);
  tcase_add_test(run_, messages_rate_limited);
  tcase_add_test(run_, step_failure);
  tcase_add_test(run_, step_failure_every);
  tcase_add_test(run_, step_retried);
  tcase_add_test(run_, span_hit_exactly);
  tcase_add_test(run_, span_steps);
  tcase_add_test(run_, no_progress_off_terminal);
  tcase_add_test(run_, progress_on_terminal);
  tcase_set_timeout(run_, 30);
  suite_add_tcase(s, run_);
  return s;
}
