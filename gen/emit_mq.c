/* emit_mq.c - what the step's iteration adds for a mass matrix M(q).
 *
 * The sweep with M(q) (step_mq.c) reads Theta, the coefficients of p's
 * polynomial, from its input pth, and the iteration carries the sweep's new
 * Theta (sw[th0..]) to the next sweep. This file prints the three pieces
 * the fixed-point iteration (emit_iterate.c) calls: NAME_predict_theta, the
 * warm start of Theta (emit_mq_predict, beside NAME_predict); the local pth
 * and its start (emit_mq_start); and after each sweep Theta's increment,
 * which joins gamma's in the convergence test, and the carry (emit_mq_carry).
 * The end of the step (emit_end.c) calls emit_mq_rescale: p1 rescaled to the
 * run's energy, so that the iteration may stop at 2 ulps (the poly family's
 * contraction test, emit_iterate.c) and k = s nodes suffice for H. */
#include <stdio.h>

#include "emit.h"

// NAME_predict_theta: the last step's Theta (x->pinc holds p1 - p0 =
// -h Theta_0, then Theta_1..) extrapolated to a step of size h as gamma is
// (emit_warm_extrapolation: the coefficients E[j][i](r) as literals, the
// same sums as the loop over their table that took 1.7k of the 32k
// instructions of a step of the double pendulum in angles, (6,6)); 0 on
// the first step or when cold.
void emit_mq_predict(Emitter *e) {
  tmpl(e, "\n/* Theta for a step of size h (M(q): p's polynomial is iterated with gamma): the last\n"
          " * step's, from x->pinc, extrapolated like gamma; 0 on the first step or when cold. */\n"
          "$P_OUT_OF_LINE void $P_predict_theta(const $P_state *x, $R h, int cold, $R *pth)\n{\n"
          "  $R prev[$P_S * $P_M];\n  int i, l;\n"
          "  for (i = 0; i < $P_S * $P_M; i++) pth[i] = 0;\n"
          "  if (cold || x->hprev == 0) return;\n"
          "  for (i = 0; i < $P_M; i++) prev[i] = -x->pinc[i] / x->hprev;\n"
          "  for (i = $P_M; i < $P_S * $P_M; i++) prev[i] = x->pinc[i];\n");
  emit_warm_extrapolation(e, "pth", "prev");
  tmpl(e, "}\n");
}

// The iteration's Theta, pth, and its warm start (with constraints the
// poly family's step has declared the contraction test's locals).
void emit_mq_start(Emitter *e) {
  tmpl(e, "  $R pth[$P_S * $P_M];  /* M(q): Theta, p's polynomial, carried from sweep to sweep */\n");
  if (!e->st->kern[K_FACTOR].nout) tmpl(e, "  $R inc_old2 = HUGE_VAL, rho;  /* the contraction test ($P_contraction) */\n");
  tmpl(e, "  $P_predict_theta(x, h, cold, pth);\n");
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

// Near rest no rescale where beta is not within 1e-6 of 1 and H(q1, p1) -
// H0 is round-off (a round-off in H is a large change of p there): the test
// printed by both ends of step that rescale, after their beta, with the
// band of emit_mq_near_rest_band.
static const char near_rest_test[] = "if (!(fabs$f(beta - 1) <= 1e-6$f) && fabs$f(H0 - U1 - K) <= %d * $P_TOL * (K + fabs$f(U1))) beta = 1;\n";

// How far, in $P_TOL (2 ulps) of |K| + |U|, H(q1, p1) may be from H0 and
// still count as round-off for the near-rest test: 64 in double, 4 in
// float. In float 128 ulps (1.5e-5) is no longer round-off but the size of
// a step's own energy error, and since beta is beyond 1e-6 of 1 there for
// any K below |K| + |U|, the test skipped the rescale wherever the error was
// under the band: 1540 of 2000 steps of the float four-bar (s = 2, h =
// 0.05), whose H then drifted to 105 ulps; with 4, 474 steps and 7 ulps,
// and the accuracy from rest the same (tests/check_mq_fourbar.c).
int emit_mq_near_rest_band(const Emitter *e) { return e->single ? 4 : 64; }

// After the commit (compensated sums): p1 rescaled, p1 = beta p1, so that
// H(q1, p1) = H0, as the poly family's end of step does (T is quadratic in
// p for any M(q)). H0 is taken anew on the first step, or where H(q0, p0)
// (Hn, before the commit) differs from it by more than round-off: the state
// or the params were changed between steps. No rescale at rest (K = 0) or
// where H0 < U(q1), nor near rest, where beta is not within 1e-6 of 1 and
// H(q1, p1) - H0 is round-off. With a constant M (--energy rescale, the
// caller emit_end.c) H0 is kept while H(q0, p0) is the energy the last step
// ended with (x->Hend), exactly.
void emit_mq_rescale(Emitter *e) {
  tmpl(e, e->mod->mass_q ? "  {  /* M(q): p1 rescaled to the run's energy H0 */\n"
                          : "  {  /* p1 rescaled to the run's energy H0 (--energy rescale) */\n");
  tmpl(e, "    $R z[$P_M], U1, K, H0, beta = 1;\n"
          "    for (i = 0; i < $P_M; i++) z[i] = 0;\n"
          "    $(energy_kernel q0=x->q p0=z out=&U1);\n"
          "    K = $P_energy(x, prm) - U1;\n");
  tmpl(e, e->mod->mass_q ? "    H0 = x->hprev != 0 && fabs$f(Hn - x->H0) <= 64 * $P_TOL * (K + fabs$f(U1)) ? x->H0 : Hn;\n"
                         /* --energy rescale: a rescale skipped (near rest, or H0 < U(q1) at a turning
                          * point) is made up by the next step's, not taken for a change of the state */
                         : "    H0 = x->hprev != 0 && Hn == x->Hend ? x->H0 : Hn;  /* the state unchanged since */\n");
  tmpl(e, "    if (K > 0 && H0 - U1 > 0) beta = sqrt$f((H0 - U1) / K);\n"
          "    /* near rest a round-off in H is a large change of p (it is that over |v|): a\n"
          "     * discrepancy at round-off is corrected only where the correction is small (s = 2,\n"
          "     * tol 1e-10 from rest: 1000x the error without this test) */\n"
          "    ");
  tmplf(e, near_rest_test, emit_mq_near_rest_band(e));
  tmpl(e, "    for (i = 0; i < $P_M; i++) $P_add(&x->p[i], &x->pc[i], (beta - 1) * (x->p[i] - x->pc[i]));\n"
          "    x->H0 = H0;\n");
  if (!e->mod->mass_q) tmpl(e, "    x->Hend = $P_energy(x, prm);\n");
  tmpl(e, "  }\n");
}

// With constraints, after the poly family's beta (emit_end_poly): no rescale
// near rest, where beta is not within 1e-6 of 1 and H(q1, p1) - H0 is
// round-off, as emit_mq_rescale does (from rest, s = 2, tol 1e-9: 17 tol of
// global error without it, 0.3 tol with it; tests/check_mq_fourbar.c).
void emit_mq_near_rest(Emitter *e) {
  tmpl(e, "  /* M(q): near rest a round-off in H is a large change of p: corrected only where small */\n"
          "  ");
  tmplf(e, near_rest_test, emit_mq_near_rest_band(e));
}
