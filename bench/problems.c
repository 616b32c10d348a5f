/* problems.c - the seven benchmark problems, written by hand from
 * models/NAME.ham (the same functions hbvmgen differentiates), and the
 * helpers every peer shares: energy, constraint residual, the index-1
 * multiplier and the observer of invariants. */
#include "problems.h"

#include <math.h>
#include <string.h>

#include "linalg.h"
#include "stiff.h"

static const double unit_minv[BENCH_MAXM] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};

/* ---------------------------------------------------------------- pendulum
 * m=2, nu=1: U = y, g = x^2 + y^2 - 1, q0 = (0, -1), p0 = (1, 0). */

static void pend_init(double *q0, double *p0)
{
  q0[0] = 0;
  q0[1] = -1;
  p0[0] = 1;
  p0[1] = 0;
}

static double pend_pot(const double *q) { return q[1]; }

static void pend_grad(const double *q, double *gu)
{
  (void)q;
  gu[0] = 0;
  gu[1] = 1;
}

/* g = |q|^2 - 1 for any m: the pendulum (m=2) and the conical pendulum (m=3). */
static void sphere_cons(int m, const double *q, double *g)
{
  double s = 0;
  int i;
  for (i = 0; i < m; i++) s += q[i] * q[i];
  g[0] = s - 1;
}

static void sphere_jac(int m, const double *q, double *G)
{
  int i;
  for (i = 0; i < m; i++) G[i] = 2 * q[i];
}

static void sphere_hessq(int m, const double *v, double *hq)
{
  double s = 0;
  int i;
  for (i = 0; i < m; i++) s += v[i] * v[i];
  hq[0] = 2 * s;
}

static void pend_cons(const double *q, double *g) { sphere_cons(2, q, g); }
static void pend_jac(const double *q, double *G) { sphere_jac(2, q, G); }
static void pend_hessq(const double *q, const double *v, double *hq)
{
  (void)q;
  sphere_hessq(2, v, hq);
}

/* ----------------------------------------------------------------- conical
 * m=3, nu=1: U = z, g = |q|^2 - 1, q0 = (2^-1/2, 0, -2^-1/2), p0 = (0, 2^-1/4, 0). */

static void con_init(double *q0, double *p0)
{
  q0[0] = sqrt(0.5);
  q0[1] = 0;
  q0[2] = -sqrt(0.5);
  p0[0] = 0;
  p0[1] = pow(2, -0.25);
  p0[2] = 0;
}

static double con_pot(const double *q) { return q[2]; }

static void con_grad(const double *q, double *gu)
{
  (void)q;
  gu[0] = 0;
  gu[1] = 0;
  gu[2] = 1;
}

static void con_cons(const double *q, double *g) { sphere_cons(3, q, g); }
static void con_jac(const double *q, double *G) { sphere_jac(3, q, G); }
static void con_hessq(const double *q, const double *v, double *hq)
{
  (void)q;
  sphere_hessq(3, v, hq);
}

/* ---------------------------------------------------------------- modified
 * m=3, nu=1: U = z^4, g = x^6 + y^4 + z^2 - 0.625, initial values as conical. */

static double mod_pot(const double *q)
{
  double z2 = q[2] * q[2];
  return z2 * z2;
}

static void mod_grad(const double *q, double *gu)
{
  gu[0] = 0;
  gu[1] = 0;
  gu[2] = 4 * q[2] * q[2] * q[2];
}

static void mod_cons(const double *q, double *g)
{
  double x2 = q[0] * q[0], y2 = q[1] * q[1];
  g[0] = x2 * x2 * x2 + y2 * y2 + q[2] * q[2] - 0.625;
}

static void mod_jac(const double *q, double *G)
{
  double x2 = q[0] * q[0];
  G[0] = 6 * x2 * x2 * q[0];
  G[1] = 4 * q[1] * q[1] * q[1];
  G[2] = 2 * q[2];
}

/* Hess(g) = diag(30 x^4, 12 y^2, 2). */
static void mod_hessq(const double *q, const double *v, double *hq)
{
  double x2 = q[0] * q[0];
  hq[0] = 30 * x2 * x2 * v[0] * v[0] + 12 * q[1] * q[1] * v[1] * v[1] + 2 * v[2] * v[2];
}

/* -------------------------------------------------------------- satellites
 * m=9, nu=3: three unit masses q_1, q_2, q_3 in R^3, U = -sum_i 1/|q_i|,
 * tethers g_j = |q_a - q_b|^2 - 1 for (a,b) = (1,2), (2,3), (3,1). */

static const int sat_pair[3][2] = {{0, 1}, {1, 2}, {2, 0}};

static void sat_init(double *q0, double *p0)
{
  const double z0 = 20;
  double u = 0;
  int i;
  for (i = 0; i < 9; i++) q0[i] = p0[i] = 0;
  q0[1] = 0.5;
  q0[2] = z0;
  q0[4] = -0.5;
  q0[5] = z0;
  q0[8] = z0 - sqrt(3.0) / 2;
  for (i = 0; i < 3; i++) u += 1 / sqrt(q0[3 * i] * q0[3 * i] + q0[3 * i + 1] * q0[3 * i + 1] + q0[3 * i + 2] * q0[3 * i + 2]);
  p0[6] = sqrt(2 * u); /* H(q0, p0) = 0 */
}

static double sat_pot(const double *q)
{
  double u = 0;
  int i;
  for (i = 0; i < 3; i++) u -= 1 / sqrt(q[3 * i] * q[3 * i] + q[3 * i + 1] * q[3 * i + 1] + q[3 * i + 2] * q[3 * i + 2]);
  return u;
}

static void sat_grad(const double *q, double *gu)
{
  int i, c;
  for (i = 0; i < 3; i++) {
    const double *r = q + 3 * i;
    double n2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2], inv3 = 1 / (n2 * sqrt(n2));
    for (c = 0; c < 3; c++) gu[3 * i + c] = r[c] * inv3;
  }
}

static void sat_cons(const double *q, double *g)
{
  int j, c;
  for (j = 0; j < 3; j++) {
    const double *a = q + 3 * sat_pair[j][0], *b = q + 3 * sat_pair[j][1];
    double d2 = 0;
    for (c = 0; c < 3; c++) d2 += (a[c] - b[c]) * (a[c] - b[c]);
    g[j] = d2 - 1;
  }
}

static void sat_jac(const double *q, double *G)
{
  int i, j, c;
  for (i = 0; i < 27; i++) G[i] = 0;
  for (j = 0; j < 3; j++) {
    int a = sat_pair[j][0], b = sat_pair[j][1];
    for (c = 0; c < 3; c++) {
      double d = 2 * (q[3 * a + c] - q[3 * b + c]);
      G[(3 * a + c) * 3 + j] = d;
      G[(3 * b + c) * 3 + j] = -d;
    }
  }
}

/* v' Hess(g_j) v = 2 |v_a - v_b|^2. */
static void sat_hessq(const double *q, const double *v, double *hq)
{
  int j, c;
  (void)q;
  for (j = 0; j < 3; j++) {
    const double *a = v + 3 * sat_pair[j][0], *b = v + 3 * sat_pair[j][1];
    double d2 = 0;
    for (c = 0; c < 3; c++) d2 += (a[c] - b[c]) * (a[c] - b[c]);
    hq[j] = 2 * d2;
  }
}

/* ------------------------------------------------------------------ kepler
 * m=2, nu=0: U = -1/|q|, e = 0.6, q0 = (1 - e, 0), p0 = (0, sqrt((1+e)/(1-e))).
 * Period 2 pi: after whole periods the exact solution is (q0, p0). */

static void kep_orbit(double e, double *q0, double *p0)
{
  q0[0] = 1 - e;
  q0[1] = 0;
  p0[0] = 0;
  p0[1] = sqrt((1 + e) / (1 - e));
}

static void kep_init(double *q0, double *p0) { kep_orbit(0.6, q0, p0); }

/* The eccentric orbits of the adaptive benchmark (bench/adaptive/run.sh):
 * e = 0.9, and e = 0.99, where the speed at the perihelion is 199 times
 * that at the aphelion and a step that keeps the error even varies by
 * ~(1 + e)^(3/2) / (1 - e)^(3/2) ~ 2800x over an orbit. */
static void kep09_init(double *q0, double *p0) { kep_orbit(0.9, q0, p0); }
static void kep099_init(double *q0, double *p0) { kep_orbit(0.99, q0, p0); }

static double kep_pot(const double *q) { return -1 / sqrt(q[0] * q[0] + q[1] * q[1]); }

static void kep_grad(const double *q, double *gu)
{
  double n2 = q[0] * q[0] + q[1] * q[1], inv3 = 1 / (n2 * sqrt(n2));
  gu[0] = q[0] * inv3;
  gu[1] = q[1] * inv3;
}

/* ------------------------------------------------------------------ chain8
 * m=16, nu=8: a planar chain of 8 unit masses on rods of unit length, the
 * first hinged at the origin; q = (x_1..x_8, y_1..y_8), U = sum_i y_i,
 * g_1 = x_1^2 + y_1^2 - 1, g_i = |(x_i, y_i) - (x_i-1, y_i-1)|^2 - 1;
 * released from rest, stretched out horizontally: x_i = i, y_i = 0. */

#define CHAIN 8

static void chain_init(double *q0, double *p0)
{
  int i;
  for (i = 0; i < CHAIN; i++) {
    q0[i] = i + 1;
    q0[CHAIN + i] = 0;
  }
  for (i = 0; i < 2 * CHAIN; i++) p0[i] = 0;
}

static double chain_pot(const double *q)
{
  double u = 0;
  int i;
  for (i = 0; i < CHAIN; i++) u += q[CHAIN + i];
  return u;
}

static void chain_grad(const double *q, double *gu)
{
  int i;
  (void)q;
  for (i = 0; i < CHAIN; i++) {
    gu[i] = 0;
    gu[CHAIN + i] = 1;
  }
}

/* The difference of link a (a = 0: the first mass against the hinge) in
 * the components x (c = 0) or y (c = 1) of w. */
static double chain_diff(const double *w, int a, int c)
{
  const double *v = w + c * CHAIN;
  return a == 0 ? v[0] : v[a] - v[a - 1];
}

static void chain_cons(const double *q, double *g)
{
  int a;
  for (a = 0; a < CHAIN; a++) {
    double dx = chain_diff(q, a, 0), dy = chain_diff(q, a, 1);
    g[a] = dx * dx + dy * dy - 1;
  }
}

static void chain_jac(const double *q, double *G)
{
  int i, a, c;
  for (i = 0; i < 2 * CHAIN * CHAIN; i++) G[i] = 0;
  for (a = 0; a < CHAIN; a++)
    for (c = 0; c < 2; c++) {
      double d = 2 * chain_diff(q, a, c);
      G[(c * CHAIN + a) * CHAIN + a] = d;
      if (a > 0) G[(c * CHAIN + a - 1) * CHAIN + a] = -d;
    }
}

/* v' Hess(g_a) v = 2 |link a of v|^2. */
static void chain_hessq(const double *q, const double *v, double *hq)
{
  int a;
  (void)q;
  for (a = 0; a < CHAIN; a++) {
    double dx = chain_diff(v, a, 0), dy = chain_diff(v, a, 1);
    hq[a] = 2 * (dx * dx + dy * dy);
  }
}

/* --------------------------------------------------------- double_pendulum
 * m=4, nu=2: two unit masses on rods of unit length, the first hinged at the
 * origin; q = (x1, y1, x2, y2), U = y1 + y2, g_1 = x1^2 + y1^2 - 1,
 * g_2 = (x2 - x1)^2 + (y2 - y1)^2 - 1; released from rest at angles 0.5
 * and -0.3 from the downward vertical. */

static void dpend_init(double *q0, double *p0)
{
  q0[0] = sin(0.5);
  q0[1] = -cos(0.5);
  q0[2] = q0[0] + sin(-0.3);
  q0[3] = q0[1] - cos(-0.3);
  p0[0] = p0[1] = p0[2] = p0[3] = 0;
}

static double dpend_pot(const double *q) { return q[1] + q[3]; }

static void dpend_grad(const double *q, double *gu)
{
  (void)q;
  gu[0] = gu[2] = 0;
  gu[1] = gu[3] = 1;
}

static void dpend_cons(const double *q, double *g)
{
  double dx = q[2] - q[0], dy = q[3] - q[1];
  g[0] = q[0] * q[0] + q[1] * q[1] - 1;
  g[1] = dx * dx + dy * dy - 1;
}

static void dpend_jac(const double *q, double *G)
{
  double dx = q[2] - q[0], dy = q[3] - q[1];
  G[0 * 2 + 0] = 2 * q[0];
  G[1 * 2 + 0] = 2 * q[1];
  G[2 * 2 + 0] = G[3 * 2 + 0] = 0;
  G[0 * 2 + 1] = -2 * dx;
  G[1 * 2 + 1] = -2 * dy;
  G[2 * 2 + 1] = 2 * dx;
  G[3 * 2 + 1] = 2 * dy;
}

/* v' Hess(g_1) v = 2 |v_1|^2, v' Hess(g_2) v = 2 |v_2 - v_1|^2. */
static void dpend_hessq(const double *q, const double *v, double *hq)
{
  double dx = v[2] - v[0], dy = v[3] - v[1];
  (void)q;
  hq[0] = 2 * (v[0] * v[0] + v[1] * v[1]);
  hq[1] = 2 * (dx * dx + dy * dy);
}

/* ------------------------------------------------------------------- table */

static const Problem problems[] = {
    {"pendulum", 2, 1, 10, unit_minv, pend_init, pend_pot, pend_grad, pend_cons, pend_jac, pend_hessq},
    {"conical", 3, 1, 10, unit_minv, con_init, con_pot, con_grad, con_cons, con_jac, con_hessq},
    {"modified", 3, 1, 10, unit_minv, con_init, mod_pot, mod_grad, mod_cons, mod_jac, mod_hessq},
    {"satellites", 9, 3, 10, unit_minv, sat_init, sat_pot, sat_grad, sat_cons, sat_jac, sat_hessq},
    {"kepler", 2, 0, 20 * 3.14159265358979323846, unit_minv, kep_init, kep_pot, kep_grad, NULL, NULL, NULL},
    {"kepler09", 2, 0, 20 * 3.14159265358979323846, unit_minv, kep09_init, kep_pot, kep_grad, NULL, NULL, NULL},
    {"kepler099", 2, 0, 4 * 3.14159265358979323846, unit_minv, kep099_init, kep_pot, kep_grad, NULL, NULL, NULL},
    {"chain8", 2 * CHAIN, CHAIN, 5, unit_minv, chain_init, chain_pot, chain_grad, chain_cons, chain_jac,
     chain_hessq},
    {"double_pendulum", 4, 2, 10, unit_minv, dpend_init, dpend_pot, dpend_grad, dpend_cons, dpend_jac,
     dpend_hessq},
};

const Problem *problem_find(const char *name)
{
  size_t i;
  for (i = 0; name && i < sizeof problems / sizeof problems[0]; i++)
    if (strcmp(problems[i].name, name) == 0) return &problems[i];
  return name ? stiff_problem_find(name) : NULL;
}

double problem_error(const Problem *pb, const double *q, const double *p, const double *qref, const double *pref)
{
  const Stiff *st = stiff_find(pb);
  double a[STIFF_MAXSLOW], b[STIFF_MAXSLOW];
  int n;
  if (!st) return fmax(maxdiff(pb->m, q, qref), maxdiff(pb->m, p, pref));
  n = st->slow(q, p, a);
  st->slow(qref, pref, b);
  for (int i = 0; i < n; i++)
    if (!isfinite(a[i])) return NAN; /* fmax in maxdiff would drop it: a run that blew up */
  return maxdiff(n, a, b);
}

double problem_energy(const Problem *pb, const double *q, const double *p)
{
  double kin = 0;
  int i;
  for (i = 0; i < pb->m; i++) kin += p[i] * pb->minv[i] * p[i];
  return 0.5 * kin + pb->pot(q);
}

double problem_gmax(const Problem *pb, const double *q)
{
  double g[BENCH_MAXNU];
  if (!pb->nu) return 0;
  pb->cons(q, g);
  return maxabs(pb->nu, g);
}

int problem_lambda(const Problem *pb, const double *q, const double *p, double *lambda, double *gu_out,
                   double *G_out)
{
  double gu[BENCH_MAXM], G[BENCH_MAXM * BENCH_MAXNU], A[BENCH_MAXNU * BENCH_MAXNU], v[BENCH_MAXM];
  double Gtg[BENCH_MAXNU];
  int m = pb->m, nu = pb->nu, i;
  pb->grad(q, gu);
  if (gu_out) memcpy(gu_out, gu, (size_t)m * sizeof *gu);
  if (!nu) return 0;
  pb->jac(q, G);
  if (G_out) memcpy(G_out, G, (size_t)(m * nu) * sizeof *G);
  for (i = 0; i < m; i++) v[i] = pb->minv[i] * p[i];
  pb->hessq(q, v, lambda);
  gram(m, nu, nu, G, nu, pb->minv, G, nu, A);
  gram(m, nu, 1, G, nu, pb->minv, gu, 1, Gtg);
  for (i = 0; i < nu; i++) lambda[i] -= Gtg[i];
  return dense_solve(nu, A, lambda);
}

void observer_start(Observer *ob, const Problem *pb, const double *q, const double *p)
{
  ob->pb = pb;
  ob->H0 = problem_energy(pb, q, p);
  ob->dH = 0;
  ob->dg = problem_gmax(pb, q);
}

void observer_point(Observer *ob, const double *q, const double *p)
{
  ob->dH = fmax(ob->dH, fabs(problem_energy(ob->pb, q, p) - ob->H0));
  ob->dg = fmax(ob->dg, problem_gmax(ob->pb, q));
}
