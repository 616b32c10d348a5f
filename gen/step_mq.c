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
 * th0, Theta_0, which with theta after it is the whole new Theta. */
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
      int t = th ? th[j][i] : step_in(b, IN_LAM, j * m + i);
      acc = dag_add(d, acc, dag_mul(d, dag_const(d, b->me->Ihat[l * s + j]), t));
    }
    P[i] = dag_sub(d, step_in(b, IN_P0, i), dag_mul(d, b->h, acc));
  }
}

// The sweep with M(q), Gauss-Seidel: at each stage (Q_l, P_l) the force
// grad_q T + grad U (mod->mq_force substituted there) summed with the
// weights b_l P_j(c_l) into the new Theta_j; then with the stage momenta of
// the new Theta, v = M(Q_l)^-1 P_l (mod->mq_v, whose factors of M(Q_l) the
// force has built already) summed into the new gamma_j.
void build_mq_sweep(Build *b) {
  Dag *d = b->d;
  Model *mod = b->mod;
  int m = b->m, s = b->s, k = b->k;
  int *img = step_nodes(m), *qp = step_nodes(2 * k * m);
  int *gam = step_nodes(s * m), **theta = arena_alloc((size_t)s * sizeof(int *));
  for (int j = 0; j < s; j++) {
    theta[j] = step_nodes(m);
    for (int i = 0; i < m; i++) gam[j * m + i] = theta[j][i] = dag_const(d, 0);
  }
  b->owners = 1u << K_SWEEP;
  for (int l = 0; l < k; l++) {
    char *label = arena_alloc(160);
    snprintf(label, 160, "stage %d of %d: Q, P = (q0, p0) + h sum_j Ihat[%d][j] (gamma_j, -Theta_j), "
             "grad_q T + grad U", l + 1, k, l + 1);
    step_section(b, label);
    step_stage_point(b, l, qp + 2 * l * m);
    stage_momentum(b, l, NULL, qp + 2 * l * m + m);
    dag_subst(d, mod->mq_force, m, qp + 2 * l * m, 2 * m, img);
    for (int j = 0; j < s; j++) {
      int w = dag_const(d, b->me->W[l * s + j]);
      for (int i = 0; i < m; i++) theta[j][i] = dag_add(d, theta[j][i], dag_mul(d, w, img[i]));
    }
  }
  for (int l = 0; l < k; l++) {
    char *label = arena_alloc(160);
    snprintf(label, 160, "stage %d of %d again: P from the new Theta, v = M(Q)^-1 P", l + 1, k);
    step_section(b, label);
    stage_momentum(b, l, theta, qp + 2 * l * m + m);
    dag_subst(d, mod->mq_v, m, qp + 2 * l * m, 2 * m, img);
    for (int j = 0; j < s; j++) {
      int w = dag_const(d, b->me->W[l * s + j]);
      for (int i = 0; i < m; i++) gam[j * m + i] = dag_add(d, gam[j * m + i], dag_mul(d, w, img[i]));
    }
  }
  step_section(b, "p1 - p0 = -h Theta_0");
  int *dp = step_nodes(m);
  for (int i = 0; i < m; i++) dp[i] = dag_neg(d, dag_mul(d, b->h, theta[0][i]));
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
