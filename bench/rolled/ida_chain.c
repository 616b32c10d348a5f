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
 * Usage: ida_chain T h,h,... reps tol,tol,...
 * B takes T / h steps of each h; IDA runs to T at each tolerance tol
 * (relative and absolute on q, p; ALG_ATOL on the multipliers, as
 * bench/ida.c). The runs alternate reps times (B at each h, then IDA at
 * each tol), in CPU time, setup included; the medians are printed, one CSV
 * row per h and per tol:
 *   N,method,T,h_or_tol,steps,ns_step,us_per_time,err
 * (method rolled or ida_band; us_per_time: microseconds of CPU a unit of
 * simulated time). err is the max norm of (q, p) at T against a reference:
 * B is of order 2 with --multiplier const (docs/api.md), so the reference
 * is Richardson's (4 B(h/8) - B(h/4)) / 3 at h = REF_H; its distance to IDA
 * at REF_TOL goes to stderr. Exits 1 if a run fails. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <nvector/nvector_serial.h>

#include "B.h"
#include "ida_run.h"
#include "linalg.h"
#include "timing.h"

#define NB B_NU     /* bodies: one link each */
#define PER 6       /* unknowns per body */
#define BAND 11     /* mupper = mlower */
#define ALG_ATOL 1e-3
#define MAXREPS 64
#define MAXTOLS 8
#define MAXH 8
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

/* B from the model's initial state, n steps of h: (q, p) at the end. */
static int run_rolled(double h, long n, double *q, double *p)
{
  static B_state x;
  long k;
  int bad = 0;
  B_init(&x, NULL, NULL);
  for (k = 0; k < n; k++) bad |= B_step(&x, h, NULL, NULL);
  memcpy(q, x.q, sizeof x.q);
  memcpy(p, x.p, sizeof x.p);
  return bad;
}

/* IDA from the consistent initial state to T at tol: (q, p) at T. */
static int run_ida(double T, double tol, double *q, double *p, long *steps)
{
  static double y[PER * NB], yd[PER * NB], id[PER * NB], atol[PER * NB];
  IdaSystem sys = {PER * NB, BAND, residual, NULL, tol, atol, id, NULL, NULL};
  int i;
  memset(yd, 0, sizeof yd);
  for (i = 0; i < PER * NB; i++) {
    y[i] = i % PER == 0 ? i / PER + 1 : 0;
    yd[i] = i % PER == 3 ? -1 : 0;
    id[i] = i % PER < 4;
    atol[i] = i % PER < 4 ? tol : ALG_ATOL;
  }
  if (ida_run(&sys, y, yd, T, 10000000, steps) != 0) return 1;
  qp_of(y, q, p);
  return 0;
}

/* The max norm of (q, p) - (qr, pr). */
static double error_of(const double *q, const double *p, const double *qr, const double *pr)
{
  double eq = maxdiff(B_M, q, qr), ep = maxdiff(B_M, p, pr);
  return eq > ep ? eq : ep;
}

/* Parse up to max numbers separated by commas from s into v; their count. */
static int numbers(const char *s, double *v, int max)
{
  int k = 0;
  char *end;
  while (k < max) {
    v[k++] = strtod(s, &end);
    if (*end != ',') break;
    s = end + 1;
  }
  return k;
}

int main(int argc, char **argv)
{
  static double q[B_M], p[B_M], qr[B_M], pr[B_M], qh[B_M], ph[B_M], tr[MAXH][MAXREPS], ti[MAXTOLS][MAXREPS];
  double T, hs[MAXH], tol[MAXTOLS], er[MAXH], e[MAXTOLS], t0;
  long n[MAXH], steps[MAXTOLS];
  int reps, nh, ntol, r, j, k;
  if (argc != 5) {
    fprintf(stderr, "usage: ida_chain T h,... reps tol,...\n");
    return 2;
  }
  T = atof(argv[1]);
  nh = numbers(argv[2], hs, MAXH);
  reps = atoi(argv[3]);
  ntol = numbers(argv[4], tol, MAXTOLS);
  if (reps < 1 || reps > MAXREPS) reps = MAXREPS;
  for (k = 0; k < nh; k++) n[k] = (long)(T / hs[k] + 0.5);
  /* the reference: Richardson on B's order 2 from REF_H / 4 and REF_H / 8,
   * checked against IDA at REF_TOL (on stderr) */
  if (run_rolled(REF_H / 8, (long)(8 * T / REF_H + 0.5), qr, pr) ||
      run_rolled(REF_H / 4, (long)(4 * T / REF_H + 0.5), qh, ph))
    goto failed;
  for (j = 0; j < B_M; j++) {
    qr[j] += (qr[j] - qh[j]) / 3;
    pr[j] += (pr[j] - ph[j]) / 3;
  }
  if (run_ida(T, REF_TOL, qh, ph, &steps[0])) goto failed;
  fprintf(stderr, "ida_chain: N = %d: the reference against IDA at %g: %.2g\n", NB, REF_TOL,
          error_of(qh, ph, qr, pr));
  for (k = 0; k < nh; k++) {
    if (run_rolled(hs[k], n[k], q, p)) goto failed;
    er[k] = error_of(q, p, qr, pr);
  }
  for (j = 0; j < ntol; j++) {
    if (run_ida(T, tol[j], q, p, &steps[j])) goto failed;
    e[j] = error_of(q, p, qr, pr);
  }
  for (r = 0; r < reps; r++) {
    for (k = 0; k < nh; k++) {
      t0 = cpu_seconds();
      if (run_rolled(hs[k], n[k], q, p)) goto failed;
      tr[k][r] = cpu_seconds() - t0;
    }
    for (j = 0; j < ntol; j++) {
      t0 = cpu_seconds();
      if (run_ida(T, tol[j], q, p, &steps[j])) goto failed;
      ti[j][r] = cpu_seconds() - t0;
    }
  }
  for (k = 0; k < nh; k++) {
    double m = median(tr[k], reps);
    printf("%d,rolled,%g,%g,%ld,%.1f,%.1f,%.2g\n", NB, T, hs[k], n[k], m / (double)n[k] * 1e9, m / T * 1e6, er[k]);
  }
  for (j = 0; j < ntol; j++) {
    double m = median(ti[j], reps);
    printf("%d,ida_band,%g,%g,%ld,%.1f,%.1f,%.2g\n", NB, T, tol[j], steps[j], m / (double)steps[j] * 1e9,
           m / T * 1e6, e[j]);
  }
  return 0;
failed:
  fprintf(stderr, "ida_chain: a run failed\n");
  return 1;
}
