/* step.c - one fixed-point sweep of HBVM(k,s), built as a DAG.
 *
 * The sweep maps (q0, p0, gamma, h, g(q0)) to the new gamma, lambda and
 * p1 - p0 exactly as METHOD.md writes it:
 *   Q_l     = q0 + h sum_j Ihat[l][j] gamma_j                  stage points
 *   F_l, G_l = grad U(Q_l), grad g(Q_l)                         model derivatives
 *   psi_j   = sum_l b_l P_j(c_l) F_l,  rho_j likewise with G_l
 *   A lambda = r                                                the multiplier system
 *   gamma_j = M^-1 [delta_j0 p0 - h sum_i X[j][i] (psi_i + rho_i lambda)]
 * Building it in the DAG (rather than printing loops) lets folding and
 * sharing do the structural work: zero Jacobian entries, constant
 * gradients, an identity M, and the zeros of A and of its LU factors never
 * reach the emitted code. A is factored without pivoting, in the order of
 * the constraints: its symmetric part h xi_0 rho_0' M^-1 rho_0 is positive
 * definite when the constraints are independent, so no pivot vanishes, and
 * a banded A (a chain) keeps its band. */
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

#define MAX_DENSE_NU 4096

typedef struct {
  Model *mod;
  const Method *me;
  Dag *d;
  Step *st;
  int m, nu, s, k;
  int h;          /* node of the step size */
  int **psi;      /* s x m */
  int ***rho;     /* s x nu x (entries of jac[a]) */
  int ***vrho;    /* s x nu x m: M^-1 rho_j[:, a], dense */
  int **vpsi;     /* s x m: M^-1 psi_j */
} Build;

static int *nodes(int n) { return arena_alloc((size_t)(n > 0 ? n : 1) * sizeof(int)); }

static int *zeros(Dag *d, int n) {
  int *v = nodes(n), z = dag_const(d, 0);
  for (int i = 0; i < n; i++) v[i] = z;
  return v;
}

// sum_r X[j][r] gamma_r (coordinate i) for the s x s matrix X of METHOD.md:
// xi_0 gamma_0 - xi_1 gamma_1 for j = 0, xi_j gamma_{j-1} - xi_{j+1} gamma_{j+1}.
static int x_gamma(Build *b, int j, int i) {
  Dag *d = b->d;
  const double *xi = b->me->xi;
  int m = b->m, in = b->st->in_gam;
  int v = dag_mul(d, dag_const(d, xi[j]), dag_input(d, in + (j == 0 ? 0 : j - 1) * m + i));
  if (j + 1 < b->s) v = dag_sub(d, v, dag_mul(d, dag_const(d, xi[j + 1]), dag_input(d, in + (j + 1) * m + i)));
  return v;
}

// The projections sum_l b_l P_j(c_l) f(Q_l) of derivative entries f that are
// affine in q, in closed form: with Q(c) = q0 + h sum_r gamma_r int_0^c P_r,
//   sum_l b_l P_j(c_l) f(Q_l) = delta_j0 f(q0) + h sum_i (df/dq_i) (X gamma)_j,i
// (Gauss is exact on polynomials of degree < 2k and <P_j, int_0^c P_r> = X[j][r]),
// so they cost nothing per stage. out[j * n + r] for root r.
static void project_affine(Build *b, const int *roots, int n, int *out) {
  Dag *d = b->d;
  int m = b->m, s = b->s;
  dag_section(d, "affine derivative entries, projected in closed form");
  int *grad = nodes(m), *q0 = nodes(m), *xg = nodes(s * m);
  for (int i = 0; i < m; i++) q0[i] = dag_input(d, b->st->in_q0 + i);
  for (int j = 0; j < s; j++)
    for (int i = 0; i < m; i++) xg[j * m + i] = -1; /* built on first use */
  for (int r = 0; r < n; r++) {
    int f0;
    ad_gradient(d, roots[r], m, grad); /* constants or parameters: f is affine */
    dag_subst(d, &roots[r], 1, q0, m, &f0);
    for (int j = 0; j < s; j++) {
      int acc = j == 0 ? f0 : dag_const(d, 0);
      for (int i = 0; i < m; i++) {
        if (dag_is_zero(d, grad[i])) continue;
        if (xg[j * m + i] < 0) xg[j * m + i] = dag_mul(d, b->h, x_gamma(b, j, i));
        acc = dag_add(d, acc, dag_mul(d, grad[i], xg[j * m + i]));
      }
      out[j * n + r] = acc;
    }
  }
}

// Stage points, model derivatives at each stage, and their projections
// psi_j and rho_j onto the Legendre basis. Entries of grad U and grad g that
// are affine in q are projected in closed form (project_affine); only the
// others are evaluated at the k stages.
static void build_stages(Build *b) {
  Dag *d = b->d;
  const Method *me = b->me;
  int m = b->m, s = b->s;
  int nroots = m;
  for (int a = 0; a < b->nu; a++) nroots += b->mod->jac[a].n;
  int *roots = nodes(nroots), *img = nodes(nroots), *Q = nodes(m);
  memcpy(roots, b->mod->gradU, (size_t)m * sizeof(int));
  for (int a = 0, r = m; a < b->nu; a++)
    for (int e = 0; e < b->mod->jac[a].n; e++) roots[r++] = b->mod->jac[a].e[e].node;
  /* split the roots: affine ones (degree 0 or 1 in q) and the rest */
  int *affine = nodes(nroots), *curved = nodes(nroots), *where = nodes(nroots), naff = 0, ncur = 0;
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
  int *proj = nodes(s * nroots); /* proj[j * nroots + r]: the projection of root r on P_j */
  int *paff = nodes(s * naff);
  if (naff) project_affine(b, affine, naff, paff);
  for (int j = 0; j < s; j++)
    for (int r = 0; r < nroots; r++) proj[j * nroots + r] = where[r] >= 0 ? paff[j * naff + where[r]] : dag_const(d, 0);
  for (int l = 0; l < b->k && ncur; l++) {
    char *label = arena_alloc(128);
    snprintf(label, 128, "stage %d of %d: Q = q0 + h sum_j Ihat[%d][j] gamma_j, grad U(Q), grad g(Q)", l + 1, b->k, l + 1);
    dag_section(d, label);
    for (int i = 0; i < m; i++) {
      int acc = dag_const(d, 0);
      for (int j = 0; j < s; j++)
        acc = dag_add(d, acc, dag_mul(d, dag_const(d, me->Ihat[l * s + j]), dag_input(d, b->st->in_gam + j * m + i)));
      Q[i] = dag_add(d, dag_input(d, b->st->in_q0 + i), dag_mul(d, b->h, acc));
    }
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
    b->psi[j] = nodes(m);
    memcpy(b->psi[j], proj + j * nroots, (size_t)m * sizeof(int));
    b->rho[j] = arena_alloc((size_t)(b->nu + 1) * sizeof(int *));
    for (int a = 0, r = m; a < b->nu; a++) {
      b->rho[j][a] = nodes(b->mod->jac[a].n);
      for (int e = 0; e < b->mod->jac[a].n; e++) b->rho[j][a][e] = proj[j * nroots + r++];
    }
  }
}

// <rho_j[:, a], v> over the structural nonzeros of column a.
static int dot_col(Build *b, int j, int a, const int *v) {
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
  dag_section(d, "M^-1 psi_j and M^-1 rho_j");
  int *dense = nodes(m);
  b->vpsi = arena_alloc((size_t)s * sizeof(int *));
  b->vrho = arena_alloc((size_t)s * sizeof(int **));
  for (int j = 0; j < s; j++) {
    b->vpsi[j] = nodes(m);
    minv_apply(b->mod, d, b->psi[j], b->vpsi[j]);
    b->vrho[j] = arena_alloc((size_t)(b->nu + 1) * sizeof(int *));
    for (int a = 0; a < b->nu; a++) {
      const SparseVec *col = &b->mod->jac[a];
      int z = dag_const(d, 0);
      for (int i = 0; i < m; i++) dense[i] = z;
      for (int e = 0; e < col->n; e++) dense[col->e[e].coord] = b->rho[j][a][e];
      b->vrho[j][a] = nodes(m);
      minv_apply(b->mod, d, dense, b->vrho[j][a]);
    }
  }
}

// The combination xi_0 <x_0, y_0> + sum_j xi_j (<x_j, y_{j-1}> - <x_{j-1}, y_j>)
// with x = rho[:, a] and y_j given by yj(j).
static int skew_form(Build *b, int a, int **y) {
  Dag *d = b->d;
  const double *xi = b->me->xi;
  int acc = dag_mul(d, dag_const(d, xi[0]), dot_col(b, 0, a, y[0]));
  for (int j = 1; j < b->s; j++) {
    int t = dag_sub(d, dot_col(b, j, a, y[j - 1]), dot_col(b, j - 1, a, y[j]));
    acc = dag_add(d, acc, dag_mul(d, dag_const(d, xi[j]), t));
  }
  return acc;
}

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
  unsigned char *adj = calloc((size_t)n * (size_t)n, 1), *done = calloc((size_t)n, 1);
  int *deg = calloc((size_t)n, sizeof(int));
  if (!adj || !done || !deg) internal_error("out of memory in min_degree_order");
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

// Solve A x = r in the elimination order perm: the LU of P A P' (whose
// symmetric part is still positive definite, so no pivoting is needed).
// pivot[k] and diag[k] receive the k-th pivot and the diagonal entry it
// started from.
static void solve_ordered(Dag *d, const int *A, const int *r, int n, int *x, int *pivot, int *diag) {
  int *perm = arena_alloc((size_t)n * sizeof(int)), *PA = arena_alloc((size_t)n * n * sizeof(int));
  int *Pr = arena_alloc((size_t)n * sizeof(int)), *Px = arena_alloc((size_t)n * sizeof(int));
  min_degree_order(d, A, n, perm);
  for (int i = 0; i < n; i++) {
    Pr[i] = r[perm[i]];
    for (int j = 0; j < n; j++) PA[i * n + j] = A[perm[i] * n + perm[j]];
    if (diag) diag[i] = PA[i * n + i];
  }
  lu_solve(d, PA, Pr, n, Px, pivot);
  for (int i = 0; i < n; i++) x[perm[i]] = Px[i];
}

// Assemble A (nu x nu, dense node matrix) and r, then solve A lambda = r.
static void build_multipliers(Build *b) {
  Dag *d = b->d;
  int nu = b->nu, m = b->m, s = b->s;
  Step *st = b->st;
  dag_section(d, "multiplier system A lambda = r");
  int *A = nodes(nu * nu), *r = nodes(nu);
  int **y = arena_alloc((size_t)s * sizeof(int *));
  /* which constraints touch each coordinate through M^-1 rho */
  IntVec *touch = arena_alloc((size_t)m * sizeof(IntVec));
  for (int a = 0; a < nu; a++)
    for (int i = 0; i < m; i++) {
      int any = 0;
      for (int j = 0; j < s; j++) any |= !dag_is_zero(d, b->vrho[j][a][i]);
      if (any) intvec_push(&touch[i], a);
    }
  int *pair = nodes(nu);
  for (int a = 0; a < nu; a++) pair[a] = -1;
  int *minvp0 = nodes(m), *p0 = nodes(m);
  for (int i = 0; i < m; i++) p0[i] = dag_input(d, st->in_p0 + i);
  minv_apply(b->mod, d, p0, minvp0);
  for (int a = 0; a < nu; a++) {
    for (int c = 0; c < nu; c++) A[a * nu + c] = dag_const(d, 0);
    const SparseVec *col = &b->mod->jac[a];
    for (int e = 0; e < col->n; e++) {
      IntVec *t = &touch[col->e[e].coord];
      for (int q = 0; q < t->n; q++) {
        int c = t->v[q];
        if (pair[c] == a) continue;
        pair[c] = a;
        for (int j = 0; j < s; j++) y[j] = b->vrho[j][c];
        A[a * nu + c] = dag_mul(d, b->h, skew_form(b, a, y));
      }
    }
    for (int j = 0; j < s; j++) y[j] = b->vpsi[j];
    int rhs = dag_sub(d, dot_col(b, 0, a, minvp0), dag_mul(d, b->h, skew_form(b, a, y)));
    r[a] = dag_add(d, rhs, dag_input(d, st->in_g0 + a)); /* input: g_a(q0) / h, or 0 */
  }
  solve_ordered(d, A, r, nu, st->lambda, st->pivot, st->adiag);
}

// gamma_j = M^-1 [delta_j0 p0 - h sum_i X[j][i] Theta_i], Theta_i = psi_i + rho_i lambda;
// and p1 - p0 = -h Theta_0.
static void build_update(Build *b) {
  Dag *d = b->d;
  int m = b->m, s = b->s;
  const double *xi = b->me->xi;
  Step *st = b->st;
  dag_section(d, "new gamma_j = M^-1 [delta_j0 p0 - h sum_i X[j][i] (psi_i + rho_i lambda)]");
  int **theta = arena_alloc((size_t)s * sizeof(int *));
  for (int j = 0; j < s; j++) {
    theta[j] = nodes(m);
    memcpy(theta[j], b->psi[j], (size_t)m * sizeof(int));
    for (int a = 0; a < b->nu; a++) {
      const SparseVec *col = &b->mod->jac[a];
      for (int e = 0; e < col->n; e++) {
        int i = col->e[e].coord;
        theta[j][i] = dag_add(d, theta[j][i], dag_mul(d, b->rho[j][a][e], st->lambda[a]));
      }
    }
  }
  int *v = nodes(m);
  for (int j = 0; j < s; j++) {
    for (int i = 0; i < m; i++) {
      int x = j == 0 ? dag_mul(d, dag_const(d, xi[0]), theta[0][i])
                     : dag_mul(d, dag_const(d, xi[j]), theta[j - 1][i]);
      if (j + 1 < s) x = dag_sub(d, x, dag_mul(d, dag_const(d, xi[j + 1]), theta[j + 1][i]));
      x = dag_mul(d, b->h, x);
      v[i] = j == 0 ? dag_sub(d, dag_input(d, st->in_p0 + i), x) : dag_neg(d, x);
    }
    minv_apply(b->mod, d, v, st->gam_new + j * m);
  }
  for (int i = 0; i < m; i++) st->dp[i] = dag_neg(d, dag_mul(d, b->h, theta[0][i]));
}

// The multiplier consistent with (q0, p0): differentiating the hidden
// constraint G' M^-1 p = 0 along the flow gives
//   (G' M^-1 G) lambda = [v' Hess(g_a) v]_a - G' M^-1 grad U,  v = M^-1 p,
// where v' Hess(g_a) v is the derivative of w_a(q) = grad g_a(q)' v along v
// (one more reverse sweep, with v held constant). For NAME_init.
static void build_initial_multiplier(Build *b, const int *q) {
  Dag *d = b->d;
  Model *mod = b->mod;
  int m = b->m, nu = b->nu;
  Step *st = b->st;
  dag_section(d, "consistent initial multiplier");
  const int *v = st->predict0; /* M^-1 p0 */
  int *dw = nodes(m), *col = nodes(m), *mcol = nodes(m), *gu = nodes(m), *mgu = nodes(m);
  int *B = nodes(nu * nu), *r = nodes(nu), *piv = nodes(nu), z = dag_const(d, 0);
  int **G = arena_alloc((size_t)nu * sizeof(int *)); /* dense columns of grad g at q0 */
  for (int a = 0; a < nu; a++) {
    G[a] = zeros(d, m);
    for (int e = 0; e < mod->jac[a].n; e++)
      dag_subst(d, &mod->jac[a].e[e].node, 1, q, m, &G[a][mod->jac[a].e[e].coord]);
  }
  dag_subst(d, mod->gradU, m, q, m, gu);
  minv_apply(mod, d, gu, mgu);
  IntVec *touch = arena_alloc((size_t)m * sizeof(IntVec)); /* constraints on each coordinate */
  for (int a = 0; a < nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) intvec_push(&touch[mod->jac[a].e[e].coord], a);
  for (int i = 0; i < nu * nu; i++) B[i] = z;
  for (int c = 0; c < nu; c++) { /* B[:, c] = G' M^-1 G[:, c], over structural nonzeros only */
    minv_apply(mod, d, G[c], mcol);
    for (int i = 0; i < m; i++)
      for (int t = 0; !dag_is_zero(d, mcol[i]) && t < touch[i].n; t++) {
        int a = touch[i].v[t];
        B[a * nu + c] = dag_add(d, B[a * nu + c], dag_mul(d, G[a][i], mcol[i]));
      }
  }
  for (int a = 0; a < nu; a++) {
    int w = z, hvv = z, gmu = z;
    for (int e = 0; e < mod->jac[a].n; e++)
      w = dag_add(d, w, dag_mul(d, mod->jac[a].e[e].node, v[mod->jac[a].e[e].coord]));
    ad_gradient(d, w, m, dw);
    for (int i = 0; i < m; i++) col[i] = dw[i];
    dag_subst(d, col, m, q, m, dw);
    for (int i = 0; i < m; i++) {
      hvv = dag_add(d, hvv, dag_mul(d, dw[i], v[i]));
      gmu = dag_add(d, gmu, dag_mul(d, G[a][i], mgu[i]));
    }
    r[a] = dag_sub(d, hvv, gmu);
  }
  solve_ordered(d, B, r, nu, st->lambda0, piv, NULL);
}

// Functions of the state outside the step: g(q), H(q,p), grad g(q)' M^-1 p,
// and the first step's prediction gamma_0 = M^-1 p0.
static void build_diagnostics(Build *b) {
  Dag *d = b->d;
  Model *mod = b->mod;
  int m = b->m, nu = b->nu;
  Step *st = b->st;
  int *q = nodes(m), *p = nodes(m);
  for (int i = 0; i < m; i++) {
    q[i] = dag_input(d, st->in_q0 + i);
    p[i] = dag_input(d, st->in_p0 + i);
  }
  dag_section(d, "g(q0)");
  dag_subst(d, mod->g, nu, q, m, st->g_at_q0);
  minv_apply(mod, d, p, st->predict0);
  dag_section(d, "energy");
  int kin = dag_const(d, 0);
  for (int i = 0; i < m; i++) kin = dag_add(d, kin, dag_mul(d, p[i], st->predict0[i]));
  int U;
  dag_subst(d, &mod->U, 1, q, m, &U);
  st->energy[0] = dag_add(d, dag_mul(d, dag_const(d, 0.5), kin), U);
  dag_section(d, "hidden constraints");
  for (int a = 0; a < nu; a++) {
    const SparseVec *col = &mod->jac[a];
    int acc = dag_const(d, 0);
    for (int e = 0; e < col->n; e++) {
      int ga;
      dag_subst(d, &col->e[e].node, 1, q, m, &ga);
      acc = dag_add(d, acc, dag_mul(d, ga, st->predict0[col->e[e].coord]));
    }
    st->hidden[a] = acc;
  }
  if (nu) build_initial_multiplier(b, q);
}

Step *step_build(Model *mod, const Method *me) {
  Step *st = arena_alloc(sizeof *st);
  int m = mod->m, nu = mod->nu, s = me->s;
  if (nu > MAX_DENSE_NU) {
    error_at((Loc){0, 0}, "%d constraints: at most %d are supported", nu, MAX_DENSE_NU);
    return NULL;
  }
  st->m = m;
  st->nu = nu;
  st->s = s;
  st->in_q0 = m;
  st->in_p0 = 2 * m;
  st->in_gam = 3 * m;
  st->in_h = 3 * m + s * m;
  st->in_g0 = st->in_h + 1;
  st->ninputs = st->in_g0 + nu;
  st->gam_new = nodes(s * m);
  st->dp = nodes(m);
  st->lambda = nodes(nu);
  st->pivot = nodes(nu);
  st->adiag = nodes(nu);
  st->predict0 = nodes(m);
  st->g_at_q0 = nodes(nu);
  st->energy = nodes(1);
  st->hidden = nodes(nu);
  st->lambda0 = nodes(nu);
  Build b = {mod, me, mod->dag, st, m, nu, s, me->k, dag_input(mod->dag, st->in_h), NULL, NULL, NULL, NULL};
  build_stages(&b);
  if (nu) {
    build_minv_products(&b);
    build_multipliers(&b);
  }
  build_update(&b);
  build_diagnostics(&b);
  return st;
}
