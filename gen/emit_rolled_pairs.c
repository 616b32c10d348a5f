/* emit_rolled_pairs.c - U and grad U of a pair sum in the rolled form: the
 * runs of roll_pair.c as double loops over the pairs (docs/rolled.md, "Pair
 * sums").
 *
 * Each run prints once, as
 *     for (b = B0; b <= B1; b += SB) {
 *       rK = what reads only q[b + o];  gK = out[b + o];
 *       for (c = b + D; c + SC <= CE; c += 2 SC) {   two pairs, c and c2 = c + SC
 *         body(c); body(c2); gK += dU/dq_(b+o); out[c + o] += dU/dq_(c+o); ... (c, then c2)
 *       }
 *       if (c <= CE) { body(c); ... }                the odd one
 *       out[b + o] = gK;
 *     }
 * with the body's other inputs q[c + o]: each pair's term and its partial
 * derivatives are computed once and grad U is scattered from them (both
 * ends of the pair), so grad U sums a coordinate's pair forces in the order
 * of the pairs, not in the straight-line order (round-off). The hoisting,
 * the locals gK and the two pairs a pass keep that order (the same sums as
 * the plain double loop, bit for bit); they take the row's invariants and
 * its gradient at b out of the inner loop, and set the two pairs' operations
 * side by side so that gcc -O2 pairs them in vector registers (the
 * straight-line step is vectorised that way). q and out are restrict: the
 * callers pass distinct arrays. A run of one item prints as one block. Only
 * the places the printed results need are printed (the value for U, the
 * gradient for grad U). */
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

// "array[at + off]" into buf (at: the index b, c or c2).
static void pair_index(char *buf, size_t size, const char *array, const char *at, int off) {
  if (off) snprintf(buf, size, "%s[%s %c %d]", array, at, off < 0 ? '-' : '+', off < 0 ? -off : off);
  else snprintf(buf, size, "%s[%s]", array, at);
}

/* How a run's loop nest prints: per place, whether it is printed (need),
 * whether it reads only inputs tied to b (inv: the same for every c of a
 * row, computed once before the inner loop), and per gradient entry tied
 * to b whether it is summed in a local over the row (acc). */
typedef struct {
  const RollPairRun *r;
  char *need, *inv, *acc;
} PairPlan;

// The C name of place k in copy `copy` of the body (0: pair c, 1: pair
// c2 = c + SC): a literal, a param, an input (q[b + o], q[c + o] or q[c2 +
// o]; an input at b hoisted is a temporary), or a temporary (rK for the
// hoisted places and copy 0, sK for copy 1).
static void pair_name(Emitter *e, const PairPlan *pl, int k, int copy, char *buf, size_t size) {
  const RollPairRun *r = pl->r;
  const Node *n = &e->mod->dag->nodes[r->body[k]];
  if (n->op == OP_CONST) format_real(e, buf, size, n->val);
  else if (n->op == OP_PARAM) snprintf(buf, size, "prm->%s", e->mod->params[n->idx].name);
  else if (n->op == OP_INPUT && !pl->inv[k]) pair_index(buf, size, "q", !r->base[k] ? "b" : copy ? "c2" : "c", r->off[k]);
  else snprintf(buf, size, "%c%d", copy && !pl->inv[k] ? 's' : 'r', k);
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

// Mark in inv[] the places that read no input tied to c.
static void mark_invariant(const Dag *d, const RollPairRun *r, char *inv) {
  for (int k = 0; k < r->nbody; k++) {
    const Node *n = &d->nodes[r->body[k]];
    if (n->op == OP_INPUT) inv[k] = !r->base[k];
    else inv[k] = (n->a < 0 || inv[place_of(r, n->a)]) && (n->b < 0 || inv[place_of(r, n->b)]);
  }
}

// Mark in acc[] the gradient entries tied to b: summed in a local over the
// row, in the same order, as out[b + o] is never an out[c + o'] of the row
// (the item of that pair would read one input in both places, which no run
// holds: its shape would differ; checked).
static void mark_accumulated(const RollPairRun *r, char *acc) {
  for (int g = 0; g < r->ngrad; g++) {
    acc[g] = !r->gbase[g];
    for (int h = 0; h < r->ngrad && acc[g]; h++) {
      int delta = r->goff[g] - r->goff[h]; /* c - b where out[b + goff[g]] is out[c + goff[h]] */
      if (r->gbase[h] && delta >= r->D && delta <= r->CE - r->B0 && (delta - r->D) % r->SC == 0)
        internal_error("a pair run adds to out[b %+d] from c", r->goff[g]);
    }
  }
}

// Print the needed places that are (hoisted 1) or are not (0) invariant,
// in copy `copy`, indented by ind.
static void emit_places(Emitter *e, const PairPlan *pl, int hoisted, int copy, const char *ind) {
  const RollPairRun *r = pl->r;
  const Dag *d = e->mod->dag;
  char a[NAME_SIZE], b[NAME_SIZE], name[NAME_SIZE], rhs[8 * NAME_SIZE];
  for (int k = 0; k < r->nbody; k++) {
    const Node *n = &d->nodes[r->body[k]];
    if (!pl->need[k] || pl->inv[k] != hoisted || (n->a < 0 && !(hoisted && n->op == OP_INPUT))) continue;
    pair_name(e, pl, k, copy, name, sizeof name);
    if (n->op == OP_INPUT) {
      pair_index(rhs, sizeof rhs, "q", "b", r->off[k]);
    } else {
      pair_name(e, pl, place_of(r, n->a), copy, a, sizeof a);
      if (n->b >= 0) pair_name(e, pl, place_of(r, n->b), copy, b, sizeof b);
      op_rhs(e, n, a, b, rhs, sizeof rhs);
    }
    out(e, "%sconst %s %s = %s;\n", ind, real_type(e, 0), name, rhs);
  }
}

// Print what copy `copy` of the body adds: acc += its value (value), or
// its gradient into out[c + o], and into out[b + o] or its local gK.
static void emit_updates(Emitter *e, const PairPlan *pl, int value, int copy, const char *ind) {
  const RollPairRun *r = pl->r;
  char a[NAME_SIZE], b[NAME_SIZE];
  if (value) {
    pair_name(e, pl, r->value, copy, a, sizeof a);
    out(e, "%sacc += %s;\n", ind, a);
  }
  for (int g = 0; !value && g < r->ngrad; g++) {
    pair_name(e, pl, r->gplace[g], copy, a, sizeof a);
    if (pl->acc[g]) snprintf(b, sizeof b, "g%d", g);
    else pair_index(b, sizeof b, "out", r->gbase[g] ? (copy ? "c2" : "c") : "b", r->goff[g]);
    out(e, "%s%s += %s;\n", ind, b, a);
  }
}

// One run: acc += its value (value) or out[...] += its gradient. A run of
// several items is the double loop over the pairs (b, c): per row, the
// places that read only b are computed once and the gradient at b is
// summed in locals (gK); the inner loop takes two pairs, c and c2 = c + SC,
// a pass (their expressions side by side, so that the compiler can pair
// their operations in vector registers) and one more when the row is odd.
// Every sum adds in the order of the pairs, as the plain double loop does.
static void emit_pair_run(Emitter *e, const RollPairRun *r, int value) {
  const Dag *d = e->mod->dag;
  PairPlan pl = {r, xcalloc((size_t)r->nbody + 1, 1), xcalloc((size_t)r->nbody + 1, 1), xcalloc((size_t)r->ngrad + 1, 1)};
  mark_needed(d, r, value ? &r->value : r->gplace, value ? 1 : r->ngrad, pl.need);
  mark_invariant(d, r, pl.inv);
  if (!value) mark_accumulated(r, pl.acc);
  if (r->nitems == 1) {
    out(e, "  b = %d;\n  c = %d;\n  { /* one item */\n", r->B0, r->B0 + r->D);
    memset(pl.acc, 0, (size_t)r->ngrad); /* nothing to hoist out of one pair */
    memset(pl.inv, 0, (size_t)r->nbody);
    emit_places(e, &pl, 0, 0, "    ");
    emit_updates(e, &pl, value, 0, "    ");
    out(e, "  }\n");
  } else {
    out(e, "  for (b = %d; b <= %d; b += %d) { /* %d items */\n", r->B0, r->B1, r->SB, r->nitems);
    emit_places(e, &pl, 1, 0, "    ");
    for (int g = 0; g < r->ngrad; g++)
      if (pl.acc[g]) {
        char at[NAME_SIZE];
        pair_index(at, sizeof at, "out", "b", r->goff[g]);
        out(e, "    %s g%d = %s;\n", real_type(e, 0), g, at);
      }
    out(e, "    for (c = b + %d; c + %d <= %d; c += %d) {\n      const int c2 = c + %d;\n", r->D, r->SC, r->CE,
        2 * r->SC, r->SC);
    emit_places(e, &pl, 0, 0, "      ");
    emit_places(e, &pl, 0, 1, "      ");
    emit_updates(e, &pl, value, 0, "      ");
    emit_updates(e, &pl, value, 1, "      ");
    out(e, "    }\n    if (c <= %d) {\n", r->CE);
    emit_places(e, &pl, 0, 0, "      ");
    emit_updates(e, &pl, value, 0, "      ");
    out(e, "    }\n");
    for (int g = 0; g < r->ngrad; g++)
      if (pl.acc[g]) {
        char at[NAME_SIZE];
        pair_index(at, sizeof at, "out", "b", r->goff[g]);
        out(e, "    %s = g%d;\n", at, g);
      }
    out(e, "  }\n");
  }
  free(pl.need);
  free(pl.inv);
  free(pl.acc);
}

void emit_roll_pairs(Emitter *e, const char *name, const char *what, int value) {
  const RollPairs *p = e->roll->pairs;
  tmplf(e, "\n/* %s: U's pair sums as %d runs of items of up to %d terms, loops over the pairs (b, c) */\n"
           "static void $P_roll_%s(const $R *restrict q, const $R *v, const $P_params *prm, $R *restrict out)\n{\n"
           "  int b = 0, c = 0;\n%s  (void)q; (void)v; (void)prm;\n", what, p->nruns, p->period, name,
        value ? "  $R acc = 0;\n" : "");
  if (!value) out(e, "  for (b = 0; b < %d; b++) out[b] = 0;\n", e->mod->m);
  for (int i = 0; i < p->nruns; i++) emit_pair_run(e, &p->runs[i], value);
  out(e, value ? "  (void)b; (void)c;\n  out[0] = acc;\n}\n" : "  (void)b; (void)c;\n}\n");
}
