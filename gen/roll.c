/* roll.c - find the repetition of a model's index, for the rolled form.
 *
 * The front end expands `variables x[N]`, `sum(... for i in a..b)` and
 * comprehensions into N copies, and the derivatives of the model are N
 * copies too. This pass rolls them up again, the way a compiler's loop
 * reroller does, on the analysed model rather than on its syntax, so that it
 * does not matter how the user wrote the repetition (a comprehension, a sum
 * or a list):
 *   - the items of a family (dU/dq_i for each coordinate i, the Jacobian
 *     entries d g_c / dq_i, the constraints g_a, the terms of U, the
 *     curvatures v' Hess(g_a) v) are each walked once, in post-order, and
 *     encoded with every input written as its offset from the item's base
 *     index (the coordinate i, or the lowest coordinate the item reads);
 *   - consecutive items with the same code whose bases step by a constant
 *     stride form a run: one loop body, printed once by emit_rolled.c with
 *     q[b + offset] for the inputs; what is left (the boundary terms) is runs
 *     of one item, printed straight-line.
 * A family that breaks into more than ROLL_MAX_RUNS runs is not uniform in
 * its index, and the model is not rolled. roll_choose also refuses what the
 * rolled kernels do not cover yet (docs/rolled.md). The cost is the size of
 * the items' expressions, not of the DAG. */
#include <stdlib.h>
#include <string.h>

#include "roll.h"

#define ROLL_MAX_BODY 4096 /* nodes of one item's expression */

/* One node of an item's code: op, operands as places in the post-order,
 * and what a leaf is (an input's array and offset, a constant, a param). */
typedef struct {
  int op, a, b, tag, off, idx;
  double val;
} Code;

typedef struct {
  Dag *d;
  int m;
  int *stamp, *local; /* per node id: the walk that saw it, its place in the post-order */
  int room, epoch;    /* ids stamp and local have room for */
  IntVec order, stack;
  Code *code[2];      /* the item being encoded and the one before */
  int ncode[2], cap[2];
} Walk;

// The nodes of root's expression in post-order (operands first) into
// w->order; -1 when it is too large or has an operation the rolled form
// cannot print (a table row, a stage loop).
static int walk(Walk *w, int root) {
  Dag *d = w->d;
  w->epoch++;
  w->order.n = w->stack.n = 0;
  intvec_push(&w->stack, root * 2);
  while (w->stack.n) {
    int x = w->stack.v[--w->stack.n], id = x >> 1;
    if (x & 1) { /* its operands are done */
      w->local[id] = w->order.n;
      intvec_push(&w->order, id);
      continue;
    }
    if (w->stamp[id] == w->epoch) continue;
    const Node *n = &d->nodes[id];
    if (n->op == OP_TROW || n->op == OP_VEC || n->op == OP_SSUM || w->order.n + w->stack.n > ROLL_MAX_BODY) return -1;
    w->stamp[id] = w->epoch;
    intvec_push(&w->stack, id * 2 + 1);
    if (n->b >= 0 && w->stamp[n->b] != w->epoch) intvec_push(&w->stack, n->b * 2);
    if (n->a >= 0 && w->stamp[n->a] != w->epoch) intvec_push(&w->stack, n->a * 2);
  }
  return w->order.n;
}

// The lowest coordinate (slot mod m) an item's walked expression reads, 0
// for none: the base of items that are not one per coordinate.
static int lowest_coordinate(const Walk *w) {
  int lo = -1;
  for (int k = 0; k < w->order.n; k++) {
    const Node *n = &w->d->nodes[w->order.v[k]];
    if (n->op == OP_INPUT && (lo < 0 || n->idx % w->m < lo)) lo = n->idx % w->m;
  }
  return lo < 0 ? 0 : lo;
}

// Encode the walked expression into code slot s, inputs relative to base.
static void encode(Walk *w, int s, int base) {
  int n = w->order.n;
  VEC_RESERVE(w->code[s], w->ncode[s], w->cap[s], n);
  for (int k = 0; k < n; k++) {
    const Node *nd = &w->d->nodes[w->order.v[k]];
    Code c = {nd->op, nd->a >= 0 ? w->local[nd->a] : -1, nd->b >= 0 ? w->local[nd->b] : -1, 0, 0, 0, 0};
    if (nd->op == OP_INPUT) {
      c.tag = nd->idx / w->m;
      c.off = nd->idx % w->m - base;
    } else if (nd->op == OP_CONST) {
      c.val = nd->val;
    } else if (nd->op == OP_PARAM) {
      c.idx = nd->idx;
    }
    w->code[s][k] = c;
  }
  w->ncode[s] = n;
}

// Whether the codes of the two slots are the same expression (constants
// bit for bit, so that 0 and -0 differ).
static int same_code(const Walk *w) {
  if (w->ncode[0] != w->ncode[1]) return 0;
  for (int k = 0; k < w->ncode[0]; k++) {
    const Code *x = &w->code[0][k], *y = &w->code[1][k];
    if (x->op != y->op || x->a != y->a || x->b != y->b || x->tag != y->tag || x->off != y->off || x->idx != y->idx ||
        memcmp(&x->val, &y->val, sizeof x->val))
      return 0;
  }
  return 1;
}

// Room in w for every node of the DAG, which grows as families are built.
static void walk_fit(Walk *w) {
  if (w->room >= w->d->n) return;
  w->stamp = xrealloc(w->stamp, (size_t)w->d->n * sizeof(int));
  w->local = xrealloc(w->local, (size_t)w->d->n * sizeof(int));
  memset(w->stamp + w->room, 0, (size_t)(w->d->n - w->room) * sizeof(int));
  w->room = w->d->n;
}

// Split the n items nodes[] into runs (base[u] their base indices, or NULL:
// the lowest coordinate each reads). Returns 0, or -1 when an item cannot
// be printed or there are more than ROLL_MAX_RUNS runs.
static int family(Walk *w, RollFamily *f, const int *nodes, const int *base, int n) {
  int cap = 0, prev_base = 0;
  walk_fit(w);
  f->nitems = n;
  f->nruns = 0;
  f->runs = NULL;
  for (int u = 0; u < n; u++) {
    int s = u & 1;
    if (walk(w, nodes[u]) < 0) return -1;
    int b = base ? base[u] : lowest_coordinate(w);
    encode(w, s, b);
    RollRun *r = f->nruns ? &f->runs[f->nruns - 1] : NULL;
    int joins = r && same_code(w) && (r->n == 1 || b - prev_base == r->stride);
    if (joins) {
      if (r->n == 1) r->stride = b - prev_base;
      r->n++;
    } else {
      if (f->nruns == ROLL_MAX_RUNS) return -1;
      VEC_RESERVE(f->runs, f->nruns, cap, f->nruns + 1);
      r = &f->runs[f->nruns++];
      *r = (RollRun){u, 1, b, 0, step_nodes(w->order.n), w->order.n};
      memcpy(r->body, w->order.v, (size_t)w->order.n * sizeof(int));
    }
    prev_base = b;
  }
  f->zero = 1;
  for (int i = 0; i < f->nruns; i++) {
    const RollRun *r = &f->runs[i];
    f->zero &= r->nbody == 1 && dag_is_zero(w->d, r->body[0]);
  }
  return 0;
}

int roll_family(Dag *d, int m, RollFamily *f, const int *nodes, const int *base, int n) {
  Walk w = {d, m, NULL, NULL, 0, 0, {0}, {0}, {0}, {0}, {0}};
  int rc = family(&w, f, nodes, base, n);
  free(w.stamp);
  free(w.local);
  return rc;
}

// The family of the n items nodes[] split into affine, linear part and
// curved (RollSplit), the items one per coordinate (base[u] = u). Returns 0
// or -1 as family does.
static int split_family(Walk *w, RollSplit *sp, const int *nodes, const int *base, int n) {
  Dag *d = w->d;
  int m = w->m, zero = dag_const(d, 0);
  int *aff = step_nodes(n), *lin = step_nodes(n), *cur = step_nodes(n);
  for (int u = 0; u < n; u++) {
    int deg = d->nodes[nodes[u]].deg;
    aff[u] = lin[u] = cur[u] = zero;
    if (deg != 0 && deg != 1) {
      cur[u] = nodes[u];
      continue;
    }
    SparseVec gr; /* constants or params: the item is affine */
    ad_gradient_sparse(d, nodes[u], m, &gr);
    aff[u] = nodes[u];
    for (int e = 0; e < gr.n; e++) lin[u] = dag_add(d, lin[u], dag_mul(d, gr.e[e].node, dag_input(d, m + gr.e[e].coord)));
  }
  return family(w, &sp->affine, aff, base, n) || family(w, &sp->lin, lin, base, n) || family(w, &sp->curved, cur, base, n)
             ? -1
             : 0;
}

// The terms of U in the order its sums add them: U's tree of additions,
// left operand first, so that adding the terms in order from 0 repeats the
// straight-line sums.
static int *potential_terms(Dag *d, int U, int *n) {
  IntVec stack = {0}, terms = {0};
  intvec_push(&stack, U);
  while (stack.n) {
    int id = stack.v[--stack.n];
    const Node *nd = &d->nodes[id];
    if (nd->op == OP_ADD) {
      intvec_push(&stack, nd->b);
      intvec_push(&stack, nd->a);
    } else {
      intvec_push(&terms, id);
    }
  }
  *n = terms.n;
  return terms.v;
}

// v' Hess(g_a)(q) v for each constraint a (nodes over q at inputs 0..m-1
// and v at m..2m-1): the derivative along v of grad g_a(q)' v.
static void curvatures(Model *mod, int *hvv) {
  Dag *d = mod->dag;
  int m = mod->m;
  for (int a = 0; a < mod->nu; a++) {
    const SparseVec *col = &mod->jac[a];
    int w = dag_const(d, 0), acc = dag_const(d, 0);
    for (int e = 0; e < col->n; e++) w = dag_add(d, w, dag_mul(d, col->e[e].node, dag_input(d, m + col->e[e].coord)));
    SparseVec dw;
    ad_gradient_sparse(d, w, m, &dw);
    for (int e = 0; e < dw.n; e++) acc = dag_add(d, acc, dag_mul(d, dw.e[e].node, dag_input(d, m + dw.e[e].coord)));
    hvv[a] = acc;
  }
}

// Which constraints touch each coordinate (r->tcon, r->T), the Jacobian
// entry of each (jnode, m*T), and the half band of G' M^-1 G (r->bw).
static int *coupling(const Model *mod, Roll *r) {
  int m = mod->m;
  IntVec *touch = arena_alloc((size_t)m * sizeof(IntVec));
  IntVec *node = arena_alloc((size_t)m * sizeof(IntVec));
  for (int a = 0; a < mod->nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) {
      intvec_push(&touch[mod->jac[a].e[e].coord], a);
      intvec_push(&node[mod->jac[a].e[e].coord], mod->jac[a].e[e].node);
    }
  for (int i = 0; i < m; i++) {
    if (touch[i].n > r->T) r->T = touch[i].n;
    if (touch[i].n && touch[i].v[touch[i].n - 1] - touch[i].v[0] > r->bw) r->bw = touch[i].v[touch[i].n - 1] - touch[i].v[0];
  }
  int T = r->T, zero = dag_const(mod->dag, 0), *jnode = step_nodes(m * T + 1);
  r->tcon = step_nodes(m * T + 1);
  for (int i = 0; i < m; i++)
    for (int t = 0; t < T; t++) {
      r->tcon[i * T + t] = t < touch[i].n ? touch[i].v[t] : -1;
      jnode[i * T + t] = t < touch[i].n ? node[i].v[t] : zero;
    }
  return jnode;
}

// grad U scattered from U's pair runs (roll_pair.c): no per-coordinate
// family; the whole gradient is evaluated at the stages, as curved entries
// are (exact for affine ones too).
static void pair_gradient(Roll *r) {
  static const RollFamily none = {0, NULL, 0, 1};
  r->gradU = r->gradU_s.affine = r->gradU_s.lin = none;
  r->gradU_s.curved = (RollFamily){0, NULL, 0, 0};
}

// The analysis of a model the rolled form covers, or NULL with *why set.
static Roll *analyse_roll(Model *mod, const char **why) {
  Dag *d = mod->dag;
  int m = mod->m, nu = mod->nu;
  Roll *r = arena_alloc(sizeof *r);
  r->m = m;
  r->nu = nu;
  r->identity = mod->mass == MASS_IDENTITY;
  int *jnode = coupling(mod, r), *coord = step_nodes(m), *items = step_nodes(m + 1), *hvv = step_nodes(nu + 1);
  for (int i = 0; i < m; i++) coord[i] = i;
  curvatures(mod, hvv);
  Walk w = {d, m, NULL, NULL, 0, 0, {0}, {0}, {0}, {0}, {0}};
  int nterms, *terms = potential_terms(d, mod->U, &nterms), bad = 0;
  const char *what = NULL;
  int per_coordinate = !family(&w, &r->gradU, mod->gradU, coord, m);
  if (!per_coordinate || r->gradU.nruns > ROLL_PAIR_TRY_RUNS) { /* a pair sum? (roll_pair.c) */
    r->pairs = roll_pairs(d, m, mod->U);
    if (r->pairs && per_coordinate && r->pairs->nruns >= r->gradU.nruns) r->pairs = NULL;
    if (!r->pairs && !per_coordinate) bad = 1, what = "the gradient of U";
  }
  if (r->pairs) pair_gradient(r);
  r->jac = arena_alloc((size_t)(r->T + 1) * sizeof(RollFamily));
  for (int t = 0; t < r->T && !bad; t++) {
    for (int i = 0; i < m; i++) items[i] = jnode[i * r->T + t];
    if (family(&w, &r->jac[t], items, coord, m)) bad = 1, what = "the Jacobian of g";
  }
  if (!bad && !r->pairs && split_family(&w, &r->gradU_s, mod->gradU, coord, m)) bad = 1, what = "the gradient of U";
  r->jac_s = arena_alloc((size_t)(r->T + 1) * sizeof(RollSplit));
  for (int t = 0; t < r->T && !bad; t++) {
    for (int i = 0; i < m; i++) items[i] = jnode[i * r->T + t];
    if (split_family(&w, &r->jac_s[t], items, coord, m)) bad = 1, what = "the Jacobian of g";
  }
  r->curved = !bad && !r->gradU_s.curved.zero;
  r->lin = !bad && !r->gradU_s.lin.zero;
  for (int t = 0; t < r->T && !bad; t++) {
    r->curved |= !r->jac_s[t].curved.zero;
    r->lin |= !r->jac_s[t].lin.zero;
  }
  if (!bad && family(&w, &r->g, mod->g, NULL, nu)) bad = 1, what = "g";
  if (!bad && !r->pairs && family(&w, &r->U, terms, NULL, nterms)) bad = 1, what = "U";
  if (!bad && family(&w, &r->hvv, hvv, NULL, nu)) bad = 1, what = "the curvature of g";
  free(w.stamp);
  free(w.local);
  if (!bad) return r;
  static char msg[160];
  snprintf(msg, sizeof msg, "%s is not uniform in the index (more than %d runs of one expression, or a "
           "table or stage loop in it)", what, ROLL_MAX_RUNS);
  *why = msg;
  return NULL;
}

// What of the method and options the rolled form does not cover yet, or NULL.
static const char *not_covered(const Model *mod, const Method *me, const EmitOptions *eo) {
  (void)me;
  if (eo->wide_step) return "it does not cover --wide-step";
  if (mod->mass_q || mod->minv_node || mod->mass == MASS_DENSE) return "it covers a constant diagonal mass matrix only";
  return NULL;
}

// Operations of the straight-line sweep: what --rolled auto compares with
// ROLL_AUTO_OPS.
static long sweep_ops(const Model *mod, const Step *st) {
  const Kernel *k = &st->kern[K_SWEEP];
  int *outs = step_nodes(kernel_size(k));
  for (int b = 0; b < k->nout; b++) memcpy(outs + k->out[b].first, k->out[b].nodes, (size_t)k->out[b].len * sizeof(int));
  return dag_count_ops(mod->dag, outs, kernel_size(k));
}

// Items per run of the derivatives' families: how many times the rolled
// form shortens them.
static double compression(const Roll *r) {
  long items = r->gradU.nitems + r->g.nitems, runs = r->gradU.nruns + r->g.nruns;
  if (r->pairs) items += r->pairs->nitems, runs += r->pairs->nruns;
  for (int t = 0; t < r->T; t++) {
    items += r->jac[t].nitems;
    runs += r->jac[t].nruns;
  }
  return runs ? (double)items / (double)runs : 0;
}

// Whether --rolled auto takes the analysed form r: a pair sum of
// ROLL_AUTO_PAIR_ITEMS items or more in runs of ROLL_AUTO_COMPRESSION items
// on average; else, when big (the sweep has ROLL_AUTO_OPS operations, or
// the model ROLL_LEAN_M coordinates), derivatives it shortens
// ROLL_AUTO_COMPRESSION times.
static int auto_rolls(const Roll *r, int big) {
  if (r->pairs) return r->pairs->nitems >= ROLL_AUTO_PAIR_ITEMS && r->pairs->nitems >= ROLL_AUTO_COMPRESSION * r->pairs->nruns;
  return big && compression(r) >= ROLL_AUTO_COMPRESSION;
}

// Whether the form is tried before the straight-line step is built:
// --rolled on, or auto on a model of ROLL_LEAN_M coordinates or more.
static int tried_first(const Model *mod, const EmitOptions *eo) {
  return eo->rolled == ROLL_ON || (eo->rolled == ROLL_AUTO && mod->m >= ROLL_LEAN_M);
}

int roll_plan(const Model *mod, const Method *me, const EmitOptions *eo) {
  if (!tried_first(mod, eo) || not_covered(mod, me, eo)) return 0;
  return 1;
}

int roll_choose(Model *mod, const Method *me, const Step *st, int layout, EmitOptions *eo) {
  eo->roll = NULL;
  int on = eo->rolled == ROLL_ON;
  if (!layout && (eo->rolled == ROLL_OFF || (tried_first(mod, eo) && !on))) return 0; /* decided on the layout */
  const char *why = not_covered(mod, me, eo);
  int big = layout || (!on && !why && sweep_ops(mod, st) >= ROLL_AUTO_OPS);
  if (!on && !layout && (why || (!big && mod->m < ROLL_AUTO_PAIR_M))) return 0;
  Roll *r = why ? NULL : analyse_roll(mod, &why);
  if (r && me->iteration != ITER_FIXED && roll_hessian(mod, me, r, &why)) r = NULL; /* the Newton matrix's band */
  if (r && !on && !auto_rolls(r, big)) return 0; /* little repetition: straight-line is as short */
  if (!r && on) {
    error_at(mod->nu ? mod->g_loc[0] : mod->U_loc, "--rolled on: the rolled form cannot print this model: %s", why);
    return 1;
  }
  eo->roll = r;
  return 0;
}

// Mark (dag_reach) the nodes of every run's body: what the rolled kernels
// print of the model, for emit_check.
void roll_reach(const Roll *r, const Dag *d, unsigned char *mark) {
  const RollFamily *fam[] = {&r->gradU, &r->g, &r->U, &r->hvv, &r->gradU_s.affine, &r->gradU_s.lin, &r->gradU_s.curved};
  for (size_t f = 0; f < sizeof fam / sizeof *fam; f++)
    for (int i = 0; i < fam[f]->nruns; i++) dag_reach(d, fam[f]->runs[i].body, fam[f]->runs[i].nbody, mark);
  for (int t = 0; r->hess && t < r->ht; t++)
    for (int i = 0; i < r->hess[t].nruns; i++) dag_reach(d, r->hess[t].runs[i].body, r->hess[t].runs[i].nbody, mark);
  for (int t = 0; t < r->T; t++) {
    const RollFamily *jf[] = {&r->jac[t], &r->jac_s[t].affine, &r->jac_s[t].lin, &r->jac_s[t].curved};
    for (int f = 0; f < 4; f++)
      for (int i = 0; i < jf[f]->nruns; i++) dag_reach(d, jf[f]->runs[i].body, jf[f]->runs[i].nbody, mark);
  }
}
