/* step_mq.c - the sweep of HBVM(k,s) for H(q, p) = p' M(q)^-1 p / 2 + U(q).
 *
 * With M depending on q the Hamiltonian is not separable, and the method is
 * the line-integral method for a general H on y = (q, p), y' = J grad H(y)
 * (docs/method-mq.md): the polynomial u of degree s has the Legendre
 * coefficients gamma_j (of q') and -Theta_j (of p'),
 *   gamma_j = sum_l b_l P_j(c_l) M(Q_l)^-1 P_l,
 *   Theta_j = sum_l b_l P_j(c_l) [grad_q T(Q_l, P_l) + grad U(Q_l)],
 *   Q_l = q0 + h sum_j Ihat[l][j] gamma_j,  P_l = p0 - h sum_j Ihat[l][j] Theta_j,
 * and q1 = q0 + h gamma_0, p1 = p0 - h Theta_0. The sweep is one Jacobi
 * step of this fixed point: from gamma (input gam) and Theta (input pth,
 * the last sweep's Theta carried by the iteration) to the new ones. Its
 * results are those of the constant family without constraints (gam, dp,
 * theta: the dense output and the estimate read them as they are) and
 * th0, Theta_0, which with theta after it is the whole new Theta. */
#include <string.h>

#include "step.h"

// Stage l's momentum P = p0 - h sum_j Ihat[l][j] Theta_j, Theta the input pth.
static void stage_momentum(Build *b, int l, int *P) {
  Dag *d = b->d;
  int m = b->m, s = b->s;
  for (int i = 0; i < m; i++) {
    int acc = dag_const(d, 0);
    for (int j = 0; j < s; j++)
      acc = dag_add(d, acc, dag_mul(d, dag_const(d, b->me->Ihat[l * s + j]), step_in(b, IN_LAM, j * m + i)));
    P[i] = dag_sub(d, step_in(b, IN_P0, i), dag_mul(d, b->h, acc));
  }
}

// The sweep with M(q): at each stage (Q_l, P_l), v = M(Q_l)^-1 P_l and the
// force grad_q T + grad U (mod->mq_v, mod->mq_force substituted there),
// summed with the weights b_l P_j(c_l) into the new gamma_j and Theta_j.
void build_mq_sweep(Build *b) {
  Dag *d = b->d;
  Model *mod = b->mod;
  int m = b->m, s = b->s;
  int *roots = step_nodes(2 * m), *img = step_nodes(2 * m), *qp = step_nodes(2 * m);
  memcpy(roots, mod->mq_v, (size_t)m * sizeof(int));
  memcpy(roots + m, mod->mq_force, (size_t)m * sizeof(int));
  int *gam = step_nodes(s * m), **theta = arena_alloc((size_t)s * sizeof(int *));
  for (int j = 0; j < s; j++) {
    theta[j] = step_nodes(m);
    for (int i = 0; i < m; i++) gam[j * m + i] = theta[j][i] = dag_const(d, 0);
  }
  b->owners = 1u << K_SWEEP;
  for (int l = 0; l < b->k; l++) {
    char *label = arena_alloc(160);
    snprintf(label, 160, "stage %d of %d: Q, P = (q0, p0) + h sum_j Ihat[%d][j] (gamma_j, -Theta_j), "
             "v = M(Q)^-1 P, grad_q T + grad U", l + 1, b->k, l + 1);
    step_section(b, label);
    step_stage_point(b, l, qp);
    stage_momentum(b, l, qp + m);
    dag_subst(d, roots, 2 * m, qp, 2 * m, img);
    for (int j = 0; j < s; j++) {
      int w = dag_const(d, b->me->W[l * s + j]);
      for (int i = 0; i < m; i++) {
        gam[j * m + i] = dag_add(d, gam[j * m + i], dag_mul(d, w, img[i]));
        theta[j][i] = dag_add(d, theta[j][i], dag_mul(d, w, img[m + i]));
      }
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
