/* mass.c - the mass matrix M and products with its inverse.
 *
 * However M is written (identity, c, diag(...), or a full [[...]] matrix),
 * it is checked to be symmetric positive definite (GSL's Cholesky) and
 * classified by what it really is: identity, a scalar multiple of the
 * identity, diagonal, or dense. Products M^-1 v are then built as DAG nodes
 * for exactly that structure, so equal matrices written differently give
 * the same generated code, and multiplications by 1 and 0 never appear.
 *
 * An M whose entries use params cannot be inverted here. It is checked at
 * the default params like a constant one, and factored symbolically,
 * M = L D L' with L unit lower triangular, on DAG nodes of the params
 * (mass_setup_params); M^-1 v is then two triangular solves and a scaling
 * by D^-1 (for a diagonal M just v_i / m_ii). These nodes depend on params
 * only, so they are the same at every stage, and the emitted kernels
 * compute them from the params they are called with. Each D^-1 entry
 * carries a guard that makes it NaN when its pivot is not positive: params
 * that make M singular or indefinite make the step fail with a non-finite
 * result instead of running on. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>

#include "hbvmgen.h"

/* Operations the factorisation of an M with params may add to the DAG: it
 * is redone in every kernel call. A dense M of up to 38 coordinates fits. */
#define MAX_MASS_FACTOR 20000

// Why M fails its checks: at its value, or at the default params.
static const char *at_defaults(const Model *mod) {
  return mod->mass_q ? " at q0" : mod->minv_node ? " at the default params" : "";
}

// Record a diagonal M given by its m diagonal entries: each must be
// positive; M is then the identity, a scalar multiple of it, or diagonal.
// Returns 0, or -1 after reporting an error at loc. Costs O(m), so a large
// diagonal M never becomes an m x m matrix.
int mass_setup_diag(Model *mod, const double *diag, Loc loc) {
  int m = mod->m;
  mod->minv_diag = arena_alloc((size_t)m * sizeof(double));
  mod->mass = MASS_IDENTITY;
  if (loc.line == 0) loc = (Loc){1, 1};
  for (int i = 0; i < m; i++) {
    double d = diag[i];
    if (!(d > 0)) {
      error_at(loc, "M is not positive definite%s: diagonal entry %d is %.17g", at_defaults(mod), i + 1, d);
      return -1;
    }
    mod->minv_diag[i] = 1 / d;
    if (!isfinite(mod->minv_diag[i])) {
      error_at(loc, "M^-1 is not finite in double%s: diagonal entry %d of M is %.17g (below 1/DBL_MAX)",
               at_defaults(mod), i + 1, d);
      return -1;
    }
    if (d != diag[0]) mod->mass = MASS_DIAG;
  }
  if (mod->mass == MASS_IDENTITY && m > 0 && diag[0] != 1) mod->mass = MASS_SCALAR;
  return 0;
}

// Check a dense M (row-major m x m; NULL means identity) and record its
// structure and inverse in mod. Returns 0, or -1 after reporting an error.
int mass_setup(Model *mod, const double *dense, Loc loc) {
  int m = mod->m;
  mod->minv_diag = arena_alloc((size_t)m * sizeof(double));
  mod->mass = MASS_IDENTITY;
  for (int i = 0; i < m; i++) mod->minv_diag[i] = 1;
  if (!dense) return 0;
  if (loc.line == 0) loc = (Loc){1, 1};
  int diagonal = 1;
  for (int i = 0; i < m; i++)
    for (int j = 0; j < m; j++) {
      double a = dense[(size_t)i * m + j], b = dense[(size_t)j * m + i];
      if (i != j && a != 0) diagonal = 0;
      if (fabs(a - b) > 1e-14 * (fabs(a) + fabs(b))) {
        error_at(loc, "M is not symmetric%s: M[%d][%d] = %.17g but M[%d][%d] = %.17g", at_defaults(mod), i + 1, j + 1,
                 a, j + 1, i + 1, b);
        return -1;
      }
    }
  if (diagonal) {
    double *diag = arena_alloc((size_t)m * sizeof(double));
    for (int i = 0; i < m; i++) diag[i] = dense[(size_t)i * m + i];
    return mass_setup_diag(mod, diag, loc);
  }
  gsl_error_handler_t *old = gsl_set_error_handler_off();
  gsl_matrix *a = gsl_matrix_alloc((size_t)m, (size_t)m);
  memcpy(a->data, dense, (size_t)m * (size_t)m * sizeof(double));
  int rc = gsl_linalg_cholesky_decomp1(a);
  if (rc == 0) rc = gsl_linalg_cholesky_invert(a);
  gsl_set_error_handler(old);
  if (rc) {
    gsl_matrix_free(a);
    error_at(loc, "M is not positive definite%s (its Cholesky factorisation fails)", at_defaults(mod));
    return -1;
  }
  for (size_t i = 0; i < (size_t)m * m; i++)
    if (!isfinite(a->data[i])) {
      gsl_matrix_free(a);
      error_at(loc, "M^-1 is not finite in double%s: M is too close to singular", at_defaults(mod));
      return -1;
    }
  mod->mass = MASS_DENSE;
  mod->minv = arena_alloc((size_t)m * (size_t)m * sizeof(double));
  memcpy(mod->minv, a->data, (size_t)m * (size_t)m * sizeof(double));
  for (int i = 0; i < m; i++) mod->minv_diag[i] = mod->minv[(size_t)i * m + i];
  gsl_matrix_free(a);
  return 0;
}

// 1/x as a node, NaN unless x > 0: sqrt(x)/sqrt(x) is exactly 1 for every
// positive finite x and NaN otherwise, so the value is exactly 1/x where M
// is positive definite. For a constant x it folds to the constant 1/x.
// bounded: plain 1/x where x cannot be zero or negative (dag_positive),
// the guard's sqrt and division being 8% of the double pendulum in angles'
// step.
static int guarded_inverse(Dag *d, int x, int bounded) {
  if (bounded && dag_positive(d, x)) return dag_div(d, dag_const(d, 1), x);
  int r = dag_op(d, OP_SQRT, x, -1);
  return dag_mul(d, dag_div(d, dag_const(d, 1), x), dag_div(d, r, r));
}

// M = L D L' on nodes, row by row, without pivoting (the pivots of a
// positive definite M are positive): for i < j
//   W_ji = M_ji - sum_{k<i} W_jk L_ik    (= L_ji d_i),   L_ji = W_ji / d_i,
//   d_j  = M_jj - sum_{k<j} W_jk L_jk.
// a: m*m row-major nodes; L: m rows below the diagonal (arena), dinv: the m
// guarded 1/d_j (bounded: unguarded where d_j > 0 is proved). Zeros stay structural (folding), so a banded M keeps its
// band. Returns the entries of L, or -1 after an error at loc when the
// factorisation takes more than MAX_MASS_FACTOR operations (what: why it
// is redone, for the message).
long mass_ldl(Dag *d, const int *a, int m, SparseVec *L, int *dinv, int bounded, Loc loc, const char *what) {
  int start = d->n;
  int *w = xmalloc((size_t)m * sizeof *w);
  long total = 0;
  for (int j = 0; j < m; j++) {
    int nnz = 0;
    for (int i = 0; i < j; i++) {
      int x = a[(size_t)j * m + i];
      const SparseVec *row = &L[i];
      for (int e = 0; e < row->n; e++)
        if (!dag_is_zero(d, w[row->e[e].coord])) x = dag_sub(d, x, dag_mul(d, w[row->e[e].coord], row->e[e].node));
      w[i] = x;
      nnz += !dag_is_zero(d, x);
    }
    SparseVec *lj = &L[j];
    lj->e = arena_alloc((size_t)(nnz + 1) * sizeof *lj->e);
    lj->n = 0;
    int dj = a[(size_t)j * m + j];
    for (int i = 0; i < j; i++) {
      if (dag_is_zero(d, w[i])) continue;
      int l = dag_mul(d, w[i], dinv[i]);
      lj->e[lj->n++] = (Entry){i, l};
      dj = dag_sub(d, dj, dag_mul(d, w[i], l));
    }
    dinv[j] = guarded_inverse(d, dj, bounded);
    total += lj->n;
    if (d->n - start > MAX_MASS_FACTOR) {
      free(w);
      error_at(loc, "M %s, so it is factored in every kernel call: here that needs more than %d operations "
               "(at row %d of %d); make M constant, diagonal or sparser", what, MAX_MASS_FACTOR, j + 1, m);
      return -1;
    }
  }
  free(w);
  return total;
}

// M with params: its L D L' factors in mod (mass_L NULL when diagonal
// after all). Returns 0, or -1 after an error.
static int factor_params(Model *mod, const int *a, Loc loc) {
  mod->mass_L = arena_alloc((size_t)mod->m * sizeof *mod->mass_L);
  long total = mass_ldl(mod->dag, a, mod->m, mod->mass_L, mod->minv_node, 0, loc, "has params");
  if (total < 0) return -1;
  if (!total) mod->mass_L = NULL; /* diagonal after all */
  return 0;
}

// M with params: entries are m nodes of the diagonal, or m*m row-major when
// dense (constants or expressions of params, never of coordinates). Builds
// M^-1 in the DAG (mod->minv_node, mod->mass_L); the caller then checks M
// at the default params with mass_setup or mass_setup_diag. A dense M must
// be symmetric in its expressions, not only at the defaults. Returns 0, or
// -1 after reporting an error at loc.
int mass_setup_params(Model *mod, const int *entries, int dense, Loc loc) {
  Dag *d = mod->dag;
  int m = mod->m;
  mod->minv_node = arena_alloc((size_t)m * sizeof(int));
  if (!dense) {
    for (int i = 0; i < m; i++) mod->minv_node[i] = guarded_inverse(d, entries[i], 0);
    return 0;
  }
  for (int i = 0; i < m; i++)
    for (int j = i + 1; j < m; j++) {
      int a = entries[(size_t)i * m + j], b = entries[(size_t)j * m + i];
      if (a != b && !(d->nodes[a].op == OP_CONST && d->nodes[b].op == OP_CONST)) {
        error_at(loc, "M is not symmetric: M[%d][%d] and M[%d][%d] are different expressions of params (write the "
                 "same expression in both, or name it)", i + 1, j + 1, j + 1, i + 1);
        return -1;
      }
    }
  return factor_params(mod, entries, loc);
}

// out = M^-1 v from factors M = L D L' (L NULL: diagonal; dinv: D^-1):
// L y = v, z = D^-1 y, L' out = z (the last solve column by column, from
// the rows of L). out may not alias v.
void mass_ldl_solve(Dag *d, const SparseVec *L, const int *dinv, int m, const int *v, int *out) {
  memcpy(out, v, (size_t)m * sizeof *out);
  for (int i = 0; L && i < m; i++)
    for (int e = 0; e < L[i].n; e++)
      if (!dag_is_zero(d, out[L[i].e[e].coord]))
        out[i] = dag_sub(d, out[i], dag_mul(d, L[i].e[e].node, out[L[i].e[e].coord]));
  for (int i = 0; i < m; i++)
    if (!dag_is_zero(d, out[i])) out[i] = dag_mul(d, dinv[i], out[i]);
  for (int i = m - 1; L && i >= 0; i--)
    for (int e = 0; e < L[i].n && !dag_is_zero(d, out[i]); e++)
      out[L[i].e[e].coord] = dag_sub(d, out[L[i].e[e].coord], dag_mul(d, L[i].e[e].node, out[i]));
}

// The table of M^-1 in the DAG (registered on first use).
static int minv_table(const Model *mod, Dag *d) {
  for (int t = 0; t < d->ntables; t++)
    if (d->tables[t].v == mod->minv) return t;
  return dag_table(d, "minv", mod->minv, mod->m, mod->m);
}

// out = M^-1 v for node vectors of length m (out may not alias v). Zeros of
// v cost no lookup: the columns of a sparse Jacobian are mostly zeros. A
// dense constant M whose product has mod->mass_loop multiplications or
// more (nonzeros of M^-1 against those of v) is applied as rows of its table (dag_table_row), which the emitter
// prints as loops: m^2 operations would be m^2 lines of C. An M(q) with
// constraints is taken at mod->mass_at, the q0 input of the kernel being
// built (step_build sets it): M(q1) in the projection, M(q0) in the factor.
void minv_apply(const Model *mod, Dag *d, const int *v, int *out) {
  if (mod->mass_q && mod->mass_at) { /* M(q) with constraints: M at the kernel's point */
    minv_apply_at(mod, d, mod->mass_at, v, out);
    return;
  }
  if (mod->minv_node) {
    mass_ldl_solve(d, mod->mass_L, mod->minv_node, mod->m, v, out);
    return;
  }
  int m = mod->m, zero = dag_const(d, 0);
  long products = 0; /* of the straight-line form */
  for (int j = 0; mod->mass == MASS_DENSE && j < m; j++)
    for (int i = 0; !dag_is_zero(d, v[j]) && i < m; i++) products += mod->minv[(size_t)i * m + j] != 0;
  if (products && products >= mod->mass_loop) {
    int t = minv_table(mod, d), vec = dag_vector(d, v, m);
    for (int i = 0; i < m; i++) out[i] = dag_table_row(d, t, i, vec);
    return;
  }
  for (int i = 0; i < m; i++) {
    if (mod->mass != MASS_DENSE) {
      out[i] = dag_is_zero(d, v[i]) ? zero : dag_mul(d, dag_const(d, mod->minv_diag[i]), v[i]);
      continue;
    }
    int acc = dag_const(d, 0);
    for (int j = 0; j < m; j++) {
      double c = mod->minv[(size_t)i * m + j];
      if (c != 0 && !dag_is_zero(d, v[j])) acc = dag_add(d, acc, dag_mul(d, dag_const(d, c), v[j]));
    }
    out[i] = acc;
  }
}
