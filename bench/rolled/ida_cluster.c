/* ida_cluster.c - the cluster of N rigid diatomics (tests/models/cluster4.ham
 * with N molecules) in the rolled solver B (bench/rolled/cluster.sh
 * generates B.h/B.c with --rolled on) against SUNDIALS IDA with a dense
 * linear solver.
 *
 * IDA integrates the stabilised index-2 (GGL) form of bench/ida.c, M = I:
 *   q' = p - G' mu,  p' = -grad U - G' lambda,  0 = g(q),  0 = G p,
 * with the unknowns ordered per molecule i: (r_a, r_b, p_a, p_b, lambda_i,
 * mu_i), 14 a molecule, g_i = |r_a - r_b|^2 - d^2. Every atom feels every
 * other through the pair potential, so the Jacobian's momentum rows are
 * full: dense (SUNDenseMatrix, SUNLinSol_Dense, IDA's difference-quotient
 * Jacobian: 14 N residuals each; a sparse solver would store the same
 * entries). U is the model's: phi(s) = eps ((s / s0)^2 - 2 s / s0) of s =
 * |r_A - r_B|^2 for the four atom pairs of two molecules, eps = 4 / N, and
 * the trap 0.01 z^2 on every atom (the constants below repeat the model's).
 * The initial state is B's (B_init: the model's q0, p0; the bonds hold and
 * G p0 = 0), lambda the consistent multiplier from the second derivative
 * of g, mu = 0, and y' from the equations.
 *
 * Usage: ida_cluster T h,h,... reps tol,tol,... (ida_vs.h: the runs, the
 * reference and the CSV rows). */
#include <string.h>

#include <nvector/nvector_serial.h>

#include "ida_vs.h"
#include "rolled_run.h"

#define NM B_NU      /* molecules: one bond each */
#define PER 14       /* unknowns per molecule */
#define S0 2.25      /* phi's s0 */
#define BOND 1.0     /* d */
#define TRAP 0.01    /* 0.01 z^2 */
#define ALG_ATOL 1e-3
/* The reference's step (ida_vs.h), as the chain's (ida_chain.c). */
#define REF_H 0.0025
#define REF_TOL 1e-12

/* Position (c = 0) or momentum (c = 6) of atom a (0: r_a, 1: r_b) of
 * molecule i in y. */
static const double *atom(const double *y, int i, int a, int c)
{
  return y + PER * i + c + 3 * a;
}

/* grad U at the positions of y, per atom: f[6 i + 3 a + k]. */
static void gradient(const double *y, double *f)
{
  const double eps = 4.0 / NM;
  int i, j, a, b, k;
  for (i = 0; i < NM; i++)
    for (a = 0; a < 2; a++) {
      f[6 * i + 3 * a] = f[6 * i + 3 * a + 1] = 0;
      f[6 * i + 3 * a + 2] = 2 * TRAP * atom(y, i, a, 0)[2];
    }
  for (i = 0; i < NM; i++)
    for (j = i + 1; j < NM; j++)
      for (a = 0; a < 2; a++)
        for (b = 0; b < 2; b++) {
          const double *ra = atom(y, i, a, 0), *rb = atom(y, j, b, 0);
          double d[3], s = 0, dphi;
          for (k = 0; k < 3; k++) {
            d[k] = ra[k] - rb[k];
            s += d[k] * d[k];
          }
          dphi = 2 * eps * (2 * s / (S0 * S0) - 2 / S0); /* 2 phi'(s) */
          for (k = 0; k < 3; k++) {
            f[6 * i + 3 * a + k] += dphi * d[k];
            f[6 * j + 3 * b + k] -= dphi * d[k];
          }
        }
}

/* F(t, y, y') of the GGL system, per molecule (see the top). */
static int residual(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *user_data)
{
  static double f[6 * NM];
  const double *y = N_VGetArrayPointer(yy), *yd = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  int i, k;
  (void)t;
  (void)user_data;
  gradient(y, f);
  for (i = 0; i < NM; i++) {
    const double *m = y + PER * i, *md = yd + PER * i, lam = m[12], mu = m[13];
    double *ri = r + PER * i, g = 0, gp = 0;
    for (k = 0; k < 3; k++) {
      double d = m[k] - m[3 + k], v = m[6 + k] - m[9 + k]; /* r_a - r_b, p_a - p_b */
      ri[k] = md[k] - (m[6 + k] - 2 * d * mu);
      ri[3 + k] = md[3 + k] - (m[9 + k] + 2 * d * mu);
      ri[6 + k] = md[6 + k] + f[6 * i + k] + 2 * d * lam;
      ri[9 + k] = md[9 + k] + f[6 * i + 3 + k] - 2 * d * lam;
      g += d * d;
      gp += 2 * d * v;
    }
    ri[12] = g - BOND * BOND;
    ri[13] = gp;
  }
  return 0;
}

/* The consistent start from B's (q, p): lambda from d^2 g_i / dt^2 = 0,
 * 2 |p_a - p_b|^2 - 2 (r_a - r_b).(f_a - f_b) - 8 |r_a - r_b|^2 lambda = 0,
 * mu = 0, and y' = (p, -f - G' lambda, 0, 0). */
static void initial(double *y, double *yd)
{
  static B_state x;
  static double f[6 * NM];
  int i, k;
  B_init(&x, NULL, NULL);
  for (i = 0; i < NM; i++)
    for (k = 0; k < 3; k++) { /* B: x[2N], y[2N], z[2N], atom a of i at i, atom b at N + i */
      y[PER * i + k] = x.q[2 * NM * k + i];
      y[PER * i + 3 + k] = x.q[2 * NM * k + NM + i];
      y[PER * i + 6 + k] = x.p[2 * NM * k + i];
      y[PER * i + 9 + k] = x.p[2 * NM * k + NM + i];
    }
  gradient(y, f);
  for (i = 0; i < NM; i++) {
    double *m = y + PER * i, *md = yd + PER * i, vv = 0, df = 0, dd = 0;
    for (k = 0; k < 3; k++) {
      double d = m[k] - m[3 + k], v = m[6 + k] - m[9 + k];
      vv += v * v;
      df += d * (f[6 * i + k] - f[6 * i + 3 + k]);
      dd += d * d;
    }
    m[12] = (2 * vv - 2 * df) / (8 * dd);
    m[13] = 0;
    for (k = 0; k < 3; k++) {
      double d = m[k] - m[3 + k];
      md[k] = m[6 + k];
      md[3 + k] = m[9 + k];
      md[6 + k] = -f[6 * i + k] - 2 * d * m[12];
      md[9 + k] = -f[6 * i + 3 + k] + 2 * d * m[12];
    }
    md[12] = md[13] = 0;
  }
}

/* B's (q, p) from IDA's y. */
static void qp_of(const double *y, double *q, double *p)
{
  int i, k;
  for (i = 0; i < NM; i++)
    for (k = 0; k < 3; k++) {
      q[2 * NM * k + i] = y[PER * i + k];
      q[2 * NM * k + NM + i] = y[PER * i + 3 + k];
      p[2 * NM * k + i] = y[PER * i + 6 + k];
      p[2 * NM * k + NM + i] = y[PER * i + 9 + k];
    }
}

/* IDA from the consistent initial state to T at tol: (q, p) at T. */
static int run_ida(double T, double tol, double *q, double *p, long *steps)
{
  static double y[PER * NM], yd[PER * NM], w[2 * PER * NM];
  IdaSystem sys = {PER * NM, 0, residual, NULL, tol, NULL, NULL, NULL, NULL};
  initial(y, yd);
  if (ida_vs_run(&sys, PER, 12, ALG_ATOL, w, y, yd, T, steps)) return 1;
  qp_of(y, q, p);
  return 0;
}

int main(int argc, char **argv)
{
  static const IdaVs v = {"ida_cluster", "ida_dense", NM, B_M, REF_H, REF_TOL, run_rolled, run_ida};
  return ida_vs_main(&v, argc, argv);
}
