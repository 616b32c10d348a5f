/* check_dense.c - NAME_dense, the output inside the last step, against the
 * reference at off-step times.
 *
 * The local error of the dense output: start the solver on the reference
 * at t_{n-1}, take one step (for its usual warm start), put the state back
 * on the reference at t_n, take the step, and compare NAME_dense at
 * theta = 1/4, 1/2, 3/4 with the reference at t_n + theta h (max norm over
 * q and p, max over the steps of a span). The step's polynomials are of
 * degree s and uniformly of order s+1, so that error falls like h^(s+1):
 * halving h must divide it by 2^(s+1), within 0.4 in the measured rate
 * (HBVM_DENSE_TABLE=1 prints the errors and rates). At theta = 1 the
 * output is the state exactly and at theta = 0 the state before the step
 * to round-off. */
#define _POSIX_C_SOURCE 200809L
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "errest.h"
#include "solvers.h"

Suite *dense_suite(void);

#define SUB 4 /* reference points per step */

typedef struct {
  double err;     /* max error at the interior points */
  double end_gap; /* max |dense(1) - state|, bitwise: must be 0 */
  double start_gap; /* max |dense(0) - state before the step| / (1 + |value|) */
} DenseErr;

static void gap(double *g, const double *a, const double *b, int m, int rel) {
  for (int i = 0; i < m; i++) *g = fmax(*g, fabs(a[i] - b[i]) / (rel ? 1 + fabs(b[i]) : 1));
}

// The dense output's errors over the steps n = 1..N-1 of the grid h.
static DenseErr measure(const char *problem, const char *solver, double h, long N) {
  const Solver *sv = solver_find(solver);
  ck_assert_msg(sv != NULL, "no solver %s", solver);
  int m = sv->m;
  long npt = SUB * (N + 1) + 1;
  double *q = malloc(sizeof(double) * m * (npt + 1)), *p = malloc(sizeof(double) * m * (npt + 1));
  double *x = malloc(sv->state_size), *qd = malloc(sizeof(double) * m), *pd = malloc(sizeof(double) * m);
  ck_assert(q && p && x && qd && pd);
  ck_assert_int_eq(errest_reference(problem, h / SUB, npt, m, q, p), 0);
  DenseErr r = {0, 0, 0};
  for (long n = 1; n < N; n++) {
    double est;
    sv->init(x, q + SUB * (n - 1) * m, p + SUB * (n - 1) * m);
    ck_assert_int_eq(sv->step_est(x, h, &est), 0);
    memcpy(solver_q(sv, x), q + SUB * n * m, sizeof(double) * m);
    memcpy(solver_p(sv, x), p + SUB * n * m, sizeof(double) * m);
    ck_assert_int_eq(sv->step_est(x, h, &est), 0);
    for (int k = 1; k < SUB; k++) {
      sv->dense(x, (double)k / SUB, qd, pd);
      gap(&r.err, qd, q + (SUB * n + k) * m, m, 0);
      gap(&r.err, pd, p + (SUB * n + k) * m, m, 0);
    }
    sv->dense(x, 1, qd, pd);
    gap(&r.end_gap, qd, solver_q(sv, x), m, 0);
    gap(&r.end_gap, pd, solver_p(sv, x), m, 0);
    sv->dense(x, 0, qd, pd);
    gap(&r.start_gap, qd, q + SUB * n * m, m, 1);
    gap(&r.start_gap, pd, p + SUB * n * m, m, 1);
  }
  free(q);
  free(p);
  free(x);
  free(qd);
  free(pd);
  return r;
}

static const StepCase cases[] = {
    {"pendulum", "pendulum_poly_k1s1", 0.1, 40}, {"pendulum", "pendulum_poly_k2s2", 0.2, 20},
    {"pendulum", "pendulum_poly_k3s3", 0.4, 10}, {"pendulum", "pendulum_poly_k4s4", 0.4, 10},
    {"kepler", "kepler_k1s1", 0.02, 100},       {"kepler", "kepler_k2s2", 0.02, 100},
    {"kepler", "kepler_k3s3", 0.04, 50},         {"kepler", "kepler_k4s4", 0.05, 40},
    {"double_pendulum", "double_pendulum_k3s3", 0.2, 20},
};

START_TEST(dense_order)
{
  const Solver *sv = solver_find(cases[_i].solver);
  ck_assert_ptr_nonnull(sv);
  DenseErr a = measure(cases[_i].problem, cases[_i].solver, cases[_i].h, cases[_i].N);
  DenseErr b = measure(cases[_i].problem, cases[_i].solver, cases[_i].h / 2, 2 * cases[_i].N);
  double rate = log2(a.err / b.err);
  if (getenv("HBVM_DENSE_TABLE"))
    printf("%-16s %-24s h=%-5g err %.3e  h/2 err %.3e  rate %.2f (s+1 = %d)  start gap %.1e\n", cases[_i].problem,
           cases[_i].solver, cases[_i].h, a.err, b.err, rate, sv->s + 1, fmax(a.start_gap, b.start_gap));
  ck_assert_msg(a.end_gap == 0 && b.end_gap == 0, "%s: dense(1) is not the state", cases[_i].solver);
  ck_assert_msg(a.start_gap <= 1e-13 && b.start_gap <= 1e-13, "%s: dense(0) off the previous state by %g",
                cases[_i].solver, fmax(a.start_gap, b.start_gap));
  ck_assert_msg(b.err > 1e-13, "%s: error %g at round-off, no rate to measure", cases[_i].solver, b.err);
  ck_assert_msg(rate >= sv->s + 1 - 0.4, "%s: dense output of order %.2f, below s+1 = %d", cases[_i].solver, rate,
                sv->s + 1);
}
END_TEST

Suite *dense_suite(void) {
  Suite *s = suite_create("dense");
  TCase *tc = tcase_create("dense");
  tcase_set_tags(tc, "sanlong"); /* the generated arithmetic: sanitized in check-long */
  tcase_add_loop_test(tc, dense_order, 0, sizeof cases / sizeof cases[0]);
  suite_add_tcase(s, tc);
  return s;
}
