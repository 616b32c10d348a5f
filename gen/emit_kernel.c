/* emit_kernel.c - kernels: straight-line C from the DAG.
 *
 * Every computation of the generated solver is a "kernel": a static
 * function printed from the result blocks of a Kernel as straight-line
 * code, one operation a line (but a product with a constant table, a TROW
 * node, is a loop over the table), each intermediate a named const temporary, a
 * comment where a new section of the method starts, constants with 17
 * significant digits. All kernels share one signature, printed from the
 * Step's input blocks (q0, p0, gamma, h, g0, ..., params -> out[]), so that
 * the input slots of the DAG map to the same C names everywhere. This file
 * also holds the small printing helpers the other emitters use: out, tmpl (the
 * template expander, which also names kernel calls and result offsets from
 * the blocks) and format_real.
 *
 * With e->lanes = W (--batch W) the same kernels print as NAME_batch_KERNEL:
 * the straight-line body inside one loop over W lanes, every array in
 * struct-of-arrays form (value i of lane l at [i * W + l]), so that each
 * lane does exactly the scalar kernel's operations and the compiler can
 * vectorise the loop. */
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "emit.h"

/* A kernel with more operations than this is printed as several functions
 * of straight-line code (values crossing parts pass through an array):
 * compilers take time superlinear in a function's size. */
#define PART_NODES 2000

/* A sweep with more operations than this is not inlined into the fused step
 * but stays a function (of parts, above PART_NODES). Measured with gcc 12 -O2
 * (bench/step/ab.sh, fused against the call): 0.78-0.92 of the time up to
 * Kepler's k = 16 sweep (486 operations), 0.95-1.0 for chain8 (1268), but
 * 1.17 for the satellites (6,2) const (1354) and 1.08-1.13 for their poly
 * sweep (2200): past about a thousand values the compiler spills. */
#define INLINE_NODES 1000

/* Room for the C name of one value: a temporary, a literal, an input with
 * its coordinate's name, or prm->NAME. */
#define NAME_SIZE 1024

void out(Emitter *e, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vfprintf(e->f, fmt, ap);
  va_end(ap);
}

// The name of a real type of the generated code, and the suffix of its
// math functions (sqrt, sqrtf, sqrtl): the solver's real type, or with wide
// the next wider one (--wide-step: long double for double, double for float).
const char *real_type(const Emitter *e, int wide) {
  if (wide) return e->single ? "double" : "long double";
  return e->single ? "float" : "double";
}

const char *math_suffix(const Emitter *e, int wide) {
  if (wide) return e->single ? "" : "l";
  return e->single ? "f" : "";
}


// The C expression of the total length of blocks[0..n): the sum of their
// symbolic lengths in the solver's size macros, equal ones merged
// ("P_S * P_M + P_M + 2 * P_NU"); "" for none.
static void size_expr(const char *P, const Slots *blocks, int n, char *buf, size_t size) {
  static const char *const sym[SZ_COUNT][2] = {[SZ_SM] = {"S", "M"}, [SZ_M] = {"M", NULL}, [SZ_NU] = {"NU", NULL},
                                               [SZ_SNU] = {"S", "NU"}};
  int coef[SZ_COUNT] = {0}, order[SZ_COUNT], norder = 0;
  for (int i = 0; i < n; i++) {
    if (!blocks[i].coef) continue;
    if (!coef[blocks[i].sym]) order[norder++] = blocks[i].sym;
    coef[blocks[i].sym] += blocks[i].coef;
  }
  size_t len = 0;
  buf[0] = 0;
  for (int i = 0; i < norder && len < size; i++) {
    int c = coef[order[i]];
    const char *sep = i ? " + " : "";
    const char *const *y = sym[order[i]];
    if (order[i] == SZ_ONE) len += (size_t)snprintf(buf + len, size - len, "%s%d", sep, c);
    else if (c == 1) len += (size_t)snprintf(buf + len, size - len, "%s%s_%s", sep, P, y[0]);
    else len += (size_t)snprintf(buf + len, size - len, "%s%d * %s_%s", sep, c, P, y[0]);
    if (order[i] != SZ_ONE && y[1] && len < size) len += (size_t)snprintf(buf + len, size - len, " * %s_%s", P, y[1]);
  }
}

// The kernel named name (up to the first character not in a C name).
static KernelId kernel_named(const Emitter *e, const char *name, size_t n) {
  for (int k = 0; k < K_COUNT; k++)
    if (strlen(e->st->kern[k].name) == n && !strncmp(e->st->kern[k].name, name, n)) return (KernelId)k;
  internal_error("template names an unknown kernel '%.*s'", (int)n, name);
  return K_COUNT;
}

// Expand "kernel.block" or "kernel" (text up to end) into the C expression
// of that block's offset in the kernel's out[] (of its total length without
// a block): "" when it is zero. With plus, "OFFSET + " so that
// "sw[$[sweep.dp]i]" reads sw[S * M + i] or sw[i].
static void offset_of(const Emitter *e, const char *text, const char *end, int plus) {
  const char *dot = memchr(text, '.', (size_t)(end - text));
  KernelId id = kernel_named(e, text, (size_t)((dot ? dot : end) - text));
  const Kernel *k = &e->st->kern[id];
  int upto = k->nout;
  if (dot) {
    char name[64];
    snprintf(name, sizeof name, "%.*s", (int)(end - dot - 1), dot + 1);
    const Slots *bl = step_block(e->st, id, name);
    if (!bl) internal_error("template names an unknown result '%.*s'", (int)(end - text), text);
    upto = (int)(bl - k->out);
  }
  char buf[1024];
  size_expr(e->P, k->out, upto, buf, sizeof buf);
  if (plus && buf[0]) fprintf(e->f, "%s + ", buf);
  else if (!plus) fputs(buf[0] ? buf : "0", e->f);
}

// Print a call of a kernel from "name arg=value ...": the arguments in
// signature order, 0 for an input not given, prm unless given, out= last.
static void kernel_call(Emitter *e, const char *text, const char *end) {
  size_t n = strcspn(text, " )");
  KernelId k = kernel_named(e, text, n);
  const char *val[IN_COUNT + 3] = {0}; /* the inputs, then prm, out and skip */
  size_t vlen[IN_COUNT + 3] = {0};
  for (const char *p = text + n; p < end;) {
    while (*p == ' ') p++;
    size_t nl = strcspn(p, "="), vl = strcspn(p + nl + 1, " )");
    int slot = -1;
    for (int i = 0; i < IN_COUNT; i++)
      if (strlen(e->st->in[i].name) == nl && !strncmp(e->st->in[i].name, p, nl)) slot = i;
    if (nl == 3 && !strncmp(p, "prm", 3)) slot = IN_COUNT;
    if (nl == 3 && !strncmp(p, "out", 3)) slot = IN_COUNT + 1;
    if (nl == 4 && !strncmp(p, "skip", 4)) slot = IN_COUNT + 2; /* the rolled batch sweep's (kernel_signature) */
    if (slot < 0) internal_error("template passes an unknown argument '%.*s'", (int)nl, p);
    val[slot] = p + nl + 1;
    vlen[slot] = vl;
    p += nl + 1 + vl;
  }
  fprintf(e->f, "%s_%s%s(", e->P, e->lanes ? "batch_" : "", e->st->kern[k].name);
  for (int i = 0; i < IN_COUNT; i++)
    if (e->st->in[i].len || i < IN_LAM) fprintf(e->f, "%.*s, ", val[i] ? (int)vlen[i] : 1, val[i] ? val[i] : "0");
  fprintf(e->f, "%.*s, %.*s", val[IN_COUNT] ? (int)vlen[IN_COUNT] : 3, val[IN_COUNT] ? val[IN_COUNT] : "prm",
          (int)vlen[IN_COUNT + 1], val[IN_COUNT + 1] ? val[IN_COUNT + 1] : "");
  if (val[IN_COUNT + 2]) fprintf(e->f, ", %.*s", (int)vlen[IN_COUNT + 2], val[IN_COUNT + 2]);
  fputc(')', e->f);
}

// Print text, replacing $P by the prefix, $R by the real type name, $M by
// the integer type as wide as it (a lane mask of --batch), $f by
// the suffix of its math functions, $W by the type the step iterates in (the
// real type, or the next wider one with --wide-step) and $g by the suffix of
// that type's math functions. Kernels are named through the Step, never by
// position: $(kernel arg=value ...) prints a call, $[kernel.result] the
// offset of a result block followed by " + " (nothing for the first),
// $<kernel.result> the offset alone and $<kernel> the length of out[].
void tmpl(Emitter *e, const char *text) {
  for (const char *p = text; *p; p++) {
    if (*p != '$' || !p[1]) {
      fputc(*p, e->f);
      continue;
    }
    const char *close = NULL;
    switch (p[1]) {
    case 'P': fputs(e->P, e->f); break;
    case 'R': fputs(real_type(e, 0), e->f); break;
    case 'M': fputs(strcmp(real_type(e, 0), "float") ? "long long" : "int", e->f); break; /* a lane mask as wide as $R */
    case 'f': fputs(math_suffix(e, 0), e->f); break;
    case 'W': fputs(real_type(e, e->wide_step), e->f); break;
    case 'g': fputs(math_suffix(e, e->wide_step), e->f); break;
    case '(':
      close = strchr(p, ')');
      kernel_call(e, p + 2, close);
      break;
    case '[':
      close = strchr(p, ']');
      offset_of(e, p + 2, close, 1);
      break;
    case '<':
      close = strchr(p, '>');
      offset_of(e, p + 2, close, 0);
      break;
    default: fputc(*p, e->f); continue;
    }
    p = close ? close : p + 1;
  }
}

// tmpl of a printf format's result (at most 4095 characters).
void tmplf(Emitter *e, const char *fmt, ...) {
  char text[4096];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(text, sizeof text, fmt, ap);
  va_end(ap);
  tmpl(e, text);
}
// A literal that reads back exactly in the real type and is a C floating
// constant: 17 significant digits for double, 9 and an f suffix for float.
void format_real(const Emitter *e, char *buf, size_t size, double v) {
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
  case OP_PARAM:
    if (e->lanes) snprintf(buf, size, "prm[%d + l] /* %s */", n->idx * e->lanes, e->mod->params[n->idx].name);
    else snprintf(buf, size, "prm->%s", e->mod->params[n->idx].name);
    return;
  case OP_INPUT:
    if (e->body && n->idx < e->mod->m) {
      snprintf(buf, size, "Q[%d] /* %s */", n->idx, e->mod->coord_names[n->idx]);
      return;
    }
    for (int i = 0; i < IN_COUNT; i++) {
      const Slots *in = &st->in[i];
      if (n->idx < in->first || n->idx >= in->first + in->len) continue;
      int i = n->idx - in->first, slot = (int)(in - st->in);
      const char *nm = e->arg[slot] ? e->arg[slot] : in->name;
      char at[32];
      if (e->local >> slot & 1u) { /* the fused step: a scalar local */
        snprintf(buf, size, "%s%d", nm, i);
        return;
      }
      snprintf(at, sizeof at, e->lanes ? "%d + l" : "%d", e->lanes ? i * e->lanes : i);
      if (in->scalar) snprintf(buf, size, "%s", nm);
      else if (i < e->mod->m && (in == &st->in[IN_Q0] || in == &st->in[IN_P0])) /* name the coordinate */
        snprintf(buf, size, "%s[%s] /* %s%s */", nm, at, in == &st->in[IN_P0] ? "p_" : "", e->mod->coord_names[i]);
      else snprintf(buf, size, "%s[%s]", nm, at);
      return;
    }
    internal_error("model coordinate %d reached a kernel", n->idx);
    return;
  default:
    if (e->body) snprintf(buf, size, "b%d", id); /* a stage loop's body: all its own */
    else if (e->chunk && e->chunk[id] != e->part && e->lanes) snprintf(buf, size, "w[%d + l]", e->slot[id] * e->lanes);
    else if (e->chunk && e->chunk[id] != e->part) snprintf(buf, size, "w[%d]", e->slot[id]);
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
  char leaf[NAME_SIZE - 16]; /* room for the cast */
  name_of(e, id, leaf, sizeof leaf);
  snprintf(buf, size, "(%s)%s", real_type(e, 1), leaf);
}

// x^n for a small integer n as products, so no pow() call is needed.
static int power_expr(char *buf, size_t size, const char *x, double n) {
  static const char *const forms[] = {NULL, "%s", "%s * %s", "%s * %s * %s", "(%s * %s) * (%s * %s)",
                                      "(%s * %s) * (%s * %s) * %s", "(%s * %s * %s) * (%s * %s * %s)"};
  if (n != floor(n) || fabs(n) < 2 || fabs(n) > 6) return 0; /* (int) of 1e40 would be undefined */
  int k = (int)fabs(n);
  char prod[7 * NAME_SIZE];
  snprintf(prod, sizeof prod, forms[k], x, x, x, x, x, x);
  if (n < 0) snprintf(buf, size, "1 / (%s)", prod);
  else snprintf(buf, size, "%s", prod);
  return 1;
}

// The type the tables are printed in: that of the widest kernel, so that
// each kernel reads the value its literal would have (after a cast).
static const char *table_type(const Emitter *e) { return real_type(e, e->wide_step); }

// The constant tables TROW nodes of the kernels read (dag_table), as static
// arrays before the kernels; those no kernel uses are left out.
void emit_tables(Emitter *e) {
  const Dag *d = e->mod->dag;
  unsigned char *used = xcalloc((size_t)d->ntables + 1, 1), *mark = xcalloc((size_t)d->n + 1, 1);
  for (int k = 0; k < K_COUNT; k++)
    for (int b = 0; b < e->st->kern[k].nout; b++) dag_reach(d, e->st->kern[k].out[b].nodes, e->st->kern[k].out[b].len, mark);
  for (int id = 0; id < d->n; id++)
    if (mark[id] && d->nodes[id].op == OP_TROW) used[(int)d->nodes[id].val] = 1;
  for (int t = 0; t < d->ntables; t++) {
    const DagTable *tb = &d->tables[t];
    if (!used[t]) continue;
    out(e, "/* The table the loops of the kernels below multiply by (%s), transposed:\n"
           " * %s_%s[j][i] is row i, column j. */\n", tb->name, e->P, tb->name);
    out(e, "static const %s %s_%s[%d][%d] = {\n", table_type(e), e->P, tb->name, tb->cols, tb->rows);
    int wide = e->wide;
    e->wide = e->wide_step; /* the literals of the table's type */
    for (int j = 0; j < tb->cols; j++) {
      out(e, "  {");
      for (int i = 0; i < tb->rows; i++) {
        char lit[64];
        format_real(e, lit, sizeof lit, tb->v[(size_t)i * (size_t)tb->cols + (size_t)j]);
        out(e, "%s%s", i ? ", " : "", lit);
      }
      out(e, "}%s\n", j + 1 < tb->cols ? "," : "");
    }
    e->wide = wide;
    out(e, "};\n\n");
  }
  free(used);
  free(mark);
}

// The product of table t with the vector whose chain ends at vec, in the
// part being printed on first use there: the vector's entries in an array
// vID, then yID[i] = sum_j T[i][j] vID[j] for every row i, summed in order
// of j (as dag.c evaluates it) with the loop over i innermost, so that the
// compiler vectorises it; the table is printed transposed for that.
static void declare_product(Emitter *e, const DagTable *tb, int vec) {
  const Dag *d = e->mod->dag;
  if (e->vec_part[vec] == e->part + 1) return;
  e->vec_part[vec] = e->part + 1;
  int n = dag_vector_len(d, vec), *ent = xmalloc((size_t)n * sizeof *ent);
  const char *ty = real_type(e, e->wide), *in = e->lanes ? "  " : "";
  char cast[32] = "";
  if (strcmp(ty, table_type(e))) snprintf(cast, sizeof cast, "(%s)", ty);
  dag_vector_entries(d, vec, ent);
  out(e, "%s  const %s v%d[%d] = {", in, ty, vec, n);
  for (int j = 0; j < n; j++) {
    char r[NAME_SIZE];
    ref(e, ent[j], r, sizeof r);
    out(e, "%s%s", j ? ", " : "", r);
  }
  out(e, "};\n%s  %s y%d[%d];\n", in, ty, vec, tb->rows);
  out(e, "%s  for (int i = 0; i < %d; i++) y%d[i] = %s%s_%s[0][i] * v%d[0];\n", in, tb->rows, vec, cast, e->P, tb->name, vec);
  out(e, "%s  for (int j = 1; j < %d; j++)\n%s    for (int i = 0; i < %d; i++) y%d[i] += %s%s_%s[j][i] * v%d[j];\n", in,
      n, in, tb->rows, vec, cast, e->P, tb->name, vec);
  free(ent);
}

// A TROW node: row idx of its table's product with its vector.
static void emit_table_row(Emitter *e, int id) {
  const Dag *d = e->mod->dag;
  const Node *n = &d->nodes[id];
  declare_product(e, &d->tables[(int)n->val], n->a);
  out(e, "%s  const %s t%d = y%d[%d];\n", e->lanes ? "  " : "", real_type(e, e->wide), e->temp[id], n->a, n->idx);
}

static void emit_node(Emitter *e, int id);

// A static table of the method's constants (k x s) for a stage loop,
// literals of the kernel's type.
static void stage_table(Emitter *e, const char *name, const double *v, int k, int s) {
  out(e, "%s    static const %s %s[%d][%d] = {", e->lanes ? "  " : "", real_type(e, e->wide), name, k, s);
  for (int l = 0; l < k; l++) {
    out(e, "%s{", l ? ", " : "");
    for (int j = 0; j < s; j++) {
      char lit[64];
      format_real(e, lit, sizeof lit, v[l * s + j]);
      out(e, "%s%s", j ? ", " : "", lit);
    }
    out(e, "}");
  }
  out(e, "};\n");
}

// Stage loop number loop, in the part being printed on first use there:
// sLOOP[j * nroots + r] = sum_l W[l][j] f_r(Q_l), for l in order (as the
// straight-line stages sum them), the model's operations printed once as
// the loop's body (emit_node with e->body).
static void emit_stage_loop(Emitter *e, int loop) {
  const Dag *d = e->mod->dag;
  const DagLoop *lp = &d->loops[loop];
  const char *ty = real_type(e, e->wide), *in = e->lanes ? "  " : "";
  if (e->loop_part[loop] == e->part + 1) return;
  e->loop_part[loop] = e->part + 1;
  char r[NAME_SIZE];
  out(e, "%s  %s s%d[%d];\n%s  for (int i = 0; i < %d; i++) s%d[i] = 0;\n", in, ty, loop, lp->s * lp->nroots, in,
      lp->s * lp->nroots, loop);
  out(e, "%s  for (int st = 0; st < %d; st++) { /* the stages */\n", in, lp->k);
  stage_table(e, "Ihat", lp->Ihat, lp->k, lp->s);
  stage_table(e, "Wt", lp->W, lp->k, lp->s);
  out(e, "%s    %s Q[%d];\n", in, ty, lp->m);
  for (int i = 0; i < lp->m; i++) {
    ref(e, lp->q0[i], r, sizeof r);
    out(e, "%s    Q[%d] = %s + ", in, i, r);
    ref(e, lp->h, r, sizeof r);
    out(e, "%s * (", r);
    for (int j = 0; j < lp->s; j++) {
      ref(e, lp->gam[j * lp->m + i], r, sizeof r);
      out(e, "%sIhat[st][%d] * %s", j ? " + " : "", j, r);
    }
    out(e, ");\n");
  }
  unsigned char *mark = xcalloc((size_t)d->n + 1, 1);
  dag_reach(d, lp->roots, lp->nroots, mark);
  e->body = 1;
  for (int id = 0; id < d->n; id++)
    if (mark[id] && d->nodes[id].a >= 0) emit_node(e, id);
  for (int j = 0; j < lp->s; j++)
    for (int t = 0; t < lp->nroots; t++) {
      ref(e, lp->roots[t], r, sizeof r);
      out(e, "%s    s%d[%d] += Wt[st][%d] * %s;\n", in, loop, j * lp->nroots + t, j, r);
    }
  e->body = 0;
  out(e, "%s  }\n", in);
  free(mark);
}

// The indentation of a kernel's body: none in a function of its own, one
// level inside the loop over lanes, two inside the fused step's loop.
static const char *body_indent(const Emitter *e) {
  return e->res ? "    " : e->lanes ? "  " : "";
}

// One line computing node id into its temporary.
static void emit_node(Emitter *e, int id) {
  const Node *n = &e->mod->dag->nodes[id];
  char a[NAME_SIZE], b[NAME_SIZE], rhs[8 * NAME_SIZE];
  if (n->op == OP_TROW) {
    emit_table_row(e, id);
    return;
  }
  if (n->op == OP_SSUM) {
    emit_stage_loop(e, (int)n->val);
    out(e, "%s  const %s t%d = s%d[%d];\n", e->lanes ? "  " : "", real_type(e, e->wide), e->temp[id], (int)n->val, n->idx);
    return;
  }
  ref(e, n->a, a, sizeof a);
  if (n->b >= 0) ref(e, n->b, b, sizeof b);
  op_rhs(e, n, a, b, rhs, sizeof rhs);
  char lhs[32];
  snprintf(lhs, sizeof lhs, e->body ? "b%d" : "t%d", e->body ? id : e->temp[id]);
  out(e, "%s%s  const %s %s = %s;\n", body_indent(e), e->body ? "    " : "", real_type(e, e->wide), lhs, rhs);
}

// The C expression of operation n on its operands' names a and b (b unused
// for a unary one) into rhs: an operator, x^n for a small integer n as
// products, or the math function in the kernel's precision.
void op_rhs(Emitter *e, const Node *n, const char *a, const char *b, char *rhs, size_t size) {
  switch ((Op)n->op) {
  case OP_ADD: snprintf(rhs, size, "%s + %s", a, b); break;
  case OP_SUB: snprintf(rhs, size, "%s - %s", a, b); break;
  case OP_MUL: snprintf(rhs, size, "%s * %s", a, b); break;
  case OP_DIV: snprintf(rhs, size, "%s / %s", a, b); break;
  case OP_NEG: snprintf(rhs, size, "-%s", a); break;
  case OP_SIGN: snprintf(rhs, size, "(%s > 0) - (%s < 0)", a, a); break;
  case OP_POW: {
    const Node *ex = &e->mod->dag->nodes[n->b];
    if (ex->op == OP_CONST && power_expr(rhs, size, a, ex->val)) break;
    snprintf(rhs, size, "pow%s(%s, %s)", math_suffix(e, e->wide), a, b);
    break;
  }
  default:
    if (n->b >= 0) snprintf(rhs, size, "%s%s(%s, %s)", op_cfun((Op)n->op), math_suffix(e, e->wide), a, b);
    else snprintf(rhs, size, "%s%s(%s)", op_cfun((Op)n->op), math_suffix(e, e->wide), a);
  }
}

// Whether the batch kernel k is inlined where it is called: those that each
// batch step calls once (not the factor, called again when a lane's
// iteration slows down), so that their results need not pass through memory
// and a call between the step's dependent parts (bench/README.md, "Batches").
static int lane_inlined(const Emitter *e, const Kernel *k) {
  static const KernelId once[] = {K_SWEEP, K_MINV_P, K_ENERGY, K_G, K_PROJECT, K_LAMBDA0};
  for (size_t i = 0; i < sizeof once / sizeof once[0]; i++)
    if (k == &e->st->kern[once[i]]) return 1;
  return 0;
}

// Whether kernel k takes the lanes to skip after out[]: the rolled form's
// batch sweep, which copies a skipped lane's last results instead of
// sweeping it again (emit_rolled_batch.c).
int lane_skips(const Emitter *e, const Kernel *k) { return e->lanes && e->roll && k == &e->st->kern[K_SWEEP]; }

// The signature of kernel k (of its part-th part when part >= 0): one
// argument per input block of the Step, then the parameters and out[].
void kernel_signature(Emitter *e, const Kernel *k, int part) {
  const Step *st = e->st;
  const char *t = real_type(e, e->wide); /* the sweep of --wide-step: state, gamma, results wider */
  const char *rs = e->lanes ? "*restrict " : "*"; /* lanes: the compiler may assume no overlap */
  tmpl(e, !e->lanes ? "static void $P_" : part < 0 && lane_inlined(e, k) ? "$P_LANE_INLINE void $P_batch_" : "static void $P_batch_");
  out(e, part >= 0 ? "%s_part%d(" : "%s(", k->name, part);
  for (int i = 0; i < IN_COUNT; i++) {
    const Slots *in = &st->in[i];
    if (!in->len && i >= IN_LAM) continue; /* the inputs of one family only */
    const char *ty = in->narrow ? real_type(e, 0) : t;
    if (in->scalar) out(e, "%s %s,%s", ty, in->name, in->wrap ? "\n    " : " ");
    else out(e, "const %s %s%s,%s", ty, rs, in->name, in->wrap ? "\n    " : " ");
  }
  if (e->lanes) out(e, "const %s *restrict prm, ", t);
  else tmpl(e, "const $P_params *prm, ");
  if (part >= 0) out(e, "%s %sw, ", t, rs);
  out(e, "%s %sout", t, rs);
  if (lane_skips(e, k)) tmpl(e, ", const $M *restrict skip");
  out(e, ")\n{\n ");
  for (int i = 0; i < IN_COUNT; i++)
    if (st->in[i].len || i < IN_LAM) out(e, " (void)%s;", st->in[i].name);
  out(e, " (void)prm;%s\n", part >= 0 ? " (void)w; (void)out;" : "");
}

// Whether section sec of the DAG was built for the kernel being printed.
// Its nodes reused by another kernel (shared subexpressions) are not
// labelled there, so a label never names what that kernel does not do.
static int section_here(const Emitter *e, int sec) {
  const IntVec *own = &e->st->sec_owner;
  return sec < own->n && ((unsigned)own->v[sec] >> e->kid & 1u);
}

// Print the operations ops[from..to) of a kernel, one a line, with a comment
// where a new section of the method that belongs to it starts; values
// needed by a later part are also stored in w[].
static void emit_ops(Emitter *e, const int *ops, int from, int to) {
  const Dag *d = e->mod->dag;
  int sec = -1, shown = -1;
  const char *said = NULL; /* a section built again under the same label is not labelled twice */
  for (int i = from; i < to; i++) {
    int id = ops[i];
    while (sec + 1 < d->marks.n && d->marks.v[sec + 1] <= id) sec++;
    if (sec >= 0 && sec != shown) {
      if (section_here(e, sec) && !(said && !strcmp(said, d->labels[sec]))) {
        out(e, "%s  /* %s */\n", body_indent(e), d->labels[sec]);
        said = d->labels[sec];
      }
      shown = sec;
    }
    e->temp[id] = i;
    emit_node(e, id);
    if (e->chunk && e->slot[id] >= 0 && e->lanes) out(e, "    w[%d + l] = t%d;\n", e->slot[id] * e->lanes, i);
    else if (e->chunk && e->slot[id] >= 0) out(e, "  w[%d] = t%d;\n", e->slot[id], i);
  }
}

// out[i] = outs[i], for the outputs of the part being printed (all of
// them when the kernel is one part), each result block under its name.
static void emit_outputs(Emitter *e, const Kernel *k, const int *outs, int nouts) {
  for (int i = 0, b = 0; i < nouts; i++) {
    if (e->chunk && e->chunk[outs[i]] != e->part) continue;
    while (b + 1 < k->nout && k->out[b + 1].first <= i) b++;
    if (i == k->out[b].first || (e->chunk && i > 0 && e->chunk[outs[i - 1]] != e->part))
      out(e, "%s  /* %s */\n", body_indent(e), k->out[b].name);
    char r[NAME_SIZE];
    ref(e, outs[i], r, sizeof r);
    if (e->res) out(e, "      %s%d = %s;\n", e->res, i, r);
    else if (e->lanes) out(e, "    out[%d + l] = %s;\n", i * e->lanes, r);
    else out(e, "  out[%d] = %s;\n", i, r);
  }
}

// The values an operation reads: its operands, or for a TROW node the
// entries of its vector (the VEC chain itself is never printed).
static void operands(const Dag *d, const Node *n, IntVec *kids) {
  kids->n = 0;
  if (n->op != OP_TROW) {
    intvec_push(kids, n->a);
    intvec_push(kids, n->b);
    return;
  }
  int len = dag_vector_len(d, n->a);
  while (kids->n < len) intvec_push(kids, -1);
  dag_vector_entries(d, n->a, kids->v);
}

// Assign each operation its part, and a slot in w[] to every value used in
// a later part than its own. Returns the number of slots.
static int split_parts(Emitter *e, const int *ops, int nops) {
  const Dag *d = e->mod->dag;
  int nslots = 0;
  for (int i = 0; i < nops; i++) e->chunk[ops[i]] = i / PART_NODES;
  IntVec kids = {0};
  for (int i = 0; i < nops; i++) {
    const Node *n = &d->nodes[ops[i]];
    operands(d, n, &kids);
    for (int k = 0; k < kids.n; k++) {
      int x = kids.v[k];
      if (x >= 0 && d->nodes[x].a >= 0 && e->chunk[x] < e->chunk[ops[i]] && e->slot[x] < 0) e->slot[x] = nslots++;
    }
  }
  return nslots;
}

// The loop over the lanes around a kernel's body (open, else close); nothing
// for a scalar kernel.
static void lane_loop(Emitter *e, int open) {
  if (e->lanes && open) tmpl(e, "  for (int l = 0; l < $P_W; l++) {\n");
  else if (e->lanes) out(e, "  }\n");
}

// Print the kernel k's parts, each a function of straight-line code over
// ops[] (ops in DAG order), and the kernel calling them in order.
static void emit_parts(Emitter *e, const Kernel *k, const int *ops, int nops, const int *outs, int nouts, int top) {
  int nparts = (nops + PART_NODES - 1) / PART_NODES;
  e->chunk = xmalloc((size_t)(top + 1) * sizeof(int));
  e->slot = xmalloc((size_t)(top + 1) * sizeof(int));
  for (int id = 0; id <= top; id++) {
    e->chunk[id] = nparts - 1;
    e->slot[id] = -1;
  }
  int nslots = split_parts(e, ops, nops);
  for (e->part = 0; e->part < nparts; e->part++) {
    kernel_signature(e, k, e->part);
    int from = e->part * PART_NODES, to = from + PART_NODES < nops ? from + PART_NODES : nops;
    lane_loop(e, 1);
    emit_ops(e, ops, from, to);
    emit_outputs(e, k, outs, nouts); /* those computed in this part (leaves in the last) */
    lane_loop(e, 0);
    out(e, "}\n\n");
  }
  out(e, "/* %s: the %d parts above in order */\n", k->name, nparts);
  kernel_signature(e, k, -1);
  out(e, "  %s w[%d];\n", real_type(e, e->wide), (nslots > 0 ? nslots : 1) * (e->lanes ? e->lanes : 1)); /* C has no empty arrays */
  for (int p = 0; p < nparts; p++) {
    out(e, "  %s_%s%s_part%d(", e->P, e->lanes ? "batch_" : "", k->name, p);
    for (int i = 0; i < IN_COUNT; i++)
      if (e->st->in[i].len || i < IN_LAM) out(e, "%s, ", e->st->in[i].name);
    out(e, "prm, w, out);\n");
  }
  out(e, "}\n");
  free(e->chunk);
  free(e->slot);
  e->chunk = e->slot = NULL;
}

// The results of kernel k in out order, into a new array (to free).
static int *kernel_outs(const Kernel *k) {
  int *outs = xmalloc((size_t)(kernel_size(k) + 1) * sizeof(int));
  for (int b = 0; b < k->nout; b++)
    memcpy(outs + k->out[b].first, k->out[b].nodes, (size_t)k->out[b].len * sizeof(int));
  return outs;
}

// The operations of kernel k, in DAG order, into *ops (to free); returns
// their number. With ops NULL, only the number.
static int kernel_ops(const Emitter *e, KernelId id, int **ops) {
  const Kernel *k = &e->st->kern[id];
  const Dag *d = e->mod->dag;
  int nouts = kernel_size(k), top = -1, nops = 0, *outs = kernel_outs(k);
  for (int i = 0; i < nouts; i++)
    if (outs[i] > top) top = outs[i];
  unsigned char *mark = xcalloc((size_t)top + 2, 1);
  int *v = xmalloc((size_t)(top + 2) * sizeof(int));
  dag_reach(d, outs, nouts, mark);
  for (int i = 0; i <= top; i++) /* stage sums first: they read inputs only, and their loop runs once */
    if (mark[i] && d->nodes[i].op == OP_SSUM) v[nops++] = i;
  for (int i = 0; i <= top; i++)
    if (mark[i] && d->nodes[i].a >= 0 && d->nodes[i].op != OP_VEC && d->nodes[i].op != OP_SSUM) v[nops++] = i;
  free(outs);
  free(mark);
  if (ops) *ops = v;
  else free(v);
  return nops;
}

// The offset in out[] of kernel k's result block named name, or -1.
static int block_first(const Kernel *k, const char *name) {
  for (int b = 0; b < k->nout; b++)
    if (!strcmp(k->out[b].name, name)) return k->out[b].first;
  return -1;
}

// Whether the batch sweep prints the lane test's reductions of its results
// (emit_lane_reductions): when it is one function, so that its results are
// still at hand in its loop over the lanes (not the rolled form's, which
// runs the scalar sweep in each lane: emit_rolled_batch.c).
int sweep_reduces(const Emitter *e) {
  return e->lanes && !e->roll && kernel_ops(e, K_SWEEP, NULL) <= PART_NODES;
}

// In the batch sweep's loop over the lanes, after its results: the three
// reductions of them that the lane test after a sweep needs
// (emit_batch_step.c), each in the order the test took them, so that the
// test reads three values a lane instead of passing over the results again.
// After the N results in out[]: out[N] = max_i |q0_i| + |h gamma_0,i| (the
// scale), out[N + 1] = max_i |h (gamma_i - gam_i)| (the increment), out[N + 2]
// = the sum of r - r over the results before theta (poly) or pivot (const),
// not 0 where one of them is not finite. The increment is taken as |h| max_i
// |gamma_i - gam_i|, one product instead of one a result: the same value
// bit for bit, as rounding is monotone and symmetric, so the largest of the
// rounded |h| |d_i| is the rounded |h| times the largest |d_i|.
static void emit_lane_reductions(Emitter *e, const Kernel *k, const int *outs, int nouts) {
  int g = block_first(k, "gam"), end = block_first(k, "theta");
  const char *R = real_type(e, e->wide), *f = math_suffix(e, e->wide);
  char r[NAME_SIZE];
  if (end < 0) end = block_first(k, "pivot");
  if (end < 0) end = nouts;
  out(e, "    { /* the lane test's scale, increment and finiteness of these results */\n"
         "      %s sc = 0, inc = 0, nan = 0, v;\n", R);
  for (int i = 0; i < e->mod->m; i++) {
    ref(e, outs[g + i], r, sizeof r);
    out(e, "      v = fabs%s(q0[%d + l]) + fabs%s(h * %s);\n      sc = v > sc ? v : sc;\n", f, i * e->lanes, f, r);
  }
  for (int i = 0; i < e->me->s * e->mod->m; i++) {
    ref(e, outs[g + i], r, sizeof r);
    out(e, "      v = fabs%s(%s - gam[%d + l]);\n      inc = v > inc ? v : inc;\n", f, r, i * e->lanes);
  }
  out(e, "      inc = fabs%s(h) * inc;\n", f);
  for (int i = 0; i < end; i++) {
    ref(e, outs[i], r, sizeof r);
    out(e, "      nan += %s - %s;\n", r, r);
  }
  out(e, "      out[%d + l] = sc;\n      out[%d + l] = inc;\n      out[%d + l] = nan;\n    }\n", nouts * e->lanes,
      (nouts + 1) * e->lanes, (nouts + 2) * e->lanes);
}

// Print kernel k, computing its result blocks into out[]: straight-line
// code from the DAG, in several parts when it is large. Kernels marked wide
// compute one precision wider under --wide-step.
void emit_kernel(Emitter *e, KernelId id) {
  if (e->roll && emit_rolled_kernel(e, id)) return; /* the rolled form's loops instead (emit_rolled.c) */
  const Kernel *k = &e->st->kern[id];
  int *ops, nops = kernel_ops(e, id, &ops), nouts = kernel_size(k), top = -1;
  int *outs = kernel_outs(k);
  for (int i = 0; i < nouts; i++)
    if (outs[i] > top) top = outs[i];
  e->kid = id;
  e->vec_part = xcalloc((size_t)top + 2, sizeof *e->vec_part);
  e->loop_part = xcalloc((size_t)e->mod->dag->nloops + 1, sizeof *e->loop_part);
  e->wide = e->wide_step && k->wide;
  if (e->wide) out(e, "\n/* --wide-step: the %s below computes in %s. */", k->name, real_type(e, 1));
  out(e, "\n/* %s */\n", k->what);
  if (nops > PART_NODES) {
    emit_parts(e, k, ops, nops, outs, nouts, top);
  } else {
    kernel_signature(e, k, -1);
    lane_loop(e, 1);
    emit_ops(e, ops, 0, nops);
    emit_outputs(e, k, outs, nouts);
    if (id == K_SWEEP && sweep_reduces(e)) emit_lane_reductions(e, k, outs, nouts);
    lane_loop(e, 0);
    out(e, "}\n");
  }
  e->wide = 0;
  free(e->vec_part);
  free(e->loop_part);
  e->vec_part = e->loop_part = NULL;
  free(outs);
  free(ops);
}

// Whether kernel k is small enough, and free of tables and stage loops, to
// be printed as one block of the fused step (emit_kernel_inline, INLINE_NODES).
int kernel_inlinable(const Emitter *e, KernelId id) {
  if (e->roll) return 0; /* the rolled kernels are loops */
  int *ops, nops = kernel_ops(e, id, &ops), plain = nops <= INLINE_NODES;
  for (int i = 0; plain && i < nops; i++) /* tables and stage loops only in functions of their own */
    plain = e->mod->dag->nodes[ops[i]].op != OP_TROW && e->mod->dag->nodes[ops[i]].op != OP_SSUM;
  free(ops);
  return plain;
}

// The body of kernel k alone, for the fused step: its operations inside a
// block, inputs named by e->arg / e->local and results assigned to the
// locals e->res0, e->res1, ... Returns 0, or -1 (nothing printed) when the
// kernel is too large to gain from it (INLINE_NODES).
int emit_kernel_inline(Emitter *e, KernelId id) {
  const Kernel *k = &e->st->kern[id];
  int *ops, nops = kernel_ops(e, id, &ops);
  if (nops > INLINE_NODES) {
    free(ops);
    return -1;
  }
  int *outs = kernel_outs(k);
  e->kid = id;
  out(e, "    { /* the kernel %s, inline */\n", k->name);
  emit_ops(e, ops, 0, nops);
  emit_outputs(e, k, outs, kernel_size(k));
  out(e, "    }\n");
  free(outs);
  free(ops);
  return 0;
}
