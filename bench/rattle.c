/* rattle.c - the method "rattle": the standard RATTLE scheme (second order,
 * symplectic, constraints and hidden constraints held at every step):
 *
 *   p~  = p0 - h/2 (grad U(q0) + G(q0) lambda)
 *   q1  = q0 + h M^-1 p~,         g(q1) = 0            (lambda: Newton)
 *   p1  = p~ - h/2 (grad U(q1) + G(q1) mu),  G(q1)' M^-1 p1 = 0   (mu: linear)
 *
 * The position constraints are solved by Newton's method on lambda with the
 * exact Jacobian -h^2/2 G(q1)' M^-1 G(q0), re-evaluated each iteration,
 * from the previous step's lambda, until the correction of q1 reaches 2
 * ulps or stops decreasing (as the HBVM iteration stops). grad U(q1) and
 * G(q1) are kept for the next step, so a step costs one gradient and
 * (iterations + 1) Jacobians. Without constraints this is Stormer-Verlet. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "linalg.h"

#define MAXITER 50
#define TOL 4.4408920985006262e-16

typedef struct {
  const Problem *pb;
  double q[BENCH_MAXM], p[BENCH_MAXM], gu[BENCH_MAXM], G[BENCH_MAXM * BENCH_MAXNU], lambda[BENCH_MAXNU];
} Rattle;

/* y = x - f W G lam for m-vectors x, y (y may be x), W = diag(w) or the
 * identity when w is NULL. */
static void sub_glam(const Problem *pb, const double *G, const double *lam, double f, const double *w,
                     const double *x, double *y)
{
  int m = pb->m, nu = pb->nu, i, a;
  for (i = 0; i < m; i++) {
    double acc = 0;
    for (a = 0; a < nu; a++) acc += G[i * nu + a] * lam[a];
    y[i] = x[i] - f * (w ? w[i] : 1) * acc;
  }
}

/* Solve g(qt - h^2/2 M^-1 G0 lambda) = 0 for lambda (in/out, the start
 * value on entry) by Newton; q1 is the resulting position. Returns the
 * number of iterations, or -1 on failure. */
static int solve_positions(const Problem *pb, const double *qt, const double *G0, double h, double *lambda,
                           double *q1)
{
  int m = pb->m, nu = pb->nu, it, a;
  double f = 0.5 * h * h, inc = HUGE_VAL, inc_old;
  double g[BENCH_MAXNU], G1[BENCH_MAXM * BENCH_MAXNU], J[BENCH_MAXNU * BENCH_MAXNU], dq[BENCH_MAXM];
  for (it = 1; it <= MAXITER; it++) {
    sub_glam(pb, G0, lambda, f, pb->minv, qt, q1);
    pb->cons(q1, g);
    pb->jac(q1, G1);
    gram(m, nu, nu, G1, nu, pb->minv, G0, nu, J); /* dg/dlambda = -f J */
    if (dense_solve(nu, J, g) != 0) return -1;    /* g <- J^-1 g: the Newton correction / f */
    for (a = 0; a < nu; a++) lambda[a] += g[a] / f;
    sub_glam(pb, G0, g, 1, pb->minv, qt, dq); /* qt - dq: the correction of q1 */
    inc_old = inc;
    inc = maxdiff(m, dq, qt) / fmax(maxabs(m, q1), 1e-300);
    if (!isfinite(inc)) return -1;
    if (inc <= TOL || (it > 1 && inc >= inc_old)) break;
  }
  sub_glam(pb, G0, lambda, f, pb->minv, qt, q1);
  return it > MAXITER ? MAXITER : it;
}

static int rattle_step(void *state, double h, int *iters)
{
  Rattle *r = state;
  const Problem *pb = r->pb;
  int m = pb->m, nu = pb->nu, i, it = 0;
  double pt[BENCH_MAXM], qt[BENCH_MAXM], q1[BENCH_MAXM], C[BENCH_MAXNU * BENCH_MAXNU], mu[BENCH_MAXNU];
  for (i = 0; i < m; i++) {
    pt[i] = r->p[i] - 0.5 * h * r->gu[i];
    qt[i] = r->q[i] + h * pb->minv[i] * pt[i];
  }
  if (nu) {
    it = solve_positions(pb, qt, r->G, h, r->lambda, q1);
    if (it < 0) return -1;
    sub_glam(pb, r->G, r->lambda, 0.5 * h, NULL, pt, pt); /* p~ = p0 - h/2 (grad U + G0 lambda) */
  } else
    memcpy(q1, qt, (size_t)m * sizeof *q1);
  memcpy(r->q, q1, (size_t)m * sizeof *q1);
  pb->grad(r->q, r->gu);
  for (i = 0; i < m; i++) r->p[i] = pt[i] - 0.5 * h * r->gu[i];
  if (nu) { /* project p onto G' M^-1 p = 0 */
    pb->jac(r->q, r->G);
    gram(m, nu, nu, r->G, nu, pb->minv, r->G, nu, C);
    gram(m, nu, 1, r->G, nu, pb->minv, r->p, 1, mu);
    if (dense_solve(nu, C, mu) != 0) return -1;
    sub_glam(pb, r->G, mu, 1, NULL, r->p, r->p);
  }
  *iters = it;
  return 0;
}

static void rattle_get(const void *state, double *q, double *p)
{
  const Rattle *r = state;
  memcpy(q, r->q, (size_t)r->pb->m * sizeof *q);
  memcpy(p, r->p, (size_t)r->pb->m * sizeof *p);
}

int rattle_open(const Setting *set, Stepper *sp)
{
  Rattle *r = calloc(1, sizeof *r);
  if (!r) return -1;
  r->pb = set->pb;
  r->pb->init(r->q, r->p);
  r->pb->grad(r->q, r->gu);
  if (r->pb->nu) r->pb->jac(r->q, r->G);
  sp->state = r;
  sp->step = rattle_step;
  sp->get = rattle_get;
  return 0;
}

void rattle_close(Stepper *sp) { free(sp->state); }
