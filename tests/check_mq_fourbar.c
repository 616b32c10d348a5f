/* check_mq_fourbar.c - M(q) with constraints (suite mq): the four-bar
 * linkage of models/fourbar_angles.ham (three absolute angles, two
 * loop-closure constraints, M depends on th1 - th2), HBVM(s,s) for s = 1..4,
 * against GSL's rk8pd at 1e-14 on its index-1 ODE in the same angles,
 *   q' = v = M(q)^-1 p,  p' = -grad_q T - grad U - G lambda,
 *   (G' M^-1 G) lambda = [v' Hess(g_a) v]_a - G' M^-1 (grad_q T + grad U + Mdot v),
 * written here by hand (G = grad g; the last line is d/dt G' v = 0):
 *   order     the max error over the run in (q, p) falls like h^(2s).
 *   invariant H, g and the hidden constraint G' M^-1 p at round-off over
 *             2000 steps.
 *   errest    NAME_stats.err_est against the true local error of a step
 *             started on the reference.
 *   adaptive  NAME_step_adaptive's global error follows the tolerance.
 *   project   NAME_project puts a state moved off the constraints back on
 *             them, the changes of q and p in the M(q) norm: M dq and dp in
 *             the range of G.
 * HBVM_MQ_TABLE=1 prints the measured figures (docs/method-mq.md). The
 * tests join suite mq through mq_fourbar_tests (check_mq.c). */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_odeiv2.h>

#include "fb1_k1s1.h"
#include "fb2_k2s2.h"
#include "fb3_k3s3.h"
#include "fb4_k4s4.h"

#include "../bench/mq/fourbar_ode.h"

void mq_fourbar_tests(Suite *s);

// The reference at t from (q, p) at t0: rk8pd at 1e-14, in place.
static void reference(double t0, double t, double *q, double *p) {
  gsl_odeiv2_system sys = {fourbar_rhs, NULL, 6, NULL};
  gsl_odeiv2_driver *dr = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-4, 1e-14, 1e-14);
  double y[6];
  memcpy(y, q, 3 * sizeof *y);
  memcpy(y + 3, p, 3 * sizeof *y);
  ck_assert_int_eq(gsl_odeiv2_driver_apply(dr, &t0, t, y), GSL_SUCCESS);
  gsl_odeiv2_driver_free(dr);
  memcpy(q, y, 3 * sizeof *y);
  memcpy(p, y + 3, 3 * sizeof *y);
}

/* ---- the generated solvers behind one interface ---- */

typedef struct {
  const char *name;
  int s;
  void (*init)(void *x, const double *q, const double *p); /* NULL q: the model's */
  int (*step)(void *x, double h, double *est);
  int (*adaptive)(void *x, double *h, double tol);
  void (*get)(const void *x, double *t, double *q, double *p, double *H, double *g, double *hidden);
  int (*project)(void *x);
  void (*set)(void *x, const double *q, const double *p); /* the state's q, p, the polynomials kept */
  void (*lambda)(const void *x, double *lam);
} Solver;

#define WRAP(P)                                                                                           \
  static void P##_i(void *x, const double *q, const double *p) { P##_init(x, q, p); }                     \
  static int P##_s(void *x, double h, double *est) {                                                      \
    P##_stats st;                                                                                         \
    int rc = P##_step(x, h, 0, &st);                                                                      \
    *est = st.err_est;                                                                                    \
    return rc;                                                                                            \
  }                                                                                                       \
  static int P##_a(void *x, double *h, double tol) { return P##_step_adaptive(x, h, tol, 0, 0); }         \
  static void P##_g(const void *x, double *t, double *q, double *p, double *H, double *g, double *hid) { \
    const P##_state *y = x;                                                                               \
    *t = y->t;                                                                                            \
    memcpy(q, y->q, 3 * sizeof *q);                                                                       \
    memcpy(p, y->p, 3 * sizeof *p);                                                                       \
    *H = P##_energy(x, 0);                                                                                \
    P##_constraints(x, 0, g);                                                                             \
    P##_hidden(x, 0, hid);                                                                                \
  }                                                                                                       \
  static int P##_pr(void *x) { return P##_project(x, 0, 0, 0); }                                         \
  static void P##_t(void *x, const double *q, const double *p) {                                          \
    P##_state *y = x;                                                                                     \
    memcpy(y->q, q, 3 * sizeof *q);                                                                       \
    memcpy(y->p, p, 3 * sizeof *p);                                                                       \
    memset(y->qc, 0, sizeof y->qc);                                                                       \
    memset(y->pc, 0, sizeof y->pc);                                                                       \
  }                                                                                                       \
  static void P##_l(const void *x, double *lam) { memcpy(lam, ((const P##_state *)x)->lambda, 2 * sizeof *lam); }
#define SOLVER(P, s) {#P, s, P##_i, P##_s, P##_a, P##_g, P##_pr, P##_t, P##_l}

WRAP(fb1_k1s1)
WRAP(fb2_k2s2)
WRAP(fb3_k3s3)
WRAP(fb4_k4s4)

static const Solver solvers[] = {SOLVER(fb1_k1s1, 1), SOLVER(fb2_k2s2, 2), SOLVER(fb3_k3s3, 3), SOLVER(fb4_k4s4, 4)};

static union {
  double d[512];
  long double l[256];
} state;

static int table(void) {
  const char *v = getenv("HBVM_MQ_TABLE");
  return v && *v == '1';
}

// The model's start (q0 from the loop closure at th1 = 1.2, at rest).
static void start(const Solver *sv, double *q, double *p) {
  double t, H, g[2], hid[2];
  sv->init(&state, NULL, NULL);
  sv->get(&state, &t, q, p, &H, g, hid);
}

// max |(q, p) - reference| over n steps of h from the model's start.
static double run_error(const Solver *sv, double h, int n) {
  double q[3], p[3], rq[3], rp[3], t, H, g[2], hid[2], err = 0, est;
  start(sv, rq, rp);
  for (int k = 1; k <= n; k++) {
    ck_assert_int_eq(sv->step(&state, h, &est), 0);
    reference((k - 1) * h, k * h, rq, rp);
    sv->get(&state, &t, q, p, &H, g, hid);
    for (int i = 0; i < 3; i++) err = fmax(err, fmax(fabs(q[i] - rq[i]), fabs(p[i] - rp[i])));
  }
  return err;
}

/* ---- order ---- */

static const struct {
  int s;
  double h, T;
} order_cases[] = {{1, 0.02, 4}, {2, 0.05, 4}, {3, 0.05, 4}, {4, 0.1, 4}};

// The max error over the run at h and h/2: its rate is 2s (within 0.3
// below, 0.6 above, as for the unconstrained models).
START_TEST(fourbar_order_2s) {
  const Solver *sv = &solvers[order_cases[_i].s - 1];
  double h = order_cases[_i].h, T = order_cases[_i].T;
  double e1 = run_error(sv, h, (int)lround(T / h)), e2 = run_error(sv, h / 2, (int)lround(2 * T / h));
  double rate = log2(e1 / e2);
  if (table()) printf("order: four-bar s=%d h=%g: %.3e, h/2: %.3e, rate %.2f\n", sv->s, h, e1, e2, rate);
  ck_assert_msg(e2 > 1e-13, "%s: the error %.3e at h/2 is at round-off: take a larger h", sv->name, e2);
  ck_assert_msg(rate > 2 * sv->s - 0.3 && rate < 2 * sv->s + 0.6, "%s: rate %.2f, want %d (%.3e -> %.3e)", sv->name,
                rate, 2 * sv->s, e1, e2);
}
END_TEST

/* ---- H, g and the hidden constraint ---- */

static const struct {
  int s;
  double h;
} inv_cases[] = {{1, 0.02}, {2, 0.05}, {3, 0.1}, {4, 0.2}};

// 2000 steps: |H - H0| within 64 ulps of |K| + |U| at its largest, |g|
// within 16 ulps of the loop's size l0 + l1 + l2 + l3, the hidden
// constraint within 64 ulps of it times max |v|.
START_TEST(fourbar_invariants) {
  const Solver *sv = &solvers[inv_cases[_i].s - 1];
  double h = inv_cases[_i].h, q[3], p[3], t, H, H0, g[2], hid[2], est, dH = 0, dg = 0, dhid = 0, dlam = 0, vmax = 0, Hs = 0;
  double size = L0 + L1 + L2 + L3;
  start(sv, q, p);
  sv->get(&state, &t, q, p, &H0, g, hid);
  for (int n = 0; n < 2000; n++) {
    ck_assert_int_eq(sv->step(&state, h, &est), 0);
    sv->get(&state, &t, q, p, &H, g, hid);
    double U = energy(q, (double[3]){0, 0, 0}), v[3];
    Terms tm;
    terms(q, q, &tm);
    msolve(tm.M, p, v);
    Hs = fmax(Hs, fabs(H - U) + fabs(U));
    for (int i = 0; i < 3; i++) vmax = fmax(vmax, fabs(v[i]));
    dH = fmax(dH, fabs(H - H0));
    double lam[2], want[2], f[3];
    sv->lambda(&state, lam);
    multiplier(q, p, want, f, &tm);
    for (int a = 0; a < 2; a++) {
      dg = fmax(dg, fabs(g[a]));
      dhid = fmax(dhid, fabs(hid[a]));
      dlam = fmax(dlam, fabs(lam[a] - want[a]));
    }
  }
  if (table())
    printf("invariants: four-bar s=%d h=%g: max |H - H0| %.2e (%.1f ulps), |g| %.2e (%.1f ulps), hidden %.2e (%.1f ulps), "
           "lambda %.1e\n", sv->s, h, dH, dH / (DBL_EPSILON * Hs), dg, dg / (DBL_EPSILON * size), dhid,
           dhid / (DBL_EPSILON * size * vmax), dlam);
  ck_assert_msg(dH <= 64 * DBL_EPSILON * Hs, "%s: |H - H0| = %.3e", sv->name, dH);
  ck_assert_msg(dg <= 16 * DBL_EPSILON * size, "%s: |g| = %.3e", sv->name, dg);
  ck_assert_msg(dhid <= 64 * DBL_EPSILON * size * vmax, "%s: hidden constraint %.3e", sv->name, dhid);
  ck_assert_msg(dlam <= 1e-12, "%s: lambda %.3e from the multiplier consistent with (q, p)", sv->name, dlam);
}
END_TEST

/* ---- the error estimate and adaptive steps ---- */

static const struct {
  int s;
  double h;
} errest_cases[] = {{2, 0.1}, {3, 0.2}, {4, 0.3}};

// From the reference at t_k: a first step (the warm start), the state put
// back on the reference at t_{k+1} by NAME_init, the step measured from
// there against the reference at t_{k+2}: true / estimate in geometric mean
// within [1/10, 10].
START_TEST(fourbar_errest_tracks) {
  const Solver *sv = &solvers[errest_cases[_i].s - 1];
  double h = errest_cases[_i].h, rq[3], rp[3], q[3], p[3], t, H, g[2], hid[2], lsum = 0, lo = HUGE_VAL, hi = 0;
  int n = 0;
  start(sv, rq, rp);
  for (int k = 0; k < 30; k++) {
    double est, nq[3], np[3], err = 0;
    sv->init(&state, rq, rp);
    ck_assert_int_eq(sv->step(&state, h, &est), 0);
    reference(k * h, (k + 1) * h, rq, rp);
    sv->set(&state, rq, rp);
    ck_assert_int_eq(sv->step(&state, h, &est), 0);
    sv->get(&state, &t, q, p, &H, g, hid);
    memcpy(nq, rq, sizeof nq);
    memcpy(np, rp, sizeof np);
    reference((k + 1) * h, (k + 2) * h, nq, np);
    for (int i = 0; i < 3; i++) err = fmax(err, fabs(q[i] - nq[i]));
    if (err < 1e-14) continue;
    double r = err / est;
    lsum += log(r);
    lo = fmin(lo, r);
    hi = fmax(hi, r);
    n++;
  }
  ck_assert_int_gt(n, 10);
  double mean = exp(lsum / n);
  if (table())
    printf("errest: four-bar s=%d h=%g: true/estimate mean %.2f, range [%.2f, %.2f], %d steps\n", sv->s, h, mean, lo,
           hi, n);
  ck_assert_msg(mean > 0.1 && mean < 10, "%s: true / estimate %.3g in geometric mean", sv->name, mean);
}
END_TEST

// NAME_step_adaptive to T = 4 at tol = 1e-6, 1e-8, 1e-10: the global error
// within [1e-3, 10] tol and falling with tol; g and the hidden constraint at
// round-off at the end (the iteration may stop at the tolerance: the end of
// the step restores them).
START_TEST(fourbar_adaptive_follows_tolerance) {
  const Solver *sv = &solvers[_i + 1];
  double last = HUGE_VAL;
  for (double tol = 1e-6; tol > 1e-11; tol /= 100) {
    double h = 0.01, t = 0, q[3], p[3], rq[3], rp[3], H, g[2], hid[2], err = 0;
    int steps = 0;
    start(sv, rq, rp);
    while (t < 4 - 1e-9 && steps < 100000) {
      double hh = fmin(h, 4 - t);
      ck_assert_int_eq(sv->adaptive(&state, &hh, tol), 0);
      h = hh;
      sv->get(&state, &t, q, p, &H, g, hid);
      steps++;
    }
    reference(0, t, rq, rp);
    for (int i = 0; i < 3; i++) err = fmax(err, fmax(fabs(q[i] - rq[i]), fabs(p[i] - rp[i])));
    if (table())
      printf("adaptive: four-bar s=%d tol %.0e: error %.2e (%.3g tol), %d steps, |g| %.1e, hidden %.1e\n", sv->s, tol,
             err, err / tol, steps, fmax(fabs(g[0]), fabs(g[1])), fmax(fabs(hid[0]), fabs(hid[1])));
    ck_assert_msg(err < 10 * tol && (err > 1e-3 * tol || err < 1e-13), "%s: tol %g, error %.3e", sv->name, tol, err);
    ck_assert_msg(err < last || err < 1e-13, "%s: the error %.3e at tol %g is not below %.3e", sv->name, err, tol, last);
    for (int a = 0; a < 2; a++) {
      ck_assert_msg(fabs(g[a]) <= 16 * DBL_EPSILON * (L0 + L1 + L2 + L3), "%s: tol %g: g %.3e", sv->name, tol, g[a]);
      ck_assert_msg(fabs(hid[a]) <= 1e-13, "%s: tol %g: hidden constraint %.3e", sv->name, tol, hid[a]);
    }
    last = err;
  }
}
END_TEST

/* ---- the projection ---- */

// The model's start moved off the constraints by 1e-6 in q and 1e-3 in p,
// then NAME_project: g and the hidden constraint at round-off, and the
// changes in the M(q) norm: M(q) dq (Newton steps, each -G y: to the
// square of the change) and dp (-G mu, exactly) in the range of G at the
// new q. A projection in another norm (M = I: 1e-1 off the range here)
// fails the first.
START_TEST(fourbar_project_in_mq_norm) {
  const Solver *sv = &solvers[1];
  double q0[3], p0[3], q[3], p[3], t, H, g[2], hid[2];
  start(sv, q0, p0);
  double dq0[3] = {3e-7, -5e-7, 8e-7}, dp0[3] = {1e-3, 2e-3, -1e-3};
  for (int i = 0; i < 3; i++) {
    q0[i] += dq0[i];
    p0[i] += dp0[i];
  }
  sv->init(&state, q0, p0);
  ck_assert_int_eq(sv->project(&state), 0);
  sv->get(&state, &t, q, p, &H, g, hid);
  Terms tm;
  terms(q, q, &tm);
  double Mdq[3], dp[3], off[2];
  for (int i = 0; i < 3; i++) {
    Mdq[i] = 0;
    for (int j = 0; j < 3; j++) Mdq[i] += tm.M[i * 3 + j] * (q[j] - q0[j]);
    dp[i] = p[i] - p0[i];
  }
  /* the part of w outside the range of G: w minus its least-squares fit G c,
   * relative to |w| */
  double *w[2] = {Mdq, dp};
  for (int r = 0; r < 2; r++) {
    double A[4] = {0}, b[2] = {0}, c[2], res = 0, nw = 0;
    for (int a = 0; a < 2; a++) {
      for (int i = 0; i < 3; i++) b[a] += tm.G[a][i] * w[r][i];
      for (int e = 0; e < 2; e++)
        for (int i = 0; i < 3; i++) A[a * 2 + e] += tm.G[a][i] * tm.G[e][i];
    }
    double det = A[0] * A[3] - A[1] * A[2];
    c[0] = (A[3] * b[0] - A[1] * b[1]) / det;
    c[1] = (A[0] * b[1] - A[2] * b[0]) / det;
    for (int i = 0; i < 3; i++) {
      res = fmax(res, fabs(w[r][i] - tm.G[0][i] * c[0] - tm.G[1][i] * c[1]));
      nw = fmax(nw, fabs(w[r][i]));
    }
    off[r] = res / nw;
  }
  if (table())
    printf("project: four-bar: |g| %.1e, hidden %.1e; M dq off the range of G %.1e, dp %.1e (relative)\n",
           fmax(fabs(g[0]), fabs(g[1])), fmax(fabs(hid[0]), fabs(hid[1])), off[0], off[1]);
  for (int a = 0; a < 2; a++) {
    ck_assert_msg(fabs(g[a]) <= 16 * DBL_EPSILON * (L0 + L1 + L2 + L3), "g %.3e", g[a]);
    ck_assert_msg(fabs(hid[a]) <= 1e-15, "hidden constraint %.3e", hid[a]);
  }
  ck_assert_msg(off[0] < 1e-5, "M dq is %.3e off the range of G", off[0]);
  ck_assert_msg(off[1] < 1e-10, "dp is %.3e off the range of G", off[1]);
}
END_TEST

void mq_fourbar_tests(Suite *s) {
  TCase *tc = tcase_create("fourbar");
  tcase_set_timeout(tc, 120);
  tcase_add_loop_test(tc, fourbar_order_2s, 0, (int)(sizeof order_cases / sizeof order_cases[0]));
  tcase_add_loop_test(tc, fourbar_invariants, 0, (int)(sizeof inv_cases / sizeof inv_cases[0]));
  tcase_add_loop_test(tc, fourbar_errest_tracks, 0, (int)(sizeof errest_cases / sizeof errest_cases[0]));
  tcase_add_loop_test(tc, fourbar_adaptive_follows_tolerance, 0, 3);
  tcase_add_test(tc, fourbar_project_in_mq_norm);
  suite_add_tcase(s, tc);
}
