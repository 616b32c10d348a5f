/* emit_batch_by_lane.c - --batch W where the lanes take the scalar step in
 * turn: with the Newton iteration (--iteration newton, and --iteration auto
 * on a stiff model), and where M depends on q and there are constraints.
 *
 * The lanes take the scalar step, NAME_step_within, one after another: a
 * lane moves into a NAME_state of its own (NAME_batch_get into x->next[l]),
 * steps there and moves back (NAME_batch_set) when it succeeds. So each
 * lane repeats NAME_step (or one try of NAME_step_adaptive) exactly: its
 * own prediction, its own sweeps (and Newton iterations), and with Newton
 * its own decision to keep or refresh the factor, which NAME_batch keeps per
 * lane (nf, nfh, nfrate, and hnewton under auto, as NAME_state does). The
 * scalar emission is reused whole, not printed again over lanes: a Newton
 * step's cost is the factorisation and the solves, and M(q) with
 * constraints adds per-step Newton solves on g(q1) and a projection in the
 * M(q1) norm, all lane by lane (not in SIMD lanes). NAME_batch_step_adaptive
 * is the controller of emit_batch_step.c around NAME_batch_within below,
 * whose try writes no lane unless every active lane passed. */
#include "emit.h"

// Whether the batch step is the scalar step lane by lane (this file) rather
// than the step's kernels over SIMD lanes (emit_batch_step.c).
int emit_batch_by_lane(const Emitter *e) { return emit_is_newton(e) || (e->mod->mass_q && e->mod->nu); }

// NAME_batch's fields for the lanes' scalar steps: with Newton each lane's
// factor kept across steps (value i of lane l at [i * W + l], as the other
// private fields); the lanes' states of the step under way.
void emit_batch_by_lane_fields(Emitter *e) {
  if (emit_is_newton(e)) {
    tmpl(e, "  /* Newton (docs/method-newton.md): each lane's factor kept across steps, as in $P_state */\n"
            "  $R nf[($<newton_factor> + 1) * $P_W], nfh[$P_W], nfrate[$P_W];\n");
    if (emit_is_auto(e)) tmpl(e, "  $R hnewton[$P_W];\n");
  }
  tmpl(e, "  $P_state next[$P_W];  /* each lane's step under way (written to the lane when it passes) */\n");
}

// NAME_batch_stats's fields for Newton, per lane as NAME_stats's.
void emit_batch_newton_stats(Emitter *e) {
  tmpl(e, "  int newton[$P_W], factors[$P_W], jacobians[$P_W];  /* as $P_stats's, per lane */\n");
}

// The Newton fields' lines of NAME_batch_set (get 0) and NAME_batch_get
// (get 1).
void emit_batch_newton_set_get(Emitter *e, int get) {
  static const char *const scalar[] = {"nfh", "nfrate", "hnewton"};
  for (int f = 0; f < (emit_is_auto(e) ? 3 : 2); f++)
    out(e, get ? "  s->%s = x->%s[l];\n" : "  x->%s[l] = s->%s;\n", scalar[f], scalar[f]);
  tmpl(e, get ? "  for (i = 0; i <= $<newton_factor>; i++) s->nf[i] = x->nf[i * $P_W + l];\n"
              : "  for (i = 0; i <= $<newton_factor>; i++) x->nf[i * $P_W + l] = s->nf[i];\n");
}

// NAME_batch_within and NAME_batch_step, the lanes' scalar steps in turn
// (NAME_batch_step_adaptive is emit_batch_adaptive's controller around this
// NAME_batch_within).
void emit_batch_by_lane_step(Emitter *e) {
  int newton = emit_is_newton(e);
  tmpl(e, "/* Each active lane's $P_step_within in turn, on its own state x->next[l]: the lane is\n"
          " * bitwise $P_step (tol 0) or one try of $P_step_adaptive (tol > 0, cold as there)");
  tmpl(e, newton ? ", its\n * Newton factor kept or refreshed by its own contraction. tol 0: each lane that succeeds\n"
                 : ".\n * tol 0: each lane that succeeds\n");
  tmpl(e, ""
          " * is written, the others are left as they were; returns the number that failed.\n"
          " * tol > 0: the lanes are written only when every active lane succeeded within tol,\n"
          " * else -2 (a lane failed) or -1 (a lane over tol) with no lane written. */\n"
          "static int $P_batch_within($P_batch *x, $R h, $R tol, int cold, const $P_params *prm, $P_batch_stats *st)\n{\n"
          "  $P_stats ls;\n  int l, rc, nfail = 0, over = 0;\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    rc = $P_OK;\n"
          "    ls.iters = ");
  tmpl(e, newton ? "ls.newton = ls.factors = ls.jacobians = 0;\n" : "0;\n");
  tmpl(e, "    ls.increment = ls.err_est = 0;\n"
          "    if (!x->idle[l] && !(nfail && tol > 0)) {  /* (a try with a failed lane is over) */\n"
          "      $P_batch_get(x, l, &x->next[l]);\n"
          "      rc = $P_step_within(&x->next[l], h, tol, cold, prm ? prm + l : 0, st ? &ls : 0);\n"
          "      if (rc == $P_OK && tol == 0) $P_batch_set(x, l, &x->next[l]);\n"
          "      over |= rc == $P_EREJECT;\n"
          "      nfail += rc != $P_OK && rc != $P_EREJECT;\n    }\n"
          "    if (st) {\n"
          "      st->code[l] = rc;\n      st->iters[l] = ls.iters;\n      st->increment[l] = ls.increment;\n"
          "      st->err_est[l] = tol > 0 ? ls.err_est : 0;\n");
  if (newton) tmpl(e, "      st->newton[l] = ls.newton;\n      st->factors[l] = ls.factors;\n      st->jacobians[l] = ls.jacobians;\n");
  tmpl(e, "    }\n  }\n"
          "  if (tol > 0 && (nfail || over)) {\n    if (st) st->h = 0;\n    return nfail ? -2 : -1;\n  }\n"
          "  if (tol > 0)  /* every active lane passed: all written */\n"
          "    for (l = 0; l < $P_W; l++)\n      if (!x->idle[l]) $P_batch_set(x, l, &x->next[l]);\n"
          "  if (st) {\n    st->h = h;\n    st->rejected = 0;\n  }\n"
          "  return nfail;\n}\n\n"
          "int $P_batch_step($P_batch *x, $P_real h, const $P_params *prm, $P_batch_stats *st)\n{\n"
          "  return $P_batch_within(x, h, 0, 0, prm, st);\n}\n\n");
}
