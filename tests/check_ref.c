/* check_ref.c - Check suite verifying the reference solutions of ref.c.
 *
 * For every problem, with h = 0.1 and N = 100 (t in [0,10]):
 *   - constraints |g(q_n)| and hidden constraints |G(q_n)'p_n| < 1e-11,
 *     energy drift |H_n - H_0| < 1e-12;
 *   - lambda consistent with the equations of motion: p' estimated by
 *     fourth-order central differences of a run with step 1e-3 satisfies
 *     p' + grad U + G lambda = 0 to 1e-9 (truncation ~1e-13, round-off
 *     ~1e-12), and lambda agrees with the h = 0.1 run;
 *   - grad U and grad g against central differences of U and g;
 *   - an error estimate from independent runs (other tolerance, finer output
 *     grid, and for pendulum, double pendulum and conical the generic
 *     index-1 integrator against the angle formulation / the closed form);
 *   - the double pendulum's angle run against that integrator at every
 *     step point of the order tests' grids, its invariants at round-off,
 *     and its initial angles; the satellites' reference independent of
 *     the output grid to 3e-14;
 *   - ref_max_error against ref_solve and a known perturbation.
 * The suite is exposed as ref_suite(); the project's runner calls it. */
#include "ref.h"

#include <check.h>
#include <math.h>
#include <stdlib.h>

#define NSTEP 100
#define HSTEP 0.1
#define MAXM 9
#define MAXNU 3

Suite *ref_suite(void);

static const char *const prob_names[] = {"pendulum", "conical", "modified",
                                         "satellites", "double_pendulum"};
#define NPROB 5

/* A reference run: sizes and the trajectory arrays. */
typedef struct {
  int m, nu;
  long N;
  double *q, *p, *lambda;
} run;

/* Allocate and fill a run of problem name with step h and N steps, through
 * ref_solve (mode 0), ref_solve_tol with tolerance tol (mode 1) or
 * ref_solve_index1 with tolerance tol (mode 2).  Fails the test on error. */
static run make_run(const char *name, double h, long N, int mode, double tol)
{
  run r;
  int rc;
  ck_assert_int_eq(ref_dims(name, &r.m, &r.nu), 0);
  r.N = N;
  r.q = malloc((size_t)(N + 1) * (size_t)r.m * sizeof *r.q);
  r.p = malloc((size_t)(N + 1) * (size_t)r.m * sizeof *r.p);
  r.lambda = malloc((size_t)(N + 1) * (size_t)r.nu * sizeof *r.lambda);
  ck_assert(r.q != NULL && r.p != NULL && r.lambda != NULL);
  if (mode == 0)
    rc = ref_solve(name, h, N, r.q, r.p, r.lambda);
  else if (mode == 1)
    rc = ref_solve_tol(name, h, N, tol, r.q, r.p, r.lambda);
  else
    rc = ref_solve_index1(name, h, N, tol, r.q, r.p, r.lambda);
  ck_assert_int_eq(rc, 0);
  return r;
}

static void free_run(run *r)
{
  free(r->q);
  free(r->p);
  free(r->lambda);
}

/* Largest |difference| of q, p (and separately lambda) between point n of
 * a and point n*stride of b, over n = 0..a->N. */
static void run_diff(const run *a, const run *b, long stride, double *dqp,
                     double *dl)
{
  long n;
  int i;
  *dqp = 0.0;
  *dl = 0.0;
  for (n = 0; n <= a->N; n++) {
    long nb = n * stride;
    for (i = 0; i < a->m; i++) {
      *dqp = fmax(*dqp, fabs(a->q[n * a->m + i] - b->q[nb * a->m + i]));
      *dqp = fmax(*dqp, fabs(a->p[n * a->m + i] - b->p[nb * a->m + i]));
    }
    for (i = 0; i < a->nu; i++)
      *dl = fmax(*dl, fabs(a->lambda[n * a->nu + i]
                           - b->lambda[nb * a->nu + i]));
  }
}

/* Points n of a and n*stride of b agree within lim in q, p and lambda. */
static void assert_agree(const run *a, const run *b, long stride, double lim)
{
  double dqp, dl;
  run_diff(a, b, stride, &dqp, &dl);
  ck_assert_double_lt(dqp, lim);
  ck_assert_double_lt(dl, lim);
}

START_TEST(test_dims)
{
  int m = 0, nu = 0;
  static const int want[NPROB][2] = {{2, 1}, {3, 1}, {3, 1}, {9, 3},
                                     {4, 2}};
  ck_assert_int_eq(ref_dims(prob_names[_i], &m, &nu), 0);
  ck_assert_int_eq(m, want[_i][0]);
  ck_assert_int_eq(nu, want[_i][1]);
}
END_TEST

START_TEST(test_unknown)
{
  double x[9];
  int m, nu;
  ck_assert_int_eq(ref_dims("nosuch", &m, &nu), -1);
  ck_assert_int_eq(ref_solve("nosuch", 0.1, 1, x, x, x), -1);
  ck_assert_int_eq(ref_solve("pendulum", -0.1, 1, x, x, x), -1);
}
END_TEST

/* Initial values of the run equal ref_initial and are consistent. */
START_TEST(test_initial)
{
  const char *name = prob_names[_i];
  double q0[MAXM], p0[MAXM], H, g[MAXNU], hc[MAXNU];
  run r = make_run(name, HSTEP, 1, 0, 0.0);
  int i;
  ck_assert_int_eq(ref_initial(name, q0, p0), 0);
  for (i = 0; i < r.m; i++) {
    ck_assert_double_eq(r.q[i], q0[i]);
    ck_assert_double_eq(r.p[i], p0[i]);
  }
  ck_assert_int_eq(ref_invariants(name, q0, p0, &H, g, hc), 0);
  for (i = 0; i < r.nu; i++) { /* satellites: rounding at |z| = 20 */
    ck_assert_double_le(fabs(g[i]), 1e-14);
    ck_assert_double_le(fabs(hc[i]), 1e-14);
  }
  if (_i == 3) /* satellites: v0 chosen so that H(q0,p0) = 0 */
    ck_assert_double_le(fabs(H), 1e-15);
  free_run(&r);
}
END_TEST

/* Constraints, hidden constraints and energy along the run. */
START_TEST(test_invariants)
{
  const char *name = prob_names[_i];
  run r = make_run(name, HSTEP, NSTEP, 0, 0.0);
  double H0, H, g[MAXNU], hc[MAXNU], eg = 0.0, ehc = 0.0, eH = 0.0;
  long n;
  int j;
  ref_invariants(name, r.q, r.p, &H0, NULL, NULL);
  for (n = 0; n <= r.N; n++) {
    ck_assert_int_eq(ref_invariants(name, r.q + n * r.m, r.p + n * r.m, &H,
                                    g, hc), 0);
    eH = fmax(eH, fabs(H - H0));
    for (j = 0; j < r.nu; j++) {
      eg = fmax(eg, fabs(g[j]));
      ehc = fmax(ehc, fabs(hc[j]));
    }
  }
  ck_assert_double_lt(eg, 1e-11);
  ck_assert_double_lt(ehc, 1e-11);
  ck_assert_double_lt(eH, 1e-12);
  free_run(&r);
}
END_TEST

/* lambda against the equations of motion p' = -grad U - G lambda, with p'
 * from fourth-order central differences of a run with step d = 1e-3, at
 * the times t_n = n*0.1, n = 1..N; and the d-run's lambda against the
 * 0.1-run's lambda. */
START_TEST(test_lambda_motion)
{
  const char *name = prob_names[_i];
  const double d = 1e-3;
  const long ratio = 100; /* HSTEP / d */
  run r = make_run(name, HSTEP, NSTEP, 0, 0.0);
  run f = make_run(name, d, ratio * NSTEP + 2, 0, 0.0);
  double gu[MAXM], G[MAXM * MAXNU], res = 0.0, dl = 0.0;
  long n;
  int i, j;
  for (n = 1; n <= NSTEP; n++) {
    long c = n * ratio;
    const double *lam = f.lambda + c * f.nu;
    ck_assert_int_eq(ref_gradients(name, f.q + c * f.m, gu, G), 0);
    for (i = 0; i < f.m; i++) {
      double dp = (f.p[(c - 2) * f.m + i] - 8.0 * f.p[(c - 1) * f.m + i]
                   + 8.0 * f.p[(c + 1) * f.m + i]
                   - f.p[(c + 2) * f.m + i]) / (12.0 * d);
      double acc = dp + gu[i];
      for (j = 0; j < f.nu; j++)
        acc += G[i * f.nu + j] * lam[j];
      res = fmax(res, fabs(acc));
    }
    for (j = 0; j < f.nu; j++)
      dl = fmax(dl, fabs(lam[j] - r.lambda[n * r.nu + j]));
  }
  ck_assert_double_lt(res, 1e-9);
  ck_assert_double_lt(dl, 1e-12);
  free_run(&r);
  free_run(&f);
}
END_TEST

/* lambda returned equals the index-1 formula lambda(q,p) at the same point
 * (for pendulum: theta formula; for conical: the constant 2^-1/2). */
START_TEST(test_lambda_formula)
{
  const char *name = prob_names[_i];
  run r = make_run(name, HSTEP, NSTEP, 0, 0.0);
  double lam[MAXNU], dl = 0.0;
  long n;
  int j;
  for (n = 0; n <= r.N; n++) {
    ck_assert_int_eq(ref_lambda(name, r.q + n * r.m, r.p + n * r.m, lam), 0);
    for (j = 0; j < r.nu; j++)
      dl = fmax(dl, fabs(lam[j] - r.lambda[n * r.nu + j]));
  }
  ck_assert_double_lt(dl, 1e-12);
  free_run(&r);
}
END_TEST

/* Error estimate: against a run at tolerance 1e-13 and a run at the
 * default tolerance on a 4x finer output grid (different step sequence). */
START_TEST(test_error_estimate)
{
  const char *name = prob_names[_i];
  const double lim = (_i <= 1 || _i == 4) ? 1e-12 : 1e-11;
  run r = make_run(name, HSTEP, NSTEP, 0, 0.0);
  run a = make_run(name, HSTEP, NSTEP, 1, 1e-13);
  run b = make_run(name, HSTEP / 4, 4 * NSTEP, 0, 0.0);
  assert_agree(&r, &a, 1, lim);
  assert_agree(&r, &b, 4, lim);
  free_run(&r);
  free_run(&a);
  free_run(&b);
}
END_TEST

/* grad U and G = grad g against central differences of U (from H with
 * p = 0) and g at the initial point and at a perturbed point. */
START_TEST(test_gradients)
{
  const char *name = prob_names[_i];
  double q[MAXM], zero[MAXM] = {0.0}, gu[MAXM], G[MAXM * MAXNU];
  int m, nu, i, j, pt;
  ck_assert_int_eq(ref_dims(name, &m, &nu), 0);
  for (pt = 0; pt < 2; pt++) {
    double dummy[MAXM];
    ck_assert_int_eq(ref_initial(name, q, dummy), 0);
    if (pt == 1)
      for (i = 0; i < m; i++)
        q[i] += 0.01 * (double)(i + 1) * ((i % 2) ? -1.0 : 1.0);
    ck_assert_int_eq(ref_gradients(name, q, gu, G), 0);
    for (i = 0; i < m; i++) {
      const double d = 1e-5;
      double qp[MAXM], qm[MAXM], up, um, gp[MAXNU], gm[MAXNU];
      for (j = 0; j < m; j++)
        qp[j] = qm[j] = q[j];
      qp[i] += d;
      qm[i] -= d;
      ref_invariants(name, qp, zero, &up, gp, NULL);
      ref_invariants(name, qm, zero, &um, gm, NULL);
      ck_assert_double_eq_tol(gu[i], (up - um) / (2.0 * d), 1e-8);
      for (j = 0; j < nu; j++)
        ck_assert_double_eq_tol(G[i * nu + j], (gp[j] - gm[j]) / (2.0 * d),
                                1e-8);
    }
  }
}
END_TEST

/* Conical pendulum: closed form checked directly (radius, plane, speed,
 * period), and the generic index-1 integrator against it over 10 periods. */
START_TEST(test_conical)
{
  const double T = pow(2.0, 0.75) * 3.14159265358979323846;
  const double r0 = sqrt(0.5), w = pow(2.0, 0.25);
  run c = make_run("conical", T / 10.0, 100, 0, 0.0);
  run a = make_run("conical", T / 10.0, 100, 2, 1e-15);
  long n;
  for (n = 0; n <= c.N; n++) {
    const double *q = c.q + 3 * n, *p = c.p + 3 * n;
    ck_assert_double_eq_tol(hypot(q[0], q[1]), r0, 1e-15);
    ck_assert_double_eq_tol(q[2], -r0, 1e-15);
    ck_assert_double_eq_tol(hypot(p[0], p[1]), r0 * w, 1e-15);
    ck_assert_double_eq_tol(p[2], 0.0, 1e-15);
    ck_assert_double_eq_tol(c.lambda[n], r0, 1e-15);
    if (n % 10 == 0) { /* back at the start after each period */
      ck_assert_double_eq_tol(q[0], r0, 1e-13);
      ck_assert_double_eq_tol(q[1], 0.0, 1e-13);
    }
  }
  assert_agree(&c, &a, 1, 1e-11);
  free_run(&c);
  free_run(&a);
}
END_TEST

/* The angle formulations of the pendulum and the double pendulum
 * (ref_solve) against the generic index-1 integrator in Cartesian
 * coordinates, at every point t_n = n h on [0,10]; for the double pendulum
 * on each of the order tests' grids h = 0.1 .. 0.0125 (measured: 1.6e-14
 * at h = 0.1, 2.7e-15 at 0.0125; lambda 3e-14). A wrong sign or factor in
 * the angle equations, or in the Jacobian or Hessians, shows as O(1). */
START_TEST(test_angles_index1)
{
  const char *name = _i == 0 ? "pendulum" : "double_pendulum";
  const int halvings = _i == 0 ? 0 : _i - 1;
  const double h = HSTEP / (double)(1 << halvings);
  const long N = (long)NSTEP << halvings;
  run r = make_run(name, h, N, 0, 0.0);
  run a = make_run(name, h, N, 2, 1e-15);
  assert_agree(&r, &a, 1, 1e-12);
  free_run(&r);
  free_run(&a);
}
END_TEST

/* Double pendulum: energy, constraints and hidden constraints along the
 * reference at round-off (measured 8.9e-16, 4.4e-16, 2.2e-16), the start
 * at rest at angles 0.5 and -0.3, and the motion not trivial: the second
 * mass swings to the other side (x2 changes sign) and both multipliers
 * vary by more than 0.1. */
START_TEST(test_double_pendulum)
{
  run r = make_run("double_pendulum", 0.0125, 800, 0, 0.0);
  double H0, H, g[2], hc[2], eH = 0.0, eg = 0.0, ehc = 0.0;
  double x2min = 0.0, x2max = 0.0, lmin[2] = {1e300, 1e300}, lmax[2] = {0, 0};
  long n;
  int j;
  ck_assert_double_eq_tol(r.q[0], sin(0.5), 1e-16);
  ck_assert_double_eq_tol(r.q[1], -cos(0.5), 1e-16);
  ck_assert_double_eq_tol(r.q[2] - r.q[0], sin(-0.3), 1e-16);
  ck_assert_double_eq_tol(r.q[3] - r.q[1], -cos(-0.3), 1e-16);
  for (j = 0; j < 4; j++)
    ck_assert_double_eq(r.p[j], 0.0);
  ck_assert_int_eq(ref_invariants("double_pendulum", r.q, r.p, &H0, NULL,
                                  NULL), 0);
  ck_assert_double_eq_tol(H0, -2.0 * cos(0.5) - cos(0.3), 1e-15);
  for (n = 0; n <= r.N; n++) {
    ref_invariants("double_pendulum", r.q + 4 * n, r.p + 4 * n, &H, g, hc);
    eH = fmax(eH, fabs(H - H0));
    x2min = fmin(x2min, r.q[4 * n + 2]);
    x2max = fmax(x2max, r.q[4 * n + 2]);
    for (j = 0; j < 2; j++) {
      eg = fmax(eg, fabs(g[j]));
      ehc = fmax(ehc, fabs(hc[j]));
      lmin[j] = fmin(lmin[j], r.lambda[2 * n + j]);
      lmax[j] = fmax(lmax[j], r.lambda[2 * n + j]);
    }
  }
  ck_assert_double_le(eH, 4e-15);
  ck_assert_double_le(eg, 2e-15);
  ck_assert_double_le(ehc, 2e-15);
  ck_assert_double_lt(x2min, -0.1);
  ck_assert_double_gt(x2max, 0.1);
  ck_assert_double_gt(lmax[0] - lmin[0], 0.1);
  ck_assert_double_gt(lmax[1] - lmin[1], 0.1);
  free_run(&r);
}
END_TEST

/* Satellites at tolerance 1e-15 for max-over-run errors: the reference at
 * the points of h = 0.1 and of h = 0.0125 agree at every common point to
 * 3e-14 (measured 7e-15; integrating q rather than q - q0 gave 1.1e-13,
 * round-off at |z| = 20), and against tolerance 1e-14 on the fine grid. */
START_TEST(test_satellites_grid)
{
  run r = make_run("satellites", 0.1, 100, 1, 1e-15);
  run f = make_run("satellites", 0.0125, 800, 1, 1e-15);
  run g = make_run("satellites", 0.0125, 800, 1, 1e-14);
  assert_agree(&r, &f, 8, 3e-14);
  assert_agree(&f, &g, 1, 3e-14);
  free_run(&r);
  free_run(&f);
  free_run(&g);
}
END_TEST

/* ref_max_error: zero against ref_solve's own run, the size of a planted
 * perturbation otherwise, NaN for a NaN, and -1 for bad arguments. */
START_TEST(test_max_error)
{
  const char *name = prob_names[_i];
  run r = make_run(name, 0.05, 200, 0, 0.0);
  double eqp = -1.0, el = -1.0;
  ck_assert_int_eq(ref_max_error(name, 0.05, 200, r.q, r.p, r.lambda, &eqp,
                                 &el), 0);
  ck_assert_double_eq(eqp, 0.0);
  ck_assert_double_eq(el, 0.0);
  r.p[137 * r.m + r.m - 1] += 3e-9;
  r.lambda[200 * r.nu] -= 2e-7;
  ck_assert_int_eq(ref_max_error(name, 0.05, 200, r.q, r.p, r.lambda, &eqp,
                                 &el), 0);
  ck_assert_double_eq_tol(eqp, 3e-9, 1e-15);
  ck_assert_double_eq_tol(el, 2e-7, 1e-15);
  el = -1.0;
  r.q[5] = NAN;
  ck_assert_int_eq(ref_max_error(name, 0.05, 200, r.q, r.p, NULL, &eqp,
                                 &el), 0);
  ck_assert(isnan(eqp));
  ck_assert_double_eq(el, -1.0);
  ck_assert_int_eq(ref_max_error("nosuch", 0.05, 200, r.q, r.p, NULL, &eqp,
                                 NULL), -1);
  ck_assert_int_eq(ref_max_error(name, 0.0, 200, r.q, r.p, NULL, &eqp,
                                 NULL), -1);
  free_run(&r);
}
END_TEST

Suite *ref_suite(void)
{
  Suite *s = suite_create("ref");
  TCase *tc = tcase_create("reference");
  tcase_set_tags(tc, "sanlong"); /* the generated arithmetic: sanitized in check-long */
  tcase_set_timeout(tc, 60);
  tcase_add_loop_test(tc, test_dims, 0, NPROB);
  tcase_add_test(tc, test_unknown);
  tcase_add_loop_test(tc, test_initial, 0, NPROB);
  tcase_add_loop_test(tc, test_invariants, 0, NPROB);
  tcase_add_loop_test(tc, test_lambda_motion, 0, NPROB);
  tcase_add_loop_test(tc, test_lambda_formula, 0, NPROB);
  tcase_add_loop_test(tc, test_error_estimate, 0, NPROB);
  tcase_add_loop_test(tc, test_gradients, 0, NPROB);
  tcase_add_loop_test(tc, test_angles_index1, 0, 5);
  tcase_add_test(tc, test_conical);
  tcase_add_test(tc, test_double_pendulum);
  tcase_add_test(tc, test_satellites_grid);
  tcase_add_loop_test(tc, test_max_error, 0, NPROB);
  suite_add_tcase(s, tc);
  return s;
}
