/* stiff.c - the stiff benchmark problems (stiff.h): potential, gradient,
 * constraints and their derivatives by hand, as problems.c's, plus omega,
 * the slow quantities and (without constraints) the Hessian. */
#include "stiff.h"

#include <math.h>
#include <string.h>

#include "dihedral.h"

static const double unit_minv[BENCH_MAXM] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};

/* --------------------------------------------------------------- FPU chain
 * m = 6, nu = 0: q = (x0[1..3], x1[1..3]) (models/fpu.ham),
 * U = omega^2 / 2 sum x1^2 + sum_j (r c_j . q)^4 over the four soft springs,
 * c_j their coefficient rows, r = 1 / sqrt 2. */

#define FPU_R 0.70710678118654752
static const double fpu_c[4][6] = {
    {1, 0, 0, -1, 0, 0}, {-1, 1, 0, -1, -1, 0}, {0, -1, 1, 0, -1, -1}, {0, 0, 1, 0, 0, 1}};

/* The elongation of soft spring j. */
static double fpu_d(int j, const double *q) {
  double d = 0;
  for (int i = 0; i < 6; i++) d += fpu_c[j][i] * q[i];
  return FPU_R * d;
}

static double fpu_pot(double omega, const double *q) {
  double u = 0;
  for (int i = 3; i < 6; i++) u += omega * omega / 2 * q[i] * q[i];
  for (int j = 0; j < 4; j++) {
    double d2 = fpu_d(j, q) * fpu_d(j, q);
    u += d2 * d2;
  }
  return u;
}

static void fpu_grad(double omega, const double *q, double *gu) {
  for (int i = 0; i < 6; i++) gu[i] = i >= 3 ? omega * omega * q[i] : 0;
  for (int j = 0; j < 4; j++) {
    double d = fpu_d(j, q), f = 4 * d * d * d * FPU_R;
    for (int i = 0; i < 6; i++) gu[i] += f * fpu_c[j][i];
  }
}

static void fpu_hess(double omega, const double *q, double *H) {
  for (int i = 0; i < 36; i++) H[i] = 0;
  for (int i = 3; i < 6; i++) H[i * 6 + i] = omega * omega;
  for (int j = 0; j < 4; j++) {
    double d = fpu_d(j, q), f = 12 * d * d * FPU_R * FPU_R;
    for (int a = 0; a < 6; a++)
      for (int b = 0; b < 6; b++) H[a * 6 + b] += f * fpu_c[j][a] * fpu_c[j][b];
  }
}

/* The book's start: x0[1] = 1, p0[1] = 1, x1[1] = 1 / omega, p1[1] = 1. */
static void fpu_init(double omega, double *q0, double *p0) {
  memset(q0, 0, 6 * sizeof *q0);
  memset(p0, 0, 6 * sizeof *p0);
  q0[0] = 1;
  q0[3] = 1 / omega;
  p0[0] = p0[3] = 1;
}

static int fpu_slow(const double *q, const double *p, double *out) {
  memcpy(out, q, 3 * sizeof *q);
  memcpy(out + 3, p, 3 * sizeof *p);
  return 6;
}

#define FPU_AT(W)                                                                           \
  static double fpu##W##_pot(const double *q) { return fpu_pot(W, q); }                     \
  static void fpu##W##_grad(const double *q, double *gu) { fpu_grad(W, q, gu); }            \
  static void fpu##W##_hess(const double *q, double *H) { fpu_hess(W, q, H); }              \
  static void fpu##W##_init(double *q0, double *p0) { fpu_init(W, q0, p0); }
FPU_AT(50)
FPU_AT(1000)

/* ---------------------------------------------------------- the stiff bob
 * m = 4, nu = 1: q = (x1, y1, x2, y2), U = y1 + y2 + k / 2 (L - l)^2,
 * L = |r2 - r1|, l = 0.1; g = x1^2 + y1^2 - 1. */

#define BOB_L 0.1

static double bob_pot(double k, const double *q) {
  double dx = q[2] - q[0], dy = q[3] - q[1], e = sqrt(dx * dx + dy * dy) - BOB_L;
  return q[1] + q[3] + k / 2 * e * e;
}

static void bob_grad(double k, const double *q, double *gu) {
  double dx = q[2] - q[0], dy = q[3] - q[1], L = sqrt(dx * dx + dy * dy), f = k * (L - BOB_L) / L;
  gu[0] = -f * dx;
  gu[1] = 1 - f * dy;
  gu[2] = f * dx;
  gu[3] = 1 + f * dy;
}

static void bob_cons(const double *q, double *g) { g[0] = q[0] * q[0] + q[1] * q[1] - 1; }

static void bob_jac(const double *q, double *G) {
  G[0] = 2 * q[0];
  G[1] = 2 * q[1];
  G[2] = G[3] = 0;
}

static void bob_hessq(const double *q, const double *v, double *hq) {
  (void)q;
  hq[0] = 2 * (v[0] * v[0] + v[1] * v[1]);
}

/* At rest 0.5 from the downward vertical, the spring at rest length along the rod. */
static void bob_init(double *q0, double *p0) {
  double s = sin(0.5), c = cos(0.5);
  q0[0] = s;
  q0[1] = -c;
  q0[2] = (1 + BOB_L) * s;
  q0[3] = -(1 + BOB_L) * c;
  memset(p0, 0, 4 * sizeof *p0);
}

/* The centre of mass. (Not the total momentum: the rod's tension carries the
 * spring's fast force to it.) */
static int bob_slow(const double *q, const double *p, double *out) {
  (void)p;
  out[0] = (q[0] + q[2]) / 2;
  out[1] = (q[1] + q[3]) / 2;
  return 2;
}

#define BOB_AT(NAME, K)                                                                 \
  static double NAME##_pot(const double *q) { return bob_pot(K, q); }                   \
  static void NAME##_grad(const double *q, double *gu) { bob_grad(K, q, gu); }
BOB_AT(bob4, 1e4)
BOB_AT(bob6, 1e6)

/* ----------------------------------------------------------------- butane
 * m = 12, nu = 3: q = (r1, r2, r3, r4) in R^3, bonds |r_{b+1} - r_b|^2 = 1,
 * U = ka / 2 ((a - c0)^2 + (b - c0)^2) + kt / 2 D^2 with
 * a = (r1 - r2).(r3 - r2), b = (r2 - r3).(r4 - r3), D = |r4 - r1|^2 - 41/9,
 * c0 = -1/3, ka = 1e4, kt = 1 (models/butane.ham). */

#define BUT_KA 1e4
#define BUT_KT 1.0
#define BUT_C0 (-1.0 / 3)

/* (u - v).(w - v) for the atoms u, v, w of q. */
static double but_dot(const double *q, int u, int v, int w) {
  double s = 0;
  for (int c = 0; c < 3; c++) s += (q[3 * u + c] - q[3 * v + c]) * (q[3 * w + c] - q[3 * v + c]);
  return s;
}

static double but_pot(const double *q) {
  double a = but_dot(q, 0, 1, 2) - BUT_C0, b = but_dot(q, 1, 2, 3) - BUT_C0, D = but_dot(q, 3, 0, 3) - 41.0 / 9;
  return BUT_KA / 2 * (a * a + b * b) + BUT_KT / 2 * D * D;
}

/* Adds f grad((u - v).(w - v)) to gu. */
static void but_dot_grad(const double *q, int u, int v, int w, double f, double *gu) {
  for (int c = 0; c < 3; c++) {
    double du = q[3 * u + c] - q[3 * v + c], dw = q[3 * w + c] - q[3 * v + c];
    gu[3 * u + c] += f * dw;
    gu[3 * w + c] += f * du;
    gu[3 * v + c] -= f * (du + dw);
  }
}

static void but_grad(const double *q, double *gu) {
  double a = but_dot(q, 0, 1, 2) - BUT_C0, b = but_dot(q, 1, 2, 3) - BUT_C0, D = but_dot(q, 3, 0, 3) - 41.0 / 9;
  memset(gu, 0, 12 * sizeof *gu);
  but_dot_grad(q, 0, 1, 2, BUT_KA * a, gu);
  but_dot_grad(q, 1, 2, 3, BUT_KA * b, gu);
  but_dot_grad(q, 3, 0, 3, BUT_KT * D, gu);
}

static void but_cons(const double *q, double *g) {
  for (int b = 0; b < 3; b++) g[b] = but_dot(q, b + 1, b, b + 1) - 1;
}

static void but_jac(const double *q, double *G) {
  memset(G, 0, 36 * sizeof *G);
  for (int b = 0; b < 3; b++)
    for (int c = 0; c < 3; c++) {
      double d = 2 * (q[3 * (b + 1) + c] - q[3 * b + c]);
      G[(3 * (b + 1) + c) * 3 + b] = d;
      G[(3 * b + c) * 3 + b] = -d;
    }
}

static void but_hessq(const double *q, const double *v, double *hq) {
  (void)q;
  for (int b = 0; b < 3; b++) hq[b] = 2 * but_dot(v, b + 1, b, b + 1);
}

/* At rest, bonds 1, angles at c0, dihedral 2 (models/butane.ham). */
static void but_init(double *q0, double *p0) {
  double th = acos(BUT_C0), phi = 2;
  const double q[12] = {cos(th), sin(th), 0, 0, 0, 0, 1, 0, 0, 1 - cos(th), sin(th) * cos(phi), sin(th) * sin(phi)};
  memcpy(q0, q, sizeof q);
  memset(p0, 0, 12 * sizeof *p0);
}

/* The dihedral angle (tests/dihedral.h). */
static int but_slow(const double *q, const double *p, double *out) {
  (void)p;
  out[0] = dihedral(q);
  return 1;
}

/* ------------------------------------------------------------- the tables */

static const Problem problems[] = {
    {"fpu50", 6, 0, 10, unit_minv, fpu50_init, fpu50_pot, fpu50_grad, NULL, NULL, NULL},
    {"fpu1000", 6, 0, 10, unit_minv, fpu1000_init, fpu1000_pot, fpu1000_grad, NULL, NULL, NULL},
    {"stiff_bob", 4, 1, 10, unit_minv, bob_init, bob4_pot, bob4_grad, bob_cons, bob_jac, bob_hessq},
    {"stiff_bob6", 4, 1, 10, unit_minv, bob_init, bob6_pot, bob6_grad, bob_cons, bob_jac, bob_hessq},
    {"butane", 12, 3, 10, unit_minv, but_init, but_pot, but_grad, but_cons, but_jac, but_hessq},
};

static const Stiff extras[] = {
    {&problems[0], 50, fpu_slow, fpu50_hess},
    {&problems[1], 1000, fpu_slow, fpu1000_hess},
    {&problems[2], 141.42135623730950, bob_slow, NULL},
    {&problems[3], 1414.2135623730950, bob_slow, NULL},
    {&problems[4], 175.1, but_slow, NULL},
};

const Problem *stiff_problem_find(const char *name) {
  for (size_t i = 0; i < sizeof problems / sizeof problems[0]; i++)
    if (strcmp(problems[i].name, name) == 0) return &problems[i];
  return NULL;
}

const Stiff *stiff_find(const Problem *pb) {
  for (size_t i = 0; i < sizeof extras / sizeof extras[0]; i++)
    if (extras[i].pb == pb) return &extras[i];
  return NULL;
}
