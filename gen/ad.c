/* ad.c - reverse-mode differentiation on the DAG.
 *
 * One reverse sweep visits the nodes reachable from the seeded outputs in
 * decreasing id order (a topological order, see dag.c), and only those: its
 * scratch lives in the Dag and is reset by an epoch, so many small
 * constraints cost their sizes, not their number times the size of the
 * DAG. It accumulates each node's adjoint into its operands with the local
 * derivative. Adjoints are themselves DAG nodes, so derivatives share
 * subexpressions with the values they come from (d exp(x) reuses exp(x),
 * d sqrt(x) reuses sqrt(x)) and with each other, and zeros fold away: a
 * structural zero of a gradient is the constant 0 node.
 *
 * Where a function has a kink the sweep takes a subgradient, the same at
 * every tie: d abs(a) = sign(a), 0 at a = 0; d sign(a) = 0 everywhere (the
 * jump at 0 has no derivative), and so is d floor(a) (its jumps at the
 * integers neither); min and max pass the adjoint to the
 * operand they select, and half to each when a = b, through
 * (1 -+ sign(a - b)) / 2, so at a tie the derivative is the mean of the
 * two one-sided ones. */
#include <stdlib.h>

#include "hbvmgen.h"

typedef struct {
  Dag *d;
  int *adj;   /* adjoint node per id (d->sweep_adj), -1 for zero */
} Sweep;

static void accumulate(Sweep *sw, int id, int contribution) {
  if (dag_is_zero(sw->d, contribution)) return;
  sw->adj[id] = sw->adj[id] < 0 ? contribution : dag_add(sw->d, sw->adj[id], contribution);
}

// The adjoint w of a table row (OP_TROW node n) into its vector's entries.
static void propagate_table_row(Sweep *sw, const Node *n, int w) {
  Dag *d = sw->d;
  const DagTable *t = &d->tables[(int)n->val];
  int *e = xmalloc((size_t)t->cols * sizeof *e);
  dag_vector_entries(d, n->a, e);
  for (int j = 0; j < t->cols; j++) {
    double c = t->v[(size_t)n->idx * (size_t)t->cols + (size_t)j];
    if (c != 0) accumulate(sw, e[j], dag_mul(d, dag_const(d, c), w));
  }
  free(e);
}

// Propagate the adjoint w of node id into its operands.
static void propagate(Sweep *sw, int id, int w) {
  Dag *d = sw->d;
  Node n = d->nodes[id];
  int a = n.a, b = n.b, one = dag_const(d, 1);
  switch ((Op)n.op) {
  case OP_CONST:
  case OP_VEC:
  case OP_INPUT:
  case OP_PARAM:
  case OP_SIGN:
  case OP_FLOOR:
    return;
  case OP_ADD:
    accumulate(sw, a, w);
    accumulate(sw, b, w);
    return;
  case OP_SUB:
    accumulate(sw, a, w);
    accumulate(sw, b, dag_neg(d, w));
    return;
  case OP_MUL:
    accumulate(sw, a, dag_mul(d, w, b));
    accumulate(sw, b, dag_mul(d, w, a));
    return;
  case OP_DIV: { /* d(a/b) = da/b - (a/b) db/b, with one reciprocal 1/b shared by both
                  * (and with a reciprocal a/b = 1/b itself: d(1/b) = -(1/b)^2 db) */
    int rb = dag_div(d, one, b);
    accumulate(sw, a, dag_mul(d, w, rb));
    accumulate(sw, b, dag_neg(d, dag_mul(d, dag_mul(d, w, id), rb)));
    return;
  }
  case OP_NEG:
    accumulate(sw, a, dag_neg(d, w));
    return;
  case OP_TROW: /* sum_j T[row][j] v_j: w T[row][j] to each entry (VEC nodes pass nothing) */
    propagate_table_row(sw, &n, w);
    return;
  case OP_POW:
    if (d->nodes[b].op == OP_CONST) {
      double c = d->nodes[b].val;
      int dpow = dag_mul(d, dag_const(d, c), dag_op(d, OP_POW, a, dag_const(d, c - 1)));
      accumulate(sw, a, dag_mul(d, w, dpow));
    } else {
      int dpow = dag_mul(d, b, dag_op(d, OP_POW, a, dag_sub(d, b, one)));
      accumulate(sw, a, dag_mul(d, w, dpow));
      accumulate(sw, b, dag_mul(d, w, dag_mul(d, dag_op(d, OP_LOG, a, -1), id)));
    }
    return;
  case OP_MIN:
  case OP_MAX: { /* the selected operand gets w, each half of w at a tie */
    int sg = dag_op(d, OP_SIGN, dag_sub(d, a, b), -1), half = dag_const(d, 0.5);
    int to_a = dag_mul(d, half, n.op == OP_MAX ? dag_add(d, one, sg) : dag_sub(d, one, sg));
    int to_b = dag_sub(d, one, to_a);
    accumulate(sw, a, dag_mul(d, w, to_a));
    accumulate(sw, b, dag_mul(d, w, to_b));
    return;
  }
  case OP_ATAN2: { /* atan2(y, x): dy x/(x^2+y^2), dx -y/(x^2+y^2) */
    int r2 = dag_add(d, dag_mul(d, a, a), dag_mul(d, b, b));
    accumulate(sw, a, dag_div(d, dag_mul(d, w, b), r2));
    accumulate(sw, b, dag_neg(d, dag_div(d, dag_mul(d, w, a), r2)));
    return;
  }
  default:
    break;
  }
  int local; /* derivative of a unary function at a */
  switch ((Op)n.op) {
  case OP_SIN: local = dag_op(d, OP_COS, a, -1); break;
  case OP_COS: local = dag_neg(d, dag_op(d, OP_SIN, a, -1)); break;
  case OP_TAN: local = dag_add(d, one, dag_mul(d, id, id)); break;
  case OP_ASIN: local = dag_div(d, one, dag_op(d, OP_SQRT, dag_sub(d, one, dag_mul(d, a, a)), -1)); break;
  case OP_ACOS: local = dag_neg(d, dag_div(d, one, dag_op(d, OP_SQRT, dag_sub(d, one, dag_mul(d, a, a)), -1))); break;
  case OP_ATAN: local = dag_div(d, one, dag_add(d, one, dag_mul(d, a, a))); break;
  case OP_SINH: local = dag_op(d, OP_COSH, a, -1); break;
  case OP_COSH: local = dag_op(d, OP_SINH, a, -1); break;
  case OP_TANH: local = dag_sub(d, one, dag_mul(d, id, id)); break;
  case OP_EXP: local = id; break;
  case OP_LOG: accumulate(sw, a, dag_div(d, w, a)); return;
  case OP_SQRT: /* w / (2 sqrt a), through the reciprocal of sqrt a that 1/sqrt(a) shares */
    accumulate(sw, a, dag_mul(d, dag_mul(d, dag_const(d, 0.5), w), dag_div(d, one, id)));
    return;
  case OP_ABS: local = dag_op(d, OP_SIGN, a, -1); break;
  default: internal_error("no derivative for %s", op_name((Op)n.op)); return;
  }
  accumulate(sw, a, dag_mul(d, w, local));
}

static int by_decreasing_id(const void *a, const void *b) {
  int x = *(const int *)a, y = *(const int *)b;
  return (x < y) - (x > y);
}

// Mark the nodes reachable from the roots with a new epoch (their adjoints
// set to zero) and list them in d->sweep_ids in decreasing id order, a
// reverse topological order. The scratch arrays grow to the largest id.
static void visit(Dag *d, const int *roots, int nroots) {
  int top = -1;
  for (int r = 0; r < nroots; r++)
    if (roots[r] > top) top = roots[r];
  if (top >= d->sweep_cap) {
    int cap = d->sweep_cap ? d->sweep_cap : 1024;
    while (cap <= top) cap *= 2;
    d->sweep_stamp = arena_alloc((size_t)cap * sizeof(int)); /* zeroed: no epoch yet */
    d->sweep_adj = arena_alloc((size_t)cap * sizeof(int));
    d->sweep_cap = cap;
  }
  int epoch = ++d->sweep_epoch;
  IntVec *ids = &d->sweep_ids;
  ids->n = 0;
  for (int r = 0; r < nroots; r++)
    if (roots[r] >= 0 && d->sweep_stamp[roots[r]] != epoch) {
      d->sweep_stamp[roots[r]] = epoch;
      intvec_push(ids, roots[r]);
    }
  for (int i = 0; i < ids->n; i++) { /* the list is its own work queue */
    const Node *nd = &d->nodes[ids->v[i]];
    int kids[2] = {nd->a, nd->b};
    for (int k = 0; k < 2; k++)
      if (kids[k] >= 0 && d->sweep_stamp[kids[k]] != epoch) {
        d->sweep_stamp[kids[k]] = epoch;
        intvec_push(ids, kids[k]);
      }
  }
  for (int i = 0; i < ids->n; i++) d->sweep_adj[ids->v[i]] = -1;
  qsort(ids->v, (size_t)ids->n, sizeof(int), by_decreasing_id);
}

// Reverse sweep from roots[r] seeded with weight nodes seeds[r] (NULL: all
// ones), over the reachable nodes only, listed in d->sweep_ids. Returns
// the adjoints, indexed by id (valid for the listed ids; -1 for zero).
static int *sweep(Dag *d, const int *roots, const int *seeds, int nroots) {
  visit(d, roots, nroots);
  Sweep sw = {d, d->sweep_adj};
  for (int r = 0; r < nroots; r++)
    if (roots[r] >= 0) accumulate(&sw, roots[r], seeds ? seeds[r] : dag_const(d, 1));
  for (int i = 0; i < d->sweep_ids.n; i++) {
    int id = d->sweep_ids.v[i];
    if (sw.adj[id] >= 0 && d->nodes[id].op != OP_INPUT) propagate(&sw, id, sw.adj[id]);
  }
  return sw.adj;
}

// grad[i], i < n, receives d(sum_r seed_r root_r)/d(input i) as a node.
void ad_reverse(Dag *d, const int *roots, const int *seeds, int nroots, int n, int *grad) {
  int zero = dag_const(d, 0);
  for (int i = 0; i < n; i++) grad[i] = zero;
  const int *adj = sweep(d, roots, seeds, nroots);
  for (int i = 0; i < d->sweep_ids.n; i++) {
    const Node *nd = &d->nodes[d->sweep_ids.v[i]];
    if (nd->op == OP_INPUT && nd->idx < n && adj[d->sweep_ids.v[i]] >= 0) grad[nd->idx] = adj[d->sweep_ids.v[i]];
  }
}

void ad_gradient(Dag *d, int root, int n, int *grad) {
  d->work += n; ad_reverse(d, &root, NULL, 1, n, grad); }

static int by_coord(const void *a, const void *b) {
  const Entry *x = a, *y = b;
  return (x->coord > y->coord) - (x->coord < y->coord);
}

// The nonzero entries of the gradient of root (see hbvmgen.h).
void ad_gradient_sparse(Dag *d, int root, int n, SparseVec *out) {
  dag_const(d, 0); /* as ad_reverse does first: the same nodes in the same order */
  const int *adj = sweep(d, &root, NULL, 1);
  int nnz = 0;
  for (int pass = 0; pass < 2; pass++) { /* count, then fill */
    if (pass) out->e = arena_alloc((size_t)(nnz + 1) * sizeof(Entry));
    out->n = 0;
    for (int i = 0; i < d->sweep_ids.n; i++) {
      int id = d->sweep_ids.v[i];
      if (d->nodes[id].op != OP_INPUT || d->nodes[id].idx >= n || adj[id] < 0 || dag_is_zero(d, adj[id])) continue;
      if (pass) out->e[out->n] = (Entry){d->nodes[id].idx, adj[id]};
      out->n++;
    }
    nnz = out->n;
  }
  qsort(out->e, (size_t)out->n, sizeof(Entry), by_coord);
}
