/* solvers.c - adapters from the typed interface of each generated solver
 * (NAME_step(NAME_state *, ...)) to the untyped Solver table of solvers.h. */
#include <stdio.h>
#include <string.h>

#include "solvers.h"

#include "conical_k1s1.h"
#include "conical_k2s2.h"
#include "conical_k3s3.h"
#include "conical_k4s4.h"
#include "modified_k3s1.h"
#include "modified_k6s2.h"
#include "modified_k9s3.h"
#include "pendulum_k1s1.h"
#include "pendulum_k2s2.h"
#include "pendulum_k3s3.h"
#include "satellites_k6s1.h"
#include "satellites_k6s2.h"
#include "satellites_k6s3.h"
#include "kepler_k1s1.h"
#include "kepler_k2s2.h"
#include "kepler_k3s3.h"
#include "kepler_k6s1.h"
#include "kepler_k6s2.h"
#include "kepler_k6s3.h"
#include "kepler_k16s2.h"
#include "kepler_k4s4.h"
#include "henon_heiles_k2s2.h"
#include "henon_heiles_k3s2.h"
#include "pendulum_poly_k1s1.h"
#include "pendulum_poly_k2s2.h"
#include "pendulum_poly_k3s3.h"
#include "pendulum_poly_k4s4.h"
#include "double_pendulum_k2s2.h"
#include "double_pendulum_k3s3.h"
#include "double_pendulum_k4s4.h"
#include "double_pendulum_const_k2s2.h"
#include "double_pendulum_const_k4s4.h"
#include "conical_poly_k2s2.h"
#include "modified_poly_k6s2.h"
#include "modified_poly_k9s3.h"
#include "satellites_poly_k6s2.h"
#include "satellites_poly_k6s3.h"

#define SOLVERS(X)                                                                                          \
  X(pendulum_k1s1) X(pendulum_k2s2) X(pendulum_k3s3) X(conical_k1s1) X(conical_k2s2) X(conical_k3s3)       \
  X(conical_k4s4) X(modified_k3s1) X(modified_k6s2) X(modified_k9s3) X(satellites_k6s1) X(satellites_k6s2) \
  X(satellites_k6s3) X(kepler_k1s1) X(kepler_k2s2) X(kepler_k3s3) X(kepler_k6s1) X(kepler_k6s2) X(kepler_k6s3)   \
  X(kepler_k16s2) X(kepler_k4s4) X(henon_heiles_k2s2) X(henon_heiles_k3s2) X(pendulum_poly_k1s1) X(pendulum_poly_k2s2)               \
  X(pendulum_poly_k3s3) X(pendulum_poly_k4s4) X(double_pendulum_k2s2) X(double_pendulum_k3s3) X(double_pendulum_k4s4)    \
  X(double_pendulum_const_k2s2) X(double_pendulum_const_k4s4) X(conical_poly_k2s2) X(modified_poly_k6s2) X(modified_poly_k9s3)                        \
  X(satellites_poly_k6s2) X(satellites_poly_k6s3)

SOLVERS(SOLVER_ADAPT)

static const Solver solvers[] = {SOLVERS(SOLVER_ENTRY)};

const Solver *solver_find(const char *name) {
  for (size_t i = 0; i < sizeof solvers / sizeof solvers[0]; i++)
    if (!strcmp(solvers[i].name, name)) return &solvers[i];
  return NULL;
}

const Solver *solver_for(const char *model, int k, int s) {
  char name[64];
  snprintf(name, sizeof name, "%s_k%ds%d", model, k, s);
  return solver_find(name);
}

double *solver_t(const Solver *sv, void *x) { return (double *)((char *)x + sv->off_t); }
double *solver_q(const Solver *sv, void *x) { return (double *)((char *)x + sv->off_q); }
double *solver_p(const Solver *sv, void *x) { return (double *)((char *)x + sv->off_p); }
double *solver_lambda(const Solver *sv, void *x) { return (double *)((char *)x + sv->off_lambda); }
