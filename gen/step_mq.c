/* step_mq.c - the sweep of HBVM(k,s) for H(q, p) = p' M(q)^-1 p / 2 + U(q).
 *
 * With M depending on q the Hamiltonian is not separable, and the method is
 * the line-integral method for a general H on y = (q, p), y' = J grad H(y)
 * (docs/method-mq.md): the polynomial u of degree s has the Legendre
 * coefficients gamma_j (of q') and -Theta_j (of p'),
 *   gamma_j = sum_l b_l P_j(c_l) M(Q_l)^-1 P_l,
 *   Theta_j = sum_l b_l P_j(c_l) [grad_q T(Q_l, P_l) + grad U(Q_l)],
 *   Q_l = q0 + h sum_j Ihat[l][j] gamma_j,  P_l = p0 - h sum_j Ihat[l][j] Theta_j,
 * and q1 = q0 + h gamma_0, p1 = p0 - h Theta_0. The sweep is one
 * Gauss-Seidel step of this fixed point: from gamma (input gam) and Theta
 * (input pth, the last sweep's Theta carried by the iteration) the new
 * Theta, then from gamma and the new Theta the new gamma. Its
 * results are those of the constant family without constraints (gam, dp,
 * theta: the dense output and the estimate read them as they are) and
 * th0, Theta_0, which with theta after it is the whole new Theta.
 *
 * With constraints (build_mq_constrained) the multiplier is the poly
 * family's, a polynomial of degree s-1 in the force, with its frozen matrix
 * (the kernel "factor", with M(q0)) and its end of step, in the M(q1) norm
 * (the kernel "project_p1"); the sweep adds lam to the results. */
#include <string.h>

#include "step.h"

// Stage l's momentum P = p0 - h sum_j Ihat[l][j] Theta_j, for Theta the
// input pth (th NULL) or the nodes th[j].
static void stage_momentum(Build *b, int l, int **th, int *P) {
  Dag *d = b->d;
  int m = b->m, s = b->s;
  for (int i = 0; i < m; i++) {
    int acc = dag_const(d, 0);
    for (int j = 0; j < s; j++) {
      int t = th ? th[j][i] : step_in(b, IN_PTH, j * m + i);
      acc = dag_add(d, acc, dag_mul(d, dag_const(d, b->me->Ihat[l * s + j]), t));
    }
    P[i] = dag_sub(d, step_in(b, IN_P0, i), dag_mul(d, b->h, acc));
  }
}

// The first pass of a sweep: at each stage (Q_l, P_l) of the input gamma
// and Theta (pth) the force grad_q T + grad U (mod->mq_force substituted
// there), summed with the weights b_l P_j(c_l) into the returned Theta_j;
// the stage points Q_l into qp + 2 l m.
static int **stage_forces(Build *b, int *qp) {
  Dag *d = b->d;
  int m = b->m, s = b->s, k = b->k, *img = step_nodes(m);
  int **theta = arena_alloc((size_t)s * sizeof(int *));
  for (int j = 0; j < s; j++) {
    theta[j] = step_nodes(m);
    for (int i = 0; i < m; i++) theta[j][i] = dag_const(d, 0);
  }
  for (int l = 0; l < k; l++) {
    char *label = arena_alloc(160);
    snprintf(label, 160, "stage %d of %d: Q, P = (q0, p0) + h sum_j Ihat[%d][j] (gamma_j, -Theta_j), "
             "grad_q T + grad U", l + 1, k, l + 1);
    step_section(b, label);
    step_stage_point(b, l, qp + 2 * l * m);
    stage_momentum(b, l, NULL, qp + 2 * l * m + m);
    dag_subst(d, b->mod->mq_force, m, qp + 2 * l * m, 2 * m, img);
    for (int j = 0; j < s; j++) {
      int w = dag_const(d, b->me->W[l * s + j]);
      for (int i = 0; i < m; i++) theta[j][i] = dag_add(d, theta[j][i], dag_mul(d, w, img[i]));
    }
  }
  return theta;
}

// The second pass: gamma_j = sum_l b_l P_j(c_l) M(Q_l)^-1 P_l with the stage
// momenta of theta (mod->mq_v, whose factors of M(Q_l) the first pass has
// built already: one triangular solve a stage), into gam (s*m nodes).
static void stage_velocities(Build *b, int *qp, int **theta, int *gam, const char *what) {
  Dag *d = b->d;
  int m = b->m, s = b->s, k = b->k, *img = step_nodes(m);
  for (int t = 0; t < s * m; t++) gam[t] = dag_const(d, 0);
  for (int l = 0; l < k; l++) {
    char *label = arena_alloc(160);
    snprintf(label, 160, "stage %d of %d again: P from the %s, v = M(Q)^-1 P", l + 1, k, what);
    step_section(b, label);
    stage_momentum(b, l, theta, qp + 2 * l * m + m);
    dag_subst(d, b->mod->mq_v, m, qp + 2 * l * m, 2 * m, img);
    for (int j = 0; j < s; j++) {
      int w = dag_const(d, b->me->W[l * s + j]);
      for (int i = 0; i < m; i++) gam[j * m + i] = dag_add(d, gam[j * m + i], dag_mul(d, w, img[i]));
    }
  }
}

// p1 - p0 = -h Theta_0, the sweep's result dp.
static int *momentum_change(Build *b, int **theta) {
  int *dp = step_nodes(b->m);
  step_section(b, "p1 - p0 = -h Theta_0");
  for (int i = 0; i < b->m; i++) dp[i] = dag_neg(b->d, dag_mul(b->d, b->h, theta[0][i]));
  return dp;
}

// The sweep with M(q), Gauss-Seidel: the new Theta from the input gamma and
// Theta (stage_forces), then the new gamma from the new Theta
// (stage_velocities).
void build_mq_sweep(Build *b) {
  int m = b->m, s = b->s;
  int *qp = step_nodes(2 * b->k * m), *gam = step_nodes(s * m);
  b->owners = 1u << K_SWEEP;
  int **theta = stage_forces(b, qp);
  stage_velocities(b, qp, theta, gam, "new Theta");
  int *dp = momentum_change(b, theta);
  Step *st = b->st;
  step_result(st, K_SWEEP, "gam", SZ_SM, 1, s * m, gam);
  step_result(st, K_SWEEP, "dp", SZ_M, 1, m, dp);
  step_result(st, K_SWEEP, "th0", SZ_M, 1, m, theta[0]);
  step_result(st, K_SWEEP, "lambda", SZ_NU, 1, 0, dp);
  step_result(st, K_SWEEP, "pivot", SZ_NU, 1, 0, dp);
  step_result(st, K_SWEEP, "adiag", SZ_NU, 1, 0, dp);
  b->theta = theta;
  step_theta_result(b);
  st->kern[K_SWEEP].what = "One fixed-point sweep with M(q): out = new gamma (S*M), p1 - p0 (M), Theta_0 (M),\n"
                           " * Theta_1.. (M*(S-1)): with Theta_0 the whole new Theta, the next sweep's pth.";
}

// M(q) with constraints: the poly family's multiplier, a polynomial of
// degree s-1 with coefficients lambda_r (input lam), in the general-H
// sweep. The kernel "factor" is the poly family's A with M(q0) for M
// (mod->mass_at: the frozen matrix of a quasi-Newton update, exact to
// O(h)). The sweep: psi_j from the stage forces at the input gamma and
// Theta (stage_forces), Theta_j(lambda) = psi_j + sum_l b_l P_j(c_l) G_l
// Lambda_l, gamma from it (stage_velocities), the conditions C at that
// gamma, lambda1 = lambda + A^-1 C, and the new Theta and gamma at lambda1
// (a second triangular solve a stage). The end of the step is the poly
// family's: p1 projected onto the hidden constraint at q1 in the M(q1)
// norm and rescaled to H0 ("project_p1", build_projection).
void build_mq_constrained(Build *b) {
  Dag *d = b->d;
  Step *st = b->st;
  int m = b->m, s = b->s, n = s * b->nu;
  LuFactor in;
  int ****R, ***G = build_poly_factor(b, &in, &R);
  (void)R;
  b->owners = 1u << K_SWEEP;
  int *qp = step_nodes(2 * b->k * m), *gam = step_nodes(s * m), *gam1 = step_nodes(s * m);
  int *lam = step_nodes(n), *lam1 = step_nodes(n), *delta = step_nodes(n);
  for (int t = 0; t < n; t++) lam[t] = step_in(b, IN_LAM, t);
  b->psi = stage_forces(b, qp);
  step_section(b, "the multiplier coefficients: lambda += A^-1 C(lambda)");
  int **theta = force_coefficients(b, G, NULL, lam);
  stage_velocities(b, qp, theta, gam, "Theta at lambda");
  lu_apply(d, &in, conditions(b, G, NULL, gam), delta);
  for (int t = 0; t < n; t++) lam1[t] = dag_add(d, lam[t], delta[t]);
  step_section(b, "Theta_j at the new lambda");
  theta = force_coefficients(b, G, NULL, lam1);
  stage_velocities(b, qp, theta, gam1, "Theta at the new lambda");
  int *dp = momentum_change(b, theta);
  step_result(st, K_SWEEP, "gam", SZ_SM, 1, s * m, gam1);
  step_result(st, K_SWEEP, "dp", SZ_M, 1, m, dp);
  step_result(st, K_SWEEP, "lam", SZ_SNU, 1, n, lam1);
  step_result(st, K_SWEEP, "th0", SZ_M, 1, m, theta[0]);
  b->theta = theta;
  step_theta_result(b);
  st->kern[K_SWEEP].what = "One fixed-point sweep with M(q) and the frozen factor lu of A: out = new gamma\n"
                           " * (S*M), p1 - p0 (M), the multiplier's Legendre coefficients (S*NU), Theta_0 (M),\n"
                           " * Theta_1.. (M*(S-1)): with Theta_0 the whole new Theta, the next sweep's pth.";
  build_projection(b);
}
