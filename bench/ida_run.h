/* ida_run.h - one SUNDIALS IDA integration of F(t, y, y') = 0 from a
 * consistent (y, y') at t = 0 to T, with a dense or a banded direct linear
 * solver and IDA's difference-quotient Jacobian. Shared by the method "ida"
 * (bench/ida.c, the paper's problems, dense) and the chain of N pendula of
 * the rolled benchmark (bench/rolled/ida_chain.c, banded). */
#ifndef BENCH_IDA_RUN_H
#define BENCH_IDA_RUN_H

#include <ida/ida.h>

typedef struct {
  int n;              /* unknowns */
  int band;           /* 0: dense; else mupper = mlower = band (SUNBandMatrix, SUNLinSol_Band) */
  IDAResFn res;       /* F(t, y, y') */
  void *data;         /* res's user_data */
  double rtol;        /* relative tolerance */
  const double *atol; /* n absolute tolerances */
  const double *id;   /* n: 1 differential, 0 algebraic (left out of the error test) */
  /* called after every step with y (may be NULL) */
  void (*point)(void *ob, const double *y);
  void *ob;
} IdaSystem;

/* Integrate sys from (y, yp) at t = 0 to T (IDA_ONE_STEP, stopping at T):
 * the state at T in y, the steps taken in *steps. The setup (IDA memory,
 * vectors, matrix, solver) is part of the call; only the SUNDIALS context
 * is made once. 0, or -2 if IDA failed or took more than maxsteps steps. */
int ida_run(const IdaSystem *sys, double *y, const double *yp, double T, long maxsteps, long *steps);

#endif
