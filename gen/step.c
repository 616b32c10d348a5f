/* step.c - one fixed-point sweep of HBVM(k,s), built as a DAG.
 *
 * The sweep maps (q0, p0, gamma, h, g(q0)) to the new gamma and p1 - p0
 * exactly as METHOD.md writes it:
 *   Q_l      = q0 + h sum_j Ihat[l][j] gamma_j                 stage points
 *   F_l, G_l = grad U(Q_l), grad g(Q_l)                         model derivatives
 *   psi_j    = sum_l b_l P_j(c_l) F_l,  rho_j likewise with G_l
 *   Theta_j  = psi_j + (the multiplier's force, projected on P_j)
 *   gamma_j  = M^-1 [delta_j0 p0 - h sum_i X[j][i] Theta_i]
 * How the multiplier is fixed is the method family's: step_const.c (the
 * paper's constant multiplier) or step_poly.c (a polynomial one). Building
 * the step in the DAG (rather than printing loops) lets folding and sharing
 * do the structural work: zero Jacobian entries, constant gradients, an
 * identity M, and the zeros of the multiplier system and of its factors
 * never reach the emitted code.
 *
 * The results are laid out as named blocks of the kernels' out[] arrays
 * (Step.kern), and the inputs as named blocks of DAG input slots
 * (Step.in): the emitter prints both from this description. */
#include <stdlib.h>
#include <string.h>

#include "step.h"

#define MAX_POLY_COEFS 4096 /* s nu: the polynomial multiplier's (s nu)^2 matrix */

static int *zeros(Dag *d, int n) {
  int *v = step_nodes(n), z = dag_const(d, 0);
  for (int i = 0; i < n; i++) v[i] = z;
  return v;
}

// Start a section of the DAG called label, made for the kernels b->owners:
// the emitter labels it in those kernels only.
void step_section(Build *b, const char *label) {
  dag_section(b->d, label);
  while (b->st->sec_owner.n < b->d->nlabels - 1) intvec_push(&b->st->sec_owner, 0);
  intvec_push(&b->st->sec_owner, (int)b->owners);
}

int step_in(Build *b, int block, int i) { return dag_input(b->d, b->st->in[block].first + i); }

// Coefficient j, coordinate i of gamma (the sweep's input) or of Theta.
static int gamma_coef(Build *b, const void *ctx, int j, int i) {
  (void)ctx;
  return step_in(b, IN_GAM, j * b->m + i);
}

static int vector_coef(Build *b, const void *ctx, int j, int i) {
  (void)b;
  return ((int *const *)ctx)[j][i];
}

// Row j of the s x s matrix X of METHOD.md applied to coordinate i of the
// coefficients coef(j): xi_0 v_0 - xi_1 v_1 for j = 0, else
// xi_j v_{j-1} - xi_{j+1} v_{j+1} (the last term absent for j = s-1).
static int apply_x(Build *b, int j, int i, int (*coef)(Build *, const void *, int, int), const void *ctx) {
  Dag *d = b->d;
  const double *xi = b->me->xi;
  int v = dag_mul(d, dag_const(d, xi[j]), coef(b, ctx, j == 0 ? 0 : j - 1, i));
  if (j + 1 < b->s) v = dag_sub(d, v, dag_mul(d, dag_const(d, xi[j + 1]), coef(b, ctx, j + 1, i)));
  return v;
}

// Row j of X applied to coordinate i of the vectors v[0..s-1].
int step_apply_x(Build *b, int j, int i, int **v) { return apply_x(b, j, i, vector_coef, v); }

// The projections sum_l b_l P_j(c_l) f(Q_l) of derivative entries f that are
// affine in q, in closed form: with Q(c) = q0 + h sum_r gamma_r int_0^c P_r,
//   sum_l b_l P_j(c_l) f(Q_l) = delta_j0 f(q0) + h sum_i (df/dq_i) (X gamma)_j,i
// (Gauss is exact on polynomials of degree < 2k and <P_j, int_0^c P_r> = X[j][r]),
// so they cost nothing per stage. out[j * n + r] for root r.
static void project_affine(Build *b, const int *roots, int n, int *out) {
  Dag *d = b->d;
  int m = b->m, s = b->s;
  step_section(b, "affine derivative entries, projected in closed form");
  int *q0 = step_nodes(m), *xg = step_nodes(s * m), *f0 = step_nodes(n);
  for (int i = 0; i < m; i++) q0[i] = step_in(b, IN_Q0, i);
  for (int j = 0; j < s; j++)
    for (int i = 0; i < m; i++) xg[j * m + i] = -1; /* built on first use */
  dag_subst(d, roots, n, q0, m, f0); /* all at once: one pass over the DAG */
  for (int r = 0; r < n; r++) {
    SparseVec grad; /* constants or parameters: f is affine */
    ad_gradient_sparse(d, roots[r], m, &grad);
    for (int j = 0; j < s; j++) {
      int acc = j == 0 ? f0[r] : dag_const(d, 0);
      for (int e = 0; e < grad.n; e++) {
        int i = grad.e[e].coord;
        if (xg[j * m + i] < 0) xg[j * m + i] = dag_mul(d, b->h, apply_x(b, j, i, gamma_coef, NULL));
        acc = dag_add(d, acc, dag_mul(d, grad.e[e].node, xg[j * m + i]));
      }
      out[j * n + r] = acc;
    }
  }
}

// Stage point l: Q[i] = q0[i] + h sum_j Ihat[l][j] gamma_j[i].
void step_stage_point(Build *b, int l, int *Q) {
  Dag *d = b->d;
  int m = b->m, s = b->s;
  for (int i = 0; i < m; i++) {
    int acc = dag_const(d, 0);
    for (int j = 0; j < s; j++)
      acc = dag_add(d, acc, dag_mul(d, dag_const(d, b->me->Ihat[l * s + j]), step_in(b, IN_GAM, j * m + i)));
    Q[i] = dag_add(d, step_in(b, IN_Q0, i), dag_mul(d, b->h, acc));
  }
}

// Whether the k stages of the roots are printed as one loop (DagLoop):
// when their straight-line code, k times the operations of the roots,
// would reach mod->stage_loop operations.
static int stages_rolled(Build *b, const int *roots, int n) {
  return (long)b->k * dag_count_ops(b->d, roots, n) >= b->mod->stage_loop;
}

// Stage points, model derivatives at each stage, and their projections
// psi_j and rho_j onto the Legendre basis. Entries of grad U and grad g that
// are affine in q are projected in closed form (project_affine); only the
// others are evaluated at the k stages: straight-line, or as one loop over
// the stages when that would be large (stages_rolled).
static void build_stages(Build *b) {
  Dag *d = b->d;
  const Method *me = b->me;
  int m = b->m, s = b->s;
  int nroots = m;
  for (int a = 0; a < b->nu; a++) nroots += b->mod->jac[a].n;
  int *roots = step_nodes(nroots), *img = step_nodes(nroots), *Q = step_nodes(m);
  memcpy(roots, b->mod->gradU, (size_t)m * sizeof(int));
  for (int a = 0, r = m; a < b->nu; a++)
    for (int e = 0; e < b->mod->jac[a].n; e++) roots[r++] = b->mod->jac[a].e[e].node;
  /* split the roots: affine ones (degree 0 or 1 in q) and the rest */
  int *affine = step_nodes(nroots), *curved = step_nodes(nroots), *where = step_nodes(nroots), naff = 0, ncur = 0;
  for (int r = 0; r < nroots; r++) {
    int deg = d->nodes[roots[r]].deg;
    if (deg == 0 || deg == 1) {
      where[r] = naff;
      affine[naff++] = roots[r];
    } else {
      where[r] = -1 - ncur;
      curved[ncur++] = roots[r];
    }
  }
  int *proj = step_nodes(s * nroots); /* proj[j * nroots + r]: the projection of root r on P_j */
  int *paff = step_nodes(s * naff);
  if (naff) project_affine(b, affine, naff, paff);
  for (int j = 0; j < s; j++)
    for (int r = 0; r < nroots; r++) proj[j * nroots + r] = where[r] >= 0 ? paff[j * naff + where[r]] : dag_const(d, 0);
  if (ncur && stages_rolled(b, curved, ncur)) {
    step_section(b, "the k stages as one loop: Q = q0 + h sum_j Ihat[l][j] gamma_j, grad U(Q), grad g(Q), summed "
                    "with the weights b_l P_j(c_l)");
    int *q0 = step_nodes(m), *gam = step_nodes(s * m);
    for (int i = 0; i < m; i++) q0[i] = step_in(b, IN_Q0, i);
    for (int i = 0; i < s * m; i++) gam[i] = step_in(b, IN_GAM, i);
    DagLoop lp = {curved, ncur, m, b->k, s, me->W, me->Ihat, q0, gam, b->h};
    int loop = dag_loop(d, &lp);
    for (int j = 0; j < s; j++)
      for (int r = 0; r < nroots; r++)
        if (where[r] < 0) proj[j * nroots + r] = dag_stage_sum(d, loop, j, -1 - where[r]);
    ncur = 0; /* (nothing left for the straight-line stages below) */
  }
  for (int l = 0; l < b->k && ncur; l++) {
    char *label = arena_alloc(128);
    snprintf(label, 128, "stage %d of %d: Q = q0 + h sum_j Ihat[%d][j] gamma_j, grad U(Q), grad g(Q)", l + 1, b->k, l + 1);
    step_section(b, label);
    step_stage_point(b, l, Q);
    dag_subst(d, curved, ncur, Q, m, img);
    for (int j = 0; j < s; j++) {
      int w = dag_const(d, me->W[l * s + j]);
      for (int r = 0; r < nroots; r++)
        if (where[r] < 0) proj[j * nroots + r] = dag_add(d, proj[j * nroots + r], dag_mul(d, w, img[-1 - where[r]]));
    }
  }
  b->psi = arena_alloc((size_t)s * sizeof(int *));
  b->rho = arena_alloc((size_t)s * sizeof(int **));
  for (int j = 0; j < s; j++) {
    b->psi[j] = step_nodes(m);
    memcpy(b->psi[j], proj + j * nroots, (size_t)m * sizeof(int));
    b->rho[j] = arena_alloc((size_t)(b->nu + 1) * sizeof(int *));
    for (int a = 0, r = m; a < b->nu; a++) {
      b->rho[j][a] = step_nodes(b->mod->jac[a].n);
      for (int e = 0; e < b->mod->jac[a].n; e++) b->rho[j][a][e] = proj[j * nroots + r++];
    }
  }
}

// The constraints c coupled with constraint a, each once, in the order met:
// those listed in touch[i] for a coordinate i of grad g_a (touch[i]: the
// constraints whose M^-1-weighted columns are nonzero at i). pair (nu ints,
// -1 at first) remembers the last a each c was listed for. Returns how
// many, written to out.
int step_coupled(Build *b, const IntVec *touch, int *pair, int a, int *out) {
  const SparseVec *col = &b->mod->jac[a];
  int n = 0;
  for (int e = 0; e < col->n; e++) {
    const IntVec *t = &touch[col->e[e].coord];
    for (int q = 0; q < t->n; q++)
      if (pair[t->v[q]] != a) {
        pair[t->v[q]] = a;
        out[n++] = t->v[q];
      }
  }
  return n;
}

// <rho_j[:, a], v> over the structural nonzeros of column a.
int step_dot_col(Build *b, int j, int a, const int *v) {
  Dag *d = b->d;
  const SparseVec *col = &b->mod->jac[a];
  int acc = dag_const(d, 0);
  for (int e = 0; e < col->n; e++) acc = dag_add(d, acc, dag_mul(d, b->rho[j][a][e], v[col->e[e].coord]));
  return acc;
}

// M^-1 psi_j and M^-1 rho_j[:, a] as dense node vectors.
static void build_minv_products(Build *b) {
  Dag *d = b->d;
  int m = b->m, s = b->s;
  b->owners = 1u << K_SWEEP;
  step_section(b, "M^-1 psi_j and M^-1 rho_j");
  int *dense = step_nodes(m);
  b->vpsi = arena_alloc((size_t)s * sizeof(int *));
  b->vrho = arena_alloc((size_t)s * sizeof(int **));
  for (int j = 0; j < s; j++) {
    b->vpsi[j] = step_nodes(m);
    minv_apply(b->mod, d, b->psi[j], b->vpsi[j]);
    b->vrho[j] = arena_alloc((size_t)(b->nu + 1) * sizeof(int *));
    for (int a = 0; a < b->nu; a++) {
      const SparseVec *col = &b->mod->jac[a];
      int z = dag_const(d, 0);
      for (int i = 0; i < m; i++) dense[i] = z;
      for (int e = 0; e < col->n; e++) dense[col->e[e].coord] = b->rho[j][a][e];
      b->vrho[j][a] = step_nodes(m);
      minv_apply(b->mod, d, dense, b->vrho[j][a]);
    }
  }
}

// gamma_j = M^-1 [delta_j0 p0 - h sum_i X[j][i] Theta_i] (s*m nodes in gam)
// and p1 - p0 = -h Theta_0 (m nodes in dp).
void step_gamma(Build *b, int **theta, int *gam, int *dp) {
  Dag *d = b->d;
  int m = b->m, s = b->s;
  int *v = step_nodes(m);
  for (int j = 0; j < s; j++) {
    for (int i = 0; i < m; i++) {
      int x = dag_mul(d, b->h, apply_x(b, j, i, vector_coef, theta));
      v[i] = j == 0 ? dag_sub(d, step_in(b, IN_P0, i), x) : dag_neg(d, x);
    }
    minv_apply(b->mod, d, v, gam + j * m);
  }
  for (int i = 0; i < m; i++) dp[i] = dag_neg(d, dag_mul(d, b->h, theta[0][i]));
}

// step_gamma, as the sweep's results "gam" and "dp"; theta is kept for
// step_theta_result.
void step_gamma_update(Build *b, int **theta) {
  int *gam = step_nodes(b->s * b->m), *dp = step_nodes(b->m);
  step_gamma(b, theta, gam, dp);
  step_result(b->st, K_SWEEP, "gam", SZ_SM, 1, b->s * b->m, gam);
  step_result(b->st, K_SWEEP, "dp", SZ_M, 1, b->m, dp);
  b->theta = theta;
}

// The sweep's last result "theta": Theta_1 .. Theta_{s-1} ((s-1) m nodes the
// sweep has computed anyway, so only stores), with dp the Legendre
// coefficients of p's polynomial on the step (p0 + dp int_0^c P_0 -
// h sum_{j>=1} Theta_j int_0^c P_j), which NAME_dense evaluates. Last, so
// that the iteration's finiteness tests stop before it.
void step_theta_result(Build *b) {
  int n = (b->s - 1) * b->m, *v = step_nodes(n + 1);
  for (int j = 1; j < b->s; j++) memcpy(v + (j - 1) * b->m, b->theta[j], (size_t)b->m * sizeof(int));
  step_result(b->st, K_SWEEP, "theta", SZ_M, b->s - 1, n, v);
}

// The dense columns G[a] (m nodes each) of grad g at the point q.
int **step_jacobian_at(Build *b, const int *q) {
  Model *mod = b->mod;
  int nnz = 0, **G = arena_alloc((size_t)(b->nu + 1) * sizeof(int *));
  for (int a = 0; a < b->nu; a++) nnz += mod->jac[a].n;
  int *roots = step_nodes(nnz), *img = step_nodes(nnz);
  for (int a = 0, r = 0; a < b->nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) roots[r++] = mod->jac[a].e[e].node;
  dag_subst(b->d, roots, nnz, q, b->m, img); /* all entries in one pass over the DAG */
  for (int a = 0, r = 0; a < b->nu; a++) {
    G[a] = zeros(b->d, b->m);
    for (int e = 0; e < mod->jac[a].n; e++) G[a][mod->jac[a].e[e].coord] = img[r++];
  }
  return G;
}

// B = G' M^-1 G (nu x nu) for the dense columns G, over the structural
// nonzeros of the Jacobian only.
void step_gram(Build *b, int **G, int *B) {
  Dag *d = b->d;
  Model *mod = b->mod;
  int m = b->m, nu = b->nu, z = dag_const(d, 0), *mcol = step_nodes(m);
  IntVec *touch = arena_alloc((size_t)m * sizeof(IntVec)); /* constraints on each coordinate */
  for (int a = 0; a < nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) intvec_push(&touch[mod->jac[a].e[e].coord], a);
  for (int i = 0; i < nu * nu; i++) B[i] = z;
  for (int c = 0; c < nu; c++) { /* B[:, c] = G' M^-1 G[:, c] */
    minv_apply(mod, d, G[c], mcol);
    for (int i = 0; i < m; i++)
      for (int t = 0; !dag_is_zero(d, mcol[i]) && t < touch[i].n; t++) {
        int a = touch[i].v[t];
        B[a * nu + c] = dag_add(d, B[a * nu + c], dag_mul(d, G[a][i], mcol[i]));
      }
  }
}

// The M-orthogonal projection of p onto grad g(q)' M^-1 p = 0, for the dense
// columns G of grad g at q and B = G' M^-1 G: dp = -G mu (m nodes) with
// B mu = G' M^-1 p, and the pivots and diagonal entries of B's factors (nu
// each), by which the caller tells a singular B.
void step_project_momenta(Build *b, int **G, const int *B, const int *p, int *dp, int *pivot, int *adiag) {
  Dag *d = b->d;
  int m = b->m, nu = b->nu, z = dag_const(d, 0);
  int *v = step_nodes(m), *rhs = step_nodes(nu), *mu = step_nodes(nu);
  minv_apply(b->mod, d, p, v);
  for (int a = 0; a < nu; a++) {
    rhs[a] = z;
    for (int i = 0; i < m; i++) rhs[a] = dag_add(d, rhs[a], dag_mul(d, G[a][i], v[i]));
  }
  lu_solve_ordered(d, B, rhs, nu, mu, pivot, adiag);
  for (int i = 0; i < m; i++) {
    dp[i] = z;
    for (int a = 0; a < nu; a++) dp[i] = dag_sub(d, dp[i], dag_mul(d, G[a][i], mu[a]));
  }
}

// The kernel "consistent" of NAME_project: at (q, p) = inputs (q0, p0), the
// Newton step towards g(q) = 0 with the smallest change in the M norm,
//   dq = -M^-1 G y,  (G' M^-1 G) y = g(q),  G = grad g(q),
// the projection dp of p onto the hidden constraint at q, and the pivots
// and diagonal of G' M^-1 G. NAME_project iterates it until dq is at
// round-off, then adds the last dp.
static void build_consistent(Build *b, const int *q, const int *p, const int *g) {
  Dag *d = b->d;
  int m = b->m, nu = b->nu, z = dag_const(d, 0);
  b->owners = 1u << K_CONSISTENT;
  step_section(b, "Newton step of q onto g = 0 (smallest in the M norm), p projected onto the hidden constraint");
  int *B = step_nodes(nu * nu), *y = step_nodes(nu), *gy = step_nodes(m), *dq = step_nodes(m), *dp = step_nodes(m);
  int *pivot = step_nodes(nu), *adiag = step_nodes(nu), *unused = step_nodes(nu);
  int **G = step_jacobian_at(b, q);
  step_gram(b, G, B);
  lu_solve_ordered(d, B, g, nu, y, unused, NULL); /* the factors are those of the projection below, shared */
  for (int i = 0; i < m; i++) {
    gy[i] = z;
    for (int a = 0; a < nu; a++) gy[i] = dag_add(d, gy[i], dag_mul(d, G[a][i], y[a]));
  }
  minv_apply(b->mod, d, gy, dq);
  for (int i = 0; i < m; i++) dq[i] = dag_neg(d, dq[i]);
  step_project_momenta(b, G, B, p, dp, pivot, adiag);
  Step *st = b->st;
  step_result(st, K_CONSISTENT, "dq", SZ_M, 1, m, dq);
  step_result(st, K_CONSISTENT, "dp", SZ_M, 1, m, dp);
  step_result(st, K_CONSISTENT, "pivot", SZ_NU, 1, nu, pivot);
  step_result(st, K_CONSISTENT, "adiag", SZ_NU, 1, nu, adiag);
}

// The kernel "initial" when the model's q0 or p0 use params: their values
// for the params of NAME_init_params.
static void build_initial_values(Build *b) {
  Model *mod = b->mod;
  int uses = 0;
  for (int i = 0; i < b->m; i++)
    uses |= b->d->nodes[mod->q0n[i]].op != OP_CONST || b->d->nodes[mod->p0n[i]].op != OP_CONST;
  if (!uses) return;
  step_result(b->st, K_INITIAL, "q0", SZ_M, 1, b->m, mod->q0n);
  step_result(b->st, K_INITIAL, "p0", SZ_M, 1, b->m, mod->p0n);
}

// The curvature terms hvv[a] = v' Hess(g_a)(q) v for the velocity v (any
// nodes, v may depend on q): the derivative of w_a(q) = grad g_a(q)' u along
// u, with u the momentum inputs held constant while differentiating, then
// u := v. With M(q) less grad g_a' M(q)^-1 (grad_q T + Mdot v), the rest of
// what is quadratic in v in d/dt (G' M(q)^-1 p) (mass_q_inertial).
void step_curvature(Build *b, const int *q, const int *v, int *hvv) {
  Dag *d = b->d;
  Model *mod = b->mod;
  int m = b->m, nu = b->nu, z = dag_const(d, 0), ndw = 0;
  int first = b->st->in[IN_P0].first, *u = step_nodes(m), *at_u = step_nodes(nu), *map = step_nodes(first + m);
  for (int i = 0; i < m; i++) u[i] = step_in(b, IN_P0, i);
  SparseVec *dw = arena_alloc((size_t)(nu + 1) * sizeof *dw); /* grad w_a, sparse, then at q */
  for (int a = 0; a < nu; a++) {
    int w = z;
    for (int e = 0; e < mod->jac[a].n; e++) w = dag_add(d, w, dag_mul(d, mod->jac[a].e[e].node, u[mod->jac[a].e[e].coord]));
    ad_gradient_sparse(d, w, m, &dw[a]);
    ndw += dw[a].n;
  }
  int *roots = step_nodes(ndw), *img = step_nodes(ndw);
  for (int a = 0, t = 0; a < nu; a++)
    for (int e = 0; e < dw[a].n; e++) roots[t++] = dw[a].e[e].node;
  dag_subst(d, roots, ndw, q, m, img); /* all in one pass over the DAG */
  for (int a = 0, t = 0; a < nu; a++) {
    at_u[a] = z;
    for (int e = 0; e < dw[a].n; e++) at_u[a] = dag_add(d, at_u[a], dag_mul(d, img[t++], u[dw[a].e[e].coord]));
  }
  for (int k = 0; k < first; k++) map[k] = dag_input(d, k);
  memcpy(map + first, v, (size_t)m * sizeof(int));
  dag_subst(d, at_u, nu, map, first + m, hvv);
  if (!mod->mass_q) return;
  int *f = step_nodes(m), *mf = step_nodes(m), **G = step_jacobian_at(b, q);
  mass_q_inertial(mod, d, q, v, f);
  minv_apply(mod, d, f, mf);
  for (int a = 0; a < nu; a++)
    for (int i = 0; i < m; i++) hvv[a] = dag_sub(d, hvv[a], dag_mul(d, G[a][i], mf[i]));
}

// gmu[a] = grad g_a(q)' M^-1 grad U(q), G the dense columns of grad g at q.
void step_force_along(Build *b, const int *q, int **G, int *gmu) {
  Dag *d = b->d;
  Model *mod = b->mod;
  int m = b->m, *gu = step_nodes(m), *mgu = step_nodes(m);
  dag_subst(d, mod->gradU, m, q, m, gu);
  minv_apply(mod, d, gu, mgu);
  for (int a = 0; a < b->nu; a++) {
    gmu[a] = dag_const(d, 0);
    for (int e = 0; e < mod->jac[a].n; e++) {
      int i = mod->jac[a].e[e].coord;
      gmu[a] = dag_add(d, gmu[a], dag_mul(d, G[a][i], mgu[i]));
    }
  }
}

// The multiplier consistent with (q0, p0): differentiating the hidden
// constraint G' M^-1 p = 0 along the flow gives
//   (G' M^-1 G) lambda = [v' Hess(g_a) v]_a - G' M^-1 grad U,  v = M^-1 p
// (step_curvature, step_force_along). For NAME_init and NAME_project; the
// polynomial family's step has it from its projection's factors.
static void build_initial_multiplier(Build *b, const int *q, const int *v) {
  Dag *d = b->d;
  int nu = b->nu;
  b->owners = 1u << K_LAMBDA0;
  step_section(b, "consistent initial multiplier");
  int *B = step_nodes(nu * nu), *r = step_nodes(nu), *piv = step_nodes(nu), *lambda0 = step_nodes(nu);
  int *hvv = step_nodes(nu), *gmu = step_nodes(nu);
  int **G = step_jacobian_at(b, q);
  step_force_along(b, q, G, gmu);
  step_gram(b, G, B);
  step_curvature(b, q, v, hvv);
  for (int a = 0; a < nu; a++) r[a] = dag_sub(d, hvv[a], gmu[a]);
  lu_solve_ordered(d, B, r, nu, lambda0, piv, NULL);
  step_result(b->st, K_LAMBDA0, "lambda", SZ_NU, 1, nu, lambda0);
}

// The kernels of the state outside the step that grow like nu^2 in the
// DAG (dense Jacobian columns, LU of G' M^-1 G), as layout only: the same
// blocks as build_diagnostics, zeros. The rolled form prints them as loops.
static void layout_constraint_kernels(Build *b) {
  int m = b->m, nu = b->nu;
  step_placeholder(b, K_HIDDEN, "hidden", SZ_NU, 1, nu);
  step_placeholder(b, K_LAMBDA0, "lambda", SZ_NU, 1, nu);
  step_placeholder(b, K_CONSISTENT, "dq", SZ_M, 1, m);
  step_placeholder(b, K_CONSISTENT, "dp", SZ_M, 1, m);
  step_placeholder(b, K_CONSISTENT, "pivot", SZ_NU, 1, nu);
  step_placeholder(b, K_CONSISTENT, "adiag", SZ_NU, 1, nu);
}

// The kernels of the model's events and switching functions at (q0, p0).
static void build_events(Build *b, const int *q, const int *p) {
  Dag *d = b->d;
  Model *mod = b->mod;
  int m = b->m;
  if (mod->nevents) { /* the model's inputs m..2m-1 are the momenta of the events */
    int *qp = step_nodes(2 * m), *ev = step_nodes(mod->nevents);
    memcpy(qp, q, (size_t)m * sizeof(int));
    memcpy(qp + m, p, (size_t)m * sizeof(int));
    b->owners = 1u << K_EVENTS;
    step_section(b, "events");
    dag_subst(d, mod->event_nodes, mod->nevents, qp, 2 * m, ev);
    step_result(b->st, K_EVENTS, "values", SZ_ONE, mod->nevents, mod->nevents, ev);
  }
  if (mod->nswitch) {
    int *sw = step_nodes(mod->nswitch);
    b->owners = 1u << K_SWITCH;
    step_section(b, "switching functions");
    dag_subst(d, mod->switch_nodes, mod->nswitch, q, m, sw);
    step_result(b->st, K_SWITCH, "values", SZ_ONE, mod->nswitch, mod->nswitch, sw);
  }
}

// Functions of the state outside the step: g(q), H(q,p), grad g(q)' M^-1 p,
// the first step's prediction gamma_0 = M^-1 p0, and the consistent
// multiplier; the events and switches. With b->lean, the kernels that grow
// like nu^2 are layout only (layout_constraint_kernels); g, H and M^-1 p0
// are built (linear in the model) so that emit_check sees their constants.
static void build_diagnostics(Build *b) {
  Dag *d = b->d;
  Model *mod = b->mod;
  int m = b->m, nu = b->nu;
  int *q = step_nodes(m), *p = step_nodes(m), *g = step_nodes(nu), *v = step_nodes(m), *hidden = step_nodes(nu);
  for (int i = 0; i < m; i++) {
    q[i] = step_in(b, IN_Q0, i);
    p[i] = step_in(b, IN_P0, i);
  }
  b->owners = 1u << K_G;
  step_section(b, "g(q0)");
  dag_subst(d, mod->g, nu, q, m, g);
  b->owners = 1u << K_MINV_P | 1u << K_ENERGY | 1u << K_HIDDEN | 1u << K_LAMBDA0;
  step_section(b, "M^-1 p0");
  minv_apply_at(mod, d, q, p, v);
  b->owners = 1u << K_ENERGY;
  step_section(b, "energy");
  int kin = dag_const(d, 0);
  for (int i = 0; i < m; i++) kin = dag_add(d, kin, dag_mul(d, p[i], v[i]));
  int U;
  dag_subst(d, &mod->U, 1, q, m, &U);
  int H = dag_add(d, dag_mul(d, dag_const(d, 0.5), kin), U);
  b->owners = 1u << K_HIDDEN;
  step_section(b, "hidden constraints");
  int **G = b->lean ? NULL : step_jacobian_at(b, q);
  for (int a = 0; a < nu && G; a++) {
    const SparseVec *col = &mod->jac[a];
    int acc = dag_const(d, 0);
    for (int e = 0; e < col->n; e++) acc = dag_add(d, acc, dag_mul(d, G[a][col->e[e].coord], v[col->e[e].coord]));
    hidden[a] = acc;
  }
  build_events(b, q, p);
  step_result(b->st, K_MINV_P, "gam0", SZ_M, 1, m, v);
  step_result(b->st, K_ENERGY, "H", SZ_ONE, 1, 1, &H);
  build_initial_values(b);
  if (!nu) return;
  step_result(b->st, K_G, "g", SZ_NU, 1, nu, g);
  if (b->lean) {
    layout_constraint_kernels(b);
    return;
  }
  step_result(b->st, K_HIDDEN, "hidden", SZ_NU, 1, nu, hidden);
  build_initial_multiplier(b, q, v);
  build_consistent(b, q, p, g);
}

// Append the result block name (len nodes, len = coef * sym) to kernel k.
void step_result(Step *st, KernelId k, const char *name, SizeSym sym, int coef, int len, const int *nodes) {
  Kernel *kn = &st->kern[k];
  ASSERT(kn->nout < MAX_BLOCKS);
  Slots *bl = &kn->out[kn->nout++];
  bl->name = name;
  bl->sym = sym;
  bl->coef = coef;
  bl->first = kn->nout > 1 ? bl[-1].first + bl[-1].len : 0;
  bl->len = len;
  bl->nodes = step_nodes(len);
  memcpy(bl->nodes, nodes, (size_t)len * sizeof(int));
}

// A result block of zeros: its place in the layout only, for a kernel the
// rolled form prints as loops (step_build_layout).
void step_placeholder(Build *b, KernelId k, const char *name, SizeSym sym, int coef, int len) {
  step_result(b->st, k, name, sym, coef, len, zeros(b->d, len));
}

const Slots *step_block(const Step *st, KernelId k, const char *name) {
  for (int i = 0; i < st->kern[k].nout; i++)
    if (!strcmp(st->kern[k].out[i].name, name)) return &st->kern[k].out[i];
  return NULL;
}

int kernel_size(const Kernel *k) { return k->nout ? k->out[k->nout - 1].first + k->out[k->nout - 1].len : 0; }

// Lay out the input blocks: DAG inputs 0..m-1 are the model's coordinates,
// the kernels' inputs follow in signature order.
static void layout_inputs(Step *st, int m, int nu, int s, int nlam, int nlu, int npth) {
  static const struct {
    const char *name;
    SizeSym sym;
    int scalar, narrow, wrap;
  } spec[IN_COUNT] = {
      [IN_Q0] = {"q0", SZ_M, 0, 0, 0},  [IN_P0] = {"p0", SZ_M, 0, 0, 0},  [IN_GAM] = {"gam", SZ_SM, 0, 0, 0},
      [IN_H] = {"h", SZ_ONE, 1, 1, 1},  [IN_G0] = {"g0", SZ_NU, 0, 1, 0}, [IN_LAM] = {"lam", SZ_SNU, 0, 0, 0},
      [IN_LU] = {"lu", SZ_ONE, 0, 0, 0},      [IN_PTH] = {"pth", SZ_SM, 0, 0, 0},
  };
  int len[IN_COUNT] = {[IN_Q0] = m, [IN_P0] = m, [IN_GAM] = s * m, [IN_H] = 1, [IN_G0] = nu, [IN_LAM] = nlam, [IN_LU] = nlu,
                       [IN_PTH] = npth};
  for (int i = 0, first = m; i < IN_COUNT; i++) {
    Slots *bl = &st->in[i];
    bl->name = spec[i].name;
    bl->sym = spec[i].sym;
    bl->coef = spec[i].sym == SZ_ONE ? len[i] : 1;
    bl->scalar = spec[i].scalar;
    bl->narrow = spec[i].narrow;
    bl->wrap = spec[i].wrap;
    bl->first = first;
    bl->len = len[i];
    first += len[i];
  }
}

static const struct {
  const char *name, *what;
  int wide;
} kernel_spec[K_COUNT] = {
    [K_SWEEP] = {"sweep", NULL, 1},
    [K_FACTOR] = {"factor", NULL, 1},
    [K_MINV_P] = {"minv_p", "out = M^-1 p0: the first step's prediction of gamma_0", 0},
    [K_ENERGY] = {"energy_kernel", "out[0] = H(q0, p0) = p0' M^-1 p0 / 2 + U(q0)", 0},
    [K_G] = {"g", "out = g(q0)", 0},
    [K_HIDDEN] = {"hidden_kernel", "out = grad g(q0)' M^-1 p0", 0},
    [K_LAMBDA0] = {"lambda0",
                   "out = the multiplier consistent with (q0, p0):\n"
                   " * (G' M^-1 G) lambda = [v' Hess(g_a) v]_a - G' M^-1 grad U, G = grad g(q0), v = M^-1 p0",
                   0},
    [K_PROJECT] = {"project_p1", NULL, 1},
    [K_CONSISTENT] = {"consistent",
                      "The projection onto the constraints, at (q0, p0): out = the Newton step dq onto g = 0,\n"
                      " * smallest in the M norm,"
                      " -M^-1 G (G' M^-1 G)^-1 g(q0) (M), the projection dp of p0 onto the hidden constraint (M),\n"
                      " * pivots (NU) and diagonal (NU) of G' M^-1 G; G = grad g(q0)",
                      0},
    [K_INITIAL] = {"initial", "out = the model's q0 (M) and p0 (M) at the parameters prm", 0},
    [K_EVENTS] = {"events_kernel", "out = the model's event functions at (q0, p0), in the order written", 0},
    [K_SWITCH] = {"switch_kernel", "out = the model's switching functions at q0 (where U or g is not smooth)", 0},
    [K_NFACTOR] = {"newton_factor", NULL, 0},
    [K_NSOLVE] = {"newton_solve", NULL, 0},
};

// The step of step_build (lean 0) or step_build_layout (lean 1).
static Step *build_step(Model *mod, const Method *me, int lean) {
  Step *st = arena_alloc(sizeof *st);
  int m = mod->m, nu = mod->nu, s = me->s;
  if (!lean && me->family == MULT_POLY && s * nu > MAX_POLY_COEFS) { /* (the analysis caps nu itself; the rolled band has no cap) */
    error_at(mod->g_loc[0], "%d constraints at s=%d: the polynomial multiplier has at most %d coefficients "
             "(s nu); pass --multiplier const or a smaller -s", nu, s, MAX_POLY_COEFS);
    return NULL;
  }
  /* a node limit hit here is the step's: reported at the constraints (or U) */
  mod->dag->where = nu ? mod->g_loc[0] : mod->U_loc;
  mod->dag->where_note = " (the limit was reached building the step for these equations: "
                         "pass --multiplier const, or a smaller -s or -k)";
  st->m = m;
  st->nu = nu;
  st->s = s;
  for (int k = 0; k < K_COUNT; k++) {
    st->kern[k].name = kernel_spec[k].name;
    st->kern[k].what = kernel_spec[k].what;
    st->kern[k].wide = kernel_spec[k].wide;
  }
  layout_inputs(st, m, nu, s, 0, 0, 0);
  Build b = {mod, me, mod->dag, st, m, nu, s, me->k, -1, 1u << K_SWEEP | 1u << K_FACTOR, NULL, NULL, NULL, NULL, NULL, lean};
  b.h = step_in(&b, IN_H, 0);
  int poly = me->family == MULT_POLY && nu;
  if (poly) layout_inputs(st, m, nu, s, s * nu, 0, 0); /* the factor's length is known once it is built */
  if (mod->mass_q) { /* M(q): the general-H sweep carries Theta in the input pth */
    if (poly) { /* with constraints: the poly family's multiplier and end of step */
      layout_inputs(st, m, nu, s, s * nu, 0, s * m);
      int *at = step_nodes(m); /* minv_apply: M at each kernel's q0 */
      for (int i = 0; i < m; i++) at[i] = step_in(&b, IN_Q0, i);
      mod->mass_at = at;
      build_mq_constrained(&b);
    } else {
      layout_inputs(st, m, nu, s, 0, 0, s * m);
      build_mq_sweep(&b);
    }
    build_diagnostics(&b);
    return st;
  }
  if (lean) { /* the rolled kernels: their layout only */
    if (poly) layout_poly_multiplier(&b);
    else layout_const_multiplier(&b);
    build_diagnostics(&b);
    if (me->iteration != ITER_FIXED) layout_newton_rolled(&b); /* (with constraints the const family: roll.c) */
    return st;
  }
  build_stages(&b);
  if (poly) {
    build_poly_multiplier(&b);
  } else {
    if (nu) build_minv_products(&b);
    build_const_multiplier(&b);
  }
  build_diagnostics(&b);
  if (me->iteration != ITER_FIXED) build_newton(&b);
  return st;
}

Step *step_build(Model *mod, const Method *me) { return build_step(mod, me, 0); }

Step *step_build_layout(Model *mod, const Method *me) { return build_step(mod, me, 1); }
