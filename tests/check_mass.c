/* check_mass.c - Check suite for a mass matrix with params (gen/mass.c):
 * M^-1 built in the DAG from the params instead of baked in as constants.
 *
 *   same       tests/models/mass_param.ham (M = diag(m1, 1), m1 = 2) and
 *              mass_const.ham (M = diag(2, 1)) give the same trajectory,
 *              for both multiplier families; mass_dense.ham (a dense M of
 *              params, factored L D L' in the step) follows
 *              mass_dense_const.ham (its inverse at generation time) to
 *              round-off.
 *   physics    mass_osc.ham: the period of x'' = -(k/m) x is 2 pi sqrt(m/k)
 *              for every m and k set at run time.
 *   singular   params that make M singular or indefinite (a zero or
 *              negative mass, an indefinite dense M) make the step fail
 *              with NAME_ENONFINITE and leave the state as it was.
 * The generator's side (errors at the default params, the DAG's M^-1
 * against GSL's inverse) is in check_parser.c and tests/err/mass_param_*.
 * The suite is mass_suite(); the project's runner adds it. */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dense_chain_c_k2s2.h"
#include "dense_chain_k2s2.h"
#include "dense_loop_c_k2s2.h"
#include "dense_loop_fw_k2s2.h"
#include "dense_loop_k2s2.h"
#include "mass_const_c_k2s2.h"
#include "mass_const_k2s2.h"
#include "mass_dense_const_k2s2.h"
#include "mass_dense_k2s2.h"
#include "mass_osc_k2s2.h"
#include "mass_param_c_k2s2.h"
#include "mass_param_k2s2.h"
#include "side_by_side.h"

Suite *mass_suite(void);

#define PI 3.14159265358979323846

/* A diagonal M of params gives M^-1 entries 1/m_ii, exactly the constants
 * the constant M bakes in: the trajectories agree to the last bit (allowed:
 * a few ulps, should a product be formed in another order). */
START_TEST(test_diag_same_trajectory)
{
  SAME_TRAJECTORY(mass_param_k2s2, mass_const_k2s2, 0.05, 1e-14, "diag(m1, 1) vs diag(2, 1), poly family");
  SAME_TRAJECTORY(mass_param_c_k2s2, mass_const_c_k2s2, 0.05, 1e-14, "diag(m1, 1) vs diag(2, 1), const family");
}
END_TEST

/* A dense M of params is solved through its L D L' factors where the
 * constant M uses GSL's inverse: equal to round-off. */
START_TEST(test_dense_same_trajectory)
{
  SAME_TRAJECTORY(mass_dense_k2s2, mass_dense_const_k2s2, 0.05, 1e-12, "dense M of params vs constant");
}
END_TEST

/* tests/models/dense_chain.ham with M^-1 v as loops over the table of M^-1
 * (--mass-loop 1) and as straight-line code: the same sums in the same
 * order (up to a constant factor merged into a product, and the sign of a
 * zero), so equal to round-off; and the loop form keeps H and g at
 * round-off. Both multiplier families; and --real float --wide-step, whose
 * kernels read the table in two types, follows the double solver to
 * float accuracy. */
START_TEST(test_table_same_trajectory)
{
  SAME_TRAJECTORY(dense_loop_k2s2, dense_chain_k2s2, 0.01, 1e-13, "dense M, loops over M^-1 vs straight-line, poly");
  SAME_TRAJECTORY(dense_loop_c_k2s2, dense_chain_c_k2s2, 0.01, 1e-13, "dense M, loops over M^-1 vs straight-line, const");
  dense_loop_k2s2_state x;
  dense_loop_fw_k2s2_state y;
  double g[dense_loop_k2s2_NU], dH = 0, dg = 0, dq = 0;
  dense_loop_k2s2_init(&x, NULL, NULL);
  dense_loop_fw_k2s2_init(&y, NULL, NULL);
  double H0 = dense_loop_k2s2_energy(&x, NULL);
  for (int n = 0; n < NSTEPS; n++) {
    ck_assert_int_eq(dense_loop_k2s2_step(&x, 0.01, NULL, NULL), 0);
    ck_assert_int_eq(dense_loop_fw_k2s2_step(&y, 0.01f, NULL, NULL), 0);
    dense_loop_k2s2_constraints(&x, NULL, g);
    dH = fmax(dH, fabs(dense_loop_k2s2_energy(&x, NULL) - H0));
    for (int a = 0; a < dense_loop_k2s2_NU; a++) dg = fmax(dg, fabs(g[a]));
    for (int i = 0; i < dense_loop_k2s2_M; i++) dq = fmax(dq, fabs(x.q[i] - (double)y.q[i]));
  }
  printf("mass: dense M as loops: |H - H0| %.3g, |g| %.3g; float --wide-step vs double: %.3g\n", dH, dg, dq);
  ck_assert_msg(dH <= 1e-13 && dg <= 1e-13, "loops over M^-1: |H - H0| = %.3g, |g| = %.3g", dH, dg);
  ck_assert_msg(dq <= 1e-4, "float --wide-step with loops over M^-1 is %.3g from double", dq);
}
END_TEST

/* x'' = -(k/m) x from x = 1, p = 0: x(t) = cos(t sqrt(k/m)). Over one
 * period 2 pi sqrt(m/k) in 1000 steps, x returns to 1 and passes -1 half
 * way; with m = 4 and k = 1, the period of m = 1 is only half of one. */
START_TEST(test_period)
{
  static const double cases[][2] = {{1, 1}, {4, 1}, {0.25, 1}, {2, 8}, {3, 0.5}};
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    mass_osc_k2s2_params prm = {cases[c][0], cases[c][1]};
    double period = 2 * PI * sqrt(prm.m / prm.k), h = period / 1000;
    mass_osc_k2s2_state x;
    mass_osc_k2s2_init(&x, NULL, NULL);
    double H0 = mass_osc_k2s2_energy(&x, &prm);
    ck_assert_msg(fabs(H0 - prm.k / 2) <= 1e-15, "m=%g k=%g: H = %.17g, want k/2", prm.m, prm.k, H0);
    for (int n = 1; n <= 1000; n++) {
      int rc = mass_osc_k2s2_step(&x, h, &prm, NULL);
      ck_assert_msg(rc == 0, "m=%g k=%g step %d: %s", prm.m, prm.k, n, mass_osc_k2s2_strerror(rc));
      double want = cos(x.t * sqrt(prm.k / prm.m));
      ck_assert_msg(fabs(x.q[0] - want) <= 1e-9, "m=%g k=%g t=%g: x = %.12g, want %.12g", prm.m, prm.k, x.t,
                    x.q[0], want);
      if (n == 500) ck_assert_msg(fabs(x.q[0] + 1) <= 1e-9, "m=%g k=%g: x(T/2) = %.12g", prm.m, prm.k, x.q[0]);
    }
    ck_assert_msg(fabs(x.q[0] - 1) <= 1e-9 && fabs(x.p[0]) <= 1e-9, "m=%g k=%g: (x, p)(T) = (%.12g, %.3g)", prm.m,
                  prm.k, x.q[0], x.p[0]);
    ck_assert_msg(fabs(mass_osc_k2s2_energy(&x, &prm) - H0) <= 1e-14, "m=%g k=%g: |H - H0| = %.3g", prm.m, prm.k,
                  fabs(mass_osc_k2s2_energy(&x, &prm) - H0));
  }
  /* the default (m = 1) and m = 4 part ways: at t = 2 pi one is back at 1, the other at -1 */
  mass_osc_k2s2_params one, four = {4, 1};
  mass_osc_k2s2_params_default(&one);
  mass_osc_k2s2_state a, b;
  mass_osc_k2s2_init(&a, NULL, NULL);
  mass_osc_k2s2_init(&b, NULL, NULL);
  for (int n = 0; n < 1000; n++) {
    ck_assert_int_eq(mass_osc_k2s2_step(&a, 2 * PI / 1000, &one, NULL), 0);
    ck_assert_int_eq(mass_osc_k2s2_step(&b, 2 * PI / 1000, &four, NULL), 0);
  }
  ck_assert_msg(fabs(a.q[0] - 1) <= 1e-9 && fabs(b.q[0] + 1) <= 1e-9, "x(2 pi): %.12g (m = 1), %.12g (m = 4)",
                a.q[0], b.q[0]);
}
END_TEST

/* One step of solver P from its initial state with params prm must fail
 * with P_ENONFINITE and leave the state byte for byte as it was; then the
 * default params step from that same state. */
#define ASSERT_REFUSED(P, prm, what)                                                                  \
  do {                                                                                                \
    P##_state x, before;                                                                              \
    P##_params dflt;                                                                                  \
    P##_params_default(&dflt);                                                                        \
    P##_init(&x, NULL, NULL);                                                                         \
    memcpy(&before, &x, sizeof x);                                                                    \
    int rc = P##_step(&x, 0.05, &(prm), NULL);                                                        \
    ck_assert_msg(rc == P##_ENONFINITE, #P ", %s: step returned %d (%s), want ENONFINITE", what, rc,   \
                  P##_strerror(rc));                                                                  \
    ck_assert_msg(!memcmp(&before, &x, sizeof x), #P ", %s: the failed step changed the state", what); \
    ck_assert_int_eq(P##_step(&x, 0.05, &dflt, NULL), 0);                                             \
  } while (0)

/* Params that make M singular or indefinite: a failure code, never a
 * state of garbage (gen/mass.c: D^-1 is NaN where a pivot is not > 0). */
START_TEST(test_singular_mass)
{
  static const double masses[] = {0, -1, -0.0, 1e-320, INFINITY, NAN};
  for (size_t i = 0; i < sizeof masses / sizeof masses[0]; i++) {
    char what[32];
    snprintf(what, sizeof what, "mass %g", masses[i]);
    mass_osc_k2s2_params o = {masses[i], 1};
    ASSERT_REFUSED(mass_osc_k2s2, o, what);
    mass_param_k2s2_params p = {masses[i]};
    ASSERT_REFUSED(mass_param_k2s2, p, what);
    mass_param_c_k2s2_params pc = {masses[i]};
    ASSERT_REFUSED(mass_param_c_k2s2, pc, what);
    mass_dense_k2s2_params d = {masses[i], 0.5};
    ASSERT_REFUSED(mass_dense_k2s2, d, what);
  }
  mass_dense_k2s2_params indefinite = {2, 2}; /* M[1..2][1..2] = [[2, 2], [2, 1]]: a negative pivot */
  ASSERT_REFUSED(mass_dense_k2s2, indefinite, "c = 2");
  mass_dense_k2s2_params semidefinite = {2, sqrt(2)}; /* that pivot 0 (or a rounding of it) */
  ASSERT_REFUSED(mass_dense_k2s2, semidefinite, "c = sqrt 2");
}
END_TEST

Suite *mass_suite(void)
{
  Suite *s = suite_create("mass");
  TCase *tc = tcase_create("params in M");
  tcase_set_tags(tc, "sanlong"); /* the generated arithmetic: sanitized in check-long */
  tcase_add_test(tc, test_diag_same_trajectory);
  tcase_add_test(tc, test_dense_same_trajectory);
  tcase_add_test(tc, test_table_same_trajectory);
  tcase_add_test(tc, test_period);
  tcase_add_test(tc, test_singular_mass);
  suite_add_tcase(s, tc);
  return s;
}
