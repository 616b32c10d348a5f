/* mass_q.c - a mass matrix that depends on the coordinates, M(q).
 *
 * M may be any symmetric expression of q and params, in any of the
 * notations of a constant M (c, diag(...), [[...]], comprehensions). It is
 * kept as its m*m entries (mass_q_setup) and checked at q0 (mass_q_check):
 * positive definite there, by the same test as a constant M, which also
 * leaves M(q0) in mod->minv / minv_diag for the checks of the initial
 * values. For the step (step_mq.c) it gives, in the model's space of q
 * (inputs 0..m-1) and p (inputs m..2m-1),
 *   v = M(q)^-1 p                  an L D L' factorisation on nodes, unrolled
 *                                  (mass_ldl, the one an M with params has),
 *   F = grad_q T(q, p) + grad U    T = p' v / 2,
 * which the step substitutes at each stage point (Q_l, P_l). grad_q T comes
 * either in closed form, -1/2 v' (dM/dq_i) v with dM/dq_i from reverse
 * sweeps over the entries of M (the default: mass_q_closed), or from the
 * generator's reverse-mode AD through the factorisation. mass_q_report
 * prints both costs (--check); docs/method-mq.md has the measurements. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

// Record M(q) from its entries: m of the diagonal, or m*m row-major when
// dense. A dense M must be symmetric in its expressions (the same node on
// both sides, or equal constants); else an error at loc.
void mass_q_setup(Model *mod, const int *entries, int dense, Loc loc) {
  Dag *d = mod->dag;
  int m = mod->m, zero = dag_const(d, 0);
  mod->mass_loc = loc;
  mod->mass_q_closed = 1;
  int *a = arena_alloc((size_t)m * (size_t)m * sizeof *a);
  for (int i = 0; i < m; i++)
    for (int j = 0; j < m; j++) a[(size_t)i * m + j] = dense ? entries[(size_t)i * m + j] : i == j ? entries[i] : zero;
  for (int i = 0; i < m; i++)
    for (int j = i + 1; j < m; j++) {
      int x = a[(size_t)i * m + j], y = a[(size_t)j * m + i];
      if (x != y && !(d->nodes[x].op == OP_CONST && d->nodes[y].op == OP_CONST && d->nodes[x].val == d->nodes[y].val)) {
        error_at(loc, "M is not symmetric: M[%d][%d] and M[%d][%d] are different expressions (write the same "
                 "expression in both, or name it)", i + 1, j + 1, j + 1, i + 1);
        return;
      }
    }
  mod->mass_q = a;
}

// M(q0) at the params prm: symmetric positive definite, by the test of a
// constant M (mass_setup), which reports an error at M's statement.
// Returns 0, or -1 after an error.
int mass_q_check(Model *mod, const double *prm) {
  int m = mod->m;
  double *v = xmalloc((size_t)m * (size_t)m * sizeof *v);
  dag_eval_many(mod->dag, mod->mass_q, m * m, mod->q0, prm, v);
  int rc = mass_setup(mod, v, mod->mass_loc);
  free(v);
  return rc;
}

// out = M(q)^-1 v for the m*m entries a of M(q) at some point: its L D L'
// factors built on the fly (hash-consing shares them between calls at the
// same point).
static void solve_with(Model *mod, Dag *d, const int *a, const int *v, int *out) {
  int m = mod->m, *dinv = step_nodes(m);
  SparseVec *L = arena_alloc((size_t)m * sizeof *L);
  long nl = mass_ldl(d, a, m, L, dinv, 1, mod->mass_loc, "depends on q");
  if (nl < 0) { /* (reported: the step is not built) */
    for (int i = 0; i < m; i++) out[i] = dag_const(d, NAN);
    return;
  }
  mass_ldl_solve(d, nl ? L : NULL, dinv, m, v, out);
}

// out = M(q)^-1 v at the point q (m nodes of the step's inputs); for a
// constant M (or one with params only) minv_apply.
void minv_apply_at(const Model *mod, Dag *d, const int *q, const int *v, int *out) {
  if (!mod->mass_q) {
    minv_apply(mod, d, v, out);
    return;
  }
  int m = mod->m, *a = step_nodes(m * m);
  dag_subst(d, mod->mass_q, m * m, q, m, a);
  solve_with((Model *)mod, d, a, v, out);
}

// The sparse gradient dx (in the model's q) of entry (a, b) of M(q) and
// the weight of the pair in a quadratic form v' X v of a symmetric X,
// v_a v_b (twice off the diagonal); 0 where the entry does not depend on q.
static int entry_gradient(const Model *mod, Dag *d, int a, int b, const int *v, SparseVec *dx, int *w) {
  int x = mod->mass_q[(size_t)a * mod->m + b];
  if (!(d->nodes[x].flags & DEP_INPUT)) return 0;
  ad_gradient_sparse(d, x, mod->m, dx);
  *w = dag_mul(d, v[a], v[b]);
  if (a != b) *w = dag_add(d, *w, *w);
  return 1;
}

// grad_q T = -1/2 v' (dM/dq_i) v in closed form, g[i], for v the m nodes
// of M^-1 p: sum over the entries of M that depend on q, the symmetric
// pairs once with the factor 2.
static void kinetic_closed(Model *mod, const int *v, int *g) {
  Dag *d = mod->dag;
  int m = mod->m, w;
  for (int i = 0; i < m; i++) g[i] = dag_const(d, 0);
  for (int a = 0; a < m; a++)
    for (int b = a; b < m; b++) {
      SparseVec dx;
      if (!entry_gradient(mod, d, a, b, v, &dx, &w)) continue;
      for (int e = 0; e < dx.n; e++) g[dx.e[e].coord] = dag_sub(d, g[dx.e[e].coord], dag_mul(d, dx.e[e].node, w));
    }
  for (int i = 0; i < m; i++) g[i] = dag_mul(d, dag_const(d, 0.5), g[i]);
}

// out = grad_q T + Mdot v at the point q for the velocity v (m nodes each,
// a kernel's): -1/2 v' (dM/dq_i) v plus (sum_c dM/dq_c v_c) v, the terms
// quadratic in v that d/dt (G' M(q)^-1 p) adds to a constant M's (the
// multiplier consistent with (q, p), step_curvature).
void mass_q_inertial(const Model *mod, Dag *d, const int *q, const int *v, int *out) {
  int m = mod->m, w;
  for (int i = 0; i < m; i++) out[i] = dag_const(d, 0);
  for (int a = 0; a < m; a++)
    for (int b = a; b < m; b++) {
      SparseVec dx;
      if (!entry_gradient(mod, d, a, b, v, &dx, &w)) continue;
      int along = dag_const(d, 0); /* dM_ab/dt = sum_c dM_ab/dq_c v_c */
      for (int e = 0; e < dx.n; e++) {
        int at;
        dag_subst(d, &dx.e[e].node, 1, q, m, &at);
        out[dx.e[e].coord] = dag_sub(d, out[dx.e[e].coord], dag_mul(d, dag_const(d, 0.5), dag_mul(d, at, w)));
        along = dag_add(d, along, dag_mul(d, at, v[dx.e[e].coord]));
      }
      out[a] = dag_add(d, out[a], dag_mul(d, along, v[b]));
      if (a != b) out[b] = dag_add(d, out[b], dag_mul(d, along, v[a]));
    }
}

// Build mod->mq_v = M(q)^-1 p and mod->mq_force = grad_q T + grad U in the
// model's space (q: inputs 0..m-1, p: inputs m..2m-1), grad_q T in closed
// form or by AD (mod->mass_q_closed). Needs mod->gradU.
void mass_q_kinetic(Model *mod) {
  Dag *d = mod->dag;
  int m = mod->m, *p = step_nodes(m), *gt = step_nodes(2 * m);
  mod->mq_v = step_nodes(m);
  mod->mq_force = step_nodes(m);
  for (int i = 0; i < m; i++) p[i] = dag_input(d, m + i);
  dag_section(d, "M(q)^-1 p");
  d->where = mod->mass_loc;
  solve_with(mod, d, mod->mass_q, p, mod->mq_v);
  dag_section(d, "grad_q T");
  if (mod->mass_q_closed) {
    kinetic_closed(mod, mod->mq_v, gt);
  } else {
    int T = dag_const(d, 0);
    for (int i = 0; i < m; i++) T = dag_add(d, T, dag_mul(d, p[i], mod->mq_v[i]));
    ad_gradient(d, dag_mul(d, dag_const(d, 0.5), T), m, gt);
  }
  for (int i = 0; i < m; i++) mod->mq_force[i] = dag_add(d, gt[i], mod->gradU[i]);
}

// What a step with M(q) does not support yet: --iteration newton,
// --wide-step, and with constraints the constant multiplier (--multiplier
// const: the step is the poly family's). (--batch with constraints steps
// the lanes with the scalar step: emit_batch_by_lane.c.) Reports each at M's statement;
// returns 1 after an error.
int mass_q_refuse(const Model *mod, int newton, int wide, int const_mult) {
  if (!mod->mass_q) return 0;
  const char *what = newton ? "--iteration newton" : wide ? "--wide-step"
                     : mod->nu && const_mult ? "--multiplier const (constraints take the poly family's multiplier)" : NULL;
  if (!what) return 0;
  error_at(mod->mass_loc, "M depends on the coordinates: %s with such an M is not supported yet "
           "(docs/method-mq.md); write M constant, in other coordinates, or drop the option", what);
  return 1;
}

// --check: on which coordinates M depends, and the operations a stage
// spends on M(q)^-1 p and on grad_q T (closed form against AD).
void mass_q_report(FILE *f, const Model *mod) {
  Dag *d = mod->dag;
  int m = mod->m, n = 0;
  unsigned char *mark = xcalloc((size_t)d->n + 1, 1);
  dag_reach(d, mod->mass_q, m * m, mark);
  fprintf(f, "M: depends on q (");
  for (int id = 0; id < d->n; id++)
    if (mark[id] && d->nodes[id].op == OP_INPUT && d->nodes[id].idx < m)
      fprintf(f, "%s%s", n++ ? ", " : "", mod->coord_names[d->nodes[id].idx]);
  free(mark);
  long nv = dag_count_ops(d, mod->mq_v, m), nu = dag_count_ops(d, mod->gradU, m), both;
  int *all = step_nodes(2 * m);
  memcpy(all, mod->mq_v, (size_t)m * sizeof *all);
  memcpy(all + m, mod->mq_force, (size_t)m * sizeof *all);
  both = dag_count_ops(d, all, 2 * m);
  fprintf(f, "): a stage takes %ld operations for M(q)^-1 p (its L D L' factors unrolled) and %ld more for grad_q T "
          "(%s), grad U apart (%ld)\n", nv, both - nv - nu, mod->mass_q_closed ? "closed form" : "reverse-mode AD", nu);
}
