/* ad.c - reverse-mode differentiation on the DAG.
 *
 * One reverse sweep visits the nodes reachable from the seeded outputs in
 * decreasing id order (a topological order, see dag.c) and accumulates each
 * node's adjoint into its operands with the local derivative. Adjoints are
 * themselves DAG nodes, so derivatives share subexpressions with the values
 * they come from (d exp(x) reuses exp(x), d sqrt(x) reuses sqrt(x)) and with
 * each other, and zeros fold away: a structural zero of a gradient is the
 * constant 0 node. */
#include <stdlib.h>

#include "hbvmgen.h"

typedef struct {
  Dag *d;
  int *adj; /* adjoint node per id, -1 for zero */
} Sweep;

static void accumulate(Sweep *sw, int id, int contribution) {
  if (dag_is_zero(sw->d, contribution)) return;
  sw->adj[id] = sw->adj[id] < 0 ? contribution : dag_add(sw->d, sw->adj[id], contribution);
}

// Propagate the adjoint w of node id into its operands.
static void propagate(Sweep *sw, int id, int w) {
  Dag *d = sw->d;
  Node n = d->nodes[id];
  int a = n.a, b = n.b, one = dag_const(d, 1);
  switch ((Op)n.op) {
  case OP_CONST:
  case OP_INPUT:
  case OP_PARAM:
  case OP_SIGN:
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
  case OP_DIV: /* d(a/b) = da/b - (a/b) db/b */
    accumulate(sw, a, dag_div(d, w, b));
    accumulate(sw, b, dag_neg(d, dag_div(d, dag_mul(d, w, id), b)));
    return;
  case OP_NEG:
    accumulate(sw, a, dag_neg(d, w));
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
  case OP_SQRT: accumulate(sw, a, dag_div(d, w, dag_mul(d, dag_const(d, 2), id))); return;
  case OP_ABS: local = dag_op(d, OP_SIGN, a, -1); break;
  default: internal_error("no derivative for %s", op_name((Op)n.op)); return;
  }
  accumulate(sw, a, dag_mul(d, w, local));
}

// Reverse sweep from roots[r] seeded with weight nodes seeds[r] (NULL: all
// ones). grad[i], i < n, receives d(sum_r seed_r root_r)/d(input i) as a node.
void ad_reverse(Dag *d, const int *roots, const int *seeds, int nroots, int n, int *grad) {
  int top = -1;
  for (int r = 0; r < nroots; r++)
    if (roots[r] > top) top = roots[r];
  int zero = dag_const(d, 0);
  for (int i = 0; i < n; i++) grad[i] = zero;
  if (top < 0) return;
  unsigned char *mark = calloc((size_t)top + 1, 1);
  Sweep sw = {d, malloc((size_t)(top + 1) * sizeof(int))};
  if (!mark || !sw.adj) internal_error("out of memory in ad_reverse");
  for (int id = 0; id <= top; id++) sw.adj[id] = -1;
  dag_reach(d, roots, nroots, mark);
  for (int r = 0; r < nroots; r++) accumulate(&sw, roots[r], seeds ? seeds[r] : dag_const(d, 1));
  for (int id = top; id >= 0; id--) {
    if (!mark[id] || sw.adj[id] < 0) continue;
    const Node *nd = &d->nodes[id];
    if (nd->op == OP_INPUT && nd->idx < n) grad[nd->idx] = sw.adj[id];
    else propagate(&sw, id, sw.adj[id]);
  }
  free(mark);
  free(sw.adj);
}

void ad_gradient(Dag *d, int root, int n, int *grad) { ad_reverse(d, &root, NULL, 1, n, grad); }
