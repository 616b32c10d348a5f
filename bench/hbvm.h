/* hbvm.h - a generated solver behind a uniform interface.
 *
 * bench/run.sh generates NAME_kKsS.c/.h (hbvmgen --multiplier const) and
 * NAME_kKsSpoly.c/.h (--multiplier poly) into build/bench/gen, compiles
 * bench/hbvm_gen.c once per solver (-DSOLVER=NAME_kKsS[poly]) to get its
 * GenSolver, and writes the table gen_solvers[] of all of them. */
#ifndef BENCH_HBVM_H
#define BENCH_HBVM_H

#include <stddef.h>

typedef struct {
  const char *name; /* NAME_kKsS or NAME_kKsSpoly */
  int m, nu, k, s;
  size_t size;      /* of the solver's state */
  void (*init)(void *x, const double *q0, const double *p0);
  int (*step)(void *x, double h, int *iters); /* the solver's return code */
  /* NAME_step_adaptive: a step of at most *h within tol; *h the next one,
   * *taken the step taken, *iters the sweeps of all tries */
  int (*adaptive)(void *x, double *h, double tol, double *taken, int *iters);
  void (*get)(const void *x, double *q, double *p);
} GenSolver;

/* Every generated solver of the build, NULL-terminated (registry.c, written
 * by bench/run.sh). */
extern const GenSolver *const gen_solvers[];

/* The multiplier family a solver was generated with (hbvmgen --multiplier),
 * or GEN_NEWTON: --iteration newton --multiplier const (NAME_kKsSnewton), or
 * GEN_POLYNEWTON: --iteration newton, the poly family (NAME_kKsSpolynewton). */
typedef enum { GEN_CONST, GEN_POLY, GEN_NEWTON, GEN_POLYNEWTON } GenFamily;

/* The generated solver for problem at (k, s) of that family, or NULL. */
const GenSolver *gen_solver_find(const char *problem, int k, int s, GenFamily family);

#endif
