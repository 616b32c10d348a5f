/* side_by_side.h - two generated solvers of the same model stepped side by
 * side from their default states (tests/check_mass.c, tests/check_rolled.c). */
#ifndef HBVM_TESTS_SIDE_BY_SIDE_H
#define HBVM_TESTS_SIDE_BY_SIDE_H

#include <check.h>
#include <math.h>
#include <stdio.h>

#define NSTEPS 400

/* max(worst, |a[i] - b[i]| for i < n) */
static inline double max_diff(double worst, const double *a, const double *b, int n)
{
  for (int i = 0; i < n; i++) worst = fmax(worst, fabs(a[i] - b[i]));
  return worst;
}

/* Step a model with M of params (default params) and the same model with
 * that M written as constants, side by side, NSTEPS steps of h; returns the
 * largest difference of (t, q, p, lambda) over the run. P is the param
 * solver, C the constant one; their public fields lead the state. */
#define SIDE_BY_SIDE(P, C, h, worst)                                                                    \
  do {                                                                                                  \
    P##_state xp;                                                                                       \
    C##_state xc;                                                                                       \
    P##_params prm;                                                                                     \
    P##_params_default(&prm);                                                                           \
    P##_init(&xp, NULL, NULL);                                                                          \
    C##_init(&xc, NULL, NULL);                                                                          \
    (worst) = 0;                                                                                        \
    for (int n = 0; n < NSTEPS; n++) {                                                                  \
      int rp = P##_step(&xp, (h), &prm, NULL), rc = C##_step(&xc, (h), NULL, NULL);                     \
      ck_assert_msg(rp == 0 && rc == 0, #P " / " #C " step %d: %s / %s", n, P##_strerror(rp),           \
                    C##_strerror(rc));                                                                  \
      (worst) = max_diff(fmax((worst), fabs(xp.t - xc.t)), xp.q, xc.q, P##_M);                            \
      (worst) = max_diff((worst), xp.p, xc.p, P##_M);                                                   \
      (worst) = max_diff((worst), xp.lambda, xc.lambda, P##_NU);                                        \
    }                                                                                                   \
  } while (0)

/* SIDE_BY_SIDE, reported as what and asserted within tol. */
#define SAME_TRAJECTORY(P, C, h, tol, what)                                                            \
  do {                                                                                                 \
    double worst_;                                                                                     \
    SIDE_BY_SIDE(P, C, h, worst_);                                                                     \
    printf("side by side: %s: max |difference| %.3g over %d steps\n", what, worst_, NSTEPS);                 \
    ck_assert_msg(worst_ <= (tol), "%s: the trajectories differ by %.3g", what, worst_);               \
  } while (0)

/* |H - H0| and max |g| (into dH, dg: running maxima) of solver P over n
 * steps of h from its default state (tests/check_reroll.c, check_cluster.c). */
#define SOLVER_DRIFT(P, h, n, dH, dg)                                      \
  do {                                                                     \
    P##_state x;                                                           \
    double g_[P##_NU];                                                     \
    P##_init(&x, NULL, NULL);                                              \
    double H0 = P##_energy(&x, NULL);                                      \
    for (int n_ = 0; n_ < (n); n_++) {                                     \
      ck_assert_int_eq(P##_step(&x, (h), NULL, NULL), 0);                  \
      P##_constraints(&x, NULL, g_);                                       \
      (dH) = fmax((dH), fabs(P##_energy(&x, NULL) - H0));                  \
      for (int i = 0; i < P##_NU; i++) (dg) = fmax((dg), fabs(g_[i]));     \
    }                                                                      \
  } while (0)

#endif
