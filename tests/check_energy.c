/* check_energy.c - Check suite for the energy rescale of a model without
 * constraints and with a constant M (--energy rescale, the default at -k auto
 * for a U that is not a polynomial: docs/method-const.md, "Energy without
 * constraints"), on models/pendulum_angle.ham and models/kepler.ham at k = s,
 * s = 1..4 (tests/models/LIST: pa_res, kep_res):
 *   energy    max |H - H0| at round-off over 10^5 steps, where k = s without
 *             the rescale (generated/kepler_kSsS, pa_plain) is far from it.
 *   order     the error at T falls like h^(2s): Kepler (e = 0.6) after one
 *             period (the exact solution is back at q0, p0), the pendulum
 *             at T = 10 against rk8pd at 1e-14.
 *   rest      at the pendulum's equilibrium (K = 0) the step leaves p at 0
 *             (no beta = 0/0); released from rest, the turning points do not
 *             make the error larger than the quadrature's (k = 16, pa_quad).
 *   check     -k auto chooses k = s and says so; --energy quadrature 2s+12.
 * HBVM_ENERGY_TABLE=1 prints the measured figures. */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include "generate.h"
#include "kep_res_k1s1.h"
#include "kep_res_k2s2.h"
#include "kep_res_k3s3.h"
#include "kep_res_k4s4.h"
#include "kepler_k2s2.h"
#include "kepler_k4s4.h"
#include "pa_plain_k2s2.h"
#include "pa_quad_k16s2.h"
#include "pa_res_k1s1.h"
#include "pa_res_k2s2.h"
#include "pa_res_k3s3.h"
#include "pa_res_k4s4.h"

Suite *energy_suite(void);

#define PI 3.14159265358979323846
#define ULP 2.220446049250313e-16

/* ---- the solvers behind one interface ---- */

typedef struct {
  const char *name;
  int m, s;
  void (*init)(double *x, const double *q0, const double *p0); /* x: a state buffer */
  int (*step)(double *x, double h);
  double (*energy)(const double *x);
  void (*get)(const double *x, double *q, double *p);
} Solver;

#define WRAP(P)                                                                               \
  static void P##_i(double *x, const double *q0, const double *p0) { P##_init((void *)x, q0, p0); } \
  static int P##_st(double *x, double h) { return P##_step((void *)x, h, 0, 0); }          \
  static double P##_e(const double *x) { return P##_energy((const void *)x, 0); }          \
  static void P##_g(const double *x, double *q, double *p) {                                \
    const P##_state *y = (const void *)x;                                                   \
    for (int i = 0; i < P##_M; i++) {                                                       \
      q[i] = y->q[i];                                                                       \
      p[i] = y->p[i];                                                                       \
    }                                                                                       \
  }
#define ENTRY(P) {#P, P##_M, P##_S, P##_i, P##_st, P##_e, P##_g}

WRAP(pa_res_k1s1)
WRAP(pa_res_k2s2)
WRAP(pa_res_k3s3)
WRAP(pa_res_k4s4)
WRAP(kep_res_k1s1)
WRAP(kep_res_k2s2)
WRAP(kep_res_k3s3)
WRAP(kep_res_k4s4)
WRAP(pa_plain_k2s2)
WRAP(pa_quad_k16s2)
WRAP(kepler_k2s2)
WRAP(kepler_k4s4)

static const Solver PA_RES[4] = {ENTRY(pa_res_k1s1), ENTRY(pa_res_k2s2), ENTRY(pa_res_k3s3), ENTRY(pa_res_k4s4)};
static const Solver KEP_RES[4] = {ENTRY(kep_res_k1s1), ENTRY(kep_res_k2s2), ENTRY(kep_res_k3s3),
                                  ENTRY(kep_res_k4s4)};
static const Solver PA_PLAIN = ENTRY(pa_plain_k2s2), PA_QUAD = ENTRY(pa_quad_k16s2);
static const Solver KEP_PLAIN[2] = {ENTRY(kepler_k2s2), ENTRY(kepler_k4s4)};

#define STATE_WORDS 1024 /* doubles: more than any state above */

static int table(void) { return getenv("HBVM_ENERGY_TABLE") != NULL; }

// n steps of h from the model's q0, p0 (or from q0, p0 when given): max
// |H - H0| over the run; the final q, p into q, p when given, and the max
// over the run of |p| (a failed step or a state not finite fails the test).
static double run(const Solver *sv, const double *q0, const double *p0, double h, long n, double *q, double *p) {
  static double x[STATE_WORDS];
  double qq[2], pp[2], dH = 0, H0;
  sv->init(x, q0, p0);
  H0 = sv->energy(x);
  for (long i = 0; i < n; i++) {
    ck_assert_msg(sv->step(x, h) == 0, "%s: step %ld of h = %g failed", sv->name, i, h);
    double d = fabs(sv->energy(x) - H0);
    ck_assert_msg(isfinite(d), "%s: H not finite at step %ld", sv->name, i);
    if (d > dH) dH = d;
  }
  sv->get(x, q ? q : qq, p ? p : pp);
  return dH;
}

/* ---- the references ---- */

static int pendulum_rhs(double t, const double *y, double *dy, void *par) {
  (void)t;
  (void)par;
  dy[0] = y[1];
  dy[1] = -sin(y[0]);
  return GSL_SUCCESS;
}

// The pendulum (theta'' = -sin theta) at T from (q0, p0): rk8pd at 1e-14.
static void pendulum_reference(double q0, double p0, double T, double *q, double *p) {
  gsl_odeiv2_system sys = {pendulum_rhs, NULL, 2, NULL};
  gsl_odeiv2_driver *dr = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-4, 1e-14, 1e-14);
  double y[2] = {q0, p0}, t = 0;
  ck_assert_int_eq(gsl_odeiv2_driver_apply(dr, &t, T, y), GSL_SUCCESS);
  gsl_odeiv2_driver_free(dr);
  *q = y[0];
  *p = y[1];
}

// The max-norm error of (q, p) at T = n h against (qr, pr).
static double error_at(const Solver *sv, double h, long n, const double *qr, const double *pr) {
  double q[2], p[2], e = 0;
  run(sv, NULL, NULL, h, n, q, p);
  for (int i = 0; i < sv->m; i++) e = fmax(e, fmax(fabs(q[i] - qr[i]), fabs(p[i] - pr[i])));
  return e;
}

/* ---- energy ---- */

START_TEST(energy_at_roundoff_at_k_s) {
  /* at k = s the quadrature alone leaves |H - H0| at 1e-6..1e-12 at these h
   * (the contrast below); the rescale puts H back at H0 every step, so the
   * max over the run is a few ulps of |K| + |U| (pendulum: 1.5, Kepler: 1) */
  double ph[4] = {0.25, 0.25, 0.1, 0.25}, kh[4] = {2 * PI / 400, 2 * PI / 200, 2 * PI / 100, 2 * PI / 100};
  for (int s = 1; s <= 4; s++) {
    double pa = run(&PA_RES[s - 1], NULL, NULL, ph[s - 1], 100000, NULL, NULL);
    double ke = run(&KEP_RES[s - 1], NULL, NULL, kh[s - 1], 100000, NULL, NULL);
    if (table()) printf("energy s=%d: pendulum h %.3g max|H-H0| %.2e; Kepler h %.4g %.2e\n", s, ph[s - 1], pa, kh[s - 1], ke);
    ck_assert_msg(pa <= 8 * ULP * 1.5, "HBVM(%d,%d) rescaled, pendulum: max |H - H0| = %.2e", s, s, pa);
    ck_assert_msg(ke <= 8 * ULP * 1.0, "HBVM(%d,%d) rescaled, Kepler: max |H - H0| = %.2e", s, s, ke);
  }
  /* at h = 0.25, s = 3, a few steps end past a turning point (U(q1) > H0: no p
   * restores H); the next step makes it up, H0 being kept (x->Hend). Taking
   * H0 anew there, as a change of the state, moved the run's energy for good:
   * 85308 of the 10^5 steps off */
  {
    static double x[STATE_WORDS];
    const Solver *sv = &PA_RES[2];
    long off = 0;
    sv->init(x, NULL, NULL);
    double H0 = sv->energy(x);
    for (long i = 0; i < 100000; i++) {
      ck_assert_int_eq(sv->step(x, 0.25), 0);
      off += !(fabs(sv->energy(x) - H0) <= 8 * ULP * 1.5);
    }
    if (table()) printf("energy s=3, h = 0.25: %ld of 10^5 steps off round-off\n", off);
    ck_assert_msg(off <= 10, "HBVM(3,3) rescaled, h = 0.25: %ld of 10^5 steps with |H - H0| off round-off", off);
  }
  /* without the rescale, the same k = s: far from round-off */
  double pa = run(&PA_PLAIN, NULL, NULL, 0.25, 1000, NULL, NULL);
  double k2 = run(&KEP_PLAIN[0], NULL, NULL, 2 * PI / 200, 1000, NULL, NULL);
  double k4 = run(&KEP_PLAIN[1], NULL, NULL, 2 * PI / 100, 1000, NULL, NULL);
  if (table()) printf("energy without the rescale: pendulum (2,2) %.2e, Kepler (2,2) %.2e, (4,4) %.2e\n", pa, k2, k4);
  ck_assert_msg(pa >= 1e-8 && k2 >= 1e-9 && k4 >= 1e-13, "k = s without the rescale was expected off round-off: "
                "%.2e %.2e %.2e", pa, k2, k4);
}
END_TEST

/* ---- order ---- */

// The rate log2(e(h) / e(h/2)) averaged over two halvings, h .. h/4.
static double rate(const Solver *sv, double h, long n, const double *qr, const double *pr) {
  double e1 = error_at(sv, h, n, qr, pr), e3 = error_at(sv, h / 4, 4 * n, qr, pr);
  if (table()) printf("order %s: h %.4g error %.3e, h/4 %.3e: rate %.2f\n", sv->name, h, e1, e3, log2(e1 / e3) / 2);
  return log2(e1 / e3) / 2;
}

START_TEST(order_2s_with_the_rescale) {
  /* the rescale changes p by the step's energy error over |p|, O(h^(2s+1)):
   * the order stays 2s. Kepler over one period (exact: back at q0, p0), the
   * pendulum at T = 10; h where the error is well above round-off */
  double kq[2] = {0.4, 0}, kp[2] = {0, 2}, pq, pp;
  long kn[4] = {160, 80, 40, 40}, pn[4] = {40, 20, 40, 20};
  pendulum_reference(0, 1, 10, &pq, &pp);
  for (int s = 1; s <= 4; s++) {
    double rk = rate(&KEP_RES[s - 1], 2 * PI / kn[s - 1], kn[s - 1], kq, kp);
    double rp = rate(&PA_RES[s - 1], 10.0 / pn[s - 1], pn[s - 1], &pq, &pp);
    ck_assert_msg(fabs(rk - 2 * s) <= 0.3, "Kepler HBVM(%d,%d) rescaled: rate %.2f, expected %d", s, s, rk, 2 * s);
    ck_assert_msg(fabs(rp - 2 * s) <= 0.5, "pendulum HBVM(%d,%d) rescaled: rate %.2f, expected %d", s, s, rp, 2 * s);
  }
}
END_TEST

/* ---- at rest ---- */

START_TEST(no_rescale_at_rest) {
  /* at the equilibrium K = 0 before and after every step: beta would be 0/0;
   * the step must leave the state exactly at rest */
  double q0 = 0, p0 = 0, q, p;
  for (int s = 1; s <= 4; s++) {
    run(&PA_RES[s - 1], &q0, &p0, 0.1, 100, &q, &p);
    ck_assert_msg(q == 0 && p == 0, "HBVM(%d,%d) rescaled at rest: q = %g, p = %g", s, s, q, p);
  }
  /* released from rest (q0 = 1, p0 = 0): every half period a turning point,
   * where p is small and the rescale turns q1's error e into one of p of
   * U'(q1) e / |p1| (docs/method-const.md): the error at T grows, measured
   * 25x, 30x, 6.7x, 1.8x that of the quadrature's k = 16 at h = 0.1, 0.05,
   * 0.025, 0.0125, and H stays within a few ulps (3.4e-15 once at 0.0125: a
   * step that ended past a turning point, where U(q1) > H0, made up by the
   * next) */
  double qr, pr, q1 = 1, e_res, e_quad, dH;
  pendulum_reference(1, 0, 20, &qr, &pr);
  for (long n = 200; n <= 1600; n *= 2) {
    double qq, pq;
    dH = run(&PA_RES[1], &q1, &p0, 20.0 / n, n, &qq, &pq);
    e_res = fmax(fabs(qq - qr), fabs(pq - pr));
    run(&PA_QUAD, &q1, &p0, 20.0 / n, n, &qq, &pq);
    e_quad = fmax(fabs(qq - qr), fabs(pq - pr));
    if (table()) printf("from rest, s = 2, n = %ld: rescaled %.3e (max |H - H0| %.1e), k = 16 %.3e\n", n, e_res, dH, e_quad);
    ck_assert_msg(e_res <= 50 * e_quad, "from rest, n = %ld: rescaled %.3e against %.3e (k = 16)", n,
                  e_res, e_quad);
    ck_assert_msg(dH <= 32 * ULP, "from rest, n = %ld: max |H - H0| = %.2e", n, dH);
  }
}
END_TEST

/* ---- --check ---- */

START_TEST(check_reports_the_choice) {
  char out[8192];
  ck_assert_int_eq(generator_output("--check -s 4 ../models/pendulum_angle.ham", out, sizeof out), 0);
  ck_assert_msg(strstr(out, "k=4 s=4") && strstr(out, "k = s, the end of the step rescales p"), "%s", out);
  ck_assert_int_eq(generator_output("--check -s 4 --energy quadrature ../models/kepler.ham", out, sizeof out), 0);
  ck_assert_msg(strstr(out, "k=20 s=4") && strstr(out, "2s+12"), "%s", out);
  /* -k given keeps the quadrature of its nodes (byte for byte as before --energy) */
  ck_assert_int_eq(generator_output("--check -s 4 -k 4 ../models/kepler.ham", out, sizeof out), 0);
  ck_assert_msg(strstr(out, "k: given with -k"), "%s", out);
  /* with constraints the option is refused */
  ck_assert_int_ne(generator_output("--check --energy rescale ../models/pendulum.ham", out, sizeof out), 0);
  ck_assert_msg(strstr(out, "--energy applies to a model without constraints"), "%s", out);
}
END_TEST

Suite *energy_suite(void) {
  Suite *s = suite_create("energy");
  TCase *tc = tcase_create("rescale");
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, energy_at_roundoff_at_k_s);
  tcase_add_test(tc, order_2s_with_the_rescale);
  tcase_add_test(tc, no_rescale_at_rest);
  tcase_add_test(tc, check_reports_the_choice);
  suite_add_tcase(s, tc);
  return s;
}
