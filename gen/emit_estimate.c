/* emit_estimate.c - the step's error control: NAME_err_est and the
 * other parts of the local error, and NAME_step / NAME_step_adaptive.
 *
 * emit_estimators prints, before the step that calls them: NAME_err_est
 * (the velocity's part, from the converged gamma and the predictor's
 * error d1), NAME_defect (the quadrature's part, where k nodes do not
 * integrate H exactly and no rescale restores it), NAME_TOLC, NAME_itol and
 * NAME_converged (where the adaptive step's iteration stops, polynomial
 * family) and NAME_mult_err (the constant multiplier's part). After the
 * step, emit_step_adaptive prints NAME_step (a fixed step: no tolerance)
 * and NAME_step_adaptive, whose controller's factor (emit_step_factor) the
 * batch's adaptive step prints too. Which parts a solver has is decided in
 * emit_choice.c. */
#include <math.h>
#include <stdio.h>

#include "emit.h"

// The constant of NAME_err_est: the geometric mean of true / estimate over
// the problems of tests/check_errest.c (docs/api.md), by s.
static double err_constant(const Emitter *e) {
  static const double order2s[] = {0.068, 8.7e-3, 5.1e-4, 2.8e-5};
  int s = e->me->s;
  return order2s[s < 4 ? s - 1 : 3];
}

// The constant of NAME_err_est's cold estimate (the first step, no warm
// start): the largest true / (|h gamma_{s-1}| rho^(s+1)) over the cold steps
// of tests/check_errest.c's problems and Kepler, h from 0.01 to 3 (true
// errors above 1e-12), rounded up: an estimate that is never below the
// truth there, as the first step's size is a guess (docs/api.md).
static double cold_constant(const Emitter *e) {
  int s = e->me->s;
  return s <= 2 ? 70 : s <= 4 ? 40 : 250;
}

// The order p of the estimate per unit step, for the controller (h^p): the
// step's order, but 3 for NAME_mult_err's error in q (h^4 a step: q is of
// order 4 under the constant multiplier, p of order 2 across the hidden
// constraint, docs/api.md).
static int controller_order(const Emitter *e) { return mult_err_wanted(e) ? 3 : step_order(e); }

// Print "IND DST = 0; for (...) ... DST = the largest speed;": over the
// coordinates, NAME_speed of ARR's gamma_0 and gamma_1 (s >= 2; |gamma_0| at
// s = 1), each cast to the solver's real by CAST ("" or "($R)"). The
// velocity's size in NAME_err_est and the range cap (emit_range_cap).
static void emit_speed_max(Emitter *e, const char *ind, const char *dst, const char *arr, const char *cast) {
  const char *R = real_type(e, 0), *f = math_suffix(e, 0);
  char c[40];
  snprintf(c, sizeof c, *cast ? "(%s)" : "", R);
  out(e, "%s%s = 0;\n%sfor (i = 0; i < %s_M; i++) {\n", ind, dst, ind, e->P);
  if (e->me->s >= 2)
    out(e, "%s  %s w = %s_speed(%s%s[i], %s%s[%s_M + i]);\n", ind, R, e->P, c, arr, c, arr, e->P);
  else
    out(e, "%s  %s w = fabs%s(%s%s[i]);\n", ind, R, f, c, arr);
  out(e, "%s  if (w > %s) %s = w;\n%s}\n", ind, dst, dst, ind);
}

// NAME_err_est: the local error estimate of a converged step from what the
// step has anyway (docs/api.md, "The local error estimate"). The Legendre
// coefficients of the velocity of a smooth solution fall like
// |gamma_j| ~ |v| rho^j, rho ~ h / (its time scale), and the local error of
// the order 2s is ~ h |v| rho^2s. The predictor's error d1 (the first sweep's
// increment) is the first coefficient the extrapolation lacks,
// d1 ~ h |v| rho^s, so with v the velocity's size over the step (a norm over
// the whole vector)
//   local error ~ h |v| (d1 / |h v|)^2 = d1^2 / |h v|.
// Where the velocity vanishes this is too large, never too small; beyond the
// asymptotic range (d1 >= |h v|) it is d1 itself. v is, over the coordinates,
// the larger of |gamma_0| and sqrt(3) |gamma_1| (NAME_speed; |gamma_0| at
// s = 1): gamma_0 alone, the mean velocity, vanishes for a step with a turning
// point in its middle, where the velocity either side does not, and the
// pendulum in its angle (6,6) had such tries rejected with r = d1 / |h gamma_0|
// at 0.15-2.2 where the step before had 0.003 (1 of 17-33 tries at tol
// 1e-4..3e-6, 3e-8; tests/check_errest.c, adaptive_turning_point).
// The first step after NAME_init has no warm start (its predictor is
// gamma_0 = M^-1 p, the rest 0: d1 is no longer ~ h |v| rho^s, and from rest it
// is the whole velocity): there, at s >= 2, the estimate is the same model
// read off the converged coefficients, NAME_COLDC |h gamma_{s-1}| rho^(s+1),
// with rho the slower of the two-step decays (|gamma_{s-1}| / |gamma_{s-3}|)^(1/2)
// and (|gamma_{s-2}| / |gamma_{s-4}|)^(1/2): odd and even coefficients can fall
// at different rates (Kepler's perihelion; from rest, v = a t + O(t^3) makes
// gamma_2 and gamma_3 both O(h^3)). At s = 2, gamma_1 / gamma_0, which is
// 1/sqrt(3) from rest whatever h: there (rho >= 0.35) the velocity is
// a t + O(t^3) (no jerk at rest: the force depends on q, and on p
// quadratically), gamma_0 - sqrt(3) gamma_1 is that O(h^3) part, e, and the
// same model d1^2 / |h v| with d1 = |h e| reads NAME_COLDC_REST |h| e^2 /
// |gamma_0|, of the method's order from rest (h^6); it was
// NAME_COLDC_REST |h gamma_1| rho^3, of order h^2, which sent adaptive runs
// from rest at tol <= 1e-13 to the step-size floor.
// The constant multiplier's own error (order 2) is NAME_mult_err's.
static void emit_err_est(Emitter *e) {
  int s = e->me->s, p = 2 * s;
  const char *g = math_suffix(e, e->wide_step);
  tmpl(e, "/* max |gamma_j| over the coordinates */\n"
          "static $R $P_coef(const $W *gam, int j)\n{\n  $R c = 0;\n  int i;\n  for (i = 0; i < $P_M; i++)\n");
  out(e, "    if (fabs%s(gam[j * %s_M + i]) > c) c = (%s)fabs%s(gam[j * %s_M + i]);\n  return c;\n}\n\n", g, e->P,
      real_type(e, 0), g, e->P);
  if (s >= 2)
    tmpl(e, "/* The size of a coordinate's velocity over the step: the larger of its mean gamma_0\n"
            " * and sqrt(3) gamma_1, half its change across the step (gamma_0 vanishes where the\n"
            " * velocity changes sign mid-step; the change does not) */\n"
            "static $R $P_speed($R g0, $R g1)\n{\n"
            "  g0 = fabs$f(g0);\n  g1 = ($R)1.7320508075688772 * fabs$f(g1);\n  return g1 > g0 ? g1 : g0;\n}\n\n");
  tmpl(e, "/* The local error estimate of a step (max norm in q) from its converged gamma and\n"
          " * the predictor's error d1 = max |h (gamma after one sweep - predicted gamma)|:\n");
  out(e, " * |h v| (d1 / |h v|)^(%d/%d), v = gamma_0 (docs/api.md). */\n", p, s);
  tmpl(e, "#ifndef $P_ERRC\n");
  char c[40];
  format_real(e, c, sizeof c, err_constant(e));
  out(e, "#define %s_ERRC %s  /* measured: docs/api.md */\n#endif\n", e->P, c);
  if (s >= 2) {
    format_real(e, c, sizeof c, cold_constant(e));
    out(e, "#ifndef %s_COLDC\n#define %s_COLDC %s  /* the first step's: measured, docs/api.md */\n#endif\n", e->P,
        e->P, c);
  }
  if (s == 2) { /* from rest: the largest true / (|h| e^2 / |gamma_0|), rounded up (docs/api.md) */
    format_real(e, c, sizeof c, 140);
    out(e, "#ifndef %s_COLDC_REST\n#define %s_COLDC_REST %s  /* the same from rest: measured, docs/api.md */\n"
           "#endif\n", e->P, e->P, c);
  }
  tmpl(e, "$P_OUT_OF_LINE $R $P_err_est(const $W *gam, $R h, $R d1, int cold)\n{\n  $R v, r;\n  int i;\n");
  if (s >= 2) {
    emit_speed_max(e, "  ", "v", "gam", e->wide_step ? "cast" : "");
    tmpl(e, "  v *= fabs$f(h);\n");
  } else
    tmpl(e, "  v = fabs$f(h) * $P_coef(gam, 0);\n");
  if (s >= 2) {
    out(e, "  if (cold) {  /* no warm start: %s_COLDC |h gamma_%d| rho^%d */\n", e->P, s - 1, s + 1);
    out(e, "    %s c = %s_coef(gam, %d)", real_type(e, 0), e->P, s - 1);
    if (s != 3) out(e, ", b = %s_coef(gam, %d)", e->P, s - 2);
    if (s >= 3) out(e, ", a = %s_coef(gam, %d)", e->P, s - 3);
    if (s >= 4) out(e, ", z = %s_coef(gam, %d), t", e->P, s - 4);
    out(e, ";\n    if (!(c > 0)) return d1;  /* ~0 when the motion is a polynomial of degree < %d */\n", s);
    if (s == 2) {
      tmpl(e, "    r = c / b;  /* from rest 1/sqrt(3) whatever h: the constant of no decay */\n"
              "    if (!(r < 1)) return d1;  /* no decay: no asymptotic range */\n"
              "    if (!(r < ($R)0.35)) {  /* near rest: $P_COLDC_REST |h| e^2 / |gamma_0|, */\n"
              "      $R d, e = 0;  /* e = max |gamma_0 - sqrt(3) gamma_1|: 0 for v = a t */\n"
              "      for (i = 0; i < $P_M; i++) {\n");
      out(e, "        d = (%s)fabs%s(gam[i] - (%s)1.7320508075688772 * gam[%s_M + i]);\n", real_type(e, 0), g,
          real_type(e, e->wide_step), e->P);
      tmpl(e, "        if (d > e) e = d;\n      }\n      return $P_COLDC_REST * fabs$f(h) * e * e / b;\n    }\n"
              "    v = $P_COLDC * fabs$f(h) * c;\n");
    } else {
      out(e, "    r = sqrt%s(c / a);  /* the slower of the two-step decays */\n", math_suffix(e, 0));
      if (s >= 4) out(e, "    t = sqrt%s(b / z);\n    if (t > r) r = t;\n", math_suffix(e, 0));
      tmpl(e, "    if (!(r < 1)) return d1;  /* no decay: no asymptotic range */\n"
              "    v = $P_COLDC * fabs$f(h) * c;\n");
    }
    out(e, "    for (i = 0; i < %d; i++) v *= r;\n    return v;\n  }\n", s + 1);
  } else
    tmpl(e, "  (void)cold;  /* at s = 1 the cold predictor's error is the warm one's */\n");
  tmpl(e, "  if (!(v > d1)) return d1;  /* rho >= 1: no asymptotic range */\n  r = d1 / v;\n");
  tmpl(e, "  v *= $P_ERRC;\n");
  out(e, "  for (i = 0; i < %d; i++) v *= r;\n  return v;\n}\n\n", p / s);
}

// NAME_TOLC, the share of tol allowed per unit step (NAME_step_adaptive).
static void emit_tolc(Emitter *e) {
  out(e, "#ifndef %s_TOLC\n#define %s_TOLC %s  /* the local error allowed per unit step, over tol */\n#endif\n\n",
      e->P, e->P, e->single ? "0.01f" : "0.01");
}

// NAME_itol: where the adaptive step's iteration stops (docs/api.md, "The
// iteration under a tolerance"). The step's tolerance tol (1 + scale) bounds
// its local error in q; the iteration error the converged test leaves in q,
// rho inc / (1 - rho) scale (inc relative to scale), is allowed NAME_ITERC of
// it. Capped at NAME_ITOLMAX, so that the Newton steps onto g = 0 at the end
// of the step (each squares the error of the last) bring g back to round-off
// in one or two (NAME_NEWTON at most), and at least NAME_TOL, the fixed
// step's round-off test.
static void emit_itol(Emitter *e) {
  out(e, "#ifndef %s_ITERC\n#define %s_ITERC %s  /* the iteration error allowed, over the step's tolerance */\n#endif\n",
      e->P, e->P, e->single ? "0.1f" : "0.1");
  out(e, "#ifndef %s_ITOLMAX\n#define %s_ITOLMAX %s  /* at most: one or two Newton steps put g back at round-off */\n#endif\n",
      e->P, e->P, e->single ? "1e-4f" : "1e-8");
  out(e, "#ifndef %s_NEWTON\n#define %s_NEWTON 3  /* Newton steps onto g = 0 after it, at most */\n#endif\n", e->P, e->P);
  tmpl(e, "/* The scaled increment at which the iteration of $P_step_adaptive stops: the error\n"
          " * rho inc / (1 - rho) it leaves within $P_ITERC times the step's tolerance tol (1 + scale),\n"
          " * between $P_TOL and $P_ITOLMAX; $P_TOL (round-off) for a fixed step (tol 0). */\n"
          "static $R $P_itol($R tol, $R scale)\n{\n"
          "  $R t = $P_ITERC * tol * (1 + scale) / (scale > 0 ? scale : 1);\n"
          "  t = t < $P_ITOLMAX ? t : $P_ITOLMAX;\n"
          "  return ((tol > 0) & (scale > 0) & (t > $P_TOL)) ? t : $P_TOL;\n}\n\n"
          "/* The iteration's stopping test at the threshold t: the increment inc within t, or the\n"
          " * error it leaves in gamma, rho inc / (1 - rho), with rho the contraction of $P_contraction\n"
          " * (Hairer & Wanner IV.8); rho = 1 (not known yet) leaves only the first. */\n"
          "static int $P_converged($R inc, $R rho, $R t)\n{\n"
          "  return inc <= t || (rho < 1 && inc * rho <= t * (1 - rho));\n}\n\n");
}

// NAME_contraction: the contraction rate rho of the polynomial family's
// iteration that its stopping test reads, the larger of the last two ratios
// of increments, so from the third sweep on (1, not known, before). One
// ratio, read from the second sweep on, took the first sweep's increment
// (the predictor's error, which the sweep removes faster than the slowest
// part of the iteration's error) and a sweep that followed a refresh of the
// factor for the contraction: at s >= 6 in float and s >= 14 in double such
// a ratio was far below the true rate, and steps were accepted with g(q1) up
// to 1 (issue 30, item 1; tests/check_poly.c).
static void emit_contraction(Emitter *e) {
  tmpl(e, "/* The iteration's contraction rate after sweep it: the larger of the last two ratios of\n"
          " * its increments inc / inc_old and inc_old / inc_old2; 1 (not known) before the third\n"
          " * sweep. One ratio underrates it where the error has parts that contract at different\n"
          " * rates (the predictor's error, a refreshed factor), and the test then stopped early. */\n"
          "static $R $P_contraction($R inc, $R inc_old, $R inc_old2, int it)\n{\n"
          "  $R r, r0;\n"
          "  if (it < 3) return 1;\n"
          "  r = inc / inc_old;\n  r0 = inc_old / inc_old2;\n"
          "  return r0 > r ? r0 : r;\n}\n\n");
}

// The head of a loop over the coordinates, in NAME_defect and NAME_mult_err:
// the step's end (q1, p1) = x + (h sw[gam], sw[dp]) from the converged sweep,
// before the commit, and dp = max |p1 - p0|; the caller closes the loop.
static void emit_step_end_loop(Emitter *e) {
  tmpl(e, "  for (i = 0; i < $P_M; i++) {\n"
          "    q1[i] = x->q[i] + h * ($R)sw[$[sweep.gam]i];\n    p1[i] = x->p[i] + ($R)sw[$[sweep.dp]i];\n"
          "    if (fabs$f(p1[i] - x->p[i]) > dp) dp = fabs$f(p1[i] - x->p[i]);\n");
}

#define MULT_ERRC 0.12 /* NAME_MULTC: the geometric mean of true / estimate (docs/api.md) */

// NAME_mult_err: the constant multiplier's part of a step's local error,
// beside the velocity's order 2s that NAME_err_est sees. Measured (docs/api.md,
// "The local error estimate"): under the constant multiplier q has order 4,
// and p's local error is, to three digits, dp1, its projection onto the hidden
// constraint at q1 (the kernel "consistent"), ~ h^2 and alternating in sign
// from step to step (dp1 ~ -dp0 + the step's own part). So the step's own
// part is dp1 + dp0, and q's error ~ h |M^-1 (dp1 + dp0)| (h / tau), tau the
// motion's time scale, for which h / tau ~ |p1 - p0| / (|p0| + |p1 - p0|) (at
// most 1, where the momentum vanishes). True / estimate 0.45-1.7 in geometric
// mean on five problems, s = 2, 3, 4, at most 4.3x below on any step; the
// velocity's coefficients alone erred 50x high (the satellites) and 30x low
// (pendulum, s = 3). Under the adaptive step also p's error: TOLC |h| times
// that velocity, so that it stays within tol (1 + max|q|) a step (it does not
// add up over the steps; the total dp1 would keep what a large step left and
// shrink h to the floor, measured). Not finite (a singular G' M^-1 G): 0,
// NAME_err_est alone.
static void emit_mult_err(Emitter *e) {
  char c[40];
  format_real(e, c, sizeof c, MULT_ERRC);
  tmpl(e, "#ifndef $P_MULTC\n");
  out(e, "#define %s_MULTC %s  /* measured: docs/api.md */\n#endif\n", e->P, c);
  tmpl(e, "/* The constant multiplier's part of the local error in q, which $P_err_est does not\n"
          " * see: h |M^-1 (dp1 + dp0)| |p1 - p0| / (|p0| + |p1 - p0|), dp0 and dp1 the projections\n"
          " * of p0 and p1 onto the hidden constraint at q0 and q1, (q1, p1) = x + (h sw[gam], sw[dp]).\n"
          " * For $P_step_adaptive (adaptive 1) at least $P_TOLC |h| |M^-1 (dp1 + dp0)|: p's error, the\n"
          " * velocity across the hidden constraint that the step adds, within tol (1 + max|q|); it\n"
          " * alternates in sign from step to step and does not add up. */\n"
          "static $R $P_mult_err(const $P_state *x, const $W *sw, $R h, const $P_params *prm, int adaptive)\n{\n"
          "  $R q1[$P_M], p1[$P_M], pr[$<consistent>], dp0[$P_M], v[$P_M], vd = 0, dp = 0, p0 = 0, est;\n"
          "  int i;\n");
  emit_step_end_loop(e);
  tmpl(e, "    if (fabs$f(x->p[i]) > p0) p0 = fabs$f(x->p[i]);\n  }\n"
          "  $(consistent q0=x->q p0=x->p out=pr);\n"
          "  for (i = 0; i < $P_M; i++) dp0[i] = pr[$[consistent.dp]i];\n"
          "  $(consistent q0=q1 p0=p1 out=pr);\n"
          "  for (i = 0; i < $P_M; i++) dp0[i] += pr[$[consistent.dp]i];  /* dp1 + dp0 */\n"
          "  $(minv_p q0=q1 p0=dp0 out=v);\n"
          "  for (i = 0; i < $P_M; i++)\n    if (fabs$f(v[i]) > vd) vd = fabs$f(v[i]);\n"
          "  est = dp > 0 ? $P_MULTC * fabs$f(h) * vd * (dp / (p0 + dp)) : 0;\n"
          "  if (adaptive && $P_TOLC * fabs$f(h) * vd > est) est = $P_TOLC * fabs$f(h) * vd;\n"
          "  return isfinite(est) ? est : 0;\n}\n\n");
}

// NAME_defect: the quadrature's part of a step's local error, which
// NAME_err_est does not see. The step's energy defect |H(q1, p1) - H(q0, p0)|
// beyond round-off (64 ulps of |K| + |U|), as the displacement across the
// energy surface it takes, over the force |p1 - p0| / h; (q1, p1) from the
// converged sweep, before the commit (no copy of the state: a step over the
// tolerance with it is rejected as NAME_step_within rejects any, unwritten).
// Also the defect relative to |K| + |U| (at q0, p0) into *rel (if not NULL),
// for the stats.
static void emit_defect(Emitter *e) {
  tmpl(e, "/* The quadrature's part of the local error (the $P_K nodes do not integrate H exactly\n"
          " * for this model), which $P_err_est does not see: the energy defect of the step from\n"
          " * x to x + (h sw[gam], sw[dp]) beyond round-off, over the force |p1 - p0| / h; *rel (if\n"
          " * not NULL) the defect over |K| + |U| (the stats' defect). */\n"
          "static $R $P_defect(const $P_state *x, const $W *sw, $R h, const $P_params *prm, $R *rel)\n{\n"
          "  $R q1[$P_M], p1[$P_M], z[$P_M], H0, U0, H1, dH, sc, dp = 0;\n  int i;\n");
  emit_step_end_loop(e);
  tmpl(e, "    z[i] = 0;\n  }\n"
          "  $(energy_kernel q0=x->q p0=x->p out=&H0);\n"
          "  $(energy_kernel q0=x->q p0=z out=&U0);\n"
          "  $(energy_kernel q0=q1 p0=p1 out=&H1);\n"
          "  sc = fabs$f(H0 - U0) + fabs$f(U0);  /* |K| + |U| */\n"
          "  if (rel) *rel = sc > 0 ? fabs$f(H1 - H0) / sc : fabs$f(H1 - H0);\n"
          "  dH = fabs$f(H1 - H0) - $P_NOISETOL * sc;\n"
          "  return dH > 0 && dp > 0 ? dH * fabs$f(h) / dp : 0;\n}\n\n");
}

// The functions NAME_step_within calls for its error, printed before it:
// NAME_err_est, then NAME_defect, NAME_TOLC, NAME_itol (and NAME_converged),
// NAME_mult_err where the solver has them (emit_choice.c).
void emit_estimators(Emitter *e) {
  emit_err_est(e);
  if (energy_defect_wanted(e)) emit_defect(e);
  emit_tolc(e);
  if (step_end_restores_energy(e) && emit_has_sweeps(e)) emit_contraction(e);
  if (itol_wanted(e)) emit_itol(e);
  emit_settled(e); /* emit_iterate.c */
  if (mult_err_wanted(e)) emit_mult_err(e);
}

// The error the controller aims at, over the tolerance: the step from
// (rho / err)^(1/p). The estimate scatters from step to step (Kepler (11,6):
// 3-20x at about the same h, and up to 40x from one step to the next on the
// way to the perihelion), so the higher p, the smaller the aim that keeps
// such a jump under the tolerance: with the standard 0.9^p (0.28 at p = 12,
// 0.43 at p = 8, 0.53 at p = 6) 4-25% of the tries were rejected (Kepler,
// the double pendulum, the four-bar, the solar system); with 0.3 at p = 4, 6,
// 0.05 at p = 8 and 0.02 above, 0-10%, at the same work for the same error
// (the error falls as the steps grow, as h^p: docs/api.md, "Adaptive
// steps"). The constant multiplier's p = 3 keeps 0.9^3: its error, p's, is
// bounded per step and does not scatter so.
static double control_rho(const Emitter *e) {
  int p = controller_order(e);
  return p <= 3 ? pow(0.9, p) : p <= 6 ? 0.3 : p <= 8 ? 0.05 : 0.02;
}

// Print "      DST = err^(1/p);" for the controller's order p: a chain of
// square and cube roots when p = 2^a 3^b (every order of s = 1, 2, 3, 4, 6,
// 8, 9, 12, ...), cheaper than pow, and on a microcontroller by far (sqrtf is
// one instruction of a Cortex-M4F, powf a library call of a thousand cycles).
void emit_root(Emitter *e, const char *dst, const char *err) {
  int p = controller_order(e), a = 0, b = 0;
  const char *f = math_suffix(e, 0);
  while (p % 2 == 0) p /= 2, a++;
  while (p % 3 == 0) p /= 3, b++;
  if (p != 1) {
    out(e, "%s = pow%s(%s, (%s)1 / %d);\n", dst, f, err, real_type(e, 0), controller_order(e));
    return;
  }
  out(e, "%s = ", dst);
  for (int i = 0; i < b; i++) out(e, "cbrt%s(", f);
  for (int i = 0; i < a; i++) out(e, "sqrt%s(", f);
  out(e, "%s", err);
  for (int i = 0; i < a + b; i++) out(e, ")");
  out(e, ";  /* err^(1/%d) */\n", controller_order(e));
}

// The aim after a rejected try is AIM_CUT times what it was, and AIM_STEPS
// accepted steps restore it (at most to rho): the controller learns how far
// the estimate scatters. Measured (issue 31, item 3, docs/api.md "Adaptive
// steps"): 0.25 and 40 keep the rejected tries under 5% on every run of more
// than 40 tries of bench/adaptive/rejections.sh; 0.5, or 20 steps, left the
// double pendulum in angles at 6-9%.
#define AIM_CUT 0.25
#define AIM_STEPS 40

// The aim's factors in the controller's units, err^(1/p): "  LV *= c;" after
// a rejected try (aim_cut) or "  LV *= c; if (LV > 1) LV = 1;" after an
// accepted step (aim_restore), each line indented by IND.
void emit_aim_cut(Emitter *e, const char *ind, const char *lv) {
  char c[40];
  format_real(e, c, sizeof c, pow(AIM_CUT, 1.0 / controller_order(e)));
  out(e, "%s%s *= %s;  /* the aim times %g: a rejected try */\n", ind, lv, c, AIM_CUT);
}

void emit_aim_restore(Emitter *e, const char *ind, const char *lv) {
  char c[40];
  format_real(e, c, sizeof c, pow(1 / AIM_CUT, 1.0 / (AIM_STEPS * controller_order(e))));
  out(e, "%s%s *= %s;  /* %d accepted steps restore the aim */\n%sif (%s > 1) %s = 1;\n", ind, lv, c, AIM_STEPS, ind, lv,
      lv);
}

// The controller's factor for the next step, fac, from err, the error over
// its tolerance, r = err^(1/p), rq = r_{n-1}, the last step's (0: none), pq,
// Gustafsson's prediction (h_n / h_{n-1}) r_{n-1} (0: none), and ra <= 1, the
// aim's factor (NAME_step_adaptive, NAME_batch_step_adaptive): the standard
// step (rho ra^p / err)^(1/p) times the smaller of 1 and a prediction where
// the error grew (Hairer & Wanner IV.8):
// - Gustafsson's (1994, as in RADAU5), (h_n / h_{n-1}) (err_{n-1} / err_n)^(1/p)
//   = pq / r, which follows a trend in the step size;
// - once a try was rejected (ra < 1), where h grew (at most 2x), the error's
//   own trend, smaller, (err_{n-1} / err_n)^(1/p) = rq / r: that the error
//   grows again as it just did, whatever h did. On the way to Kepler's
//   perihelion the error per unit step at the same h grows 10-200x in one
//   step; a step that grew 1.3x and saw its error grow 15x (h^12 would be
//   28x) looked to Gustafsson's rule like an error falling at fixed h, and
//   the next try was rejected, once an orbit.
// The aim, ra^p rho, falls AIM_CUT-fold after each rejected try and climbs
// back over AIM_STEPS accepted steps, so that it settles where the
// estimate's own scatter rejects about one try in AIM_STEPS. The scatter is
// the model's: Kepler's error jumps 10-200x a step near the perihelion, and
// the double pendulum in angles' energy defect (k = s) 10-1000x between
// steps of the same h, a projection of the error onto grad H that changes
// sign; a fixed aim low enough for those (30x lower) cost 1.2-1.5x the work
// at equal error at p = 6, and the trend read on every step (2026-11-28,
// issue 31) cost the satellites and the pendulum 1.04 and 1.01-1.03: a step
// that grew 2x with its error 2^p was cut back, and its error read as a
// trend. Within [0.2, grow]; NaN (an estimate that is not a number) gives 0.2.
void emit_step_factor(Emitter *e) {
  char c[40];
  format_real(e, c, sizeof c, pow(control_rho(e), 1.0 / controller_order(e)));
  out(e, "      ");
  emit_root(e, "r", "err");
  out(e, "      fac = (err > 0 ? %s / r : grow) * ra;  /* (%.3g aim / err)^(1/%d), ra = aim^(1/%d) */\n", c,
      control_rho(e), controller_order(e), controller_order(e));
  tmpl(e, "      /* the error's trend, where smaller than Gustafsson's prediction: h grew, at most 2x,\n"
          "       * and a try was rejected (the aim is lowered) */\n"
          "      if (ra < 1 && rq < pq && pq <= 2 * rq) pq = rq;\n"
          "      if (pq > 0 && pq < r) fac *= pq / r;  /* the prediction, where smaller than the standard */\n"
          "      if (fac > grow) fac = grow;\n      if (!(fac >= ($R)0.2)) fac = ($R)0.2;  /* a NaN estimate too */\n");
}

// Where the estimate adds the energy defect beyond round-off (emit_defect),
// a defect still under it (NAME_stats.defect, relative, below NAME_NOISETOL)
// is 0 to the controller, which then grows h until the defect crosses the
// round-off and appears at once at up to 5x the tolerance (the double
// pendulum in angles at s = 3, tol 3e-9 .. 1e-10: a try in four rejected).
// Once the defect is a tenth of the round-off, h grows at most to where it
// would reach it, the defect growing as h^(2k+1): 24% -> 13% rejected there.
static void emit_defect_cap(Emitter *e) {
  if (!energy_defect_wanted(e)) return;
  tmpl(e, "      if (rc == $P_OK && s.defect >= ($R)0.1 * $P_NOISETOL && s.defect < $P_NOISETOL) {\n"
          "        /* the energy defect hidden in round-off: grow to where it would appear, at most */\n");
  out(e, "        %s cap = pow%s(%s_NOISETOL / s.defect, (%s)1 / %d);\n", real_type(e, 0), math_suffix(e, 0), e->P,
      real_type(e, 0), 2 * e->me->k + 1);
  tmpl(e, "        if (fac > cap) fac = cap;\n      }\n");
}

// The estimate's asymptotic range (emit_err_est): NAME_err_est is
// ERRC |h v| r^2 with r = d1 / |h v| while r < 1, and d1 itself from r = 1
// on, 1 / ERRC times more (36000x at s = 6). r grows about as h^(s+1) (h^s
// of the predictor's error, and its extrapolation over a longer step), so a
// step grown 1.8x from r = 0.035 (the solar system at (11,6), steps of 1000
// days) crossed r = 1, and its estimate jumped 4e4-fold where the controller's
// h^12 expected 1000x: all the rejected tries of the solar system at tol
// 1e-4 .. 1e-5 (3 of 34, 3 of 34, 2 of 32; bench/adaptive/rejections.sh).
// So h grows at most to where r would reach RANGE_MAX: r scatters 10x
// between steps of the same h there (the planets take turns in the max
// norm), and 0.25 still let 2 of 30 tries through (measured). r is read off
// the accepted step's estimate and v (NAME_speed's, as NAME_err_est's),
// r <= sqrt(err_est / (C |h v|)) (the estimate's other parts only raise it), C = NAME_ERRC, or
// NAME_COLDC after the first step, whose estimate is the cold one (~ C |h v|
// rho^2s as well); never a cut (at least 1), and not where the estimate is
// NAME_mult_err's (order 3, bounded a step). Where the tolerance keeps r
// below it nothing changes: at tol <= 1e-7 every run of rejections.sh takes
// the same steps; above, the solar system's runs end up to 13x closer to the
// true solution, at 0.84-0.97 of the tries at equal error, the others' at
// 1.00 (bench/results/rejections_equal_error.txt; solar (16,2) at 1e-4: 65
// tries instead of 43, error 0.17 AU instead of 1.8).
#define RANGE_MAX 0.1

static void emit_range_cap(Emitter *e) {
  char c[40], k[80];
  const char *f = math_suffix(e, 0);
  if (mult_err_wanted(e)) return;
  format_real(e, c, sizeof c, RANGE_MAX);
  if (e->me->s >= 2)
    snprintf(k, sizeof k, "(grow > 2 ? %s_COLDC : %s_ERRC)", e->P, e->P);
  else
    snprintf(k, sizeof k, "%s_ERRC", e->P);
  tmpl(e, "      if (rc == $P_OK && fac > 1) {\n"
          "        /* the estimate's asymptotic range: r = d1 / |h v|, from this step's estimate (its cold\n");
  out(e, "         * model after the first step, grow > 2), at most %g after the next (r ~ h^%d) */\n", RANGE_MAX,
      e->me->s + 1);
  tmpl(e, "        $R v, rr, cap;\n");
  emit_speed_max(e, "        ", "v", "x->gam", "cast");
  out(e, "        v *= %s * fabs%s(hh);\n", k, f);
  tmpl(e, "        if (v > 0 && s.err_est > 0) {\n");
  out(e, "          rr = sqrt%s(s.err_est / v);  /* r of this step, at most */\n", f);
  out(e, "          cap = pow%s(%s / rr, (%s)1 / %d);\n", f, c, real_type(e, 0), e->me->s + 1);
  tmpl(e, "          if (cap < 1) cap = 1;\n"
          "          if (fac > cap) fac = cap;\n        }\n      }\n");
}

// NAME_step_controlled: NAME_step_adaptive under absolute and relative
// tolerances and a largest step (NAME_controls; the driver's --atol, --rtol,
// --hmax): the tol (atol + rtol max|q|) / (1 + max|q|) at the step's start,
// so that the test tol (1 + max|q|) is atol + rtol max|q| there; *h clamped
// to hmax before the step and after it. A bad control (NULL, not finite,
// negative, atol and rtol both 0) is NAME_EBADSTEP, x unchanged.
static void emit_step_controlled(Emitter *e) {
  tmpl(e, "\nint $P_step_controlled($P_state *x, $P_real *h, const $P_controls *c, const $P_params *prm,\n"
          "                       $P_stats *st)\n{\n"
          "  $R sc = 0;\n  int i, rc;\n"
          "  if (!c || !(c->atol >= 0 && c->rtol >= 0 && c->hmax >= 0 && c->atol + c->rtol > 0) ||\n"
          "      !isfinite(c->atol + c->rtol + c->hmax))\n    return $P_EBADSTEP;\n"
          "  for (i = 0; i < $P_M; i++)\n    if (fabs$f(x->q[i]) > sc) sc = fabs$f(x->q[i]);\n"
          "  if (c->hmax > 0 && fabs$f(*h) > c->hmax) *h = *h < 0 ? -c->hmax : c->hmax;\n"
          "  rc = $P_step_adaptive(x, h, ($P_real)((c->atol + c->rtol * sc) / (1 + sc)), prm, st);\n"
          "  if (c->hmax > 0 && fabs$f(*h) > c->hmax) *h = *h < 0 ? -c->hmax : c->hmax;\n"
          "  return rc;\n}\n");
}

// NAME_step_adaptive: NAME_step with its error estimate tested before the
// commit: accepted within tol |h| (1 + max|q|) (error per unit step, absolute
// and relative at once, so that the errors of the steps up to T add up to
// about tol T, whatever their number), else retried from the unchanged state
// with a smaller step. The next step from the standard controller of
// Hairer, Norsett and Wanner (I.II.4) for an error of order h^p per unit
// step: h (rho / err)^(1/p) (control_rho) within [h/5, 2h], not growing
// right after a rejection (5h let a step outgrow the estimate's asymptotic
// range, and the next was rejected); err over tol |h| (1 + max|q|) whether
// accepted or not (without 1 + max|q| a rejected try of the solar system,
// |q| ~ 30, shrank 2.4x too much, and a quarter of the tries cycled through
// a rejection, issue 31, item 3); after the first step (hprev 0: from the caller's guess) within
// [h/5, 100h], as CVODE lets its first step grow 1e4x: the ramp from a small
// guess took three steps of the satellites' 9 to 33 (2026-11-26,
// bench/README.md). A failed step is retried with half the step. After three
// tries over the tolerance the tries start cold (no warm start): the warm
// start carries the previous step's error into the estimate at every h.
void emit_step_adaptive(Emitter *e) {
  tmpl(e, "\nint $P_step($P_state *x, $P_real h, const $P_params *prm, $P_stats *st)\n{\n"
          "  return $P_step_within(x, h, 0, 0, prm, st);\n}\n");
  out(e, "\n#ifndef %s_HMIN\n#define %s_HMIN %s  /* smallest adaptive step, relative to 1 + |t| */\n#endif\n",
      e->P, e->P, e->single ? "1e-5f" : "1e-12");
  out(e, "#ifndef %s_MAXTRIES\n#define %s_MAXTRIES 100  /* tries of one adaptive step, at most */\n#endif\n\n", e->P, e->P);
  if (controller_order(e) == step_order(e))
    out(e, "/* The exponent of the controller: the step's order %d (error per unit step). */\n", step_order(e));
  else
    out(e, "/* The exponent of the controller: %d, the order of the estimate in q per unit step\n"
           " * (%s_mult_err: q is of order 4, p of order %d across the hidden constraint). */\n",
        controller_order(e), e->P, step_order(e));
  tmpl(e, "int $P_step_adaptive($P_state *x, $P_real *h, $P_real tol, const $P_params *prm, $P_stats *st)\n{\n"
          "  $P_stats s;\n  $R hh = *h, err, sc, fac, r, pq, rq, ra, grow = x->hprev == 0 ? 100 : 2;  /* the first step: from a guess */\n"
          "  int rc, rejected = 0, misses = 0, i;\n"
          "  if (!(hh != 0 && isfinite(hh))) return $P_EBADSTEP;\n"
          "  if (!(tol > 0 && isfinite(tol))) return $P_EBADSTEP;\n"
          "  /* a non-finite t never reaches the floor $P_HMIN (1 + |t|): refused, with the state */\n"
          "  if (!isfinite(x->t)) return $P_ENONFINITE;\n"
          "  for (i = 0; i < $P_M; i++)\n"
          "    if (!(isfinite(x->q[i]) && isfinite(x->p[i]))) return $P_ENONFINITE;\n"
          "  /* the aim (emit_step_factor), written back only with an accepted step */\n"
          "  ra = x->aim > 0 && x->aim <= 1 ? x->aim : 1;  /* 1: a state not from $P_init */\n"
          "  tol *= $P_TOLC;\n"
          "  for (;;) {\n    s.iters = 0;\n    s.increment = s.err_est = 0;\n"
          "    /* after 3 tries over the tolerance the warm start is dropped: it carries the\n"
          "     * previous step's error, which no smaller h removes from the estimate */\n"
          "    rc = $P_step_within(x, hh, tol * fabs$f(hh), misses >= 3, prm, &s);\n"
          "    if (rc == $P_EREJECT) misses++;\n"
          "    if (rc == $P_OK || rc == $P_EREJECT) {\n"
          "      /* the step's error over its tolerance tol |h| (1 + max|q|): q1 when accepted, q0 when\n"
          "       * not, as the test in $P_step_within */\n"
          "      sc = 0;\n"
          "      for (i = 0; i < $P_M; i++)\n        if (fabs$f(x->q[i]) > sc) sc = fabs$f(x->q[i]);\n"
          "      err = s.err_est / (tol * fabs$f(hh) * (1 + sc));\n"
          "      /* after two steps: the last one's err^(1/p), and that times hprev (this one) over hprev2 */\n"
          "      rq = rc == $P_OK && x->hprev2 != 0 ? x->errprev : 0;\n"
          "      pq = rq * (x->hprev2 != 0 ? x->hprev / x->hprev2 : 0);\n");
  emit_step_factor(e);
  emit_defect_cap(e);
  emit_range_cap(e);
  tmpl(e, "      if (rc == $P_OK) {\n        *h = hh * fac;\n        x->errprev = r;\n");
  emit_aim_restore(e, "        ", "ra");
  tmpl(e, "        x->aim = ra;\n");
  tmpl(e, ""
          "        if (st) {\n          st->iters = s.iters;\n          st->increment = s.increment;\n"
          "          st->err_est = s.err_est;\n          st->h = hh;\n          st->rejected = rejected;\n"
          "          st->defect = s.defect;\n");
  if (emit_is_newton(e))
    tmpl(e, "          st->newton = s.newton;\n          st->factors = s.factors;\n          st->jacobians = s.jacobians;\n");
  tmpl(e, "        }\n"
          "        return $P_OK;\n      }\n"
          "      /* over the tolerance: a lower aim, but not for the first step's tries from a guess */\n"
          "      if (x->hprev != 0) {\n");
  emit_aim_cut(e, "        ", "ra");
  tmpl(e, "      }\n    } else {\n      fac = ($R)0.5;\n    }\n"
          "    rejected++;\n    grow = 1;\n    hh *= fac;\n"
          "    if (fabs$f(hh) < $P_HMIN * (1 + fabs$f(x->t)) || rejected >= $P_MAXTRIES) {\n"
          "      if (st) {\n        st->iters = s.iters;\n        st->increment = s.increment;\n"
          "        st->err_est = s.err_est;\n        st->h = 0;\n        st->rejected = rejected;\n"
          "        st->defect = s.defect;\n");
  if (emit_is_newton(e))
    tmpl(e, "        st->newton = s.newton;\n        st->factors = s.factors;\n        st->jacobians = s.jacobians;\n");
  tmpl(e, "      }\n"
          "      return rc != $P_EREJECT ? rc : $P_ETOL;\n    }\n  }\n}\n");
  emit_step_controlled(e);
}
