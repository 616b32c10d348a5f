/* model.c - what the generator derives from an analysed model: the
 * gradient of U and the sparse Jacobian of g (reverse sweeps, ad.c), and
 * the consistency of the initial values with the constraints. */
#include <math.h>
#include <stdlib.h>

#include "hbvmgen.h"

#define CONSISTENCY_TOL 1e-10

// Fill mod->gradU and the structurally nonzero columns mod->jac.
void model_differentiate(Model *mod) {
  Dag *d = mod->dag;
  int m = mod->m;
  mod->gradU = arena_alloc((size_t)m * sizeof(int));
  dag_section(d, "gradient of U");
  ad_gradient(d, mod->U, m, mod->gradU);
  mod->jac = arena_alloc((size_t)(mod->nu + 1) * sizeof(SparseVec));
  int *col = malloc((size_t)m * sizeof(int));
  if (!col) internal_error("out of memory");
  if (mod->nu) dag_section(d, "Jacobian of g");
  for (int a = 0; a < mod->nu; a++) {
    ad_gradient(d, mod->g[a], m, col);
    int nnz = 0;
    for (int i = 0; i < m; i++) nnz += !dag_is_zero(d, col[i]);
    SparseVec *sv = &mod->jac[a];
    sv->e = arena_alloc((size_t)(nnz + 1) * sizeof(Entry));
    for (int i = 0; i < m; i++)
      if (!dag_is_zero(d, col[i])) sv->e[sv->n++] = (Entry){i, col[i]};
  }
  free(col);
}

static double *param_defaults(const Model *mod) {
  double *p = arena_alloc((size_t)(mod->nparams + 1) * sizeof(double));
  for (int i = 0; i < mod->nparams; i++) p[i] = mod->params[i].value;
  return p;
}

// Warn when q0, p0 violate g(q0) = 0 or grad g(q0)' M^-1 p0 = 0, and when
// U or g are not finite at q0.
void model_check_initial(const Model *mod) {
  const double *prm = param_defaults(mod);
  int m = mod->m;
  double U0 = dag_eval(mod->dag, mod->U, mod->q0, prm);
  if (!isfinite(U0))
    warning_at(mod->q0_loc, "U is not finite at %s (U = %g)", mod->q0_loc.line ? "q0" : "the default q0 = 0", U0);
  double *v = malloc((size_t)m * sizeof(double));
  if (!v) internal_error("out of memory");
  for (int i = 0; i < m; i++) {
    v[i] = mod->minv_diag[i] * mod->p0[i];
    if (mod->mass == MASS_DENSE) {
      v[i] = 0;
      for (int j = 0; j < m; j++) v[i] += mod->minv[(size_t)i * m + j] * mod->p0[j];
    }
  }
  for (int a = 0; a < mod->nu; a++) {
    double ga = dag_eval(mod->dag, mod->g[a], mod->q0, prm);
    if (!(fabs(ga) <= CONSISTENCY_TOL))
      warning_at(mod->q0_loc, "q0 violates constraint %d: g%d(q0) = %.3e", a + 1, a + 1, ga);
    double hc = 0;
    for (int e = 0; e < mod->jac[a].n; e++)
      hc += dag_eval(mod->dag, mod->jac[a].e[e].node, mod->q0, prm) * v[mod->jac[a].e[e].coord];
    if (!(fabs(hc) <= CONSISTENCY_TOL))
      warning_at(mod->p0_loc.line ? mod->p0_loc : mod->q0_loc,
                 "p0 violates hidden constraint %d: (grad g%d' M^-1 p0)(q0) = %.3e", a + 1, a + 1, hc);
  }
  free(v);
}
