/* bench.h - what every method of the benchmark implements, and the pieces
 * the driver shares between them.
 *
 * A fixed-step method (hbvm, hbvm-poly, hbvm-generic, rattle) opens a Stepper on a
 * problem at its initial values; fixedstep_run() then takes the steps and
 * watches the invariants, the same loop for all of them. An adaptive method
 * (ida, gsl-rk8pd, gsl-rk4imp, hbvm-adaptive, hbvm-poly-adaptive) integrates
 * to the final time itself. */
#ifndef BENCH_BENCH_H
#define BENCH_BENCH_H

#include "problems.h"

/* One run of a method on a problem. */
typedef struct {
  const Problem *pb;
  int k, s;     /* HBVM(k,s); 0 for the other methods */
  double h;     /* fixed-step methods: the step, T = nsteps * h */
  long nsteps;
  double tol;   /* adaptive methods: absolute and relative tolerance */
  double T;     /* final time */
} Setting;

/* What a run leaves: the solution at T and its cost in steps and
 * iterations (fixed-point or Newton; 0 where there are none). */
typedef struct {
  double q[BENCH_MAXM], p[BENCH_MAXM];
  long steps, iters;
  int itmax;
} Outcome;

/* One step of a fixed-step method from the state it keeps. */
typedef struct {
  void *state;
  int (*step)(void *state, double h, int *iters); /* 0 on success */
  void (*get)(const void *state, double *q, double *p);
} Stepper;

typedef struct {
  const char *name; /* the CSV's method column */
  /* fixed-step methods: allocate and initialise at (q0, p0) of set->pb;
   * 0 on success, -1 if the method does not apply (e.g. no generated
   * solver for that (k,s)) */
  int (*open)(const Setting *set, Stepper *sp);
  void (*close)(Stepper *sp);
  /* adaptive methods: integrate from 0 to set->T; ob may be NULL.
   * 0 on success, -1 if not applicable, -2 if the integration failed */
  int (*integrate)(const Setting *set, Observer *ob, Outcome *out);
} MethodDef;

/* The method of that name, or NULL (methods.c). */
const MethodDef *method_find(const char *name);

/* Run a method once: open/step/close or integrate. ob may be NULL (timed
 * runs); with an observer every step's (q, p) is checked. 0 on success,
 * -1 not applicable, -2 a step or the integrator failed. */
int method_run(const MethodDef *md, const Setting *set, Observer *ob, Outcome *out);

/* Take set->nsteps steps of size set->h (fixedstep.c). */
int fixedstep_run(const Stepper *sp, const Setting *set, Observer *ob, Outcome *out);

/* `bench ab` (abrun.c). */
int cmd_ab(int argc, char **argv);

/* The methods (one file each). */
int hbvm_open(const Setting *set, Stepper *sp);      /* --multiplier const */
int hbvm_poly_open(const Setting *set, Stepper *sp); /* --multiplier poly */
int hbvm_newton_open(const Setting *set, Stepper *sp); /* --iteration newton --multiplier const */
int hbvm_poly_newton_open(const Setting *set, Stepper *sp); /* --iteration newton, the poly family */
void hbvm_close(Stepper *sp);
int generic_open(const Setting *set, Stepper *sp);
void generic_close(Stepper *sp);
int rattle_open(const Setting *set, Stepper *sp);
void rattle_close(Stepper *sp);
int ida_integrate(const Setting *set, Observer *ob, Outcome *out);
int gsl_rk8pd_integrate(const Setting *set, Observer *ob, Outcome *out);
int gsl_rk4imp_integrate(const Setting *set, Observer *ob, Outcome *out);
int gsl_msbdf_integrate(const Setting *set, Observer *ob, Outcome *out); /* stiff problems without constraints */
int gsl_bsimp_integrate(const Setting *set, Observer *ob, Outcome *out);
int hbvm_adaptive_integrate(const Setting *set, Observer *ob, Outcome *out);      /* const */
int hbvm_poly_adaptive_integrate(const Setting *set, Observer *ob, Outcome *out); /* poly */

#endif
