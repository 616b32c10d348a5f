/* wp.c - work-precision lines in minimal coordinates against GSL's rk8pd on
 * the same ODE: the pendulum in its angle (models/pendulum_angle.ham, constant
 * M), the double pendulum in angles (models/double_pendulum_angles.ham, M(q)),
 * the spherical pendulum in its angles (models/spherical_pendulum.ham) and the
 * 3-link arm in its joint angles (models/arm3.ham), with the Cartesian forms of
 * three of them (the arm's bench/mq/arm3_cartesian.ham). Each generated solver
 * is run fixed (h = T/N) and adaptive
 * (NAME_step_adaptive at tol, the last step shortened to end on T, as
 * bench/hbvm_adaptive.c does); rk8pd adaptive at tol (epsabs = epsrel = tol,
 * as bench/gslpeers.c). The error is the max-norm error of (q, p) at T against
 * rk8pd at 1e-15 (the Cartesian form's state mapped to the angles, to_problem);
 * the time of a point is the median of ROUNDS CPU times taken
 * in turns (every timed point once a round), each at least MIN_SEC long.
 * Only the points whose error lies in [ERR_LO, ERR_HI] are timed (they bracket
 * 1e-10 and 1e-12). bench/mq/wp.sh generates the solvers and writes
 * solvers.def (S(name, problem, k, s, variant)) and solvers.h (their headers),
 * then bench/mq/ratios.awk interpolates the CSV this prints. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include "dpa_ode.h"
#include "sph_arm_ode.h"

#include "solvers.h"

#define T_END 10.0
#define ROUNDS 7
#define MIN_SEC 0.004
#define ERR_LO 2e-14
#define ERR_HI 3e-9
#define MAXPTS 4096
#ifndef BUILD
#define BUILD "cc"
#endif

enum { PA, DPA, SPH, ARM, NPROBLEMS };
static const char *const problem_name[] = {"pendulum_angle", "double_pendulum_angles", "spherical_pendulum",
                                           "arm3"};
static const int problem_m[] = {1, 2, 2, 3};
#define MAXD 6 /* the largest 2 m */

/* -------------------------------------------------------- the ODEs */

static int pa_rhs(double t, const double *y, double *dy, void *par)
{
  (void)t;
  (void)par;
  dy[0] = y[1];
  dy[1] = -sin(y[0]);
  return GSL_SUCCESS;
}

static gsl_odeiv2_system ode(int pb)
{
  static int (*const rhs[])(double, const double *, double *, void *) = {pa_rhs, dpa_rhs, sph_rhs, arm_rhs};
  gsl_odeiv2_system sys = {rhs[pb], NULL, (size_t)(2 * problem_m[pb]), NULL};
  return sys;
}

static double energy(int pb, const double *y)
{
  if (pb == PA) return 0.5 * y[1] * y[1] - cos(y[0]);
  if (pb == SPH) return sph_energy(y);
  if (pb == ARM) return arm_energy(y);
  double c = cos(y[0] - y[1]), det = 2 - c * c;
  double v1 = (y[2] - c * y[3]) / det, v2 = (2 * y[3] - c * y[2]) / det;
  return 0.5 * (y[2] * v1 + y[3] * v2) - 2 * cos(y[0]) - cos(y[1]);
}

/* The models' q0 and p0 (the spherical pendulum's also its Cartesian form's
 * start, cartesian_start). */
static void initial(int pb, double *y)
{
  static const double y0[][MAXD] = {{0, 1}, {0.5, -0.3, 0, 0}, {1, 0, 0, 0.5}, {1, -0.5, 0.8, 0, 0, 0}};
  for (int c = 0; c < 2 * problem_m[pb]; c++) y[c] = y0[pb][c];
}

/* ------------------------------------------------------------ methods */

typedef void (*RunFn)(int pb, double par, double *y, long *steps); /* (q, p) at T_END */

static void run_rk8pd(int pb, double tol, double *y, long *steps)
{
  gsl_odeiv2_system sys = ode(pb);
  gsl_odeiv2_driver *dr = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-3 * T_END, tol, tol);
  double t = 0;
  initial(pb, y);
  if (gsl_odeiv2_driver_apply(dr, &t, T_END, y) != GSL_SUCCESS) abort();
  *steps = (long)dr->n;
  gsl_odeiv2_driver_free(dr);
}

/* The arm's Cartesian form (bench/mq/arm3_cartesian.ham at its defaults: unit
 * masses and rods) per axis: M_c = [[2/3, 1/6, 0], [1/6, 2/3, 1/6], [0, 1/6, 1/3]]
 * on (P1, P2, P3). */
static const double arm_mc[3][3] = {{2.0 / 3, 1.0 / 6, 0}, {1.0 / 6, 2.0 / 3, 1.0 / 6}, {0, 1.0 / 6, 1.0 / 3}};

/* The arm's joint points P = (x1, y1, x2, y2, x3, y3) and momenta p_c = M_c v
 * from its joint angles and momenta y = (q, p): absolute angles f_j = q1 + .. +
 * q_j and rates w_j from q' = M(q)^-1 p, P_i = P_(i-1) + (sin f_i, -cos f_i),
 * v_i = v_(i-1) + w_i (cos f_i, sin f_i). */
static void arm_to_cartesian(const double *y, double *P, double *pc)
{
  double Mq[9], qd[3], f = 0, w = 0, x = 0, z = 0, vx[3], vz[3];
  arm_velocity(y, y + 3, Mq, qd);
  for (int i = 0; i < 3; i++) {
    f += y[i], w += qd[i];
    P[2 * i] = x += sin(f), P[2 * i + 1] = z -= cos(f);
    vx[i] = (i ? vx[i - 1] : 0) + w * cos(f), vz[i] = (i ? vz[i - 1] : 0) + w * sin(f);
  }
  for (int i = 0; i < 3; i++) {
    pc[2 * i] = pc[2 * i + 1] = 0;
    for (int j = 0; j < 3; j++) pc[2 * i] += arm_mc[i][j] * vx[j], pc[2 * i + 1] += arm_mc[i][j] * vz[j];
  }
}

/* The inverse of arm_to_cartesian: the link directions' absolute angles f_j
 * (atan2, from the downward vertical), the relative angles q in (-pi, pi]
 * (measure_error compares them modulo 2 pi), and p = J' p_c with J = dP/dq:
 * the momentum of f_j is a_j = e_j . (p_j + .. + p_3), e_j = (cos f_j, sin f_j),
 * and p_k = a_k + .. + a_3. */
static void arm_from_cartesian(const double *P, const double *pc, double *y)
{
  double f[3], a[3], tx = 0, tz = 0;
  for (int j = 0; j < 3; j++) {
    double dx = P[2 * j] - (j ? P[2 * j - 2] : 0), dz = P[2 * j + 1] - (j ? P[2 * j - 1] : 0);
    f[j] = atan2(dx, -dz);
    y[j] = j ? remainder(f[j] - f[j - 1], 4 * acos(0.0)) : f[0];
  }
  for (int j = 2; j >= 0; j--) {
    tx += pc[2 * j], tz += pc[2 * j + 1];
    a[j] = cos(f[j]) * tx + sin(f[j]) * tz;
  }
  y[5] = a[2], y[4] = a[1] + a[2], y[3] = a[0] + a[1] + a[2];
}

/* The start of a solver with m coordinates on problem pb: the model's own q0
 * and p0 (q0 = p0 = NULL), but for the spherical pendulum in Cartesian
 * coordinates (m = 3: models/conical.ham, unit mass, rod and gravity as
 * models/spherical_pendulum.ham) the spherical pendulum's start th = 1,
 * ph = 0, p_th = 0, p_ph = 0.5 as a position on the sphere and a velocity,
 * and for the arm in Cartesian coordinates (m = 6) the arm's start mapped by
 * arm_to_cartesian. */
static void cartesian_start(int pb, int m, double *q0, double *p0, const double **q, const double **p)
{
  double y[MAXD];
  *q = *p = NULL;
  if (pb == ARM && m == 6) {
    initial(ARM, y);
    arm_to_cartesian(y, q0, p0);
    *q = q0, *p = p0;
  }
  if (pb != SPH || m != 3) return;
  q0[0] = sin(1.0), q0[1] = 0, q0[2] = -cos(1.0);
  p0[0] = 0, p0[1] = 0.5 / sin(1.0), p0[2] = 0;
  *q = q0, *p = p0;
}

/* The state of a solver with m coordinates as problem pb's y = (q, p): as it
 * is, or for the spherical pendulum in Cartesian coordinates (m = 3) its
 * angles (ph in (-pi, pi]: measure_error compares it modulo 2 pi) and
 * p_th = th', p_ph = x y' - y x', or for the double pendulum in Cartesian coordinates (m = 4, unit
 * masses and rods: models/double_pendulum.ham, its line in the double
 * pendulum's group) the angles from the downward vertical, their rates from
 * the velocities p, and p_th = M(th) th', or for the arm in Cartesian
 * coordinates (m = 6: bench/mq/arm3_cartesian.ham) arm_from_cartesian. */
static void to_problem(int pb, int m, const double *q, const double *p, double *y)
{
  if (pb == SPH && m == 3) {
    double rho = hypot(q[0], q[1]);
    y[0] = atan2(rho, -q[2]), y[1] = atan2(q[1], q[0]);
    y[2] = -q[2] * (q[0] * p[0] + q[1] * p[1]) / rho + rho * p[2], y[3] = q[0] * p[1] - q[1] * p[0];
    return;
  }
  if (m == 4) {
    double t1 = atan2(q[0], -q[1]), t2 = atan2(q[2] - q[0], -(q[3] - q[1]));
    double w1 = p[0] * cos(t1) + p[1] * sin(t1), w2 = (p[2] - p[0]) * cos(t2) + (p[3] - p[1]) * sin(t2);
    double c = cos(t1 - t2);
    y[0] = t1, y[1] = t2, y[2] = 2 * w1 + c * w2, y[3] = c * w1 + w2;
    return;
  }
  if (pb == ARM && m == 6) {
    arm_from_cartesian(q, p, y);
    return;
  }
  for (int c = 0; c < m; c++) y[c] = q[c], y[m + c] = p[c];
}

/* A run that failed (a fixed step whose Newton does not converge at a long h,
 * an adaptive step that meets no tol above HMIN): an error of inf. */
static void failed(int pb, double *y)
{
  for (int c = 0; c < 2 * problem_m[pb]; c++) y[c] = HUGE_VAL;
}

/* run_P_fixed and run_P_adaptive for the generated solver P (m coordinates). */
#define HBVM_RUNS(P)                                                              \
  static void run_##P##_fixed(int pb, double n_steps, double *y, long *steps)    \
  {                                                                               \
    P##_state x;                                                                  \
    long n = lround(n_steps);                                                     \
    double h = T_END / (double)n, q0[MAXD], p0[MAXD];                             \
    const double *qs, *ps;                                                        \
    cartesian_start(pb, P##_M, q0, p0, &qs, &ps);                                 \
    P##_init(&x, qs, ps);                                                         \
    *steps = n;                                                                   \
    for (long i = 0; i < n; i++)                                                  \
      if (P##_step(&x, h, 0, 0)) {                                                \
        failed(pb, y);                                                            \
        return;                                                                   \
      }                                                                           \
    to_problem(pb, P##_M, x.q, x.p, y);                                           \
  }                                                                               \
  static void run_##P##_adaptive(int pb, double tol, double *y, long *steps)     \
  {                                                                               \
    P##_state x;                                                                  \
    double h = 1e-3 * T_END, q0[MAXD], p0[MAXD];                                  \
    const double *qs, *ps;                                                        \
    long n = 0;                                                                   \
    cartesian_start(pb, P##_M, q0, p0, &qs, &ps);                                 \
    P##_init(&x, qs, ps);                                                         \
    while (x.t < T_END * (1 - 1e-14)) {                                           \
      double rest = T_END - x.t, hh = h >= rest * (1 - 1e-12) ? rest : h;         \
      int last = hh == rest;                                                      \
      if (P##_step_adaptive(&x, &hh, tol, 0, 0)) {                                \
        failed(pb, y);                                                            \
        return;                                                                   \
      }                                                                           \
      if (!last || x.t < T_END * (1 - 1e-14)) h = hh;                             \
      n++;                                                                        \
    }                                                                             \
    *steps = n;                                                                   \
    to_problem(pb, P##_M, x.q, x.p, y);                                           \
  }
#define S(P, PB, K, SS, VAR) HBVM_RUNS(P)
#include "solvers.def"
#undef S

typedef struct {
  const char *name, *variant;
  int pb, k, s;
  RunFn fixed, adaptive;
} Solver;

static const Solver solvers[] = {
#define S(P, PB, K, SS, VAR) {#P, VAR, PB, K, SS, run_##P##_fixed, run_##P##_adaptive},
#include "solvers.def"
#undef S
};
enum { NSOLVERS = sizeof solvers / sizeof solvers[0] };

/* ------------------------------------------------------------- points */

typedef struct {
  int pb, k, s;
  const char *method, *variant, *mode;
  RunFn run;
  double par, err, dH, sec[ROUNDS];
  long steps;
} Point;

static Point pts[MAXPTS];
static int npts;

static double cpu_now(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Run point p once untimed: its error at T against ref (the spherical
 * pendulum's azimuth and the arm's angles modulo 2 pi) and |H(T) - H0|. */
static void measure_error(Point *p, const double *ref)
{
  double y[MAXD], y0[MAXD];
  int d = 2 * problem_m[p->pb];
  p->run(p->pb, p->par, y, &p->steps);
  p->err = 0;
  for (int c = 0; c < d; c++) {
    double e = y[c] - ref[c];
    if ((p->pb == SPH && c == 1) || (p->pb == ARM && c < 3)) e = remainder(e, 4 * acos(0.0));
    p->err = fmax(p->err, fabs(e));
  }
  initial(p->pb, y0);
  p->dH = fabs(energy(p->pb, y) - energy(p->pb, y0));
}

static Point *add(int pb, const char *method, const char *variant, const char *mode, int k, int s, RunFn run,
                  double par)
{
  Point *p = &pts[npts++];
  if (npts > MAXPTS) abort();
  *p = (Point){pb, k, s, method, variant, mode, run, par, 0, 0, {0}, 0};
  return p;
}

/* Add a line: tolerances 10^-4 .. 10^-14.5, a factor 10^(1/4) apart
 * (adaptive), or N = 10 .. 2560 steps a factor 10^(1/8) apart (fixed: its
 * error falls as N^-2s), kept while the error is above ERR_LO/10. */
static void add_line(int pb, const char *method, const char *variant, const char *mode, int k, int s, RunFn run,
                     const double *ref)
{
  int fixed = mode[0] == 'f';
  for (int i = 0; i <= 42; i++) {
    double par = fixed ? round(10 * pow(10, i / 8.0)) : pow(10, -4 - i / 4.0);
    if (fixed && par > 2560) break;
    Point *p = add(pb, method, variant, mode, k, s, run, par);
    measure_error(p, ref);
    if (p->err < ERR_LO / 10) break;
  }
}

static int cmp_double(const void *a, const void *b)
{
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static int timed(const Point *p) { return p->err >= ERR_LO && p->err <= ERR_HI; }

int main(void)
{
  double ref[NPROBLEMS][MAXD];
  long n;
  for (int pb = PA; pb < NPROBLEMS; pb++) {
    run_rk8pd(pb, 1e-15, ref[pb], &n);
    add_line(pb, "gsl-rk8pd", "", "adaptive", 0, 0, run_rk8pd, ref[pb]);
  }
  for (int i = 0; i < NSOLVERS; i++) {
    const Solver *v = &solvers[i];
    add_line(v->pb, v->name, v->variant, "adaptive", v->k, v->s, v->adaptive, ref[v->pb]);
    add_line(v->pb, v->name, v->variant, "fixed", v->k, v->s, v->fixed, ref[v->pb]);
  }
  for (int r = 0; r < ROUNDS; r++) /* in turns: every timed point once a round */
    for (int i = 0; i < npts; i++) {
      double y[MAXD], t0, t1;
      long steps, reps = 0;
      if (!timed(&pts[i])) continue;
      t0 = cpu_now();
      do {
        pts[i].run(pts[i].pb, pts[i].par, y, &steps);
        reps++;
      } while ((t1 = cpu_now()) - t0 < MIN_SEC);
      pts[i].sec[r] = (t1 - t0) / (double)reps;
    }
  printf("build,problem,method,variant,mode,k,s,param,steps,err,dH,seconds\n");
  for (int i = 0; i < npts; i++) {
    Point *p = &pts[i];
    double med = 0;
    if (timed(p)) {
      qsort(p->sec, ROUNDS, sizeof p->sec[0], cmp_double);
      med = p->sec[ROUNDS / 2];
    }
    printf("%s,%s,%s,%s,%s,%d,%d,%.6g,%ld,%.3e,%.2e,%.4e\n", BUILD, problem_name[p->pb], p->method, p->variant, p->mode,
           p->k, p->s, p->par, p->steps, p->err, p->dH, med);
  }
  return 0;
}
