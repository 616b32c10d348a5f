/* stiffness.c - whether a model is stiff, from its linearisation at q0
 * (what --iteration auto decides at generation time).
 *
 * The fixed-point sweep contracts like (h omega_fast)^2 (docs/method-newton.md),
 * so it limits h to about 3 / omega_fast, while the accuracy of the motion
 * the user follows needs only h omega_slow small. A model is stiff where the
 * two frequencies are far apart. They are estimated at q0 at the default
 * parameters: the squared frequencies are the eigenvalues of
 * M^-1 Hess(U + lambda' g) on the tangent space of the constraints, lambda
 * the multiplier consistent with (q0, p0). Computed in double, all numeric:
 * the Hessian by central differences of the gradient's DAG (dag_eval_many;
 * nothing is added to the DAG, so the emitted code does not depend on this
 * estimate having run), M^-1 = R R' (Cholesky) and the symmetric
 * R' K R, projected onto the tangent space, by cyclic Jacobi.
 *
 * The ratio omega_fast / omega_slow takes |eigenvalue|: a negative curvature
 * (Kepler, the inverted pendulum) is an instability's rate, a time scale
 * just as a frequency is. Eigenvalues below STIFF_ZERO of the largest are
 * dropped (free directions, the constraints' normal space). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

#define STIFF_ZERO 1e-9   /* |eigenvalue| below this fraction of the largest: zero */
#define STIFF_MAX_M 200   /* larger models are not estimated (O(m^3) Jacobi sweeps) */

// grad U and the Jacobian's dense rows (nu x m) at q.
static void gradients_at(const Model *mod, const double *q, const double *prm, double *gu, double *G) {
  int m = mod->m, nu = mod->nu, n = m;
  for (int a = 0; a < nu; a++) n += mod->jac[a].n;
  int *roots = xmalloc((size_t)n * sizeof *roots);
  double *val = xmalloc((size_t)n * sizeof *val);
  for (int i = 0; i < m; i++) roots[i] = mod->gradU[i];
  for (int a = 0, r = m; a < nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) roots[r++] = mod->jac[a].e[e].node;
  dag_eval_many(mod->dag, roots, n, q, prm, val);
  memcpy(gu, val, (size_t)m * sizeof *gu);
  memset(G, 0, (size_t)nu * m * sizeof *G);
  for (int a = 0, r = m; a < nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) G[a * m + mod->jac[a].e[e].coord] = val[r++];
  free(roots);
  free(val);
}

// out = M^-1 v at the default parameters.
static void minv_times(const Model *mod, const double *v, double *out) {
  int m = mod->m;
  for (int i = 0; i < m; i++) {
    out[i] = mod->minv_diag[i] * v[i];
    if (mod->mass == MASS_DENSE) {
      out[i] = 0;
      for (int j = 0; j < m; j++) out[i] += mod->minv[(size_t)i * m + j] * v[j];
    }
  }
}

// Solve the n x n system A x = b in place (partial pivoting); 0 if singular.
static int dense_solve(double *A, double *b, int n) {
  for (int k = 0; k < n; k++) {
    int p = k;
    for (int i = k + 1; i < n; i++)
      if (fabs(A[i * n + k]) > fabs(A[p * n + k])) p = i;
    if (!(fabs(A[p * n + k]) > 0)) return 0;
    for (int c = 0; c < n; c++) {
      double t = A[k * n + c];
      A[k * n + c] = A[p * n + c];
      A[p * n + c] = t;
    }
    double t = b[k];
    b[k] = b[p];
    b[p] = t;
    for (int i = k + 1; i < n; i++) {
      double f = A[i * n + k] / A[k * n + k];
      for (int c = k; c < n; c++) A[i * n + c] -= f * A[k * n + c];
      b[i] -= f * b[k];
    }
  }
  for (int k = n - 1; k >= 0; k--) {
    for (int c = k + 1; c < n; c++) b[k] -= A[k * n + c] * b[c];
    b[k] /= A[k * n + k];
  }
  return 1;
}

// The eigenvalues of the symmetric n x n matrix S (destroyed) into ev, by
// cyclic Jacobi rotations.
static void jacobi_eigenvalues(double *S, int n, double *ev) {
  for (int sweep = 0; sweep < 60; sweep++) {
    double off = 0, diag = 0;
    for (int i = 0; i < n; i++)
      for (int j = 0; j < n; j++) *(i == j ? &diag : &off) += S[i * n + j] * S[i * n + j];
    if (!(off > 1e-30 * diag)) break;
    for (int p = 0; p < n; p++)
      for (int q = p + 1; q < n; q++) {
        double apq = S[p * n + q];
        if (apq == 0) continue;
        double theta = (S[q * n + q] - S[p * n + p]) / (2 * apq);
        double t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
        double c = 1 / sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < n; k++) { /* columns p, q */
          double kp = S[k * n + p], kq = S[k * n + q];
          S[k * n + p] = c * kp - s * kq;
          S[k * n + q] = s * kp + c * kq;
        }
        for (int k = 0; k < n; k++) { /* rows p, q */
          double pk = S[p * n + k], qk = S[q * n + k];
          S[p * n + k] = c * pk - s * qk;
          S[q * n + k] = s * pk + c * qk;
        }
      }
  }
  for (int i = 0; i < n; i++) ev[i] = S[i * n + i];
}

// lambda consistent with (q0, p0): the second derivative of g along the
// motion is zero, G M^-1 (grad U + G' lambda) = v' Hess(g) v, v = M^-1 p0
// (the curvature by a central difference of G along v). 0 if singular.
static void consistent_multiplier(const Model *mod, const double *prm, const double *gu, const double *G,
                                  double *lam) {
  int m = mod->m, nu = mod->nu;
  double *v = xmalloc((size_t)m * sizeof *v), *w = xmalloc((size_t)m * sizeof *w), *q = xmalloc((size_t)m * sizeof *q);
  double *Gp = xmalloc((size_t)nu * m * sizeof *Gp), *Gm = xmalloc((size_t)nu * m * sizeof *Gm);
  double *gtmp = xmalloc((size_t)m * sizeof *gtmp), *A = xmalloc((size_t)nu * nu * sizeof *A);
  minv_times(mod, mod->p0, v);
  double vn = 0, qn = 1;
  for (int i = 0; i < m; i++) vn = fmax(vn, fabs(v[i])), qn = fmax(qn, fabs(mod->q0[i]));
  double d = vn > 0 ? 1e-5 * qn / vn : 0;
  for (int i = 0; i < m; i++) q[i] = mod->q0[i] + d * v[i];
  gradients_at(mod, q, prm, gtmp, Gp);
  for (int i = 0; i < m; i++) q[i] = mod->q0[i] - d * v[i];
  gradients_at(mod, q, prm, gtmp, Gm);
  minv_times(mod, gu, w);
  for (int a = 0; a < nu; a++) {
    double rhs = 0, curv = 0;
    for (int i = 0; i < m; i++) {
      rhs -= G[a * m + i] * w[i];
      if (d > 0) curv += (Gp[a * m + i] - Gm[a * m + i]) / (2 * d) * v[i];
    }
    lam[a] = rhs + curv;
    for (int c = 0; c < nu; c++) {
      double acc = 0;
      minv_times(mod, G + c * m, gtmp);
      for (int i = 0; i < m; i++) acc += G[a * m + i] * gtmp[i];
      A[a * nu + c] = acc;
    }
  }
  if (!dense_solve(A, lam, nu)) memset(lam, 0, (size_t)nu * sizeof *lam);
  free(v), free(w), free(q), free(Gp), free(Gm), free(gtmp), free(A);
}

// R with M^-1 = R R' (lower triangular, Cholesky of M^-1); 0 if M^-1 is
// not positive definite.
static int minv_cholesky(const Model *mod, double *R) {
  int m = mod->m;
  memset(R, 0, (size_t)m * m * sizeof *R);
  for (int j = 0; j < m; j++)
    for (int i = j; i < m; i++) {
      double a = mod->mass == MASS_DENSE ? mod->minv[(size_t)i * m + j] : (i == j ? mod->minv_diag[i] : 0);
      for (int k = 0; k < j; k++) a -= R[i * m + k] * R[j * m + k];
      if (i == j) {
        if (!(a > 0)) return 0;
        R[j * m + j] = sqrt(a);
      } else
        R[i * m + j] = a / R[j * m + j];
    }
  return 1;
}

double model_stiffness(const Model *mod, double *wfast, double *wslow) {
  int m = mod->m, nu = mod->nu, ok = m <= STIFF_MAX_M && !mod->minv_node && !mod->mass_q;
  *wfast = *wslow = 0;
  if (!ok) return 0;
  double *prm = xmalloc((size_t)(mod->nparams + 1) * sizeof *prm);
  for (int i = 0; i < mod->nparams; i++) prm[i] = mod->params[i].value;
  double *gu = xmalloc((size_t)m * sizeof *gu), *G = xmalloc((size_t)(nu + 1) * m * sizeof *G);
  double *lam = xmalloc((size_t)(nu + 1) * sizeof *lam), *q = xmalloc((size_t)m * sizeof *q);
  double *K = xmalloc((size_t)m * m * sizeof *K), *R = xmalloc((size_t)m * m * sizeof *R);
  double *S = xmalloc((size_t)m * m * sizeof *S), *T = xmalloc((size_t)m * m * sizeof *T);
  double *gp = xmalloc((size_t)m * sizeof *gp), *gm = xmalloc((size_t)m * sizeof *gm);
  double *Gp = xmalloc((size_t)(nu + 1) * m * sizeof *Gp), *Gm = xmalloc((size_t)(nu + 1) * m * sizeof *Gm);
  double *B = xmalloc((size_t)(nu + 1) * m * sizeof *B), *ev = xmalloc((size_t)m * sizeof *ev);
  double ratio = 0;
  gradients_at(mod, mod->q0, prm, gu, G);
  if (nu) consistent_multiplier(mod, prm, gu, G, lam);
  /* K = Hess(U + lambda' g), column j by a central difference of the gradient */
  memcpy(q, mod->q0, (size_t)m * sizeof *q);
  for (int j = 0; j < m; j++) {
    double d = 1e-5 * fmax(1, fabs(mod->q0[j]));
    q[j] = mod->q0[j] + d;
    gradients_at(mod, q, prm, gp, Gp);
    q[j] = mod->q0[j] - d;
    gradients_at(mod, q, prm, gm, Gm);
    q[j] = mod->q0[j];
    for (int i = 0; i < m; i++) {
      double v = gp[i] - gm[i];
      for (int a = 0; a < nu; a++) v += lam[a] * (Gp[a * m + i] - Gm[a * m + i]);
      K[i * m + j] = v / (2 * d);
    }
  }
  if (!minv_cholesky(mod, R)) goto done;
  /* S = R' Ks R (Ks the symmetric part of K), then projected onto the tangent
   * space: the orthogonal complement of the columns R' G' */
  for (int i = 0; i < m; i++)
    for (int j = 0; j < m; j++) {
      double acc = 0;
      for (int k = 0; k < m; k++) acc += (K[i * m + k] + K[k * m + i]) / 2 * R[k * m + j];
      T[i * m + j] = acc; /* Ks R */
    }
  for (int i = 0; i < m; i++)
    for (int j = 0; j < m; j++) {
      double acc = 0;
      for (int k = 0; k < m; k++) acc += R[k * m + i] * T[k * m + j];
      S[i * m + j] = acc;
    }
  int rank = 0;
  for (int a = 0; a < nu; a++) { /* an orthonormal basis of R' G' (Gram-Schmidt, twice) */
    double *b = B + rank * m, norm = 0;
    for (int i = 0; i < m; i++) {
      double acc = 0;
      for (int k = 0; k < m; k++) acc += R[k * m + i] * G[a * m + k];
      b[i] = acc;
    }
    for (int pass = 0; pass < 2; pass++)
      for (int c = 0; c < rank; c++) {
        double dot = 0;
        for (int i = 0; i < m; i++) dot += B[c * m + i] * b[i];
        for (int i = 0; i < m; i++) b[i] -= dot * B[c * m + i];
      }
    for (int i = 0; i < m; i++) norm = hypot(norm, b[i]);
    if (!(norm > 0)) continue;
    for (int i = 0; i < m; i++) b[i] /= norm;
    rank++;
  }
  for (int c = 0; c < rank; c++) { /* S <- (I - b b') S (I - b b'), basis vector by vector */
    const double *b = B + c * m;
    for (int j = 0; j < m; j++) {
      double dot = 0;
      for (int i = 0; i < m; i++) dot += b[i] * S[i * m + j];
      for (int i = 0; i < m; i++) S[i * m + j] -= b[i] * dot;
    }
    for (int i = 0; i < m; i++) {
      double dot = 0;
      for (int j = 0; j < m; j++) dot += S[i * m + j] * b[j];
      for (int j = 0; j < m; j++) S[i * m + j] -= dot * b[j];
    }
  }
  jacobi_eigenvalues(S, m, ev);
  double big = 0, small = HUGE_VAL;
  for (int i = 0; i < m; i++) big = fmax(big, fabs(ev[i]));
  for (int i = 0; i < m; i++)
    if (fabs(ev[i]) > STIFF_ZERO * big) small = fmin(small, fabs(ev[i]));
  if (isfinite(big) && big > 0 && isfinite(small)) {
    *wfast = sqrt(big);
    *wslow = sqrt(small);
    ratio = *wfast / *wslow;
  }
done:
  free(prm), free(gu), free(G), free(lam), free(q), free(K), free(R), free(S), free(T);
  free(gp), free(gm), free(Gp), free(Gm), free(B), free(ev);
  return ratio;
}
