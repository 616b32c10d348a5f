/* dpa_bench.c - the double pendulum in angles (models/double_pendulum_angles.ham,
 * M(q)) against GSL's rk8pd on the same ODE and against hbvmgen's Cartesian
 * form with two constraints (models/double_pendulum.ham, poly family): the
 * error of the mass positions at T = 10 against rk8pd at 1e-14, and the time
 * of a run, the median of R runs taken in turns (A/B alternating). Built and
 * run by bench/mq/run.sh, which generates the solvers. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include "dpa_ode.h"

#include "cart_k4s4.h"
#include "dpa3.h"
#include "dpa4.h"
#include "dpa4s.h"

#define T_END 10.0
#define R 7

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// The mass positions of the angles th.
static void positions(const double *th, double *x) {
  x[0] = sin(th[0]);
  x[1] = -cos(th[0]);
  x[2] = x[0] + sin(th[1]);
  x[3] = x[1] - cos(th[1]);
}

typedef struct {
  const char *name;
  double par;           /* tol or h */
  void (*run)(double par, double *x, long *steps); /* positions at T_END */
} Method;

static void run_rk8pd(double tol, double *x, long *steps) {
  gsl_odeiv2_system sys = {dpa_rhs, NULL, 4, NULL};
  gsl_odeiv2_driver *dr = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-3, tol, tol);
  double y[4] = {0.5, -0.3, 0, 0}, t = 0;
  gsl_odeiv2_driver_apply(dr, &t, T_END, y);
  *steps = (long)dr->n;
  gsl_odeiv2_driver_free(dr);
  positions(y, x);
}

#define HBVM_RUNS(P)                                                                \
  static void run_##P##_fixed(double h, double *x, long *steps) {                  \
    P##_state s;                                                                    \
    long n = lround(T_END / h);                                                     \
    P##_init(&s, 0, 0);                                                             \
    for (long i = 0; i < n; i++)                                                    \
      if (P##_step(&s, h, 0, 0)) abort();                                           \
    *steps = n;                                                                     \
    double th[2] = {s.q[0], s.q[1]};                                                \
    positions(th, x);                                                               \
  }                                                                                 \
  static void run_##P##_adaptive(double tol, double *x, long *steps) {             \
    P##_state s;                                                                    \
    double h = 0.1;                                                                 \
    long n = 0;                                                                     \
    P##_init(&s, 0, 0);                                                             \
    while (s.t < T_END - 1e-12) {                                                   \
      double hh = fmin(h, T_END - s.t);                                             \
      if (P##_step_adaptive(&s, &hh, tol, 0, 0)) abort();                           \
      h = hh;                                                                       \
      n++;                                                                          \
    }                                                                               \
    *steps = n;                                                                     \
    double th[2] = {s.q[0], s.q[1]};                                                \
    positions(th, x);                                                               \
  }
HBVM_RUNS(dpa3)
HBVM_RUNS(dpa4)
HBVM_RUNS(dpa4s)

static void run_cart_fixed(double h, double *x, long *steps) {
  cart_k4s4_state s;
  long n = lround(T_END / h);
  cart_k4s4_init(&s, 0, 0);
  for (long i = 0; i < n; i++)
    if (cart_k4s4_step(&s, h, 0, 0)) abort();
  *steps = n;
  memcpy(x, s.q, 4 * sizeof *x);
}

static void run_cart_adaptive(double tol, double *x, long *steps) {
  cart_k4s4_state s;
  double h = 0.1;
  long n = 0;
  cart_k4s4_init(&s, 0, 0);
  while (s.t < T_END - 1e-12) {
    double hh = fmin(h, T_END - s.t);
    if (cart_k4s4_step_adaptive(&s, &hh, tol, 0, 0)) abort();
    h = hh;
    n++;
  }
  *steps = n;
  memcpy(x, s.q, 4 * sizeof *x);
}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int main(void) {
  static const Method methods[] = {
      {"gsl-rk8pd angles tol", 1e-10, run_rk8pd},
      {"gsl-rk8pd angles tol", 1e-12, run_rk8pd},
      {"hbvm angles (3,3) fixed h", 0.05, run_dpa3_fixed},
      {"hbvm angles (3,3) fixed h", 0.025, run_dpa3_fixed},
      {"hbvm angles (3,3) adaptive tol", 1e-10, run_dpa3_adaptive},
      {"hbvm angles (4,4) fixed h", 0.1, run_dpa4_fixed},
      {"hbvm angles (4,4) fixed h", 0.05, run_dpa4_fixed},
      {"hbvm angles (4,4) adaptive tol", 1e-10, run_dpa4_adaptive},
      {"hbvm angles (4,4) adaptive tol", 1e-12, run_dpa4_adaptive},
      {"hbvm angles (20,4) fixed h", 0.1, run_dpa4s_fixed},
      {"hbvm angles (20,4) adaptive tol", 1e-10, run_dpa4s_adaptive},
      {"hbvm Cartesian poly (4,4) fixed h", 0.1, run_cart_fixed},
      {"hbvm Cartesian poly (4,4) fixed h", 0.05, run_cart_fixed},
      {"hbvm Cartesian poly (4,4) adaptive tol", 1e-10, run_cart_adaptive},
      {"hbvm Cartesian poly (4,4) adaptive tol", 1e-12, run_cart_adaptive},
  };
  enum { NM = sizeof methods / sizeof methods[0] };
  static double times[NM][R];
  double ref[4], x[4], err[NM];
  long steps[NM];
  run_rk8pd(1e-14, ref, &steps[0]);
  for (int r = 0; r < R; r++) /* in turns: each method once a round */
    for (int i = 0; i < NM; i++) {
      int reps = 0;
      double t0 = now(), t1;
      do {
        methods[i].run(methods[i].par, x, &steps[i]);
        reps++;
      } while ((t1 = now()) - t0 < 0.02);
      times[i][r] = (t1 - t0) / reps;
      err[i] = 0;
      for (int c = 0; c < 4; c++) err[i] = fmax(err[i], fabs(x[c] - ref[c]));
    }
  printf("%-40s %8s %10s %7s %10s\n", "method", "param", "error", "steps", "time (us)");
  for (int i = 0; i < NM; i++) {
    qsort(times[i], R, sizeof times[i][0], cmp);
    printf("%-40s %8.0e %10.2e %7ld %10.1f\n", methods[i].name, methods[i].par, err[i], steps[i], 1e6 * times[i][R / 2]);
  }
  return 0;
}
