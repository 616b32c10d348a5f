/* ida_vs.h - a rolled solver against SUNDIALS IDA on one model, the driver
 * the rolled benchmarks share (ida_chain.c: the chain, banded; ida_cluster.c:
 * the cluster, dense). The model's file supplies both runs; ida_vs_main
 * parses the command line, takes the reference, alternates the timed runs
 * and prints the CSV rows.
 *
 * Usage: PROG T h,h,... reps tol,tol,...
 * The rolled solver takes T / h steps of each h; IDA runs to T at each
 * tolerance tol. The runs alternate reps times (the rolled solver at each h,
 * then IDA at each tol), in CPU time, setup included; the medians are
 * printed, one CSV row per h and per tol:
 *   N,method,T,h_or_tol,steps,ns_step,us_per_time,err
 * (method "rolled" or the IDA label; us_per_time: microseconds of CPU a
 * unit of simulated time). err is the max norm of (q, p) at T against a
 * reference: the rolled solver is of order 2 with --multiplier const
 * (docs/api.md), so the reference is Richardson's (4 B(h/8) - B(h/4)) / 3
 * at h = ref_h; its distance to IDA at ref_tol goes to stderr (or that IDA
 * failed there: a check only). Returns 1 if a timed run fails, 2 on a bad
 * command line. */
#ifndef BENCH_ROLLED_IDA_VS_H
#define BENCH_ROLLED_IDA_VS_H

#include "ida_run.h"

typedef struct {
  const char *prog;  /* for messages */
  const char *label; /* the IDA rows' method: ida_band, ida_dense */
  int n;             /* the model's N, the rows' first field */
  int m;             /* coordinates: q and p have m each */
  double ref_h, ref_tol;
  /* the rolled solver from the model's initial state, n steps of h: (q, p); 0 or 1 (failed) */
  int (*rolled)(double h, long n, double *q, double *p);
  /* IDA from the consistent initial state to T at tol: (q, p) and its steps; 0 or 1 (failed) */
  int (*ida)(double T, double tol, double *q, double *p, long *steps);
} IdaVs;

int ida_vs_main(const IdaVs *v, int argc, char **argv);

/* ida_run (bench/ida_run.h) of the n = sys->n unknowns in blocks of per,
 * the first ndiff of a block differential (absolute tolerance sys->rtol),
 * the others algebraic (alg_atol, left out of the error test): fills w (2 n
 * reals) with sys's id and atol. 0, or 1 if IDA failed. */
int ida_vs_run(IdaSystem *sys, int per, int ndiff, double alg_atol, double *w, double *y, const double *yd, double T,
               long *steps);

#endif
