/* check_mq.c - Check suite for a mass matrix that depends on q (gen/mass_q.c,
 * gen/step_mq.c, gen/emit_mq.c), against GSL's rk8pd on the same ODE
 *   q' = M(q)^-1 p,  p' = 1/2 v' (dM/dq_i) v - grad U,  v = M(q)^-1 p,
 * written here by hand (M and dM/dq in closed form, M^-1 by GSL's LU), at
 * tolerance 1e-14, on models/double_pendulum_angles.ham (HBVM(2s+12, s),
 * s = 1..4, in float, and HBVM(4,4)), models/spherical_pendulum.ham
 * (HBVM(16,2) and (s,s), s = 1..4) and models/arm3.ham (HBVM(18,3) and
 * (s,s), s = 1..4); the tests of order, estimate and adaptive steps are
 * tests/mq_common.c's, shared with check_mq_fourbar.c:
 *   order     the max error over the run in (q, p) falls like h^(2s).
 *   energy    |H - H0| stays at round-off over 2000 steps (with k = 2s + 12,
 *             the rule for a non-polynomial H, and with k = s, the default: the
 *             end of the step rescales p to H0); the spherical pendulum's p_ph
 *             at round-off; in float, within the bound of the rescale's
 *             near-rest band (beside the four-bar's, check_mq_fourbar.c).
 *   errest    NAME_stats.err_est against the true local error of a step
 *             started on the reference: within [1/10, 10] in geometric mean.
 *   adaptive  NAME_step_adaptive's global error at T follows the tolerance.
 *   dense     NAME_dense inside a step against the reference.
 *   check     hbvmgen --check names the coordinates M depends on.
 * HBVM_MQ_TABLE=1 prints the measured figures (docs/method-mq.md). The suite
 * is mq_suite(); the project's runner adds it. */
#define _POSIX_C_SOURCE 200809L /* popen */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_odeiv2.h>

#include "arm1k_k1s1.h"
#include "arm2k_k2s2.h"
#include "arm3k_k3s3.h"
#include "arm4k_k4s4.h"
#include "arm_k18s3.h"
#include "dpa1_k14s1.h"
#include "dpa2_k16s2.h"
#include "dpa3_k18s3.h"
#include "dpa4_k20s4.h"
#include "dpa4k_k4s4.h"
#include "dpa_float_k16s2.h"
#include "dpafloatk_k2s2.h"
#include "sph1k_k1s1.h"
#include "sph2k_k2s2.h"
#include "sph3k_k3s3.h"
#include "sph4k_k4s4.h"
#include "sph_k16s2.h"

#include "mq_common.h"

Suite *mq_suite(void);
void mq_fourbar_tests(Suite *s); /* check_mq_fourbar.c: M(q) with constraints */

#define MAXM MQ_MAXM

/* ---- the reference ODEs: M(q) and dM/dq_i in closed form ---- */

typedef struct {
  const char *name;
  int m;
  double q0[MAXM], p0[MAXM];
  /* M(q) (m x m row-major) and dM/dq_i for i = 0..m-1 (m of them) */
  void (*mass)(const double *q, double *M, double *dM);
  double (*potential_grad)(const double *q, double *g); /* returns U */
} Problem;

static void dpa_mass(const double *q, double *M, double *dM) {
  double c = cos(q[0] - q[1]), s = sin(q[0] - q[1]);
  double m[4] = {2, c, c, 1}, d0[4] = {0, -s, -s, 0};
  memcpy(M, m, sizeof m);
  for (int i = 0; i < 4; i++) {
    dM[i] = d0[i];
    dM[4 + i] = -d0[i];
  }
}

static double dpa_grad(const double *q, double *g) {
  g[0] = 2 * sin(q[0]);
  g[1] = sin(q[1]);
  return -2 * cos(q[0]) - cos(q[1]);
}

static void sph_mass(const double *q, double *M, double *dM) {
  double s = sin(q[0]), c = cos(q[0]);
  double m[4] = {1, 0, 0, s * s}, d0[4] = {0, 0, 0, 2 * s * c};
  memcpy(M, m, sizeof m);
  memcpy(dM, d0, sizeof d0);
  memset(dM + 4, 0, 4 * sizeof *dM);
}

static double sph_grad(const double *q, double *g) {
  g[0] = sin(q[0]);
  g[1] = 0;
  return -cos(q[0]);
}

/* models/arm3.ham at its defaults (unit masses and lengths, gravity 1): M =
 * S' A S with A_ij = c_ij cos(f_i - f_j), linear in a12, a13, a23. */
static void arm_assemble(double a12, double a13, double a23, double c, double *M) {
  double c11 = 7.0 / 3 * c, c22 = 4.0 / 3 * c, c33 = 1.0 / 3 * c;
  double m33 = c33, m23 = a23 + c33, m22 = c22 + 2 * a23 + c33, m13 = a13 + a23 + c33;
  double m12 = a12 + a13 + c22 + 2 * a23 + c33, m11 = c11 + c22 + c33 + 2 * (a12 + a13 + a23);
  double v[9] = {m11, m12, m13, m12, m22, m23, m13, m23, m33};
  memcpy(M, v, sizeof v);
}

static void arm_mass(const double *q, double *M, double *dM) {
  arm_assemble(1.5 * cos(q[1]), 0.5 * cos(q[1] + q[2]), 0.5 * cos(q[2]), 1, M);
  memset(dM, 0, 9 * sizeof *dM);
  arm_assemble(-1.5 * sin(q[1]), -0.5 * sin(q[1] + q[2]), 0, 0, dM + 9);
  arm_assemble(0, -0.5 * sin(q[1] + q[2]), -0.5 * sin(q[2]), 0, dM + 18);
}

static double arm_grad(const double *q, double *g) {
  double s1 = sin(q[0]), s12 = sin(q[0] + q[1]), s123 = sin(q[0] + q[1] + q[2]);
  g[0] = 2.5 * s1 + 1.5 * s12 + 0.5 * s123;
  g[1] = 1.5 * s12 + 0.5 * s123;
  g[2] = 0.5 * s123;
  return -(2.5 * cos(q[0]) + 1.5 * cos(q[0] + q[1]) + 0.5 * cos(q[0] + q[1] + q[2]));
}

static const Problem DPA = {"double pendulum in angles", 2, {0.5, -0.3}, {0, 0}, dpa_mass, dpa_grad};
static const Problem SPH = {"spherical pendulum", 2, {1, 0}, {0, 0.5}, sph_mass, sph_grad};
static const Problem ARM = {"3-link arm", 3, {1, -0.5, 0.8}, {0, 0, 0}, arm_mass, arm_grad};

// v = M(q)^-1 p and the right-hand side of the ODE (y = (q, p)).
static int rhs(double t, const double *y, double *dy, void *par) {
  const Problem *pb = par;
  int m = pb->m, sg;
  double M[MAXM * MAXM], dM[MAXM * MAXM * MAXM], g[MAXM], v[MAXM];
  (void)t;
  pb->mass(y, M, dM);
  pb->potential_grad(y, g);
  gsl_matrix_view A = gsl_matrix_view_array(M, (size_t)m, (size_t)m);
  gsl_vector_const_view b = gsl_vector_const_view_array(y + m, (size_t)m);
  gsl_vector_view x = gsl_vector_view_array(v, (size_t)m);
  gsl_permutation *perm = gsl_permutation_alloc((size_t)m);
  gsl_linalg_LU_decomp(&A.matrix, perm, &sg);
  gsl_linalg_LU_solve(&A.matrix, perm, &b.vector, &x.vector);
  gsl_permutation_free(perm);
  for (int i = 0; i < m; i++) {
    double vdv = 0;
    for (int a = 0; a < m; a++)
      for (int c = 0; c < m; c++) vdv += v[a] * dM[(i * m + a) * m + c] * v[c];
    dy[i] = v[i];
    dy[m + i] = 0.5 * vdv - g[i];
  }
  return GSL_SUCCESS;
}

// The reference at t from (q, p) at t0: rk8pd at 1e-14, into q, p.
static void reference(const void *data, double t0, double t, double *q, double *p) {
  const Problem *pb = data;
  gsl_odeiv2_system sys = {rhs, NULL, (size_t)(2 * pb->m), (void *)pb};
  gsl_odeiv2_driver *dr = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-4, 1e-14, 1e-14);
  double y[2 * MAXM];
  memcpy(y, q, (size_t)pb->m * sizeof *y);
  memcpy(y + pb->m, p, (size_t)pb->m * sizeof *y);
  ck_assert_int_eq(gsl_odeiv2_driver_apply(dr, &t0, t, y), GSL_SUCCESS);
  gsl_odeiv2_driver_free(dr);
  memcpy(q, y, (size_t)pb->m * sizeof *y);
  memcpy(p, y + pb->m, (size_t)pb->m * sizeof *y);
}

/* ---- the generated solvers behind one interface ---- */

// MqSolver (mq_common.h) and what this file reads besides: H, p's dense output.
typedef struct {
  MqSolver sv;
  double (*energy)(const void *x);
  void (*dense)(const void *x, double th, double *q, double *p);
} Solver;

#define WRAP(P)                                                                                  \
  MQ_WRAP(P)                                                                                     \
  static double P##_e(const void *x) { return P##_energy(x, 0); }                                \
  static void P##_d(const void *x, double th, double *q, double *p) {                           \
    P##_real qq[MAXM], pp[MAXM];                                                                 \
    P##_dense(x, (P##_real)th, qq, pp);                                                          \
    for (int i = 0; i < P##_M; i++) {                                                            \
      q[i] = qq[i];                                                                              \
      p[i] = pp[i];                                                                              \
    }                                                                                            \
  }
#define SOLVER(P, pb, s) {MQ_SOLVER(P, (pb)->name, s, reference, pb), P##_e, P##_d}

WRAP(dpa1_k14s1)
WRAP(dpa2_k16s2)
WRAP(dpa3_k18s3)
WRAP(dpa4_k20s4)
WRAP(dpa_float_k16s2)
WRAP(sph_k16s2)
WRAP(arm_k18s3)
WRAP(dpa4k_k4s4)
WRAP(arm3k_k3s3)
WRAP(sph1k_k1s1)
WRAP(sph2k_k2s2)
WRAP(sph3k_k3s3)
WRAP(sph4k_k4s4)
WRAP(arm1k_k1s1)
WRAP(arm2k_k2s2)
WRAP(arm4k_k4s4)
WRAP(dpafloatk_k2s2)

static const Solver solvers[] = {
    SOLVER(dpa1_k14s1, &DPA, 1), SOLVER(dpa2_k16s2, &DPA, 2), SOLVER(dpa3_k18s3, &DPA, 3), SOLVER(dpa4_k20s4, &DPA, 4),
    SOLVER(sph_k16s2, &SPH, 2),  SOLVER(arm_k18s3, &ARM, 3),  SOLVER(dpa_float_k16s2, &DPA, 2),
    SOLVER(dpa4k_k4s4, &DPA, 4), SOLVER(arm3k_k3s3, &ARM, 3), SOLVER(sph1k_k1s1, &SPH, 1), SOLVER(sph2k_k2s2, &SPH, 2),
    SOLVER(sph3k_k3s3, &SPH, 3), SOLVER(sph4k_k4s4, &SPH, 4), SOLVER(arm1k_k1s1, &ARM, 1), SOLVER(arm2k_k2s2, &ARM, 2),
    SOLVER(arm4k_k4s4, &ARM, 4), SOLVER(dpafloatk_k2s2, &DPA, 2),
};
enum { DPA1, DPA2, DPA3, DPA4, SPH2, ARM3, DPAF, DPA4K, ARM3K, SPH1K, SPH2K, SPH3K, SPH4K, ARM1K, ARM2K, ARM4K, DPAFK };

/* room for any of the states */
static union {
  double d[256];
  long double l[128];
} state;

/* ---- order ---- */

// h where the rate of e(h) / e(h/2) is asymptotic and e(h/2) well above
// round-off (mq_check_order).
static const struct {
  int solver;
  double h, T;
} order_cases[] = {
    {DPA1, 0.05, 5},  {DPA2, 0.1, 5},  {DPA3, 0.1, 5},  {DPA4, 0.2, 5},  {SPH2, 0.1, 5},  {ARM3, 0.1, 3},
    {DPA4K, 0.2, 5},  {ARM3K, 0.1, 3}, {SPH1K, 0.05, 3}, {SPH2K, 0.1, 3}, {SPH3K, 0.2, 3}, {SPH4K, 0.2, 3},
    {ARM1K, 0.02, 2}, {ARM2K, 0.05, 2}, {ARM4K, 0.2, 3},
};

START_TEST(order_2s) {
  const Solver *sv = &solvers[order_cases[_i].solver];
  mq_check_order(&sv->sv, &state, order_cases[_i].h, order_cases[_i].T);
}
END_TEST

/* ---- energy at round-off ---- */

// exact: k integrates H to round-off (k = 2s + 12), else k = s (below).
static const struct {
  int solver;
  double h;
  int exact;
} energy_cases[] = {{DPA1, 0.02, 1}, {DPA2, 0.05, 1},  {DPA3, 0.1, 1},   {DPA4, 0.2, 1},   {SPH2, 0.05, 1},
                    {ARM3, 0.05, 1}, {DPA4K, 0.2, 0},  {ARM3K, 0.1, 0},  {SPH1K, 0.05, 0}, {SPH2K, 0.1, 0},
                    {SPH3K, 0.2, 0}, {SPH4K, 0.2, 0},  {ARM1K, 0.02, 0}, {ARM2K, 0.05, 0}, {ARM4K, 0.2, 0}};

// 2000 steps: |H - H0| within 64 ulps of |K| + |U| at the start (a random
// walk of the iteration's 2-ulp stop and the compensated sums' last bits),
// where an inexact quadrature without the rescale would show (k = s = 4:
// 2.1e-11 in 100 steps of h = 0.1, docs/method-mq.md). The spherical
// pendulum's p_ph: its force is exactly 0, so only the rescale moves it, by
// the factor beta, 1 + the step's energy error: with k = 16 that is
// round-off (256 ulps, a random walk: 65 measured at the end); with k = s,
// the O(h^(2s+1)) energy error of a quadrature that is not exact, which the
// rescale turns into a drift of p_ph, O(T h^(2s)) over the run as the
// global error: within 1e-3 T h^(2s) relative (measured 6e-4, 1.7e-4,
// 2.4e-5, 3e-6 of it at s = 1..4; docs/method-mq.md).
START_TEST(energy_roundoff) {
  const Solver *sv = &solvers[energy_cases[_i].solver];
  const Problem *pb = sv->sv.data;
  double h = energy_cases[_i].h, dH = 0, q[MAXM], p[MAXM], t, est, dpph = 0;
  sv->sv.init(&state, pb->q0, pb->p0);
  double H0 = sv->energy(&state), U0 = pb->potential_grad(pb->q0, q);
  double scale = fabs(H0 - U0) + fabs(U0), pph0 = pb->p0[1];
  for (int n = 0; n < 2000; n++) {
    ck_assert_int_eq(sv->sv.step(&state, h, &est), 0);
    dH = fmax(dH, fabs(sv->energy(&state) - H0));
    if (pb == &SPH) {
      sv->sv.get(&state, &t, q, p);
      dpph = fmax(dpph, fabs(p[1] - pph0) / pph0);
    }
  }
  if (mq_table()) {
    printf("energy: %s s=%d h=%g: max |H - H0| = %.2e (%.1f ulps of |K| + |U| = %.3g)", pb->name, sv->sv.s, h, dH,
           dH / (DBL_EPSILON * scale), scale);
    if (pb == &SPH) printf("; p_ph %.2g relative", dpph);
    printf("\n");
  }
  double pph_bound = energy_cases[_i].exact ? 256 * DBL_EPSILON : 1e-3 * 2000 * h * pow(h, 2 * sv->sv.s);
  ck_assert_msg(dpph <= pph_bound, "the spherical pendulum's p_ph changed by %.3g (bound %.3g)", dpph, pph_bound);
  ck_assert_msg(dH <= 64 * DBL_EPSILON * scale, "%s: |H - H0| = %.3e", sv->sv.name, dH);
}
END_TEST

// In float: H within 64 float ulps, and the solution within 1e-4 of the
// reference at T = 5 (the error of double at this h is 5e-7).
START_TEST(float_holds) {
  const Solver *sv = &solvers[DPAF];
  double h = 0.05, est, dH = 0;
  sv->sv.init(&state, NULL, NULL);
  double H0 = sv->energy(&state);
  for (int n = 0; n < 100; n++) {
    ck_assert_int_eq(sv->sv.step(&state, h, &est), 0);
    dH = fmax(dH, fabs(sv->energy(&state) - H0));
  }
  if (mq_table()) printf("float: max |H - H0| = %.2e\n", dH);
  ck_assert_msg(dH <= 64 * FLT_EPSILON * 4, "float: |H - H0| = %.3e", dH);
  ck_assert_msg(mq_run_error(&sv->sv, &state, h, 100) < 1e-4, "float: the solution strays");
}
END_TEST

// The float double pendulum in angles at k = s (HBVM(2,2)), 2000 steps of
// 0.05: H within the bound of mq_float_drift, as the four-bar's (check_mq_fourbar.c).
static double dpa_potential(const double *q) {
  double g[MAXM];
  return dpa_grad(q, g);
}

START_TEST(float_energy_bounded) {
  const Solver *sv = &solvers[DPAFK];
  double dH = mq_float_drift(&sv->sv, &state, sv->energy, dpa_potential, 0.05, 2000);
  ck_assert_msg(dH <= 16.0, "float double pendulum: |H - H0| %.1f ulps of |K| + |U|", dH);
}
END_TEST

/* ---- the error estimate, adaptive steps, dense output ---- */

static const struct {
  int solver;
  double h;
} errest_cases[] = {{DPA2, 0.1}, {DPA3, 0.2}, {DPA4, 0.4}, {ARM3, 0.1}, {DPA4K, 0.4},
                    {SPH2K, 0.2}, {SPH3K, 0.3}, {SPH4K, 0.4}, {ARM2K, 0.1}, {ARM4K, 0.2}};

START_TEST(errest_tracks) {
  mq_check_errest(&solvers[errest_cases[_i].solver].sv, &state, errest_cases[_i].h);
}
END_TEST

// To T = 5 (measured: docs/method-mq.md).
static const int adaptive_cases[] = {DPA2, DPA3, DPA4, ARM3, DPA4K, ARM3K, SPH2K, SPH3K, SPH4K, ARM2K, ARM4K};

START_TEST(adaptive_follows_tolerance) {
  mq_check_adaptive(&solvers[adaptive_cases[_i]].sv, &state, 5, NULL);
}
END_TEST

// NAME_dense at theta = 1/4, 1/2, 3/4 of steps of h against the reference:
// an error of order at least s + 1 (h^(s+1) at most, with constant 1).
START_TEST(dense_inside_step) {
  static const int which[] = {DPA2, DPA3, ARM3};
  const Solver *sv = &solvers[which[_i]];
  const Problem *pb = sv->sv.data;
  double h = 0.05, rq[MAXM], rp[MAXM], q[MAXM], p[MAXM], err = 0;
  sv->sv.init(&state, pb->q0, pb->p0);
  for (int k = 0; k < 20; k++) {
    double est;
    ck_assert_int_eq(sv->sv.step(&state, h, &est), 0);
    for (int j = 1; j <= 3; j++) {
      sv->dense(&state, j / 4.0, q, p);
      memcpy(rq, pb->q0, sizeof rq);
      memcpy(rp, pb->p0, sizeof rp);
      reference(pb, 0, (k + j / 4.0) * h, rq, rp);
      for (int i = 0; i < pb->m; i++) err = fmax(err, fmax(fabs(q[i] - rq[i]), fabs(p[i] - rp[i])));
    }
  }
  if (mq_table()) printf("dense: %s s=%d h=%g: max error %.2e\n", pb->name, sv->sv.s, h, err);
  ck_assert_msg(err < pow(h, sv->sv.s + 1), "%s: dense error %.3e", sv->sv.name, err);
}
END_TEST

/* ---- check ---- */

// --check says whether M is constant, or on which coordinates it depends.
START_TEST(check_reports_dependence) {
  static const struct {
    const char *model, *want;
  } c[] = {{"../models/double_pendulum_angles.ham", "M: depends on q (th1, th2)"},
           {"../models/spherical_pendulum.ham", "M: depends on q (th)"},
           {"../models/arm3.ham", "M: depends on q (q2, q3)"},
           {"../models/fourbar_angles.ham", "M: depends on q (th1, th2)"},
           {"../models/fourbar_angles.ham", "multiplier: poly (degree 1, projection and energy rescale)"},
           {"../models/pendulum.ham", "M: constant, identity"},
           {"../tests/models/mass_param.ham", "M: with params (constant in q)"}};
  for (size_t i = 0; i < sizeof c / sizeof c[0]; i++) {
    char cmd[256], line[512];
    int found = 0;
    snprintf(cmd, sizeof cmd, "../gen/hbvmgen --check %s", c[i].model);
    FILE *f = popen(cmd, "r");
    ck_assert_ptr_nonnull(f);
    while (fgets(line, sizeof line, f)) found |= !strncmp(line, c[i].want, strlen(c[i].want));
    ck_assert_int_eq(pclose(f), 0);
    ck_assert_msg(found, "%s: no line '%s'", c[i].model, c[i].want);
  }
}
END_TEST

Suite *mq_suite(void) {
  Suite *s = suite_create("mq");
  TCase *tc = tcase_create("mq");
  tcase_set_timeout(tc, 120);
  tcase_add_loop_test(tc, order_2s, 0, (int)(sizeof order_cases / sizeof order_cases[0]));
  tcase_add_loop_test(tc, energy_roundoff, 0, (int)(sizeof energy_cases / sizeof energy_cases[0]));
  tcase_add_test(tc, float_holds);
  tcase_add_test(tc, float_energy_bounded);
  tcase_add_loop_test(tc, errest_tracks, 0, (int)(sizeof errest_cases / sizeof errest_cases[0]));
  tcase_add_loop_test(tc, adaptive_follows_tolerance, 0, (int)(sizeof adaptive_cases / sizeof adaptive_cases[0]));
  tcase_add_loop_test(tc, dense_inside_step, 0, 3);
  tcase_add_test(tc, check_reports_dependence);
  suite_add_tcase(s, tc);
  mq_fourbar_tests(s);
  return s;
}
