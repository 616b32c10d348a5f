/* emit_batch_mq.c - what --batch W adds for a mass matrix M(q).
 *
 * The scalar step with M(q) (emit_mq.c) carries Theta, the coefficients of
 * p's polynomial, from sweep to sweep in pth, joins Theta's increment to
 * gamma's in the convergence test, and rescales p1 to the run's energy at
 * the end. The batch step (emit_batch_step.c) does the same in every lane,
 * bitwise: Theta lives in the sweep's input buffer beside gamma (where the
 * polynomial family keeps its multiplier), at the offset of the sweep's
 * results th0.. (Theta_0 then Theta_1..: contiguous, as M(q) has no
 * constraints), so the swap of the two buffers after a sweep is the carry
 * and a lane that has stopped gets its Theta back with its gamma. This file
 * prints NAME_batch_predict_theta (NAME_predict_theta over the lanes), the
 * lane test's Theta increment and that restore, and the commit's rescale. */
#include "emit.h"

// NAME_batch_predict_theta: every lane's NAME_predict_theta into pth (value
// i of lane l at pth[i * W + l]): the last step's Theta (pinc) extrapolated
// with the coefficients E[j][i](r) of gamma's warm start, each product
// added only where its coefficient is not 0, as the scalar loop skips it;
// 0 in a cold lane (cold_all, or no last step).
void emit_batch_mq_predict(Emitter *e) {
  tmpl(e, "/* $P_predict_theta in every lane (M(q): Theta, p's polynomial, is iterated with gamma). */\n"
          "$P_LANE_INLINE void $P_batch_predict_theta(const $P_batch *restrict x, $R h, int cold_all, $R *restrict pth)\n{\n"
          "  $R prev[$P_S * $P_M * $P_W], r[$P_W], hp[$P_W];\n  $M cold[$P_W];\n  int i, j, l, m, d;\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    cold[l] = (x->hprev[l] == 0) | (cold_all != 0);\n"
          "    hp[l] = cold[l] ? 1 : x->hprev[l];  /* (a cold lane's values are not used) */\n"
          "    r[l] = h / hp[l];\n  }\n"
          "  for (i = 0; i < $P_M; i++)\n    for (l = 0; l < $P_W; l++) prev[i * $P_W + l] = -x->pinc[i * $P_W + l] / hp[l];\n"
          "  for (i = $P_M * $P_W; i < $P_S * $P_M * $P_W; i++) prev[i] = x->pinc[i];\n"
          "  for (i = 0; i < $P_S * $P_M * $P_W; i++) pth[i] = 0;\n"
          "  for (j = 0; j < $P_S; j++)\n    for (i = 0; i < $P_S; i++) {\n"
          "      $R c[$P_W];\n"
          "      for (l = 0; l < $P_W; l++) c[l] = 0;\n"
          "      for (d = $P_S - 1; d >= 0; d--)\n"
          "        for (l = 0; l < $P_W; l++) c[l] = c[l] * r[l] + $P_E[(j * $P_S + i) * $P_S + d];\n"
          "      for (m = 0; m < $P_M; m++)\n        for (l = 0; l < $P_W; l++) {\n"
          "          $R a = pth[(j * $P_M + m) * $P_W + l], t = a + c[l] * prev[(i * $P_M + m) * $P_W + l];\n"
          "          pth[(j * $P_M + m) * $P_W + l] = ((c[l] != 0) & (cold[l] == 0)) ? t : a;\n        }\n"
          "    }\n}\n\n");
}

// In the lane test, after a sweep that read Theta from pth (the test's lam)
// and wrote the new one to sw: thi[l], lane l's Theta increment |h (Theta_new
// - Theta)| over max |p0| + |h Theta_0|, as NAME_step's (emit_mq_carry),
// which the test then joins to gamma's.
void emit_batch_mq_increment(Emitter *e) {
  tmpl(e, "  $R thi[$P_W], ps[$P_W];  /* M(q): Theta's scaled increment, as in $P_step */\n"
          "  for (l = 0; l < $P_W; l++) thi[l] = ps[l] = 0;\n"
          "  for (i = 0; i < $P_M; i++)\n    for (l = 0; l < $P_W; l++) {\n"
          "      $R v = fabs$f(x->p[i * $P_W + l]) + fabs$f(h * sw[($[sweep.th0]i) * $P_W + l]);\n"
          "      ps[l] = v > ps[l] ? v : ps[l];\n    }\n"
          "  for (i = 0; i < $P_S * $P_M; i++)\n    for (l = 0; l < $P_W; l++) {\n"
          "      $R v = fabs$f(h * (sw[($[sweep.th0]i) * $P_W + l] - lam[i * $P_W + l]));\n"
          "      thi[l] = v > thi[l] ? v : thi[l];\n    }\n"
          "  for (l = 0; l < $P_W; l++) thi[l] = thi[l] / (ps[l] > 0 ? ps[l] : 1);\n");
}

// In the lane test's restore of the lanes that stopped (keep[l]): their
// Theta from pth (lam), so that the next sweeps repeat their last one.
void emit_batch_mq_keep(Emitter *e) {
  tmpl(e, "      for (i = 0; i < $P_S * $P_M; i++)  /* M(q): and its Theta */\n        for (l = 0; l < $P_W; l++) {\n"
          "          $R s = sw[($[sweep.th0]i) * $P_W + l], g = lam[i * $P_W + l];\n"
          "          sw[($[sweep.th0]i) * $P_W + l] = keep[l] ? g : s;\n        }\n");
}

// In the commit, after q1, p1 are written in the lanes cm[l]: p1 rescaled
// to the run's energy H0 in those lanes, NAME_step's end (emit_mq_rescale)
// as selects: Hn[l] is H(q0, p0), taken before the commit.
void emit_batch_mq_rescale(Emitter *e) {
  tmpl(e, "    {  /* M(q): p1 rescaled to the run's energy H0, as at the end of $P_step */\n"
          "      $R z[$P_M * $P_W], U1[$P_W], E1[$P_W], beta[$P_W];\n"
          "      for (i = 0; i < $P_M * $P_W; i++) z[i] = 0;\n"
          "      $(energy_kernel q0=x->q p0=z prm=par out=U1);\n"
          "      $(energy_kernel q0=x->q p0=x->p prm=par out=E1);\n"
          "      for (l = 0; l < $P_W; l++) {\n"
          "        $R u = U1[l], K = E1[l] - u, tl = 64 * $P_TOL * (K + fabs$f(u)), ho = x->H0[l];\n"
          "        $M keep = (x->hprev[l] != 0) & (fabs$f(Hn[l] - ho) <= tl);\n"
          "        $R H0 = keep ? ho : Hn[l];\n"
          "        $M up = (K > 0) & (H0 - u > 0);\n"
          "        $R b = sqrt$f(up ? (H0 - u) / (K > 0 ? K : 1) : 1);\n"
          "        b = up ? b : 1;\n"
          "        b = (((fabs$f(b - 1) <= 1e-6$f) == 0) & (fabs$f(H0 - u - K) <= ");
  if (emit_mq_near_rest_band(e) == 64) tmpl(e, "tl"); /* the band of NAME_step's test */
  else tmplf(e, "%d * $P_TOL * (K + fabs$f(u))", emit_mq_near_rest_band(e));
  tmpl(e, ")) ? 1 : b;  /* near rest */\n"
          "        beta[l] = b;\n"
          "        x->H0[l] = cm[l] ? H0 : x->H0[l];\n      }\n"
          "      for (i = 0; i < $P_M; i++)\n        for (l = 0; l < $P_W; l++) {\n"
          "          $R p = x->p[i * $P_W + l], pc = x->pc[i * $P_W + l];\n"
          "          $P_add(&p, &pc, (beta[l] - 1) * (p - pc));\n"
          "          x->p[i * $P_W + l] = cm[l] ? p : x->p[i * $P_W + l];\n"
          "          x->pc[i * $P_W + l] = cm[l] ? pc : x->pc[i * $P_W + l];\n        }\n    }\n");
}
