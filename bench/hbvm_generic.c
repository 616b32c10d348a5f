/* hbvm_generic.c - the method "hbvm-generic": HBVM(k,s) for constrained
 * Hamiltonian systems written once as ordinary C, the honest baseline for
 * what generating the step buys.
 *
 * k, s, m and nu are run-time values, grad U and grad g are called through
 * the function pointers of problems.c, grad g is a dense m x nu matrix, and
 * the Gauss-Legendre nodes come from GSL. The algorithm is the generated
 * step's (gen/step.c, gen/emit.c; METHOD.md): the same fixed-point sweep,
 * the multiplier system with the g(q0)/h correction, the stopping rule (the
 * scaled increment max |h dgamma| / max(|q| + |h gamma_0|) below 2 ulps / 256,
 * or below 2 ulps and falling less than 4x, or no longer decreasing), the
 * warm start from the previous step's polynomial and the Kahan-compensated
 * update. Keep it in step with emit_step when the generated step changes.
 * Only A lambda = r is solved with partial pivoting (linalg.c) where the
 * generated code factors without pivoting. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_integration.h>

#include "bench.h"
#include "linalg.h"

#define MAXITER 100
#define TOL 4.4408920985006262e-16 /* 2 ulps (of the scale) */
#define STAGTOL 1e-10              /* stagnation above this is divergence */
#define GTOL 1.4210854715202004e-14 /* |g(q0)| up to 64 ulps is round-off */

enum { OK, ENOCONV, ENONFINITE, ESINGULAR };

typedef struct {
  const Problem *pb;
  int m, nu, k, s;
  /* the method: Ihat[l*s+j] = int_0^c_l P_j, W[l*s+j] = b_l P_j(c_l),
   * xi[0..s], E[(j*s+i)*s+d]: the warm start's polynomials in r */
  double *Ihat, *W, *xi, *E;
  /* the state */
  double t, tc, hprev, *q, *p, *qc, *pc, *lambda, *gam;
  /* work */
  double *g0, *gnew, *dp, *Q, *F, *G, *psi, *rho, *theta, *A, *r;
} Generic;

/* P_j(x) = sqrt(2j+1) L_j(2x-1), orthonormal on [0,1]. */
static double legendre(int j, double x)
{
  double t = 2 * x - 1, lm1 = 1, l = t;
  int n;
  if (j == 0) return 1;
  for (n = 1; n < j; n++) {
    double next = ((2 * n + 1) * t * l - n * lm1) / (n + 1);
    lm1 = l;
    l = next;
  }
  return sqrt(2.0 * j + 1) * l;
}

/* Coefficients of P_i(1 + r) as a polynomial in r, i = 0..s-1:
 * c[i*s + d], by the three-term recurrence on coefficient arrays
 * (2x - 1 = 1 + 2r). */
static void legendre_at_one_plus(int s, double *c)
{
  double *lm1 = calloc((size_t)s + 1, sizeof *lm1), *l = calloc((size_t)s + 1, sizeof *l);
  double *nx = calloc((size_t)s + 1, sizeof *nx);
  int n, d;
  l[0] = 1;
  for (n = 0; n < s; n++) {
    for (d = 0; d < s; d++) c[n * s + d] = sqrt(2.0 * n + 1) * l[d];
    for (d = 0; d <= s; d++) /* L_{n+1} = ((2n+1)(1+2r) L_n - n L_{n-1}) / (n+1) */
      nx[d] = ((2 * n + 1) * (l[d] + (d ? 2 * l[d - 1] : 0)) - n * lm1[d]) / (n + 1);
    memcpy(lm1, l, (size_t)(s + 1) * sizeof *l);
    memcpy(l, nx, (size_t)(s + 1) * sizeof *l);
  }
  free(lm1);
  free(l);
  free(nx);
}

/* The constants of HBVM(k,s): nodes and weights from GSL, then Ihat, W, xi
 * and the warm start E_ji(r) = int_0^1 P_j(x) P_i(1 + r x) dx (METHOD.md). */
static void method_constants(Generic *g)
{
  int k = g->k, s = g->s, l, j, i, d;
  gsl_integration_glfixed_table *tab = gsl_integration_glfixed_table_alloc((size_t)k);
  double *c = malloc((size_t)k * sizeof *c), *b = malloc((size_t)k * sizeof *b);
  double *taylor = malloc((size_t)(s * s) * sizeof *taylor);
  for (l = 0; l < k; l++) gsl_integration_glfixed_point(0, 1, (size_t)l, &c[l], &b[l], tab);
  for (j = 0; j <= s; j++) g->xi[j] = 1 / (2 * sqrt(fabs(4.0 * j * j - 1)));
  for (l = 0; l < k; l++)
    for (j = 0; j < s; j++) {
      g->W[l * s + j] = b[l] * legendre(j, c[l]);
      g->Ihat[l * s + j] = j == 0 ? c[l] : g->xi[j + 1] * legendre(j + 1, c[l]) - g->xi[j] * legendre(j - 1, c[l]);
    }
  legendre_at_one_plus(s, taylor);
  for (j = 0; j < s; j++)
    for (i = 0; i < s; i++)
      for (d = 0; d < s; d++) {
        double moment = 0; /* int_0^1 P_j(x) x^d dx, exact by Gauss */
        for (l = 0; l < k; l++) moment += g->W[l * s + j] * pow(c[l], d);
        g->E[(j * s + i) * s + d] = taylor[i * s + d] * moment;
      }
  free(taylor);
  free(c);
  free(b);
  gsl_integration_glfixed_table_free(tab);
}

/* sum_i x_i minv_i y_i over m entries, x and y with strides. */
static double dot_minv(int m, const double *minv, const double *x, int sx, const double *y, int sy)
{
  double acc = 0;
  int i;
  for (i = 0; i < m; i++) acc += x[i * sx] * minv[i] * y[i * sy];
  return acc;
}

/* xi_0 <x_0, y_0> + sum_{j>=1} xi_j (<x_j, y_{j-1}> - <x_{j-1}, y_j>) in the
 * M^-1 inner product, for s-sequences of m-vectors x_j[i] = x[(j*m+i)*sx]. */
static double skew_form(const Generic *g, const double *x, int sx, const double *y, int sy)
{
  int m = g->m, j;
  const double *mi = g->pb->minv;
  double acc = g->xi[0] * dot_minv(m, mi, x, sx, y, sy);
  for (j = 1; j < g->s; j++)
    acc += g->xi[j] * (dot_minv(m, mi, x + j * m * sx, sx, y + (j - 1) * m * sy, sy) -
                       dot_minv(m, mi, x + (j - 1) * m * sx, sx, y + j * m * sy, sy));
  return acc;
}

/* One fixed-point sweep from gam: the new gamma into gnew, p1 - p0 into dp
 * and the multiplier into lambda. Returns OK or ESINGULAR. */
static int sweep(Generic *g, const double *gam, double h, double *lambda)
{
  int m = g->m, nu = g->nu, k = g->k, s = g->s, i, j, l, a, c;
  const Problem *pb = g->pb;
  const double *xi = g->xi;
  memset(g->psi, 0, (size_t)(s * m) * sizeof *g->psi);
  memset(g->rho, 0, (size_t)(s * m * nu) * sizeof *g->rho);
  /* stages: Q_l, grad U(Q_l), grad g(Q_l), projected onto P_0..P_{s-1} */
  for (l = 0; l < k; l++) {
    for (i = 0; i < m; i++) {
      double acc = 0;
      for (j = 0; j < s; j++) acc += g->Ihat[l * s + j] * gam[j * m + i];
      g->Q[i] = g->q[i] + h * acc;
    }
    pb->grad(g->Q, g->F);
    if (nu) pb->jac(g->Q, g->G);
    for (j = 0; j < s; j++) {
      double w = g->W[l * s + j];
      for (i = 0; i < m; i++) g->psi[j * m + i] += w * g->F[i];
      for (i = 0; i < m * nu; i++) g->rho[j * m * nu + i] += w * g->G[i];
    }
  }
  /* the multiplier system A lambda = r, and theta_j = psi_j + rho_j lambda */
  memcpy(g->theta, g->psi, (size_t)(s * m) * sizeof *g->theta);
  if (nu) {
    for (a = 0; a < nu; a++) {
      for (c = 0; c < nu; c++) g->A[a * nu + c] = h * skew_form(g, g->rho + a, nu, g->rho + c, nu);
      g->r[a] = dot_minv(m, pb->minv, g->rho + a, nu, g->p, 1) - h * skew_form(g, g->rho + a, nu, g->psi, 1) +
                g->g0[a]; /* g(q0) / h, or 0 at round-off: see generic_step */
    }
    if (dense_solve(nu, g->A, g->r) != 0) return ESINGULAR;
    memcpy(lambda, g->r, (size_t)nu * sizeof *lambda);
    for (j = 0; j < s; j++)
      for (i = 0; i < m; i++)
        for (a = 0; a < nu; a++) g->theta[j * m + i] += g->rho[(j * m + i) * nu + a] * lambda[a];
  }
  /* gamma_j = M^-1 [delta_j0 p0 - h sum_i X[j][i] theta_i], p1 - p0 = -h theta_0 */
  for (j = 0; j < s; j++)
    for (i = 0; i < m; i++) {
      double x = j == 0 ? xi[0] * g->theta[i] : xi[j] * g->theta[(j - 1) * m + i];
      if (j + 1 < s) x -= xi[j + 1] * g->theta[(j + 1) * m + i];
      g->gnew[j * m + i] = pb->minv[i] * ((j == 0 ? g->p[i] : 0) - h * x);
    }
  for (i = 0; i < m; i++) g->dp[i] = -h * g->theta[i];
  return OK;
}

/* gamma for a step of size h: the previous step's polynomial extrapolated,
 * or gamma_0 = M^-1 p, gamma_j = 0 on the first step. */
static void predict(const Generic *g, double h, double *gam)
{
  int m = g->m, s = g->s, i, j, l, d;
  memset(gam, 0, (size_t)(s * m) * sizeof *gam);
  if (g->hprev == 0) {
    for (l = 0; l < m; l++) gam[l] = g->pb->minv[l] * g->p[l];
    return;
  }
  for (j = 0; j < s; j++)
    for (i = 0; i < s; i++) {
      double r = h / g->hprev, e = 0;
      for (d = s - 1; d >= 0; d--) e = e * r + g->E[(j * s + i) * s + d];
      if (e != 0)
        for (l = 0; l < m; l++) gam[j * m + l] += e * g->gam[i * m + l];
    }
}

/* 1 if x[0..n-1] are all finite. */
static int all_finite(int n, const double *x)
{
  int i;
  for (i = 0; i < n; i++)
    if (!isfinite(x[i])) return 0;
  return 1;
}

/* a += b with the rounding error carried in *c (Kahan). */
static void kahan_add(double *a, double *c, double b)
{
  double y = b - *c, t = *a + y;
  *c = (t - *a) - y;
  *a = t;
}

/* One step of HBVM(k,s); commits to the state only on success. */
static int generic_step(void *state, double h, int *iters)
{
  Generic *g = state;
  int m = g->m, nu = g->nu, s = g->s, it, i, rc = ENOCONV;
  double gam[BENCH_MAXM * 8], lambda[BENCH_MAXNU + 1], inc = HUGE_VAL, inc_old, scale;
  predict(g, h, gam);
  if (nu) g->pb->cons(g->q, g->g0);
  for (i = 0; i < nu; i++) /* as the generated step: round-off g(q0) is not corrected */
    g->g0[i] = fabs(g->g0[i]) <= GTOL ? 0 : g->g0[i] / h;
  for (it = 1; it <= MAXITER; it++) {
    if (sweep(g, gam, h, lambda) != OK) {
      rc = ESINGULAR;
      break;
    }
    inc_old = inc;
    inc = 0;
    scale = 0;
    for (i = 0; i < m; i++) scale = fmax(scale, fabs(g->q[i]) + fabs(h * g->gnew[i]));
    for (i = 0; i < s * m; i++) {
      inc = fmax(inc, fabs(h * (g->gnew[i] - gam[i])));
      gam[i] = g->gnew[i];
    }
    if (scale > 0) inc /= scale;
    if (!isfinite(inc) || !all_finite(s * m, g->gnew) || !all_finite(m, g->dp) || !all_finite(nu, lambda)) {
      rc = ENONFINITE;
      break;
    }
    /* converged: far below an ulp, or within 2 ulps and no longer falling 4x
     * per sweep (round-off noise); as gen/emit.c since commit c3bf713 */
    if (inc <= TOL / 256 || (inc <= TOL && 4 * inc > inc_old)) {
      rc = OK;
      break;
    }
    if (it > 1 && inc >= inc_old) {
      rc = inc <= STAGTOL ? OK : ENOCONV;
      break;
    }
  }
  *iters = it > MAXITER ? MAXITER : it;
  if (rc != OK) return rc;
  for (i = 0; i < m; i++) /* the new state must be finite too */
    if (!isfinite(g->q[i] + h * g->gnew[i]) || !isfinite(g->p[i] + g->dp[i])) return ENONFINITE;
  for (i = 0; i < m; i++) {
    kahan_add(&g->q[i], &g->qc[i], h * g->gnew[i]);
    kahan_add(&g->p[i], &g->pc[i], g->dp[i]);
  }
  memcpy(g->lambda, lambda, (size_t)nu * sizeof *lambda);
  memcpy(g->gam, gam, (size_t)(s * m) * sizeof *gam);
  kahan_add(&g->t, &g->tc, h);
  g->hprev = h;
  return OK;
}

static void generic_get(const void *state, double *q, double *p)
{
  const Generic *g = state;
  memcpy(q, g->q, (size_t)g->m * sizeof *q);
  memcpy(p, g->p, (size_t)g->m * sizeof *p);
}

int generic_open(const Setting *set, Stepper *sp)
{
  const Problem *pb = set->pb;
  int m = pb->m, nu = pb->nu, k = set->k, s = set->s, i;
  size_t n;
  Generic *g;
  double *w;
  if (s < 1 || s > 8 || k < s) return -1;
  g = calloc(1, sizeof *g);
  /* one block for every array: the constants, the state and the work */
  n = (size_t)(2 * k * s + (s + 1) + s * s * s) + (size_t)(4 * m + nu + s * m) +
      (size_t)(nu + s * m + m + m + m + m * nu + s * m + s * m * nu + s * m + nu * nu + nu) + 1;
  w = calloc(n, sizeof *w);
  if (!g || !w) {
    free(g);
    free(w);
    return -1;
  }
#define TAKE(ptr, count) (ptr = w, w += (count))
  TAKE(g->Ihat, k * s);
  TAKE(g->W, k * s);
  TAKE(g->xi, s + 1);
  TAKE(g->E, s * s * s);
  TAKE(g->q, m);
  TAKE(g->p, m);
  TAKE(g->qc, m);
  TAKE(g->pc, m);
  TAKE(g->lambda, nu);
  TAKE(g->gam, s * m);
  TAKE(g->g0, nu);
  TAKE(g->gnew, s * m);
  TAKE(g->dp, m);
  TAKE(g->Q, m);
  TAKE(g->F, m);
  TAKE(g->G, m * nu);
  TAKE(g->psi, s * m);
  TAKE(g->rho, s * m * nu);
  TAKE(g->theta, s * m);
  TAKE(g->A, nu * nu);
  TAKE(g->r, nu);
#undef TAKE
  g->pb = pb;
  g->m = m;
  g->nu = nu;
  g->k = k;
  g->s = s;
  method_constants(g);
  pb->init(g->q, g->p);
  for (i = 0; i < nu; i++) g->lambda[i] = 0;
  sp->state = g;
  sp->step = generic_step;
  sp->get = generic_get;
  return 0;
}

void generic_close(Stepper *sp)
{
  Generic *g = sp->state;
  free(g->Ihat); /* the start of the one block */
  free(g);
}
