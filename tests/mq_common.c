/* mq_common.c - the tests of suite mq that read a solver only through
 * MqSolver (tests/mq_common.h), shared by check_mq.c (M(q)) and
 * check_mq_fourbar.c (M(q) with constraints). Each asserts with Check, so
 * it is called from inside a test. */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mq_common.h"

int mq_table(void) {
  const char *v = getenv("HBVM_MQ_TABLE");
  return v && *v == '1';
}

void mq_start(const MqSolver *sv, void *x, double *q, double *p) {
  double t;
  sv->init(x, NULL, NULL);
  sv->get(x, &t, q, p);
}

// The max-norm distance of (q, p) from (rq, rp), or err if larger.
static double distance(int m, double err, const double *q, const double *p, const double *rq, const double *rp) {
  for (int i = 0; i < m; i++) err = fmax(err, fmax(fabs(q[i] - rq[i]), fabs(p[i] - rp[i])));
  return err;
}

// The reference carried step by step beside the solver.
double mq_run_error(const MqSolver *sv, void *x, double h, int n) {
  double q[MQ_MAXM], p[MQ_MAXM], rq[MQ_MAXM], rp[MQ_MAXM], t, est, err = 0;
  mq_start(sv, x, rq, rp);
  for (int k = 1; k <= n; k++) {
    ck_assert_int_eq(sv->step(x, h, &est), 0);
    sv->reference(sv->data, (k - 1) * h, k * h, rq, rp);
    sv->get(x, &t, q, p);
    err = distance(sv->m, err, q, p, rq, rp);
  }
  return err;
}

// The rate log2(e(h) / e(h/2)) within 0.3 below 2s and 0.6 above (the rate
// of a max over a run scatters a little), the error at h/2 well above
// round-off (else the rate is noise: take a larger h).
void mq_check_order(const MqSolver *sv, void *x, double h, double T) {
  double e1 = mq_run_error(sv, x, h, (int)lround(T / h)), e2 = mq_run_error(sv, x, h / 2, (int)lround(2 * T / h));
  double rate = log2(e1 / e2);
  if (mq_table()) printf("order: %s s=%d h=%g: %.3e, h/2: %.3e, rate %.2f\n", sv->model, sv->s, h, e1, e2, rate);
  ck_assert_msg(e2 > 1e-12, "%s: the error %.3e at h/2 is near round-off: take a larger h", sv->name, e2);
  ck_assert_msg(rate > 2 * sv->s - 0.3 && rate < 2 * sv->s + 0.6, "%s: rate %.2f, want %d (%.3e -> %.3e)", sv->name,
                rate, 2 * sv->s, e1, e2);
}

// From the reference at t_k: a first step (for the warm start), the state
// put back on the reference at t_{k+1}, the step measured from there
// against the reference at t_{k+2}, over the steps whose true error is
// above round-off (at least 10 of them).
void mq_check_errest(const MqSolver *sv, void *x, double h) {
  double rq[MQ_MAXM], rp[MQ_MAXM], q[MQ_MAXM], p[MQ_MAXM], t, lsum = 0, lo = HUGE_VAL, hi = 0;
  int n = 0;
  mq_start(sv, x, rq, rp);
  for (int k = 0; k < 30; k++) {
    double est, nq[MQ_MAXM], np[MQ_MAXM], err = 0;
    sv->init(x, rq, rp);
    ck_assert_int_eq(sv->step(x, h, &est), 0);
    sv->reference(sv->data, k * h, (k + 1) * h, rq, rp);
    sv->set(x, rq, rp);
    ck_assert_int_eq(sv->step(x, h, &est), 0);
    sv->get(x, &t, q, p);
    memcpy(nq, rq, sizeof nq);
    memcpy(np, rp, sizeof np);
    sv->reference(sv->data, (k + 1) * h, (k + 2) * h, nq, np);
    for (int i = 0; i < sv->m; i++) err = fmax(err, fabs(q[i] - nq[i]));
    if (err < 1e-14) continue;
    double r = err / est;
    lsum += log(r);
    lo = fmin(lo, r);
    hi = fmax(hi, r);
    n++;
  }
  ck_assert_int_gt(n, 10);
  double mean = exp(lsum / n);
  if (mq_table())
    printf("errest: %s s=%d h=%g: true/estimate mean %.2f, range [%.2f, %.2f], %d steps\n", sv->model, sv->s, h, mean,
           lo, hi, n);
  ck_assert_msg(mean > 0.1 && mean < 10, "%s: true / estimate %.3g in geometric mean", sv->name, mean);
}

// From the start at h = 0.01, the last step shortened to end on T (to
// round-off); the error against the reference at the t reached.
void mq_check_adaptive(const MqSolver *sv, void *x, double T, void (*at_end)(const MqSolver *sv, const void *x, double tol)) {
  double last = HUGE_VAL;
  for (double tol = 1e-6; tol > 1e-11; tol /= 100) {
    double h = 0.01, t = 0, q[MQ_MAXM], p[MQ_MAXM], rq[MQ_MAXM], rp[MQ_MAXM];
    int steps = 0;
    mq_start(sv, x, rq, rp);
    while (t < T - 1e-9 && steps < 100000) {
      double hh = fmin(h, T - t);
      ck_assert_int_eq(sv->adaptive(x, &hh, tol), 0);
      h = hh;
      sv->get(x, &t, q, p);
      steps++;
    }
    sv->reference(sv->data, 0, t, rq, rp);
    double err = distance(sv->m, 0, q, p, rq, rp);
    if (mq_table())
      printf("adaptive: %s s=%d tol %.0e: error %.2e (%.3g tol), %d steps\n", sv->model, sv->s, tol, err, err / tol,
             steps);
    /* above: the tolerance holds; below: the controller is not grossly conservative. The
     * error at T is one sample of an error that oscillates in sign, so it may sit well
     * under its size at high s (the spherical pendulum at s = 4 and tol 1e-6: 9.5e-4 tol
     * after 27 steps; the four-bar at s = 4: 1.3e-3 tol) */
    ck_assert_msg(err < 10 * tol && (err > 3e-4 * tol || err < 1e-13), "%s: tol %g, error %.3e", sv->name, tol, err);
    ck_assert_msg(err < last || err < 1e-13, "%s: the error %.3e at tol %g is not below %.3e", sv->name, err, tol, last);
    if (at_end) at_end(sv, x, tol);
    last = err;
  }
}

double mq_float_drift(const MqSolver *sv, void *x, double (*energy)(const void *x), double (*potential)(const double *q),
                      double h, int n) {
  double q[MQ_MAXM], p[MQ_MAXM], t, est, dH = 0, scale = 0;
  mq_start(sv, x, q, p);
  double H0 = energy(x);
  for (int k = 0; k < n; k++) {
    ck_assert_int_eq(sv->step(x, h, &est), 0);
    sv->get(x, &t, q, p);
    double H = energy(x), U = potential(q);
    scale = fmax(scale, fabs(H - U) + fabs(U));
    dH = fmax(dH, fabs(H - H0));
  }
  dH /= FLT_EPSILON * scale;
  if (mq_table()) printf("float: %s s=%d h=%g, %d steps: max |H - H0| %.1f float ulps of |K| + |U|\n", sv->model, sv->s, h, n, dH);
  return dH;
}
