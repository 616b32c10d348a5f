/* reference.h - the solution at the final time that errors are measured
 * against: exact where there is a closed form, otherwise an independent
 * high-accuracy run that is not an HBVM. */
#ifndef BENCH_REFERENCE_H
#define BENCH_REFERENCE_H

#include "problems.h"

/* Fill q[m], p[m] with the reference at T for pb; tol is the tolerance of
 * the integrator where one is used. how (size n) receives a one-line
 * description. 0 on success, -1 unknown problem, -2 integrator failure. */
int reference_final(const Problem *pb, double T, double tol, double *q, double *p, char *how, int n);

/* The index-1 reference integrator on any problem of problems.c (GSL
 * rk8pd at absolute and relative tolerance tol on q' = M^-1 p,
 * p' = -grad U - G lambda(q, p)), with the maxima of |g| and |H - H0| over
 * its steps in *dg, *dH (either may be NULL). */
int reference_index1(const Problem *pb, double T, double tol, double *q, double *p, double *dg, double *dH);

#endif
