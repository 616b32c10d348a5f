/* emit_iterate.c - the step's fixed-point iteration.
 *
 * emit_fixed_point prints, inside NAME_step_within, the iteration block
 * (see emit_step.c for what it may assume and must leave): for the
 * polynomial family the multiplier matrix factored at the predicted gamma
 * (emit_factor), then the loop of at most NAME_MAXITER sweeps. Each sweep
 * computes the sweep kernel at the current gamma (a call, or with e->fused
 * its body inline on scalar locals gm0.., sw0.., lm0..: emit_fused_*),
 * the scaled increment, after the first sweep the predictor's error d1
 * and the early rejection under NAME_step_adaptive (emit_first_sweep),
 * the finiteness and pivot checks of its results, and the test for
 * convergence or a stall (emit_convergence). The polynomial family
 * refactors when the increments fall slowly. The fused locals are written
 * back to gam[] and sw[] at the end, for the rest of the step. */
#include <stdio.h>
#include <string.h>

#include "emit.h"

// Factor the polynomial family's multiplier matrix at the current gamma
// into fa[], returning from the step when a pivot is not finite or is
// negligible (the system is singular). indent: the code's indentation.
static void emit_factor(Emitter *e, const char *indent) {
  char text[1024];
  snprintf(text, sizeof text,
           "%s$(factor q0=%s gam=gam h=h out=fa);\n"
           "%sfor (j = 0; j < $P_S * $P_NU; j++) {\n"
           "%s  $W piv = fa[$[factor.pivot]j], dia = fa[$[factor.adiag]j];\n"
           "%s  if (!isfinite(piv) || !isfinite(dia)) return $P_ENONFINITE;\n"
           "%s  if (!(fabs$g(piv) > $P_SINGTOL * fabs$g(dia))) return $P_ESINGULAR;\n"
           "%s}\n",
           indent, e->wide_step ? "q0w" : "x->q", indent, indent, indent, indent, indent);
  tmpl(e, text);
}

// Whether the iteration's round-off test is per coordinate: in the family
// whose end of step does not restore H (no multiplier factor, no rescale),
// without constraints. There increments that fall by less than 4x are
// round-off noise only if each coordinate's largest increment dm is within
// 2 ulps (NAME_TOL) of its own size over the step, |q0| + |h| sum_j
// |gamma_j|, or far below an ulp of the largest (NAME_TOL / 256), where the
// global test took them as noise within 2 ulps of the largest coordinate:
// that left a small stiff one 2000 of its own ulps off (the FPU chain at
// omega = 1000, x1 = 1e-3), and H drifted, 1.7e-3 in float and 3.1e-13 in
// double at h omega = 1 (docs/api.md, "Cost per step and the iteration
// limits"). With the size |q0| + |h gamma_0| alone, a coordinate at a
// turning point mid-step looked small, and the two oscillators of
// tests/check_stress.c failed at h omega = 2.8. Not with constraints: the
// multiplier's force puts the round-off of the large coordinates into every
// one, and the conical pendulum and the satellites then reached NAME_MAXITER
// at the h where they had converged. dm replaces the one running maximum of
// the increments (their largest is the same), and the sizes are summed only
// where the increments fall by less than 4x, so a sweep costs what it did.
int noise_per_coordinate(const Emitter *e) {
  return !step_end_restores_energy(e) && e->mod->nu == 0;
}

// NAME_settled, before the step (noise_per_coordinate's test).
void emit_settled(Emitter *e) {
  if (!noise_per_coordinate(e) || !emit_has_sweeps(e)) return;
  tmpl(e, "/* Whether the sweep's increments are round-off coordinate by coordinate: each one's\n"
          " * largest, dm[i], within 2 ulps ($P_TOL) of its size over the step, |q0| + |h| sum_j\n"
          " * |gamma_j| (gam: the sweep's), or far below an ulp of the state's scale (gen/emit_iterate.c,\n"
          " * noise_per_coordinate: 2 ulps of the largest coordinate left a small stiff one unconverged) */\n"
          "static int $P_settled(const $P_state *x, const $W *gam, const $R *dm, $R h, $R scale)\n{\n"
          "  int i, j;\n  for (i = 0; i < $P_M; i++) {\n"
          "    $R o = fabs$f(x->q[i]) + fabs$g(h * gam[i]);\n"
          "    for (j = 1; j < $P_S; j++) o += fabs$g(h * gam[j * $P_M + i]);\n"
          "    if (!(dm[i] <= $P_TOL * o || dm[i] <= $P_TOL / 256 * scale)) return 0;\n"
          "  }\n  return 1;\n}\n\n");
}

// Where result block name of the sweep starts in its out[].
static int sweep_at(const Emitter *e, const char *name) {
  return step_block(e->st, K_SWEEP, name)->first;
}

// "if (!isfinite(sw0) || ... || !isfinite(sw{n-1})) rc = CODE;", the finiteness
// test of the fused step's first n results.
static void emit_all_finite(Emitter *e, int n) {
  out(e, "    if (");
  for (int i = 0; i < n; i++) out(e, "%s!isfinite(sw%d)", i ? (i % 6 ? " || " : " ||\n        ") : "", i);
  tmpl(e, ") rc = $P_ENONFINITE;\n");
}

// After the first sweep: d1, the predictor's error (the increment; after the
// two-step start, the one-step start's miss, which the estimate is built on),
// and the error estimate, with which NAME_step_adaptive rejects a step the
// first sweep already puts over its tolerance rather than after the
// iteration has converged. gamma (gm0, ... in the fused step) is the sweep's.
// Not on a cold try (no warm start): one sweep from the cold predictor leaves
// the highest coefficients far from their converged values, and the early
// test rejected chain8's first step from rest (s = 3, tol 1e-12) down to the
// floor; there the converged estimate decides.
static void emit_first_sweep(Emitter *e) {
  tmpl(e, "    if (it == 1 && (st || tol > 0)) {  /* for $P_err_est: only when someone reads it */\n"
          "      d1 = inc;  /* the predictor's error */\n");
  if (e->fused)
    for (int i = 0; i < e->me->s * e->mod->m; i++) out(e, "      gam[%d] = gm%d;\n", i, i);
  if (e->st->kern[K_FACTOR].nout)
    tmpl(e, "      if (two)  /* the two-step start: the one-step start's miss */\n"
            "        for (d1 = 0, i = 0; i < $P_S * $P_M; i++) {\n"
            "          $R v = fabs$g(h * (gam[i] - ref[i]));\n"
            "          if (v > d1) d1 = v;\n        }\n");
  tmpl(e, "      if (tol > 0 && !(cold || x->hprev == 0)) {  /* $P_step_adaptive's, warm tries only */\n"
          "        est = $P_err_est(gam, h, d1, 0);\n"
          "        if (!(est <= tol * (1 + scale))) {\n"
          "          if (st) {\n            st->iters = 1;\n            st->increment = inc;\n"
          "            st->err_est = est;\n            st->h = h;\n            st->rejected = 0;\n"
          "            st->defect = 0;\n          }\n"
          "          return $P_EREJECT;\n        }\n      }\n    }\n");
}

// The fused step's locals: gamma as gm0, gm1, ... (from the predicted
// gam[]), the sweep's results as sw0, sw1, ... and, for the polynomial
// family, the multiplier's coefficients as lm0, lm1, ...
static void emit_fused_locals(Emitter *e) {
  int sm = e->me->s * e->mod->m, n = kernel_size(&e->st->kern[K_SWEEP]);
  out(e, "  /* the iteration's values in locals: gamma, the sweep's results%s */\n",
      e->st->kern[K_FACTOR].nout ? ", the multiplier" : "");
  for (int i = 0; i < sm; i++) out(e, "%s%s gm%d = gam[%d]", i ? "," : "  ", i ? "" : real_type(e, 0), i, i);
  out(e, ";\n");
  for (int i = 0; i < n; i++) out(e, "%s%s%s sw%d = 0", i ? "," : "  ", i ? "" : real_type(e, 0), i && i % 8 == 0 ? "\n   " : "", i);
  out(e, ";\n");
  if (e->st->kern[K_FACTOR].nout) {
    for (int i = 0; i < e->me->s * e->mod->nu; i++) out(e, "%s%s lm%d = 0", i ? "," : "  ", i ? "" : real_type(e, 0), i);
    out(e, ";\n");
  }
}

// The fused step's sweep and increment: the sweep kernel's body inline,
// reading gamma (and lambda) from locals and leaving its results in locals,
// then the increment unrolled: the same operations in the same order as
// the loops over sw[] and gam[] of the plain step, so the same bits.
static void emit_fused_sweep(Emitter *e) {
  int m = e->mod->m, sm = e->me->s * m, g = sweep_at(e, "gam");
  e->arg[IN_Q0] = "x->q";
  e->arg[IN_P0] = "x->p";
  e->arg[IN_GAM] = "gm";
  e->arg[IN_LAM] = "lm";
  e->arg[IN_LU] = "fa";
  e->local = 1u << IN_GAM | 1u << IN_LAM;
  e->res = "sw";
  emit_kernel_inline(e, K_SWEEP);
  memset(e->arg, 0, sizeof e->arg);
  e->local = 0;
  e->res = NULL;
  tmpl(e, "    /* increment: max |h (gamma_new - gamma)| over max |q| + |h gamma_0| */\n"
          "    inc_old = inc;\n    inc = 0;\n    scale = 0;\n    {\n      $R v;\n");
  int own = noise_per_coordinate(e);
  for (int i = 0; i < m; i++)
    tmplf(e, "      v = fabs$f(x->q[%d]) + fabs$g(h * sw%d);\n      if (v > scale) scale = v;\n", i, g + i);
  for (int i = 0; i < sm; i++) { /* own: dm0.. each coordinate's largest, the first of it taken as it is */
    if (own && i < m) tmplf(e, "      dm%d = fabs$g(h * (sw%d - gm%d));\n", i, g + i, i);
    else if (own) tmplf(e, "      v = fabs$g(h * (sw%d - gm%d));\n      if (v > dm%d) dm%d = v;\n", g + i, i, i % m, i % m);
    else tmplf(e, "      v = fabs$g(h * (sw%d - gm%d));\n      if (v > inc) inc = v;\n", g + i, i);
    out(e, "      gm%d = sw%d;\n", i, g + i);
  }
  for (int i = 0; own && i < m; i++) out(e, "      if (dm%d > inc) inc = dm%d;\n", i, i);
  out(e, "    }\n");
  emit_first_sweep(e);
  out(e, "    if (scale > 0) inc /= scale;\n");
}

// The plain step's sweep (a call), increment and the checks of its results.
static void emit_sweep_checks(Emitter *e) {
  int wide = e->wide_step, poly = e->st->kern[K_FACTOR].nout > 0;
  char call[128];
  snprintf(call, sizeof call, "    $(sweep q0=%s p0=%s gam=gam h=h%s%s%s out=sw);\n", wide ? "q0w" : "x->q",
           wide ? "p0w" : "x->p", e->mod->nu ? " g0=g0" : "", poly ? " lam=lam lu=fa" : "",
           e->mod->mass_q ? " pth=pth" : "");
  tmpl(e, call);
  tmpl(e, "    /* increment: max |h (gamma_new - gamma)| over max |q| + |h gamma_0| */\n"
          "    inc_old = inc;\n    inc = 0;\n    scale = 0;\n"
          "    for (i = 0; i < $P_M; i++) {\n"
          "      $R v = fabs$f(x->q[i]) + fabs$g(h * sw[$[sweep.gam]i]);\n"
          "      if (v > scale) scale = v;\n    }\n");
  if (noise_per_coordinate(e)) /* each coordinate's largest increment, dm (noise_per_coordinate) */
    tmpl(e, "    for (i = 0; i < $P_M; i++) {\n"
            "      dm[i] = fabs$g(h * (sw[$[sweep.gam]i] - gam[i]));\n"
            "      gam[i] = sw[$[sweep.gam]i];\n    }\n"
            "    for (i = $P_M; i < $P_S * $P_M; i += $P_M) {\n"
            "      int c;\n"
            "      for (c = 0; c < $P_M; c++) {\n"
            "        $R v = fabs$g(h * (sw[$[sweep.gam]i + c] - gam[i + c]));\n"
            "        if (v > dm[c]) dm[c] = v;\n"
            "        gam[i + c] = sw[$[sweep.gam]i + c];\n      }\n    }\n"
            "    for (i = 0; i < $P_M; i++)\n      if (dm[i] > inc) inc = dm[i];\n");
  else
    tmpl(e, "    for (i = 0; i < $P_S * $P_M; i++) {\n"
            "      $R v = fabs$g(h * (sw[$[sweep.gam]i] - gam[i]));\n"
            "      if (v > inc) inc = v;\n"
            "      gam[i] = sw[$[sweep.gam]i];\n    }\n");
  emit_first_sweep(e);
  tmpl(e, "    if (scale > 0) inc /= scale;\n");
  if (e->mod->mass_q) emit_mq_carry(e); /* emit_mq.c */
  if (poly)
    tmpl(e, "    for (i = 0; i < $P_S * $P_NU; i++) lam[i] = sw[$[sweep.lam]i];\n"
            "    for (i = 0; i < $<sweep.theta>; i++)\n      if (!isfinite(sw[i])) rc = $P_ENONFINITE;\n");
  else if (e->mod->nu) /* before the finiteness test: a zero pivot makes lambda 0/0 */
    tmpl(e, "    for (i = 0; i < $P_NU; i++) {\n"
            "      $R piv = sw[$[sweep.pivot]i], dia = sw[$[sweep.adiag]i];\n"
            "      if (isfinite(piv) && isfinite(dia) && !(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) rc = $P_ESINGULAR;\n"

            "    }\n"
            "    if (rc == $P_ESINGULAR) break;\n");
  if (!poly) tmpl(e, "    for (i = 0; i < $<sweep.pivot>; i++)\n      if (!isfinite(sw[i])) rc = $P_ENONFINITE;\n");
}

// The same for the fused step: the sweep inline, then its checks on the
// locals, in the plain step's order.
static void emit_fused_checks(Emitter *e) {
  int poly = e->st->kern[K_FACTOR].nout > 0, nu = e->mod->nu;
  emit_fused_sweep(e);
  if (poly) {
    for (int i = 0; i < e->me->s * nu; i++) out(e, "    lm%d = sw%d;\n", i, sweep_at(e, "lam") + i);
    emit_all_finite(e, sweep_at(e, "theta"));
    return;
  }
  if (nu) {
    for (int i = 0; i < nu; i++)
      tmplf(e, "    {\n      $R piv = sw%d, dia = sw%d;\n"
               "      if (isfinite(piv) && isfinite(dia) && !(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) rc = $P_ESINGULAR;\n"
               "    }\n", sweep_at(e, "pivot") + i, sweep_at(e, "adiag") + i);
    tmpl(e, "    if (rc == $P_ESINGULAR) break;\n");
  }
  emit_all_finite(e, sweep_at(e, "pivot"));
}

// The end of an iteration: failure, convergence or a stall.
static void emit_convergence(Emitter *e) {
  int poly = step_end_restores_energy(e); /* (the constant family with the rescale, too) */
  tmpl(e, "    if (rc == $P_ENONFINITE || !isfinite(inc)) { rc = $P_ENONFINITE; break; }\n");
  if (poly) { /* the end of the step restores H and the hidden constraint */
    tmpl(e, "    /* converged: the increment is within 2 ulps of the state ($P_TOL), or the error it\n"
            "     * leaves in gamma is: rho inc / (1 - rho), rho = inc / inc_old the contraction (the\n"
            "     * standard test, Hairer & Wanner IV.8), which saves the sweep that would only\n"
            "     * confirm it. Iterating further would not help H, which the rescale keeps.");
    if (itol_wanted(e))
      tmpl(e, " Under\n"
              "     * $P_step_adaptive the error allowed is the step's tolerance's share ($P_itol):\n"
              "     * the end of the step restores H, g and the hidden constraint. */\n"
              "    if (tol > 0 && it == 1) tit = $P_itol(tol, scale);  /* once a step, at the first sweep's scale */\n"
              "    rho = $P_contraction(inc, inc_old, inc_old2, it);\n"
              "    if ($P_converged(inc, rho, tit)) {\n"
              "      attol = !$P_converged(inc, rho, $P_TOL);\n");
    else
      tmpl(e, " */\n    rho = $P_contraction(inc, inc_old, inc_old2, it);\n"
              "    if (inc <= $P_TOL || (rho < 1 && inc * rho <= $P_TOL * (1 - rho))) {\n");
    tmpl(e, "      rc = $P_OK;\n      break;\n    }\n"
            "    inc_old2 = inc_old;  /* the sweep overwrites inc_old: the increment before it */\n");
  } else if (!noise_per_coordinate(e)) {
    tmpl(e, "    /* converged: the increment is far below an ulp of the state ($P_TOL / 256), or\n"
            "     * within 2 ulps ($P_TOL) and falling by less than 4x (round-off noise). Iterating\n"
            "     * this far, rather than stopping at 2 ulps, makes |H - H0| grow like a\n"
            "     * random walk over millions of steps (bench/results/longrun.txt). */\n"
            "    if (inc <= $P_TOL / 256 || (inc <= $P_TOL && 4 * inc > inc_old)) { rc = $P_OK; break; }\n");
  } else {
    tmpl(e, "    /* converged: the increment is far below an ulp of the state ($P_TOL / 256), or it\n"
            "     * falls by less than 4x and is round-off coordinate by coordinate ($P_settled: within\n"
            "     * 2 ulps of the coordinate's own size over the step, or far below an ulp of the\n"
            "     * state). Iterating this far, rather than stopping at 2 ulps, makes |H - H0|\n"
            "     * grow like a random walk over millions of steps (bench/results/longrun.txt). */\n"
            "    if (inc <= $P_TOL / 256) { rc = $P_OK; break; }\n"
            "    if (4 * inc > inc_old) {\n");
    for (int i = 0; e->fused && i < e->me->s * e->mod->m; i++) out(e, "      gam[%d] = gm%d;\n", i, i);
    for (int i = 0; e->fused && i < e->mod->m; i++) out(e, "      dm[%d] = dm%d;\n", i, i);
    tmpl(e, "      if ($P_settled(x, gam, dm, h, scale)) { rc = $P_OK; break; }\n    }\n");
  }
  tmpl(e, "    /* otherwise progress is a new smallest increment: those of a converging sweep\n"
          "     * need not fall every time (X_s has complex eigenvalues), so a rise alone is\n"
          "     * no failure. $P_STALL sweeps without one are a stall: converged if it is at\n"
          "     * round-off ($P_NOISETOL), else a failure: never a step that has not converged. */\n"
          "    if (inc < inc_min) {\n      inc_min = inc;\n      stall = 0;\n    } else if (++stall >= $P_STALL) {\n"
          "      rc = inc_min <= $P_NOISETOL ? $P_OK : $P_ENOCONV;\n      break;\n    }\n");
  if (emit_is_auto(e)) emit_auto_slow(e); /* emit_newton.c */
  out(e, "  }\n");
}

// The fixed-point iteration of the step: gamma swept until the increment
// reaches round-off (or NAME_itol's threshold) or stalls, leaving gam[] and
// sw[] at the last sweep and rc set (emit_step.c, "iterate").
void emit_fixed_point(Emitter *e) {
  int poly = e->st->kern[K_FACTOR].nout > 0;
  if (poly) {
    tmpl(e, e->fused ? "  $W fa[$<factor> + 1];\n" : "  $W fa[$<factor> + 1], lam[$P_S * $P_NU];\n");
    tmpl(e, e->fused ? "  int j;\n" : "  int j;\n  for (i = 0; i < $P_S * $P_NU; i++) lam[i] = 0;\n");
    tmpl(e, ""
            "  /* the multiplier matrix at the predicted stages, factored once for all sweeps\n"
            "   * (again below when the iteration slows down) */\n");
    emit_factor(e, "  ");
  }
  if (e->fused) emit_fused_locals(e);
  if (noise_per_coordinate(e)) tmpl(e, "  $R dm[$P_M];  /* each coordinate's largest increment in the sweep */\n");
  for (int i = 0; noise_per_coordinate(e) && e->fused && i < e->mod->m; i++)
    out(e, "%s%s dm%d = 0%s", i ? ", " : "  ", i ? "" : real_type(e, 0), i,
        i == e->mod->m - 1 ? ";  /* (dm in locals, for the fused sweeps) */\n" : "");
  if (e->mod->mass_q) emit_mq_start(e); /* emit_mq.c */
  else if (energy_rescale_wanted(e) && !poly) tmpl(e, "  $R inc_old2 = HUGE_VAL, rho;  /* the contraction test ($P_contraction) */\n");
  tmpl(e, "  for (it = 1; it <= $P_MAXITER; it++) {\n");
  if (poly) {
    tmpl(e, "    /* the frozen factor converges as fast as a fresh one every sweep while h is\n"
            "     * small; where the increments fall by less than 8x it is refreshed at the\n"
            "     * current gamma, which keeps the iteration converging up to the h of the\n"
            "     * constant family (pendulum, s = 3: 2.4 instead of 0.84) */\n"
            "    if (it > 2 && inc > inc_old / 8) {\n");
    for (int i = 0; e->fused && i < e->me->s * e->mod->m; i++) out(e, "      gam[%d] = gm%d;\n", i, i);
    emit_factor(e, "      ");
    tmpl(e, "    }\n");
  }
  if (e->fused) emit_fused_checks(e);
  else emit_sweep_checks(e);
  emit_convergence(e);
  if (e->fused) { /* the rest of the step reads the arrays */
    for (int i = 0; i < e->me->s * e->mod->m; i++) out(e, "  gam[%d] = gm%d;\n", i, i);
    for (int i = 0; i < kernel_size(&e->st->kern[K_SWEEP]); i++) out(e, "  sw[%d] = sw%d;\n", i, i);
  }
}
