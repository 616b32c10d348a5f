/* emit_solver.c - the emitter's entry points: emit_check and emit_solver.
 *
 * emit_check tests, before anything is written, that every constant the
 * solver will hold is a finite value of its real type. emit_solver prints
 * NAME.h and NAME.c in order: the header (emit_api.c, with the batch's
 * declarations from emit_batch.c), the prelude and kernels, the public
 * functions, the step (emit_step.c), NAME_step and NAME_step_adaptive
 * (emit_estimate.c), NAME_project (emit_project.c), NAME_dense
 * (emit_predict.c), and the batch's functions (emit_batch.c). It is the only
 * file that calls both the scalar and the batch emitters. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "emit.h"
#include "roll.h"

// Check one constant the solver will print: finite, and in range of float
// for --real float (where below FLT_MIN it becomes 0 or a denormal: a
// warning). Returns 1 after an error.
static int check_constant(const EmitOptions *o, double v, Loc loc, const char *what, int *small) {
  if (!isfinite(v) || (o->single && fabs(v) > FLT_MAX)) {
    error_at(loc, "%s %.17g is not a finite %s", what, v, o->single ? "float (beyond FLT_MAX)" : "double");
    return 1;
  }
  if (o->single && v != 0 && fabs(v) < FLT_MIN && (*small)++ == 0)
    warning_at(loc, "%s %.9g is below FLT_MIN: in float it loses precision or becomes 0", what, v);
  return 0;
}

// Before anything is written: every constant the generated code will hold
// (the kernels' literals, the rolled form's loop bodies, the parameters'
// defaults, q0 and p0) must be a
// finite value of the solver's real type. Returns 0, or 1 after errors.
int emit_check(const Model *mod, const Step *st, const EmitOptions *o) {
  const Dag *d = mod->dag;
  unsigned char *mark = xcalloc((size_t)d->n + 1, 1);
  int bad = 0, small = 0;
  for (int k = 0; k < K_COUNT; k++)
    for (int b = 0; b < st->kern[k].nout; b++) dag_reach(d, st->kern[k].out[b].nodes, st->kern[k].out[b].len, mark);
  for (int l = 0; l < d->nloops; l++) dag_reach(d, d->loops[l].roots, d->loops[l].nroots, mark); /* their bodies */
  if (o->roll) roll_reach(o->roll, d, mark); /* the rolled kernels' loop bodies */
  for (int id = 0; id < d->n && !bad; id++)
    if (mark[id] && d->nodes[id].op == OP_CONST) bad = check_constant(o, d->nodes[id].val, (Loc){0, 0}, "a constant of the step", &small);
  for (int i = 0; i < mod->nparams && !bad; i++)
    bad = check_constant(o, mod->params[i].value, mod->params[i].loc, "the parameter's value", &small);
  for (int i = 0; i < mod->m && !bad; i++)
    bad = check_constant(o, mod->q0[i], mod->q0_loc, "q0", &small) || check_constant(o, mod->p0[i], mod->p0_loc, "p0", &small);
  free(mark);
  double nfb = newton_factor_bytes(st, o->single);
  if (!bad && o->batch && nfb > NEWTON_LOCAL_MAX_BYTES) { /* each lane's scalar state is a local of the batch step */
    fprintf(stderr, "hbvmgen: error: --batch with Newton: the Newton matrix's factor is %.1f MB, and each lane steps "
                    "a copy of the scalar state on the stack (at most %d KB of factor): leave out --batch, or pass "
                    "--iteration fixed\n", nfb / 1e6, NEWTON_LOCAL_MAX_BYTES / 1024);
    bad = 1;
  }
  return bad;
}

// Write NAME.h to hf and NAME.c to cf. Returns 0, or -1 on a write error.
int emit_solver(FILE *hf, FILE *cf, const Model *mod, const Method *me, const Step *st, const EmitOptions *o) {
  Emitter e = {.f = hf, .mod = mod, .me = me, .st = st, .P = o->name, .single = o->single,
               .compensated = o->compensated, .wide_step = o->wide_step, .kid = K_SWEEP, .roll = o->roll};
  e.fused = !o->wide_step && !emit_is_newton(&e) && !mod->mass_q && kernel_inlinable(&e, K_SWEEP);
  e.temp = xmalloc((size_t)mod->dag->n * sizeof(int));
  emit_header(&e, o);
  if (o->batch) emit_batch_header(&e, o->batch);
  emit_header_end(&e);
  e.f = cf;
  emit_prelude(&e, o);
  emit_kernels(&e);
  emit_public(&e);
  emit_events(&e);
  emit_switches(&e);
  emit_step(&e);
  emit_step_adaptive(&e);
  emit_project(&e);
  emit_dense(&e);
  if (o->batch) emit_batch_source(&e, o->batch);
  free(e.temp);
  return ferror(hf) || ferror(cf) ? -1 : 0;
}
