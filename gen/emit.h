/* emit.h - what the two halves of the emitter share.
 *
 * emit_kernel.c prints kernels: straight-line C from the DAG, addressing
 * inputs and results through the blocks of the Step. emit_step.c prints
 * everything around them (header, constants, the public functions and the
 * step's predict / iterate / commit templates), naming the kernels' inputs
 * and results only through those blocks. */
#ifndef EMIT_H
#define EMIT_H

#include "hbvmgen.h"

typedef struct {
  FILE *f;
  const Model *mod;
  const Method *me;
  const Step *st;
  const char *P;   /* prefix */
  int *temp;       /* temporary number per node, -1 if none */
  int single;      /* float instead of double */
  int compensated; /* Kahan summation of the q, p, t updates */
  int *chunk;      /* kernel split in parts: part of each node (NULL: one part) */
  int *slot;       /* its place in the array w[] passing values between parts, or -1 */
  int part;        /* the part being printed */
  int wide_step;   /* --wide-step: the step iterates one precision wider */
  int wide;        /* the kernel being printed computes one precision wider */
  KernelId kid;    /* the kernel being printed */
  int lanes;       /* W > 0: kernels print as loops over W lanes (--batch, emit_batch.c) */
  int *vec_part;   /* per VEC node: 1 + the part whose function declares its array, or 0 */
  int *loop_part;  /* per stage loop (DagLoop): 1 + the part that runs it, or 0 */
  int body;        /* printing the body of a stage loop: coordinates are Q[i], values bID */
  /* the fused step (emit_kernel_inline): what the kernel's inputs are called in
   * the step, and which of them are scalar locals PREFIX0, PREFIX1, ... */
  const char *arg[IN_COUNT];
  unsigned local;  /* 1 << input slot */
  const char *res; /* non-NULL: results go to locals res0, res1, ..., not out[] */
  int fused;       /* the step's iteration has the sweep inlined, gamma in locals */
} Emitter;

void out(Emitter *e, const char *fmt, ...);
const char *real_type(const Emitter *e, int wide);
const char *math_suffix(const Emitter *e, int wide);
void format_real(const Emitter *e, char *buf, size_t size, double v);
void tmpl(Emitter *e, const char *text);
void emit_kernel(Emitter *e, KernelId k);
void emit_tables(Emitter *e);
int kernel_inlinable(const Emitter *e, KernelId k);
int sweep_reduces(const Emitter *e);
int emit_kernel_inline(Emitter *e, KernelId k);

/* emit_step.c, for the batch's adaptive step too */
int energy_defect_wanted(const Emitter *e);
int mult_err_wanted(const Emitter *e);
int itol_wanted(const Emitter *e);
void emit_two_step_start(Emitter *e, const char *ind, const char *row);
void emit_step_factor(Emitter *e);

/* emit_newton.c: the iteration of --iteration newton (hooks in emit_step.c) */
int emit_is_newton(const Emitter *e);
void emit_newton_helpers(Emitter *e);
void emit_newton_iteration(Emitter *e);
void emit_newton_stats(Emitter *e);

/* emit_batch.c: --batch W, W trajectories stepped together in SIMD lanes */
void emit_batch_header(Emitter *e, int lanes);
void emit_batch_source(Emitter *e, int lanes);
/* emit_batch_step.c: NAME_batch_step, its lane control as masked loops */
void emit_batch_step(Emitter *e);

#endif
