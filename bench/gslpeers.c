/* gslpeers.c - the methods "gsl-rk8pd", "gsl-rk4imp", "gsl-msbdf" and
 * "gsl-bsimp": GSL odeiv2's adaptive explicit Runge-Kutta-Prince-Dormand
 * (8,9), implicit Gauss (2 stages, order 4, modified Newton with the exact
 * Jacobian), variable-order BDF (1-5, Nordsieck form) and the implicit
 * Bulirsch-Stoer of Bader and Deuflhard, on the minimal-coordinate
 * formulation of the problems that have one, and on the stiff problems
 * without constraints (stiff.h: the FPU chain) as they are, y = (q, p),
 * with the Jacobian from their Hessian:
 *
 *   pendulum  theta'' = -sin theta;  q = (sin th, -cos th)
 *   conical   spherical angles (theta from the downward vertical, phi):
 *             theta'' = sin th cos th phi'^2 - sin th,
 *             phi''   = -2 cot th theta' phi';
 *             q = (sin th cos phi, sin th sin phi, -cos th)
 *   kepler    Cartesian, already unconstrained: q'' = -q / |q|^3
 *   double_pendulum  the angles th1, th2 of the rods from the downward
 *             vertical (Euler-Lagrange equations below);
 *             q = (sin th1, -cos th1, sin th1 + sin th2, -cos th1 - cos th2)
 *
 * with p = q' mapped back, so errors, energy and constraints are measured
 * on (q, p) exactly as for the other methods. Absolute and relative
 * tolerance both set->tol (the standard y-control); steps are counted as
 * accepted steps. */
#include <math.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include "bench.h"
#include "stiff.h"

typedef struct {
  const char *problem;
  size_t dim;
  int (*f)(double t, const double y[], double dydt[], void *params);
  int (*jac)(double t, const double y[], double *dfdy, double dfdt[], void *params);
  void (*init)(double *y);
  void (*to_qp)(const double *y, double *q, double *p);
} MinimalForm;

/* ------------------------------------------------------- pendulum, angle */

static int pend_f(double t, const double y[], double f[], void *params)
{
  (void)t;
  (void)params;
  f[0] = y[1];
  f[1] = -sin(y[0]);
  return GSL_SUCCESS;
}

static int pend_jac(double t, const double y[], double *J, double dfdt[], void *params)
{
  (void)t;
  (void)params;
  J[0] = 0;
  J[1] = 1;
  J[2] = -cos(y[0]);
  J[3] = 0;
  dfdt[0] = dfdt[1] = 0;
  return GSL_SUCCESS;
}

static void pend_init(double *y)
{
  y[0] = 0;
  y[1] = 1;
}

static void pend_to_qp(const double *y, double *q, double *p)
{
  double s = sin(y[0]), c = cos(y[0]);
  q[0] = s;
  q[1] = -c;
  p[0] = c * y[1];
  p[1] = s * y[1];
}

/* ------------------------------------------- conical, spherical angles
 * y = (theta, phi, theta', phi'). */

static int con_f(double t, const double y[], double f[], void *params)
{
  double s = sin(y[0]), c = cos(y[0]);
  (void)t;
  (void)params;
  f[0] = y[2];
  f[1] = y[3];
  f[2] = s * c * y[3] * y[3] - s;
  f[3] = -2 * c / s * y[2] * y[3];
  return GSL_SUCCESS;
}

static int con_jac(double t, const double y[], double *J, double dfdt[], void *params)
{
  double s = sin(y[0]), c = cos(y[0]), w2 = y[3] * y[3];
  int i;
  (void)t;
  (void)params;
  for (i = 0; i < 16; i++) J[i] = 0;
  J[0 * 4 + 2] = 1;
  J[1 * 4 + 3] = 1;
  J[2 * 4 + 0] = (c * c - s * s) * w2 - c;
  J[2 * 4 + 3] = 2 * s * c * y[3];
  J[3 * 4 + 0] = 2 * y[2] * y[3] / (s * s);
  J[3 * 4 + 2] = -2 * c / s * y[3];
  J[3 * 4 + 3] = -2 * c / s * y[2];
  for (i = 0; i < 4; i++) dfdt[i] = 0;
  return GSL_SUCCESS;
}

/* theta = pi/4, phi = 0, theta' = 0, phi' = 2^(1/4): models/conical.ham's q0, p0. */
static void con_init(double *y)
{
  y[0] = atan(1.0);
  y[1] = 0;
  y[2] = 0;
  y[3] = pow(2, 0.25);
}

static void con_to_qp(const double *y, double *q, double *p)
{
  double st = sin(y[0]), ct = cos(y[0]), sp = sin(y[1]), cp = cos(y[1]);
  q[0] = st * cp;
  q[1] = st * sp;
  q[2] = -ct;
  p[0] = ct * cp * y[2] - st * sp * y[3];
  p[1] = ct * sp * y[2] + st * cp * y[3];
  p[2] = st * y[2];
}

/* ------------------------------------------------------ kepler, Cartesian
 * y = (q, p). */

static int kep_f(double t, const double y[], double f[], void *params)
{
  double r2 = y[0] * y[0] + y[1] * y[1], inv3 = 1 / (r2 * sqrt(r2));
  (void)t;
  (void)params;
  f[0] = y[2];
  f[1] = y[3];
  f[2] = -y[0] * inv3;
  f[3] = -y[1] * inv3;
  return GSL_SUCCESS;
}

/* d(-q/r^3)/dq = -I/r^3 + 3 q q'/r^5. */
static int kep_jac(double t, const double y[], double *J, double dfdt[], void *params)
{
  double r2 = y[0] * y[0] + y[1] * y[1], inv3 = 1 / (r2 * sqrt(r2)), inv5 = inv3 / r2;
  int i, j;
  (void)t;
  (void)params;
  for (i = 0; i < 16; i++) J[i] = 0;
  J[0 * 4 + 2] = J[1 * 4 + 3] = 1;
  for (i = 0; i < 2; i++)
    for (j = 0; j < 2; j++) J[(2 + i) * 4 + j] = 3 * y[i] * y[j] * inv5 - (i == j ? inv3 : 0);
  for (i = 0; i < 4; i++) dfdt[i] = 0;
  return GSL_SUCCESS;
}

static void kep_orbit(const char *problem, double *y)
{
  double q0[2], p0[2];
  problem_find(problem)->init(q0, p0);
  y[0] = q0[0];
  y[1] = q0[1];
  y[2] = p0[0];
  y[3] = p0[1];
}

static void kep_init(double *y) { kep_orbit("kepler", y); }
static void kep09_init(double *y) { kep_orbit("kepler09", y); }
static void kep099_init(double *y) { kep_orbit("kepler099", y); }

static void kep_to_qp(const double *y, double *q, double *p)
{
  memcpy(q, y, 2 * sizeof *q);
  memcpy(p, y + 2, 2 * sizeof *p);
}

/* --------------------------------------- double pendulum, rod angles
 * y = (th1, th2, w1, w2), w = th'. With D = th1 - th2, c = cos D,
 * s = sin D the Euler-Lagrange equations of
 *     L = w1^2 + w2^2/2 + w1 w2 c + 2 cos th1 + cos th2
 * are [[2, c], [c, 1]] (w1', w2') = (r1, r2) with
 *     r1 = -s w2^2 - 2 sin th1,   r2 = s w1^2 - sin th2,
 * so w1' = (r1 - c r2)/det, w2' = (2 r2 - c r1)/det, det = 2 - c^2. */

static int dpend_f(double t, const double y[], double f[], void *params)
{
  double c = cos(y[0] - y[1]), s = sin(y[0] - y[1]), det = 2 - c * c;
  double r1 = -s * y[3] * y[3] - 2 * sin(y[0]), r2 = s * y[2] * y[2] - sin(y[1]);
  (void)t;
  (void)params;
  f[0] = y[2];
  f[1] = y[3];
  f[2] = (r1 - c * r2) / det;
  f[3] = (2 * r2 - c * r1) / det;
  return GSL_SUCCESS;
}

/* Column j of the Jacobian of (w1', w2') from the derivatives of D, r1 and
 * r2 along y_j: d(n/det) = (dn - (n/det) ddet)/det, dc = -s dD,
 * ddet = 2 c s dD. */
static int dpend_jac(double t, const double y[], double *J, double dfdt[], void *params)
{
  double c = cos(y[0] - y[1]), s = sin(y[0] - y[1]), det = 2 - c * c;
  double r1 = -s * y[3] * y[3] - 2 * sin(y[0]), r2 = s * y[2] * y[2] - sin(y[1]);
  double a1 = (r1 - c * r2) / det, a2 = (2 * r2 - c * r1) / det;
  /* dD, dr1, dr2 along th1, th2, w1, w2 */
  const double dD[4] = {1, -1, 0, 0};
  const double dr1[4] = {-c * y[3] * y[3] - 2 * cos(y[0]), c * y[3] * y[3], 0, -2 * s * y[3]};
  const double dr2[4] = {c * y[2] * y[2], -c * y[2] * y[2] - cos(y[1]), 2 * s * y[2], 0};
  int j;
  (void)t;
  (void)params;
  for (j = 0; j < 4; j++) {
    double dc = -s * dD[j], ddet = 2 * c * s * dD[j];
    J[0 * 4 + j] = j == 2;
    J[1 * 4 + j] = j == 3;
    J[2 * 4 + j] = (dr1[j] - c * dr2[j] - dc * r2 - a1 * ddet) / det;
    J[3 * 4 + j] = (2 * dr2[j] - c * dr1[j] - dc * r1 - a2 * ddet) / det;
    dfdt[j] = 0;
  }
  return GSL_SUCCESS;
}

/* At rest at th1 = 0.5, th2 = -0.3: models/double_pendulum.ham's q0, p0. */
static void dpend_init(double *y)
{
  y[0] = 0.5;
  y[1] = -0.3;
  y[2] = y[3] = 0;
}

static void dpend_to_qp(const double *y, double *q, double *p)
{
  double s1 = sin(y[0]), c1 = cos(y[0]), s2 = sin(y[1]), c2 = cos(y[1]);
  q[0] = s1;
  q[1] = -c1;
  q[2] = s1 + s2;
  q[3] = -c1 - c2;
  p[0] = c1 * y[2];
  p[1] = s1 * y[2];
  p[2] = c1 * y[2] + c2 * y[3];
  p[3] = s1 * y[2] + s2 * y[3];
}

/* ------------------------- stiff problems without constraints, y = (q, p)
 * f = (M^-1 p, -grad U(q)), J = [[0, M^-1], [-Hess U, 0]]; params: the Stiff. */

static int sep_f(double t, const double y[], double f[], void *params)
{
  const Problem *pb = ((const Stiff *)params)->pb;
  int m = pb->m, i;
  (void)t;
  pb->grad(y, f + m);
  for (i = 0; i < m; i++) {
    f[i] = pb->minv[i] * y[m + i];
    f[m + i] = -f[m + i];
  }
  return GSL_SUCCESS;
}

static int sep_jac(double t, const double y[], double *J, double dfdt[], void *params)
{
  const Stiff *st = params;
  int m = st->pb->m, n = 2 * m, i, j;
  double H[BENCH_MAXM * BENCH_MAXM];
  (void)t;
  st->hess(y, H);
  for (i = 0; i < n * n; i++) J[i] = 0;
  for (i = 0; i < m; i++) {
    J[i * n + m + i] = st->pb->minv[i];
    for (j = 0; j < m; j++) J[(m + i) * n + j] = -H[i * m + j];
  }
  for (i = 0; i < n; i++) dfdt[i] = 0;
  return GSL_SUCCESS;
}

/* -------------------------------------------------------------- the runs */

/* (q, p) from y: the minimal form's map, or y itself (mf NULL). */
static void y_to_qp(const MinimalForm *mf, int m, const double *y, double *q, double *p)
{
  if (mf) {
    mf->to_qp(y, q, p);
    return;
  }
  memcpy(q, y, (size_t)m * sizeof *q);
  memcpy(p, y + m, (size_t)m * sizeof *p);
}

static const MinimalForm forms[] = {
    {"pendulum", 2, pend_f, pend_jac, pend_init, pend_to_qp},
    {"conical", 4, con_f, con_jac, con_init, con_to_qp},
    {"kepler", 4, kep_f, kep_jac, kep_init, kep_to_qp},
    {"kepler09", 4, kep_f, kep_jac, kep09_init, kep_to_qp},
    {"kepler099", 4, kep_f, kep_jac, kep099_init, kep_to_qp},
    {"double_pendulum", 4, dpend_f, dpend_jac, dpend_init, dpend_to_qp},
};

/* Integrate the minimal form of set->pb from 0 to set->T with the stepper
 * type, watching (q, p) after every accepted step when ob is not NULL. The
 * driver object only holds step, control and evolve together (the
 * implicit steppers need it); the loop is evolve_apply's, step by step. */
static int integrate(const gsl_odeiv2_step_type *type, const Setting *set, Observer *ob, Outcome *out)
{
  const MinimalForm *mf = NULL;
  const Stiff *st = stiff_find(set->pb);
  gsl_odeiv2_system sys;
  gsl_odeiv2_driver *d;
  double y[2 * BENCH_MAXM], t = 0, h = 1e-3 * set->T;
  size_t i;
  int rc = 0, m = set->pb->m;
  for (i = 0; i < sizeof forms / sizeof forms[0]; i++)
    if (strcmp(forms[i].problem, set->pb->name) == 0) mf = &forms[i];
  if (mf) {
    sys.function = mf->f;
    sys.jacobian = mf->jac;
    sys.dimension = mf->dim;
    sys.params = NULL;
  } else if (st && st->hess && set->pb->nu == 0) {
    sys.function = sep_f;
    sys.jacobian = sep_jac;
    sys.dimension = (size_t)(2 * m);
    sys.params = (void *)st;
  } else
    return -1;
  d = gsl_odeiv2_driver_alloc_y_new(&sys, type, h, set->tol, set->tol);
  if (!d) return -2;
  if (mf)
    mf->init(y);
  else
    set->pb->init(y, y + m);
  if (ob) {
    y_to_qp(mf, m, y, out->q, out->p);
    observer_start(ob, set->pb, out->q, out->p);
  }
  while (t < set->T) {
    if (gsl_odeiv2_evolve_apply(d->e, d->c, d->s, &sys, &t, set->T, &h, y) != GSL_SUCCESS) {
      rc = -2;
      break;
    }
    if (ob) {
      y_to_qp(mf, m, y, out->q, out->p);
      observer_point(ob, out->q, out->p);
    }
  }
  y_to_qp(mf, m, y, out->q, out->p);
  out->steps = (long)(d->e->count - d->e->failed_steps);
  out->iters = 0;
  out->itmax = 0;
  gsl_odeiv2_driver_free(d);
  return rc;
}

int gsl_rk8pd_integrate(const Setting *set, Observer *ob, Outcome *out)
{
  return integrate(gsl_odeiv2_step_rk8pd, set, ob, out);
}

int gsl_rk4imp_integrate(const Setting *set, Observer *ob, Outcome *out)
{
  return integrate(gsl_odeiv2_step_rk4imp, set, ob, out);
}

int gsl_msbdf_integrate(const Setting *set, Observer *ob, Outcome *out)
{
  return integrate(gsl_odeiv2_step_msbdf, set, ob, out);
}

int gsl_bsimp_integrate(const Setting *set, Observer *ob, Outcome *out)
{
  return integrate(gsl_odeiv2_step_bsimp, set, ob, out);
}
