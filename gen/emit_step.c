/* emit_step.c - NAME_step_within, the step, as a sequence of named blocks.
 *
 * emit_step prints the step's helpers (NAME_predict and NAME_add:
 * emit_predict.c; NAME_err_est and the other estimators: emit_estimate.c),
 * then NAME_step_within, the one step that NAME_step (tol 0) and
 * NAME_step_adaptive (tol > 0) call, as five blocks, each one function:
 *
 *   head      emit_step_head: the comment, the signature (x, h_, tol, cold,
 *             prm, st) and the locals every block shares, initialised:
 *               h (the step in $R), gam[S M] ($W: gamma), sw[sweep + 1]
 *               ($W: the sweep's results), inc = HUGE_VAL, inc_old,
 *               inc_min = HUGE_VAL, scale = 0, d1 = 0, est, it, i,
 *               stall = 0, rc = NAME_ENOCONV; polynomial family: ref[S M],
 *               two; with NAME_itol: tit = NAME_TOL, attol = 0.
 *             Returns NAME_EBADSTEP for an h that is 0 or not finite.
 *   predict   emit_step_predict: gam = NAME_predict's warm start (two, ref:
 *             the two-step start and the one-step one beside it); with
 *             --wide-step also q0w, p0w, the compensated state in $W; with
 *             constraints g0 = g(q0) / h (0 where round-off).
 *   iterate   emit_iterate: solves the step's equations for gamma. Assumes
 *             the locals above as head and predict left them; may declare
 *             its own (the fixed-point loop: fa, lam, j, the fused gm*, sw*,
 *             lm*). Must leave: gam the solution and sw[] the sweep's results
 *             at it (sw[sweep.gam], [sweep.dp], [sweep.theta], and
 *             [sweep.lambda] or the polynomial multiplier's), rc NAME_OK or
 *             the failure (NAME_ENOCONV, NAME_ENONFINITE, NAME_ESINGULAR),
 *             it the iterations taken (NAME_MAXITER + 1 when it ran out), inc
 *             the last scaled increment, scale = max |q0| + |h gamma_0|, d1
 *             the predictor's error when st || tol > 0, attol with NAME_itol
 *             (it stopped above round-off). It may return early: a singular
 *             or non-finite factor, or NAME_EREJECT after the first sweep
 *             (st filled) under NAME_step_adaptive. It writes nothing to x.
 *             Today's iteration is the fixed-point sweep loop
 *             (emit_fixed_point, emit_iterate.c); a second one is another
 *             branch of emit_iterate, in a file of its own.
 *   estimate  emit_step_estimate: est from NAME_err_est (gam, d1, cold), and
 *             NAME_mult_err, NAME_defect (x, sw) where the solver has them;
 *             the stats (it, inc, est, h, the relative energy defect, which
 *             costs NAME_defect only when st is given); returns rc when not NAME_OK,
 *             NAME_EREJECT over the tolerance, NAME_ENONFINITE for a t or a
 *             Theta_j (sw[sweep.theta]) not finite.
 *   end       emit_step_end: the constant or polynomial family's end of the
 *             step (emit_end.c): from sw (and gam, q0w, p0w, attol) the new
 *             state committed to x, return NAME_OK, and the closing brace.
 *
 * Only the end writes x, so every failure leaves the state unchanged. With
 * --wide-step the iteration (gamma, the sweep's results) is in the wider
 * type, starts from the compensated state q - qc, p - pc, and the new q, p
 * and their compensations come from rounding the wide sums once. */
#include <stdio.h>

#include "emit.h"

// head: the comment and signature of NAME_step_within, its shared locals.
static void emit_step_head(Emitter *e) {
  int poly = e->st->kern[K_FACTOR].nout > 0;
  out(e, "/* One step of HBVM(%d,%d). Iterates the sweep until the increment reaches round-off\n", e->me->k, e->me->s);
  tmpl(e, itol_wanted(e) ? " * (under $P_step_adaptive, tol > 0: the threshold of $P_itol)\n"
                           " * or stops decreasing; commits to *x only on success. */\n"
                         : " * or stops decreasing; commits to *x only on success. */\n");
  tmpl(e, "static int $P_step_within($P_state *x, $P_real h_, $R tol, int cold, const $P_params *prm, $P_stats *st)\n{\n"
          "  const $R h = ($R)h_;\n"
          "  $W gam[$P_S * $P_M], sw[$<sweep> + 1];\n"
          "  $R inc = HUGE_VAL, inc_old, inc_min = HUGE_VAL, scale = 0, d1 = 0, est;\n"
          "  int it, i, stall = 0, rc = $P_ENOCONV;\n  $P_DEFAULT_PARAMS(prm)\n"
          "  if (!(h != 0 && isfinite(h))) return $P_EBADSTEP;\n");
  if (poly && emit_has_sweeps(e)) tmpl(e, "  $R ref[$P_S * $P_M], inc_old2 = HUGE_VAL, rho;\n  int two;\n");
  if (itol_wanted(e))
    tmpl(e, "  $R tit = $P_TOL;  /* where the iteration stops ($P_itol) */\n"
            "  int attol = 0;  /* it stopped there, above round-off */\n");
}

// predict: the warm start into gam (through a $R guess with --wide-step,
// which also takes the compensated state q0w, p0w), and g0 = g(q0) / h.
static void emit_step_predict(Emitter *e) {
  int wide = e->wide_step, poly = e->st->kern[K_FACTOR].nout > 0;
  if (wide) {
    tmpl(e, "  $W q0w[$P_M], p0w[$P_M];\n"
            "  {\n    $R guess[$P_S * $P_M];\n");
    tmpl(e, poly ? "    two = $P_predict(x, h, cold, prm, guess, st || tol > 0 ? ref : 0);\n"
                 : "    $P_predict(x, h, cold, prm, guess);\n");
    tmpl(e, "    for (i = 0; i < $P_S * $P_M; i++) gam[i] = guess[i];\n  }\n"
            "  /* the sweep starts from the compensated state q - qc, p - pc, in $W */\n"
            "  for (i = 0; i < $P_M; i++) {\n"
            "    q0w[i] = ($W)x->q[i] - x->qc[i];\n"
            "    p0w[i] = ($W)x->p[i] - x->pc[i];\n  }\n");
  } else if (poly && !emit_has_sweeps(e)) /* (Newton's d1 is its first correction) */
    tmpl(e, "  $P_predict(x, h, cold, prm, gam, 0);  /* (the one-step start: no sweeps) */\n");
  else if (poly && emit_is_newton(e)) /* auto: ref is where Newton starts, if it runs */
    tmpl(e, "  two = $P_predict(x, h, cold, prm, gam, ref);  /* ref: for d1, and Newton's start */\n");
  else
    tmpl(e, poly ? "  two = $P_predict(x, h, cold, prm, gam, st || tol > 0 ? ref : 0);  /* ref: for d1 */\n"
                 : "  $P_predict(x, h, cold, prm, gam);\n");
  if (!e->mod->nu) return;
  tmpl(e, "  $R g0[$P_NU];\n  $(g q0=x->q p0=x->p out=g0);\n"
          "  /* g(q0) / h in the multiplier equation makes g(q1) = 0 rather than g(q0), so g\n"
          "   * cannot drift; below $P_GTOL, g(q0) is round-off, and kicking the momenta by it\n"
          "   * (eps / h a step) would only add noise, so it is left out. */\n");
  tmpl(e, e->single ? "  {  /* (in float the threshold grows with g's round-off: $P_gtol) */\n"
                      "    $R gt = $P_gtol(x->q, 1);\n"
                      "    for (i = 0; i < $P_NU; i++) g0[i] = fabs$f(g0[i]) <= gt ? 0 : g0[i] / h;\n  }\n"
                    : "  for (i = 0; i < $P_NU; i++) g0[i] = fabs$f(g0[i]) <= $P_GTOL ? 0 : g0[i] / h;\n");
}

// iterate: the step's equations solved for gamma (the contract above). The
// one place that chooses the iteration: the fixed-point sweep loop, or
// simplified Newton (--iteration newton, emit_newton.c), or the sweeps
// switching to Newton where they are slow (--iteration auto on a stiff model).
static void emit_iterate(Emitter *e) {
  if (emit_is_auto(e)) emit_auto_iteration(e); /* emit_newton.c */
  else if (emit_is_newton(e)) emit_newton_iteration(e);
  else emit_fixed_point(e);
}

// estimate: the step's error estimate and stats, and the tests that end
// the step before anything is written.
static void emit_step_estimate(Emitter *e) {
  tmpl(e, "  est = st || tol > 0 ? $P_err_est(gam, h, d1, cold || x->hprev == 0) : 0;  /* for whom asks */\n");
  if (mult_err_wanted(e))
    tmpl(e, "  if ((tol > 0 || st) && rc == $P_OK) {  /* the multiplier's part: for $P_step_adaptive and the stats */\n"
            "    $R em = $P_mult_err(x, sw, h, prm, tol > 0);\n    if (em > est) est = em;\n  }\n");
  if (energy_defect_wanted(e))
    tmpl(e, "  $R rel = 0;  /* the step's relative energy defect, for the stats */\n"
            "  if ((tol > 0 || st) && rc == $P_OK) {  /* for $P_step_adaptive and the stats */\n"
            "    $R ed = $P_defect(x, sw, h, prm, &rel);\n    if (tol > 0) est += ed;\n  }\n");
  tmpl(e, "  if (st) {\n    st->iters = it > $P_MAXITER ? $P_MAXITER : it;\n    st->increment = inc;\n"
          "    st->err_est = est;\n    st->h = h;\n    st->rejected = 0;\n");
  tmpl(e, energy_defect_wanted(e) ? "    st->defect = rel;\n  }\n" : "    st->defect = 0;\n  }\n");
  tmpl(e, "  if (rc != $P_OK) return rc;\n"
          "  /* $P_step_adaptive: over tol (1 + max|q0| + |h gamma_0|), nothing is written */\n"
          "  if (tol > 0 && !(est <= tol * (1 + scale))) return $P_EREJECT;\n"
          "  if (!isfinite(x->t + h) || !isfinite(x->tc)) return $P_ENONFINITE;\n"
          "  for (i = 0; i < ($P_S - 1) * $P_M; i++) /* the rest of p's polynomial, for $P_dense */\n"
          "    if (!isfinite(sw[$[sweep.theta]i])) return $P_ENONFINITE;\n");
}

// end: the family's end of the step, the commit to x (emit_end.c).
static void emit_step_end(Emitter *e) {
  if (e->st->kern[K_FACTOR].nout > 0) emit_end_poly(e);
  else emit_end_const(e);
}

// The step's helpers, then NAME_step_within block by block (above).
void emit_step(Emitter *e) {
  emit_predict(e);
  if (e->mod->mass_q) emit_mq_predict(e); /* emit_mq.c */
  emit_estimators(e);
  if (emit_is_newton(e)) emit_newton_helpers(e);
  emit_step_head(e);
  emit_step_predict(e);
  emit_iterate(e);
  emit_step_estimate(e);
  emit_step_end(e);
}
