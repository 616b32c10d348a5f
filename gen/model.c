/* model.c - what the generator derives from an analysed model: the
 * gradient of U and the sparse Jacobian of g (reverse sweeps, ad.c), and
 * the consistency of the initial values with the constraints. */
#include <math.h>
#include <stdlib.h>

#include "hbvmgen.h"

#define CONSISTENCY_TOL 1e-10
#define RANK_TOL 1e-8            /* a unit gradient this close to the span of the others is dependent */
#define RANK_WORK_MAX 1e8        /* m nu^2 above this: the rank is not checked */

// Fill mod->gradU and the structurally nonzero columns mod->jac.
void model_differentiate(Model *mod) {
  Dag *d = mod->dag;
  int m = mod->m;
  mod->gradU = arena_alloc((size_t)m * sizeof(int));
  dag_section(d, "gradient of U");
  d->where = mod->U_loc;
  ad_gradient(d, mod->U, m, mod->gradU);
  mod->jac = arena_alloc((size_t)(mod->nu + 1) * sizeof(SparseVec));
  if (mod->nu) dag_section(d, "Jacobian of g");
  for (int a = 0; a < mod->nu; a++) {
    d->where = mod->g_loc[a];
    ad_gradient_sparse(d, mod->g[a], m, &mod->jac[a]);
  }
  if (mod->mass_q) mass_q_kinetic(mod);
}

static double *param_defaults(const Model *mod) {
  double *p = arena_alloc((size_t)(mod->nparams + 1) * sizeof(double));
  for (int i = 0; i < mod->nparams; i++) p[i] = mod->params[i].value;
  return p;
}

// Warn about each constraint whose gradient at q0 is zero or lies in the
// span of the gradients of the constraints before it (relative RANK_TOL,
// after normalisation, by Gram-Schmidt with reorthogonalisation): grad g(q0)
// has no full column rank, the multiplier system of the method is singular
// there (dependent constraints, or a singular configuration). jac holds the
// values of the entries of mod->jac at q0, column after column.
static void check_rank(const Model *mod, const double *jac) {
  int m = mod->m, nu = mod->nu;
  if (nu == 0 || (double)m * nu * nu > RANK_WORK_MAX) return;
  double *basis = xmalloc((size_t)m * nu * sizeof *basis), *v = xmalloc((size_t)m * sizeof *v);
  for (int a = 0, r = 0, rank = 0; a < nu; a++) {
    double norm = 0;
    for (int i = 0; i < m; i++) v[i] = 0;
    for (int e = 0; e < mod->jac[a].n; e++, r++) v[mod->jac[a].e[e].coord] = jac[r];
    for (int i = 0; i < m; i++) norm = hypot(norm, v[i]);
    if (!isfinite(norm)) continue; /* g not smooth at q0: no statement */
    if (norm == 0) {
      warning_at(mod->g_loc[a], "constraint %d has a zero gradient at q0: the constraints are not independent "
                 "there and the multiplier system is singular", a + 1);
      continue;
    }
    for (int i = 0; i < m; i++) v[i] /= norm;
    for (int pass = 0; pass < 2; pass++)
      for (int b = 0; b < rank; b++) {
        const double *u = basis + (size_t)b * m;
        double dot = 0;
        for (int i = 0; i < m; i++) dot += u[i] * v[i];
        for (int i = 0; i < m; i++) v[i] -= dot * u[i];
      }
    double rest = 0;
    for (int i = 0; i < m; i++) rest = hypot(rest, v[i]);
    if (rest <= RANK_TOL) {
      warning_at(mod->g_loc[a], "the gradient of constraint %d at q0 is a combination of those of the constraints "
                 "before it: the constraints are not independent there and the multiplier system is singular",
                 a + 1);
      continue;
    }
    for (int i = 0; i < m; i++) basis[(size_t)rank * m + i] = v[i] / rest;
    rank++;
  }
  free(basis);
  free(v);
}

// Warn when q0, p0 violate g(q0) = 0 or grad g(q0)' M^-1 p0 = 0, when U or g
// are not finite at q0, and when the constraints are dependent at q0.
void model_check_initial(const Model *mod) {
  const double *prm = param_defaults(mod);
  int m = mod->m, nu = mod->nu, nroots = 1 + nu;
  for (int a = 0; a < nu; a++) nroots += mod->jac[a].n;
  /* U, g and the Jacobian's entries at q0, all in one evaluation */
  int *roots = xmalloc((size_t)nroots * sizeof *roots);
  double *val = xmalloc((size_t)nroots * sizeof *val), *v = xmalloc((size_t)m * sizeof *v);
  roots[0] = mod->U;
  for (int a = 0, r = 1 + nu; a < nu; a++) {
    roots[1 + a] = mod->g[a];
    for (int e = 0; e < mod->jac[a].n; e++) roots[r++] = mod->jac[a].e[e].node;
  }
  dag_eval_many(mod->dag, roots, nroots, mod->q0, prm, val);
  if (!isfinite(val[0]))
    warning_at(mod->q0_loc, "U is not finite at %s (U = %g)", mod->q0_loc.line ? "q0" : "the default q0 = 0", val[0]);
  for (int i = 0; i < m; i++) {
    v[i] = mod->minv_diag[i] * mod->p0[i];
    if (mod->mass == MASS_DENSE) {
      v[i] = 0;
      for (int j = 0; j < m; j++) v[i] += mod->minv[(size_t)i * m + j] * mod->p0[j];
    }
  }
  const double *jac = val + 1 + nu;
  for (int a = 0, r = 0; a < nu; a++) {
    double ga = val[1 + a], hc = 0;
    if (!(fabs(ga) <= CONSISTENCY_TOL))
      warning_at(mod->q0_loc, "q0 violates constraint %d: g%d(q0) = %.3e", a + 1, a + 1, ga);
    for (int e = 0; e < mod->jac[a].n; e++, r++) hc += jac[r] * v[mod->jac[a].e[e].coord];
    if (!(fabs(hc) <= CONSISTENCY_TOL))
      warning_at(mod->p0_loc.line ? mod->p0_loc : mod->q0_loc,
                 "p0 violates hidden constraint %d: (grad g%d' M^-1 p0)(q0) = %.3e", a + 1, a + 1, hc);
  }
  check_rank(mod, jac);
  free(roots);
  free(val);
  free(v);
}
