/* emit.h - what the emitter's files share, one section per file.
 *
 * emit_kernel.c prints kernels: straight-line C from the DAG, addressing
 * inputs and results through the blocks of the Step. The other emit_*.c
 * print everything around them, naming the kernels' inputs and results
 * only through those blocks. Layers, each calling only those below it:
 *   emit_solver.c (entry points: emit_check, emit_solver)
 *   emit_step.c, emit_project.c, emit_batch.c
 *   emit_api.c, emit_iterate.c, emit_newton.c, emit_end.c, emit_batch_step.c,
 *   emit_batch_by_lane.c
 *   emit_estimate.c, emit_predict.c, emit_mq.c, emit_batch_mq.c
 *   emit_choice.c
 *   emit_kernel.c
 * (emit_main.c, the driver, stands apart.) */
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
  const struct Roll *roll; /* non-NULL: the rolled form (roll.h, emit_rolled.c) */
  int roll_helpers; /* its helpers are printed */
} Emitter;

/* emit_kernel.c: printing, and the kernels */
void out(Emitter *e, const char *fmt, ...);
const char *real_type(const Emitter *e, int wide);
const char *math_suffix(const Emitter *e, int wide);
void format_real(const Emitter *e, char *buf, size_t size, double v);
void tmpl(Emitter *e, const char *text);
void tmplf(Emitter *e, const char *fmt, ...); /* tmpl of a printf format's result */
void emit_kernel(Emitter *e, KernelId k);
/* emit_rolled_pairs.c: $P_roll_NAME(q, v, prm, out) of the rolled form's pair
 * runs (roll.h): out[0] = U (value), else out[i] = dU/dq_i. */
void emit_roll_pairs(Emitter *e, const char *name, const char *what, int value);
void kernel_signature(Emitter *e, const Kernel *k, int part);
void op_rhs(Emitter *e, const Node *n, const char *a, const char *b, char *rhs, size_t size);
void emit_tables(Emitter *e);
int kernel_inlinable(const Emitter *e, KernelId k);
int sweep_reduces(const Emitter *e);
int noise_per_coordinate(const Emitter *e); /* emit_iterate.c: the round-off test per coordinate */
void emit_settled(Emitter *e);             /* emit_iterate.c: NAME_settled, that test */
int lane_skips(const Emitter *e, const Kernel *k); /* the kernel takes skip[] after out[] */
int emit_kernel_inline(Emitter *e, KernelId k);

/* emit_rolled.c: kernel k in the rolled form (e->roll), 1; 0 when it has none */
int emit_rolled_kernel(Emitter *e, KernelId k);
const char *rolled_lit(Emitter *e, double v);  /* a literal of the method's constants */
void rolled_x_row(Emitter *e, int j, const char *name, int stride, char *buf, size_t size);
void rolled_projections(Emitter *e, int jac);   /* psi (and with jac rho) into the sweep's locals */
void rolled_gamma(Emitter *e, int results);     /* gamma from th[] in the loop over i */
/* emit_rolled_tcon.c: the coordinates cut into segments on which each
 * constraint slot t is absent or a = i + off[t] (or read from the table) */
typedef struct { int i0, i1, *off; } TconSeg;
enum { TCON_ABSENT = -0x40000000, TCON_TABLE = -0x3fffffff }; /* off[t] besides offsets */
TconSeg *rolled_tcon_segments(const struct Roll *r, int *n);
void rolled_tcon_free(TconSeg *s);
void rolled_tcon_open(Emitter *e, const TconSeg *s, int pad); /* for (i ...) { and a0.. */
const char *rolled_tcon_guard(const TconSeg *s, int t);       /* "", "if (a >= 0) " or NULL */
struct RollRun;
void rolled_run(Emitter *e, const struct RollRun *r, int os, int oo); /* one run: out[os u + oo] = item u */
void rolled_int_table(Emitter *e, const char *type, const char *name, const int *v, int n); /* static const TYPE $P_name[n] */
/* emit_rolled_newton.c: the Newton matrix's kernels as band loops */
void rolled_newton_kernel(Emitter *e, KernelId k);
/* emit_rolled_poly.c: the poly family's kernels factor, sweep, project_p1 as loops */
void rolled_poly_helpers(Emitter *e);
int rolled_poly_pair(int s, int j, int r); /* the moment R_jr's place among the s (s + 1) / 2 kept */
void rolled_poly_kernel(Emitter *e, KernelId k);
/* emit_rolled_batch.c: NAME_batch_KERNEL of a rolled kernel, the scalar one per lane */
void emit_rolled_lane_kernel(Emitter *e, KernelId k);

/* emit_choice.c: what the model, method and options choose for the step */
int step_order(const Emitter *e);
int mult_err_wanted(const Emitter *e);
int itol_wanted(const Emitter *e);
int energy_defect_wanted(const Emitter *e);
int energy_rescale_wanted(const Emitter *e);
int step_end_restores_energy(const Emitter *e);

/* emit_api.c: NAME.h, and NAME.c's prelude, kernels and public functions */
void emit_header(Emitter *e, const EmitOptions *o);
void emit_gtol_scaled(Emitter *e); /* float: NAME_gtol(q, stride), g's round-off at q */
void emit_header_end(Emitter *e);
void emit_prelude(Emitter *e, const EmitOptions *o);
void emit_kernels(Emitter *e);
void emit_set_lambda(Emitter *e);
void emit_public(Emitter *e);
void emit_events(Emitter *e);
void emit_switches(Emitter *e);

/* emit_predict.c: NAME_predict (the warm start, with NAME_add) and NAME_dense */
double same_size_coefficient(const Emitter *e, int t);
void emit_warm_extrapolation(Emitter *e, const char *to, const char *from); /* one-step warm start */
void emit_two_step_start(Emitter *e, const char *ind, const char *row);
void emit_predict(Emitter *e);
void emit_dense(Emitter *e);

/* emit_estimate.c: the error estimates, NAME_step and NAME_step_adaptive */
void emit_estimators(Emitter *e);
void emit_step_factor(Emitter *e);
void emit_aim_cut(Emitter *e, const char *ind, const char *lv);
void emit_aim_restore(Emitter *e, const char *ind, const char *lv);
void emit_root(Emitter *e, const char *dst, const char *err);
void emit_step_adaptive(Emitter *e);

/* emit_iterate.c: the step's fixed-point iteration (the block "iterate") */
void emit_fixed_point(Emitter *e);

/* emit_end.c: the end of a step by family, the commit */
void emit_end_poly(Emitter *e);
void emit_end_const(Emitter *e);

/* emit_mq.c: what the iteration adds for M(q) (the sweep's carried Theta) */
void emit_mq_predict(Emitter *e);
void emit_mq_start(Emitter *e);
void emit_mq_carry(Emitter *e);
void emit_mq_rescale(Emitter *e);
void emit_mq_near_rest(Emitter *e); /* with constraints, in emit_end_poly */
int emit_mq_near_rest_band(const Emitter *e); /* the near-rest test's band, in TOL */

/* emit_step.c: NAME_step_within as named blocks */
void emit_step(Emitter *e);

/* emit_project.c: NAME_project */
void emit_project(Emitter *e);

/* emit_newton.c: the iteration of --iteration newton (emit_iterate chooses it; the
 * stats field in emit_api.c, emit_estimate.c) */
int emit_is_newton(const Emitter *e);
void emit_newton_helpers(Emitter *e);
void emit_newton_iteration(Emitter *e);
void emit_newton_stats(Emitter *e);
int emit_is_auto(const Emitter *e);
int emit_has_sweeps(const Emitter *e); /* the fixed-point loop is emitted (not --iteration newton) */
const char *emit_iteration_name(const Emitter *e);
void emit_auto_iteration(Emitter *e);
void emit_auto_slow(Emitter *e);
void emit_newton_commit(Emitter *e);
void emit_newton_state(Emitter *e);
/* A Newton factor over this many bytes is not a local of the step but the
 * state's scratch member nfw (emit_newton.c: the rolled Newton matrix of a
 * long chain is megabytes, and the step's stack is a thread's). */
#define NEWTON_LOCAL_MAX_BYTES (256 * 1024)
double newton_factor_bytes(const Step *st, int single); /* 0 without Newton */
void emit_newton_init(Emitter *e);

/* emit_batch.c: --batch W, W trajectories stepped together in SIMD lanes */
void emit_batch_header(Emitter *e, int lanes);
void emit_batch_source(Emitter *e, int lanes);
/* emit_batch_step.c: NAME_batch_step, its lane control as masked loops */
void emit_batch_step(Emitter *e);
void emit_batch_adaptive(Emitter *e);
/* emit_batch_by_lane.c: --batch with Newton, or with M(q) and constraints: the scalar step lane by lane (the adaptive
 * step: emit_batch_adaptive's controller around its NAME_batch_within) */
int emit_batch_by_lane(const Emitter *e);
void emit_batch_by_lane_fields(Emitter *e);
void emit_batch_newton_stats(Emitter *e);
void emit_batch_newton_set_get(Emitter *e, int get);
void emit_batch_by_lane_step(Emitter *e);
/* emit_batch_mq.c: what the batch adds for M(q) (Theta in the lanes, the rescale) */
void emit_batch_mq_predict(Emitter *e);
void emit_batch_mq_increment(Emitter *e);
void emit_batch_mq_keep(Emitter *e);
void emit_batch_mq_rescale(Emitter *e);

#endif
