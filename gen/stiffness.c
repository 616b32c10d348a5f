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
 * R' K R, projected onto the tangent space, by GSL's symmetric eigensolver.
 *
 * The ratio omega_fast / omega_slow takes |eigenvalue|: a negative curvature
 * (Kepler, the inverted pendulum) is an instability's rate, a time scale
 * just as a frequency is. Eigenvalues below STIFF_ZERO of the largest are
 * dropped (free directions, the constraints' normal space). The largest
 * ratio between consecutive nonzero frequencies (the gap) tells a
 * separation of time scales from a spectrum that is merely wide: a long
 * chain of equal soft springs has omega_fast / omega_slow of order m and
 * no gap wider than 2. */
#include <gsl/gsl_eigen.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

#define STIFF_ZERO 1e-9 /* |eigenvalue| below this fraction of the largest: zero */
/* Larger models are not estimated: the projection onto the constraints'
 * tangent space and a dense M^-1 cost O(m^3) in plain loops. Without
 * constraints and with a diagonal M, S is O(m^2) and the eigensolver's
 * O(m^3) is the cost: 0.3 s at m = 1000, 2.6 s at 2000 (measured, a banded S). */
#define STIFF_MAX_M 200
#define STIFF_MAX_M_FREE 1200

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

// The eigenvalues of the symmetric n x n matrix S (destroyed) into ev
// (GSL's Householder tridiagonalisation and implicit QL); 0 if it fails.
static int symmetric_eigenvalues(double *S, int n, double *ev) {
  gsl_matrix_view a = gsl_matrix_view_array(S, (size_t)n, (size_t)n);
  gsl_vector_view e = gsl_vector_view_array(ev, (size_t)n);
  gsl_eigen_symm_workspace *w = gsl_eigen_symm_alloc((size_t)n);
  gsl_error_handler_t *old = gsl_set_error_handler_off();
  int rc = gsl_eigen_symm(&a.matrix, &e.vector, w);
  gsl_set_error_handler(old);
  gsl_eigen_symm_free(w);
  return rc == 0;
}

static int by_value(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

// f from the eigenvalues ev (n, sorted in place by |value|): the square
// roots of the largest and the smallest nonzero |eigenvalue|, and of those
// either side of the largest ratio between consecutive nonzero ones.
// Returns fast / slow, 0 when there is no nonzero one.
static double frequencies_of(double *ev, int n, Frequencies *f) {
  for (int i = 0; i < n; i++) ev[i] = fabs(ev[i]);
  qsort(ev, (size_t)n, sizeof *ev, by_value);
  double big = n ? ev[n - 1] : 0;
  if (!(isfinite(big) && big > 0)) return 0;
  int lo = 0, gap = 0; /* the gap between ev[gap - 1] and ev[gap] (none: 0) */
  while (!(ev[lo] > STIFF_ZERO * big)) lo++;
  for (int i = lo + 1; i < n; i++)
    if (!gap || ev[i] / ev[i - 1] > ev[gap] / ev[gap - 1]) gap = i;
  f->fast = sqrt(big);
  f->slow = sqrt(ev[lo]);
  f->gap_below = sqrt(ev[gap ? gap - 1 : lo]);
  f->gap_above = sqrt(ev[gap ? gap : lo]);
  return f->fast / f->slow;
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
  if (mod->mass != MASS_DENSE) { /* R = diag(sqrt(M^-1_ii)), in O(m) */
    for (int i = 0; i < m; i++) {
      if (!(mod->minv_diag[i] > 0)) return 0;
      R[i * m + i] = sqrt(mod->minv_diag[i]);
    }
    return 1;
  }
  for (int j = 0; j < m; j++)
    for (int i = j; i < m; i++) {
      double a = mod->minv[(size_t)i * m + j];
      for (int k = 0; k < j; k++) a -= R[i * m + k] * R[j * m + k];
      if (i == j) {
        if (!(a > 0)) return 0;
        R[j * m + j] = sqrt(a);
      } else
        R[i * m + j] = a / R[j * m + j];
    }
  return 1;
}

// Whether the model is estimated: a constant M, and at most STIFF_MAX_M
// coordinates, or STIFF_MAX_M_FREE without constraints and with a diagonal M.
int model_stiffness_estimated(const Model *mod) {
  if (mod->minv_node || mod->mass_q) return 0;
  return mod->m <= STIFF_MAX_M || (mod->m <= STIFF_MAX_M_FREE && !mod->nu && mod->mass != MASS_DENSE);
}

// S = R' Ks R (Ks the symmetric part of K, R from minv_cholesky): for a
// diagonal M^-1 entry by entry (the products of the dense case, whose
// other terms are exact zeros), else by two products (T scratch).
static void congruence(const Model *mod, const double *K, const double *R, double *T, double *S) {
  int m = mod->m;
  if (mod->mass != MASS_DENSE) {
    for (int i = 0; i < m; i++)
      for (int j = 0; j < m; j++) S[i * m + j] = R[i * m + i] * ((K[i * m + j] + K[j * m + i]) / 2 * R[j * m + j]);
    return;
  }
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
}

double model_stiffness(const Model *mod, Frequencies *f) {
  int m = mod->m, nu = mod->nu;
  memset(f, 0, sizeof *f);
  if (!model_stiffness_estimated(mod)) return 0;
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
  /* S = R' Ks R, then projected onto the tangent space: the orthogonal
   * complement of the columns R' G' */
  congruence(mod, K, R, T, S);
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
  if (symmetric_eigenvalues(S, m, ev)) ratio = frequencies_of(ev, m, f);
done:
  free(prm), free(gu), free(G), free(lam), free(q), free(K), free(R), free(S), free(T);
  free(gp), free(gm), free(Gp), free(Gm), free(B), free(ev);
  return ratio;
}
