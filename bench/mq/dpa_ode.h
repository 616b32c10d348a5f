/* dpa_ode.h - the double pendulum in its two rod angles as a first-order ODE
 * for GSL, y = (th1, th2, p1, p2): H = p' M(q)^-1 p / 2 - 2 cos th1 - cos th2,
 * M = [[2, c], [c, 1]], c = cos(th1 - th2) (models/double_pendulum_angles.ham).
 * Shared by bench/mq/dpa_bench.c and bench/mq/wp.c. */
#ifndef DPA_ODE_H
#define DPA_ODE_H

#include <math.h>

#include <gsl/gsl_errno.h>

static int dpa_rhs(double t, const double *y, double *dy, void *par)
{
  double d = y[0] - y[1], c = cos(d), s = sin(d), det = 2 - c * c;
  double v1 = (y[2] - c * y[3]) / det, v2 = (2 * y[3] - c * y[2]) / det;
  (void)t;
  (void)par;
  dy[0] = v1;
  dy[1] = v2;
  dy[2] = -s * v1 * v2 - 2 * sin(y[0]);
  dy[3] = s * v1 * v2 - sin(y[1]);
  return GSL_SUCCESS;
}

#endif
