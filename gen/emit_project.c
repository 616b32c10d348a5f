/* emit_project.c - NAME_project: the state moved onto the constraints.
 *
 * Newton's iteration of the kernel "consistent" on a copy of q until its
 * correction is at round-off, then p projected onto the hidden constraint
 * at that q and the multiplier recomputed (emit_set_lambda, emit_api.c);
 * the step's history is cleared, as after NAME_init. Without constraints
 * it only reports no change. */
#include "emit.h"

// NAME_project: the Newton iteration of the kernel "consistent" on a copy of
// q until its correction is at round-off, then p projected at that q; the
// state is written only on success.
void emit_project(Emitter *e) {
  tmpl(e, "\n/* Newton's iteration onto g(q) = 0 until the correction is within 2 ulps of q\n"
          " * ($P_TOL) or stops decreasing at round-off, at most $P_MAXITER times; then p\n"
          " * projected onto the hidden constraint at that q. x is written only on success. */\n"
          "int $P_project($P_state *x, const $P_params *prm, $P_real *dq, $P_real *dp)\n{\n");
  if (!e->mod->nu) {
    tmpl(e, "  (void)x;\n  (void)prm;\n  if (dq) *dq = 0;\n  if (dp) *dp = 0;\n  return $P_OK;\n}\n");
    return;
  }
  tmpl(e, "  $R q[$P_M], p[$P_M], out[$<consistent>], inc = HUGE_VAL, inc_old, scale, dqmax = 0, dpmax = 0;\n"
          "  int it, i, rc = $P_ENOCONV;\n  $P_DEFAULT_PARAMS(prm)\n"
          "  for (i = 0; i < $P_M; i++) {\n    q[i] = x->q[i];\n    p[i] = x->p[i];\n  }\n"
          "  for (it = 1; it <= $P_MAXITER; it++) {\n"
          "    $(consistent q0=q p0=p out=out);\n"
          "    for (i = 0; i < $P_NU; i++) {\n"
          "      $R piv = out[$[consistent.pivot]i], dia = out[$[consistent.adiag]i];\n"
          "      if (isfinite(piv) && isfinite(dia) && !(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) rc = $P_ESINGULAR;\n"
          "    }\n"
          "    if (rc == $P_ESINGULAR) break;\n"
          "    for (i = 0; i < $<consistent>; i++)\n      if (!isfinite(out[i])) rc = $P_ENONFINITE;\n"
          "    if (rc == $P_ENONFINITE) break;\n"
          "    inc_old = inc;\n    inc = 0;\n    scale = 0;\n"
          "    for (i = 0; i < $P_M; i++) {\n"
          "      if (fabs$f(q[i]) > scale) scale = fabs$f(q[i]);\n"
          "      if (fabs$f(out[$[consistent.dq]i]) > inc) inc = fabs$f(out[$[consistent.dq]i]);\n    }\n"
          "    if (scale > 0) inc /= scale;\n"
          "    /* at round-off the last correction is left out, so that dp below is at q */\n"
          "    if (inc <= $P_TOL) { rc = $P_OK; break; }\n"
          "    if (it > 1 && inc >= inc_old) { rc = inc <= 16 * $P_TOL ? $P_OK : $P_ENOCONV; break; }\n"
          "    for (i = 0; i < $P_M; i++) q[i] += out[$[consistent.dq]i];\n  }\n"
          "  if (rc != $P_OK) return rc;\n"
          "  for (i = 0; i < $P_M; i++) {\n"
          "    p[i] += out[$[consistent.dp]i];\n"
          "    if (!isfinite(p[i])) return $P_ENONFINITE;\n"
          "    if (fabs$f(q[i] - x->q[i]) > dqmax) dqmax = fabs$f(q[i] - x->q[i]);\n"
          "    if (fabs$f(p[i] - x->p[i]) > dpmax) dpmax = fabs$f(p[i] - x->p[i]);\n  }\n"
          "  for (i = 0; i < $P_M; i++) {\n"
          "    x->q[i] = q[i];\n    x->p[i] = p[i];\n    x->qc[i] = x->pc[i] = 0;\n  }\n"
          "  for (i = 0; i < $P_S * $P_M; i++) x->gam[i] = x->pinc[i] = 0;\n"
          "  x->hprev = 0;  /* the next step starts afresh, as after init */\n");
  if (e->st->kern[K_FACTOR].nout) tmpl(e, "  x->H0 = 0;\n  for (i = 0; i < $P_M; i++) x->pcorr[i] = 0;\n");
  emit_set_lambda(e);
  tmpl(e, "  if (dq) *dq = dqmax;\n  if (dp) *dp = dpmax;\n  return $P_OK;\n}\n");
}
