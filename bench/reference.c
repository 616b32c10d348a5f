/* reference.c - reference solutions at the final time.
 *
 *   kepler      exact: whole periods bring the orbit back to (q0, p0)
 *   conical     exact: uniform circular motion (tests/ref.c, closed form)
 *   pendulum    tests/ref.c: theta'' = -sin theta by GSL rk8pd
 *   double_pendulum  tests/ref.c: the equations of the rod angles by GSL
 *               rk8pd
 *   modified,   tests/ref.c: the index-1 formulation by GSL rk8pd (the
 *   satellites  satellites' state as q - q0)
 *   chain8      here: the index-1 formulation by GSL rk8pd, with the
 *               hand-coded gradient, Jacobian and contracted Hessians of
 *               problems.c
 *
 * tests/ref.c is compiled into the benchmark as it is (not copied). The
 * index-1 integrator below is run on every problem by `bench refcheck`,
 * to check it (and problems.c) against tests/ref.c. */
#include "reference.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include "ref.h"
#include "stiff.h"

/* q' = M^-1 p, p' = -grad U - G lambda(q, p), y = (q, p); params: Problem. */
static int index1_rhs(double t, const double y[], double f[], void *params)
{
  const Problem *pb = params;
  double lambda[BENCH_MAXNU], gu[BENCH_MAXM], G[BENCH_MAXM * BENCH_MAXNU];
  int m = pb->m, nu = pb->nu, i, a;
  (void)t;
  if (problem_lambda(pb, y, y + m, lambda, gu, G) != 0) return GSL_EBADFUNC;
  for (i = 0; i < m; i++) {
    double acc = gu[i];
    for (a = 0; a < nu; a++) acc += G[i * nu + a] * lambda[a];
    f[i] = pb->minv[i] * y[m + i];
    f[m + i] = -acc;
  }
  return GSL_SUCCESS;
}

int reference_index1(const Problem *pb, double T, double tol, double *q, double *p, double *dg, double *dH)
{
  gsl_odeiv2_system sys;
  gsl_odeiv2_step *st;
  gsl_odeiv2_control *con;
  gsl_odeiv2_evolve *ev;
  Observer ob;
  double y[2 * BENCH_MAXM], t = 0, h = 1e-4;
  int m = pb->m, rc = 0;
  sys.function = index1_rhs;
  sys.jacobian = NULL;
  sys.dimension = (size_t)(2 * m);
  sys.params = (void *)pb;
  st = gsl_odeiv2_step_alloc(gsl_odeiv2_step_rk8pd, sys.dimension);
  con = gsl_odeiv2_control_y_new(tol, tol);
  ev = gsl_odeiv2_evolve_alloc(sys.dimension);
  pb->init(y, y + m);
  observer_start(&ob, pb, y, y + m);
  while (t < T && rc == 0) {
    if (gsl_odeiv2_evolve_apply(ev, con, st, &sys, &t, T, &h, y) != GSL_SUCCESS) rc = -2;
    observer_point(&ob, y, y + m);
  }
  memcpy(q, y, (size_t)m * sizeof *q);
  memcpy(p, y + m, (size_t)m * sizeof *p);
  if (dg) *dg = ob.dg;
  if (dH) *dH = ob.dH;
  gsl_odeiv2_evolve_free(ev);
  gsl_odeiv2_control_free(con);
  gsl_odeiv2_step_free(st);
  return rc;
}

int reference_final(const Problem *pb, double T, double tol, double *q, double *p, char *how, int n)
{
  double qq[2 * BENCH_MAXM], pp[2 * BENCH_MAXM], ll[2 * BENCH_MAXNU]; /* t = 0 and t = T */
  int m = pb->m;
  if (strncmp(pb->name, "kepler", 6) == 0) {
    double periods = T / (2 * 3.14159265358979323846);
    if (fabs(periods - floor(periods + 0.5)) > 1e-12) return -1;
    pb->init(q, p);
    snprintf(how, (size_t)n, "exact: (q0, p0) after %.0f whole periods", periods);
    return 0;
  }
  if (strcmp(pb->name, "chain8") == 0 || stiff_find(pb)) {
    double dg, dH;
    int rc = reference_index1(pb, T, tol, q, p, &dg, &dH);
    snprintf(how, (size_t)n, "index-1 formulation, GSL rk8pd, tol %g (bench/reference.c): max|g| %.2e, max|H-H0| %.2e",
             tol, dg, dH);
    return rc;
  }
  if (strcmp(pb->name, "conical") == 0)
    snprintf(how, (size_t)n, "exact: uniform circular motion (tests/ref.c)");
  else if (strcmp(pb->name, "pendulum") == 0)
    snprintf(how, (size_t)n, "theta'' = -sin theta, GSL rk8pd, tol %g (tests/ref.c)", tol);
  else if (strcmp(pb->name, "double_pendulum") == 0)
    snprintf(how, (size_t)n, "rod angles' Euler-Lagrange equations, GSL rk8pd, tol %g (tests/ref.c)", tol);
  else
    snprintf(how, (size_t)n, "index-1 formulation, GSL rk8pd, tol %g (tests/ref.c)", tol);
  if (ref_solve_tol(pb->name, T, 1, tol, qq, pp, ll) != 0) return -2;
  memcpy(q, qq + m, (size_t)m * sizeof *q);
  memcpy(p, pp + m, (size_t)m * sizeof *p);
  return 0;
}
