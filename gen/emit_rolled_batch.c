/* emit_rolled_batch.c - --batch W on the rolled form: its lane kernels.
 *
 * The batch step (emit_batch.c, emit_batch_step.c) calls its kernels as
 * NAME_batch_KERNEL over struct-of-arrays (value i of lane l at [i * W + l],
 * the params at prm[k * W + l]) and runs the scalar step's control around
 * them lane by lane. For a kernel the rolled form prints as loops over the
 * coordinates (emit_rolled.c, emit_rolled_poly.c), NAME_batch_KERNEL runs
 * the scalar rolled kernel once a lane: the lane's inputs gathered into
 * arrays of their own, its params into a NAME_params, the results scattered
 * back. Each lane so does exactly the operations of the scalar kernel that
 * NAME_step calls, in its order, and the batch step's lanes stay bitwise
 * NAME_step (docs/api.md, "Batches"). The lanes are not vectorised across:
 * the rolled kernels' loops run over the coordinates (docs/rolled.md). So
 * the sweep does not repeat the last sweep of a lane that has stopped
 * iterating while others go on, as the straight-line lanes do for free in
 * SIMD: the batch step passes skip[] (those lanes) and keeps their results
 * in its buffers (emit_batch_step.c), and the sweep copies them over. */
#include "emit.h"

// Whether input slot i of the kernels is an argument of their signature.
static int in_signature(const Step *st, int i) { return st->in[i].len || i < IN_LAM; }

// NAME_batch_KERNEL of the rolled kernel id: per lane, the params and the
// inputs the caller passed (not 0) gathered, the scalar NAME_KERNEL called,
// its results scattered into out[i * W + l]. The gathered copies are
// locals: one lane's inputs and results beside the scalar kernel's own.
void emit_rolled_lane_kernel(Emitter *e, KernelId id) {
  const Step *st = e->st;
  const Kernel *k = &st->kern[id];
  const Model *mod = e->mod;
  out(e, "\n/* %s (rolled): the scalar kernel $P_%s in each lane */\n", k->what, k->name);
  kernel_signature(e, k, -1);
  tmplf(e, "  $P_params pl;\n  $R res[%d];\n  int i, l;\n", kernel_size(k) > 0 ? kernel_size(k) : 1);
  for (int i = 0; i < IN_COUNT; i++)
    if (in_signature(st, i) && !st->in[i].scalar)
      tmplf(e, "  $R l_%s[%d];  /* the lane's %s */\n", st->in[i].name, st->in[i].len > 0 ? st->in[i].len : 1, st->in[i].name);
  tmpl(e, "  for (l = 0; l < $P_W; l++) {\n");
  if (lane_skips(e, k)) /* the batch step swaps its two buffers: gam is the last sweep's results */
    tmplf(e, "    if (skip[l]) {  /* the lane stopped iterating: its last sweep's results again */\n"
             "      for (i = 0; i < %d; i++) out[i * $P_W + l] = gam[i * $P_W + l];\n"
             "      continue;\n    }\n", kernel_size(k));
  for (int p = 0; p < mod->nparams; p++) out(e, "    pl.%s = prm[%d * %s_W + l];\n", mod->params[p].name, p, e->P);
  if (!mod->nparams) out(e, "    pl.unused_ = 0;\n");
  for (int i = 0; i < IN_COUNT; i++) /* an input the caller passes as 0 the kernel does not read */
    if (in_signature(st, i) && !st->in[i].scalar && st->in[i].len)
      tmplf(e, "    if (%s)\n      for (i = 0; i < %d; i++) l_%s[i] = %s[i * $P_W + l];\n", st->in[i].name, st->in[i].len,
            st->in[i].name, st->in[i].name);
  tmplf(e, "    $P_%s(", k->name);
  for (int i = 0; i < IN_COUNT; i++)
    if (in_signature(st, i) && st->in[i].scalar) out(e, "%s, ", st->in[i].name);
    else if (in_signature(st, i)) out(e, "%s ? l_%s : 0, ", st->in[i].name, st->in[i].name);
  tmplf(e, "&pl, res);\n"
           "    for (i = 0; i < %d; i++) out[i * $P_W + l] = res[i];\n  }\n}\n", kernel_size(k));
}
