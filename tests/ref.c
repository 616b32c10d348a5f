/* ref.c - independent reference solutions of the paper's test problems.
 * See ref.h for the problems, the methods and the accuracy achieved. */
#include "ref.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#define REF_MAXM 9   /* largest m of the problems below */
#define REF_MAXNU 3  /* largest nu */
#define REF_TOL 1e-15

/* One problem: sizes, initial values and hand-coded U, grad U, g, grad g
 * and the contracted constraint Hessians [p' Hess(g_j) p]_j. */
typedef struct {
  const char *name;
  int m, nu;
  void (*init)(double *q0, double *p0);
  double (*pot)(const double *q);
  void (*gradpot)(const double *q, double *gu);
  void (*cons)(const double *q, double *g);
  void (*jac)(const double *q, double *G);           /* G[i*nu+j] */
  void (*hessq)(const double *q, const double *p, double *hq);
  int shift; /* 1: the index-1 integrator's state holds q - q0 (ref_ctx) */
} ref_problem;

/* ---------------------------------------------------------------- pendulum */

/* Pendulum initial values q0 = (0,-1), p0 = (1,0). */
static void pend_init(double *q0, double *p0)
{
  q0[0] = 0.0; q0[1] = -1.0;
  p0[0] = 1.0; p0[1] = 0.0;
}

static double pend_pot(const double *q) { return q[1]; }

static void pend_gradpot(const double *q, double *gu)
{
  (void)q;
  gu[0] = 0.0; gu[1] = 1.0;
}

static void pend_cons(const double *q, double *g)
{
  g[0] = q[0] * q[0] + q[1] * q[1] - 1.0;
}

static void pend_jac(const double *q, double *G)
{
  G[0] = 2.0 * q[0]; G[1] = 2.0 * q[1];
}

/* p' Hess(g) p with Hess(g) = 2 I. */
static void pend_hessq(const double *q, const double *p, double *hq)
{
  (void)q;
  hq[0] = 2.0 * (p[0] * p[0] + p[1] * p[1]);
}

/* ----------------------------------------------------------------- conical */

/* Conical (and modified) pendulum initial values
 * q0 = (2^-1/2, 0, -2^-1/2), p0 = (0, 2^-1/4, 0). */
static void con_init(double *q0, double *p0)
{
  q0[0] = sqrt(0.5); q0[1] = 0.0; q0[2] = -sqrt(0.5);
  p0[0] = 0.0; p0[1] = pow(2.0, -0.25); p0[2] = 0.0;
}

static double con_pot(const double *q) { return q[2]; }

static void con_gradpot(const double *q, double *gu)
{
  (void)q;
  gu[0] = 0.0; gu[1] = 0.0; gu[2] = 1.0;
}

static void con_cons(const double *q, double *g)
{
  g[0] = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] - 1.0;
}

static void con_jac(const double *q, double *G)
{
  G[0] = 2.0 * q[0]; G[1] = 2.0 * q[1]; G[2] = 2.0 * q[2];
}

static void con_hessq(const double *q, const double *p, double *hq)
{
  (void)q;
  hq[0] = 2.0 * (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
}

/* ---------------------------------------------------------------- modified */

/* U = z^4. */
static double mod_pot(const double *q)
{
  double z2 = q[2] * q[2];
  return z2 * z2;
}

static void mod_gradpot(const double *q, double *gu)
{
  gu[0] = 0.0; gu[1] = 0.0; gu[2] = 4.0 * q[2] * q[2] * q[2];
}

/* g = x^6 + y^4 + z^2 - 0.625. */
static void mod_cons(const double *q, double *g)
{
  double x2 = q[0] * q[0], y2 = q[1] * q[1];
  g[0] = x2 * x2 * x2 + y2 * y2 + q[2] * q[2] - 0.625;
}

static void mod_jac(const double *q, double *G)
{
  double x2 = q[0] * q[0];
  G[0] = 6.0 * x2 * x2 * q[0];
  G[1] = 4.0 * q[1] * q[1] * q[1];
  G[2] = 2.0 * q[2];
}

/* Hess(g) = diag(30 x^4, 12 y^2, 2). */
static void mod_hessq(const double *q, const double *p, double *hq)
{
  double x2 = q[0] * q[0];
  hq[0] = 30.0 * x2 * x2 * p[0] * p[0] + 12.0 * q[1] * q[1] * p[1] * p[1]
          + 2.0 * p[2] * p[2];
}

/* -------------------------------------------------------------- satellites */

/* Tethered satellites initial values (z0 = 20, v0 such that H = 0). */
static void sat_init(double *q0, double *p0)
{
  const double z0 = 20.0;
  double u = 0.0;
  int i;
  for (i = 0; i < 9; i++) {
    q0[i] = 0.0;
    p0[i] = 0.0;
  }
  q0[1] = 0.5;  q0[2] = z0;
  q0[4] = -0.5; q0[5] = z0;
  q0[8] = z0 - sqrt(3.0) / 2.0;
  for (i = 0; i < 3; i++)
    u += 1.0 / sqrt(q0[3 * i] * q0[3 * i] + q0[3 * i + 1] * q0[3 * i + 1]
                    + q0[3 * i + 2] * q0[3 * i + 2]);
  p0[6] = sqrt(2.0 * u);
}

/* Euclidean norm of a 3-vector. */
static double norm3(const double *v)
{
  return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* U = -sum_i 1/|q_i|. */
static double sat_pot(const double *q)
{
  return -(1.0 / norm3(q) + 1.0 / norm3(q + 3) + 1.0 / norm3(q + 6));
}

static void sat_gradpot(const double *q, double *gu)
{
  int i, c;
  for (i = 0; i < 3; i++) {
    double r = norm3(q + 3 * i), r3 = r * r * r;
    for (c = 0; c < 3; c++)
      gu[3 * i + c] = q[3 * i + c] / r3;
  }
}

/* Pairs (a,b) of satellites joined by tether j: g_j = |q_a - q_b|^2 - 1. */
static const int sat_pair[3][2] = {{0, 1}, {1, 2}, {2, 0}};

static void sat_cons(const double *q, double *g)
{
  int j, c;
  for (j = 0; j < 3; j++) {
    const double *a = q + 3 * sat_pair[j][0], *b = q + 3 * sat_pair[j][1];
    double d2 = 0.0;
    for (c = 0; c < 3; c++)
      d2 += (a[c] - b[c]) * (a[c] - b[c]);
    g[j] = d2 - 1.0;
  }
}

static void sat_jac(const double *q, double *G)
{
  int i, j, c;
  for (i = 0; i < 27; i++)
    G[i] = 0.0;
  for (j = 0; j < 3; j++) {
    int a = sat_pair[j][0], b = sat_pair[j][1];
    for (c = 0; c < 3; c++) {
      double d = 2.0 * (q[3 * a + c] - q[3 * b + c]);
      G[(3 * a + c) * 3 + j] = d;
      G[(3 * b + c) * 3 + j] = -d;
    }
  }
}

/* p' Hess(g_j) p = 2 |p_a - p_b|^2. */
static void sat_hessq(const double *q, const double *p, double *hq)
{
  int j, c;
  (void)q;
  for (j = 0; j < 3; j++) {
    const double *a = p + 3 * sat_pair[j][0], *b = p + 3 * sat_pair[j][1];
    double d2 = 0.0;
    for (c = 0; c < 3; c++)
      d2 += (a[c] - b[c]) * (a[c] - b[c]);
    hq[j] = 2.0 * d2;
  }
}

/* --------------------------------------------------------- double_pendulum */

/* The double pendulum's initial angles from the downward vertical. */
#define DP_TH1 0.5
#define DP_TH2 (-0.3)

/* Cartesian point (q, p) of the angles th1, th2 and their rates w1, w2:
 * x1 = sin th1, y1 = -cos th1, x2 = x1 + sin th2, y2 = y1 - cos th2. */
static void dp_from_angles(double th1, double th2, double w1, double w2,
                           double *q, double *p)
{
  double s1 = sin(th1), c1 = cos(th1), s2 = sin(th2), c2 = cos(th2);
  q[0] = s1;
  q[1] = -c1;
  q[2] = s1 + s2;
  q[3] = -c1 - c2;
  p[0] = w1 * c1;
  p[1] = w1 * s1;
  p[2] = w1 * c1 + w2 * c2;
  p[3] = w1 * s1 + w2 * s2;
}

/* Double pendulum at rest with angles 0.5 and -0.3. */
static void dp_init(double *q0, double *p0)
{
  dp_from_angles(DP_TH1, DP_TH2, 0.0, 0.0, q0, p0);
}

/* U = y1 + y2. */
static double dp_pot(const double *q) { return q[1] + q[3]; }

static void dp_gradpot(const double *q, double *gu)
{
  (void)q;
  gu[0] = 0.0; gu[1] = 1.0; gu[2] = 0.0; gu[3] = 1.0;
}

/* g = (x1^2 + y1^2 - 1, (x2-x1)^2 + (y2-y1)^2 - 1). */
static void dp_cons(const double *q, double *g)
{
  double dx = q[2] - q[0], dy = q[3] - q[1];
  g[0] = q[0] * q[0] + q[1] * q[1] - 1.0;
  g[1] = dx * dx + dy * dy - 1.0;
}

static void dp_jac(const double *q, double *G)
{
  double dx = q[2] - q[0], dy = q[3] - q[1];
  G[0] = 2.0 * q[0]; G[1] = -2.0 * dx;  /* d/dx1 */
  G[2] = 2.0 * q[1]; G[3] = -2.0 * dy;  /* d/dy1 */
  G[4] = 0.0;        G[5] = 2.0 * dx;   /* d/dx2 */
  G[6] = 0.0;        G[7] = 2.0 * dy;   /* d/dy2 */
}

/* p' Hess(g_1) p = 2 |p1|^2, p' Hess(g_2) p = 2 |p2 - p1|^2. */
static void dp_hessq(const double *q, const double *p, double *hq)
{
  double dx = p[2] - p[0], dy = p[3] - p[1];
  (void)q;
  hq[0] = 2.0 * (p[0] * p[0] + p[1] * p[1]);
  hq[1] = 2.0 * (dx * dx + dy * dy);
}

/* ------------------------------------------------------------------ table */

static const ref_problem problems[] = {
  {"pendulum", 2, 1, pend_init, pend_pot, pend_gradpot, pend_cons, pend_jac,
   pend_hessq, 0},
  {"conical", 3, 1, con_init, con_pot, con_gradpot, con_cons, con_jac,
   con_hessq, 0},
  {"modified", 3, 1, con_init, mod_pot, mod_gradpot, mod_cons, mod_jac,
   mod_hessq, 0},
  {"satellites", 9, 3, sat_init, sat_pot, sat_gradpot, sat_cons, sat_jac,
   sat_hessq, 1},
  {"double_pendulum", 4, 2, dp_init, dp_pot, dp_gradpot, dp_cons, dp_jac,
   dp_hessq, 0},
};

/* The problem called name, or NULL. */
static const ref_problem *find_problem(const char *name)
{
  size_t i;
  if (name == NULL)
    return NULL;
  for (i = 0; i < sizeof problems / sizeof problems[0]; i++)
    if (strcmp(problems[i].name, name) == 0)
      return &problems[i];
  return NULL;
}

/* -------------------------------------------------------- index-1 lambda */

/* Solve the n x n system A x = b (A row-major, overwritten; b overwritten
 * by x) by Gaussian elimination with partial pivoting.  Returns 0, or -1
 * if a pivot is zero. */
static int solve_small(int n, double *A, double *b)
{
  int i, j, k;
  for (k = 0; k < n; k++) {
    int piv = k;
    for (i = k + 1; i < n; i++)
      if (fabs(A[i * n + k]) > fabs(A[piv * n + k]))
        piv = i;
    if (A[piv * n + k] == 0.0)
      return -1;
    if (piv != k) {
      double t;
      for (j = 0; j < n; j++) {
        t = A[k * n + j]; A[k * n + j] = A[piv * n + j]; A[piv * n + j] = t;
      }
      t = b[k]; b[k] = b[piv]; b[piv] = t;
    }
    for (i = k + 1; i < n; i++) {
      double f = A[i * n + k] / A[k * n + k];
      for (j = k; j < n; j++)
        A[i * n + j] -= f * A[k * n + j];
      b[i] -= f * b[k];
    }
  }
  for (i = n - 1; i >= 0; i--) {
    double acc = b[i];
    for (j = i + 1; j < n; j++)
      acc -= A[i * n + j] * b[j];
    b[i] = acc / A[i * n + i];
  }
  return 0;
}

/* Multiplier of the index-1 formulation at (q,p).  Differentiating the
 * hidden constraint G(q)'p = 0 along q' = p gives
 *     [p' Hess(g_j) p]_j + G' p' = 0,   p' = -grad U - G lambda,
 * hence (G'G) lambda = [p' Hess(g_j) p]_j - G' grad U.  Also returns
 * grad U and G (for the right-hand side) when gu, G are not NULL. */
static int index1_lambda(const ref_problem *pr, const double *q,
                         const double *p, double *lambda, double *gu_out,
                         double *G_out)
{
  double gu[REF_MAXM], G[REF_MAXM * REF_MAXNU], A[REF_MAXNU * REF_MAXNU];
  int m = pr->m, nu = pr->nu, i, j, l;
  pr->gradpot(q, gu);
  pr->jac(q, G);
  pr->hessq(q, p, lambda);
  for (j = 0; j < nu; j++) {
    for (l = 0; l < nu; l++) {
      double a = 0.0;
      for (i = 0; i < m; i++)
        a += G[i * nu + j] * G[i * nu + l];
      A[j * nu + l] = a;
    }
    for (i = 0; i < m; i++)
      lambda[j] -= G[i * nu + j] * gu[i];
  }
  if (solve_small(nu, A, lambda) != 0)
    return -2;
  if (gu_out != NULL)
    memcpy(gu_out, gu, (size_t)m * sizeof *gu);
  if (G_out != NULL)
    memcpy(G_out, G, (size_t)(m * nu) * sizeof *G);
  return 0;
}

/* What the integrator's right-hand sides and outputs see: the problem and
 * the origin of its positions. For a problem with shift set the index-1
 * state holds q - q0 rather than q: the satellites' coordinates are near
 * 20, where an ulp is 3.6e-15, and the increments of thousands of steps
 * rounded at that size moved the result at t = 10 by 1.1e-13 between
 * output grids h = 0.1 and 0.0125; with q - q0 the runs agree to 7e-15.
 * The other problems' coordinates are of size 1 (origin 0: unchanged). */
typedef struct {
  const ref_problem *pr;
  double q0[REF_MAXM];
} ref_ctx;

/* GSL right-hand side of the index-1 system, y = (q - q0, p):
 * q' = p,  p' = -grad U(q) - G(q) lambda(q,p). */
static int index1_rhs(double t, const double y[], double f[], void *params)
{
  const ref_ctx *cx = params;
  const ref_problem *pr = cx->pr;
  double lambda[REF_MAXNU], gu[REF_MAXM], G[REF_MAXM * REF_MAXNU];
  double q[REF_MAXM] = {0.0}; /* set below; gcc cannot see that m <= 9 */
  int m = pr->m, nu = pr->nu, i, j;
  (void)t;
  for (i = 0; i < m; i++)
    q[i] = cx->q0[i] + y[i];
  if (index1_lambda(pr, q, y + m, lambda, gu, G) != 0)
    return GSL_EBADFUNC;
  for (i = 0; i < m; i++) {
    double acc = gu[i];
    for (j = 0; j < nu; j++)
      acc += G[i * nu + j] * lambda[j];
    f[i] = y[m + i];
    f[m + i] = -acc;
  }
  return GSL_SUCCESS;
}

/* One output point of a trajectory: q[m], p[m] and lambda[nu] from the
 * integrator's state y. 0, or -2 if lambda cannot be computed. */
typedef int (*ref_output)(const ref_ctx *cx, const double *y, double *q,
                          double *p, double *lambda);

/* Integrate sys from y (the initial state, overwritten) with GSL rk8pd at
 * absolute and relative tolerance tol, one driver over all the output
 * times t_n = n*h, n = 0..N (no restart: the driver only shortens the
 * step that would pass t_n), writing point n through out. sys->params is
 * the ref_ctx of the problem. */
static int drive(gsl_odeiv2_system *sys, double *y, double h, long N,
                 double tol, ref_output out, double *q, double *p,
                 double *lambda)
{
  const ref_ctx *cx = sys->params;
  const ref_problem *pr = cx->pr;
  gsl_odeiv2_driver *drv;
  double t = 0.0;
  int rc = 0;
  long n;

  drv = gsl_odeiv2_driver_alloc_y_new(sys, gsl_odeiv2_step_rk8pd, 0.1 * h,
                                      tol, tol);
  if (drv == NULL)
    return -2;
  for (n = 0; n <= N && rc == 0; n++) {
    if (n > 0 && gsl_odeiv2_driver_apply(drv, &t, (double)n * h, y)
                     != GSL_SUCCESS)
      rc = -2;
    else
      rc = out(cx, y, q + n * pr->m, p + n * pr->m, lambda + n * pr->nu);
  }
  gsl_odeiv2_driver_free(drv);
  return rc;
}

/* Output of the index-1 formulation: y = (q - q0, p), lambda(q, p). */
static int index1_output(const ref_ctx *cx, const double *y, double *q,
                         double *p, double *lambda)
{
  int i, m = cx->pr->m;
  for (i = 0; i < m; i++)
    q[i] = cx->q0[i] + y[i];
  memcpy(p, y + m, (size_t)m * sizeof *y);
  return index1_lambda(cx->pr, q, p, lambda, NULL, NULL);
}

/* Integrate the index-1 formulation of pr from its initial values, storing
 * q, p and lambda(q,p) at each t_n = n*h. */
static int solve_index1(const ref_problem *pr, double h, long N, double tol,
                        double *q, double *p, double *lambda)
{
  gsl_odeiv2_system sys;
  ref_ctx cx;
  double y[2 * REF_MAXM];
  int i;

  cx.pr = pr;
  sys.function = index1_rhs;
  sys.jacobian = NULL;
  sys.dimension = (size_t)(2 * pr->m);
  sys.params = &cx;
  pr->init(y, y + pr->m);
  for (i = 0; i < pr->m; i++) {
    cx.q0[i] = pr->shift ? y[i] : 0.0;
    y[i] -= cx.q0[i];
  }
  return drive(&sys, y, h, N, tol, index1_output, q, p, lambda);
}

/* ------------------------------------------- closed forms and angles */

/* GSL right-hand side of theta'' = -sin theta, y = (theta, theta'). */
static int theta_rhs(double t, const double y[], double f[], void *params)
{
  (void)t;
  (void)params;
  f[0] = y[1];
  f[1] = -sin(y[0]);
  return GSL_SUCCESS;
}

/* Pendulum from its angle: x = sin th, y = -cos th,
 * p = th' (cos th, sin th), lambda = (th'^2 + cos th)/2. */
static int theta_output(const ref_ctx *cx, const double *y, double *q,
                        double *p, double *lambda)
{
  double s = sin(y[0]), c = cos(y[0]);
  (void)cx;
  q[0] = s;
  q[1] = -c;
  p[0] = c * y[1];
  p[1] = s * y[1];
  lambda[0] = 0.5 * (y[1] * y[1] + c);
  return 0;
}

/* GSL right-hand side of the double pendulum in its angles from the
 * downward vertical, y = (th1, th2, w1, w2), w = th'. With unit masses,
 * rods and gravity the Lagrangian is
 *     L = w1^2 + w2^2/2 + w1 w2 cos(th1 - th2) + 2 cos th1 + cos th2,
 * and its Euler-Lagrange equations, with c = cos(th1 - th2),
 * s = sin(th1 - th2):
 *     2 w1' + c w2' = -s w2^2 - 2 sin th1,
 *     c w1' +   w2' =  s w1^2 -   sin th2   (determinant 2 - c^2 >= 1). */
static int dp_angle_rhs(double t, const double y[], double f[], void *params)
{
  double c = cos(y[0] - y[1]), s = sin(y[0] - y[1]);
  double r1 = -s * y[3] * y[3] - 2.0 * sin(y[0]);
  double r2 = s * y[2] * y[2] - sin(y[1]);
  double det = 2.0 - c * c;
  (void)t;
  (void)params;
  f[0] = y[2];
  f[1] = y[3];
  f[2] = (r1 - c * r2) / det;
  f[3] = (2.0 * r2 - c * r1) / det;
  return GSL_SUCCESS;
}

/* Double pendulum from its angles; lambda by the index-1 formula at the
 * Cartesian point. */
static int dp_angle_output(const ref_ctx *cx, const double *y, double *q,
                           double *p, double *lambda)
{
  dp_from_angles(y[0], y[1], y[2], y[3], q, p);
  return index1_lambda(cx->pr, q, p, lambda, NULL, NULL);
}

/* Pendulum (theta(0) = 0, theta'(0) = 1) or double pendulum (at rest at
 * angles 0.5, -0.3) through their angle equations. */
static int solve_angles(const ref_problem *pr, double h, long N, double tol,
                        double *q, double *p, double *lambda)
{
  ref_ctx cx;
  gsl_odeiv2_system sys = {theta_rhs, NULL, 2, NULL};
  double y[4] = {0.0, 1.0, 0.0, 0.0};
  ref_output out = theta_output;
  cx.pr = pr;
  sys.params = &cx;
  if (strcmp(pr->name, "double_pendulum") == 0) {
    sys.function = dp_angle_rhs;
    sys.dimension = 4;
    y[0] = DP_TH1;
    y[1] = DP_TH2;
    y[2] = y[3] = 0.0;
    out = dp_angle_output;
  }
  return drive(&sys, y, h, N, tol, out, q, p, lambda);
}

/* Conical pendulum, exact: radius r = 2^-1/2 in the plane z = -r, angular
 * speed w = 2^(1/4), lambda = 2^-1/2 (then -2 q lambda - e3 = -w^2 (x,y,0)
 * is the centripetal acceleration). */
static void solve_conical(double h, long N, double *q, double *p,
                          double *lambda)
{
  const double r = sqrt(0.5), w = pow(2.0, 0.25), v = pow(2.0, -0.25);
  long n;
  for (n = 0; n <= N; n++) {
    double wt = w * ((double)n * h), c = cos(wt), s = sin(wt);
    q[3 * n] = r * c;
    q[3 * n + 1] = r * s;
    q[3 * n + 2] = -r;
    p[3 * n] = -v * s;       /* v = r w, the speed */
    p[3 * n + 1] = v * c;
    p[3 * n + 2] = 0.0;
    lambda[n] = r;
  }
}

/* ------------------------------------------------------------- public API */

int ref_dims(const char *problem, int *m, int *nu)
{
  const ref_problem *pr = find_problem(problem);
  if (pr == NULL)
    return -1;
  if (m != NULL)
    *m = pr->m;
  if (nu != NULL)
    *nu = pr->nu;
  return 0;
}

int ref_initial(const char *problem, double *q0, double *p0)
{
  const ref_problem *pr = find_problem(problem);
  if (pr == NULL)
    return -1;
  pr->init(q0, p0);
  return 0;
}

/* Common argument check of the solvers; returns the problem or NULL. */
static const ref_problem *check_args(const char *problem, double h, long N,
                                     double tol, const double *q,
                                     const double *p, const double *lambda)
{
  if (!(h > 0.0) || N < 0 || !(tol > 0.0) || q == NULL || p == NULL
      || lambda == NULL)
    return NULL;
  return find_problem(problem);
}

int ref_solve_tol(const char *problem, double h, long N, double tol,
                  double *q, double *p, double *lambda)
{
  const ref_problem *pr = check_args(problem, h, N, tol, q, p, lambda);
  if (pr == NULL)
    return -1;
  if (strcmp(pr->name, "pendulum") == 0
      || strcmp(pr->name, "double_pendulum") == 0)
    return solve_angles(pr, h, N, tol, q, p, lambda);
  if (strcmp(pr->name, "conical") == 0) {
    solve_conical(h, N, q, p, lambda);
    return 0;
  }
  return solve_index1(pr, h, N, tol, q, p, lambda);
}

int ref_solve(const char *problem, double h, long N, double *q, double *p,
              double *lambda)
{
  return ref_solve_tol(problem, h, N, REF_TOL, q, p, lambda);
}

int ref_solve_index1(const char *problem, double h, long N, double tol,
                     double *q, double *p, double *lambda)
{
  const ref_problem *pr = check_args(problem, h, N, tol, q, p, lambda);
  if (pr == NULL)
    return -1;
  return solve_index1(pr, h, N, tol, q, p, lambda);
}

int ref_invariants(const char *problem, const double *q, const double *p,
                   double *H, double *g, double *hc)
{
  const ref_problem *pr = find_problem(problem);
  int i, j;
  if (pr == NULL)
    return -1;
  if (H != NULL) {
    double kin = 0.0;
    for (i = 0; i < pr->m; i++)
      kin += p[i] * p[i];
    *H = 0.5 * kin + pr->pot(q);
  }
  if (g != NULL)
    pr->cons(q, g);
  if (hc != NULL) {
    double G[REF_MAXM * REF_MAXNU];
    pr->jac(q, G);
    for (j = 0; j < pr->nu; j++) {
      double acc = 0.0;
      for (i = 0; i < pr->m; i++)
        acc += G[i * pr->nu + j] * p[i];
      hc[j] = acc;
    }
  }
  return 0;
}

int ref_gradients(const char *problem, const double *q, double *gu,
                  double *G)
{
  const ref_problem *pr = find_problem(problem);
  if (pr == NULL)
    return -1;
  if (gu != NULL)
    pr->gradpot(q, gu);
  if (G != NULL)
    pr->jac(q, G);
  return 0;
}

int ref_lambda(const char *problem, const double *q, const double *p,
               double *lambda)
{
  const ref_problem *pr = find_problem(problem);
  if (pr == NULL)
    return -1;
  return index1_lambda(pr, q, p, lambda, NULL, NULL);
}

/* max(a, b), NaN if b is NaN (fmax would drop it: a solver's NaN must
 * show as an error). */
static double max_nan(double a, double b)
{
  return isnan(a) || b <= a ? a : b;
}

int ref_max_error(const char *problem, double h, long N, const double *q,
                  const double *p, const double *lambda, double *err_qp,
                  double *err_lambda)
{
  const ref_problem *pr = find_problem(problem);
  double *rq, *rp, *rl, eqp = 0.0, el = 0.0;
  size_t nm, nl, i;
  int rc;
  if (pr == NULL || !(h > 0.0) || N < 0 || q == NULL || p == NULL
      || err_qp == NULL)
    return -1;
  nm = (size_t)(N + 1) * (size_t)pr->m;
  nl = (size_t)(N + 1) * (size_t)pr->nu;
  rq = malloc(nm * sizeof *rq);
  rp = malloc(nm * sizeof *rp);
  rl = malloc((nl > 0 ? nl : 1) * sizeof *rl);
  rc = rq != NULL && rp != NULL && rl != NULL ? 0 : -3;
  if (rc == 0)
    rc = ref_solve(problem, h, N, rq, rp, rl);
  if (rc == 0) {
    for (i = 0; i < nm; i++) {
      eqp = max_nan(eqp, fabs(q[i] - rq[i]));
      eqp = max_nan(eqp, fabs(p[i] - rp[i]));
    }
    for (i = 0; lambda != NULL && i < nl; i++)
      el = max_nan(el, fabs(lambda[i] - rl[i]));
    *err_qp = eqp;
    if (lambda != NULL && err_lambda != NULL)
      *err_lambda = el;
  }
  free(rq);
  free(rp);
  free(rl);
  return rc;
}
