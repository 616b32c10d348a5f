/* fourbar_ode.h - the four-bar linkage of models/fourbar_angles.ham (at its
 * default params) as the index-1 ODE in its three angles, y = (q, p):
 *   q' = v = M(q)^-1 p,  p' = -grad_q T - grad U - G lambda,
 *   (G' M^-1 G) lambda = [v' Hess(g_a) v]_a - G' M^-1 (grad_q T + grad U + Mdot v),
 * G = grad g, all in closed form. Shared by tests/check_mq_fourbar.c (the
 * reference of suite mq) and bench/mq/fourbar.c. */
#ifndef FOURBAR_ODE_H
#define FOURBAR_ODE_H

#include <math.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>

/* the model's params: ground, crank, coupler, rocker; masses; gravity */
static const double L0 = 2, L1 = 1, L2 = 2, L3 = 1.5, M1 = 1, M2 = 1, M3 = 1, GRAV = 1;

// M(q), its time derivative Mdot v along v, grad_q T at v, grad U, the
// columns of G = grad g and v' Hess(g_a) v.
typedef struct {
  double M[9], mdv[3], gt[3], gu[3], G[2][3], hvv[2];
} Terms;

static void terms(const double *q, const double *v, Terms *t) {
  double c1 = cos(q[0]), s1 = sin(q[0]), c2 = cos(q[1]), s2 = sin(q[1]), c3 = cos(q[2]), s3 = sin(q[2]);
  double c = M2 * L1 * L2 / 2, cd = c * cos(q[0] - q[1]), sd = c * sin(q[0] - q[1]);
  double M[9] = {M1 * L1 * L1 / 3 + M2 * L1 * L1, cd, 0, cd, M2 * L2 * L2 / 3, 0, 0, 0, M3 * L3 * L3 / 3};
  memcpy(t->M, M, sizeof M);
  /* dM01/dth1 = -sd, dM01/dth2 = sd */
  t->mdv[0] = -sd * (v[0] - v[1]) * v[1];
  t->mdv[1] = -sd * (v[0] - v[1]) * v[0];
  t->mdv[2] = 0;
  t->gt[0] = sd * v[0] * v[1];
  t->gt[1] = -sd * v[0] * v[1];
  t->gt[2] = 0;
  t->gu[0] = GRAV * (M1 / 2 + M2) * L1 * c1;
  t->gu[1] = GRAV * M2 * L2 / 2 * c2;
  t->gu[2] = GRAV * M3 * L3 / 2 * c3;
  double G[2][3] = {{-L1 * s1, -L2 * s2, L3 * s3}, {L1 * c1, L2 * c2, -L3 * c3}};
  memcpy(t->G, G, sizeof G);
  t->hvv[0] = -L1 * c1 * v[0] * v[0] - L2 * c2 * v[1] * v[1] + L3 * c3 * v[2] * v[2];
  t->hvv[1] = -L1 * s1 * v[0] * v[0] - L2 * s2 * v[1] * v[1] + L3 * s3 * v[2] * v[2];
}

// x = M^-1 b for the 3 x 3 M (GSL's LU on a copy).
static void msolve(const double *M, const double *b, double *x) {
  double A[9], bb[3];
  int sg;
  memcpy(A, M, sizeof A);
  memcpy(bb, b, sizeof bb);
  gsl_matrix_view Av = gsl_matrix_view_array(A, 3, 3);
  gsl_vector_view bv = gsl_vector_view_array(bb, 3), xv = gsl_vector_view_array(x, 3);
  gsl_permutation *perm = gsl_permutation_alloc(3);
  gsl_linalg_LU_decomp(&Av.matrix, perm, &sg);
  gsl_linalg_LU_solve(&Av.matrix, perm, &bv.vector, &xv.vector);
  gsl_permutation_free(perm);
}

static double energy(const double *q, const double *p) {
  double v[3], U = GRAV * ((M1 / 2 + M2) * L1 * sin(q[0]) + M2 * L2 / 2 * sin(q[1]) + M3 * L3 / 2 * sin(q[2]));
  Terms t;
  terms(q, p, &t);
  msolve(t.M, p, v);
  return (p[0] * v[0] + p[1] * v[1] + p[2] * v[2]) / 2 + U;
}

// The multiplier consistent with (q, p), and the force f = grad_q T + grad U,
// the columns of G into t.
static void multiplier(const double *q, const double *p, double *lam, double *f, Terms *tt) {
  double v[3], w[3], S[4], r[2], Mg[2][3];
  Terms t;
  terms(q, q, &t); /* M(q) first, then the terms at v */
  msolve(t.M, p, v);
  terms(q, v, &t);
  for (int i = 0; i < 3; i++) {
    f[i] = t.gt[i] + t.gu[i];
    w[i] = f[i] + t.mdv[i];
  }
  msolve(t.M, w, w);
  for (int a = 0; a < 2; a++) msolve(t.M, t.G[a], Mg[a]);
  for (int a = 0; a < 2; a++) {
    r[a] = t.hvv[a];
    for (int i = 0; i < 3; i++) r[a] -= t.G[a][i] * w[i];
    for (int c = 0; c < 2; c++) {
      S[a * 2 + c] = 0;
      for (int i = 0; i < 3; i++) S[a * 2 + c] += t.G[a][i] * Mg[c][i];
    }
  }
  double det = S[0] * S[3] - S[1] * S[2];
  lam[0] = (S[3] * r[0] - S[1] * r[1]) / det;
  lam[1] = (S[0] * r[1] - S[2] * r[0]) / det;
  *tt = t;
}

static int fourbar_rhs(double tt, const double *y, double *dy, void *par) {
  const double *q = y, *p = y + 3;
  double v[3], f[3], lam[2];
  Terms t;
  (void)tt;
  (void)par;
  multiplier(q, p, lam, f, &t);
  msolve(t.M, p, v);
  for (int i = 0; i < 3; i++) {
    dy[i] = v[i];
    dy[3 + i] = -f[i] - t.G[0][i] * lam[0] - t.G[1][i] * lam[1];
  }
  return GSL_SUCCESS;
}

#endif
