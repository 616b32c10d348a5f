/* step_const.c - the paper's method family: a multiplier constant over the step.
 *
 * In each sweep the nu x nu system of METHOD.md (eq. sisld),
 *   A = h [xi_0 rho_0' M^-1 rho_0 + sum_j xi_j (rho_j' M^-1 rho_{j-1} - rho_{j-1}' M^-1 rho_j)]
 *   r = rho_0' M^-1 (p0 - h xi_0 psi_0) - h sum_j xi_j (rho_j' M^-1 psi_{j-1} - rho_{j-1}' M^-1 psi_j)
 * is assembled from the sweep's stage data and solved for lambda, and
 * Theta_j = psi_j + rho_j lambda. With g(q0)/h added to r the step makes
 * g(q1) = 0 rather than g(q1) = g(q0), so g cannot drift. A is factored
 * without pivoting (lu.c): its symmetric part h xi_0 rho_0' M^-1 rho_0 is
 * positive definite when the constraints are independent, so no pivot
 * vanishes, and a banded A (a chain) keeps its band. Order 2 in general,
 * 2s when the true multiplier is constant. */
#include <string.h>

#include "step.h"

// The combination xi_0 <x_0, y_0> + sum_j xi_j (<x_j, y_{j-1}> - <x_{j-1}, y_j>)
// with x = rho[:, a]: the form in which the paper writes A and r.
static int skew_form(Build *b, int a, int **y) {
  Dag *d = b->d;
  const double *xi = b->me->xi;
  int acc = dag_mul(d, dag_const(d, xi[0]), step_dot_col(b, 0, a, y[0]));
  for (int j = 1; j < b->s; j++) {
    int t = dag_sub(d, step_dot_col(b, j, a, y[j - 1]), step_dot_col(b, j - 1, a, y[j]));
    acc = dag_add(d, acc, dag_mul(d, dag_const(d, xi[j]), t));
  }
  return acc;
}

// Assemble A (nu x nu, dense node matrix) and r, then solve A lambda = r.
static void build_system(Build *b, int *lambda, int *pivot, int *adiag) {
  Dag *d = b->d;
  int nu = b->nu, m = b->m, s = b->s;
  b->owners = 1u << K_SWEEP;
  step_section(b, "multiplier system A lambda = r");
  int *A = step_nodes(nu * nu), *r = step_nodes(nu);
  int **y = arena_alloc((size_t)s * sizeof(int *));
  /* which constraints touch each coordinate through M^-1 rho */
  IntVec *touch = arena_alloc((size_t)m * sizeof(IntVec));
  for (int a = 0; a < nu; a++)
    for (int i = 0; i < m; i++) {
      int any = 0;
      for (int j = 0; j < s; j++) any |= !dag_is_zero(d, b->vrho[j][a][i]);
      if (any) intvec_push(&touch[i], a);
    }
  int *pair = step_nodes(nu), *coupled = step_nodes(nu);
  for (int a = 0; a < nu; a++) pair[a] = -1;
  int *minvp0 = step_nodes(m), *p0 = step_nodes(m);
  for (int i = 0; i < m; i++) p0[i] = step_in(b, IN_P0, i);
  minv_apply(b->mod, d, p0, minvp0);
  for (int a = 0; a < nu; a++) {
    for (int c = 0; c < nu; c++) A[a * nu + c] = dag_const(d, 0);
    for (int q = 0, n = step_coupled(b, touch, pair, a, coupled); q < n; q++) {
      int c = coupled[q];
      for (int j = 0; j < s; j++) y[j] = b->vrho[j][c];
      A[a * nu + c] = dag_mul(d, b->h, skew_form(b, a, y));
    }
    for (int j = 0; j < s; j++) y[j] = b->vpsi[j];
    int rhs = dag_sub(d, step_dot_col(b, 0, a, minvp0), dag_mul(d, b->h, skew_form(b, a, y)));
    r[a] = dag_add(d, rhs, step_in(b, IN_G0, a)); /* input: g_a(q0) / h, or 0 */
  }
  lu_solve_ordered(d, A, r, nu, lambda, pivot, adiag);
}

static const char sweep_what[] = "One fixed-point sweep: out = new gamma (S*M), p1 - p0 (M), lambda (NU),\n"
                                 " * pivots of the LU of A (NU), diagonal of A (NU), Theta_1.. (M*(S-1)).";

// The sweep of the constant-multiplier family: results gam, dp, and with
// constraints lambda, the pivots of A and the diagonal entries they started
// from (the step tests them for a singular A).
void build_const_multiplier(Build *b) {
  Dag *d = b->d;
  int m = b->m, s = b->s, nu = b->nu;
  int *lambda = step_nodes(nu), *pivot = step_nodes(nu), *adiag = step_nodes(nu);
  if (nu) build_system(b, lambda, pivot, adiag);
  step_section(b, "new gamma_j = M^-1 [delta_j0 p0 - h sum_i X[j][i] (psi_i + rho_i lambda)]");
  int **theta = arena_alloc((size_t)s * sizeof(int *));
  for (int j = 0; j < s; j++) {
    theta[j] = step_nodes(m);
    memcpy(theta[j], b->psi[j], (size_t)m * sizeof(int));
    for (int a = 0; a < nu; a++) {
      const SparseVec *col = &b->mod->jac[a];
      for (int e = 0; e < col->n; e++) {
        int i = col->e[e].coord;
        theta[j][i] = dag_add(d, theta[j][i], dag_mul(d, b->rho[j][a][e], lambda[a]));
      }
    }
  }
  step_gamma_update(b, theta);
  step_result(b->st, K_SWEEP, "lambda", SZ_NU, 1, nu, lambda);
  step_result(b->st, K_SWEEP, "pivot", SZ_NU, 1, nu, pivot);
  step_result(b->st, K_SWEEP, "adiag", SZ_NU, 1, nu, adiag);
  step_theta_result(b);
  b->st->kern[K_SWEEP].what = sweep_what;
}

// The sweep's result blocks as build_const_multiplier lays them out, zeros:
// for the rolled form, which prints the sweep as loops (emit_rolled.c).
void layout_const_multiplier(Build *b) {
  int m = b->m, s = b->s, nu = b->nu;
  step_placeholder(b, K_SWEEP, "gam", SZ_SM, 1, s * m);
  step_placeholder(b, K_SWEEP, "dp", SZ_M, 1, m);
  step_placeholder(b, K_SWEEP, "lambda", SZ_NU, 1, nu);
  step_placeholder(b, K_SWEEP, "pivot", SZ_NU, 1, nu);
  step_placeholder(b, K_SWEEP, "adiag", SZ_NU, 1, nu);
  step_placeholder(b, K_SWEEP, "theta", SZ_M, s - 1, (s - 1) * m);
  b->st->kern[K_SWEEP].what = sweep_what;
}
