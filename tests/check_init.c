/* check_init.c - consistent initial values (NAME_project, NAME_init_params)
 * and the float interface, as a user meets them.
 *
 *   - a standalone driver of models/pendulum.ham refuses --q0 0,-1.1 with a
 *     message naming the sizes and a nonzero status; with --project it
 *     starts with |g| and the hidden constraint <= 1e-14 and keeps H; the
 *     same for a --param that makes the model's q0 inconsistent, and a q0
 *     written with the params follows them (lambda too); a --real float
 *     driver does the same in float;
 *   - NAME_project moves perturbed states of the double pendulum and the
 *     chain (both multiplier families) onto g = 0 and the hidden constraint
 *     to round-off, and a failed projection leaves the state byte for byte;
 *   - the float interface takes and returns float.
 * The suite is init_suite(); the project's runner (check_main.c) adds it. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "chain_const_k2s2.h"
#include "chain_poly_k2s2.h"
#include "double_pendulum_const_k2s2.h"
#include "double_pendulum_k2s2.h"
#include "kepler_k2s2.h"
#include "polyfloat_k3s3.h"

Suite *init_suite(void);

/* ---- standalone drivers, generated and built into a temporary directory ---- */

/* A pendulum of length L under gravity G whose q0 follows L... */
static const char pendulum_of_params[] = "param L = 1.5\nparam G = 1\nvariables x, y\nU = G * y\n"
                                         "g = x^2 + y^2 - L^2\nq0 = [0, -L]\np0 = [1, 0]\n";
/* ... and one whose q0 was written for L = 1.5 only. */
static const char pendulum_fixed_q0[] = "param L = 1.5\nvariables x, y\nU = y\ng = x^2 + y^2 - L^2\n"
                                        "q0 = [0, -1.5]\np0 = [1, 0]\n";

static char dir[64];

static int sh(const char *cmd)
{
  int rc = system(cmd);
  return rc == -1 || !WIFEXITED(rc) ? -1 : WEXITSTATUS(rc);
}

/* Generate NAME (from model, a path, or the text src) with flags and build
 * its driver against runtime/libhbvmrt.a, warning-free. */
static void build(const char *name, const char *model, const char *src, const char *flags)
{
  char cmd[2048], path[256];
  if (src) {
    snprintf(path, sizeof path, "%s/%s.ham", dir, name);
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fputs(src, f);
    fclose(f);
    model = path;
  }
  const char *san = getenv("HBVM_SANITIZED") && *getenv("HBVM_SANITIZED")
                        ? "-fsanitize=address,undefined -fno-omit-frame-pointer" : "";
  snprintf(cmd, sizeof cmd,
           "../gen/hbvmgen %s --main -n %s -o %s %s 2>/dev/null && cc -O2 -std=c99 -Wall -Wextra -pedantic -Werror %s "
           "-I../runtime -I%s %s/%s.c %s/%s_main.c ../runtime/libhbvmrt.a -lm -o %s/%s",
           flags, name, dir, model, san, dir, dir, name, dir, name, dir, name);
  ck_assert_msg(sh(cmd) == 0, "cannot build: %s", cmd);
}

/* What a run of a driver left: its status, stderr, the CSV's first row. */
typedef struct {
  int status;
  char err[4096];
  double row[16];
  int ncols;
} Run;

/* Run dir/name with args, the CSV of t = 0 in r->row. */
static Run run(const char *name, const char *args)
{
  Run r;
  char cmd[1024], path[128], line[1024];
  snprintf(cmd, sizeof cmd, "%s/%s %s --quiet --csv %s/out.csv 2>%s/err.txt", dir, name, args, dir, dir);
  memset(&r, 0, sizeof r);
  r.status = sh(cmd);
  snprintf(path, sizeof path, "%s/err.txt", dir);
  FILE *f = fopen(path, "r");
  ck_assert_ptr_nonnull(f);
  size_t n = fread(r.err, 1, sizeof r.err - 1, f);
  r.err[n] = '\0';
  fclose(f);
  snprintf(path, sizeof path, "%s/out.csv", dir);
  if ((f = fopen(path, "r"))) {
    if (fgets(line, sizeof line, f) && fgets(line, sizeof line, f))
      for (char *p = line; r.ncols < 16 && *p && *p != '\n'; r.ncols++) {
        char *end;
        r.row[r.ncols] = strtod(p, &end);
        p = *end == ',' ? end + 1 : end;
      }
    fclose(f);
  }
  return r;
}

/* The summary's max_dH. */
static double max_dH(const Run *r)
{
  const char *p = strstr(r->err, "max_dH=");
  ck_assert_msg(p != NULL, "no summary: %s", r->err);
  return strtod(p + 7, NULL);
}

static void setup_dir(void)
{
  strcpy(dir, "/tmp/hbvm-init-XXXXXX");
  ck_assert_ptr_nonnull(mkdtemp(dir));
}

static void remove_dir(void)
{
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  ck_assert_int_eq(sh(cmd), 0);
}

/* Row t,x,y,p_x,p_y,lambda_1,H,g_1,hc_1 at t = 0 on the constraints. */
static void assert_consistent_row(const Run *r, double tol)
{
  ck_assert_int_eq(r->ncols, 9);
  ck_assert_msg(fabs(r->row[7]) <= tol && fabs(r->row[8]) <= tol, "t = 0: |g| = %.3e, |hidden| = %.3e", r->row[7],
                r->row[8]);
}

/* _i: double, float. models/pendulum.ham from q0 = (0, -1.1): refused,
 * then projected with --project and H kept from there. */
START_TEST(driver_refuses_or_projects)
{
  static const char *const flags[2] = {"-s 2", "-s 2 --real float"};
  const double tol[2] = {1e-14, 4 * FLT_EPSILON};
  setup_dir();
  build("pendulum", "../models/pendulum.ham", NULL, flags[_i]);
  Run r = run("pendulum", "--q0 0,-1.1 -h 0.01 -T 10");
  ck_assert_int_ne(r.status, 0);
  ck_assert_msg(strstr(r.err, "pendulum: error: the initial values are off the constraints: max|g(q0)| = 2.100e-01") &&
                    strstr(r.err, "--project"), "%s", r.err);
  r = run("pendulum", "--q0 0,-1.1 -h 0.01 -T 10 --project");
  ck_assert_msg(r.status == 0, "%s", r.err);
  ck_assert_msg(strstr(r.err, "pendulum: projected the initial values onto the constraints: max|g(q0)| = 2.100e-01") &&
                    strstr(r.err, "q moved by 1.000e-01"), "%s", r.err);
  assert_consistent_row(&r, tol[_i]);
  ck_assert_msg(fabs(r.row[2] + 1) <= tol[_i], "y = %.17g after the projection", r.row[2]);
  ck_assert_msg(max_dH(&r) <= tol[_i], "max_dH %.3e after the projection", max_dH(&r));
  r = run("pendulum", "-h 0.01 -T 1");
  ck_assert_msg(r.status == 0 && !strstr(r.err, "projected"), "%s", r.err);
  remove_dir();
}
END_TEST

/* --param L=2: a q0 written for L = 1.5 is refused or projected like --q0; a
 * q0 written with L follows it, and lambda is computed with the run's params. */
START_TEST(driver_params_make_q0)
{
  setup_dir();
  build("fixed", NULL, pendulum_fixed_q0, "-s 2");
  build("follows", NULL, pendulum_of_params, "-s 2");
  Run r = run("fixed", "--param L=2");
  ck_assert_int_ne(r.status, 0);
  ck_assert_msg(strstr(r.err, "fixed: error: the initial values are off the constraints: max|g(q0)| = 1.750e+00"), "%s",
                r.err);
  r = run("fixed", "--param L=2 --project");
  ck_assert_msg(r.status == 0, "%s", r.err);
  assert_consistent_row(&r, 1e-14);
  ck_assert_msg(fabs(r.row[2] + 2) <= 1e-15 && max_dH(&r) <= 1e-14, "y = %.17g, max_dH = %.3e", r.row[2], max_dH(&r));
  r = run("follows", "--param L=2 --param G=2 -T 1");
  ck_assert_msg(r.status == 0 && !strstr(r.err, "projected"), "%s", r.err);
  ck_assert_msg(r.row[2] == -2, "q0 = [0, -L] at L = 2 gives y = %.17g", r.row[2]);
  /* (G' M^-1 G) lambda = v' Hess g v - G' M^-1 grad U = 2 |p|^2 + 2 G L, G' M^-1 G = 4 L^2 */
  ck_assert_msg(fabs(r.row[5] - 10.0 / 16) <= 1e-15, "lambda at t = 0: %.17g, want 0.625", r.row[5]);
  remove_dir();
}
END_TEST

/* ---- NAME_project on the committed solvers ---- */

/* The adapters of a solver with prefix P under one interface. */
typedef struct {
  const char *name;
  int m, nu;
  size_t size;
  void (*init)(void *x);
  int (*project)(void *x, double *dq, double *dp);
  double *(*q)(void *x), *(*p)(void *x);
  void (*g)(const void *x, double *g), (*hidden)(const void *x, double *hc);
  double (*energy)(const void *x);
  int (*step)(void *x, double h);
} Proj;

#define PROJ_ADAPT(P)                                                                                              \
  static void P##_i(void *x) { P##_init(x, NULL, NULL); }                                                          \
  static int P##_pr(void *x, double *dq, double *dp) { return P##_project(x, NULL, dq, dp); }                     \
  static double *P##_q(void *x) { return ((P##_state *)x)->q; }                                                   \
  static double *P##_p(void *x) { return ((P##_state *)x)->p; }                                                   \
  static void P##_gg(const void *x, double *g) { P##_constraints(x, NULL, g); }                                   \
  static void P##_hc(const void *x, double *hc) { P##_hidden(x, NULL, hc); }                                      \
  static double P##_en(const void *x) { return P##_energy(x, NULL); }                                              \
  static int P##_st(void *x, double h) { return P##_step(x, h, NULL, NULL); }
#define PROJ_ENTRY(P) {#P, P##_M, P##_NU, sizeof(P##_state), P##_i, P##_pr, P##_q, P##_p, P##_gg, P##_hc, P##_en, P##_st},

#define PROJ_SOLVERS(X) X(double_pendulum_k2s2) X(double_pendulum_const_k2s2) X(chain_poly_k2s2) X(chain_const_k2s2)
PROJ_SOLVERS(PROJ_ADAPT)
static const Proj projs[] = {PROJ_SOLVERS(PROJ_ENTRY)};

/* A perturbed state (every q and p moved by up to 0.1) projected: |g| and
 * |hidden| at round-off of the coordinates, corrections reported, and H
 * conserved by the steps from there. _i: the solver. */
START_TEST(project_converges_to_roundoff)
{
  const Proj *s = &projs[_i];
  unsigned char x[4096];
  double g[16], hc[16], dq = -1, dp = -1, gmax = 0, hmax = 0, qmax = 0, dH = 0;
  ck_assert_uint_le(s->size, sizeof x);
  s->init(x);
  for (int i = 0; i < s->m; i++) {
    s->q(x)[i] += 0.1 * sin(i + 1.0);
    s->p(x)[i] += 0.1 * cos(i + 2.0);
  }
  ck_assert_int_eq(s->project(x, &dq, &dp), 0);
  s->g(x, g);
  s->hidden(x, hc);
  for (int i = 0; i < s->m; i++) qmax = fmax(qmax, fabs(s->q(x)[i]));
  for (int a = 0; a < s->nu; a++) {
    gmax = fmax(gmax, fabs(g[a]));
    hmax = fmax(hmax, fabs(hc[a]));
  }
  ck_assert_msg(gmax <= 8 * DBL_EPSILON * qmax * qmax && hmax <= 1e-14, "%s: |g| = %.3e, |hidden| = %.3e", s->name, gmax,
                hmax);
  ck_assert_msg(dq > 0.01 && dq < 0.5 && dp > 0.01 && dp < 0.5, "%s: dq = %g, dp = %g", s->name, dq, dp);
  /* projected again, it stays where it is */
  unsigned char y[4096];
  memcpy(y, x, s->size);
  ck_assert_int_eq(s->project(y, &dq, &dp), 0);
  ck_assert_msg(dq <= 4 * DBL_EPSILON * qmax && dp <= 1e-15, "%s: a consistent state moved by %g, %g", s->name, dq, dp);
  double H0 = s->energy(x);
  for (int n = 0; n < 200; n++) {
    ck_assert_int_eq(s->step(x, 0.01), 0);
    dH = fmax(dH, fabs(s->energy(x) - H0));
  }
  ck_assert_msg(dH <= 64 * DBL_EPSILON * fmax(1, fabs(H0)), "%s: |H - H0| = %.3e after the projection", s->name, dH);
}
END_TEST

/* q at the hinge (grad g_1 = 0: singular) or a NaN in p: an error code,
 * and the state byte for byte as it was. _i: the solver. */
START_TEST(failed_projection_leaves_state)
{
  const Proj *s = &projs[_i];
  unsigned char x[4096], before[4096];
  double dq = 7, dp = 7;
  s->init(x);
  for (int i = 0; i < s->m; i++) s->q(x)[i] = 0;
  memcpy(before, x, s->size);
  ck_assert_int_eq(s->project(x, &dq, &dp), 3); /* ESINGULAR */
  ck_assert_msg(!memcmp(x, before, s->size) && dq == 7 && dp == 7, "%s: a singular projection changed x", s->name);
  s->init(x);
  s->p(x)[0] = NAN;
  memcpy(before, x, s->size);
  ck_assert_int_eq(s->project(x, NULL, NULL), 2); /* ENONFINITE */
  ck_assert_msg(!memcmp(x, before, s->size), "%s: a non-finite projection changed x", s->name);
}
END_TEST

/* Without constraints NAME_project does nothing and says so. */
START_TEST(project_without_constraints)
{
  kepler_k2s2_state x, y;
  double dq = 1, dp = 1;
  kepler_k2s2_init(&x, NULL, NULL);
  memcpy(&y, &x, sizeof x);
  ck_assert_int_eq(kepler_k2s2_project(&x, NULL, &dq, &dp), kepler_k2s2_OK);
  ck_assert(dq == 0 && dp == 0 && !memcmp(&x, &y, sizeof x));
}
END_TEST

/* The float interface: NAME_real in and out, and project to float round-off. */
/* The summary's max_dH_rel where H0 is round-off (the satellites: 2.8e-17 in
 * double, 0 in float): over |K0| + |U0|, so at round-off too, 64 ulps at most
 * (measured 4.6e-16 and 1.5e-7). max_dH / |H0| said 5 and inf; a float driver's
 * U0 must come from its own float state, which a copy of the double q and p
 * the runtime sees with p zeroed does not change (inf again). */
START_TEST(summary_relative_where_H0_is_roundoff)
{
  static const char *const flags[2] = {"-k 6 -s 2", "-k 6 -s 2 --real float"};
  static const double eps[2] = {DBL_EPSILON, FLT_EPSILON};
  setup_dir();
  build("satrel", "../models/satellites.ham", NULL, flags[_i]);
  Run r = run("satrel", "-h 0.05 -T 50");
  ck_assert_int_eq(r.status, 0);
  const char *p = strstr(r.err, "max_dH_rel=");
  ck_assert_msg(p != NULL, "no summary: %s", r.err);
  double rel = strtod(p + 11, NULL);
  ck_assert_msg(rel <= 64 * eps[_i], "%s: max_dH_rel = %g over 1000 steps (max_dH = %g)", flags[_i], rel, max_dH(&r));
  remove_dir();
}
END_TEST

START_TEST(float_interface)
{
  polyfloat_k3s3_state x;
  const float q0[2] = {0.0f, -1.1f}, p0[2] = {1.0f, 0.25f};
  float g, hc, dq, dp, h = 0.1f;
  ck_assert(sizeof(polyfloat_k3s3_real) == sizeof(float));
  ck_assert(sizeof polyfloat_k3s3_energy(&x, NULL) == sizeof(float));
  polyfloat_k3s3_init_params(&x, q0, p0, NULL);
  ck_assert_int_eq(polyfloat_k3s3_project(&x, NULL, &dq, &dp), polyfloat_k3s3_OK);
  polyfloat_k3s3_constraints(&x, NULL, &g);
  polyfloat_k3s3_hidden(&x, NULL, &hc);
  ck_assert_msg(fabsf(g) <= 4 * FLT_EPSILON && fabsf(hc) <= 4 * FLT_EPSILON && fabsf(dq - 0.1f) <= 1e-6f,
                "float: |g| = %.3e, |hidden| = %.3e, dq = %g", g, hc, dq);
  float H0 = polyfloat_k3s3_energy(&x, NULL);
  for (int n = 0; n < 100; n++) ck_assert_int_eq(polyfloat_k3s3_step(&x, h, NULL, NULL), 0);
  ck_assert_msg(fabsf(polyfloat_k3s3_energy(&x, NULL) - H0) <= 4 * FLT_EPSILON, "float: H drifts after the projection");
}
END_TEST

Suite *init_suite(void)
{
  Suite *s = suite_create("init");
  TCase *tc = tcase_create("init");
  tcase_set_timeout(tc, 120);
  tcase_add_loop_test(tc, driver_refuses_or_projects, 0, 2);
  tcase_add_test(tc, driver_params_make_q0);
  tcase_add_loop_test(tc, project_converges_to_roundoff, 0, (int)(sizeof projs / sizeof projs[0]));
  tcase_add_loop_test(tc, failed_projection_leaves_state, 0, (int)(sizeof projs / sizeof projs[0]));
  tcase_add_test(tc, project_without_constraints);
  tcase_add_test(tc, float_interface);
  tcase_add_loop_test(tc, summary_relative_where_H0_is_roundoff, 0, 2);
  suite_add_tcase(s, tc);
  return s;
}
