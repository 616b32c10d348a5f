/* solvers.h - the committed generated solvers (generated/LIST) behind one
 * interface, so tests can run any of them by name. */
#ifndef HBVM_TESTS_SOLVERS_H
#define HBVM_TESTS_SOLVERS_H

#include <stddef.h>

typedef struct {
  const char *name;      /* e.g. "pendulum_k2s2" */
  int m, nu, k, s;
  size_t state_size;
  size_t off_t, off_q, off_p, off_lambda;
  void (*init)(void *x, const double *q0, const double *p0);
  int (*step)(void *x, double h, int *iters);
  double (*energy)(const void *x);
  void (*constraints)(const void *x, double *g);
  void (*hidden)(const void *x, double *hc);
} Solver;

/* The solver of that name, or NULL. */
const Solver *solver_find(const char *name);
/* The solver for model (e.g. "pendulum") at (k, s), or NULL. */
const Solver *solver_for(const char *model, int k, int s);

/* Views into an opaque state. */
double *solver_t(const Solver *sv, void *x);
double *solver_q(const Solver *sv, void *x);
double *solver_p(const Solver *sv, void *x);
double *solver_lambda(const Solver *sv, void *x);

#endif
