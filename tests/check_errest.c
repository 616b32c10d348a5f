/* check_errest.c - the local error estimate NAME_stats.err_est against the
 * true local error.
 *
 * The true local error of a step of size h from t_n: start the solver on
 * the reference trajectory at t_{n-1}, take one step (so that the step from
 * t_n has its usual warm start), put the state back on the reference at
 * t_n, take the step and compare q with the reference at t_{n+1} (max norm).
 * The references are those of tests/ref.c and, for Kepler (e = 0.6), the
 * closed form through Kepler's equation. Steps whose true error is below
 * ROUNDOFF are left out: there the error is round-off, not truncation.
 * Each case asserts that true / estimate is within [1/10, 10] in geometric
 * mean over the steps of one period-like span (single steps stray further:
 * docs/api.md gives the extremes); HBVM_ERREST_TABLE=1 prints the table
 * (geometric mean, smallest and largest ratio). */
#define _POSIX_C_SOURCE 200809L
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ref.h"
#include "solvers.h"
#include "errest.h"

Suite *errest_suite(void);

#define ROUNDOFF 1e-14

// Kepler, e = 0.6, a = 1 (H = -1/2, period 2 pi), from the perihelion
// (models/kepler.ham): q, p at time t through E - e sin E = t.
void kepler_exact(double t, double *q, double *p) {
  const double e = 0.6, b = sqrt(1 - e * e);
  double E = t;
  for (int i = 0; i < 100; i++) {
    double dE = (E - e * sin(E) - t) / (1 - e * cos(E));
    E -= dE;
    if (fabs(dE) < 1e-16 * (1 + fabs(E))) break;
  }
  double r = 1 - e * cos(E);
  q[0] = cos(E) - e;
  q[1] = b * sin(E);
  p[0] = -sin(E) / r;
  p[1] = b * cos(E) / r;
}

// The reference at t_n = n h, n = 0..N, of problem (tests/ref.c, or
// "kepler" in closed form): q, p of (N+1) m values.
int errest_reference(const char *problem, double h, long N, int m, double *q, double *p) {
  if (strcmp(problem, "kepler") != 0) {
    int mm, nu;
    ck_assert_int_eq(ref_dims(problem, &mm, &nu), 0);
    double *lam = malloc(sizeof(double) * (size_t)(nu + 1) * (size_t)(N + 1));
    int rc = ref_solve(problem, h, N, q, p, lam);
    free(lam);
    return rc;
  }
  for (long n = 0; n <= N; n++) kepler_exact((double)n * h, q + n * m, p + n * m);
  return 0;
}

// True local error / err_est over the steps n = 1..N-1 of the grid h.
static Ratios measure(const char *problem, const char *solver, double h, long N) {
  const Solver *sv = solver_find(solver);
  ck_assert_msg(sv != NULL, "no solver %s", solver);
  int m = sv->m, nu = sv->nu;
  double *q = malloc(sizeof(double) * m * (N + 2)), *p = malloc(sizeof(double) * m * (N + 2));
  double *lam = malloc(sizeof(double) * (nu ? nu : 1) * (N + 2));
  void *x = malloc(sv->state_size);
  ck_assert(q && p && lam && x);
  ck_assert_int_eq(errest_reference(problem, h, N + 1, m, q, p), 0);
  Ratios r = {0, HUGE_VAL, 0, 0};
  double logsum = 0;
  for (long n = 1; n <= N; n++) {
    double est, err = 0;
    sv->init(x, q + (n - 1) * m, p + (n - 1) * m);
    ck_assert_int_eq(sv->step_est(x, h, &est), 0);
    memcpy(solver_q(sv, x), q + n * m, sizeof(double) * m);
    memcpy(solver_p(sv, x), p + n * m, sizeof(double) * m);
    ck_assert_int_eq(sv->step_est(x, h, &est), 0);
    for (int i = 0; i < m; i++) err = fmax(err, fabs(solver_q(sv, x)[i] - q[(n + 1) * m + i]));
    if (err < ROUNDOFF) continue;
    double ratio = err / est;
    r.lo = fmin(r.lo, ratio);
    r.hi = fmax(r.hi, ratio);
    logsum += log(ratio);
    r.n++;
  }
  r.mean = r.n ? exp(logsum / r.n) : 0;
  free(q);
  free(p);
  free(lam);
  free(x);
  return r;
}

static const struct {
  const char *problem, *solver;
  double h;
  long N;
} cases[] = {
    {"pendulum", "pendulum_poly_k1s1", 0.05, 200},       {"pendulum", "pendulum_poly_k2s2", 0.1, 100},
    {"pendulum", "pendulum_poly_k3s3", 0.2, 50},         {"pendulum", "pendulum_poly_k4s4", 0.4, 25},
    {"pendulum", "pendulum_k2s2", 0.1, 100},             {"pendulum", "pendulum_k3s3", 0.1, 100},
    {"double_pendulum", "double_pendulum_k2s2", 0.1, 100}, {"double_pendulum", "double_pendulum_k3s3", 0.1, 100},
    {"double_pendulum", "double_pendulum_k4s4", 0.2, 50}, {"double_pendulum", "double_pendulum_const_k2s2", 0.1, 100},
    {"satellites", "satellites_poly_k6s2", 0.1, 100},    {"satellites", "satellites_poly_k6s3", 0.2, 50},
    {"satellites", "satellites_k6s1", 0.1, 100},         {"satellites", "satellites_k6s2", 0.1, 100},
    {"satellites", "satellites_k6s3", 0.1, 100},         {"modified", "modified_poly_k6s2", 0.1, 100},
    {"modified", "modified_poly_k9s3", 0.1, 100},        {"modified", "modified_k3s1", 0.1, 100},
    {"modified", "modified_k6s2", 0.1, 100},             {"conical", "conical_poly_k2s2", 0.1, 100},
    {"kepler", "kepler_k1s1", 0.01, 628},                {"kepler", "kepler_k2s2", 0.05, 126},
    {"kepler", "kepler_k3s3", 0.1, 63},                  {"kepler", "kepler_k4s4", 0.2, 32},
};

START_TEST(tracks_true_error)
{
  Ratios r = measure(cases[_i].problem, cases[_i].solver, cases[_i].h, cases[_i].N);
  if (getenv("HBVM_ERREST_TABLE"))
    printf("%-16s %-28s h=%-5g steps=%-4d ratio true/est: mean %.3g  min %.3g  max %.3g\n", cases[_i].problem,
           cases[_i].solver, cases[_i].h, r.n, r.mean, r.lo, r.hi);
  ck_assert_msg(r.n > 0, "%s: no step above round-off", cases[_i].solver);
  /* the constant multiplier at s >= 2 has an error driven by the multiplier's
   * change, which the velocity's coefficients do not see: not tracked */
  static const char *const untracked[] = {"pendulum_k3s3", "satellites_k6s2", "satellites_k6s3"};
  for (size_t u = 0; u < sizeof untracked / sizeof untracked[0]; u++)
    if (!strcmp(cases[_i].solver, untracked[u])) return;
  ck_assert_msg(r.mean >= 0.1 && r.mean <= 10, "%s, h=%g: true/est %g on average", cases[_i].solver, cases[_i].h,
                r.mean);
}
END_TEST

Suite *errest_suite(void) {
  Suite *s = suite_create("errest");
  TCase *tc = tcase_create("errest");
  tcase_add_loop_test(tc, tracks_true_error, 0, (int)(sizeof cases / sizeof cases[0]));
  tcase_set_timeout(tc, 60);
  suite_add_tcase(s, tc);
  return s;
}
