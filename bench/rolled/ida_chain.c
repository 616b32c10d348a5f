/* ida_chain.c - the chain of N pendula (models/chain8.ham with N bodies) in
 * the rolled solver B (bench/rolled/ida.sh generates B.h/B.c with
 * --rolled on) against SUNDIALS IDA with a banded linear solver.
 *
 * IDA integrates the stabilised index-2 (GGL) form of bench/ida.c, with the
 * unknowns ordered per body, body i = (x_i, y_i, px_i, py_i, lambda_i,
 * mu_i) where lambda_i, mu_i belong to link i (body i against body i-1, or
 * the hinge): every equation of body i involves only bodies i-1, i, i+1, so
 * the Jacobian is banded with half-bandwidth 11 (SUNBandMatrix,
 * SUNLinSol_Band, IDA's difference-quotient Jacobian: 23 residuals each).
 * The chain starts at rest, stretched out horizontally, where the index-1
 * multiplier is 0 (no velocity, and gravity is normal to every link); so
 * lambda = mu = 0 and y' = (0, 0, 0, -1, 0, 0) per body are consistent.
 *
 * Usage: ida_chain T h,h,... reps tol,tol,... (ida_vs.h: the runs, the
 * reference and the CSV rows). */
#include <string.h>

#include <nvector/nvector_serial.h>

#include "ida_vs.h"
#include "rolled_run.h"

#define NB B_NU     /* bodies: one link each */
#define PER 6       /* unknowns per body */
#define BAND 11     /* mupper = mlower */
#define ALG_ATOL 1e-3
/* The reference's step: Richardson from REF_H / 4 and REF_H / 8. Not
 * smaller: at N = 1000 the Richardson value from h = 0.0005 (B at 6e-5 and
 * 1.2e-4) was 2e-6 off both B at h = 0.0005 and IDA at 1e-10, which agree
 * with the one from 0.0025 to 1e-7 (presumably B's round-off, kicked into p
 * by 1 / h every step). Its distance to IDA at REF_TOL: 7e-11 (N = 8) to
 * 5e-8 (N = 1000), the limit of the errors measured. */
#define REF_H 0.0025
#define REF_TOL 1e-12

/* Link i of body's components c, c + 1 of y (c = 0: position, c = 2:
 * momentum) in d[0..1]: body i minus body i - 1 (the hinge at rest at 0). */
static void link_of(const double *y, int i, int c, double *d)
{
  d[0] = y[PER * i + c] - (i ? y[PER * (i - 1) + c] : 0);
  d[1] = y[PER * i + c + 1] - (i ? y[PER * (i - 1) + c + 1] : 0);
}

/* F(t, y, y') of the GGL system, per body (see the top). */
static int residual(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *user_data)
{
  const double *y = N_VGetArrayPointer(yy), *yd = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr);
  double d[2], v[2], dn[2] = {0, 0};
  int i, c;
  (void)t;
  (void)user_data;
  for (i = 0; i < NB; i++) {
    const double *b = y + PER * i, *bd = yd + PER * i;
    double lamn = 0, mun = 0, *rb = r + PER * i;
    link_of(y, i, 0, d);
    link_of(y, i, 2, v);
    if (i + 1 < NB) {
      link_of(y, i + 1, 0, dn);
      lamn = b[PER + 4];
      mun = b[PER + 5];
    }
    for (c = 0; c < 2; c++) { /* grad g of links i and i + 1 at body i: 2 d, -2 dn */
      double gmu = 2 * (d[c] * b[5] - dn[c] * mun), glam = 2 * (d[c] * b[4] - dn[c] * lamn);
      rb[c] = bd[c] - (b[2 + c] - gmu);
      rb[2 + c] = bd[2 + c] + (c == 1) + glam;
    }
    rb[4] = d[0] * d[0] + d[1] * d[1] - 1;
    rb[5] = 2 * (d[0] * v[0] + d[1] * v[1]);
  }
  return 0;
}

/* B's (q, p) from IDA's y: q = (x_1..x_N, y_1..y_N), p alike. */
static void qp_of(const double *y, double *q, double *p)
{
  int i;
  for (i = 0; i < NB; i++) {
    q[i] = y[PER * i];
    q[NB + i] = y[PER * i + 1];
    p[i] = y[PER * i + 2];
    p[NB + i] = y[PER * i + 3];
  }
}

/* IDA from the consistent initial state to T at tol: (q, p) at T. */
static int run_ida(double T, double tol, double *q, double *p, long *steps)
{
  static double y[PER * NB], yd[PER * NB], w[2 * PER * NB];
  IdaSystem sys = {PER * NB, BAND, residual, NULL, tol, NULL, NULL, NULL, NULL};
  int i;
  for (i = 0; i < PER * NB; i++) {
    y[i] = i % PER == 0 ? i / PER + 1 : 0;
    yd[i] = i % PER == 3 ? -1 : 0;
  }
  if (ida_vs_run(&sys, PER, 4, ALG_ATOL, w, y, yd, T, steps)) return 1;
  qp_of(y, q, p);
  return 0;
}

int main(int argc, char **argv)
{
  static const IdaVs v = {"ida_chain", "ida_band", NB, B_M, REF_H, REF_TOL, run_rolled, run_ida};
  return ida_vs_main(&v, argc, argv);
}
