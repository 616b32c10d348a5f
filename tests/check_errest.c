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
 * mean over the steps of one period-like span, and at most 100 on any step
 * (single steps stray further below: docs/api.md gives the extremes);
 * HBVM_ERREST_TABLE=1 prints the table
 * (geometric mean, smallest and largest ratio). */
#define _POSIX_C_SOURCE 200809L
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ref.h"
#include "solvers.h"
#include "errest.h"

Suite *errest_suite(void);
Suite *adaptive_suite(void);

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

static const StepCase cases[] = {
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
    /* the constant multiplier's part (NAME_mult_err) at a second h, and where it is 0 */
    {"satellites", "satellites_k6s2", 0.05, 200},        {"modified", "modified_k9s3", 0.1, 100},
    {"conical", "conical_k2s2", 0.1, 100},               {"double_pendulum", "double_pendulum_const_k4s4", 0.2, 50},
};

START_TEST(tracks_true_error)
{
  Ratios r = measure(cases[_i].problem, cases[_i].solver, cases[_i].h, cases[_i].N);
  if (getenv("HBVM_ERREST_TABLE"))
    printf("%-16s %-28s h=%-5g steps=%-4d ratio true/est: mean %.3g  min %.3g  max %.3g\n", cases[_i].problem,
           cases[_i].solver, cases[_i].h, r.n, r.mean, r.lo, r.hi);
  fflush(stdout);
  ck_assert_msg(r.n > 0, "%s: no step above round-off", cases[_i].solver);
  ck_assert_msg(r.mean >= 0.1 && r.mean <= 10, "%s, h=%g: true/est %g on average", cases[_i].solver, cases[_i].h,
                r.mean);
  /* and no step's estimate far below its true error (measured: at most 60x,
   * Kepler s = 4 at h = 0.2; the estimate errs high where the velocity vanishes) */
  ck_assert_msg(r.hi <= 100, "%s, h=%g: a step's true error %g times its estimate", cases[_i].solver, cases[_i].h,
                r.hi);
}
END_TEST

// The first step after NAME_init has no warm start, and its size is the
// caller's guess: its (cold) estimate must not be below the true error, or a
// first step far too long is accepted. Before the cold estimate was
// calibrated (NAME_COLDC), a first step of 0.6 on the pendulum (s = 4) was
// accepted with 1e5 times its estimate, and at s = 6-8 with 1e6-1e9. For
// each case's solver (s >= 2), from the model's initial values, h = the
// case's h times 1/2 .. 8: true / estimate at most 3 (measured at most 1 on
// the calibration problems, h = 0.01 .. 3, docs/api.md). The constant
// multiplier with constraints (order 2) has its error in NAME_mult_err, a
// geometric mean, which decides there: at most 10, as tracks_true_error's
// mean (measured 5.6, double_pendulum_const_k4s4 at h = 1.6; 9.3 at most over
// the calibration sweep).
START_TEST(cold_estimate_not_below_truth)
{
  const Solver *sv = solver_find(cases[_i].solver);
  ck_assert(sv != NULL);
  if (sv->s < 2) return; /* at s = 1 the cold predictor's error is the warm one's */
  int m = sv->m;
  double q[2 * 9], p[2 * 9], worst = 0, worst_h = 0;
  void *x = malloc(sv->state_size);
  ck_assert(x != NULL);
  for (double h = cases[_i].h / 2; h <= 8 * cases[_i].h; h *= 2) {
    double est, err = 0;
    ck_assert_int_eq(errest_reference(cases[_i].problem, h, 1, m, q, p), 0);
    sv->init(x, q, p);
    if (sv->step_est(x, h, &est) != 0) continue; /* beyond the iteration's reach */
    for (int i = 0; i < m; i++) err = fmax(err, fabs(solver_q(sv, x)[i] - q[m + i]));
    if (err < ROUNDOFF) continue;
    if (err / est > worst) worst = err / est, worst_h = h;
  }
  free(x);
  if (getenv("HBVM_ERREST_TABLE"))
    printf("%-16s %-28s cold first step: largest true/est %.3g (h=%g)\n", cases[_i].problem, cases[_i].solver, worst,
           worst_h);
  double bound = sv->nu > 0 && !strstr(sv->name, "_poly_") ? 10 : 3;
  ck_assert_msg(worst <= bound, "%s: a cold step of h=%g has %g times its estimate", cases[_i].solver, worst_h, worst);
}
END_TEST

// From rest the velocity is a t + O(t^3), and at s = 2 gamma_1 / gamma_0 is
// 1/sqrt(3) whatever h: the cold estimate reads the O(t^3) part, e = gamma_0 -
// sqrt(3) gamma_1, and falls like the error, h^6 (docs/api.md). Before, it was
// NAME_COLDC_REST |h gamma_1| rho^3, of order h^2: 400-1e6 times the truth
// at h = 0.26-0.03, which sent adaptive runs from rest at tol <= 1e-13 to the
// step-size floor (adaptive_from_rest_tight). The double pendulum from rest
// (s = 2): the estimate's order between h and 2h within 5.5..6.5, and not
// below the true error (measured 0.002-0.009 of it, h = 0.03-1.3).
START_TEST(cold_estimate_from_rest)
{
  const Solver *sv = solver_find("double_pendulum_k2s2");
  ck_assert(sv != NULL);
  int m = sv->m;
  double q[2 * 4], p[2 * 4], prev = 0;
  void *x = malloc(sv->state_size);
  ck_assert(x != NULL);
  for (double h = 0.05; h <= 0.81; h *= 2) {
    double est, err = 0;
    ck_assert_int_eq(errest_reference("double_pendulum", h, 1, m, q, p), 0);
    sv->init(x, q, p);
    ck_assert_int_eq(sv->step_est(x, h, &est), 0);
    for (int i = 0; i < m; i++) err = fmax(err, fabs(solver_q(sv, x)[i] - q[m + i]));
    ck_assert_msg(err <= est, "h=%g: true error %g over its estimate %g", h, err, est);
    if (prev > 0 && h <= 0.41) {
      double order = log2(est / prev);
      ck_assert_msg(order >= 5.5 && order <= 6.5, "h=%g: the estimate's order from rest %g, not 6", h, order);
    }
    prev = est;
  }
  free(x);
}
END_TEST

Suite *errest_suite(void) {
  Suite *s = suite_create("errest");
  TCase *tc = tcase_create("errest");
  tcase_set_tags(tc, "sanlong"); /* the generated arithmetic: sanitized in check-long */
  tcase_add_loop_test(tc, tracks_true_error, 0, (int)(sizeof cases / sizeof cases[0]));
  tcase_add_loop_test(tc, cold_estimate_not_below_truth, 0, (int)(sizeof cases / sizeof cases[0]));
  tcase_add_test(tc, cold_estimate_from_rest);
  tcase_set_timeout(tc, 60);
  suite_add_tcase(s, tc);
  return s;
}

/* ---- NAME_step_adaptive ---- */

#include "double_pendulum_const_k2s2.h"
#include "double_pendulum_k2s2.h"
#include "double_pendulum_k4s4.h"
#include "solar_k16s2.h"
#include "solar_k11s6.h"
#include "kepler_k3s3.h"
#include "kepler_k4s4.h"
#include "kepler_k11s6.h"
#include "kepler_k18s3.h"
#include "dpa4_k4s4.h"
#include "pa6_k6s6.h"
#include "pendulum_k3s3.h"
#include "pendulum_poly_k3s3.h"
#include "satellites_poly_k6s3.h"

typedef struct {
  double err, dH, dg, dhc; /* error at T (max over q, p), max |H - H0|, |g|, |hidden| */
  long steps, rejected;
} Adaptive;

/* Run solver P adaptively from its model's initial values to T (the last
 * step shortened to end on T) within tol, into *a; q, p at T in qT, pT. */
#define RUN_ADAPTIVE(P)                                                                              \
  static Adaptive adaptive_##P(double T, double tol, double *qT, double *pT) {                       \
    P##_state x;                                                                                     \
    P##_stats st;                                                                                    \
    Adaptive a = {0, 0, 0, 0, 0, 0};                                                                 \
    double h = 0.01, g[P##_NU + 1], hc[P##_NU + 1];                                                  \
    P##_init(&x, NULL, NULL);                                                                        \
    double H0 = P##_energy(&x, NULL);                                                                \
    while (x.t != T) {                                                                               \
      double rest = T - x.t, hn = h >= rest * (1 - 1e-12) ? rest : h;                                \
      ck_assert_int_eq(P##_step_adaptive(&x, &hn, tol, NULL, &st), P##_OK);                          \
      a.steps++;                                                                                     \
      a.rejected += st.rejected;                                                                     \
      a.dH = fmax(a.dH, fabs(P##_energy(&x, NULL) - H0));                                            \
      P##_constraints(&x, NULL, g);                                                                  \
      P##_hidden(&x, NULL, hc);                                                                      \
      for (int i = 0; i < P##_NU; i++) {                                                             \
        a.dg = fmax(a.dg, fabs(g[i]));                                                               \
        a.dhc = fmax(a.dhc, fabs(hc[i]));                                                            \
      }                                                                                              \
      if (st.h == rest) break;                                                                       \
      h = hn;                                                                                        \
    }                                                                                                \
    memcpy(qT, x.q, sizeof x.q);                                                                     \
    memcpy(pT, x.p, sizeof x.p);                                                                     \
    return a;                                                                                        \
  }
RUN_ADAPTIVE(kepler_k3s3)
RUN_ADAPTIVE(kepler_k4s4)
RUN_ADAPTIVE(pendulum_poly_k3s3)
RUN_ADAPTIVE(satellites_poly_k6s3)
RUN_ADAPTIVE(pendulum_k3s3)
RUN_ADAPTIVE(double_pendulum_const_k2s2)
RUN_ADAPTIVE(double_pendulum_k2s2)
RUN_ADAPTIVE(solar_k11s6)
RUN_ADAPTIVE(pa6_k6s6)

static const struct {
  const char *problem;
  double T;
} adaptive_cases[] = {{"kepler", 6.283185307179586}, {"pendulum", 10}, {"satellites", 10}};

// The global error at T against tol = 1e-6 .. 1e-12, and the invariants
// at round-off on every adaptive step.
START_TEST(adaptive_proportional)
{
  const char *problem = adaptive_cases[_i].problem;
  double T = adaptive_cases[_i].T, q[2 * 9], p[2 * 9], qT[9], pT[9];
  int m = 0, nu = 0;
  if (strcmp(problem, "kepler")) {
    ck_assert_int_eq(ref_dims(problem, &m, &nu), 0);
  } else {
    m = 2;
  }
  ck_assert_int_eq(errest_reference(problem, T, 1, m, q, p), 0);
  for (double tol = 1e-6; tol > 1e-12 / 2; tol /= 100) {
    Adaptive a = !strcmp(problem, "kepler")     ? adaptive_kepler_k3s3(T, tol, qT, pT)
                 : !strcmp(problem, "pendulum") ? adaptive_pendulum_poly_k3s3(T, tol, qT, pT)
                                                : adaptive_satellites_poly_k6s3(T, tol, qT, pT);
    for (int i = 0; i < m; i++) a.err = fmax(a.err, fmax(fabs(qT[i] - q[m + i]), fabs(pT[i] - p[m + i])));
    if (getenv("HBVM_ERREST_TABLE"))
      printf("%-10s tol=%-6g error at T=%.3e (%.3g tol) steps=%ld rejected=%ld max|dH|=%.1e max|g|=%.1e "
             "max|hc|=%.1e\n", problem, tol, a.err, a.err / tol, a.steps, a.rejected, a.dH, a.dg, a.dhc);
    fflush(stdout);
    /* tolerance proportionality: within a factor 30 of tol above (measured 0.09 to 14,
     * docs/api.md) and 100 below: the pendulum's error at T is 0.035-0.05 tol at 1e-6..1e-10,
     * and at 1e-12 0.43 tol in 625 steps, 0.015 tol in 619 since the turning point's
     * estimate (NAME_speed): fewer steps and a smaller error, a cancellation at T */
    ck_assert_msg(a.err <= 30 * tol && a.err >= tol / 100, "%s, tol %g: error %g", problem, tol, a.err);
    ck_assert_double_le(a.dg, 1e-13);
    ck_assert_double_le(a.dhc, 1e-13);
    if (strcmp(problem, "kepler")) ck_assert_double_le(a.dH, 1e-13);
  }
}
END_TEST

// The default s = 2 from rest at tight tolerances (the double pendulum,
// T = 1): the first step is sized by the cold estimate from rest
// (cold_estimate_from_rest). When that estimate was of order h^2, the first
// step shrank to 1e-9..1e-12, where the velocity is so small that the
// iteration's round-off in gamma dominated the next estimates, and every run
// at tol <= 1e-13 (1e-10 at T = 10) ended at the step-size floor at t < 1e-7.
// Now: the run ends, its error at T within 30 tol (as adaptive_proportional;
// measured 0.09 and 1.8 tol at 1e-12 and 1e-13) or, at 1e-14, within the
// round-off of its 3852 steps (measured 3.5e-13), 2-3 rejected tries, H and
// g at round-off.
START_TEST(adaptive_from_rest_tight)
{
  double T = 1, q[2 * 4], p[2 * 4], qT[4], pT[4];
  int m, nu;
  ck_assert_int_eq(ref_dims("double_pendulum", &m, &nu), 0);
  ck_assert_int_eq(errest_reference("double_pendulum", T, 1, m, q, p), 0);
  for (double tol = 1e-12; tol > 1e-14 / 2; tol /= 10) {
    Adaptive a = adaptive_double_pendulum_k2s2(T, tol, qT, pT);
    for (int i = 0; i < m; i++) a.err = fmax(a.err, fmax(fabs(qT[i] - q[m + i]), fabs(pT[i] - p[m + i])));
    if (getenv("HBVM_ERREST_TABLE"))
      printf("double_pendulum from rest, s=2, tol=%-6g error at T=%.3e (%.3g tol) steps=%ld rejected=%ld "
             "max|dH|=%.1e max|g|=%.1e\n", tol, a.err, a.err / tol, a.steps, a.rejected, a.dH, a.dg);
    fflush(stdout);
    /* 30 tol, or the round-off of the run: 4 ulps of |q| <= 2 a step */
    ck_assert_msg(a.err <= fmax(30 * tol, a.steps * 8 * DBL_EPSILON), "tol %g: error %g", tol, a.err);
    ck_assert_msg(a.rejected * 20 <= a.steps, "tol %g: %ld of %ld steps rejected", tol, a.rejected, a.steps);
    ck_assert_double_le(a.dg, 1e-14);
    ck_assert_double_le(a.dH, 1e-14);
  }
}
END_TEST

// The constant multiplier (s >= 2, order 4 in q, 2 in p across the hidden
// constraint): its estimate adds NAME_mult_err, q's part and, under the
// adaptive step, the velocity across the hidden constraint the step adds.
// The global error at T in q and p against tol = 1e-6 .. 1e-10 (measured
// 0.11-1.6; before NAME_mult_err the double pendulum failed at the h floor at
// tol 1e-8 and the pendulum ended at 43-209 tol), few rejections, g and H
// at round-off (U and g polynomial, k = s integrates H exactly). The steps
// grow 10x for 100x tol (p's order 2): 1e-12 would take 3e6.
START_TEST(adaptive_const_proportional)
{
  const char *problem = _i ? "double_pendulum" : "pendulum";
  double T = 10, q[2 * 4], p[2 * 4], qT[4], pT[4];
  int m, nu;
  ck_assert_int_eq(ref_dims(problem, &m, &nu), 0);
  ck_assert_int_eq(errest_reference(problem, T, 1, m, q, p), 0);
  for (double tol = 1e-6; tol > 1e-10 / 2; tol /= 100) {
    Adaptive a = _i ? adaptive_double_pendulum_const_k2s2(T, tol, qT, pT) : adaptive_pendulum_k3s3(T, tol, qT, pT);
    for (int i = 0; i < m; i++) a.err = fmax(a.err, fmax(fabs(qT[i] - q[m + i]), fabs(pT[i] - p[m + i])));
    if (getenv("HBVM_ERREST_TABLE"))
      printf("%-16s const tol=%-6g error at T=%.3e (%.3g tol) steps=%ld rejected=%ld max|dH|=%.1e max|g|=%.1e\n",
             problem, tol, a.err, a.err / tol, a.steps, a.rejected, a.dH, a.dg);
    fflush(stdout);
    ck_assert_msg(a.err <= 30 * tol && a.err >= tol / 30, "%s const, tol %g: error %g", problem, tol, a.err);
    ck_assert_msg(a.rejected * 10 <= a.steps, "%s const, tol %g: %ld of %ld steps rejected", problem, tol, a.rejected,
                  a.steps);
    ck_assert_double_le(a.dg, 1e-13);
    ck_assert_double_le(a.dH, 1e-13);
  }
}
END_TEST

// Kepler at k = s = 3: U is not polynomial, the 3 nodes do not integrate H
// exactly, and the quadrature's error, which err_est does not see, dominates
// over many periods. NAME_step_adaptive adds it from the step's energy
// defect: over ten periods (e = 0.6) error / tol is 37-49 at tol 1e-6 ..
// 1e-10 (measured), 300-1400 without it.
START_TEST(adaptive_quadrature_defect)
{
  double T = 20 * 3.141592653589793, q[4], p[4], qT[2], pT[2];
  ck_assert_int_eq(errest_reference("kepler", T, 1, 2, q, p), 0);
  for (double tol = 1e-6; tol > 1e-10 / 2; tol /= 100) {
    Adaptive a = adaptive_kepler_k3s3(T, tol, qT, pT);
    for (int i = 0; i < 2; i++) a.err = fmax(a.err, fmax(fabs(qT[i] - q[2 + i]), fabs(pT[i] - p[2 + i])));
    ck_assert_msg(a.err <= 100 * tol, "kepler (3,3) over ten periods, tol %g: error %g", tol, a.err);
  }
}
END_TEST

// A rejected or failed adaptive step leaves the state byte-identical: a
// tolerance no step can meet fails at the floor with x untouched, and with
// NAME_ETOL, which says so (it was NAME_ENOCONV, "did not converge").
START_TEST(adaptive_rejected_unchanged)
{
  pendulum_poly_k3s3_state x, before;
  pendulum_poly_k3s3_stats st;
  double h = 0.1;
  memset(&x, 0, sizeof x);
  pendulum_poly_k3s3_init(&x, NULL, NULL);
  ck_assert_int_eq(pendulum_poly_k3s3_step(&x, 0.1, NULL, NULL), 0);
  memcpy(&before, &x, sizeof x);
  ck_assert_int_eq(pendulum_poly_k3s3_step_adaptive(&x, &h, 1e-300, NULL, &st), pendulum_poly_k3s3_ETOL);
  ck_assert_str_eq(pendulum_poly_k3s3_strerror(pendulum_poly_k3s3_ETOL),
                   "error estimate over the tolerance down to the smallest step");
  ck_assert(st.rejected > 0);
  ck_assert_int_eq(memcmp(&before, &x, sizeof x), 0);
  h = 0.5; /* rejected first, then accepted: smaller than asked */
  ck_assert_int_eq(pendulum_poly_k3s3_step_adaptive(&x, &h, 1e-10, NULL, &st), 0);
  ck_assert(st.rejected > 0 && st.h < 0.5);
  ck_assert_double_eq_tol(x.t, 0.1 + st.h, 1e-15);
}
END_TEST

// The controller does not cycle: Kepler e = 0.6 at (4,4) over ten periods
// had 18% of its tries rejected at tol 1e-8 and 1e-10 under the standard
// 0.9 err^(-1/p) (issue 31, item 3: the required step shrinks by a fifth a
// step towards the perihelion, and every such step was rejected once); with
// Gustafsson's prediction and the aim 0.1 (emit_estimate.c) 0.2% and 7.6%
// (measured). The error at T still follows tol (within 30x, as above).
START_TEST(adaptive_few_rejections)
{
  double T = 20 * 3.141592653589793, q[4], p[4], qT[2], pT[2];
  ck_assert_int_eq(errest_reference("kepler", T, 1, 2, q, p), 0);
  for (double tol = 1e-8; tol > 1e-10 / 2; tol /= 100) {
    Adaptive a = adaptive_kepler_k4s4(T, tol, qT, pT);
    for (int i = 0; i < 2; i++) a.err = fmax(a.err, fmax(fabs(qT[i] - q[2 + i]), fabs(pT[i] - p[2 + i])));
    ck_assert_msg(a.rejected * 10 <= a.steps + a.rejected, "kepler (4,4), tol %g: %ld of %ld tries rejected", tol,
                  a.rejected, a.steps + a.rejected);
    ck_assert_msg(a.err <= 30 * tol, "kepler (4,4), tol %g: error %g", tol, a.err);
  }
}
END_TEST

// The tries of an adaptive run of solver P from its initial values to T at
// tol from h = 0.01, the last step shortened to end on T; the rejected ones
// in *rejected.
#define REJECTION_RUN(P)                                                                  \
  static long P##_tries(double T, double tol, long *rejected) {                           \
    P##_state x;                                                                          \
    P##_stats st;                                                                         \
    double h = 0.01;                                                                      \
    long n = 0;                                                                           \
    P##_init(&x, NULL, NULL);                                                             \
    *rejected = 0;                                                                        \
    while (x.t < T * (1 - 1e-12)) {                                                       \
      double left = T - x.t, hn = h < left ? h : left;                                    \
      ck_assert_int_eq(P##_step_adaptive(&x, &hn, tol, NULL, &st), 0);                    \
      if (h < left) h = hn;                                                               \
      *rejected += st.rejected;                                                           \
      n += 1 + st.rejected;                                                               \
    }                                                                                     \
    return n;                                                                             \
  }
REJECTION_RUN(double_pendulum_k4s4)
REJECTION_RUN(solar_k16s2)
REJECTION_RUN(kepler_k4s4)
REJECTION_RUN(kepler_k11s6)
REJECTION_RUN(kepler_k18s3)
REJECTION_RUN(dpa4_k4s4)

// At most 5% of the tries rejected (issue 31, item 3): the solar system
// (s = 2, |q| up to 40 AU, 20000 days) had 25% at every tol, a rejected try
// shrinking 2.4x too much (its error read over tol |h| without 1 + max|q|)
// and the steps growing back into the next rejection; the double pendulum
// poly (4,4) 9.4% and 6.8% under the standard aim (measured: 0%, 3.8%, 1.1%).
// Kepler e = 0.6 over ten periods, once an orbit a try rejected on the way to
// the perihelion, where the error at the same h grows 10-200x in a step, at
// (11,6) and (18,3) at tol 1e-6 and (4,4) at 1e-10: 5.3%, 8.5%, 5.5% with
// Gustafsson's prediction alone, 4.1%, 0%, 4.5% with the error's trend
// (emit_step_factor; measured with this loop).
// The run of solver P to T at tol rejects at most 5% of its tries.
#define UNDER_5_PERCENT(P, T, TOL)                                                                       \
  do {                                                                                                 \
    long rej_, n_ = P##_tries(T, TOL, &rej_);                                                          \
    ck_assert_msg(rej_ * 20 <= n_, #P ", tol %g: %ld of %ld tries rejected", (double)(TOL), rej_, n_); \
  } while (0)

START_TEST(adaptive_rejections_under_5_percent)
{
  const double T = 20 * 3.141592653589793;
  UNDER_5_PERCENT(kepler_k11s6, T, 1e-6);
  UNDER_5_PERCENT(kepler_k18s3, T, 1e-6);
  UNDER_5_PERCENT(kepler_k4s4, T, 1e-10);
  UNDER_5_PERCENT(solar_k16s2, 20000, 1e-10);
  /* the aim lowered by rejected tries (emit_step_factor): Kepler at tol 1e-5, once an
   * orbit a 10-200x jump of the error (11 of 170 and 16 of 246 tries without it), and the
   * double pendulum in angles, whose energy defect (k = s) scatters 10-1000x from step to
   * step (9 of 151 at 1e-8); measured 5 of 183, 7 of 263, 4 of 156 */
  UNDER_5_PERCENT(kepler_k11s6, T, 1e-5);
  UNDER_5_PERCENT(kepler_k4s4, T, 1e-5);
  UNDER_5_PERCENT(dpa4_k4s4, 10, 1e-8);
  UNDER_5_PERCENT(double_pendulum_k4s4, 10, 1e-6);
  UNDER_5_PERCENT(double_pendulum_k4s4, 10, 1e-8);
}
END_TEST

// The estimate's asymptotic range (issue 31, item 3): the outer solar system
// at (11,6) over 20000 days grew its 1000-day steps 1.8x past r = d1 / |h v|
// = 1, where NAME_err_est becomes d1 and jumps 4e4-fold, and each such try
// was rejected: 3 of 34, 3 of 34, 2 of 32 tries at tol 1e-4, 3e-5, 1e-5
// (measured with this loop); the steps now grow at most to r = 0.1
// (emit_range_cap): 0 of 27, 27, 28. The error at T stays within 30 tol,
// as in adaptive_proportional (measured 0.2-1.8 tol, 1-4.9 before),
// against the same solver at tol 1e-11 (its own error ~1e-9 here).
START_TEST(adaptive_asymptotic_range)
{
  double q[solar_k11s6_M], p[solar_k11s6_M], qT[solar_k11s6_M], pT[solar_k11s6_M];
  adaptive_solar_k11s6(20000, 1e-11, q, p);
  for (double tol = 1e-4; tol > 1e-5 / 2; tol /= sqrt(10)) {
    Adaptive a = adaptive_solar_k11s6(20000, tol, qT, pT);
    for (int i = 0; i < solar_k11s6_M; i++) a.err = fmax(a.err, fmax(fabs(qT[i] - q[i]), fabs(pT[i] - p[i])));
    ck_assert_msg(a.rejected * 20 <= a.steps + a.rejected, "solar (11,6), tol %g: %ld of %ld tries rejected", tol,
                  a.rejected, a.steps + a.rejected);
    ck_assert_msg(a.err <= 30 * tol, "solar (11,6), tol %g: error %g", tol, a.err);
  }
}
END_TEST

// The pendulum's turning point in the middle of a step (issue 31, item 3):
// the pendulum in its angle (6,6) from theta = 0, p = 1 (amplitude pi/3) to
// T = 10, h growing from 0.01, tried a step of 1.1-1.4 across its first
// turning point (t = 1.68), where the step's mean velocity gamma_0 is
// 0.02-0.12 of the velocity either side: r = d1 / |h gamma_0| went from 0.003
// to 0.15-2.2, and NAME_err_est, d1 itself past r = 1, rejected it, 1 of 17,
// 18, 17, 18 tries at tol 1e-4, 3e-5, 1e-5, 3e-6 (measured with this loop;
// bench/results/rejections.txt). The velocity's size is now the larger of
// gamma_0 and sqrt(3) gamma_1 (NAME_speed), which a turning point does not
// make vanish: 0 of 10-13. The error at T stays within 30 tol, as in
// adaptive_proportional, against the same solver at tol 1e-12.
START_TEST(adaptive_turning_point)
{
  double q[1], p[1], qT[1], pT[1];
  adaptive_pa6_k6s6(10, 1e-12, q, p);
  for (double tol = 1e-4; tol > 3e-6 / 2; tol /= sqrt(10)) {
    Adaptive a = adaptive_pa6_k6s6(10, tol, qT, pT);
    a.err = fmax(fabs(qT[0] - q[0]), fabs(pT[0] - p[0]));
    ck_assert_msg(a.rejected * 20 <= a.steps + a.rejected, "pendulum in its angle (6,6), tol %g: %ld of %ld tries rejected",
                  tol, a.rejected, a.steps + a.rejected);
    ck_assert_msg(a.err <= 30 * tol, "pendulum in its angle (6,6), tol %g: error %g", tol, a.err);
    if (getenv("HBVM_ERREST_TABLE"))
      printf("pa (6,6) tol=%-6g error at T=%.3e (%.3g tol) steps=%ld rejected=%ld\n", tol, a.err, a.err / tol, a.steps,
             a.rejected);
  }
}
END_TEST

// NAME_step_controlled: atol = rtol = tol takes NAME_step_adaptive's steps
// (to the rounding of (tol + tol s) / (1 + s), which the controller carried
// to 3.5e-6 of t over 76 steps of Kepler; since the error's trend, a rounding
// flips which prediction is smaller at step 42 (8e-5 of h), and the trend,
// which feeds err_{n-1} / err_n back, carries it on: the two grids part by a
// tenth of a step, 1.3e-2 at t = 10 after 83 steps);
// hmax bounds the step tried
// and the one proposed; a bad control is NAME_EBADSTEP with x unchanged.
START_TEST(adaptive_controls)
{
  kepler_k4s4_state a, b;
  kepler_k4s4_stats st;
  kepler_k4s4_controls c = {1e-8, 1e-8, 0};
  double ha = 0.01, hb = 0.01, T = 10;
  long na = 0, nb = 0;
  kepler_k4s4_init(&a, NULL, NULL);
  kepler_k4s4_init(&b, NULL, NULL);
  for (; a.t < T; na++) ck_assert_int_eq(kepler_k4s4_step_adaptive(&a, &ha, 1e-8, NULL, &st), 0);
  for (; b.t < T; nb++) ck_assert_int_eq(kepler_k4s4_step_controlled(&b, &hb, &c, NULL, &st), 0);
  ck_assert_msg(labs(na - nb) <= 2 && fabs(a.t - b.t) <= 0.2 * st.h, "%ld and %ld steps, to t = %.17g and %.17g", na,
                nb, a.t, b.t);
  c.hmax = 0.05;
  kepler_k4s4_init(&b, NULL, NULL);
  hb = 1;
  for (int k = 0; k < 100; k++) {
    ck_assert_int_eq(kepler_k4s4_step_controlled(&b, &hb, &c, NULL, &st), 0);
    ck_assert(st.h <= 0.05 && hb <= 0.05);
  }
  kepler_k4s4_state before = b;
  c.atol = c.rtol = 0;
  ck_assert_int_eq(kepler_k4s4_step_controlled(&b, &hb, &c, NULL, &st), kepler_k4s4_EBADSTEP);
  ck_assert_int_eq(kepler_k4s4_step_controlled(&b, &hb, NULL, NULL, &st), kepler_k4s4_EBADSTEP);
  ck_assert(memcmp(&b, &before, sizeof b) == 0);
}
END_TEST

// A state the adaptive step cannot start from (t, q or p not finite) is
// refused at once with NAME_ENONFINITE and left as it was (issue 30, item 6:
// with t = NaN the floor NAME_HMIN (1 + |t|) was never reached, and the tries
// went on forever, their counter overflowing). The alarm fails the test on
// the old code, which never returns.
START_TEST(adaptive_nonfinite_state)
{
  pendulum_poly_k3s3_state x, before;
  pendulum_poly_k3s3_stats st;
  const double bad[] = {NAN, INFINITY, -INFINITY};
  alarm(20);
  for (int k = 0; k < 9; k++) {
    double h = 0.1;
    pendulum_poly_k3s3_init(&x, NULL, NULL);
    if (k < 3) x.t = bad[k];
    else if (k < 6) x.q[1] = bad[k - 3];
    else x.p[0] = bad[k - 6];
    memcpy(&before, &x, sizeof x);
    ck_assert_int_eq(pendulum_poly_k3s3_step_adaptive(&x, &h, 1e-8, NULL, &st), pendulum_poly_k3s3_ENONFINITE);
    ck_assert_int_eq(memcmp(&before, &x, sizeof x), 0);
    ck_assert(h == 0.1);
  }
  alarm(0);
}
END_TEST

/* The sweeps of pendulum_poly_k3s3_step_adaptive over T = 10 at tol against
 * those of the fixed step at each accepted step's h from its state; the
 * largest |g| after a step in *gmax. */
static double sweeps_against_fixed(double tol, double *gmax) {
  pendulum_poly_k3s3_state x, y;
  pendulum_poly_k3s3_stats st, sf;
  double h = 0.01, g[1];
  long na = 0, nf = 0;
  *gmax = 0;
  pendulum_poly_k3s3_init(&x, NULL, NULL);
  while (x.t < 10) {
    y = x;
    ck_assert_int_eq(pendulum_poly_k3s3_step_adaptive(&x, &h, tol, NULL, &st), 0);
    pendulum_poly_k3s3_constraints(&x, NULL, g);
    *gmax = fmax(*gmax, fabs(g[0]));
    if (st.rejected) continue;
    ck_assert_int_eq(pendulum_poly_k3s3_step(&y, st.h, NULL, &sf), 0);
    na += st.iters;
    nf += sf.iters;
  }
  return (double)na / (double)nf;
}

// Under a tolerance the polynomial family's iteration stops where the error
// it leaves is NAME_ITERC of the step's tolerance (NAME_itol), not at
// round-off; a Newton step then puts q1 back on g = 0, and the projection and
// rescale keep the hidden constraint and H (adaptive_proportional). Over the
// pendulum (s = 3) the accepted steps take 0.60 of the fixed step's sweeps at
// tol 1e-6 and 0.76 at 1e-8 (measured); at 1e-13 the tolerance is below
// round-off and the iteration the fixed step's.
START_TEST(adaptive_iteration_stops_at_tolerance)
{
  double gmax, r6 = sweeps_against_fixed(1e-6, &gmax);
  ck_assert_msg(r6 <= 0.7, "tol 1e-6: %.3f of the fixed step's sweeps", r6);
  ck_assert_double_le(gmax, 1e-13);
  double r8 = sweeps_against_fixed(1e-8, &gmax);
  ck_assert_msg(r8 <= 0.85, "tol 1e-8: %.3f of the fixed step's sweeps", r8);
  ck_assert_double_le(gmax, 1e-13);
  ck_assert_double_eq(sweeps_against_fixed(1e-13, &gmax), 1);
}
END_TEST

Suite *adaptive_suite(void) {
  Suite *s = suite_create("adaptive");
  TCase *tc = tcase_create("adaptive");
  tcase_set_tags(tc, "sanlong"); /* the generated arithmetic: sanitized in check-long */
  tcase_add_loop_test(tc, adaptive_proportional, 0, (int)(sizeof adaptive_cases / sizeof adaptive_cases[0]));
  tcase_add_loop_test(tc, adaptive_const_proportional, 0, 2);
  tcase_add_test(tc, adaptive_from_rest_tight);
  tcase_add_test(tc, adaptive_rejected_unchanged);
  tcase_add_test(tc, adaptive_nonfinite_state);
  tcase_add_test(tc, adaptive_few_rejections);
  tcase_add_test(tc, adaptive_rejections_under_5_percent);
  tcase_add_test(tc, adaptive_asymptotic_range);
  tcase_add_test(tc, adaptive_turning_point);
  tcase_add_test(tc, adaptive_controls);
  tcase_add_test(tc, adaptive_iteration_stops_at_tolerance);
  tcase_add_test(tc, adaptive_quadrature_defect);
  tcase_set_timeout(tc, 60);
  suite_add_tcase(s, tc);
  return s;
}
