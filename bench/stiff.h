/* stiff.h - the stiff benchmark problems (issue 27), hand-written from
 * models/fpu.ham, models/stiff_bob.ham and models/butane.ham, with what the
 * other problems do not need: the fastest frequency omega (for h omega),
 * the slow motion the error is measured on (the fast phase is not resolved
 * at h omega >> 1, and is not what a user of a long step asks for), and the
 * Hessian of U for the GSL implicit steppers (problems without constraints).
 *
 *   fpu50, fpu1000   the FPU chain at omega = 50, 1000; slow: x0 and its
 *                    momenta (the stiff springs' centres)
 *   stiff_bob        the stiff two-mass bob, k = 1e4 (omega = 141), and
 *   stiff_bob6       k = 1e6 (omega = 1414); slow: the bob's centre of mass
 *                    and total momentum
 *   butane           the molecule, ka = 1e4 (omega = 175); slow: the
 *                    dihedral angle */
#ifndef BENCH_STIFF_H
#define BENCH_STIFF_H

#include "problems.h"

#define STIFF_MAXSLOW 6

typedef struct {
  const Problem *pb;
  double omega;
  /* the slow quantities at (q, p); returns how many (<= STIFF_MAXSLOW) */
  int (*slow)(const double *q, const double *p, double *out);
  /* H[i*m + j] = d^2 U / dq_i dq_j; NULL where not needed (constraints) */
  void (*hess)(const double *q, double *H);
} Stiff;

/* The stiff problem of that name, or NULL. */
const Problem *stiff_problem_find(const char *name);

/* The stiff extras of pb, or NULL for the other problems. */
const Stiff *stiff_find(const Problem *pb);

#endif
