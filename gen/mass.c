/* mass.c - the mass matrix M and products with its inverse.
 *
 * However M is written (identity, c, diag(...), or a full [[...]] matrix),
 * it is checked to be symmetric positive definite (GSL's Cholesky) and
 * classified by what it really is: identity, a scalar multiple of the
 * identity, diagonal, or dense. Products M^-1 v are then built as DAG nodes
 * for exactly that structure, so equal matrices written differently give
 * the same generated code, and multiplications by 1 and 0 never appear. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>

#include "hbvmgen.h"

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
      error_at(loc, "M is not positive definite: diagonal entry %d is %.17g", i + 1, d);
      return -1;
    }
    mod->minv_diag[i] = 1 / d;
    if (!isfinite(mod->minv_diag[i])) {
      error_at(loc, "M^-1 is not finite in double: diagonal entry %d of M is %.17g (below 1/DBL_MAX)", i + 1, d);
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
        error_at(loc, "M is not symmetric: M[%d][%d] = %.17g but M[%d][%d] = %.17g", i + 1, j + 1, a, j + 1, i + 1, b);
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
    error_at(loc, "M is not positive definite (its Cholesky factorisation fails)");
    return -1;
  }
  for (size_t i = 0; i < (size_t)m * m; i++)
    if (!isfinite(a->data[i])) {
      gsl_matrix_free(a);
      error_at(loc, "M^-1 is not finite in double: M is too close to singular");
      return -1;
    }
  mod->mass = MASS_DENSE;
  mod->minv = arena_alloc((size_t)m * (size_t)m * sizeof(double));
  memcpy(mod->minv, a->data, (size_t)m * (size_t)m * sizeof(double));
  for (int i = 0; i < m; i++) mod->minv_diag[i] = mod->minv[(size_t)i * m + i];
  gsl_matrix_free(a);
  return 0;
}

// out = M^-1 v for node vectors of length m (out may not alias v). Zeros of
// v cost no lookup: the columns of a sparse Jacobian are mostly zeros.
void minv_apply(const Model *mod, Dag *d, const int *v, int *out) {
  int m = mod->m, zero = dag_const(d, 0);
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
