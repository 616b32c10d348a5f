/* check_rollnewton.c - Check suite for --iteration newton on the rolled form
 * (gen/roll_newton.c, gen/emit_rolled_newton.c, docs/rolled.md "Newton"):
 * the Newton matrix's blocks as bands, on the stiff FPU chain without
 * constraints (tests/models/fpu_n8.ham, fpu_n500.ham: models/fpu.ham with N
 * = 8 and 500, omega a param).
 *
 *   same      the rolled Newton step against the straight-line Newton step
 *             (chain of 8, s = 2 and 3, omega = 1000, h omega = 10 and 100,
 *             T = 4): the same trajectory up to the reordering of the
 *             elimination (REORDER_TOL), and the same Newton iterations and
 *             factorisations in all;
 *   converge  every step of the rolled chains of 8 and 500 (m = 1000)
 *             converges at h omega = 10, 100, 1000 (omega = 1000) and 10,
 *             100 (omega = 50; h omega = 1000 is h = 20, the step the
 *             rollback test makes fail) in a bounded number of iterations
 *             and factorisations, H at round-off (the bound of
 *             tests/check_newton.c);
 *   fixed     on the chain of 500 at h omega = 1 (where the sweeps converge)
 *             the rolled Newton step follows the rolled fixed-point step to
 *             round-off;
 *   auto      --iteration auto on the rolled form: on the chain of 8 the
 *             rolled sweeps-then-Newton step against the straight-line one
 *             (the same trajectory to REORDER_TOL at h omega = 0.1, where
 *             Newton never runs, and at 10 and 100, where it takes over);
 *             the chain of 500 with the generator's defaults follows the
 *             rolled Newton step at h omega = 10;
 *   rollback  a step that fails (h = 20) leaves the state byte-identical;
 *   batch     --batch 2: each lane is bitwise the rolled scalar Newton step;
 *   refused   what the rolled form does not cover under Newton (a pair sum
 *             whose Hessian is full) is a located error, and --rolled auto
 *             falls back; constraints in both families are covered; a
 *             chain x[i] rolls with its band in the natural order.
 * With constraints (both families, rp* const and rp*p poly; tcase
 * "constrained"), on the stiff
 * polymer (tests/models/polymer_stiff6.ham, polymer_stiff100.ham; omega =
 * 205 at ka = 1e4, the largest frequency auto's estimate finds at q0):
 *   kkt_same      rolled against straight-line Newton, 6 beads, h omega = 10
 *                 and 30, T = 2 (REORDER_KKT_TOL), in both families, the
 *                 same iterations and
 *                 factorisations within a tenth, H and g at round-off; an
 *                 adaptive run of the rolled step keeps g at round-off;
 *   kkt_long      the polymer of 100 beads (m = 300, nu = 99; both families) converges at h
 *                 omega = 10 in a bounded number of iterations, H and g at
 *                 round-off; its rolled C is at most twice the 6 beads' C;
 *   kkt_rollback  a step too long for the iteration (h omega = 100) leaves
 *                 the state byte-identical.
 * The suite is rollnewton_suite(); the project's runner adds it. */
#define _POSIX_C_SOURCE 200809L /* pthread_attr_setstacksize */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <pthread.h>

#include "generate.h"
#include "rn500_fixed_k4s2.h"
#include "rn500_k4s2.h"
#include "rn500auto_k4s2.h"
#include "rn8_k4s2.h"
#include "rn8auto_k4s2.h"
#include "rn8auto_straight_k4s2.h"
#include "rn8_straight_k4s2.h"
#include "rn8s3_k6s3.h"
#include "rn8s3_straight_k6s3.h"
#include "rnb8_k4s2.h"
#include "rp100_k4s2.h"
#include "rp100p_k4s2.h"
#include "rp6_k4s2.h"
#include "rp6_straight_k4s2.h"
#include "rp6p_k4s2.h"
#include "rp6p_straight_k4s2.h"

Suite *rollnewton_suite(void);

/* The two forms compute the same Newton matrix and solve it by eliminations
 * in another order (band in Cuthill-McKee order, a pair's block in complex
 * arithmetic, against lu.c's minimum-degree order of its real form): the
 * corrections differ by a few ulps of gamma each iteration, and the converged
 * steps by round-off (measured at most 8e-14 over the runs below). */
#define REORDER_TOL 1e-11

typedef struct {
  int steps, failed, max_iters, max_factors;
  long iters, factors;
  double dH, H0, diff;
} Run;

/* The start of RUN and RUN_KKT: solvers P and C (states x_, y_, params
 * prm_, cprm_ in the caller's block) at their default params changed by
 * SETUP, initialised; r zeroed but for H0 and the number of steps to T. */
#define START_PAIR(P, C, h, T, r, SETUP)                                                          \
  do {                                                                                             \
    memset(&(r), 0, sizeof(r));                                                                    \
    P##_params_default(&prm_);                                                                     \
    C##_params_default(&cprm_);                                                                    \
    SETUP;                                                                                         \
    P##_init_params(&x_, NULL, NULL, &prm_);                                                       \
    C##_init_params(&y_, NULL, NULL, &cprm_);                                                      \
    (r).H0 = P##_energy(&x_, &prm_);                                                               \
    (r).steps = (int)lround((T) / (h));                                                            \
  } while (0)

/* Step solver P and solver C beside it (the largest difference of q, p
 * into r.diff) at omega = w in steps of h to T; counts and |H - H0|. */
#define RUN(P, C, w, h, T, r)                                                                     \
  do {                                                                                             \
    P##_params prm_;                                                                               \
    P##_state x_;                                                                                  \
    C##_params cprm_;                                                                              \
    C##_state y_;                                                                                  \
    START_PAIR(P, C, h, T, r, prm_.omega = cprm_.omega = (w));                                   \
    for (int n_ = 0; n_ < (r).steps; n_++) {                                                       \
      P##_stats st_;                                                                               \
      C##_stats ct_;                                                                               \
      if (P##_step(&x_, (h), &prm_, &st_) != P##_OK) {                                             \
        (r).failed++;                                                                              \
        break;                                                                                     \
      }                                                                                            \
      if (C##_step(&y_, (h), &cprm_, &ct_) != C##_OK) {                                            \
        (r).failed++;                                                                              \
        break;                                                                                     \
      }                                                                                            \
      (r).iters += st_.newton;                                                                     \
      (r).factors += st_.factors;                                                                  \
      if (st_.iters > (r).max_iters) (r).max_iters = st_.iters;                                    \
      if (st_.factors > (r).max_factors) (r).max_factors = st_.factors;                            \
      (r).dH = fmax((r).dH, fabs(P##_energy(&x_, &prm_) - (r).H0));                                \
      for (int i_ = 0; i_ < P##_M; i_++)                                                           \
        (r).diff = fmax((r).diff, fmax(fabs(x_.q[i_] - y_.q[i_]), fabs(x_.p[i_] - y_.p[i_])));     \
    }                                                                                              \
  } while (0)

/* Rolled against straight-line Newton on the chain of 8: measured at most
 * 3.2e-14 (s = 2) and 7.2e-14 (s = 3) apart over T = 4, the same counts. */
START_TEST(test_same_as_straight)
{
  static const double h[2] = {0.01, 0.1};
  for (int c = 0; c < 2; c++) {
    Run a, b, a3, b3;
    RUN(rn8_k4s2, rn8_straight_k4s2, 1000, h[c], 4.0, a);
    RUN(rn8_straight_k4s2, rn8_straight_k4s2, 1000, h[c], 4.0, b);
    RUN(rn8s3_k6s3, rn8s3_straight_k6s3, 1000, h[c], 4.0, a3);
    RUN(rn8s3_straight_k6s3, rn8s3_straight_k6s3, 1000, h[c], 4.0, b3);
    printf("rolled vs straight-line Newton, h omega = %g: s = 2 %.3g apart (%ld / %ld iterations), s = 3 %.3g\n",
           1000 * h[c], a.diff, a.iters, b.iters, a3.diff);
    ck_assert_msg(!a.failed && !b.failed && !a3.failed && !b3.failed, "h omega = %g: a step failed", 1000 * h[c]);
    ck_assert_msg(a.diff <= REORDER_TOL && a3.diff <= REORDER_TOL, "h omega = %g: the forms are %.3g (s = 2), %.3g (s = 3) apart",
                  1000 * h[c], a.diff, a3.diff);
    ck_assert_msg(a.factors == b.factors && a3.factors == b3.factors, "h omega = %g: %ld / %ld factorisations",
                  1000 * h[c], a.factors, b.factors);
    ck_assert_msg(labs(a.iters - b.iters) <= a.steps / 10 && labs(a3.iters - b3.iters) <= a3.steps / 10,
                  "h omega = %g: %ld / %ld iterations (s = 2), %ld / %ld (s = 3)", 1000 * h[c], a.iters, b.iters, a3.iters, b3.iters);
  }
}
END_TEST

/* Every step converges, in at most 12 iterations up to h omega = 100 at
 * omega = 1000, 40 at h omega = 1000 and at omega = 50 (measured, chain of
 * 8 / of 500: 5 / 5, 8 / 8 and 25 / 26 at omega = 1000; 10 / 11 at omega =
 * 50, h omega = 10; 14 on the chain of 8 at h omega = 30, h = 0.6, the
 * longest step check_stiff.c takes at omega = 50), within NAME_REFRESH = 4
 * factorisations; H within 8 ulps of (1 + h omega) H0 a step as a random
 * walk (measured at most 0.062 of that bound). The chain of 500 starts with
 * every site moving (H0 = 750). Not tested: omega = 50 at h = 2 (h omega =
 * 100), where the soft springs' nonlinearity over the step, not the
 * stiffness, sets the contraction (a local error estimate of 7: no step a
 * user would take); there the chain of 8 took 37 and 58 iterations before
 * the accelerated update (docs/method-newton.md), 71 and 95 with it, and the
 * rolled step's rounding then fails one step, which the driver halves. */
START_TEST(test_converges)
{
  static const struct {
    double omega, hw, T;
    int iters, large;
  } cases[] = {{1000, 10, 2, 12, 1}, {1000, 100, 2, 12, 1}, {1000, 1000, 2, 40, 1}, {50, 10, 2, 40, 1}, {50, 30, 4, 40, 0}};
  for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
    Run r[2];
    double h = cases[c].hw / cases[c].omega;
    RUN(rn8_k4s2, rn8_k4s2, cases[c].omega, h, cases[c].T, r[0]);
    if (cases[c].large) RUN(rn500_k4s2, rn500_k4s2, cases[c].omega, h, cases[c].T, r[1]);
    for (int n = 0; n < 1 + cases[c].large; n++) {
      double bound = 8 * DBL_EPSILON * (1 + cases[c].hw) * fabs(r[n].H0) * sqrt(r[n].steps);
      printf("rolled Newton, m = %d, omega = %g, h omega = %g: %d steps, %d iterations at most, %d factorisations, "
             "|H - H0| %.3g\n", n ? 1000 : 16, cases[c].omega, cases[c].hw, r[n].steps, r[n].max_iters, r[n].max_factors, r[n].dH);
      ck_assert_msg(!r[n].failed, "m = %d, omega = %g, h omega = %g: a step failed", n ? 1000 : 16, cases[c].omega, cases[c].hw);
      ck_assert_msg(r[n].max_iters <= cases[c].iters && r[n].max_factors <= 4, "omega = %g, h omega = %g: %d iterations, %d factorisations",
                    cases[c].omega, cases[c].hw, r[n].max_iters, r[n].max_factors);
      ck_assert_msg(r[n].dH <= bound, "omega = %g, h omega = %g: |H - H0| = %.3g > %.3g", cases[c].omega, cases[c].hw, r[n].dH, bound);
    }
  }
}
END_TEST

/* At h omega = 1 the rolled fixed-point step converges too: the chain of 500
 * under Newton follows it over T = 1 (1000 steps) to the round-off of two
 * iterations that both converge, each committing its own last iterate
 * (measured 9.4e-13; asserted 1e-10). */
START_TEST(test_same_as_fixed)
{
  Run r;
  RUN(rn500_k4s2, rn500_fixed_k4s2, 1000, 0.001, 1.0, r);
  printf("rolled Newton vs rolled fixed point, m = 1000, h omega = 1: %.3g apart\n", r.diff);
  ck_assert_msg(!r.failed, "a step failed");
  ck_assert_msg(r.diff <= 1e-10, "the iterations' steps are %.3g apart", r.diff);
}
END_TEST

/* --iteration auto, rolled: the sweeps run first and hand over to Newton
 * where they are slow, as in the straight-line auto step (check_auto.c),
 * so the two forms take the same path and reach the same steps up to the
 * reordered eliminations; at h omega = 0.1 Newton never runs. The chain of
 * 500 under the defaults (gen/main.c's rolled_newton_candidate) hands over
 * in its first step and then matches the rolled Newton step to the
 * round-off of two converged iterations (as test_same_as_fixed). */
START_TEST(test_auto)
{
  static const double hw[3] = {0.1, 10, 100};
  for (int c = 0; c < 3; c++) {
    Run a, b;
    double h = hw[c] / 1000;
    RUN(rn8auto_k4s2, rn8auto_straight_k4s2, 1000, h, 500 * h, a);
    RUN(rn8auto_straight_k4s2, rn8auto_straight_k4s2, 1000, h, 500 * h, b);
    printf("rolled vs straight-line auto, h omega = %g: %.3g apart, %ld / %ld Newton iterations\n", hw[c], a.diff, a.iters,
           b.iters);
    ck_assert_msg(!a.failed && !b.failed, "h omega = %g: a step failed", hw[c]);
    ck_assert_msg(a.diff <= REORDER_TOL, "h omega = %g: the forms are %.3g apart", hw[c], a.diff);
    ck_assert_msg(c == 0 ? a.iters == 0 && b.iters == 0 : a.iters >= a.steps && labs(a.iters - b.iters) <= a.steps / 10,
                  "h omega = %g: %ld / %ld Newton iterations in %d steps", hw[c], a.iters, b.iters, a.steps);
  }
  Run r;
  RUN(rn500auto_k4s2, rn500_k4s2, 1000, 0.01, 0.5, r);
  printf("chain of 500, defaults vs rolled Newton, h omega = 10: %.3g apart, %ld Newton iterations in %d steps\n", r.diff,
         r.iters, r.steps);
  ck_assert_msg(!r.failed && r.iters >= r.steps && r.diff <= 1e-10, "defaults: %d failed, %ld iterations, %.3g apart",
                r.failed, r.iters, r.diff);
}
END_TEST

/* A step too long for the soft springs' nonlinearity (h = 20) fails; the
 * state, the kept factor and the compensations included, is unchanged to
 * the byte. */
START_TEST(test_failed_step_rolls_back)
{
  rn500_k4s2_state x, before;
  rn500_k4s2_params prm;
  rn500_k4s2_params_default(&prm);
  memset(&x, 0, sizeof x);
  rn500_k4s2_init_params(&x, NULL, NULL, &prm);
  for (int n = 0; n < 3; n++) ck_assert_int_eq(rn500_k4s2_step(&x, 0.1, &prm, NULL), rn500_k4s2_OK);
  memcpy(&before, &x, sizeof x);
  int rc = rn500_k4s2_step(&x, 20, &prm, NULL);
  ck_assert_int_ne(rc, rn500_k4s2_OK);
  ck_assert_msg(!memcmp(&before, &x, sizeof x), "the failed step (%s) changed the state", rn500_k4s2_strerror(rc));
}
END_TEST

/* --batch 2 on the rolled Newton step: lanes at omega = 1000 and 500 (h
 * omega = 10 and 5), then a step of h = 20 that fails in both; each lane's
 * state and code bitwise the scalar step's. */
START_TEST(test_batch_lanes)
{
  rnb8_k4s2_batch b;
  rnb8_k4s2_state s[2], y;
  rnb8_k4s2_params prm[2];
  rnb8_k4s2_batch_stats bs;
  memset(&b, 0, sizeof b);
  for (int l = 0; l < 2; l++) {
    rnb8_k4s2_params_default(&prm[l]);
    prm[l].omega = l ? 500 : 1000;
    rnb8_k4s2_init_params(&s[l], NULL, NULL, &prm[l]);
    rnb8_k4s2_batch_set(&b, l, &s[l]);
  }
  for (int n = 0; n < 21; n++) {
    double h = n < 20 ? 0.01 : 20;
    rnb8_k4s2_batch_step(&b, h, prm, &bs);
    for (int l = 0; l < 2; l++) {
      int rc = rnb8_k4s2_step(&s[l], h, &prm[l], NULL);
      ck_assert_msg(bs.code[l] == rc, "step %d lane %d: code %d, scalar %d", n, l, bs.code[l], rc);
      ck_assert(n < 20 || rc != rnb8_k4s2_OK);
      rnb8_k4s2_batch_get(&b, l, &y);
      ck_assert_msg(!memcmp(&y, &s[l], sizeof y), "step %d lane %d: the state differs from the scalar step's", n, l);
    }
  }
}
END_TEST

/* The stiff polymer's fastest frequency at ka = 1e4 (auto's estimate at q0,
 * `hbvmgen --check`: 205 for 6 beads). */
#define POLY_OMEGA 205.0

/* Rolled and straight-line Newton with constraints factor the same saddle
 * point in other orders (one band in the order of the coordinates, against
 * the blocks and the dense Schur complement of step_newton.c). Each step
 * stops when its increment is at round-off, so each commits its own last
 * iterate: the first step's results differ by 1e-13 (h omega = 10) to 2e-13
 * (30), a few times NAME_NOISETOL, and the difference grows along the run
 * with the polymer's sensitivity to its initial state (measured 1.5e-12 and
 * 1.2e-11 at T = 2). Asserted 1e-10: round-off times a growth of 1e3. */
#define REORDER_KKT_TOL 1e-10

typedef struct {
  int steps, failed, max_iters;
  long iters, factors, citers, cfactors;
  double dH, H0, g, diff;
} KktRun;

/* The largest |g_a| of solver P's state x, and the scale of its round-off:
 * 64 ulps of the largest 1 + |q_i| (g's terms are squares of the bonds'
 * coordinates, differences of coordinates of the size of q rounded to ulps
 * of it). */
#define G_ROUNDOFF(P, x, prm, gmax, gscale)                                \
  do {                                                                     \
    P##_real g_[P##_NU];                                                   \
    P##_constraints(&(x), &(prm), g_);                                     \
    for (int a_ = 0; a_ < P##_NU; a_++) (gmax) = fmax((gmax), fabs(g_[a_])); \
    for (int i_ = 0; i_ < P##_M; i_++)                                     \
      (gscale) = fmax((gscale), 64 * DBL_EPSILON * (1 + fabs((x).q[i_]))); \
  } while (0)

/* Step the polymer P (default params) and C beside it in steps of h to T:
 * counts of both, |H - H0| and max |g| over gscale (g's round-off) of P, the
 * largest difference of q, p into r.diff. */
#define RUN_KKT(P, C, h, T, r)                                                                     \
  do {                                                                                             \
    static P##_state x_;                                                                           \
    static C##_state y_;                                                                           \
    P##_params prm_;                                                                               \
    C##_params cprm_;                                                                              \
    double gs_ = 0;                                                                                \
    START_PAIR(P, C, h, T, r, (void)0);                                                            \
    for (int n_ = 0; n_ < (r).steps; n_++) {                                                       \
      P##_stats st_;                                                                               \
      C##_stats ct_;                                                                               \
      if (P##_step(&x_, (h), &prm_, &st_) != P##_OK || C##_step(&y_, (h), &cprm_, &ct_) != C##_OK) { \
        (r).failed++;                                                                              \
        break;                                                                                     \
      }                                                                                            \
      (r).iters += st_.newton;                                                                     \
      (r).factors += st_.factors;                                                                  \
      (r).citers += ct_.newton;                                                                    \
      (r).cfactors += ct_.factors;                                                                 \
      if (st_.newton > (r).max_iters) (r).max_iters = st_.newton;                                  \
      (r).dH = fmax((r).dH, fabs(P##_energy(&x_, &prm_) - (r).H0));                                \
      G_ROUNDOFF(P, x_, prm_, (r).g, gs_);                                                         \
      for (int i_ = 0; i_ < P##_M; i_++)                                                           \
        (r).diff = fmax((r).diff, fmax(fabs(x_.q[i_] - y_.q[i_]), fabs(x_.p[i_] - y_.p[i_])));     \
    }                                                                                              \
    (r).g /= gs_ > 0 ? gs_ : 1;                                                                    \
  } while (0)

/* The bound of |H - H0| of tests/check_newton.c: 8 ulps of (1 + h omega)
 * |H0| a step, as a random walk. */
static double h_bound(double hw, double H0, int steps) { return 8 * DBL_EPSILON * (1 + hw) * fabs(H0) * sqrt(steps); }

/* The polymer of 6 beads, rolled against straight-line, at h omega = 10 and
 * 30, in both families (measured, const / poly: 1.5e-12 / 1.5e-12 and 1.2e-11 /
 * 4.1e-11 apart; 10.2 / 13.9 and 23.0 / 35.7 iterations a step, at most 11 /
 * 18 and 37 / 56, the straight-line step within 2 %; the same
 * factorisations; max |g| 1.3e-15 / 1.1e-15, 1.7e-15 / 2e-15). Then 40
 * adaptive steps (tol 1e-4) of the rolled const step from the same state
 * (measured: h omega up to 0.49, where the error control holds the step, 148
 * Newton iterations). */
START_TEST(test_kkt_same_as_straight)
{
  static const double hw[2] = {10, 30};
  static const int max_iters[2] = {25, 80};
  for (int c = 0; c < 2; c++) {
    KktRun r[2];
    RUN_KKT(rp6_k4s2, rp6_straight_k4s2, hw[c] / POLY_OMEGA, 2.0, r[0]);
    RUN_KKT(rp6p_k4s2, rp6p_straight_k4s2, hw[c] / POLY_OMEGA, 2.0, r[1]);
    for (int f = 0; f < 2; f++) {
      const char *fam = f ? "poly" : "const";
      printf("rolled vs straight-line Newton with constraints (%s), h omega = %g: %.3g apart, %.3g (max %d) / %.3g iterations "
             "a step, %ld / %ld factorisations, |H - H0| %.3g, max |g| %.3g of its round-off\n",
             fam, hw[c], r[f].diff, (double)r[f].iters / r[f].steps, r[f].max_iters, (double)r[f].citers / r[f].steps, r[f].factors,
             r[f].cfactors, r[f].dH, r[f].g);
      ck_assert_msg(!r[f].failed, "%s, h omega = %g: a step failed", fam, hw[c]);
      ck_assert_msg(r[f].diff <= REORDER_KKT_TOL, "%s, h omega = %g: the forms are %.3g apart", fam, hw[c], r[f].diff);
      ck_assert_msg(r[f].max_iters <= max_iters[c], "%s, h omega = %g: %d iterations in a step", fam, hw[c], r[f].max_iters);
      ck_assert_msg(labs(r[f].iters - r[f].citers) <= r[f].iters / 10 && labs(r[f].factors - r[f].cfactors) <= r[f].factors / 10 + 1,
                    "%s, h omega = %g: %ld / %ld iterations, %ld / %ld factorisations", fam, hw[c], r[f].iters, r[f].citers,
                    r[f].factors, r[f].cfactors);
      ck_assert_msg(r[f].dH <= h_bound(hw[c], r[f].H0, r[f].steps), "%s, h omega = %g: |H - H0| = %.3g", fam, hw[c], r[f].dH);
      ck_assert_msg(r[f].g <= 1, "%s, h omega = %g: max |g| is %.3g times its round-off", fam, hw[c], r[f].g);
    }
  }
  rp6_k4s2_state x;
  rp6_k4s2_params prm;
  rp6_k4s2_stats st;
  double h = 0.01, gmax = 0, gs = 0, hmax = 0;
  long newton = 0;
  rp6_k4s2_params_default(&prm);
  rp6_k4s2_init_params(&x, NULL, NULL, &prm);
  for (int n = 0; n < 40; n++) {
    ck_assert_int_eq(rp6_k4s2_step_adaptive(&x, &h, 1e-4, &prm, &st), rp6_k4s2_OK);
    G_ROUNDOFF(rp6_k4s2, x, prm, gmax, gs);
    newton += st.newton;
    hmax = fmax(hmax, st.h);
  }
  printf("rolled Newton with constraints, adaptive (tol 1e-4): t = %.3g after 40 steps, h omega up to %.3g, %ld Newton "
         "iterations, max |g| %.3g\n", x.t, hmax * POLY_OMEGA, newton, gmax);
  ck_assert_msg(gmax <= gs, "adaptive: max |g| = %.3g", gmax);
  ck_assert_msg(newton > 0, "adaptive: no Newton iteration");
}
END_TEST

/* The polymer of 100 beads P at h omega = 10, T = 0.5: every step converges
 * in a bounded number of iterations, H and g at round-off. */
#define LONG_CHAIN(P, fam)                                                                                            \
  do {                                                                                                               \
    KktRun r_;                                                                                                       \
    RUN_KKT(P, P, 10 / POLY_OMEGA, 0.5, r_);                                                                         \
    printf("rolled Newton with constraints (%s), 100 beads, h omega = 10: %.3g (max %d) iterations, %.3g "            \
           "factorisations a step, |H - H0| %.3g, max |g| %.3g of its round-off\n", fam, (double)r_.iters / r_.steps,  \
           r_.max_iters, (double)r_.factors / r_.steps, r_.dH, r_.g);                                                  \
    ck_assert_msg(!r_.failed, "%s: a step failed", fam);                                                             \
    ck_assert_msg(r_.max_iters <= 25 && r_.factors <= 4 * r_.steps, "%s: %d iterations, %ld factorisations", fam,    \
                  r_.max_iters, r_.factors);                                                                          \
    ck_assert_msg(r_.dH <= h_bound(10, r_.H0, r_.steps), "%s: |H - H0| = %.3g", fam, r_.dH);                         \
    ck_assert_msg(r_.g <= 1, "%s: max |g| is %.3g times its round-off", fam, r_.g);                                  \
  } while (0)

/* The polymer of 100 beads (m = 300, nu = 99) at h omega = 10, T = 0.5 (10
 * steps; measured const / poly: 10.9 / 10.7 iterations a step, at most 11,
 * one factorisation a step, |H - H0| 2.1e-12 / 0 of H0 = 158); its C,
 * generated from the model, at most twice that of the 6 beads (measured 406
 * KB and 310 KB: the loops do not grow with N, the tables of the band and of
 * q0, p0 do). */
START_TEST(test_kkt_long_chain)
{
  LONG_CHAIN(rp100_k4s2, "const");
  LONG_CHAIN(rp100p_k4s2, "poly");
  char *t6 = read_text("models/polymer_stiff6.ham"), *t100 = read_text("models/polymer_stiff100.ham");
  ck_assert(t6 && t100);
  const char *flags = "-s 2 -k 4 --multiplier const --iteration newton --rolled on";
  char *c6 = generate_source(t6, flags), *c100 = generate_source(t100, flags);
  ck_assert_msg(c6 && c100, "generation failed (or wrote more than 4 MiB)");
  printf("rolled Newton with constraints: C of 6 beads %zu bytes, of 100 beads %zu\n", strlen(c6), strlen(c100));
  ck_assert_msg(strlen(c100) <= 2 * strlen(c6), "the C of 100 beads is %zu bytes against %zu for 6", strlen(c100), strlen(c6));
  free(t6);
  free(t100);
  free(c6);
  free(c100);
}
END_TEST

/* Two steps of h omega = 10, then one of h omega = 100 that fails (the
 * iteration does not converge: measured from h omega = 60 on); the state,
 * the kept factor included, unchanged to the byte but for nfw, the factor
 * being made, which the 100 beads' solvers keep in the state (317 and
 * 391 KB, over NEWTON_LOCAL_MAX_BYTES) as the step's scratch. */
#define ROLLBACK(P)                                                                                       \
  do {                                                                                                   \
    static P##_state x_, before_;                                                                        \
    P##_params prm_;                                                                                     \
    P##_params_default(&prm_);                                                                           \
    memset(&x_, 0, sizeof x_);                                                                           \
    P##_init_params(&x_, NULL, NULL, &prm_);                                                             \
    for (int n_ = 0; n_ < 2; n_++) ck_assert_int_eq(P##_step(&x_, 10 / POLY_OMEGA, &prm_, NULL), P##_OK); \
    memcpy(&before_, &x_, sizeof x_);                                                                    \
    int rc_ = P##_step(&x_, 100 / POLY_OMEGA, &prm_, NULL);                                              \
    ck_assert_int_ne(rc_, P##_OK);                                                                       \
    memcpy(before_.nfw, x_.nfw, sizeof x_.nfw); /* the step's scratch (docs/api.md): all but it */      \
    ck_assert_msg(!memcmp(&before_, &x_, sizeof x_), #P ": the failed step (%s) changed the state",      \
                  P##_strerror(rc_));                                                                    \
  } while (0)

START_TEST(test_kkt_failed_step_rolls_back)
{
  ROLLBACK(rp100_k4s2);
  ROLLBACK(rp100p_k4s2);
}
END_TEST

/* Two steps of the 100 beads (both families) on a thread whose stack is 256
 * KB: the factor being made (317 and 391 KB) is the state's scratch, not a
 * local of the step. Fails (a stack overflow: the runner's fork reports the
 * signal) on a step that makes it on the stack, as the polymer of 1000
 * beads at s = 4 did with 15 MB on the 8 MB main stack. */
static void *two_steps(void *arg)
{
  static rp100_k4s2_state x;
  static rp100p_k4s2_state y;
  rp100_k4s2_params prm;
  rp100p_k4s2_params prmp;
  int *ok = arg;
  rp100_k4s2_params_default(&prm);
  rp100p_k4s2_params_default(&prmp);
  rp100_k4s2_init_params(&x, NULL, NULL, &prm);
  rp100p_k4s2_init_params(&y, NULL, NULL, &prmp);
  *ok = 1;
  for (int n = 0; n < 2; n++)
    *ok &= rp100_k4s2_step(&x, 10 / POLY_OMEGA, &prm, NULL) == rp100_k4s2_OK &&
           rp100p_k4s2_step(&y, 10 / POLY_OMEGA, &prmp, NULL) == rp100p_k4s2_OK;
  return NULL;
}

START_TEST(test_kkt_small_stack)
{
  pthread_attr_t attr;
  pthread_t t;
  int ok = 0;
  ck_assert_int_eq(sizeof(((rp100_k4s2_state *)0)->nfw) > 256 * 1024, 1); /* gen/emit.h's NEWTON_LOCAL_MAX_BYTES */
  ck_assert_int_eq(pthread_attr_init(&attr), 0);
  ck_assert_int_eq(pthread_attr_setstacksize(&attr, 256 * 1024), 0);
  ck_assert_int_eq(pthread_create(&t, &attr, two_steps, &ok), 0);
  ck_assert_int_eq(pthread_join(t, NULL), 0);
  pthread_attr_destroy(&attr);
  ck_assert_msg(ok, "a step of the 100 beads failed");
}
END_TEST

/* What the rolled form does not cover under Newton is refused, at the
 * model's line; --rolled auto falls back to straight-line code there. */
START_TEST(test_refused)
{
  char out[4096];
  ck_assert_msg(!generator_output("--check --rolled on --iteration newton ../models/chain8.ham", out, sizeof out),
                "poly family: %s", out);
  ck_assert_msg(!generator_output("--check --rolled on --iteration newton --multiplier const ../models/chain8.ham", out, sizeof out),
                "const family: %s", out);
  ck_assert_int_ne(generator_output("--check --rolled on --iteration newton --wide-step ../models/chain8.ham", out, sizeof out), 0);
  static const char pairs[] = "N = 12\nvariables x[N]\nU = sum(i in 1..N - 1, j in i + 1..N, ((x[i] - x[j])^2 - 1)^2)\n"
                              "q0 = [0.1 * i for i in 1..N]\np0 = [0 for i in 1..N]\n";
  ck_assert_ptr_null(generate_source(pairs, "-s 2 --iteration newton --rolled on")); /* the band would be full */
  char *a = generate_source(pairs, "-s 2 --iteration newton");
  ck_assert_msg(a && !strstr(a, "(rolled)"), "--rolled auto rolled a pair sum under Newton");
  free(a);
  char *c = generate_source("N = 64\nvariables x[N]\nU = sum(i in 1..N - 1, (x[i + 1] - x[i])^4) + sum(i in 1..N, x[i]^2)\n"
                            "q0 = [0.1 for i in 1..N]\np0 = [0 for i in 1..N]\n", "-s 2 --iteration newton --rolled on");
  ck_assert_msg(c && strstr(c, "_nband_factor_c") && strstr(c, "(i)  /* the band's rows in the natural order"),
                "the chain x[64] under Newton was not rolled with its band in the natural order");
  free(c);
}
END_TEST

Suite *rollnewton_suite(void)
{
  Suite *s = suite_create("rollnewton");
  TCase *tc = tcase_create("rolled Newton");
  tcase_set_timeout(tc, 600);
  tcase_add_test(tc, test_same_as_straight);
  tcase_add_test(tc, test_converges);
  tcase_add_test(tc, test_same_as_fixed);
  tcase_add_test(tc, test_auto);
  tcase_add_test(tc, test_failed_step_rolls_back);
  tcase_add_test(tc, test_batch_lanes);
  tcase_add_test(tc, test_refused);
  suite_add_tcase(s, tc);
  TCase *kkt = tcase_create("constrained");
  tcase_set_timeout(kkt, 600);
  tcase_add_test(kkt, test_kkt_same_as_straight);
  tcase_add_test(kkt, test_kkt_long_chain);
  tcase_add_test(kkt, test_kkt_failed_step_rolls_back);
  tcase_add_test(kkt, test_kkt_small_stack);
  suite_add_tcase(s, kkt);
  return s;
}
