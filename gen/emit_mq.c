/* emit_mq.c - what the step's iteration adds for a mass matrix M(q).
 *
 * The sweep with M(q) (step_mq.c) reads Theta, the coefficients of p's
 * polynomial, from its input pth, and the iteration carries the sweep's new
 * Theta (sw[th0..]) to the next sweep. This file prints the three pieces
 * the fixed-point iteration (emit_iterate.c) calls: NAME_predict_theta, the
 * warm start of Theta (emit_mq_predict, beside NAME_predict); the local pth
 * and its start (emit_mq_start); and after each sweep Theta's increment,
 * which joins gamma's in the convergence test, and the carry (emit_mq_carry). */
#include <stdio.h>

#include "emit.h"

// NAME_predict_theta: the last step's Theta (x->pinc holds p1 - p0 =
// -h Theta_0, then Theta_1..) extrapolated to a step of size h with the
// warm start's E[j][i](r) = sum_d E[(j*S+i)*S+d] r^d, as gamma is; 0 on the
// first step or when cold (p constant over the step).
void emit_mq_predict(Emitter *e) {
  int s = e->me->s, n = s * s * s;
  tmpl(e, "\n/* Theta for a step of size h (M(q): p's polynomial is iterated with gamma): the last\n"
          " * step's, from x->pinc, extrapolated like gamma; 0 on the first step or when cold. */\n"
          "$P_OUT_OF_LINE void $P_predict_theta(const $P_state *x, $R h, int cold, $R *pth)\n{\n"
          "  static const $R E[");
  out(e, "%d] = {", n);
  for (int t = 0; t < n; t++) {
    char lit[40];
    format_real(e, lit, sizeof lit, e->me->E[t]);
    out(e, "%s%s", t ? (t % 4 ? ", " : ",\n    ") : "", lit);
  }
  tmpl(e, "};\n  $R prev[$P_S * $P_M], r, c;\n  int i, j, l, d;\n"
          "  for (i = 0; i < $P_S * $P_M; i++) pth[i] = 0;\n"
          "  if (cold || x->hprev == 0) return;\n"
          "  for (i = 0; i < $P_M; i++) prev[i] = -x->pinc[i] / x->hprev;\n"
          "  for (i = $P_M; i < $P_S * $P_M; i++) prev[i] = x->pinc[i];\n"
          "  r = h / x->hprev;\n"
          "  for (j = 0; j < $P_S; j++)\n    for (i = 0; i < $P_S; i++) {\n"
          "      for (c = 0, d = $P_S - 1; d >= 0; d--) c = c * r + E[(j * $P_S + i) * $P_S + d];\n"
          "      if (c != 0)\n        for (l = 0; l < $P_M; l++) pth[j * $P_M + l] += c * prev[i * $P_M + l];\n"
          "    }\n}\n");
}

// The iteration's Theta, pth, and its warm start.
void emit_mq_start(Emitter *e) {
  tmpl(e, "  $R pth[$P_S * $P_M];  /* M(q): Theta, p's polynomial, carried from sweep to sweep */\n"
          "  $P_predict_theta(x, h, cold, pth);\n");
}

// After a sweep (inc already scaled): Theta's increment |h (Theta_new -
// Theta)| over max |p0| + |h Theta_0| joins inc, and the new Theta becomes pth.
void emit_mq_carry(Emitter *e) {
  tmpl(e, "    {  /* M(q): Theta's scaled increment joins gamma's; the new Theta is carried */\n"
          "      $R pi = 0, ps = 0;\n"
          "      for (i = 0; i < $P_M; i++) {\n"
          "        $R v = fabs$f(x->p[i]) + fabs$f(h * sw[$[sweep.th0]i]);\n"
          "        if (v > ps) ps = v;\n      }\n"
          "      for (i = 0; i < $P_S * $P_M; i++) {\n"
          "        $R v = fabs$f(h * (sw[$[sweep.th0]i] - pth[i]));\n"
          "        if (v > pi) pi = v;\n        pth[i] = sw[$[sweep.th0]i];\n      }\n"
          "      if (ps > 0) pi /= ps;\n      if (pi > inc) inc = pi;\n    }\n");
}
