/* fourbar.c - the four-bar linkage in its angles (models/fourbar_angles.ham:
 * M(q), two constraints) against its natural coordinates
 * (bench/mq/fourbar_cartesian.ham: constant M, three constraints), fixed
 * steps h = T/N, N a factor 10^(1/8) apart. The error is the max-norm error
 * at T of the tips of the crank and the rocker (both forms have them) against
 * rk8pd at 1e-14 on the index-1 ODE in the angles (fourbar_ode.h); the time
 * of a point is the median of ROUNDS CPU times taken in turns (every point
 * once a round), each at least MIN_SEC long. Prints the points as CSV, then
 * each solver's time at an error of 1e-10 and 1e-12 (log-log between the two
 * points that bracket it) and the ratio angles / natural per s. fourbar.sh
 * generates solvers.def (S(name, form, s), form 0 angles, 1 natural) and
 * solvers.h. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include "fourbar_ode.h"

#include "solvers.h"

#define T_END 10.0
#define ROUNDS 7
#define MIN_SEC 0.004
#define NPTS 24

typedef struct {
  const char *name;
  int form, s;
  int (*run)(int n, double *tips); /* n steps to T_END from the model's start: the tips (4) */
} Solver;

// The tips B (crank) and C (rocker) from the angles.
static void angle_tips(const double *q, double *tips) {
  tips[0] = L1 * cos(q[0]);
  tips[1] = L1 * sin(q[0]);
  tips[2] = L0 + L3 * cos(q[2]);
  tips[3] = L3 * sin(q[2]);
}

#define S(P, form, s)                                                   \
  static int P##_run(int n, double *tips) {                             \
    P##_state x;                                                        \
    double q[P##_M];                                                    \
    P##_init(&x, 0, 0);                                                 \
    for (int k = 0; k < n; k++)                                         \
      if (P##_step(&x, T_END / n, 0, 0)) return 1;                      \
    for (int i = 0; i < P##_M; i++) q[i] = x.q[i];                      \
    if (form == 0) angle_tips(q, tips);                                 \
    else                                                                \
      for (int i = 0; i < 4; i++) tips[i] = q[i];                       \
    return 0;                                                           \
  }
#include "solvers.def"
#undef S
#define S(P, form, s) {#P, form, s, P##_run},
static const Solver solvers[] = {
#include "solvers.def"
};
#undef S
enum { NSOLV = sizeof solvers / sizeof solvers[0] };

static double cpu(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

// The time at error level e, log-log between the bracketing points; NAN if none.
static double time_at(const double *err, const double *t, int n, double e) {
  for (int i = 0; i + 1 < n; i++)
    if (err[i] >= e && err[i + 1] <= e && err[i] > err[i + 1]) {
      double f = log(e / err[i]) / log(err[i + 1] / err[i]);
      return exp(log(t[i]) + f * log(t[i + 1] / t[i]));
    }
  return NAN;
}

// The time of one solver's line at error level e: time_at over its timed
// points (tm not NaN; err and tm NPTS long).
static double line_time_at(const double *err, const double *tm, double e) {
  double e1[NPTS], t1[NPTS];
  int n = 0;
  for (int j = 0; j < NPTS; j++)
    if (!isnan(tm[j])) {
      e1[n] = err[j];
      t1[n++] = tm[j];
    }
  return time_at(e1, t1, n, e);
}

int main(void) {
  static double err[NSOLV][NPTS], tm[NSOLV][NPTS], samples[NSOLV][NPTS][ROUNDS];
  static int nn[NPTS], reps[NSOLV][NPTS];
  double q[3] = {1.2, 0, 0}, p[3] = {0, 0, 0}, ref[4], t0 = 0, y[6];
  /* the start from the angles model's q0 (the loop closed at th1 = 1.2) */
  {
    double bx = L1 * cos(1.2), by = L1 * sin(1.2), d = sqrt((L0 - bx) * (L0 - bx) + by * by);
    q[1] = atan2(-by, L0 - bx) + acos((L2 * L2 + d * d - L3 * L3) / (2 * L2 * d));
    q[2] = atan2(by + L2 * sin(q[1]), bx + L2 * cos(q[1]) - L0);
  }
  for (int i = 0; i < 3; i++) {
    y[i] = q[i];
    y[3 + i] = p[i];
  }
  double H0 = energy(q, p);
  gsl_odeiv2_system sys = {fourbar_rhs, NULL, 6, NULL};
  gsl_odeiv2_driver *dr = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-4, 1e-14, 1e-14);
  if (gsl_odeiv2_driver_apply(dr, &t0, T_END, y) != GSL_SUCCESS) return 1;
  gsl_odeiv2_driver_free(dr);
  angle_tips(y, ref);
  fprintf(stderr, "reference: |H(T) - H0| = %.1e\n", fabs(energy(y, y + 3) - H0));
  for (int j = 0; j < NPTS; j++) nn[j] = (int)lround(20 * pow(10, j / 8.0));
  for (int v = 0; v < NSOLV; v++)
    for (int j = 0; j < NPTS; j++) {
      double tips[4];
      err[v][j] = NAN;
      if (solvers[v].run(nn[j], tips)) continue;
      err[v][j] = 0;
      for (int i = 0; i < 4; i++) err[v][j] = fmax(err[v][j], fabs(tips[i] - ref[i]));
      double c0 = cpu();
      reps[v][j] = 1;
      solvers[v].run(nn[j], tips);
      double once = cpu() - c0;
      if (once < MIN_SEC) reps[v][j] = (int)ceil(MIN_SEC / fmax(once, 1e-7));
    }
  for (int r = 0; r < ROUNDS; r++) /* every point once a round, in turns */
    for (int j = 0; j < NPTS; j++)
      for (int v = 0; v < NSOLV; v++) {
        double tips[4], c0 = cpu();
        if (!(err[v][j] >= 3e-15 && err[v][j] <= 1e-8)) continue; /* only around the levels */
        for (int k = 0; k < reps[v][j]; k++) solvers[v].run(nn[j], tips);
        samples[v][j][r] = (cpu() - c0) / reps[v][j];
      }
  printf("solver,form,s,N,error,time_s\n");
  for (int v = 0; v < NSOLV; v++)
    for (int j = 0; j < NPTS; j++) {
      tm[v][j] = NAN;
      if (!(err[v][j] >= 3e-15 && err[v][j] <= 1e-8)) continue;
      qsort(samples[v][j], ROUNDS, sizeof(double), cmp);
      tm[v][j] = samples[v][j][ROUNDS / 2];
      printf("%s,%s,%d,%d,%.3e,%.4e\n", solvers[v].name, solvers[v].form ? "natural" : "angles", solvers[v].s, nn[j],
             err[v][j], tm[v][j]);
    }
  for (int v = 0; v < NSOLV; v++) {
    printf("# %s: time at 1e-10 %.3e s, at 1e-12 %.3e s\n", solvers[v].name, line_time_at(err[v], tm[v], 1e-10),
           line_time_at(err[v], tm[v], 1e-12));
    for (int w = 0; w < NSOLV; w++) { /* the ratio angles / natural at the same s */
      if (solvers[v].form != 0 || solvers[w].form != 1 || solvers[w].s != solvers[v].s) continue;
      printf("# s=%d: angles / natural at equal error: %.2f at 1e-10, %.2f at 1e-12\n", solvers[v].s,
             line_time_at(err[v], tm[v], 1e-10) / line_time_at(err[w], tm[w], 1e-10),
             line_time_at(err[v], tm[v], 1e-12) / line_time_at(err[w], tm[w], 1e-12));
    }
  }
  return 0;
}
