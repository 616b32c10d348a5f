/* emit_end.c - the end of a step: from the converged sweep to the new state.
 *
 * After the iteration has converged and the estimate accepted the step
 * (emit_step.c), the step ends by family. The constant family (emit_end_const)
 * checks the new state is finite and commits it: q1 = q0 + h gamma_0 and
 * p1 = p0 + (p1 - p0) as compensated sums (or the wide sums rounded once
 * with --wide-step), lambda the step's constant multiplier; with M(q) or
 * --energy rescale p1 is then rescaled to the run's energy (emit_mq.c). The polynomial
 * family (emit_end_poly) first forms q1 and p1 aside, puts q1 back on g = 0
 * by Newton steps where the adaptive iteration stopped above round-off,
 * projects p1 onto the hidden constraint and rescales it to the run's energy
 * H0, and takes the multiplier consistent with (q1, p1). Both then commit
 * gamma (the last polynomial becomes the one before, for the two-step
 * start) and p's polynomial (for NAME_dense), advance t and return NAME_OK.
 * Nothing is written to the state before every test has passed. */
#include "emit.h"

// The commit of the step's polynomial: the last one becomes the one before
// (for the two-step warm start), gamma the last. One loop, except with
// --wide-step: gcc 12 -O2 then vectorised the qc/pc loop before it wrongly
// (qc[1] = pc[0] = 0, pendulum with --real float, check_lean); as two loops
// without --wide-step, gcc spilled the fused iteration of Kepler's k = 16
// sweep (20% more instructions a sweep).
static void emit_commit_gamma(Emitter *e) {
  if (e->wide_step)
    tmpl(e, "  for (i = 0; i < $P_S * $P_M; i++) x->gam2[i] = x->gam[i];\n"
            "  for (i = 0; i < $P_S * $P_M; i++) x->gam[i] = ($R)gam[i];\n");
  else
    tmpl(e, "  for (i = 0; i < $P_S * $P_M; i++) {\n    x->gam2[i] = x->gam[i];\n    x->gam[i] = gam[i];\n  }\n");
}

// The commit of p's polynomial over the step (pinc: p1 - p0, then the
// Theta_j) for NAME_dense, in loops of their own: in one loop with gamma's,
// GCC 12's SLP vectoriser (-O2) folded the float --wide-step commit's pc to 0
// (caught by check_lean's float_wide_step_holds_H).
static void emit_commit_pinc(Emitter *e) {
  tmpl(e, "  for (i = 0; i < $P_M; i++) x->pinc[i] = ($R)sw[$[sweep.dp]i];\n"
          "  for (i = 0; i < ($P_S - 1) * $P_M; i++) x->pinc[$P_M + i] = ($R)sw[$[sweep.theta]i];\n");
}

// The end of a step of the polynomial family: q1 and p1 as the state will
// hold them (compensated sums, or the wide sums with --wide-step), p1
// projected onto the hidden constraint at q1 and rescaled to the energy H0
// of the run, the multiplier consistent with (q1, p1), then the commit.
void emit_end_poly(Emitter *e) {
  int wide = e->wide_step;
  tmpl(e, "  $W q1[$P_M], p1[$P_M], pr[$<project_p1> + 1], K, U1, beta = 1;\n  $R H0, Hn = $P_energy(x, prm);\n");
  if (wide)
    tmpl(e, "  for (i = 0; i < $P_M; i++) {\n"
            "    q1[i] = q0w[i] + h * sw[$[sweep.gam]i];\n    p1[i] = p0w[i] + sw[$[sweep.dp]i];\n  }\n");
  else
    tmpl(e, "  $R qc1[$P_M], pc1[$P_M];\n"
            "  for (i = 0; i < $P_M; i++) {\n"
            "    q1[i] = x->q[i];\n    qc1[i] = x->qc[i];\n    p1[i] = x->p[i];\n    pc1[i] = x->pc[i];\n"
            "    $P_add(&q1[i], &qc1[i], h * sw[$[sweep.gam]i]);\n"
            "    $P_add(&p1[i], &pc1[i], sw[$[sweep.dp]i]);\n  }\n");
  if (itol_wanted(e)) {
    tmpl(e, "  /* the iteration stopped at $P_step_adaptive's tolerance ($P_itol), above round-off:\n"
            "   * while g(q1) is not round-off ($P_GTOL), q1 onto g = 0 by Newton steps ($P_NEWTON at\n"
            "   * most: one, or two from $P_ITOLMAX), and gamma_0 with it, so that $P_dense still\n"
            "   * starts the step at q0 */\n");
    /* M(q): every step, as k = s leaves g(q1) = O(h^(2s+1)) for a g that is not a
     * polynomial (the four-bar's loop closure; docs/method-mq.md) */
    tmpl(e, e->mod->mass_q ? "  {  /* M(q): every step, also where k = s leaves g(q1) above round-off */\n"
                             "    (void)attol;\n"
                           : "  if (attol) {\n");
    tmpl(e, "    $R g1[$P_NU], cs[$<consistent>];\n    int n, off;\n"
            "    for (n = 0; n < $P_NEWTON; n++) {\n"
            "      $(g q0=q1 out=g1);\n");
    tmpl(e, e->single ? "      for (off = 0, i = 0; i < $P_NU; i++) off |= !(fabs$f(g1[i]) <= $P_gtol(q1, 1));\n"
                      : "      for (off = 0, i = 0; i < $P_NU; i++) off |= !(fabs$f(g1[i]) <= $P_GTOL);\n");
    tmpl(e, "      if (!off) break;\n"
            "      $(consistent q0=q1 p0=p1 out=cs);\n"
            "      for (i = 0; i < $P_NU; i++) {\n"
            "        $R piv = cs[$[consistent.pivot]i], dia = cs[$[consistent.adiag]i];\n"
            "        if (isfinite(piv) && isfinite(dia) && !(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) return $P_ESINGULAR;\n"
            "      }\n"
            "      for (i = 0; i < $P_M; i++) {\n"
            "        $R d = cs[$[consistent.dq]i];\n"
            "        if (!isfinite(d)) return $P_ENONFINITE;\n"
            "        $P_add(&q1[i], &qc1[i], d);\n"
            "        gam[i] += d / h;\n      }\n    }\n  }\n");
  }
  tmpl(e, "  $W phat[$P_M];  /* p1 before the projection, the end of p's polynomial */\n"
          "  for (i = 0; i < $P_M; i++) phat[i] = p1[i];\n");
  /* the finiteness test stops before the multiplier's lamv and lamu, the last
   * results: a multiplier not finite is stored as 0, not a failed step */
  tmpl(e, "  /* p1 projected onto grad g(q1)' M^-1 p1 = 0: p1 + pr[dp], q1 untouched */\n"
          "  $(project_p1 q0=q1 p0=p1 out=pr);\n"
          "  for (i = 0; i < $P_NU; i++) {\n"
          "    $W piv = pr[$[project_p1.pivot]i], dia = pr[$[project_p1.adiag]i];\n"
          "    if (isfinite(piv) && isfinite(dia) && !(fabs$g(piv) > $P_SINGTOL * fabs$g(dia))) return $P_ESINGULAR;\n  }\n"
          "  for (i = 0; i < $<project_p1.lamv>; i++)\n    if (!isfinite(pr[i])) return $P_ENONFINITE;\n"
          "  /* and rescaled, p1 = beta (p1 + dp), so that H(q1, p1) = H0, the energy of the run:\n"
          "   * taken anew on the first step, or when the state or parameters were changed\n"
          "   * since the last step (H(q0, p0) differs from H0 by more than round-off). No\n"
          "   * rescale at rest (K = 0) or where H0 < U(q1). */\n"
          "  K = pr[$[project_p1.kin]0];\n  U1 = pr[$[project_p1.U]0];\n"
          "  H0 = x->hprev != 0 && fabs$f(Hn - x->H0) <= 64 * $P_TOL * (K + fabs$g(U1)) ? x->H0 : Hn;\n"
          "  if (K > 0 && H0 - U1 > 0) beta = sqrt$g((H0 - U1) / K);\n");
  if (e->mod->mass_q) emit_mq_near_rest(e); /* emit_mq.c */
  if (wide)
    tmpl(e, "  for (i = 0; i < $P_M; i++) {\n"
            "    p1[i] = beta * (p1[i] + pr[$[project_p1.dp]i]);\n"
            "    if (!isfinite(q1[i]) || !isfinite(p1[i])) return $P_ENONFINITE;\n  }\n");
  else
    tmpl(e, "  for (i = 0; i < $P_M; i++) {\n"
            "    $P_add(&p1[i], &pc1[i], pr[$[project_p1.dp]i] + (beta - 1) * (p1[i] + pr[$[project_p1.dp]i]));\n"
            "    if (!isfinite(q1[i]) || !isfinite(p1[i])) return $P_ENONFINITE;\n  }\n");
  tmpl(e, "  /* g(q1) at round-off, or the iteration stopped short of convergence: no step */\n"
          "  for (i = 0; i < $P_NU; i++)\n"
          "    if (!(fabs$g(pr[$[project_p1.g]i]) <= $P_GSTEP * pr[$[project_p1.gscale]i] + $P_GTOL)) return $P_ENOCONV;\n");
  if (wide)
    tmpl(e, "  /* q1, p1 rounded once into q, p; what the rounding lost is the new qc, pc */\n"
            "  for (i = 0; i < $P_M; i++) {\n    x->q[i] = ($R)q1[i];\n    x->p[i] = ($R)p1[i];\n");
  else
    tmpl(e, "  for (i = 0; i < $P_M; i++) {\n    x->q[i] = q1[i];\n    x->p[i] = p1[i];\n"
            "    x->qc[i] = qc1[i];\n    x->pc[i] = pc1[i];\n");
  if (wide && e->compensated) tmpl(e, "    x->qc[i] = ($R)(x->q[i] - q1[i]);\n    x->pc[i] = ($R)(x->p[i] - p1[i]);\n");
  tmpl(e, "    x->pcorr[i] = ($R)(p1[i] - phat[i]);\n  }\n");
  emit_commit_gamma(e);
  emit_commit_pinc(e);
  tmpl(e, "  x->H0 = H0;\n"
          "  /* the multiplier consistent with (q1, p1), from the projection's factors (0 where not finite) */\n"
          "  for (i = 0; i < $P_NU; i++) {\n"
          "    $W lam = beta * beta * pr[$[project_p1.lamv]i] - pr[$[project_p1.lamu]i];\n"
          "    x->lambda[i] = isfinite(lam) ? ($R)lam : 0;\n  }\n");
  emit_newton_commit(e);
  tmpl(e, "  $P_add(&x->t, &x->tc, h);\n  x->hprev2 = x->hprev;\n  x->hprev = h;\n  return $P_OK;\n}\n");
}

// The end of a step of the constant family: the new state finite, then the
// commit (compensated sums, or the wide sums rounded once with --wide-step).
void emit_end_const(Emitter *e) {
  int wide = e->wide_step;
  if (energy_rescale_wanted(e)) tmpl(e, "  $R Hn = $P_energy(x, prm);  /* H(q0, p0), for the rescale */\n");
  tmpl(e, "  for (i = 0; i < $P_M; i++) /* the new state must be finite too, compensations included */\n"
          "    if (!isfinite(x->q[i] + h * sw[$[sweep.gam]i]) || !isfinite(x->p[i] + sw[$[sweep.dp]i]) ||\n"
          "        !isfinite(x->qc[i]) || !isfinite(x->pc[i]))\n      return $P_ENONFINITE;\n");
  if (!wide)
    tmpl(e, "  for (i = 0; i < $P_M; i++) {\n"
            "    $P_add(&x->q[i], &x->qc[i], h * sw[$[sweep.gam]i]);\n"
            "    $P_add(&x->p[i], &x->pc[i], sw[$[sweep.dp]i]);\n  }\n"
            "  for (i = 0; i < $P_NU; i++) x->lambda[i] = sw[$[sweep.lambda]i];\n");
  if (energy_rescale_wanted(e)) emit_mq_rescale(e); /* emit_mq.c (never with --wide-step) */
  if (wide) {
    tmpl(e, "  /* q1 = (q - qc) + h gamma_0 and p1 = (p - pc) + (p1 - p0) in $W, rounded once into\n"
            "   * q, p; what the rounding lost is the new qc, pc */\n"
            "  for (i = 0; i < $P_M; i++) {\n"
            "    $W q1 = q0w[i] + h * sw[$[sweep.gam]i], p1 = p0w[i] + sw[$[sweep.dp]i];\n"
            "    x->q[i] = ($R)q1;\n    x->p[i] = ($R)p1;\n");
    if (e->compensated) tmpl(e, "    x->qc[i] = ($R)(x->q[i] - q1);\n    x->pc[i] = ($R)(x->p[i] - p1);\n");
    tmpl(e, "  }\n"
            "  for (i = 0; i < $P_NU; i++) x->lambda[i] = ($R)sw[$[sweep.lambda]i];\n");
  }
  emit_commit_gamma(e);
  emit_commit_pinc(e);
  emit_newton_commit(e);
  tmpl(e, "  $P_add(&x->t, &x->tc, h);\n  x->hprev2 = x->hprev;\n  x->hprev = h;\n  return $P_OK;\n}\n");
}
