/* ida.c - the method "ida": SUNDIALS IDA (variable order BDF, 1..5) on the
 * stabilised index-2 formulation of Gear, Gupta and Leimkuhler (GGL),
 * y = (q, p, lambda, mu):
 *
 *   q' = M^-1 (p - G(q) mu),   p' = -grad U(q) - G(q) lambda,
 *   0  = g(q),                 0  = G(q)' M^-1 p,
 *
 * with a dense direct linear solver and IDA's difference-quotient Jacobian;
 * lambda and mu are algebraic and left out of the error test (the usual
 * setting for index 2), relative tolerance tol, absolute tolerance tol on
 * q and p and ALG_ATOL on lambda and mu. The initial lambda is the index-1
 * multiplier, mu = 0, so (y, y') is consistent. Without constraints (Kepler) this is the plain
 * ODE written as an implicit DAE of index 0. The run's setup (IDA memory,
 * vectors, matrix, solver) is part of what is timed, as for the other
 * methods (ida_run.c). */
#include <math.h>
#include <stdio.h>

#include <nvector/nvector_serial.h>

#include "bench.h"
#include "ida_run.h"

#define MAXSTEPS 1000000 /* a run that needs more has failed */
/* Absolute tolerance of lambda and mu. They are outside the error test;
 * this only loosens the Newton convergence test on them, which at the
 * problem's own tolerance (index 2: their Newton corrections are amplified
 * by 1/h) failed on the first step for tol <= 1e-9 (IDA_CONV_FAIL on
 * conical, modified, satellites) and made no progress on chain8 with 1e-6;
 * 1e-3 passes at every tolerance on every problem. bench/rolled/ida_chain.c
 * uses the same. */
#define ALG_ATOL 1e-3

/* F(t, y, y') of the GGL system; user_data is the Problem. */
static int residual(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *user_data)
{
  const Problem *pb = user_data;
  const double *y = N_VGetArrayPointer(yy), *yd = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr), gu[BENCH_MAXM], G[BENCH_MAXM * BENCH_MAXNU];
  int m = pb->m, nu = pb->nu, i, a;
  const double *q = y, *p = y + m, *lam = y + 2 * m, *mu = y + 2 * m + nu;
  (void)t;
  pb->grad(q, gu);
  if (nu) {
    pb->jac(q, G);
    pb->cons(q, r + 2 * m);
  }
  for (a = 0; a < nu; a++) r[2 * m + nu + a] = 0;
  for (i = 0; i < m; i++) {
    double glam = 0, gmu = 0;
    for (a = 0; a < nu; a++) {
      glam += G[i * nu + a] * lam[a];
      gmu += G[i * nu + a] * mu[a];
      r[2 * m + nu + a] += G[i * nu + a] * pb->minv[i] * p[i];
    }
    r[i] = yd[i] - pb->minv[i] * (p[i] - gmu);
    r[m + i] = yd[m + i] + gu[i] + glam;
  }
  return isfinite(r[0]) ? 0 : 1;
}

/* Consistent y, y' at t = 0: the problem's q0, p0, the index-1 lambda, mu = 0. */
static int initial_values(const Problem *pb, double *y, double *yd, double *id)
{
  int m = pb->m, nu = pb->nu, n = 2 * m + 2 * nu, i, a;
  double gu[BENCH_MAXM], G[BENCH_MAXM * BENCH_MAXNU];
  for (i = 0; i < n; i++) {
    y[i] = yd[i] = 0;
    id[i] = i < 2 * m;
  }
  pb->init(y, y + m);
  if (problem_lambda(pb, y, y + m, y + 2 * m, gu, G) != 0) return -1;
  for (i = 0; i < m; i++) {
    double glam = 0;
    for (a = 0; a < nu; a++) glam += G[i * nu + a] * y[2 * m + a];
    yd[i] = pb->minv[i] * y[m + i];
    yd[m + i] = -gu[i] - glam;
  }
  return 0;
}

/* The observer's step: y = (q, p, ...). */
static void observe(void *ob, const double *y)
{
  observer_point(ob, y, y + ((Observer *)ob)->pb->m);
}

int ida_integrate(const Setting *set, Observer *ob, Outcome *out)
{
  const Problem *pb = set->pb;
  int m = pb->m, n = 2 * m + 2 * pb->nu, i;
  double y[2 * BENCH_MAXM + 2 * BENCH_MAXNU], yd[2 * BENCH_MAXM + 2 * BENCH_MAXNU];
  double id[2 * BENCH_MAXM + 2 * BENCH_MAXNU], atol[2 * BENCH_MAXM + 2 * BENCH_MAXNU];
  IdaSystem sys = {n, 0, residual, (void *)pb, set->tol, atol, id, ob ? observe : NULL, ob};
  if (initial_values(pb, y, yd, id) != 0) return -2;
  for (i = 0; i < n; i++) atol[i] = i < 2 * m ? set->tol : ALG_ATOL;
  if (ob) observer_start(ob, pb, y, y + m);
  if (ida_run(&sys, y, yd, set->T, MAXSTEPS, &out->steps) != 0) return -2;
  for (i = 0; i < m; i++) {
    out->q[i] = y[i];
    out->p[i] = y[m + i];
  }
  out->iters = 0;
  out->itmax = 0;
  return 0;
}
