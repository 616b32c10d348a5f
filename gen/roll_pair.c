/* roll_pair.c - pair sums for the rolled form (docs/rolled.md, "Pair sums").
 *
 * A pair potential, U = sum(i in 1..N, j in i + 1..N, phi(...)), makes
 * dU/dq_i a sum over all the other particles, in other places relative to i
 * at every i: the per-coordinate families of roll.c cannot roll it. Here U's
 * terms are rolled instead, and grad U is scattered from them, as molecular
 * dynamics codes do: one double loop over the pairs computes each pair's term
 * and its partial derivatives once and adds them into grad U at both ends.
 *   - U's terms (in the order of its sums) are cut into items of P
 *     consecutive terms, P the period of the pair sum's body (4 for the atom
 *     pairs of two diatomics): the P of 1..ROLL_PAIR_MAX_PERIOD that gives
 *     the fewest runs;
 *   - each input of an item is tied to the outer index b or the inner one
 *     c: against the next item of the same inner loop, the inputs that stay
 *     are tied to b, those that move (all by the same stride) to c. A run is
 *     a triangle of items, b = B0, B0 + SB, .. B1 and for each b c = b + D,
 *     b + D + SC, .. CE, each the first item's expression with its inputs
 *     shifted with b or c;
 *   - the first item of a run is differentiated (ad.c) once, and its value
 *     and gradient walked together as the run's body, which
 *     emit_rolled_pairs.c prints once, as a double loop.
 * A one-body sum (every input moves) is a run with one b; what is left over
 * is runs of one item. More than ROLL_MAX_RUNS runs, or fewer than two items
 * a run on average (no repetition): not rolled. */
#include <stdlib.h>
#include <string.h>

#include "roll.h"

#define ROLL_PAIR_MAX_PERIOD 8
#define ROLL_PAIR_MAX_BODY 4096 /* nodes of one item */

/* One node of a walked item: op, operands as places, and a leaf's value. */
typedef struct {
  int op, a, b, idx; /* idx: an input's slot, a param's number */
  double val;
} PCode;

typedef struct {
  PCode *code;
  int n;
} PItem;

typedef struct {
  Dag *d;
  int epoch, room;
  int *stamp, *local;
  IntVec order, stack;
} PairWalk;

// Walk roots[0..n) together into w->order (post-order, shared nodes once);
// -1 when it is too large or holds what the rolled form cannot print.
static int walk_roots(PairWalk *w, const int *roots, int n) {
  if (w->room < w->d->n) {
    w->stamp = xrealloc(w->stamp, (size_t)w->d->n * sizeof(int));
    w->local = xrealloc(w->local, (size_t)w->d->n * sizeof(int));
    memset(w->stamp + w->room, 0, (size_t)(w->d->n - w->room) * sizeof(int));
    w->room = w->d->n;
  }
  w->epoch++;
  w->order.n = w->stack.n = 0;
  for (int r = 0; r < n; r++) {
    intvec_push(&w->stack, roots[r] * 2);
    while (w->stack.n) {
      int x = w->stack.v[--w->stack.n], id = x >> 1;
      const Node *nd = &w->d->nodes[id];
      if (x & 1) {
        w->local[id] = w->order.n;
        intvec_push(&w->order, id);
      } else if (w->stamp[id] != w->epoch) {
        if (nd->op == OP_TROW || nd->op == OP_VEC || nd->op == OP_SSUM || w->order.n > ROLL_PAIR_MAX_BODY) return -1;
        w->stamp[id] = w->epoch;
        intvec_push(&w->stack, id * 2 + 1);
        if (nd->b >= 0 && w->stamp[nd->b] != w->epoch) intvec_push(&w->stack, nd->b * 2);
        if (nd->a >= 0 && w->stamp[nd->a] != w->epoch) intvec_push(&w->stack, nd->a * 2);
      }
    }
  }
  return 0;
}

// The walked nodes as an item's code (operands as places).
static PItem item_code(const PairWalk *w) {
  PItem it = {xmalloc((size_t)(w->order.n + 1) * sizeof(PCode)), w->order.n};
  for (int k = 0; k < w->order.n; k++) {
    const Node *nd = &w->d->nodes[w->order.v[k]];
    it.code[k] = (PCode){nd->op, nd->a >= 0 ? w->local[nd->a] : -1, nd->b >= 0 ? w->local[nd->b] : -1,
                         nd->op == OP_INPUT || nd->op == OP_PARAM ? nd->idx : 0, nd->op == OP_CONST ? nd->val : 0};
  }
  return it;
}

// Whether two items are the same expression but for their input slots.
static int same_shape(const PItem *x, const PItem *y) {
  if (x->n != y->n) return 0;
  for (int k = 0; k < x->n; k++) {
    const PCode *a = &x->code[k], *b = &y->code[k];
    if (a->op != b->op || a->a != b->a || a->b != b->b || memcmp(&a->val, &b->val, sizeof a->val) ||
        (a->op != OP_INPUT && a->idx != b->idx))
      return 0;
  }
  return 1;
}

// The inner stride from item x to item y (same shape): the one nonzero
// shift of their inputs, tie[k] = 1 for the inputs it moves and 0 for those
// that stay; 0 when none moves or the shifts differ.
static int inner_stride(const PItem *x, const PItem *y, char *tie) {
  int step = 0;
  for (int k = 0; k < x->n; k++) {
    if (x->code[k].op != OP_INPUT) continue;
    int delta = y->code[k].idx - x->code[k].idx;
    tie[k] = delta != 0;
    if (delta && step && delta != step) return 0;
    if (delta) step = delta;
  }
  return step > 0 ? step : 0;
}

/* A run being found: its shape's ties and the triangle's parameters. */
typedef struct {
  char *tie;               /* per place of the first item: an input tied to c (1) or b (0) */
  int ki, kj;              /* places of the first input tied to b, to c (-1: none) */
  int B0, SB, D, CE, SC;   /* SB, CE: 0, -1 until the first change of b */
} Tri;

static int base_b(const Tri *t, const PItem *x) { return t->ki >= 0 ? x->code[t->ki].idx : t->B0; }
static int base_c(const Tri *t, const PItem *x) { return t->kj >= 0 ? x->code[t->kj].idx : base_b(t, x); }

// Whether item y continues the run t after item prev (first: the run's
// first item): its inputs shifted with b or c, and its (b, c) next in the
// triangle. Fixes SB and CE at the first change of b.
static int continues(Tri *t, const PItem *first, const PItem *prev, const PItem *y) {
  if (!same_shape(first, y)) return 0;
  int b = base_b(t, y), c = base_c(t, y), b1 = base_b(t, first), c1 = base_c(t, first);
  for (int k = 0; k < y->n; k++)
    if (y->code[k].op == OP_INPUT && y->code[k].idx - first->code[k].idx != (t->tie[k] ? c - c1 : b - b1)) return 0;
  int pb = base_b(t, prev), pc = base_c(t, prev);
  if (b == pb) return c == pc + t->SC && (t->CE < 0 || c <= t->CE);
  if (t->ki < 0 || b <= pb || c != b + t->D || (t->CE >= 0 && pc != t->CE) || (t->SB && b - pb != t->SB)) return 0;
  if (t->CE < 0) t->CE = pc;
  t->SB = b - pb;
  return 1;
}

/* A run found: its first item, length and triangle. */
typedef struct {
  int u0, n;
  Tri t;
} PRun;

// The run starting at item u: the longest triangle of items from it, or
// the item alone (every input tied to b).
static PRun find_run(const PItem *items, int n, int u) {
  const PItem *x = &items[u];
  PRun r = {u, 1, {xcalloc((size_t)x->n + 1, 1), -1, -1, 0, 0, 0, -1, 1}};
  int sc = u + 1 < n && same_shape(x, &items[u + 1]) ? inner_stride(x, &items[u + 1], r.t.tie) : 0;
  if (!sc) memset(r.t.tie, 0, (size_t)x->n + 1);
  for (int k = 0; k < x->n; k++)
    if (x->code[k].op == OP_INPUT) {
      if (!r.t.tie[k] && r.t.ki < 0) r.t.ki = k;
      if (r.t.tie[k] && r.t.kj < 0) r.t.kj = k;
    }
  r.t.B0 = r.t.ki >= 0 ? x->code[r.t.ki].idx : r.t.kj >= 0 ? x->code[r.t.kj].idx : 0;
  r.t.D = base_c(&r.t, x) - base_b(&r.t, x);
  if (sc) {
    r.t.SC = sc;
    while (u + r.n < n && continues(&r.t, x, &items[u + r.n - 1], &items[u + r.n])) r.n++;
    if (r.t.CE >= 0 && base_c(&r.t, &items[u + r.n - 1]) != r.t.CE) { /* the last b is partial: not in the run */
      int last_b = base_b(&r.t, &items[u + r.n - 1]);
      while (base_b(&r.t, &items[u + r.n - 1]) == last_b) r.n--;
    }
  }
  if (r.t.CE < 0) r.t.CE = base_c(&r.t, &items[u + r.n - 1]);
  return r;
}

// The runs of the items, at most ROLL_MAX_RUNS + 1 (then it stops).
static int item_runs(const PItem *items, int n, PRun *runs) {
  int nruns = 0;
  for (int u = 0; u < n && nruns <= ROLL_MAX_RUNS; u += runs[nruns - 1].n) runs[nruns++] = find_run(items, n, u);
  return nruns;
}

// The items of period p: each p consecutive terms walked together.
static int period_items(PairWalk *w, const int *terms, int nterms, int p, PItem *items) {
  for (int u = 0; u < nterms / p; u++) {
    items[u] = (PItem){NULL, 0};
    if (walk_roots(w, terms + u * p, p) < 0) return -1;
    items[u] = item_code(w);
  }
  return 0;
}

static void free_found(PItem *items, int nitems, PRun *runs, int nruns) {
  for (int u = 0; u < nitems; u++) free(items[u].code);
  for (int i = 0; i < nruns; i++) free(runs[i].t.tie);
  free(items);
  free(runs);
}

// The base (0: b, 1: c) and offset of input slot `slot` of run r's first
// item (first): where the item reads it.
static void input_place(const PRun *r, const PItem *first, int slot, int *base, int *off) {
  for (int k = 0; k < first->n; k++)
    if (first->code[k].op == OP_INPUT && first->code[k].idx == slot) {
      *base = r->t.kj >= 0 && r->t.tie[k];
      *off = slot - (*base ? base_c(&r->t, first) : base_b(&r->t, first));
      return;
    }
  internal_error("a pair run's gradient reads slot %d outside its item", slot);
}

// The body of run r (terms: its first item's p terms): their sum and its
// gradient walked together, each input with its base and offset.
static void run_body(PairWalk *w, const PRun *r, const PItem *items, const int *terms, int p, int m, RollPairRun *out) {
  Dag *d = w->d;
  const PItem *first = &items[r->u0];
  int value = terms[0];
  for (int k = 1; k < p; k++) value = dag_add(d, value, terms[k]);
  SparseVec gr;
  ad_gradient_sparse(d, value, m, &gr);
  int *roots = step_nodes(gr.n + 1);
  roots[0] = value;
  for (int e = 0; e < gr.n; e++) roots[e + 1] = gr.e[e].node;
  if (walk_roots(w, roots, gr.n + 1) < 0) internal_error("a pair run's body cannot be walked");
  int n = w->order.n;
  *out = (RollPairRun){r->n, r->t.B0, base_b(&r->t, &items[r->u0 + r->n - 1]), r->t.SB ? r->t.SB : 1, r->t.D, r->t.CE,
                       r->t.SC, step_nodes(n), n, step_nodes(n), step_nodes(n), w->local[value], gr.n,
                       step_nodes(gr.n + 1), step_nodes(gr.n + 1), step_nodes(gr.n + 1)};
  memcpy(out->body, w->order.v, (size_t)n * sizeof(int));
  for (int k = 0; k < n; k++)
    if (d->nodes[out->body[k]].op == OP_INPUT) input_place(r, first, d->nodes[out->body[k]].idx, &out->base[k], &out->off[k]);
  for (int e = 0; e < gr.n; e++) {
    out->gplace[e] = w->local[gr.e[e].node];
    input_place(r, first, gr.e[e].coord, &out->gbase[e], &out->goff[e]);
  }
}

// Append the terms of the sum at node id, times scale, to *terms: through
// additions, subtractions (a negated term) and a constant factor of a sum
// (2^e floats up a sum of scaled terms: dag.c), each term as its own node.
static void sum_terms(Dag *d, int id, double scale, IntVec *terms) {
  const Node *n = &d->nodes[id];
  int k = n->op == OP_MUL ? (d->nodes[n->a].op == OP_CONST ? n->a : d->nodes[n->b].op == OP_CONST ? n->b : -1) : -1;
  int x = k < 0 ? -1 : k == n->a ? n->b : n->a;
  if (n->op == OP_ADD || n->op == OP_SUB) {
    int a = n->a, b = n->b, sub = n->op == OP_SUB; /* n moves when the DAG grows */
    sum_terms(d, a, scale, terms);
    sum_terms(d, b, sub ? -scale : scale, terms);
  } else if (x >= 0 && (d->nodes[x].op == OP_ADD || d->nodes[x].op == OP_SUB)) {
    double c = d->nodes[k].val;
    sum_terms(d, x, scale * c, terms);
  } else {
    intvec_push(terms, scale == 1 ? id : dag_mul(d, dag_const(d, scale), id));
  }
}

RollPairs *roll_pairs(Dag *d, int m, int U) {
  IntVec all = {0};
  sum_terms(d, U, 1, &all);
  const int *terms = all.v;
  int nterms = all.n;
  PairWalk w = {d, 0, 0, NULL, NULL, {0}, {0}};
  PItem *best_items = NULL;
  PRun *best_runs = NULL;
  int best_p = 0, best_n = ROLL_MAX_RUNS + 1;
  for (int p = 1; p <= ROLL_PAIR_MAX_PERIOD && p <= nterms; p++) {
    if (nterms % p) continue;
    PItem *items = xcalloc((size_t)(nterms / p), sizeof *items);
    PRun *runs = xcalloc(ROLL_MAX_RUNS + 1, sizeof *runs);
    int nruns = period_items(&w, terms, nterms, p, items) < 0 ? ROLL_MAX_RUNS + 1 : item_runs(items, nterms / p, runs);
    if (nruns < best_n) {
      if (best_items) free_found(best_items, nterms / best_p, best_runs, best_n);
      best_items = items, best_runs = runs, best_p = p, best_n = nruns;
    } else {
      free_found(items, nterms / p, runs, nruns);
    }
  }
  RollPairs *rp = NULL;
  if (best_items && 2 * best_n > nterms / best_p) { /* runs of one or two items: no repetition to roll */
    free_found(best_items, nterms / best_p, best_runs, best_n);
    best_items = NULL;
  }
  if (best_items) {
    rp = arena_alloc(sizeof *rp);
    *rp = (RollPairs){best_p, nterms / best_p, best_n, arena_alloc((size_t)best_n * sizeof(RollPairRun))};
    for (int i = 0; i < best_n; i++)
      run_body(&w, &best_runs[i], best_items, terms + best_runs[i].u0 * best_p, best_p, m, &rp->runs[i]);
    free_found(best_items, nterms / best_p, best_runs, best_n);
  }
  free(w.stamp);
  free(w.local); /* order and stack are in the arena */
  return rp;
}
