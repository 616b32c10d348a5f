/* ida_run.c - one IDA integration (ida_run.h). */
#include "ida_run.h"

#include <string.h>

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_band.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_dense.h>

/* IDA's messages are not wanted: failures are reported by the caller. */
static void quiet(int error_code, const char *module, const char *function, char *msg, void *data)
{
  (void)error_code;
  (void)module;
  (void)function;
  (void)msg;
  (void)data;
}

/* A new serial vector holding v[0..n). */
static N_Vector vector_of(int n, const double *v, SUNContext ctx)
{
  N_Vector x = N_VNew_Serial(n, ctx);
  if (x) memcpy(N_VGetArrayPointer(x), v, (size_t)n * sizeof *v);
  return x;
}

int ida_run(const IdaSystem *sys, double *y, const double *yp, double T, long maxsteps, long *steps)
{
  static SUNContext ctx;
  int n = sys->n, rc = -2, flag = 0;
  void *mem;
  N_Vector yy, yd, id, atol;
  SUNMatrix A;
  SUNLinearSolver LS;
  realtype t = 0;
  long nst = 0;
  if (!ctx && SUNContext_Create(NULL, &ctx) != 0) return -2;
  yy = vector_of(n, y, ctx);
  yd = vector_of(n, yp, ctx);
  id = vector_of(n, sys->id, ctx);
  atol = vector_of(n, sys->atol, ctx);
  A = sys->band ? SUNBandMatrix(n, sys->band, sys->band, ctx) : SUNDenseMatrix(n, n, ctx);
  LS = !yy || !A ? NULL : sys->band ? SUNLinSol_Band(yy, A, ctx) : SUNLinSol_Dense(yy, A, ctx);
  mem = IDACreate(ctx);
  if (!yy || !yd || !id || !atol || !A || !LS || !mem) goto done;
  if (IDAInit(mem, sys->res, 0, yy, yd) != IDA_SUCCESS || IDASVtolerances(mem, sys->rtol, atol) != IDA_SUCCESS ||
      IDASetUserData(mem, sys->data) != IDA_SUCCESS || IDASetLinearSolver(mem, LS, A) != IDA_SUCCESS ||
      IDASetId(mem, id) != IDA_SUCCESS || IDASetSuppressAlg(mem, SUNTRUE) != IDA_SUCCESS ||
      IDASetStopTime(mem, T) != IDA_SUCCESS || IDASetMaxNumSteps(mem, 10000000) != IDA_SUCCESS ||
      IDASetErrHandlerFn(mem, quiet, NULL) != IDA_SUCCESS)
    goto done;
  while (flag != IDA_TSTOP_RETURN) {
    flag = IDASolve(mem, T, &t, yy, yd, IDA_ONE_STEP);
    if (flag < 0 || ++nst > maxsteps) goto done;
    if (sys->point) sys->point(sys->ob, N_VGetArrayPointer(yy));
  }
  IDAGetNumSteps(mem, steps);
  memcpy(y, N_VGetArrayPointer(yy), (size_t)n * sizeof *y);
  rc = 0;
done:
  IDAFree(&mem);
  SUNLinSolFree(LS);
  SUNMatDestroy(A);
  N_VDestroy(yy);
  N_VDestroy(yd);
  N_VDestroy(id);
  N_VDestroy(atol);
  return rc;
}
