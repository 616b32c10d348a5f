/* emit_rolled_poly.c - the poly family's kernels in the rolled form.
 *
 * The polynomial multiplier (step_poly.c, docs/method-poly.md) has three
 * kernels whose size grows with the model; with e->roll they are loops over
 * the coordinates, as the constant family's are (emit_rolled.c):
 *   - the moments R_jr = sum_l b_l P_j(c_l) P_r(c_l) G_l of the stage
 *     Jacobians, j <= r (symmetric), at every entry d g_a / dq_i (the table
 *     tcon): the k stages in one helper, $P_roll_moments;
 *   - "factor": the (s nu) x (s nu) matrix
 *       A[(i,a),(r,c)] = h sum_j sum_l X[j][l] (R_ij' M^-1 R_lr)_ac,
 *     assembled by one loop over the coordinates into band storage, its
 *     unknowns in the order (a, r) -> a s + r, so that two constraints a, c
 *     on one coordinate give entries at most s (bw + 1) - 1 from the
 *     diagonal (PBW); factored by LU without pivoting over the band (in
 *     that order the diagonal s x s blocks are about h X (G' M^-1 G)_aa, and
 *     X's elimination needs no pivoting: its pivots are xi_0, xi_1^2 /
 *     xi_0, ... > 0);
 *   - "sweep": psi as in the constant family, Theta_j(lambda) = psi_j +
 *     sum_r R_jr lambda_r (the moment form of step_poly.c), gamma from it,
 *     the conditions C_i = sum_j R_ij' gamma_j (+ g(q0)/h), lambda +=
 *     A^-1 C with the frozen band factor, and Theta, gamma at the new
 *     lambda;
 *   - "project_p1": the projection of p1 onto the hidden constraint at q1,
 *     the kinetic energy after it, U(q1), the multiplier's two solutions
 *     and g(q1) with its scale, with G1' M^-1 G1 in band storage
 *     ($P_roll_gram, $P_band_factor of emit_rolled.c).
 * The straight-line step takes the moments of affine entries in closed form
 * and the sweep in stage or moment form, whichever is shorter; here they
 * are always the stage sums and the moment form: the same quantities,
 * rounded in another order (docs/rolled.md, "Same results"). */
#include <stdlib.h>

#include "emit.h"
#include "roll.h"

// The place of the moment (j, r) among the s (s + 1) / 2 kept: (min, max).
int rolled_poly_pair(int s, int j, int r) {
  int lo = j < r ? j : r, hi = j < r ? r : j;
  return lo * s - lo * (lo - 1) / 2 + (hi - lo);
}

// "Rm[...]": the moment (j, r) at entry t of coordinate i.
static void moment(const Emitter *e, int j, int r, int t, char *buf, size_t size) {
  int s = e->me->s, mt = e->mod->m * e->roll->T;
  snprintf(buf, size, "Rm[%d + %d * i]", rolled_poly_pair(s, j, r) * mt + t, e->roll->T);
}

// "sum_l X[j][l] R_lr" at entry t of coordinate i (row j of X, METHOD.md).
static void x_moment(Emitter *e, int j, int r, int t, char *buf, size_t size) {
  const double *xi = e->me->xi;
  char a[64], b[64];
  moment(e, j ? j - 1 : 0, r, t, a, sizeof a);
  if (j + 1 < e->me->s) {
    moment(e, j + 1, r, t, b, sizeof b);
    snprintf(buf, size, "(%s * %s - %s * %s)", rolled_lit(e, xi[j]), a, rolled_lit(e, xi[j + 1]), b);
  } else {
    snprintf(buf, size, "%s * %s", rolled_lit(e, xi[j]), a);
  }
}

// The constraints on coordinate i as locals a0.. (pad: -1, or nu with pad).
static void tcon_locals(Emitter *e, int pad) {
  int T = e->roll->T, nu = e->mod->nu;
  for (int t = 0; t < T; t++)
    if (pad) out(e, "    const int a%d = %s_tcon[%d * i + %d] < 0 ? %d : %s_tcon[%d * i + %d];\n", t, e->P, T, t, nu, e->P, T, t);
    else out(e, "    const int a%d = %s_tcon[%d * i + %d];\n", t, e->P, T, t);
}

// The helpers of the rolled poly kernels: the moments at the stages of
// (q0, gamma), and the LU of the multiplier matrix's band and its solve.
void rolled_poly_helpers(Emitter *e) {
  const Method *me = e->me;
  int m = e->mod->m, s = me->s, mt = m * e->roll->T, np = s * (s + 1) / 2;
  tmplf(e, "\n/* The poly family's multiplier matrix: S*NU unknowns a S + r, half band PBW. */\n"
           "#define $P_PBW %d\n#define $P_PW (2 * $P_PBW + 1)\n\n", poly_band(e->mod, s));
  tmplf(e, "/* Rm[p M T + i T + t] = sum_l b_l P_j(c_l) P_r(c_l) (d g_a / dq_i)(Q_l), p the pair j <= r,\n"
           " * a = $P_tcon[i T + t], Q_l = q0 + h sum_j Ihat[l][j] gamma_j: the moments of the stage Jacobians. */\n"
           "static void $P_roll_moments(const $R *q0, const $R *gam, $R h, const $P_params *prm, $R *Rm)\n{\n"
           "  $R Q[%d], J[%d];\n  int i;\n  for (i = 0; i < %d; i++) Rm[i] = 0;\n", m, mt, np * mt);
  for (int l = 0; l < me->k; l++) {
    out(e, "  /* stage %d of %d */\n  for (i = 0; i < %d; i++) Q[i] = q0[i] + h * (", l + 1, me->k, m);
    for (int j = 0; j < s; j++) out(e, "%s%s * gam[%d + i]", j ? " + " : "", rolled_lit(e, me->Ihat[l * s + j]), j * m);
    tmpl(e, ");\n  $P_roll_jac(Q, 0, prm, J);\n");
    out(e, "  for (i = 0; i < %d; i++) {\n", mt);
    for (int j = 0; j < s; j++)
      for (int r = j; r < s; r++)
        out(e, "    Rm[%d + i] += %s * J[i];\n", rolled_poly_pair(s, j, r) * mt,
            rolled_lit(e, me->W[l * s + j] * me->Phat[l * s + r]));
    out(e, "  }\n");
  }
  tmpl(e, "}\n\n"
          "/* A (S NU x S NU, band storage A[u * $P_PW + w - u + $P_PBW]) = L U without pivoting, in place:\n"
          " * pivot[k] the k-th pivot, adiag[k] the diagonal entry it started from. */\n"
          "static void $P_pband_factor($R *A, $R *pivot, $R *adiag)\n{\n"
          "  int k, d, c;\n"
          "  for (k = 0; k < $P_S * $P_NU; k++) adiag[k] = A[k * $P_PW + $P_PBW];\n"
          "  for (k = 0; k < $P_S * $P_NU; k++) {\n"
          "    const $R *Ak = A + k * $P_PW + $P_PBW;  /* Ak[c] = A[k][k + c] */\n"
          "    pivot[k] = Ak[0];\n"
          "    for (d = 1; d <= $P_PBW && k + d < $P_S * $P_NU; d++) {\n"
          "      $R *Ai = A + (k + d) * $P_PW + $P_PBW - d;  /* Ai[c] = A[k + d][k + c] */\n"
          "      const $R f = Ai[0] / Ak[0];\n"
          "      Ai[0] = f;\n"
          "      for (c = 1; c <= $P_PBW && k + c < $P_S * $P_NU; c++) Ai[c] -= f * Ak[c];\n"
          "    }\n"
          "  }\n}\n\n"
          "/* x = A^-1 x for A factored by $P_pband_factor. */\n"
          "static void $P_pband_solve(const $R *A, $R *x)\n{\n"
          "  int k, d;\n"
          "  for (k = 0; k < $P_S * $P_NU; k++)\n"
          "    for (d = 1; d <= $P_PBW && k + d < $P_S * $P_NU; d++) x[k + d] -= A[(k + d) * $P_PW + $P_PBW - d] * x[k];\n"
          "  for (k = $P_S * $P_NU - 1; k >= 0; k--) {\n"
          "    $R acc = x[k];\n"
          "    for (d = 1; d <= $P_PBW && k + d < $P_S * $P_NU; d++) acc -= A[k * $P_PW + $P_PBW + d] * x[k + d];\n"
          "    x[k] = acc / A[k * $P_PW + $P_PBW];\n"
          "  }\n}\n");
}

// "factor": the moments at the predicted gamma, A assembled over the
// coordinates (the T x T pairs of constraints on each, s x s entries a
// pair, unrolled), its band LU into out.
static void emit_poly_factor(Emitter *e) {
  int m = e->mod->m, s = e->me->s, T = e->roll->T, mt = m * T, np = s * (s + 1) / 2;
  char a[64], y[256];
  tmplf(e, "  $R Rm[%d], *A = out + $<factor.lu>;\n  int i;\n", np * mt);
  tmpl(e, "  $P_roll_moments(q0, gam, h, prm, Rm);\n"
          "  for (i = 0; i < $P_S * $P_NU * $P_PW; i++) A[i] = 0;\n");
  out(e, "  /* A[(a, i), (c, r)] += h sum_j R_ij[., a] M^-1 sum_l X[j][l] R_lr[., c] at each coordinate */\n"
         "  for (i = 0; i < %d; i++) {\n", m);
  tcon_locals(e, 0);
  for (int t = 0; t < T; t++)
    for (int u = 0; u < T; u++) {
      out(e, "    if (a%d >= 0 && a%d >= 0) {\n", t, u);
      tmplf(e, "      $R *At = A + a%d * %d * $P_PW + (a%d - a%d) * %d + $P_PBW;\n", t, s, u, t, s);
      for (int ii = 0; ii < s; ii++)
        for (int r = 0; r < s; r++) {
          tmplf(e, "      At[%d * $P_PW + %d] += h * ($P_MINV(i) (", ii, r - ii);
          for (int j = 0; j < s; j++) {
            moment(e, ii, j, t, a, sizeof a);
            x_moment(e, j, r, u, y, sizeof y);
            out(e, "%s%s * %s", j ? " + " : "", a, y);
          }
          out(e, "));\n");
        }
      out(e, "    }\n");
    }
  out(e, "  }\n");
  tmpl(e, "  $P_pband_factor(A, out + $<factor.pivot>, out + $<factor.adiag>);\n");
}

// In a loop over the coordinates i: th[j] = Theta_j = psi_j + sum_r R_jr
// lambda_r at i, lambda_r from lm (r (NU + 1) + a, 0 at a = NU).
static void emit_theta(Emitter *e) {
  int m = e->mod->m, s = e->me->s, T = e->roll->T, nu = e->mod->nu;
  char a[64];
  out(e, "    %s th[%d];\n", real_type(e, 0), s);
  for (int j = 0; j < s; j++) {
    out(e, "    th[%d] = psi[%d + i]", j, j * m);
    for (int t = 0; t < T; t++)
      for (int r = 0; r < s; r++) {
        moment(e, j, r, t, a, sizeof a);
        out(e, " + %s * lm[%d + a%d]", a, r * (nu + 1), t);
      }
    out(e, ";\n");
  }
}

// "sweep": Theta at lambda, gamma from it, the conditions at that gamma,
// lambda += A^-1 C, and the results at the new lambda.
static void emit_poly_sweep(Emitter *e) {
  int m = e->mod->m, s = e->me->s, T = e->roll->T, mt = m * T, nu = e->mod->nu, np = s * (s + 1) / 2;
  char a[64];
  tmplf(e, "  $R Q[%d], F[%d], hX[%d], psi[%d], Rm[%d], gm[%d], x[%d], lm[%d];\n  int i, j = 0;\n"
           "  (void)Q; (void)F; (void)hX; (void)j;\n", m, m, s * m, s * m, np * mt, s * m, s * nu, s * (nu + 1));
  rolled_projections(e, 0);
  tmpl(e, "  $P_roll_moments(q0, gam, h, prm, Rm);\n");
  out(e, "  for (i = 0; i < %d; i++) lm[i] = 0;\n", s * (nu + 1));
  out(e, "  for (i = 0; i < %d; i++) lm[i / %d * %d + i %% %d] = lam[i];\n", s * nu, nu, nu + 1, nu);
  out(e, "  /* Theta(lambda) and gamma from it */\n  for (i = 0; i < %d; i++) {\n", m);
  tcon_locals(e, 1);
  emit_theta(e);
  rolled_gamma(e, 0);
  out(e, "  }\n  /* the conditions C_i = sum_j R_ij' gamma_j + delta_i0 g(q0) / h, at a S + i */\n"
         "  for (i = 0; i < %d; i++) x[i] = 0;\n  for (i = 0; i < %d; i++) {\n", s * nu, m);
  tcon_locals(e, 0);
  for (int t = 0; t < T; t++) {
    out(e, "    if (a%d >= 0) {\n", t);
    for (int ii = 0; ii < s; ii++) {
      out(e, "      x[a%d * %d + %d] += ", t, s, ii);
      for (int j = 0; j < s; j++) {
        moment(e, ii, j, t, a, sizeof a);
        out(e, "%s%s * gm[%d + i]", j ? " + " : "", a, j * m);
      }
      out(e, ";\n");
    }
    out(e, "    }\n");
  }
  out(e, "  }\n  for (i = 0; i < %d; i++) x[%d * i] += g0[i];  /* g(q0) / h, or 0 */\n", nu, s);
  tmpl(e, "  $P_pband_solve(lu, x);\n");
  out(e, "  for (i = 0; i < %d; i++) {\n", nu);
  for (int r = 0; r < s; r++)
    tmplf(e, "    lm[%d + i] = lam[%d + i] + x[%d * i + %d];\n    out[$[sweep.lam]%d + i] = lm[%d + i];\n", r * (nu + 1),
          r * nu, s, r, r * nu, r * (nu + 1));
  out(e, "  }\n  /* Theta(lambda + A^-1 C), the new gamma */\n  for (i = 0; i < %d; i++) {\n", m);
  tcon_locals(e, 1);
  emit_theta(e);
  rolled_gamma(e, 1);
  out(e, "  }\n");
}

// "project_p1": at (q0, p0) = (q1, p1), dp = -G1 mu with (G1' M^-1 G1) mu =
// G1' M^-1 p1, the kinetic energy after it, U(q1), the multiplier's lamv
// and lamu, g(q1) and its round-off scale, G1' M^-1 G1 in band storage.
static void emit_poly_project(Emitter *e) {
  int m = e->mod->m, nu = e->mod->nu, mt = m * e->roll->T;
  tmplf(e, "  $R J[%d], B[%d], y[%d], v[%d], gu[%d], kin = 0, u;\n  int i, t;\n", mt, nu * (2 * e->roll->bw + 1), nu + 1, m, m);
  tmpl(e, "  $P_roll_jac(q0, 0, prm, J);\n  $P_roll_gram(J, B);\n"
          "  $P_band_factor(B, out + $<project_p1.pivot>, out + $<project_p1.adiag>);\n"
          "  for (i = 0; i < $P_NU; i++) y[i] = 0;\n"
          "  for (i = 0; i < $P_M; i++)\n"
          "    for (t = 0; t < $P_RT; t++)\n"
          "      if ($P_tcon[i * $P_RT + t] >= 0) y[$P_tcon[i * $P_RT + t]] += J[i * $P_RT + t] * ($P_MINV(i) p0[i]);\n"
          "  $P_band_solve(B, y);\n"
          "  for (i = 0; i < $P_M; i++) {\n"
          "    $R acc = 0, pt;\n"
          "    for (t = 0; t < $P_RT; t++)\n"
          "      if ($P_tcon[i * $P_RT + t] >= 0) acc -= J[i * $P_RT + t] * y[$P_tcon[i * $P_RT + t]];\n"
          "    out[$[project_p1.dp]i] = acc;\n"
          "    pt = p0[i] + acc;\n"
          "    v[i] = $P_MINV(i) pt;\n"
          "    kin += pt * v[i];\n"
          "  }\n");
  tmplf(e, "  out[$[project_p1.kin]0] = %s * kin;\n", rolled_lit(e, 0.5));
  tmpl(e, "  $P_roll_U(q0, 0, prm, &u);\n  out[$[project_p1.U]0] = u;\n"
          "  $P_roll_hvv(q0, v, prm, out + $<project_p1.lamv>);\n"
          "  $P_band_solve(B, out + $<project_p1.lamv>);\n"
          "  $P_roll_gradU(q0, 0, prm, gu);\n"
          "  for (i = 0; i < $P_NU; i++) out[$[project_p1.lamu]i] = 0;\n"
          "  for (i = 0; i < $P_NU; i++) out[$[project_p1.gscale]i] = 0;\n"
          "  for (i = 0; i < $P_M; i++)\n"
          "    for (t = 0; t < $P_RT; t++)\n"
          "      if ($P_tcon[i * $P_RT + t] >= 0) {\n"
          "        out[$[project_p1.lamu]$P_tcon[i * $P_RT + t]] += J[i * $P_RT + t] * ($P_MINV(i) gu[i]);\n"
          "        out[$[project_p1.gscale]$P_tcon[i * $P_RT + t]] += fabs$f(J[i * $P_RT + t] * q0[i]);\n"
          "      }\n"
          "  $P_band_solve(B, out + $<project_p1.lamu>);\n"
          "  $P_roll_g(q0, 0, prm, out + $<project_p1.g>);\n");
}

void rolled_poly_kernel(Emitter *e, KernelId id) {
  if (id == K_FACTOR) emit_poly_factor(e);
  else if (id == K_SWEEP) emit_poly_sweep(e);
  else emit_poly_project(e);
}
