/* lu.c - linear systems whose entries are DAG nodes.
 *
 * The step solves small systems (the multiplier system, the consistent
 * initial multiplier) symbolically: the factorisation is built as DAG
 * nodes at generation time, so structural zeros are skipped and only real
 * fill-in is computed. The systems met here have a positive definite
 * symmetric part, so LU without pivoting is stable in any symmetric order;
 * the order is chosen at generation time by minimum degree, which keeps a
 * chain's band. */
#include <stdlib.h>

#include "step.h"

// Solve A x = r (n x n node matrix, overwritten) by an LU factorisation
// without pivoting, in the given order, skipping structural zeros (so fill-in
// is only where it really happens). pivot[k] receives the k-th pivot.
static void lu_solve(Dag *d, int *A, int *r, int n, int *x, int *pivot) {
  for (int k = 0; k < n; k++) {
    pivot[k] = A[k * n + k];
    for (int i = k + 1; i < n; i++) {
      if (dag_is_zero(d, A[i * n + k])) continue;
      int f = dag_div(d, A[i * n + k], A[k * n + k]);
      for (int c = k + 1; c < n; c++)
        if (!dag_is_zero(d, A[k * n + c])) A[i * n + c] = dag_sub(d, A[i * n + c], dag_mul(d, f, A[k * n + c]));
      r[i] = dag_sub(d, r[i], dag_mul(d, f, r[k]));
    }
  }
  for (int k = n - 1; k >= 0; k--) {
    int acc = r[k];
    for (int c = k + 1; c < n; c++)
      if (!dag_is_zero(d, A[k * n + c])) acc = dag_sub(d, acc, dag_mul(d, A[k * n + c], x[c]));
    x[k] = dag_div(d, acc, A[k * n + k]);
  }
}

// A fill-reducing elimination order for the n x n matrix of nodes A, chosen
// at generation time by the greedy minimum-degree rule on its (symmetric)
// structural pattern; ties go to the lower index, so an already banded
// order, like a chain's, is kept. perm[k] is the k-th row/column eliminated.
static void min_degree_order(const Dag *d, const int *A, int n, int *perm) {
  unsigned char *adj = xcalloc((size_t)n * (size_t)n, 1), *done = xcalloc((size_t)n, 1);
  int *deg = xcalloc((size_t)n, sizeof(int));
  for (int a = 0; a < n; a++)
    for (int c = 0; c < n; c++)
      if (a != c && (!dag_is_zero(d, A[a * n + c]) || !dag_is_zero(d, A[c * n + a]))) adj[a * n + c] = 1;
  for (int a = 0; a < n; a++)
    for (int c = 0; c < n; c++) deg[a] += adj[a * n + c];
  for (int k = 0; k < n; k++) {
    int best = -1;
    for (int a = 0; a < n; a++)
      if (!done[a] && (best < 0 || deg[a] < deg[best])) best = a;
    perm[k] = best;
    done[best] = 1;
    /* eliminating best joins its remaining neighbours pairwise (fill-in) */
    for (int a = 0; a < n; a++) {
      if (done[a] || !adj[best * n + a]) continue;
      deg[a]--;
      for (int c = 0; c < n; c++)
        if (c != a && !done[c] && adj[best * n + c] && !adj[a * n + c]) {
          adj[a * n + c] = 1;
          deg[a]++;
        }
    }
  }
  free(adj);
  free(done);
  free(deg);
}

// Solve A x = r in a minimum-degree elimination order perm: the LU of
// P A P' (whose symmetric part is still positive definite, so no pivoting
// is needed). pivot[k] and diag[k] (diag may be NULL) receive the k-th
// pivot and the diagonal entry it started from.
void lu_solve_ordered(Dag *d, const int *A, const int *r, int n, int *x, int *pivot, int *diag) {
  int *perm = step_nodes(n), *PA = step_nodes(n * n), *Pr = step_nodes(n), *Px = step_nodes(n);
  min_degree_order(d, A, n, perm);
  for (int i = 0; i < n; i++) {
    Pr[i] = r[perm[i]];
    for (int j = 0; j < n; j++) PA[i * n + j] = A[perm[i] * n + perm[j]];
    if (diag) diag[i] = PA[i * n + i];
  }
  lu_solve(d, PA, Pr, n, Px, pivot);
  for (int i = 0; i < n; i++) x[perm[i]] = Px[i];
}

// Factor A (n x n node matrix) once, for solves whose right-hand sides
// come later (the frozen multiplier matrix of step_poly.c): P A P' = L U in
// the minimum-degree order, no pivoting. f->F holds the multipliers of L
// below the diagonal, U above it and the reciprocals of U's pivots on it,
// so that a solve needs no division; structural zeros stay the DAG's zero.
// pivot[k] and diag[k] receive the k-th pivot and its starting diagonal.
void lu_factor(Dag *d, const int *A, int n, LuFactor *f, int *pivot, int *diag) {
  f->n = n;
  f->perm = step_nodes(n);
  f->F = step_nodes(n * n);
  min_degree_order(d, A, n, f->perm);
  int *F = f->F;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) F[i * n + j] = A[f->perm[i] * n + f->perm[j]];
  for (int k = 0; k < n; k++) diag[k] = F[k * n + k];
  for (int k = 0; k < n; k++) {
    pivot[k] = F[k * n + k];
    for (int i = k + 1; i < n; i++) {
      if (dag_is_zero(d, F[i * n + k])) continue;
      F[i * n + k] = dag_div(d, F[i * n + k], F[k * n + k]);
      for (int c = k + 1; c < n; c++)
        if (!dag_is_zero(d, F[k * n + c]))
          F[i * n + c] = dag_sub(d, F[i * n + c], dag_mul(d, F[i * n + k], F[k * n + c]));
    }
    F[k * n + k] = dag_div(d, dag_const(d, 1), F[k * n + k]);
  }
}

// Solve with a factor: x = A^-1 r, where f->F may hold the factor's own
// nodes or, in a later kernel, inputs standing for them at the same places.
void lu_apply(Dag *d, const LuFactor *f, const int *r, int *x) {
  int n = f->n, *y = step_nodes(n);
  const int *F = f->F;
  for (int i = 0; i < n; i++) y[i] = r[f->perm[i]];
  for (int k = 0; k < n; k++)
    for (int i = k + 1; i < n; i++)
      if (!dag_is_zero(d, F[i * n + k])) y[i] = dag_sub(d, y[i], dag_mul(d, F[i * n + k], y[k]));
  for (int k = n - 1; k >= 0; k--) {
    int acc = y[k];
    for (int c = k + 1; c < n; c++)
      if (!dag_is_zero(d, F[k * n + c])) acc = dag_sub(d, acc, dag_mul(d, F[k * n + c], y[c]));
    y[k] = dag_mul(d, acc, F[k * n + k]);
  }
  for (int i = 0; i < n; i++) x[f->perm[i]] = y[i];
}
