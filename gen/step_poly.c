/* step_poly.c - the order-2s method family: a polynomial multiplier.
 *
 * The multiplier is a polynomial of degree s-1 on the step,
 *   lambda(t0 + c h) = sum_r P_r(c) lambda_r,
 * fixed by s Legendre conditions on d/dt g along the step:
 *   C_i = sum_l b_l P_i(c_l) G_l' V_l + delta_i0 g(q0)/h = 0,  i = 0..s-1,
 * with V_l = sum_j P_j(c_l) gamma_j the velocity at stage l. The force
 * coefficients become Theta_j = psi_j + sum_l b_l P_j(c_l) G_l Lambda_l,
 * Lambda_l = sum_r P_r(c_l) lambda_r. C is affine in the lambda_r, with the
 * (s nu) x (s nu) matrix
 *   A[(i,a),(r,c)] = h sum_{j,l} X[j][l] (R_ij' M^-1 R_lr)_ac,
 *   R_jr = sum_l b_l P_j(c_l) P_r(c_l) G_l,
 * which the kernel "factor" builds from the predicted stage data and
 * factors once per step (lu.c, minimum-degree order: a chain's blocks keep
 * their band); the moments of gradient entries affine in q come in closed
 * form from q0 and gamma where that is shorter. The sweep takes Theta_j and
 * C_i stage by stage or, where that is shorter by a tenth, from the moments
 * R at its own gamma (sweep_ops): Theta_j = psi_j + sum_r R_jr lambda_r and C_i = sum_j R_ij'
 * gamma_j (+ g(q0)/h), since b_l P_i(c_l) V_l sums to them. Each sweep then
 * updates lambda <- lambda + A^-1 C(lambda) with that frozen factor and
 * recomputes Theta and gamma (docs/method-poly.md section 5: as few
 * sweeps as re-solving A every sweep while h is small; where the iteration
 * slows down the step template calls "factor" again at the current gamma,
 * which keeps it converging to the h of the constant family).
 *
 * After the iteration the step projects p1 onto the hidden constraint at
 * q1 and rescales it so that H keeps its value; the kernel "project_p1" gives
 * the correction -G1 mu (mu = (G1' M^-1 G1)^-1 G1' M^-1 p1), the kinetic
 * energy after it and U(q1), and the step template applies them. With the
 * projection the step has order 2s (section 8: without it, s or s+1). */
#include <string.h>

#include "step.h"

// grad g at every stage point, over the structural nonzeros:
// G[l][a][e] is entry e of column a at Q_l.
int ***poly_stage_jacobians(Build *b) {
  Dag *d = b->d;
  const Model *mod = b->mod;
  int m = b->m, nu = b->nu, nroots = 0;
  for (int a = 0; a < nu; a++) nroots += mod->jac[a].n;
  int *roots = step_nodes(nroots), *img = step_nodes(nroots), *Q = step_nodes(m);
  for (int a = 0, r = 0; a < nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) roots[r++] = mod->jac[a].e[e].node;
  int ***G = arena_alloc((size_t)b->k * sizeof(int **));
  for (int l = 0; l < b->k; l++) {
    step_stage_point(b, l, Q);
    dag_subst(d, roots, nroots, Q, m, img);
    G[l] = arena_alloc((size_t)nu * sizeof(int *));
    for (int a = 0, r = 0; a < nu; a++) {
      G[l][a] = step_nodes(mod->jac[a].n);
      for (int e = 0; e < mod->jac[a].n; e++) G[l][a][e] = img[r++];
    }
  }
  return G;
}

// sum_e col[e] v[coord of entry e of column a]: a sparse column dotted with v.
static int dot_sparse(Build *b, int a, const int *col, const int *v) {
  Dag *d = b->d;
  const SparseVec *jc = &b->mod->jac[a];
  int acc = dag_const(d, 0);
  for (int e = 0; e < jc->n; e++) acc = dag_add(d, acc, dag_mul(d, col[e], v[jc->e[e].coord]));
  return acc;
}

// h sum_t Y_t gamma_t,i with Y_t = sum_l b_l P_j(c_l) P_r(c_l) Ihat[l][t]:
// the moment (j, r) of the stage points' excursion Q_l - q0 in coordinate i,
// built once per (j, r, i) into the cache yg (-1: not yet).
static int excursion_moment(Build *b, int j, int r, int i, int *yg) {
  Dag *d = b->d;
  const Method *me = b->me;
  int s = b->s, *slot = yg + (j * s + r) * b->m + i;
  if (*slot >= 0) return *slot;
  int acc = dag_const(d, 0);
  for (int t = 0; t < s; t++) {
    long double y = 0;
    for (int l = 0; l < b->k; l++) y += (long double)me->W[l * s + j] * me->Phat[l * s + r] * me->Ihat[l * s + t];
    acc = dag_add(d, acc, dag_mul(d, dag_const(d, (double)y), step_in(b, IN_GAM, t * b->m + i)));
  }
  return *slot = dag_mul(d, b->h, acc);
}

// The moments R_jr = sum_l b_l P_j(c_l) P_r(c_l) G_l of the stage Jacobians
// over the structural nonzeros: R[j][r][a][e], symmetric in (j, r), so the
// pairs r < j share the nodes of (r, j). They build the matrix A, and in
// the moment form the multiplier's force sum_l b_l P_j(c_l) G_l Lambda_l =
// sum_r R_jr lambda_r and the conditions, so that the sweep keeps the
// s(s+1)/2 moments rather than the k stage Jacobians. With closed, an entry
// affine in q (every entry of a quadratic constraint's gradient) has them
// in closed form, g(q0) [j == r] + grad g . (the excursion's moment),
// without the stages.
int ****poly_jacobian_moments(Build *b, int ***G, int closed) {
  Dag *d = b->d;
  const Method *me = b->me;
  const Model *mod = b->mod;
  int m = b->m, nu = b->nu, s = b->s, *yg = step_nodes(s * s * m), *q0 = step_nodes(m), nnz = 0;
  for (int t = 0; t < s * s * m; t++) yg[t] = -1;
  for (int i = 0; i < m; i++) q0[i] = step_in(b, IN_Q0, i);
  for (int a = 0; a < nu; a++) nnz += mod->jac[a].n;
  /* per affine entry, on first use: its gradient and its value at q0 */
  SparseVec *grad = arena_alloc((size_t)(nnz + 1) * sizeof *grad);
  int *at_q0 = step_nodes(nnz + 1);
  for (int t = 0; t < nnz; t++) grad[t].n = at_q0[t] = -1;
  int ****R = arena_alloc((size_t)s * sizeof(int ***));
  for (int j = 0; j < s; j++) {
    R[j] = arena_alloc((size_t)s * sizeof(int **));
    for (int r = 0; r < s; r++) {
      if (r < j) {
        R[j][r] = R[r][j];
        continue;
      }
      R[j][r] = arena_alloc((size_t)nu * sizeof(int *));
      for (int a = 0, at = 0; a < nu; a++) {
        R[j][r][a] = step_nodes(mod->jac[a].n);
        for (int e = 0; e < mod->jac[a].n; e++, at++) {
          int node = mod->jac[a].e[e].node, acc = dag_const(d, 0);
          if (closed && (d->nodes[node].deg == 0 || d->nodes[node].deg == 1)) { /* affine: in closed form */
            SparseVec *gr = &grad[at];
            if (gr->n < 0) ad_gradient_sparse(d, node, m, gr);
            if (j == r && at_q0[at] < 0) dag_subst(d, &node, 1, q0, m, &at_q0[at]);
            if (j == r) acc = at_q0[at];
            for (int t = 0; t < gr->n; t++)
              acc = dag_add(d, acc, dag_mul(d, gr->e[t].node, excursion_moment(b, j, r, gr->e[t].coord, yg)));
          } else
            for (int l = 0; l < b->k; l++) {
              double w = me->W[l * s + j] * me->Phat[l * s + r];
              acc = dag_add(d, acc, dag_mul(d, dag_const(d, w), G[l][a][e]));
            }
          R[j][r][a][e] = acc;
        }
      }
    }
  }
  return R;
}

// The multiplier matrix A of the header, assembled from the moments R:
// (s nu) x (s nu) nodes, row (i,a) = i*nu + a.
static int *multiplier_matrix(Build *b, int ****R) {
  Dag *d = b->d;
  int m = b->m, nu = b->nu, s = b->s, n = s * nu, z = dag_const(d, 0);
  /* vR[r][c][l] = M^-1 R_lr[:, c], dense */
  int *dense = step_nodes(m);
  int ****vR = arena_alloc((size_t)s * sizeof(int ***));
  for (int r = 0; r < s; r++) {
    vR[r] = arena_alloc((size_t)nu * sizeof(int **));
    for (int c = 0; c < nu; c++) {
      vR[r][c] = arena_alloc((size_t)s * sizeof(int *));
      for (int l = 0; l < s; l++) {
        for (int i = 0; i < m; i++) dense[i] = z;
        for (int e = 0; e < b->mod->jac[c].n; e++) dense[b->mod->jac[c].e[e].coord] = R[l][r][c][e];
        vR[r][c][l] = step_nodes(m);
        minv_apply(b->mod, d, dense, vR[r][c][l]);
      }
    }
  }
  /* which constraints c reach each coordinate through M^-1: only those
   * pairs (a, c) sharing a coordinate give a nonzero block */
  IntVec *touch = arena_alloc((size_t)m * sizeof(IntVec));
  for (int c = 0; c < nu; c++)
    for (int i = 0; i < m; i++) {
      int any = 0;
      for (int r = 0; r < s; r++)
        for (int l = 0; l < s; l++) any |= !dag_is_zero(d, vR[r][c][l][i]);
      if (any) intvec_push(&touch[i], c);
    }
  int *A = step_nodes(n * n), *pair = step_nodes(nu), *coupled = step_nodes(nu), *xv = step_nodes(m);
  for (int t = 0; t < n * n; t++) A[t] = z;
  for (int a = 0; a < nu; a++) pair[a] = -1;
  for (int a = 0; a < nu; a++) {
    const SparseVec *col = &b->mod->jac[a];
    for (int q = 0, nc = step_coupled(b, touch, pair, a, coupled); q < nc; q++) {
      int c = coupled[q];
      for (int i = 0; i < s; i++)
        for (int r = 0; r < s; r++) {
          int acc = z;
          for (int j = 0; j < s; j++) {
            for (int f = 0; f < col->n; f++) xv[col->e[f].coord] = step_apply_x(b, j, col->e[f].coord, vR[r][c]);
            acc = dag_add(d, acc, dot_sparse(b, a, R[i][j][a], xv));
          }
          A[(i * nu + a) * n + r * nu + c] = dag_mul(d, b->h, acc);
        }
    }
  }
  return A;
}

// Theta_j = psi_j + sum_l b_l P_j(c_l) G_l Lambda_l for the coefficients
// lam[r*nu + a] of the multiplier, Lambda_l = sum_r P_r(c_l) lambda_r: from
// the stage Jacobians G (R NULL), or from their moments R as
// psi_j + sum_r R_jr lambda_r.
int **force_coefficients(Build *b, int ***G, int ****R, const int *lam) {
  Dag *d = b->d;
  const Method *me = b->me;
  int m = b->m, nu = b->nu, s = b->s, z = dag_const(d, 0);
  int **theta = arena_alloc((size_t)s * sizeof(int *)), *f = step_nodes(m);
  for (int j = 0; j < s; j++) {
    theta[j] = step_nodes(m);
    for (int i = 0; i < m; i++) theta[j][i] = b->psi[j][i];
  }
  if (R) {
    for (int j = 0; j < s; j++)
      for (int a = 0; a < nu; a++) {
        const SparseVec *col = &b->mod->jac[a];
        for (int e = 0; e < col->n; e++) {
          int acc = z, i = col->e[e].coord;
          for (int r = 0; r < s; r++) acc = dag_add(d, acc, dag_mul(d, R[j][r][a][e], lam[r * nu + a]));
          theta[j][i] = dag_add(d, theta[j][i], acc);
        }
      }
    return theta;
  }
  for (int l = 0; l < b->k; l++) {
    for (int i = 0; i < m; i++) f[i] = z;
    for (int a = 0; a < nu; a++) {
      int Lam = z; /* the multiplier at stage l */
      for (int r = 0; r < s; r++) Lam = dag_add(d, Lam, dag_mul(d, dag_const(d, me->Phat[l * s + r]), lam[r * nu + a]));
      const SparseVec *col = &b->mod->jac[a];
      for (int e = 0; e < col->n; e++)
        f[col->e[e].coord] = dag_add(d, f[col->e[e].coord], dag_mul(d, G[l][a][e], Lam));
    }
    for (int j = 0; j < s; j++) {
      int w = dag_const(d, me->W[l * s + j]);
      for (int i = 0; i < m; i++) theta[j][i] = dag_add(d, theta[j][i], dag_mul(d, w, f[i]));
    }
  }
  return theta;
}

// The conditions C[i*nu + a] = sum_l b_l P_i(c_l) G_l[:, a]' V_l (+ g_a(q0)/h
// for i = 0) for the velocity coefficients gam (s*m nodes), V_l = sum_j
// P_j(c_l) gamma_j: from the stage Jacobians G (R NULL), or from their
// moments as sum_j R_ij[:, a]' gamma_j, which leaves the G_l dead once the
// moments hold them.
int *conditions(Build *b, int ***G, int ****R, const int *gam) {
  Dag *d = b->d;
  const Method *me = b->me;
  int m = b->m, nu = b->nu, s = b->s, z = dag_const(d, 0);
  int *C = step_nodes(s * nu), *V = step_nodes(m);
  for (int t = 0; t < s * nu; t++) C[t] = z;
  if (R)
    for (int i = 0; i < s; i++)
      for (int a = 0; a < nu; a++)
        for (int j = 0; j < s; j++) C[i * nu + a] = dag_add(d, C[i * nu + a], dot_sparse(b, a, R[i][j][a], gam + j * m));
  for (int l = 0; l < b->k && !R; l++) {
    for (int i = 0; i < m; i++) {
      V[i] = z;
      for (int j = 0; j < s; j++) V[i] = dag_add(d, V[i], dag_mul(d, dag_const(d, me->Phat[l * s + j]), gam[j * m + i]));
    }
    for (int a = 0; a < nu; a++) {
      int gv = dot_sparse(b, a, G[l][a], V);
      for (int i = 0; i < s; i++) C[i * nu + a] = dag_add(d, C[i * nu + a], dag_mul(d, dag_const(d, me->W[l * s + i]), gv));
    }
  }
  for (int a = 0; a < nu; a++) C[a] = dag_add(d, C[a], step_in(b, IN_G0, a)); /* input: g_a(q0) / h, or 0 */
  return C;
}

// One sweep's force coefficients Theta_j(lambda + A^-1 C(lambda)) with the
// frozen factor in: gamma from Theta(lambda), the conditions C at it, the
// update of lambda into lam1, and Theta at lam1 (force_coefficients: from
// the stage Jacobians G, or from their moments R).
static int **sweep_force(Build *b, int ***G, int ****R, const LuFactor *in, const int *lam, int *lam1) {
  Dag *d = b->d;
  int n = b->s * b->nu, *gam = step_nodes(b->s * b->m), *dp = step_nodes(b->m), *delta = step_nodes(n);
  step_section(b, "the multiplier coefficients: lambda += A^-1 C(lambda)");
  step_gamma(b, force_coefficients(b, G, R, lam), gam, dp);
  lu_apply(d, in, conditions(b, G, R, gam), delta);
  for (int t = 0; t < n; t++) lam1[t] = dag_add(d, lam[t], delta[t]);
  step_section(b, "new gamma_j = M^-1 [delta_j0 p0 - h sum_i X[j][i] Theta_i(lambda)]");
  return force_coefficients(b, G, R, lam1);
}

// The operations sweep_force's result takes, its inputs and constants not
// counted.
static long sweep_ops(Build *b, int **theta, const int *lam1) {
  int m = b->m, s = b->s, n = s * b->nu, *roots = step_nodes(s * m + n);
  for (int j = 0; j < s; j++) memcpy(roots + j * m, theta[j], (size_t)m * sizeof(int));
  memcpy(roots + s * m, lam1, (size_t)n * sizeof(int));
  return dag_count_ops(b->d, roots, s * m + n);
}

static const char project_what[] =
    "The end of the step at (q0, p0) = (q1, p1): out = the correction -G1 mu onto the\n"
    " * hidden constraint (M), the kinetic energy after it (1), U(q1) (1), pivots (NU)\n"
    " * and diagonal (NU) of G1' M^-1 G1, the multiplier at the rescaled end,\n"
    " * beta^2 lamv - lamu, as lamv (NU) and lamu (NU), and g(q1) (NU) with its\n"
    " * round-off scale sum_i |dg/dq_i q_i| (NU).";
static const char sweep_what[] =
    "One fixed-point sweep with the frozen factor lu of A: out = new gamma (S*M),\n"
    " * p1 - p0 (M), the multiplier's Legendre coefficients (S*NU), Theta_1.. (M*(S-1)).";

// The kernel "project_p1": at (q, p) = inputs (q0, p0), which the step sets to
// (q1, p1), the correction dp = -G1 mu onto grad g(q1)' M^-1 p = 0, the
// kinetic energy after it, U(q1), and the pivots of G1' M^-1 G1.
void build_projection(Build *b) {
  Dag *d = b->d;
  Model *mod = b->mod;
  int m = b->m, nu = b->nu, z = dag_const(d, 0);
  b->owners = 1u << K_PROJECT;
  step_section(b, "projection onto the hidden constraint at q1, kinetic energy after it, U(q1)");
  int *q = step_nodes(m), *p = step_nodes(m), *v = step_nodes(m), *B = step_nodes(nu * nu);
  int *pivot = step_nodes(nu), *adiag = step_nodes(nu), *dp = step_nodes(m), *pt = step_nodes(m);
  for (int i = 0; i < m; i++) {
    q[i] = step_in(b, IN_Q0, i);
    p[i] = step_in(b, IN_P0, i);
  }
  int **G = step_jacobian_at(b, q);
  step_gram(b, G, B);
  step_project_momenta(b, G, B, p, dp, pivot, adiag);
  for (int i = 0; i < m; i++) pt[i] = dag_add(d, p[i], dp[i]);
  minv_apply(mod, d, pt, v);
  int kin = z, U;
  for (int i = 0; i < m; i++) kin = dag_add(d, kin, dag_mul(d, pt[i], v[i]));
  kin = dag_mul(d, dag_const(d, 0.5), kin);
  dag_subst(d, &mod->U, 1, q, m, &U);
  /* the multiplier consistent with (q1, beta (p1 + dp)), as the two
   * solutions (G1' M^-1 G1) lamv = [v' Hess(g_a) v]_a and
   * (G1' M^-1 G1) lamu = G1' M^-1 grad U, v = M^-1 (p1 + dp), by the
   * projection's factors: lambda = beta^2 lamv - lamu */
  int *hvv = step_nodes(nu), *gmu = step_nodes(nu), *lamv = step_nodes(nu), *lamu = step_nodes(nu), *unused = step_nodes(nu);
  step_curvature(b, q, v, hvv);
  step_force_along(b, q, G, gmu);
  lu_solve_ordered(d, B, hvv, nu, lamv, unused, NULL);
  lu_solve_ordered(d, B, gmu, nu, lamu, unused, NULL);
  Step *st = b->st;
  step_result(st, K_PROJECT, "dp", SZ_M, 1, m, dp);
  step_result(st, K_PROJECT, "kin", SZ_ONE, 1, 1, &kin);
  step_result(st, K_PROJECT, "U", SZ_ONE, 1, 1, &U);
  step_result(st, K_PROJECT, "pivot", SZ_NU, 1, nu, pivot);
  step_result(st, K_PROJECT, "adiag", SZ_NU, 1, nu, adiag);
  step_result(st, K_PROJECT, "lamv", SZ_NU, 1, nu, lamv);
  step_result(st, K_PROJECT, "lamu", SZ_NU, 1, nu, lamu);
  /* g(q1) and its round-off scale sum_i |dg_a/dq_i q_i|: the step fails where its
   * iteration left g above round-off (emit_end_poly) */
  int *g1 = step_nodes(nu), *gscale = step_nodes(nu);
  dag_subst(d, mod->g, nu, q, m, g1);
  for (int a = 0; a < nu; a++) {
    gscale[a] = z;
    for (int i = 0; i < m; i++)
      gscale[a] = dag_add(d, gscale[a], dag_op(d, OP_ABS, dag_mul(d, G[a][i], q[i]), -1));
  }
  step_result(st, K_PROJECT, "g", SZ_NU, 1, nu, g1);
  step_result(st, K_PROJECT, "gscale", SZ_NU, 1, nu, gscale);
  st->kern[K_PROJECT].what = project_what;
}

// The kernel "factor": the multiplier matrix A from grad g at the stages
// (returned, G[l][a][e]) and their moments (*Rout), factored; its
// structural nonzeros are the factor's results and the sweep's input lu,
// in the factor *in. Also for M(q) (step_mq.c), there with M(q0).
int ***build_poly_factor(Build *b, LuFactor *in, int *****Rout) {
  Dag *d = b->d;
  Step *st = b->st;
  int nu = b->nu, s = b->s, n = s * nu;
  step_section(b, "grad g at the stages");
  int ***G = poly_stage_jacobians(b);
  b->owners = 1u << K_FACTOR;
  step_section(b, "the multiplier matrix A, factored once per step");
  /* the moments of affine entries in closed form where that makes A shorter:
   * with more stages than s (whole runs: the satellites (6,2) and (6,3) -13%
   * and -11% instructions), not at k = s (chain8 (4,4) would be +2.5%) */
  int ****R = poly_jacobian_moments(b, G, 0), ****Rc = poly_jacobian_moments(b, G, 1);
  int *A = multiplier_matrix(b, R), *Ac = multiplier_matrix(b, Rc), *pivot = step_nodes(n), *adiag = step_nodes(n);
  if (dag_count_ops(d, Ac, n * n) < dag_count_ops(d, A, n * n)) {
    R = Rc;
    A = Ac;
  }
  LuFactor f;
  lu_factor(d, A, n, &f, pivot, adiag);
  /* the factor's structural nonzeros are its results, and the sweep's input lu */
  int nlu = 0, *lu = step_nodes(n * n);
  *in = (LuFactor){n, f.perm, step_nodes(n * n)};
  for (int t = 0; t < n * n; t++) {
    in->F[t] = f.F[t];
    if (dag_is_zero(d, f.F[t])) continue;
    lu[nlu] = f.F[t];
    in->F[t] = dag_input(d, st->in[IN_LU].first + nlu);
    nlu++;
  }
  st->in[IN_LU].len = st->in[IN_LU].coef = nlu;
  step_result(st, K_FACTOR, "lu", SZ_ONE, nlu, nlu, lu);
  step_result(st, K_FACTOR, "pivot", SZ_SNU, 1, n, pivot);
  step_result(st, K_FACTOR, "adiag", SZ_SNU, 1, n, adiag);
  st->kern[K_FACTOR].what = "The multiplier matrix A at the predicted stages, factored once per step: out = its\n"
                            " * LU factors (L, U, 1 / pivots), pivots (S*NU), diagonal (S*NU).";
  *Rout = R;
  return G;
}

// The kernels of the polynomial family: "factor" (the frozen multiplier
// matrix, once per step), "sweep" (with the factor's entries as the input
// lu) and "project_p1".
void build_poly_multiplier(Build *b) {
  Step *st = b->st;
  int n = b->s * b->nu;
  LuFactor in;
  int ****R, ***G = build_poly_factor(b, &in, &R);
  b->owners = 1u << K_SWEEP;
  int *lam = step_nodes(n), *lam1 = step_nodes(n);
  for (int t = 0; t < n; t++) lam[t] = step_in(b, IN_LAM, t);
  /* the force and the conditions from the moments where that saves a tenth
   * of the sweep's operations: with fewer stages per moment (k small against
   * s) the stage form is shorter, and a smaller saving did not show in the
   * instructions (callgrind, whole runs against the stage form, the moments
   * summed over the stages: the satellites (6,3), 7% fewer operations, +3%
   * instructions; (6,2), 25% fewer, -11%; the modified pendulum (9,3) and
   * (12,4), 20% and 11% fewer, -9% and -7%; with the closed form for the
   * satellites' affine entries their (6,3) saves 14% and takes this form) */
  int **theta = sweep_force(b, G, NULL, &in, lam, lam1);
  long ops = sweep_ops(b, theta, lam1);
  int *lam1r = step_nodes(n), **theta_r = sweep_force(b, G, R, &in, lam, lam1r);
  if (10 * sweep_ops(b, theta_r, lam1r) < 9 * ops) {
    theta = theta_r;
    memcpy(lam1, lam1r, (size_t)n * sizeof(int));
  }
  step_gamma_update(b, theta);
  step_result(st, K_SWEEP, "lam", SZ_SNU, 1, n, lam1);
  step_theta_result(b);
  st->kern[K_SWEEP].what = sweep_what;
  build_projection(b);
}

// The half band of the rolled form's multiplier matrix (emit_rolled_poly.c):
// its unknowns in the order (a, r) -> a s + r, two constraints a, c that
// share a coordinate couple all their s coefficients, so the band is
// s (bw + 1) - 1 with bw the largest c - a of such a pair.
int poly_band(const Model *mod, int s) {
  int bw = 0, *lo = step_nodes(mod->m), *hi = step_nodes(mod->m);
  for (int i = 0; i < mod->m; i++) lo[i] = hi[i] = -1;
  for (int a = 0; a < mod->nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) {
      int i = mod->jac[a].e[e].coord;
      if (lo[i] < 0) lo[i] = a;
      hi[i] = a; /* (the columns in increasing a) */
      if (hi[i] - lo[i] > bw) bw = hi[i] - lo[i];
    }
  return s * (bw + 1) - 1;
}

// The results of the polynomial family's kernels as build_poly_multiplier
// lays them out, zeros, with the factor's lu as the rolled form stores it:
// the band of the (s nu) x (s nu) matrix, 2 poly_band + 1 entries a row.
void layout_poly_multiplier(Build *b) {
  Step *st = b->st;
  int m = b->m, nu = b->nu, s = b->s, n = s * nu, nlu = n * (2 * poly_band(b->mod, s) + 1);
  st->in[IN_LU].len = st->in[IN_LU].coef = nlu;
  step_placeholder(b, K_FACTOR, "lu", SZ_ONE, nlu, nlu);
  step_placeholder(b, K_FACTOR, "pivot", SZ_SNU, 1, n);
  step_placeholder(b, K_FACTOR, "adiag", SZ_SNU, 1, n);
  st->kern[K_FACTOR].what = "The multiplier matrix A at the predicted stages, factored once per step: out = its\n"
                            " * band LU (rows and columns a S + r, A[u][w] at u W + w - u + BW), pivots (S*NU),\n"
                            " * diagonal (S*NU).";
  step_placeholder(b, K_SWEEP, "gam", SZ_SM, 1, s * m);
  step_placeholder(b, K_SWEEP, "dp", SZ_M, 1, m);
  step_placeholder(b, K_SWEEP, "lam", SZ_SNU, 1, n);
  step_placeholder(b, K_SWEEP, "theta", SZ_M, s - 1, (s - 1) * m);
  st->kern[K_SWEEP].what = sweep_what;
  static const char *const name[] = {"dp", "kin", "U", "pivot", "adiag", "lamv", "lamu", "g", "gscale"};
  for (int i = 0; i < 9; i++) step_placeholder(b, K_PROJECT, name[i], i == 0 ? SZ_M : i < 3 ? SZ_ONE : SZ_NU, 1, i == 0 ? m : i < 3 ? 1 : nu);
  st->kern[K_PROJECT].what = project_what;
}
