/* emit_rolled_pairs.c - U and grad U of a pair sum in the rolled form: the
 * runs of roll_pair.c as double loops over the pairs (docs/rolled.md, "Pair
 * sums").
 *
 * Each run prints once, as
 *     for (b = B0; b <= B1; b += SB)
 *       for (c = b + D; c <= CE; c += SC) { body; out[b + o] += dU/dq_(b+o); ... }
 * with the body's inputs q[b + o] and q[c + o]: each pair's term and its
 * partial derivatives are computed once and grad U is scattered from them
 * (both ends of the pair), so grad U sums a coordinate's pair forces in the
 * order of the pairs, not in the straight-line order (round-off). A run of
 * one item prints as one block. Only the places the printed results need
 * are printed (the value for U, the gradient for grad U). */
#include <stdlib.h>
#include <string.h>

#include "emit.h"
#include "roll.h"

#define NAME_SIZE 256

// The place of node id in run r's body (it is there: the body is closed).
static int place_of(const RollPairRun *r, int id) {
  for (int k = r->nbody - 1; k >= 0; k--)
    if (r->body[k] == id) return k;
  internal_error("a pair body reads node %d outside it", id);
  return -1;
}

// "array[b + off]" or "array[c + off]" (base 1) into buf.
static void pair_index(char *buf, size_t size, const char *array, int base, int off) {
  char at = base ? 'c' : 'b';
  if (off) snprintf(buf, size, "%s[%c %c %d]", array, at, off < 0 ? '-' : '+', off < 0 ? -off : off);
  else snprintf(buf, size, "%s[%c]", array, at);
}

// The C name of place k of run r: a literal, a param, an input at its
// offset from b or c, or the temporary rK.
static void pair_name(Emitter *e, const RollPairRun *r, int k, char *buf, size_t size) {
  const Node *n = &e->mod->dag->nodes[r->body[k]];
  if (n->op == OP_CONST) format_real(e, buf, size, n->val);
  else if (n->op == OP_PARAM) snprintf(buf, size, "prm->%s", e->mod->params[n->idx].name);
  else if (n->op == OP_INPUT) pair_index(buf, size, "q", r->base[k], r->off[k]);
  else snprintf(buf, size, "r%d", k);
}

// Mark in need[] the places the results (roots[0..n)) are computed from.
static void mark_needed(const Dag *d, const RollPairRun *r, const int *roots, int n, char *need) {
  for (int i = 0; i < n; i++) need[roots[i]] = 1;
  for (int k = r->nbody - 1; k >= 0; k--) {
    const Node *nd = &d->nodes[r->body[k]];
    if (!need[k]) continue;
    if (nd->a >= 0) need[place_of(r, nd->a)] = 1;
    if (nd->b >= 0) need[place_of(r, nd->b)] = 1;
  }
}

// One run: its loops, the needed temporaries, and acc += its value
// (value) or out[...] += its gradient.
static void emit_pair_run(Emitter *e, const RollPairRun *r, int value) {
  const Dag *d = e->mod->dag;
  char a[NAME_SIZE], b[NAME_SIZE], rhs[8 * NAME_SIZE];
  char *need = xcalloc((size_t)r->nbody + 1, 1);
  mark_needed(d, r, value ? &r->value : r->gplace, value ? 1 : r->ngrad, need);
  if (r->nitems == 1) out(e, "  b = %d;\n  c = %d;\n  { /* one item */\n", r->B0, r->B0 + r->D);
  else
    out(e, "  for (b = %d; b <= %d; b += %d) /* %d items */\n    for (c = b + %d; c <= %d; c += %d) {\n", r->B0, r->B1,
        r->SB, r->nitems, r->D, r->CE, r->SC);
  for (int k = 0; k < r->nbody; k++) {
    const Node *n = &d->nodes[r->body[k]];
    if (!need[k] || n->a < 0) continue; /* leaves are named where they are read */
    pair_name(e, r, place_of(r, n->a), a, sizeof a);
    if (n->b >= 0) pair_name(e, r, place_of(r, n->b), b, sizeof b);
    op_rhs(e, n, a, b, rhs, sizeof rhs);
    out(e, "      const %s r%d = %s;\n", real_type(e, 0), k, rhs);
  }
  if (value) {
    pair_name(e, r, r->value, a, sizeof a);
    out(e, "      acc += %s;\n", a);
  }
  for (int g = 0; !value && g < r->ngrad; g++) {
    pair_name(e, r, r->gplace[g], a, sizeof a);
    pair_index(b, sizeof b, "out", r->gbase[g], r->goff[g]);
    out(e, "      %s += %s;\n", b, a);
  }
  out(e, "    }\n");
  free(need);
}

void emit_roll_pairs(Emitter *e, const char *name, const char *what, int value) {
  const RollPairs *p = e->roll->pairs;
  tmplf(e, "\n/* %s: U's pair sums as %d runs of items of %d terms, loops over the pairs (b, c) */\n"
           "static void $P_roll_%s(const $R *q, const $R *v, const $P_params *prm, $R *out)\n{\n"
           "  int b = 0, c = 0;\n%s  (void)q; (void)v; (void)prm;\n", what, p->nruns, p->period, name,
        value ? "  $R acc = 0;\n" : "");
  if (!value) out(e, "  for (b = 0; b < %d; b++) out[b] = 0;\n", e->mod->m);
  for (int i = 0; i < p->nruns; i++) emit_pair_run(e, &p->runs[i], value);
  out(e, value ? "  (void)b; (void)c;\n  out[0] = acc;\n}\n" : "  (void)b; (void)c;\n}\n");
}
