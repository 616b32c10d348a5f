/* hbvm.c - the methods "hbvm" and "hbvm-poly": a generated solver, found by
 * problem, (k, s) and multiplier family among those bench/run.sh built
 * (NAME_kKsS: --multiplier const, the paper's method; NAME_kKsSpoly:
 * --multiplier poly, order 2s; NAME_kKsSnewton: --iteration newton
 * --multiplier const, the method "hbvm-newton" of the stiff benchmark;
 * NAME_kKsSpolynewton: --iteration newton in the poly family, the method
 * "hbvm-poly-newton"). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "hbvm.h"

const GenSolver *gen_solver_find(const char *problem, int k, int s, GenFamily family)
{
  char name[128];
  int i;
  static const char *const suffix[] = {"", "poly", "newton", "polynewton"}; /* by GenFamily */
  snprintf(name, sizeof name, "%s_k%ds%d%s", problem, k, s, suffix[family]);
  for (i = 0; gen_solvers[i]; i++)
    if (strcmp(gen_solvers[i]->name, name) == 0) return gen_solvers[i];
  return NULL;
}

/* The state of an open generated solver: which one, and its own state. */
typedef struct {
  const GenSolver *gs;
  void *x;
} Open;

static int open_step(void *state, double h, int *iters)
{
  Open *o = state;
  return o->gs->step(o->x, h, iters);
}

static void open_get(const void *state, double *q, double *p)
{
  const Open *o = state;
  o->gs->get(o->x, q, p);
}

static int open_family(const Setting *set, Stepper *sp, GenFamily family)
{
  const GenSolver *gs = gen_solver_find(set->pb->name, set->k, set->s, family);
  double q0[BENCH_MAXM], p0[BENCH_MAXM];
  Open *o;
  if (!gs || gs->m != set->pb->m || gs->nu != set->pb->nu) return -1;
  o = malloc(sizeof *o);
  if (!o || !(o->x = malloc(gs->size))) {
    free(o);
    return -1;
  }
  o->gs = gs;
  set->pb->init(q0, p0);
  gs->init(o->x, q0, p0);
  sp->state = o;
  sp->step = open_step;
  sp->get = open_get;
  return 0;
}

int hbvm_open(const Setting *set, Stepper *sp) { return open_family(set, sp, GEN_CONST); }

int hbvm_poly_open(const Setting *set, Stepper *sp) { return open_family(set, sp, GEN_POLY); }

int hbvm_newton_open(const Setting *set, Stepper *sp) { return open_family(set, sp, GEN_NEWTON); }

int hbvm_poly_newton_open(const Setting *set, Stepper *sp) { return open_family(set, sp, GEN_POLYNEWTON); }

void hbvm_close(Stepper *sp)
{
  Open *o = sp->state;
  free(o->x);
  free(o);
}
