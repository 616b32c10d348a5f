/* check_mq.c - Check suite for a mass matrix that depends on q (gen/mass_q.c,
 * gen/step_mq.c, gen/emit_mq.c), against GSL's rk8pd on the same ODE
 *   q' = M(q)^-1 p,  p' = 1/2 v' (dM/dq_i) v - grad U,  v = M(q)^-1 p,
 * written here by hand (M and dM/dq in closed form, M^-1 by GSL's LU), at
 * tolerance 1e-14, on models/double_pendulum_angles.ham (HBVM(2s+12, s),
 * s = 1..4, in float, and HBVM(4,4)), models/spherical_pendulum.ham and
 * models/arm3.ham (HBVM(18,3) and (3,3)):
 *   order     the max error over the run in (q, p) falls like h^(2s).
 *   energy    |H - H0| stays at round-off over 2000 steps (with k = 2s + 12,
 *             the rule for a non-polynomial H, and with k = s, the default: the
 *             end of the step rescales p to H0); the spherical pendulum's p_ph
 *             at round-off.
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

#include "arm3k_k3s3.h"
#include "arm_k18s3.h"
#include "dpa1_k14s1.h"
#include "dpa2_k16s2.h"
#include "dpa3_k18s3.h"
#include "dpa4_k20s4.h"
#include "dpa4k_k4s4.h"
#include "dpa_float_k16s2.h"
#include "sph_k16s2.h"

Suite *mq_suite(void);
void mq_fourbar_tests(Suite *s); /* check_mq_fourbar.c: M(q) with constraints */

#define MAXM 3

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
static void reference(const Problem *pb, double t0, double t, double *q, double *p) {
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

typedef struct {
  const char *name;
  const Problem *pb;
  int s, single;
  void (*init)(void *x, const double *q, const double *p);
  int (*step)(void *x, double h, double *est, double *defect);
  int (*adaptive)(void *x, double *h, double tol);
  double (*energy)(const void *x);
  void (*get)(const void *x, double *t, double *q, double *p);
  void (*set)(void *x, const double *q, const double *p); /* the state's q, p, the polynomials kept */
  void (*dense)(const void *x, double th, double *q, double *p);
} Solver;

#define WRAP(P)                                                                                  \
  static void P##_i(void *x, const double *q, const double *p) {                                \
    P##_real qq[MAXM], pp[MAXM];                                                                 \
    for (int i = 0; i < P##_M; i++) {                                                            \
      qq[i] = (P##_real)q[i];                                                                    \
      pp[i] = (P##_real)p[i];                                                                    \
    }                                                                                            \
    P##_init(x, qq, pp);                                                                         \
  }                                                                                              \
  static int P##_s(void *x, double h, double *est, double *defect) {                             \
    P##_stats st;                                                                                \
    int rc = P##_step(x, (P##_real)h, 0, &st);                                                   \
    *est = st.err_est;                                                                           \
    *defect = st.defect;                                                                         \
    return rc;                                                                                   \
  }                                                                                              \
  static int P##_a(void *x, double *h, double tol) {                                             \
    P##_real hh = (P##_real)*h;                                                                  \
    int rc = P##_step_adaptive(x, &hh, (P##_real)tol, 0, 0);                                     \
    *h = hh;                                                                                     \
    return rc;                                                                                   \
  }                                                                                              \
  static double P##_e(const void *x) { return P##_energy(x, 0); }                                \
  static void P##_g(const void *x, double *t, double *q, double *p) {                           \
    const P##_state *y = x;                                                                      \
    *t = y->t;                                                                                   \
    for (int i = 0; i < P##_M; i++) {                                                            \
      q[i] = y->q[i];                                                                            \
      p[i] = y->p[i];                                                                            \
    }                                                                                            \
  }                                                                                              \
  static void P##_t(void *x, const double *q, const double *p) {                                 \
    P##_state *y = x;                                                                            \
    for (int i = 0; i < P##_M; i++) {                                                            \
      y->q[i] = (P##_real)q[i];                                                                  \
      y->p[i] = (P##_real)p[i];                                                                  \
      y->qc[i] = y->pc[i] = 0;                                                                   \
    }                                                                                            \
  }                                                                                              \
  static void P##_d(const void *x, double th, double *q, double *p) {                           \
    P##_real qq[MAXM], pp[MAXM];                                                                 \
    P##_dense(x, (P##_real)th, qq, pp);                                                          \
    for (int i = 0; i < P##_M; i++) {                                                            \
      q[i] = qq[i];                                                                              \
      p[i] = pp[i];                                                                              \
    }                                                                                            \
  }
#define SOLVER(P, pb, s, single) {#P, pb, s, single, P##_i, P##_s, P##_a, P##_e, P##_g, P##_t, P##_d}

WRAP(dpa1_k14s1)
WRAP(dpa2_k16s2)
WRAP(dpa3_k18s3)
WRAP(dpa4_k20s4)
WRAP(dpa_float_k16s2)
WRAP(sph_k16s2)
WRAP(arm_k18s3)
WRAP(dpa4k_k4s4)
WRAP(arm3k_k3s3)

static const Solver solvers[] = {
    SOLVER(dpa1_k14s1, &DPA, 1, 0), SOLVER(dpa2_k16s2, &DPA, 2, 0), SOLVER(dpa3_k18s3, &DPA, 3, 0),
    SOLVER(dpa4_k20s4, &DPA, 4, 0), SOLVER(sph_k16s2, &SPH, 2, 0),  SOLVER(arm_k18s3, &ARM, 3, 0),
    SOLVER(dpa_float_k16s2, &DPA, 2, 1), SOLVER(dpa4k_k4s4, &DPA, 4, 0), SOLVER(arm3k_k3s3, &ARM, 3, 0),
};
enum { DPA1, DPA2, DPA3, DPA4, SPH2, ARM3, DPAF, DPA4K, ARM3K };

/* room for any of the states */
static union {
  double d[256];
  long double l[128];
} state;

static int table(void) {
  const char *v = getenv("HBVM_MQ_TABLE");
  return v && *v == '1';
}

// max |(q, p) - reference| over n steps of h from the model's start; the
// reference carried step by step.
static double run_error(const Solver *sv, double h, int n) {
  const Problem *pb = sv->pb;
  int m = pb->m;
  double q[MAXM], p[MAXM], rq[MAXM], rp[MAXM], t, err = 0;
  memcpy(rq, pb->q0, sizeof rq);
  memcpy(rp, pb->p0, sizeof rp);
  sv->init(&state, pb->q0, pb->p0);
  for (int k = 1; k <= n; k++) {
    double est, defect;
    ck_assert_int_eq(sv->step(&state, h, &est, &defect), 0);
    reference(pb, (k - 1) * h, k * h, rq, rp);
    sv->get(&state, &t, q, p);
    for (int i = 0; i < m; i++) err = fmax(err, fmax(fabs(q[i] - rq[i]), fabs(p[i] - rp[i])));
  }
  return err;
}

/* ---- order ---- */

static const struct {
  int solver;
  double h, T;
} order_cases[] = {
    {DPA1, 0.05, 5}, {DPA2, 0.1, 5},  {DPA3, 0.1, 5},  {DPA4, 0.2, 5},
    {SPH2, 0.1, 5},  {ARM3, 0.1, 3},  {DPA4K, 0.2, 5}, {ARM3K, 0.1, 3},
};

// The max error over the run at h and h/2: its rate is 2s (within 0.3 below,
// 0.6 above: the rate of a max over a run scatters a little).
START_TEST(order_2s) {
  const Solver *sv = &solvers[order_cases[_i].solver];
  double h = order_cases[_i].h, T = order_cases[_i].T;
  double e1 = run_error(sv, h, (int)lround(T / h)), e2 = run_error(sv, h / 2, (int)lround(2 * T / h));
  double rate = log2(e1 / e2);
  if (table()) printf("order: %s s=%d h=%g: %.3e, h/2: %.3e, rate %.2f\n", sv->pb->name, sv->s, h, e1, e2, rate);
  ck_assert_msg(e2 > 1e-13, "%s: the error %.3e at h/2 is at round-off: take a larger h", sv->name, e2);
  ck_assert_msg(rate > 2 * sv->s - 0.3 && rate < 2 * sv->s + 0.6, "%s: rate %.2f, want %d (%.3e -> %.3e)", sv->name,
                rate, 2 * sv->s, e1, e2);
}
END_TEST

/* ---- energy at round-off ---- */

static const struct {
  int solver;
  double h;
} energy_cases[] = {{DPA1, 0.02}, {DPA2, 0.05}, {DPA3, 0.1},   {DPA4, 0.2},
                    {SPH2, 0.05}, {ARM3, 0.05}, {DPA4K, 0.2}, {ARM3K, 0.1}};

// 2000 steps: |H - H0| within 64 ulps of |K| + |U| at the start (a random
// walk of the iteration's 2-ulp stop and the compensated sums' last bits),
// where an inexact quadrature without the rescale would show (k = s = 4:
// 2.1e-11 in 100 steps of h = 0.1, docs/method-mq.md). The spherical
// pendulum's p_ph (its force is 0) within 256 ulps: only the rescale touches
// it, by an ulp or so a step, a random walk (65 ulps measured at the end).
START_TEST(energy_roundoff) {
  const Solver *sv = &solvers[energy_cases[_i].solver];
  double h = energy_cases[_i].h, dH = 0, q[MAXM], p[MAXM], t, est, defect;
  sv->init(&state, sv->pb->q0, sv->pb->p0);
  double H0 = sv->energy(&state), U0 = sv->pb->potential_grad(sv->pb->q0, q);
  double scale = fabs(H0 - U0) + fabs(U0), pph0 = sv->pb->p0[1];
  for (int n = 0; n < 2000; n++) {
    ck_assert_int_eq(sv->step(&state, h, &est, &defect), 0);
    dH = fmax(dH, fabs(sv->energy(&state) - H0));
    if (sv->pb == &SPH) {
      sv->get(&state, &t, q, p);
      ck_assert_msg(fabs(p[1] - pph0) <= 256 * DBL_EPSILON * pph0, "the spherical pendulum's p_ph changed: %.17g", p[1]);
    }
  }
  if (table()) printf("energy: %s s=%d h=%g: max |H - H0| = %.2e (%.1f ulps of |K| + |U| = %.3g)\n", sv->pb->name,
                      sv->s, h, dH, dH / (DBL_EPSILON * scale), scale);
  ck_assert_msg(dH <= 64 * DBL_EPSILON * scale, "%s: |H - H0| = %.3e", sv->name, dH);
}
END_TEST

// In float: H within 64 float ulps, and the solution within 1e-4 of the
// reference at T = 5 (the error of double at this h is 5e-7).
START_TEST(float_holds) {
  const Solver *sv = &solvers[DPAF];
  double h = 0.05, est, defect, dH = 0;
  sv->init(&state, sv->pb->q0, sv->pb->p0);
  double H0 = sv->energy(&state);
  for (int n = 0; n < 100; n++) {
    ck_assert_int_eq(sv->step(&state, h, &est, &defect), 0);
    dH = fmax(dH, fabs(sv->energy(&state) - H0));
  }
  if (table()) printf("float: max |H - H0| = %.2e\n", dH);
  ck_assert_msg(dH <= 64 * FLT_EPSILON * 4, "float: |H - H0| = %.3e", dH);
  ck_assert_msg(run_error(sv, h, 100) < 1e-4, "float: the solution strays");
}
END_TEST

/* ---- the error estimate, adaptive steps, dense output ---- */

// From the reference at t_k: a first step (for the warm start), the state
// put back on the reference at t_{k+1}, the step measured from there
// against the reference at t_{k+2}: true / estimate in geometric mean
// within [1/10, 10], over the steps whose true error is above round-off.
static const struct {
  int solver;
  double h;
} errest_cases[] = {{DPA2, 0.1}, {DPA3, 0.2}, {DPA4, 0.4}, {ARM3, 0.1}, {DPA4K, 0.4}};

START_TEST(errest_tracks) {
  const Solver *sv = &solvers[errest_cases[_i].solver];
  const Problem *pb = sv->pb;
  double h = errest_cases[_i].h, rq[MAXM], rp[MAXM], q[MAXM], p[MAXM], t, lsum = 0, lo = HUGE_VAL, hi = 0;
  int m = pb->m, n = 0;
  memcpy(rq, pb->q0, sizeof rq);
  memcpy(rp, pb->p0, sizeof rp);
  for (int k = 0; k < 30; k++) {
    double est, defect, nq[MAXM], np[MAXM];
    sv->init(&state, rq, rp);
    ck_assert_int_eq(sv->step(&state, h, &est, &defect), 0);
    reference(pb, k * h, (k + 1) * h, rq, rp);
    sv->set(&state, rq, rp);
    ck_assert_int_eq(sv->step(&state, h, &est, &defect), 0);
    sv->get(&state, &t, q, p);
    memcpy(nq, rq, sizeof nq);
    memcpy(np, rp, sizeof np);
    reference(pb, (k + 1) * h, (k + 2) * h, nq, np);
    double err = 0;
    for (int i = 0; i < m; i++) err = fmax(err, fabs(q[i] - nq[i]));
    if (err < 1e-14) continue;
    double r = err / est;
    lsum += log(r);
    lo = fmin(lo, r);
    hi = fmax(hi, r);
    n++;
  }
  ck_assert_int_gt(n, 10);
  double mean = exp(lsum / n);
  if (table()) printf("errest: %s s=%d h=%g: true/estimate mean %.2f, range [%.2f, %.2f], %d steps\n", pb->name, sv->s, h,
                      mean, lo, hi, n);
  ck_assert_msg(mean > 0.1 && mean < 10, "%s: true / estimate %.3g in geometric mean", sv->name, mean);
}
END_TEST

// NAME_step_adaptive to T = 5 at tol = 1e-6, 1e-8, 1e-10: the global error
// within [1e-3, 10] tol (measured: docs/method-mq.md) and falling with tol.
START_TEST(adaptive_follows_tolerance) {
  static const int which[] = {DPA2, DPA3, DPA4, ARM3, DPA4K, ARM3K};
  const Solver *sv = &solvers[which[_i]];
  const Problem *pb = sv->pb;
  double last = HUGE_VAL;
  for (double tol = 1e-6; tol > 1e-11; tol /= 100) {
    double h = 0.01, t = 0, q[MAXM], p[MAXM], rq[MAXM], rp[MAXM], err = 0;
    int steps = 0;
    sv->init(&state, pb->q0, pb->p0);
    while (t < 5 - 1e-9 && steps < 100000) { /* (the last step ends at 5 to round-off) */
      double hh = fmin(h, 5 - t);
      ck_assert_int_eq(sv->adaptive(&state, &hh, tol), 0);
      h = hh;
      sv->get(&state, &t, q, p);
      steps++;
    }
    memcpy(rq, pb->q0, sizeof rq);
    memcpy(rp, pb->p0, sizeof rp);
    reference(pb, 0, t, rq, rp);
    for (int i = 0; i < pb->m; i++) err = fmax(err, fmax(fabs(q[i] - rq[i]), fabs(p[i] - rp[i])));
    if (table()) printf("adaptive: %s s=%d tol %.0e: error %.2e (%.3g tol), %d steps\n", pb->name, sv->s, tol, err,
                        err / tol, steps);
    ck_assert_msg(err < 10 * tol && (err > 1e-3 * tol || err < 1e-13), "%s: tol %g, error %.3e", sv->name, tol, err);
    ck_assert_msg(err < last || err < 1e-13, "%s: the error %.3e at tol %g is not below %.3e", sv->name, err, tol, last);
    last = err;
  }
}
END_TEST

// NAME_dense at theta = 1/4, 1/2, 3/4 of steps of h against the reference:
// an error of order at least s + 1 (h^(s+1) at most, with constant 1).
START_TEST(dense_inside_step) {
  static const int which[] = {DPA2, DPA3, ARM3};
  const Solver *sv = &solvers[which[_i]];
  const Problem *pb = sv->pb;
  double h = 0.05, rq[MAXM], rp[MAXM], q[MAXM], p[MAXM], err = 0;
  sv->init(&state, pb->q0, pb->p0);
  for (int k = 0; k < 20; k++) {
    double est, defect;
    ck_assert_int_eq(sv->step(&state, h, &est, &defect), 0);
    for (int j = 1; j <= 3; j++) {
      sv->dense(&state, j / 4.0, q, p);
      memcpy(rq, pb->q0, sizeof rq);
      memcpy(rp, pb->p0, sizeof rp);
      reference(pb, 0, (k + j / 4.0) * h, rq, rp);
      for (int i = 0; i < pb->m; i++) err = fmax(err, fmax(fabs(q[i] - rq[i]), fabs(p[i] - rp[i])));
    }
  }
  if (table()) printf("dense: %s s=%d h=%g: max error %.2e\n", pb->name, sv->s, h, err);
  ck_assert_msg(err < pow(h, sv->s + 1), "%s: dense error %.3e", sv->name, err);
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
  tcase_add_loop_test(tc, errest_tracks, 0, (int)(sizeof errest_cases / sizeof errest_cases[0]));
  tcase_add_loop_test(tc, adaptive_follows_tolerance, 0, 6);
  tcase_add_loop_test(tc, dense_inside_step, 0, 3);
  tcase_add_test(tc, check_reports_dependence);
  suite_add_tcase(s, tc);
  mq_fourbar_tests(s);
  return s;
}
