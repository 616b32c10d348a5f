/* check_stiff.c - Check suite "stiff": issue 27's tests of --iteration
 * newton on three stiff fields, beyond check_newton.c's (which this suite
 * does not repeat):
 *
 *   FPU chain (models/fpu.ham, HBVM(4,2)), Hairer, Lubich, Wanner, GNI I.5, XIII:
 *     fpu long steps  h omega = 1000 at omega = 1000 and 30 at omega = 50
 *                     converge in a bounded number of iterations, H at
 *                     round-off;
 *     fpu slow 50     the slow motion at omega = 50 against the fixed-point
 *                     step at h omega = 0.1;
 *     fpu adiabatic   the oscillatory energy I stays within a bound
 *                     independent of h omega over long runs at omega = 1000
 *                     (tagged long: check-long).
 *   Stiff bob (models/stiff_bob.ham, HBVM(16,2), --multiplier const):
 *     bob longest     at the largest h omega measured to keep the slow
 *                     motion within 1e-3 of the reference (the scan of bench/stiff/run.sh,
 *                     bench/results/stiff_scan.csv), a point just below it
 *                     still does, with g and H at round-off (long).
 *   A butane-like molecule (models/butane.ham, HBVM(4,2), --multiplier
 *   const: rigid bonds, stiff bond angles, a soft torsion):
 *     molecule        converges at h omega = 10 and 13 (ka = 1e4) and 10, 30
 *                     (ka = 1e6) in a bounded number of iterations, g and H at
 *                     round-off, the torsion angle at T = 10 within a bound of
 *                     the fixed-point step at h omega = 1/4; a failed step
 *                     rolls back byte-exact.
 * The bounds on the slow error are the measured values (same generated code,
 * same inputs: deterministic) with a margin of 2-4x; the round-off bounds are
 * check_newton.c's: 8 ulps of (1 + h omega) |H0| a step as a random walk. */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dihedral.h"
#include "butane_fixed_k4s2.h"
#include "butane_newton_k4s2.h"
#include "fpu_fixed_k4s2.h"
#include "fpu_newton_k4s2.h"
#include "stiff_bob_fixed_k16s2.h"
#include "stiff_bob_newton_k16s2.h"
#include "butane_polyfixed_k4s2.h"
#include "butane_polynewton_k4s2.h"
#include "stiff_bob_polyfixed_k16s2.h"
#include "stiff_bob_polynewton_k16s2.h"

Suite *stiff_suite(void);

/* What a run leaves: iterations and factorisations a step (mean, max), the
 * largest |H - H0|, |g| and deviation of a watched quantity, the end state. */
typedef struct {
  long steps;
  int failed, max_iters, max_factors;
  double iters, factors, H0, dH, g, hc, watch_dev;
  double q[12], p[12];
} Run;

/* A quantity watched along a run (its largest deviation from the start). */
typedef double (*Watch)(const double *q, const double *p, double param);

/* Account for one accepted step (gp: the hidden constraint grad g' M^-1 p). */
static void run_step(Run *r, int iters, int factors, double H, const double *g, const double *gp, int nu, double w,
                     double w0) {
  r->iters += iters;
  r->factors += factors;
  if (iters > r->max_iters) r->max_iters = iters;
  if (factors > r->max_factors) r->max_factors = factors;
  r->dH = fmax(r->dH, fabs(H - r->H0));
  for (int a = 0; a < nu; a++) {
    r->g = fmax(r->g, fabs(g[a]));
    r->hc = fmax(r->hc, fabs(gp[a]));
  }
  r->watch_dev = fmax(r->watch_dev, fabs(w - w0));
}

/* run_S(param, h, steps, watch): `steps` steps of h with solver S from the
 * model's start, the parameter PARAM set to param; watch may be NULL. */
#define DEFINE_RUN(S, PARAM)                                                                                       \
  static Run run_##S(double param, double h, long steps, Watch watch) {                                           \
    S##_params prm;                                                                                                \
    S##_state x;                                                                                                   \
    Run r;                                                                                                         \
    memset(&r, 0, sizeof r);                                                                                       \
    S##_params_default(&prm);                                                                                      \
    prm.PARAM = param;                                                                                             \
    S##_init_params(&x, NULL, NULL, &prm);                                                                         \
    r.H0 = S##_energy(&x, &prm);                                                                                   \
    double w0 = watch ? watch(x.q, x.p, param) : 0;                                                                \
    for (r.steps = 0; r.steps < steps; r.steps++) {                                                                \
      S##_stats st;                                                                                                \
      double g[4] = {0}, gp[4] = {0};                                                                              \
      if (S##_step(&x, h, &prm, &st) != S##_OK) {                                                                  \
        r.failed = 1;                                                                                              \
        break;                                                                                                     \
      }                                                                                                            \
      S##_constraints(&x, &prm, g);                                                                                \
      S##_hidden(&x, &prm, gp);                                                                                    \
      run_step(&r, st.iters, st.factors, S##_energy(&x, &prm), g, gp, S##_NU, watch ? watch(x.q, x.p, param) : 0,  \
               w0);                                                                                                \
    }                                                                                                              \
    if (r.steps) {                                                                                                 \
      r.iters /= r.steps;                                                                                          \
      r.factors /= r.steps;                                                                                        \
    }                                                                                                              \
    memcpy(r.q, x.q, sizeof x.q);                                                                                  \
    memcpy(r.p, x.p, sizeof x.p);                                                                                  \
    return r;                                                                                                      \
  }

DEFINE_RUN(fpu_newton_k4s2, omega)
DEFINE_RUN(stiff_bob_newton_k16s2, k)
DEFINE_RUN(butane_newton_k4s2, ka)
DEFINE_RUN(stiff_bob_polynewton_k16s2, k)
DEFINE_RUN(butane_polynewton_k4s2, ka)

/* ref_S(param, h, steps, q): q after `steps` fixed-point steps of h from the
 * model's start (the reference), every step asserted to succeed. */
#define DEFINE_REF(S, PARAM)                                                           \
  static void ref_##S(double param, double h, long steps, double *q) {                \
    S##_params prm;                                                                    \
    S##_state x;                                                                       \
    S##_params_default(&prm);                                                          \
    prm.PARAM = param;                                                                 \
    S##_init_params(&x, NULL, NULL, &prm);                                             \
    for (long n = 0; n < steps; n++) ck_assert_int_eq(S##_step(&x, h, &prm, NULL), S##_OK); \
    memcpy(q, x.q, sizeof x.q);                                                        \
  }

DEFINE_REF(fpu_fixed_k4s2, omega)
DEFINE_REF(stiff_bob_fixed_k16s2, k)
DEFINE_REF(butane_fixed_k4s2, ka)
DEFINE_REF(stiff_bob_polyfixed_k16s2, k)
DEFINE_REF(butane_polyfixed_k4s2, ka)

/* H within 8 ulps of (1 + h omega) |H0| a step, as a random walk. */
static double h_bound(const Run *r, double hw) { return 8 * DBL_EPSILON * (1 + hw) * fabs(r->H0) * sqrt((double)r->steps); }

/* Every step converged in at most max_iters iterations and max_factors
 * factorisations, H within h_bound, |g| within g_bound. */
static void assert_run(const char *what, const Run *r, double hw, int max_iters, int max_factors, double g_bound) {
  ck_assert_msg(!r->failed, "%s, h omega = %g: step %ld failed", what, hw, r->steps);
  ck_assert_msg(r->max_iters <= max_iters && r->max_factors <= max_factors,
                "%s, h omega = %g: %d iterations, %d factorisations (%.2f, %.2f a step)", what, hw, r->max_iters,
                r->max_factors, r->iters, r->factors);
  ck_assert_msg(r->dH <= h_bound(r, hw), "%s, h omega = %g: |H - H0| = %.3g > %.3g", what, hw, r->dH, h_bound(r, hw));
  ck_assert_msg(r->g <= g_bound, "%s, h omega = %g: |g| = %.3g > %.3g", what, hw, r->g, g_bound);
}

/* ---- the FPU chain ---- */

/* The oscillatory energy of the stiff springs, I = sum (p1^2 + omega^2 x1^2) / 2. */
static double fpu_stiff_energy(const double *q, const double *p, double omega) {
  double I = 0;
  for (int i = 3; i < 6; i++) I += (p[i] * p[i] + omega * omega * q[i] * q[i]) / 2;
  return I;
}

/* h omega = 1000 at omega = 1000 (h = 1, T = 20; measured 24 iterations and
 * 2.5 factorisations a step, docs/method-newton.md) and h omega = 30 at
 * omega = 50 (T = 20; measured 15.4 (24) and 1.0). At most 40 iterations
 * and NAME_REFRESH = 4 factorisations. */
START_TEST(test_fpu_long_steps) {
  static const struct {
    double omega, h;
  } cases[] = {{1000, 1}, {50, 0.6}};
  for (int c = 0; c < 2; c++) {
    Run r = run_fpu_newton_k4s2(cases[c].omega, cases[c].h, lround(20 / cases[c].h), NULL);
    assert_run("fpu", &r, cases[c].omega * cases[c].h, 40, 4, 0);
  }
}
END_TEST

/* The slow motion (x0) at T = 20, omega = 50, against the fixed-point step
 * at h omega = 0.1 (h = 0.002): measured 4.6e-5 at h omega = 1 and 9.6e-3
 * at h omega = 10 (h = 0.2: there the step's order 4 on the slow motion's
 * own time scale sets the error, not omega); the bounds 4x. */
START_TEST(test_fpu_slow_50) {
  double ref[6];
  ref_fpu_fixed_k4s2(50, 0.002, 10000, ref);
  static const double h[2] = {0.02, 0.2}, bound[2] = {1.9e-4, 3.9e-2};
  for (int c = 0; c < 2; c++) {
    Run r = run_fpu_newton_k4s2(50, h[c], lround(20 / h[c]), NULL);
    double err = 0;
    for (int i = 0; i < 3; i++) err = fmax(err, fabs(r.q[i] - ref[i]));
    ck_assert_msg(!r.failed && err <= bound[c], "h omega = %g: slow error %.3g > %.3g", 50 * h[c], err, bound[c]);
  }
}
END_TEST

/* The adiabatic invariant I (I0 = 1) at omega = 1000 over T = 1000 at h omega
 * = 10, 100 and 1000 (10^5, 10^4, 10^3 steps; GNI XIII: its variation stays
 * O(1 / omega) for good methods): measured max |I - I0| 3.5e-3, 3.4e-3 and
 * 3.7e-3, the same at every h omega, no drift; bound 1e-2. Iterations a
 * step 4.0 (6), 5.7 (7), 23 (32) with 1.0, 1.0, 2.2 factorisations. */
START_TEST(test_fpu_adiabatic) {
  static const double h[3] = {0.01, 0.1, 1};
  for (int c = 0; c < 3; c++) {
    Run r = run_fpu_newton_k4s2(1000, h[c], lround(1000 / h[c]), fpu_stiff_energy);
    ck_assert_msg(!r.failed, "h omega = %g: step %ld failed", 1000 * h[c], r.steps);
    ck_assert_msg(r.watch_dev <= 1e-2, "h omega = %g: max |I - I0| = %.3g", 1000 * h[c], r.watch_dev);
  }
}
END_TEST

/* ---- the stiff bob ---- */

/* The bob's centre of mass, (x1 + x2) / 2, (y1 + y2) / 2, from q. */
static double com_error(const double *q, const double *ref) {
  return fmax(fabs(q[0] + q[2] - ref[0] - ref[2]), fabs(q[1] + q[3] - ref[1] - ref[3])) / 2;
}

/* The bob's centre of mass at T = 10 against the fixed-point step at h omega
 * = 1/4, just below the longest step that keeps it within 1e-3
 * (bench/results/stiff_scan.csv): h omega = 40 at k = 1e4 (measured 4.6e-5,
 * 29.4 (58) iterations and 3.3 (4) factorisations a step) and 100 at k = 1e6
 * (6.2e-5, 19.6 (44), 2.8 (4)). g within 2 ulps of its scale 1. */
START_TEST(test_bob_longest) {
  static const struct {
    double k, hw;
  } cases[] = {{1e4, 40}, {1e6, 100}};
  for (int c = 0; c < 2; c++) {
    double omega = sqrt(2 * cases[c].k), ref[4];
    long n_ref = lround(10 * omega / 0.25), n = lround(10 * omega / cases[c].hw);
    ref_stiff_bob_fixed_k16s2(cases[c].k, 10.0 / n_ref, n_ref, ref);
    Run r = run_stiff_bob_newton_k16s2(cases[c].k, 10.0 / n, n, NULL);
    assert_run("bob", &r, cases[c].hw, 80, 4, 2 * DBL_EPSILON);
    ck_assert_msg(com_error(r.q, ref) <= 1e-3, "k = %g, h omega = %g: slow error %.3g", cases[c].k, cases[c].hw,
                  com_error(r.q, ref));
  }
}
END_TEST

/* ---- the molecule ---- */

/* omega = 1.751 sqrt(ka) (models/butane.ham). */
static double butane_omega(double ka) { return 1.751 * sqrt(ka); }

/* Converged at every step over T = 10, at most 40 iterations and 4
 * factorisations (measured 9.0 (11), 10.0 (12), 6.0 (8) and 7.9 (10)
 * iterations a step, one factorisation), g within 8 ulps of the coordinates' size
 * (up to 2.5: an ulp of q is 2 eps, g a sum of squared differences), H at
 * round-off; the torsion angle at T against the fixed-point step at h omega
 * = 1/4: measured 1.6e-4, 5.8e-4, 9.7e-8, 7.7e-6, the bounds 4x (1e-3, the
 * issue's limit, at ka = 1e4, h omega = 13). 13 is the longest step below
 * which every h omega of the scan (bench/results/stiff_scan.csv, steps of
 * 1.15) keeps the torsion within 1e-3; longer ones do not all (1.5e-3 at
 * 15.5, 1.2e-2 at 17.9, but 1.8e-4 at 20.6: the error is not monotone in h
 * omega there). */
START_TEST(test_molecule) {
  static const struct {
    double ka, hw, bound;
  } cases[] = {{1e4, 10, 6.5e-4}, {1e4, 13, 1e-3}, {1e6, 10, 4e-7}, {1e6, 30, 3.1e-5}};
  for (int c = 0; c < 4; c++) {
    double omega = butane_omega(cases[c].ka), ref[12];
    long n_ref = lround(10 * omega / 0.25), n = lround(10 * omega / cases[c].hw);
    if (c == 0 || cases[c].ka != cases[c - 1].ka) ref_butane_fixed_k4s2(cases[c].ka, 10.0 / n_ref, n_ref, ref);
    Run r = run_butane_newton_k4s2(cases[c].ka, 10.0 / n, n, NULL);
    double err = fabs(dihedral(r.q) - dihedral(ref));
    assert_run("molecule", &r, cases[c].hw, 40, 4, 16 * DBL_EPSILON);
    ck_assert_msg(err <= cases[c].bound, "ka = %g, h omega = %g: torsion error %.3g > %.3g", cases[c].ka, cases[c].hw,
                  err, cases[c].bound);
  }
}
END_TEST

/* A step too long for the iteration (h omega = 300 at ka = 1e4) fails and
 * leaves the state unchanged to the byte. */
START_TEST(test_molecule_rollback) {
  butane_newton_k4s2_state x, before;
  butane_newton_k4s2_params prm;
  butane_newton_k4s2_params_default(&prm);
  memset(&x, 0, sizeof x);
  butane_newton_k4s2_init_params(&x, NULL, NULL, &prm);
  double omega = butane_omega(prm.ka);
  for (int n = 0; n < 3; n++)
    ck_assert_int_eq(butane_newton_k4s2_step(&x, 10 / omega, &prm, NULL), butane_newton_k4s2_OK);
  memcpy(&before, &x, sizeof x);
  int rc = butane_newton_k4s2_step(&x, 300 / omega, &prm, NULL);
  ck_assert_int_ne(rc, butane_newton_k4s2_OK);
  ck_assert_msg(!memcmp(&before, &x, sizeof x), "the failed step (%s) changed the state",
                butane_newton_k4s2_strerror(rc));
}
END_TEST

/* ---- the poly family (the default with constraints) ---- */

/* Converged at every step over T = 10 in the poly family (Newton on gamma
 * and the multiplier's s nu coefficients), g, H and the hidden constraint at
 * round-off (the projection and the rescale hold them), the slow motion
 * against the poly family's fixed-point step at h omega = 1/4: the bob's
 * centre of mass at h omega = 10, 30 (k = 1e4) and 10, 100 (k = 1e6), the
 * molecule's torsion at h omega = 10 (ka = 1e4) and 10, 30 (ka = 1e6).
 * Measured (iterations a step, mean (max), factorisations a step; slow
 * error): bob k = 1e4, h omega = 10: 13.6 (18), 1.0, 4.2e-5; 30: 19.8 (27),
 * 3.0, 1.4e-5; k = 1e6, 10: 6.6 (8), 0.87, 2.8e-9; 100: 21.6 (44), 3.0,
 * 1.3e-5; molecule ka = 1e4, 10: 9.6 (11), 1.0, 7.5e-5; ka = 1e6, 10: 6.5
 * (8), 0.92, 2.0e-6; 30: 7.8 (9), 0.99, 5.9e-6. |g| <= 4.4e-16, the hidden
 * constraint <= 1.4e-16, |H - H0| <= 2.2e-16 in every run.
 * Bounds: the slow errors 4x, at most 80 iterations and NAME_REFRESH = 4
 * factorisations a step, g within 2 ulps of its scale (16 for the molecule,
 * as above), the hidden constraint within 2 ulps of |p| ~ 1. Fails on a
 * generator without Newton in the poly family (it refused these models). */
START_TEST(test_poly_bob) {
  double ref[4] = {0};
  static const struct {
    double k, hw, bound;
  } cases[] = {{1e4, 10, 1.7e-4}, {1e4, 30, 5.5e-5}, {1e6, 10, 1.1e-8}, {1e6, 100, 5.2e-5}};
  for (int c = 0; c < 4; c++) {
    double omega = sqrt(2 * cases[c].k);
    long n_ref = lround(10 * omega / 0.25), n = lround(10 * omega / cases[c].hw);
    if (c == 0 || cases[c].k != cases[c - 1].k) ref_stiff_bob_polyfixed_k16s2(cases[c].k, 10.0 / n_ref, n_ref, ref);
    Run r = run_stiff_bob_polynewton_k16s2(cases[c].k, 10.0 / n, n, NULL);
    assert_run("poly bob", &r, cases[c].hw, 80, 4, 2 * DBL_EPSILON);
    ck_assert_msg(r.hc <= 2 * DBL_EPSILON, "k = %g, h omega = %g: hidden constraint %.3g", cases[c].k, cases[c].hw, r.hc);
    ck_assert_msg(com_error(r.q, ref) <= cases[c].bound, "k = %g, h omega = %g: slow error %.3g > %.3g", cases[c].k,
                  cases[c].hw, com_error(r.q, ref), cases[c].bound);
  }
}
END_TEST

START_TEST(test_poly_molecule) {
  double ref[12] = {0};
  static const struct {
    double ka, hw, bound;
  } cases[] = {{1e4, 10, 3e-4}, {1e6, 10, 8.1e-6}, {1e6, 30, 2.4e-5}};
  for (int c = 0; c < 3; c++) {
    double omega = butane_omega(cases[c].ka);
    long n_ref = lround(10 * omega / 0.25), n = lround(10 * omega / cases[c].hw);
    if (c == 0 || cases[c].ka != cases[c - 1].ka) ref_butane_polyfixed_k4s2(cases[c].ka, 10.0 / n_ref, n_ref, ref);
    Run r = run_butane_polynewton_k4s2(cases[c].ka, 10.0 / n, n, NULL);
    double err = fabs(dihedral(r.q) - dihedral(ref));
    assert_run("poly molecule", &r, cases[c].hw, 80, 4, 16 * DBL_EPSILON);
    ck_assert_msg(r.hc <= 4 * DBL_EPSILON, "ka = %g, h omega = %g: hidden constraint %.3g", cases[c].ka, cases[c].hw, r.hc);
    ck_assert_msg(err <= cases[c].bound, "ka = %g, h omega = %g: torsion error %.3g > %.3g", cases[c].ka, cases[c].hw,
                  err, cases[c].bound);
  }
}
END_TEST

/* The poly family's Newton loop starts from the one-step start and stops at an
 * increment below an eighth of an ulp (or at round-off noise), so it takes
 * fewer iterations a step than it did from the two-step start (whose
 * coefficients, up to 166 at s = 3, magnify the stiff motion a long step does
 * not resolve) and to a 256th of an ulp. Measured, mean (max) iterations a step
 * over T = 10 at h omega = 10: the bob (k = 1e4) 10.4 (13), before 13.6 (18);
 * the molecule (ka = 1e4) 8.87 (10), before 9.63 (11); one factorisation a
 * step in each; |g| within 2 ulps as before. Bounds: the means 11.5 and 9.3,
 * 10% and 5% above the measured, below the old ones. Fails on the old
 * generator (13.6 > 11.5, 9.63 > 9.3). */
START_TEST(test_poly_iterations) {
  double omega = sqrt(2e4);
  long n = lround(10 * omega / 10);
  Run r = run_stiff_bob_polynewton_k16s2(1e4, 10.0 / n, n, NULL);
  assert_run("poly bob", &r, 10, 80, 4, 2 * DBL_EPSILON);
  ck_assert_msg(r.iters <= 11.5, "bob, h omega = 10: %.2f iterations a step (> 11.5)", r.iters);
  omega = butane_omega(1e4);
  n = lround(10 * omega / 10);
  r = run_butane_polynewton_k4s2(1e4, 10.0 / n, n, NULL);
  assert_run("poly molecule", &r, 10, 80, 4, 16 * DBL_EPSILON);
  ck_assert_msg(r.iters <= 9.3, "molecule, h omega = 10: %.2f iterations a step (> 9.3)", r.iters);
}
END_TEST

/* A step too long for the poly family's Newton iteration fails (the bob at
 * h = 0.71, h omega = 100 at k = 1e4; the molecule at h omega = 300) and
 * leaves the state unchanged to the byte: the kept factor, the two-step
 * history, the energy H0 the rescale holds, the compensations. */
#define DEFINE_ROLLBACK(S, H_OK, H_FAIL)                                                                  \
  static void rollback_##S(void) {                                                                     \
    S##_state x, before;                                                                               \
    S##_params prm;                                                                                    \
    S##_params_default(&prm);                                                                          \
    memset(&x, 0, sizeof x);                                                                           \
    S##_init_params(&x, NULL, NULL, &prm);                                                             \
    for (int n = 0; n < 3; n++) ck_assert_int_eq(S##_step(&x, H_OK, &prm, NULL), S##_OK);              \
    memcpy(&before, &x, sizeof x);                                                                     \
    int rc = S##_step(&x, H_FAIL, &prm, NULL);                                                         \
    ck_assert_int_ne(rc, S##_OK);                                                                      \
    ck_assert_msg(!memcmp(&before, &x, sizeof x), "the failed step (%s) changed the state", S##_strerror(rc)); \
  }

DEFINE_ROLLBACK(stiff_bob_polynewton_k16s2, 0.07, 0.71)
DEFINE_ROLLBACK(butane_polynewton_k4s2, 10 / butane_omega(1e4), 300 / butane_omega(1e4))

START_TEST(test_poly_rollback) {
  rollback_stiff_bob_polynewton_k16s2();
  rollback_butane_polynewton_k4s2();
}
END_TEST

Suite *stiff_suite(void) {
  Suite *s = suite_create("stiff");
  TCase *fpu = tcase_create("fpu");
  tcase_set_timeout(fpu, 120);
  tcase_add_test(fpu, test_fpu_long_steps);
  tcase_add_test(fpu, test_fpu_slow_50);
  suite_add_tcase(s, fpu);
  TCase *mol = tcase_create("molecule");
  tcase_set_timeout(mol, 120);
  tcase_add_test(mol, test_molecule);
  tcase_add_test(mol, test_molecule_rollback);
  suite_add_tcase(s, mol);
  TCase *poly = tcase_create("poly");
  tcase_set_timeout(poly, 120);
  tcase_add_test(poly, test_poly_bob);
  tcase_add_test(poly, test_poly_molecule);
  tcase_add_test(poly, test_poly_iterations);
  tcase_add_test(poly, test_poly_rollback);
  suite_add_tcase(s, poly);
  TCase *lng = tcase_create("stiff long");
  tcase_set_timeout(lng, 300);
  tcase_set_tags(lng, "long");
  tcase_add_test(lng, test_fpu_adiabatic);
  tcase_add_test(lng, test_bob_longest);
  suite_add_tcase(s, lng);
  return s;
}
