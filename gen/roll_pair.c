/* roll_pair.c - pair sums for the rolled form (docs/rolled.md, "Pair sums").
 *
 * A pair potential, U = sum(i in 1..N, j in i + 1..N, phi(...)), makes
 * dU/dq_i a sum over all the other particles, in other places relative to i
 * at every i: the per-coordinate families of roll.c cannot roll it. Here U's
 * terms are rolled instead, and grad U is scattered from them, as molecular
 * dynamics codes do: one double loop over the pairs computes each pair's term
 * and its partial derivatives once and adds them into grad U at both ends.
 *   - U's terms (in the order of its sums) are cut into runs of items of P
 *     consecutive terms, P the period of the run's body (8 for the atom
 *     pairs of two diatomics, whose four phi give two terms each): from the
 *     first term not in a run, the P of 1..ROLL_PAIR_MAX_PERIOD whose run
 *     covers the most terms (the largest on a tie), so that a one-body sum
 *     (a trap) and the pair sum after it each have their own period;
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

/* The items of period p from term t0 on, walked as far as a run needs them:
 * item u is terms t0 + u p .. t0 + (u + 1) p - 1; n of the avail are built. */
typedef struct {
  PairWalk *w;
  const int *terms;
  int t0, p, avail, n, cap;
  PItem *v;
} PItems;

// Whether item u of it exists and is built (walked now if not): 0 past the
// terms or when it cannot be walked (too large, or what the rolled form
// cannot print).
static int has_item(PItems *it, int u) {
  if (u >= it->avail) return 0;
  for (; it->n <= u; it->n++) {
    if (walk_roots(it->w, it->terms + it->t0 + it->n * it->p, it->p) < 0) {
      it->avail = it->n; /* the items end before it */
      return 0;
    }
    if (it->n == it->cap) it->v = xrealloc(it->v, (size_t)(it->cap = 2 * it->cap + 8) * sizeof *it->v);
    it->v[it->n] = item_code(it->w);
  }
  return 1;
}

// The run starting at the first item of it (built): the longest triangle
// of items from it, or the item alone (every input tied to b).
static PRun find_run(PItems *it) {
  const PItem *x = &it->v[0];
  PRun r = {0, 1, {xcalloc((size_t)x->n + 1, 1), -1, -1, 0, 0, 0, -1, 1}};
  int sc = has_item(it, 1) && same_shape(&it->v[0], &it->v[1]) ? inner_stride(&it->v[0], &it->v[1], r.t.tie) : 0;
  x = &it->v[0]; /* has_item may move the items */
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
    while (has_item(it, r.n) && continues(&r.t, &it->v[0], &it->v[r.n - 1], &it->v[r.n])) r.n++;
    if (r.t.CE >= 0 && base_c(&r.t, &it->v[r.n - 1]) != r.t.CE) { /* the last b is partial: not in the run */
      int last_b = base_b(&r.t, &it->v[r.n - 1]);
      while (base_b(&r.t, &it->v[r.n - 1]) == last_b) r.n--;
    }
  }
  if (r.t.CE < 0) r.t.CE = base_c(&r.t, &it->v[r.n - 1]);
  return r;
}

static void free_items(PItems *it) {
  for (int u = 0; u < it->n; u++) free(it->v[u].code);
  free(it->v);
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

/* A run chosen: its items (period p from term t0) and triangle. */
typedef struct {
  PItems items;
  PRun run;
} PChosen;

// The run at term t: of the periods 1..ROLL_PAIR_MAX_PERIOD, the one whose
// run from t covers the most terms (the longest on a tie: fewer items);
// 0, or -1 when no item at t can be walked.
static int choose_run(PairWalk *w, const int *terms, int nterms, int t, PChosen *out) {
  int best = 0;
  for (int p = 1; p <= ROLL_PAIR_MAX_PERIOD && t + p <= nterms; p++) {
    PItems it = {w, terms, t, p, (nterms - t) / p, 0, 0, NULL};
    if (!has_item(&it, 0)) {
      free_items(&it);
      continue;
    }
    PRun r = find_run(&it);
    if (r.n * p >= best) {
      if (best) free_items(&out->items), free(out->run.t.tie);
      *out = (PChosen){it, r};
      best = r.n * p;
    } else {
      free_items(&it);
      free(r.t.tie);
    }
  }
  return best ? 0 : -1;
}

RollPairs *roll_pairs(Dag *d, int m, int U) {
  IntVec all = {0};
  sum_terms(d, U, 1, &all);
  const int *terms = all.v;
  int nterms = all.n, nruns = 0, nitems = 0, bad = 0;
  PairWalk w = {d, 0, 0, NULL, NULL, {0}, {0}};
  PChosen *runs = xcalloc(ROLL_MAX_RUNS + 1, sizeof *runs);
  for (int t = 0; t < nterms && !bad; t += runs[nruns - 1].run.n * runs[nruns - 1].items.p) {
    if (nruns == ROLL_MAX_RUNS || choose_run(&w, terms, nterms, t, &runs[nruns]) < 0) bad = 1;
    else nitems += runs[nruns++].run.n;
  }
  RollPairs *rp = NULL;
  if (!bad && 2 * nruns <= nitems) { /* else runs of one or two items: no repetition to roll */
    rp = arena_alloc(sizeof *rp);
    *rp = (RollPairs){0, nitems, nruns, arena_alloc((size_t)nruns * sizeof(RollPairRun))};
    for (int i = 0; i < nruns; i++) {
      const PChosen *c = &runs[i];
      run_body(&w, &c->run, c->items.v, terms + c->items.t0, c->items.p, m, &rp->runs[i]);
      if (c->items.p > rp->period) rp->period = c->items.p;
    }
  }
  for (int i = 0; i < nruns; i++) {
    free_items(&runs[i].items);
    free(runs[i].run.t.tie);
  }
  free(runs);
  free(w.stamp);
  free(w.local); /* order and stack are in the arena */
  return rp;
}
