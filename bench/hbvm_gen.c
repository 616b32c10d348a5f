/* hbvm_gen.c - the GenSolver of one generated solver. Compiled once per
 * solver with -DSOLVER=NAME_kKsS -DSOLVER_H='"NAME_kKsS.h"'; defines the
 * object NAME_kKsS_bench. The step is the generated one, unchanged: this
 * file only adapts its signature. */
#include <string.h>

#include "hbvm.h"
#include SOLVER_H

#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
#define STR_(a) #a
#define STR(a) STR_(a)
#define F(suffix) CAT(SOLVER, suffix)

static void init(void *x, const double *q0, const double *p0) { F(_init)(x, q0, p0); }

static int step(void *x, double h, int *iters)
{
  F(_stats) st;
  int rc = F(_step)(x, h, NULL, &st);
  *iters = st.iters;
  return rc;
}

static int adaptive(void *x, double *h, double tol, double *taken, int *iters)
{
  F(_stats) st;
  int rc = F(_step_adaptive)(x, h, tol, NULL, &st);
  *taken = st.h;
  *iters = st.iters;
  return rc;
}

static void get(const void *x, double *q, double *p)
{
  const F(_state) *st = x;
  memcpy(q, st->q, sizeof st->q);
  memcpy(p, st->p, sizeof st->p);
}

const GenSolver F(_bench) = {STR(SOLVER), F(_M), F(_NU), F(_K), F(_S), sizeof(F(_state)), init, step, adaptive,
                              get};
