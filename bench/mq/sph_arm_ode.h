/* sph_arm_ode.h - the spherical pendulum in its angles and the 3-link arm in
 * its joint angles as first-order ODEs for GSL, y = (q, p),
 *   q' = v = M(q)^-1 p,  p' = 1/2 v' (dM/dq_i) v - grad U,
 * with M, dM/dq and grad U the closed forms of tests/check_mq.c's references
 * (models/spherical_pendulum.ham: M = diag(1, sin(th)^2), U = -cos(th);
 * models/arm3.ham at its defaults: unit masses and lengths, gravity 1), and
 * their energies. For bench/mq/wp.c. */
#ifndef SPH_ARM_ODE_H
#define SPH_ARM_ODE_H

#include <math.h>
#include <stdlib.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>

/* y = (th, ph, p_th, p_ph): p_ph is conserved. */
static int sph_rhs(double t, const double *y, double *dy, void *par)
{
  double s = sin(y[0]), c = cos(y[0]), w = y[3] / (s * s);
  (void)t;
  (void)par;
  dy[0] = y[2];
  dy[1] = w;
  dy[2] = w * w * s * c - s;
  dy[3] = 0;
  return GSL_SUCCESS;
}

static double sph_energy(const double *y)
{
  double s = sin(y[0]);
  return 0.5 * (y[2] * y[2] + y[3] * y[3] / (s * s)) - cos(y[0]);
}

/* The arm's M = S' A S with A_ij = c_ij cos(f_i - f_j), linear in a12, a13,
 * a23 (c = 1) and with c = 0 its derivatives. */
static void arm_assemble(double a12, double a13, double a23, double c, double *M)
{
  double c11 = 7.0 / 3 * c, c22 = 4.0 / 3 * c, c33 = 1.0 / 3 * c;
  double m33 = c33, m23 = a23 + c33, m22 = c22 + 2 * a23 + c33, m13 = a13 + a23 + c33;
  double m12 = a12 + a13 + c22 + 2 * a23 + c33, m11 = c11 + c22 + c33 + 2 * (a12 + a13 + a23);
  M[0] = m11, M[1] = m12, M[2] = m13;
  M[3] = m12, M[4] = m22, M[5] = m23;
  M[6] = m13, M[7] = m23, M[8] = m33;
}

/* v = M(q)^-1 p by GSL's Cholesky (M is symmetric positive definite); M
 * left in Mq. */
static void arm_velocity(const double *q, const double *p, double *Mq, double *v)
{
  double L[9];
  arm_assemble(1.5 * cos(q[1]), 0.5 * cos(q[1] + q[2]), 0.5 * cos(q[2]), 1, Mq);
  for (int i = 0; i < 9; i++) L[i] = Mq[i];
  gsl_matrix_view A = gsl_matrix_view_array(L, 3, 3);
  gsl_vector_const_view b = gsl_vector_const_view_array(p, 3);
  gsl_vector_view x = gsl_vector_view_array(v, 3);
  if (gsl_linalg_cholesky_decomp1(&A.matrix) || gsl_linalg_cholesky_solve(&A.matrix, &b.vector, &x.vector)) abort();
}

static int arm_rhs(double t, const double *y, double *dy, void *par)
{
  double M[9], dM[18], v[3];
  double s1 = sin(y[0]), s12 = sin(y[0] + y[1]), s123 = sin(y[0] + y[1] + y[2]);
  (void)t;
  (void)par;
  arm_velocity(y, y + 3, M, v);
  arm_assemble(-1.5 * sin(y[1]), -0.5 * sin(y[1] + y[2]), 0, 0, dM); /* dM/dq2 (dM/dq1 = 0) */
  arm_assemble(0, -0.5 * sin(y[1] + y[2]), -0.5 * sin(y[2]), 0, dM + 9);
  double vdv[2] = {0, 0};
  for (int i = 0; i < 2; i++)
    for (int a = 0; a < 3; a++)
      for (int c = 0; c < 3; c++) vdv[i] += v[a] * dM[9 * i + 3 * a + c] * v[c];
  dy[0] = v[0], dy[1] = v[1], dy[2] = v[2];
  dy[3] = -(2.5 * s1 + 1.5 * s12 + 0.5 * s123);
  dy[4] = 0.5 * vdv[0] - (1.5 * s12 + 0.5 * s123);
  dy[5] = 0.5 * vdv[1] - 0.5 * s123;
  return GSL_SUCCESS;
}

static double arm_energy(const double *y)
{
  double M[9], v[3];
  arm_velocity(y, y + 3, M, v);
  return 0.5 * (y[3] * v[0] + y[4] * v[1] + y[5] * v[2]) -
         (2.5 * cos(y[0]) + 1.5 * cos(y[0] + y[1]) + 0.5 * cos(y[0] + y[1] + y[2]));
}

#endif
