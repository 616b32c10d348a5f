/* emit.c - C text of NAME.h and NAME.c.
 *
 * Every computation of the generated solver is a "kernel": a static
 * function printed from a set of DAG outputs as straight-line code, one
 * operation a line, each intermediate a named const temporary, a comment
 * where a new section of the method starts, constants with 17 significant
 * digits. All kernels share one signature (q0, p0, gamma, h, g0, params ->
 * out[]) so that the input slots of the DAG map to the same C names
 * everywhere. Around the kernels the iteration, warm start, compensated
 * update and failure handling of the step are printed as ordinary C. */
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

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
} Emitter;

/* A kernel with more operations than this is printed as several functions
 * of straight-line code (values crossing parts pass through an array):
 * compilers take time superlinear in a function's size. */
#define PART_NODES 2000

static void out(Emitter *e, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vfprintf(e->f, fmt, ap);
  va_end(ap);
}

// The name of a real type of the generated code, and the suffix of its
// math functions (sqrt, sqrtf, sqrtl): the solver's real type, or with wide
// the next wider one (--wide-step: long double for double, double for float).
static const char *real_type(const Emitter *e, int wide) {
  if (wide) return e->single ? "double" : "long double";
  return e->single ? "float" : "double";
}

static const char *math_suffix(const Emitter *e, int wide) {
  if (wide) return e->single ? "" : "l";
  return e->single ? "f" : "";
}

// Print text, replacing $P by the prefix, $R by the real type name, $f by
// the suffix of its math functions, $W by the type the step iterates in (the
// real type, or the next wider one with --wide-step) and $g by the suffix of
// that type's math functions.
static void tmpl(Emitter *e, const char *text) {
  for (const char *p = text; *p; p++) {
    if (*p == '$' && p[1] == 'P') fputs(e->P, e->f);
    else if (*p == '$' && p[1] == 'R') fputs(real_type(e, 0), e->f);
    else if (*p == '$' && p[1] == 'f') fputs(math_suffix(e, 0), e->f);
    else if (*p == '$' && p[1] == 'W') fputs(real_type(e, e->wide_step), e->f);
    else if (*p == '$' && p[1] == 'g') fputs(math_suffix(e, e->wide_step), e->f);
    else {
      fputc(*p, e->f);
      continue;
    }
    p++;
  }
}

// A literal that reads back exactly in the real type and is a C floating
// constant: 17 significant digits for double, 9 and an f suffix for float.
static void format_real(const Emitter *e, char *buf, size_t size, double v) {
  char tmp[40];
  int single = e->single && !e->wide; /* a wide kernel of a float solver computes in double */
  snprintf(tmp, sizeof tmp, single ? "%.9g" : "%.17g", single ? (double)(float)v : v);
  if (!strpbrk(tmp, ".eEn")) strcat(tmp, ".0");
  if (single) strcat(tmp, "f");
  snprintf(buf, size, v < 0 ? "(%s)" : "%s", tmp);
}

// The C expression that names node id inside a kernel: a literal, a
// parameter, an input or a temporary.
static void name_of(Emitter *e, int id, char *buf, size_t size) {
  const Node *n = &e->mod->dag->nodes[id];
  const Step *st = e->st;
  switch ((Op)n->op) {
  case OP_CONST: format_real(e, buf, size, n->val); return;
  case OP_PARAM: snprintf(buf, size, "prm->%s", e->mod->params[n->idx].name); return;
  case OP_INPUT:
    if (n->idx >= st->in_g0) snprintf(buf, size, "g0[%d]", n->idx - st->in_g0);
    else if (n->idx == st->in_h) snprintf(buf, size, "h");
    else if (n->idx >= st->in_gam) snprintf(buf, size, "gam[%d]", n->idx - st->in_gam);
    else if (n->idx >= st->in_p0) snprintf(buf, size, "p0[%d]", n->idx - st->in_p0);
    else if (n->idx >= st->in_q0) snprintf(buf, size, "q0[%d]", n->idx - st->in_q0);
    else internal_error("model coordinate %d reached a kernel", n->idx);
    return;
  default:
    if (e->chunk && e->chunk[id] != e->part) snprintf(buf, size, "w[%d]", e->slot[id]);
    else snprintf(buf, size, "t%d", e->temp[id]);
    return;
  }
}

// name_of, with the leaves (constants, params, inputs) of a wide kernel cast
// to the wider type, so that no operation is done in the narrower one.
static void ref(Emitter *e, int id, char *buf, size_t size) {
  const Node *n = &e->mod->dag->nodes[id];
  if (!(e->wide && (n->op == OP_CONST || n->op == OP_PARAM || n->op == OP_INPUT))) {
    name_of(e, id, buf, size);
    return;
  }
  char leaf[96];
  name_of(e, id, leaf, sizeof leaf);
  snprintf(buf, size, "(%s)%s", real_type(e, 1), leaf);
}

// x^n for a small integer n as products, so no pow() call is needed.
static int power_expr(char *buf, size_t size, const char *x, double n) {
  static const char *const forms[] = {NULL, "%s", "%s * %s", "%s * %s * %s", "(%s * %s) * (%s * %s)",
                                      "(%s * %s) * (%s * %s) * %s", "(%s * %s * %s) * (%s * %s * %s)"};
  if (n != floor(n) || fabs(n) < 2 || fabs(n) > 6) return 0; /* (int) of 1e40 would be undefined */
  int k = (int)fabs(n);
  char prod[512];
  snprintf(prod, sizeof prod, forms[k], x, x, x, x, x, x);
  if (n < 0) snprintf(buf, size, "1 / (%s)", prod);
  else snprintf(buf, size, "%s", prod);
  return 1;
}

// One line computing node id into its temporary.
static void emit_node(Emitter *e, int id) {
  const Node *n = &e->mod->dag->nodes[id];
  char a[128], b[128], rhs[640];
  ref(e, n->a, a, sizeof a);
  if (n->b >= 0) ref(e, n->b, b, sizeof b);
  switch ((Op)n->op) {
  case OP_ADD: snprintf(rhs, sizeof rhs, "%s + %s", a, b); break;
  case OP_SUB: snprintf(rhs, sizeof rhs, "%s - %s", a, b); break;
  case OP_MUL: snprintf(rhs, sizeof rhs, "%s * %s", a, b); break;
  case OP_DIV: snprintf(rhs, sizeof rhs, "%s / %s", a, b); break;
  case OP_NEG: snprintf(rhs, sizeof rhs, "-%s", a); break;
  case OP_SIGN: snprintf(rhs, sizeof rhs, "(%s > 0) - (%s < 0)", a, a); break;
  case OP_POW: {
    const Node *ex = &e->mod->dag->nodes[n->b];
    if (ex->op == OP_CONST && power_expr(rhs, sizeof rhs, a, ex->val)) break;
    snprintf(rhs, sizeof rhs, "pow%s(%s, %s)", math_suffix(e, e->wide), a, b);
    break;
  }
  default:
    if (n->b >= 0) snprintf(rhs, sizeof rhs, "%s%s(%s, %s)", op_cfun((Op)n->op), math_suffix(e, e->wide), a, b);
    else snprintf(rhs, sizeof rhs, "%s%s(%s)", op_cfun((Op)n->op), math_suffix(e, e->wide), a);
  }
  out(e, "  const %s t%d = %s;\n", real_type(e, e->wide), e->temp[id], rhs);
}

static void kernel_signature(Emitter *e, const char *name, int part) {
  tmpl(e, "static void $P_");
  out(e, part >= 0 ? "%s_part%d" : "%s", name, part);
  const char *t = real_type(e, e->wide); /* the sweep of --wide-step: state, gamma, results wider */
  out(e, "(const %s *q0, const %s *p0, const %s *gam, ", t, t, t);
  tmpl(e, "$R h,\n    const $R *g0, const $P_params *prm, ");
  if (part >= 0) out(e, "%s *w, ", t);
  out(e, "%s *out)\n{\n", t);
  out(e, "  (void)q0; (void)p0; (void)gam; (void)h; (void)g0; (void)prm;%s\n", part >= 0 ? " (void)w; (void)out;" : "");
}

// Print the operations ops[from..to) of a kernel, one a line, with a comment
// where a new section of the method starts; values needed by a later part
// are also stored in w[].
static void emit_ops(Emitter *e, const int *ops, int from, int to) {
  const Dag *d = e->mod->dag;
  int sec = -1, shown = -1;
  for (int i = from; i < to; i++) {
    int id = ops[i];
    while (sec + 1 < d->marks.n && d->marks.v[sec + 1] <= id) sec++;
    if (sec >= 0 && sec != shown) {
      out(e, "  /* %s */\n", d->labels[sec]);
      shown = sec;
    }
    e->temp[id] = i;
    emit_node(e, id);
    if (e->chunk && e->slot[id] >= 0) out(e, "  w[%d] = t%d;\n", e->slot[id], i);
  }
}

// out[i] = outs[i], for the outputs of the part being printed (all of
// them when the kernel is one part).
static void emit_outputs(Emitter *e, const int *outs, int nouts) {
  for (int i = 0; i < nouts; i++) {
    if (e->chunk && e->chunk[outs[i]] != e->part) continue;
    char r[128];
    ref(e, outs[i], r, sizeof r);
    out(e, "  out[%d] = %s;\n", i, r);
  }
}

// Assign each operation its part, and a slot in w[] to every value used in
// a later part than its own. Returns the number of slots.
static int split_parts(Emitter *e, const int *ops, int nops) {
  const Dag *d = e->mod->dag;
  int nslots = 0;
  for (int i = 0; i < nops; i++) e->chunk[ops[i]] = i / PART_NODES;
  for (int i = 0; i < nops; i++) {
    const Node *n = &d->nodes[ops[i]];
    int kids[2] = {n->a, n->b};
    for (int k = 0; k < 2; k++)
      if (kids[k] >= 0 && d->nodes[kids[k]].a >= 0 && e->chunk[kids[k]] < e->chunk[ops[i]] && e->slot[kids[k]] < 0)
        e->slot[kids[k]] = nslots++;
  }
  return nslots;
}

// Print a kernel computing outs[] into out[0..nouts-1]: straight-line code
// from the DAG, in several parts when it is large.
static void emit_kernel(Emitter *e, const char *name, const char *what, const int *outs, int nouts) {
  const Dag *d = e->mod->dag;
  int top = -1, nops = 0;
  for (int i = 0; i < nouts; i++)
    if (outs[i] > top) top = outs[i];
  unsigned char *mark = calloc((size_t)top + 2, 1);
  int *ops = malloc((size_t)(top + 2) * sizeof(int));
  if (!mark || !ops) internal_error("out of memory");
  dag_reach(d, outs, nouts, mark);
  for (int id = 0; id <= top; id++)
    if (mark[id] && d->nodes[id].a >= 0) ops[nops++] = id;
  int nparts = (nops + PART_NODES - 1) / PART_NODES;
  out(e, "\n/* %s */\n", what);
  if (nparts <= 1) {
    kernel_signature(e, name, -1);
    emit_ops(e, ops, 0, nops);
  } else {
    e->chunk = malloc((size_t)(top + 1) * sizeof(int));
    e->slot = malloc((size_t)(top + 1) * sizeof(int));
    if (!e->chunk || !e->slot) internal_error("out of memory");
    for (int id = 0; id <= top; id++) {
      e->chunk[id] = nparts - 1;
      e->slot[id] = -1;
    }
    int nslots = split_parts(e, ops, nops);
    for (e->part = 0; e->part < nparts; e->part++) {
      kernel_signature(e, name, e->part);
      int from = e->part * PART_NODES, to = from + PART_NODES < nops ? from + PART_NODES : nops;
      emit_ops(e, ops, from, to);
      emit_outputs(e, outs, nouts); /* those computed in this part (leaves in the last) */
      out(e, "}\n\n");
    }
    out(e, "/* %s: the %d parts above in order */\n", name, nparts);
    kernel_signature(e, name, -1);
    out(e, "  %s w[%d];\n", real_type(e, e->wide), nslots);
    for (int k = 0; k < nparts; k++) out(e, "  %s_%s_part%d(q0, p0, gam, h, g0, prm, w, out);\n", e->P, name, k);
    out(e, "}\n");
    free(e->chunk);
    free(e->slot);
    e->chunk = e->slot = NULL;
    free(mark);
    free(ops);
    return;
  }
  emit_outputs(e, outs, nouts);
  out(e, "}\n");
  free(mark);
  free(ops);
}

/* ---- the header ---- */

static void emit_header(Emitter *e, const EmitOptions *o) {
  const Model *mod = e->mod;
  int m = mod->m, nu = mod->nu, s = e->me->s;
  out(e, "/* %s.h - generated by hbvmgen %s from %s: do not edit.\n", e->P, HBVMGEN_VERSION, o->model_file);
  out(e, " * HBVM(k=%d, s=%d) for a Hamiltonian system with %d coordinates and %d constraints,\n", e->me->k, s, m, nu);
  out(e, " * in %s precision%s%s. */\n", e->single ? "single" : "double", o->wide_step ? ", the step computed in " : "",
      o->wide_step ? real_type(e, 1) : "");
  tmpl(e, "#ifndef $P_H\n#define $P_H\n\n");
  out(e, "#define %s_M %d      /* coordinates */\n#define %s_NU %d     /* constraints */\n", e->P, m, e->P, nu);
  out(e, "#define %s_K %d      /* Gauss-Legendre nodes */\n#define %s_S %d      /* polynomial degree */\n", e->P, e->me->k,
      e->P, s);
  out(e, "#define %s_NPARAMS %d\n\n", e->P, mod->nparams);
  tmpl(e, "/* Return codes of $P_step; on any nonzero code the state is unchanged. */\n"
          "#define $P_OK 0\n"
          "#define $P_ENOCONV 1     /* the fixed-point iteration did not converge: reduce h */\n"
          "#define $P_ENONFINITE 2  /* a non-finite value (outside a function's domain?) */\n"
          "#define $P_ESINGULAR 3   /* the multiplier system is singular (dependent constraints?) */\n"
          "#define $P_EBADSTEP 4    /* h is zero or not finite */\n\n"
          "typedef $R $P_real;\n\n");
  out(e, "typedef struct {\n  %s_real t, q[%d], p[%d], lambda[%d];\n", e->P, m, m, nu ? nu : 1);
  out(e, "  /* private: compensated-summation errors and the last step's polynomial */\n");
  out(e, "  %s_real tc, qc[%d], pc[%d], gam[%d], hprev;\n} %s_state;\n\ntypedef struct {\n", e->P, m, m, s * m, e->P);
  for (int i = 0; i < mod->nparams; i++) {
    char v[40];
    format_real(e, v, sizeof v, mod->params[i].value);
    out(e, "  %s_real %s;   /* default %s */\n", e->P, mod->params[i].name, v);
  }
  if (!mod->nparams) out(e, "  char unused_; /* the model has no parameters */\n");
  tmpl(e, "} $P_params;\n\n"
          "typedef struct {\n"
          "  int iters;         /* fixed-point iterations */\n"
          "  double increment;  /* last scaled increment of the iteration */\n"
          "} $P_stats;\n\n"
          "/* q0, p0 NULL: the model's initial values. lambda starts as the multiplier\n"
          " * consistent with (q0, p0) at the default parameters (0 if that is singular)\n"
          " * and is the constant multiplier of the last step after each step. */\n"
          "void $P_init($P_state *x, const double *q0, const double *p0);\n"
          "void $P_params_default($P_params *prm);\n"
          "/* One step of size h; prm and st may be NULL. Returns $P_OK or an error code. */\n"
          "int $P_step($P_state *x, double h, const $P_params *prm, $P_stats *st);\n"
          "const char *$P_strerror(int code);\n"
          "double $P_energy(const $P_state *x, const $P_params *prm);\n"
          "void $P_constraints(const $P_state *x, const $P_params *prm, double *g);   /* NU values */\n"
          "void $P_hidden(const $P_state *x, const $P_params *prm, double *gp);       /* grad g' M^-1 p */\n"
          "\n#endif\n");
}

/* ---- the source ---- */

static void emit_array(Emitter *e, const char *name, const double *v, int n) {
  out(e, "static const %s %s_%s[%d] = {", real_type(e, 0), e->P, name, n > 0 ? n : 1);
  for (int i = 0; i < n; i++) {
    char b[40];
    format_real(e, b, sizeof b, v[i]);
    out(e, "%s%s", i ? ", " : "", b);
  }
  out(e, "%s};\n", n > 0 ? "" : "0");
}

static void emit_prelude(Emitter *e, const EmitOptions *o) {
  const Method *me = e->me;
  out(e, "/* %s.c - generated by hbvmgen %s from %s: do not edit.\n", e->P, HBVMGEN_VERSION, o->model_file);
  out(e, " * HBVM(k=%d, s=%d): line-integral method for Hamiltonian systems with holonomic\n", me->k, me->s);
  tmpl(e, " * constraints (Brugnano, Gurioli, Iavernaro, Weinmueller). Needs only <math.h>. */\n"
          "#include <math.h>\n\n#include \"$P.h\"\n\n"
          "#define M $P_M\n#define NU $P_NU\n#define S $P_S\n"
          "#define MAXITER 100  /* fixed-point iterations before giving up */\n");
  if (e->single)
    tmpl(e, "#define TOL 2.4e-7f     /* an increment within 2 ulps (float) ... */\n"
            "#define STAGTOL 1e-4f   /* an increment that stops decreasing above this is divergence */\n"
            "#define SINGTOL 1e-6f   /* pivot / diagonal of A below this: singular */\n"
            "#define GTOL 7.6e-6f    /* |g| up to this (64 ulps) is round-off: not corrected */\n\n");
  else
    tmpl(e, "#define TOL 4.4408920985006262e-16  /* an increment within 2 ulps ... */\n"
            "#define STAGTOL 1e-10  /* an increment that stops decreasing above this is divergence */\n"
            "#define SINGTOL 1e-13  /* pivot / diagonal of A below this: singular */\n"
            "#define GTOL 1.4210854715202004e-14  /* |g| up to this (64 ulps) is round-off: not corrected */\n\n");
  out(e, "/* Gauss-Legendre nodes c_l and weights b_l on [0,1], k = %d (the kernels below use\n", me->k);
  out(e, " * their products with P_j and int_0^c P_j, folded into the code):\n");
  for (int l = 0; l < me->k; l++) out(e, " *   c_%d = %.17g   b_%d = %.17g\n", l + 1, me->c[l], l + 1, me->b[l]);
  out(e, " */\n/* Warm start: E[j][i](r) = sum_d E[(j*S+i)*S+d] r^d, r = h / h_previous. */\n");
  emit_array(e, "E", me->E, me->s * me->s * me->s);
  out(e, "/* Model defaults for q0 and p0. */\n");
  emit_array(e, "q0", e->mod->q0, e->mod->m);
  emit_array(e, "p0", e->mod->p0, e->mod->m);
}

static void emit_kernels(Emitter *e) {
  const Step *st = e->st;
  int m = e->mod->m, nu = e->mod->nu, s = e->me->s;
  int nsweep = s * m + m + 3 * nu, wide = e->wide_step;
  int *sweep = malloc((size_t)nsweep * sizeof(int));
  if (!sweep) internal_error("out of memory");
  memcpy(sweep, st->gam_new, (size_t)(s * m) * sizeof(int));
  memcpy(sweep + s * m, st->dp, (size_t)m * sizeof(int));
  memcpy(sweep + s * m + m, st->lambda, (size_t)nu * sizeof(int));
  memcpy(sweep + s * m + m + nu, st->pivot, (size_t)nu * sizeof(int));
  memcpy(sweep + s * m + m + 2 * nu, st->adiag, (size_t)nu * sizeof(int));
  e->wide = wide;
  if (wide) out(e, "\n/* --wide-step: the sweep below computes in %s. */", real_type(e, e->wide));
  emit_kernel(e, "sweep",
              "One fixed-point sweep: out = new gamma (S*M), p1 - p0 (M), lambda (NU),\n"
              " * pivots of the LU of A (NU), diagonal of A (NU).",
              sweep, nsweep);
  e->wide = 0;
  free(sweep);
  emit_kernel(e, "minv_p", "out = M^-1 p0: the first step's prediction of gamma_0", st->predict0, m);
  emit_kernel(e, "energy_kernel", "out[0] = H(q0, p0) = p0' M^-1 p0 / 2 + U(q0)", st->energy, 1);
  if (nu) {
    emit_kernel(e, "g", "out = g(q0)", st->g_at_q0, nu);
    emit_kernel(e, "hidden_kernel", "out = grad g(q0)' M^-1 p0", st->hidden, nu);
    emit_kernel(e, "lambda0",
                "out = the multiplier consistent with (q0, p0):\n"
                " * (G' M^-1 G) lambda = [v' Hess(g_a) v]_a - G' M^-1 grad U, G = grad g(q0), v = M^-1 p0",
                st->lambda0, nu);
  }
}

static void emit_public(Emitter *e) {
  tmpl(e, "\nvoid $P_params_default($P_params *prm)\n{\n");
  for (int i = 0; i < e->mod->nparams; i++) {
    char v[40];
    format_real(e, v, sizeof v, e->mod->params[i].value);
    out(e, "  prm->%s = %s;\n", e->mod->params[i].name, v);
  }
  if (!e->mod->nparams) out(e, "  prm->unused_ = 0;\n");
  tmpl(e, "}\n\n"
          "void $P_init($P_state *x, const double *q0, const double *p0)\n{\n"
          "  int i;\n"
          "  x->t = x->tc = x->hprev = 0;\n"
          "  for (i = 0; i < M; i++) {\n"
          "    x->q[i] = q0 ? ($R)q0[i] : $P_q0[i];\n"
          "    x->p[i] = p0 ? ($R)p0[i] : $P_p0[i];\n"
          "    x->qc[i] = x->pc[i] = 0;\n  }\n"
          "  for (i = 0; i < (NU ? NU : 1); i++) x->lambda[i] = 0;\n"
          "  for (i = 0; i < S * M; i++) x->gam[i] = 0;\n");
  if (e->mod->nu)
    tmpl(e, "  {\n    $P_params prm;\n    $R lam[NU];\n    $P_params_default(&prm);\n"
            "    $P_lambda0(x->q, x->p, 0, 0, 0, &prm, lam);\n"
            "    for (i = 0; i < NU; i++) x->lambda[i] = isfinite(lam[i]) ? lam[i] : 0;\n  }\n");
  tmpl(e, "}\n\n"
          "const char *$P_strerror(int code)\n{\n  switch (code) {\n"
          "  case $P_OK: return \"ok\";\n"
          "  case $P_ENOCONV: return \"fixed-point iteration did not converge\";\n"
          "  case $P_ENONFINITE: return \"non-finite value\";\n"
          "  case $P_ESINGULAR: return \"singular multiplier system\";\n"
          "  case $P_EBADSTEP: return \"step size zero or not finite\";\n"
          "  }\n  return \"unknown error\";\n}\n\n"
          "#define DEFAULT_PARAMS(prm) $P_params dflt_; if (!prm) { $P_params_default(&dflt_); prm = &dflt_; }\n\n"
          "double $P_energy(const $P_state *x, const $P_params *prm)\n{\n  $R H;\n  DEFAULT_PARAMS(prm)\n"
          "  $P_energy_kernel(x->q, x->p, 0, 0, 0, prm, &H);\n  return H;\n}\n\n");
  if (e->mod->nu)
    tmpl(e, "void $P_constraints(const $P_state *x, const $P_params *prm, double *g)\n{\n"
            "  $R v[NU];\n  int i;\n  DEFAULT_PARAMS(prm)\n"
            "  $P_g(x->q, x->p, 0, 0, 0, prm, v);\n  for (i = 0; i < NU; i++) g[i] = v[i];\n}\n\n"
            "void $P_hidden(const $P_state *x, const $P_params *prm, double *gp)\n{\n"
            "  $R v[NU];\n  int i;\n  DEFAULT_PARAMS(prm)\n"
            "  $P_hidden_kernel(x->q, x->p, 0, 0, 0, prm, v);\n  for (i = 0; i < NU; i++) gp[i] = v[i];\n}\n");
  else
    tmpl(e, "void $P_constraints(const $P_state *x, const $P_params *prm, double *g)\n{\n"
            "  (void)x; (void)prm; (void)g;\n}\n\n"
            "void $P_hidden(const $P_state *x, const $P_params *prm, double *gp)\n{\n"
            "  (void)x; (void)prm; (void)gp;\n}\n");
}

// The warm start, iteration and compensated update around the sweep kernel.
// With --wide-step the iteration (gamma, the sweep's results) is in the wider
// type, starts from the compensated state q - qc, p - pc, and the new q, p
// and their compensations come from rounding the wide sums once.
static void emit_step(Emitter *e) {
  int wide = e->wide_step;
  tmpl(e, "\n/* gamma for a step of size h: extrapolated from the previous step's polynomial,\n"
          " * or gamma_0 = M^-1 p, gamma_j = 0 (j > 0) on the first step. */\n"
          "static void $P_predict(const $P_state *x, $R h, const $P_params *prm, $R *gam)\n{\n"
          "  int i, j, l, d;\n"
          "  for (i = 0; i < S * M; i++) gam[i] = 0;\n"
          "  if (x->hprev == 0) {\n    $P_minv_p(x->q, x->p, 0, 0, 0, prm, gam);\n    return;\n  }\n"
          "  for (j = 0; j < S; j++)\n    for (i = 0; i < S; i++) {\n"
          "      $R r = h / x->hprev, e = 0;\n"
          "      for (d = S - 1; d >= 0; d--) e = e * r + $P_E[(j * S + i) * S + d];\n"
          "      if (e != 0)\n        for (l = 0; l < M; l++) gam[j * M + l] += e * x->gam[i * M + l];\n"
          "    }\n}\n\n");
  if (e->compensated)
    tmpl(e, "/* a += b with the rounding error carried in *c (Kahan). */\n"
            "static void $P_add($R *a, $R *c, $R b)\n{\n"
            "  $R y = b - *c, t = *a + y;\n  *c = (t - *a) - y;\n  *a = t;\n}\n\n");
  else
    tmpl(e, "/* a += b, plainly (generated with --plain-sum: no compensated summation). */\n"
            "static void $P_add($R *a, $R *c, $R b)\n{\n  (void)c;\n  *a += b;\n}\n\n");
  out(e, "/* One step of HBVM(%d,%d). Iterates the sweep until the increment reaches round-off\n", e->me->k, e->me->s);
  tmpl(e, " * or stops decreasing; commits to *x only on success. */\n"
          "int $P_step($P_state *x, double h_, const $P_params *prm, $P_stats *st)\n{\n"
          "  const $R h = ($R)h_;\n"
          "  $W gam[S * M], sw[S * M + M + 3 * NU + 1];\n"
          "  $R inc = HUGE_VAL, inc_old, scale;\n"
          "  int it, i, rc = $P_ENOCONV;\n  DEFAULT_PARAMS(prm)\n"
          "  if (!(h != 0 && isfinite(h))) return $P_EBADSTEP;\n");
  if (wide)
    tmpl(e, "  $W q0w[M], p0w[M];\n"
            "  {\n    $R guess[S * M];\n    $P_predict(x, h, prm, guess);\n"
            "    for (i = 0; i < S * M; i++) gam[i] = guess[i];\n  }\n"
            "  /* the sweep starts from the compensated state q - qc, p - pc, in $W */\n"
            "  for (i = 0; i < M; i++) {\n"
            "    q0w[i] = ($W)x->q[i] - x->qc[i];\n"
            "    p0w[i] = ($W)x->p[i] - x->pc[i];\n  }\n");
  else
    tmpl(e, "  $P_predict(x, h, prm, gam);\n");
  if (e->mod->nu)
    tmpl(e, "  $R g0[NU];\n  $P_g(x->q, x->p, 0, 0, 0, prm, g0);\n"
            "  /* g(q0) / h in the multiplier equation makes g(q1) = 0 rather than g(q0), so g\n"
            "   * cannot drift; below GTOL, g(q0) is round-off, and kicking the momenta by it\n"
            "   * (eps / h a step) would only add noise, so it is left out. */\n"
            "  for (i = 0; i < NU; i++) g0[i] = fabs$f(g0[i]) <= GTOL ? 0 : g0[i] / h;\n");
  tmpl(e, "  for (it = 1; it <= MAXITER; it++) {\n");
  out(e, "    %s_sweep(%s, %s, gam, h, %s, prm, sw);\n", e->P, wide ? "q0w" : "x->q", wide ? "p0w" : "x->p",
      e->mod->nu ? "g0" : "0");
  tmpl(e, "    /* increment: max |h (gamma_new - gamma)| over max |q| + |h gamma_0| */\n"
          "    inc_old = inc;\n    inc = 0;\n    scale = 0;\n"
          "    for (i = 0; i < M; i++) {\n"
          "      $R v = fabs$f(x->q[i]) + fabs$g(h * sw[i]);\n"
          "      if (v > scale) scale = v;\n    }\n"
          "    for (i = 0; i < S * M; i++) {\n"
          "      $R v = fabs$g(h * (sw[i] - gam[i]));\n"
          "      if (v > inc) inc = v;\n"
          "      gam[i] = sw[i];\n    }\n"
          "    if (scale > 0) inc /= scale;\n");
  if (e->mod->nu) /* before the finiteness test: a zero pivot makes lambda 0/0 */
    tmpl(e, "    for (i = 0; i < NU; i++) {\n"
            "      $R piv = sw[S * M + M + NU + i], dia = sw[S * M + M + 2 * NU + i];\n"
            "      if (isfinite(piv) && isfinite(dia) && !(fabs$f(piv) > SINGTOL * fabs$f(dia))) rc = $P_ESINGULAR;\n"
            "    }\n"
            "    if (rc == $P_ESINGULAR) break;\n");
  tmpl(e, "    for (i = 0; i < S * M + M + NU; i++)\n      if (!isfinite(sw[i])) rc = $P_ENONFINITE;\n"
          "    if (rc == $P_ENONFINITE || !isfinite(inc)) { rc = $P_ENONFINITE; break; }\n"
          "    /* converged: the increment is far below an ulp of the state (TOL / 256), or\n"
          "     * within 2 ulps (TOL) and falling by less than 4x (round-off noise), or it\n"
          "     * stopped decreasing (at round-off: accept; above STAGTOL: fail). Iterating\n"
          "     * this far, rather than stopping at 2 ulps, makes |H - H0| grow like a\n"
          "     * random walk over millions of steps (bench/results/longrun.txt). */\n"
          "    if (inc <= TOL / 256 || (inc <= TOL && 4 * inc > inc_old)) { rc = $P_OK; break; }\n"
          "    if (it > 1 && inc >= inc_old) { rc = inc <= STAGTOL ? $P_OK : $P_ENOCONV; break; }\n  }\n"
          "  if (st) { st->iters = it > MAXITER ? MAXITER : it; st->increment = inc; }\n"
          "  if (rc != $P_OK) return rc;\n"
          "  for (i = 0; i < M; i++) /* the new state must be finite too */\n"
          "    if (!isfinite(x->q[i] + h * sw[i]) || !isfinite(x->p[i] + sw[S * M + i])) return $P_ENONFINITE;\n");
  if (!wide)
    tmpl(e, "  for (i = 0; i < M; i++) {\n"
            "    $P_add(&x->q[i], &x->qc[i], h * sw[i]);\n"
            "    $P_add(&x->p[i], &x->pc[i], sw[S * M + i]);\n  }\n"
            "  for (i = 0; i < NU; i++) x->lambda[i] = sw[S * M + M + i];\n"
            "  for (i = 0; i < S * M; i++) x->gam[i] = gam[i];\n");
  else {
    tmpl(e, "  /* q1 = (q - qc) + h gamma_0 and p1 = (p - pc) + (p1 - p0) in $W, rounded once into\n"
            "   * q, p; what the rounding lost is the new qc, pc */\n"
            "  for (i = 0; i < M; i++) {\n"
            "    $W q1 = q0w[i] + h * sw[i], p1 = p0w[i] + sw[S * M + i];\n"
            "    x->q[i] = ($R)q1;\n    x->p[i] = ($R)p1;\n");
    if (e->compensated) tmpl(e, "    x->qc[i] = ($R)(x->q[i] - q1);\n    x->pc[i] = ($R)(x->p[i] - p1);\n");
    tmpl(e, "  }\n"
            "  for (i = 0; i < NU; i++) x->lambda[i] = ($R)sw[S * M + M + i];\n"
            "  for (i = 0; i < S * M; i++) x->gam[i] = ($R)gam[i];\n");
  }
  tmpl(e, "  $P_add(&x->t, &x->tc, h);\n  x->hprev = h;\n  return $P_OK;\n}\n");
}

// Write NAME.h to hf and NAME.c to cf. Returns 0, or -1 on a write error.
int emit_solver(FILE *hf, FILE *cf, const Model *mod, const Method *me, const Step *st, const EmitOptions *o) {
  Emitter e = {hf, mod, me, st, o->name, NULL, o->single, o->compensated, NULL, NULL, 0, o->wide_step, 0};
  e.temp = malloc((size_t)mod->dag->n * sizeof(int));
  if (!e.temp) internal_error("out of memory");
  emit_header(&e, o);
  e.f = cf;
  emit_prelude(&e, o);
  emit_kernels(&e);
  emit_public(&e);
  emit_step(&e);
  free(e.temp);
  return ferror(hf) || ferror(cf) ? -1 : 0;
}
