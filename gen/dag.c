/* dag.c - the expression DAG.
 *
 * Every expression of a model, its derivatives and finally the whole step
 * of the method live in one Dag. Nodes are hash-consed: asking for a node
 * that exists returns the existing id, so common subexpressions are shared
 * by construction. As each node is built it is folded when all operands are
 * constants (unless the result would be NaN, an infinity or -0.0, which are
 * left for run time and reported by the caller) and simplified by the
 * algebraic identities x+0, x*1, x*0, x-x, -(-x), x^1, x^0, min(x,x), max(x,x).
 *
 * Nodes are numbered in creation order and an operand is always created
 * before its user, so id order is a topological order: evaluation, degree
 * analysis, reverse sweeps and emission are loops over ids.
 *
 * A product with a large constant table (M^-1 of a dense M, mass.c) is not
 * spelt out as rows x cols products: its vector is a chain of VEC nodes and
 * each row one TROW node reading a table the Dag holds (dag_table), which
 * the emitter prints as a loop. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

static const struct {
  const char *name;
  int arity;
  const char *cfun;
} op_info[OP_COUNT] = {
#define X(name, arity, cfun) {#name, arity, cfun},
    OPS(X)
#undef X
};

int op_arity(Op op) { return op_info[op].arity; }
const char *op_cfun(Op op) { return op_info[op].cfun; }
const char *op_name(Op op) { return op_info[op].name; }

Dag *dag_new(void) {
  Dag *d = arena_alloc(sizeof *d);
  d->cap = 1024;
  d->nodes = arena_alloc((size_t)d->cap * sizeof(Node));
  d->tcap = 2048;
  d->table = arena_alloc((size_t)d->tcap * sizeof(int));
  memset(d->table, 0xff, (size_t)d->tcap * sizeof(int));
  d->zero = -1;
  d->zero = dag_const(d, 0);
  return d;
}

static uint64_t hash_node(const Node *n) {
  uint64_t bits;
  memcpy(&bits, &n->val, sizeof bits);
  uint64_t h = 1469598103934665603ull;
  uint64_t parts[5] = {n->op, (uint64_t)(uint32_t)n->a, (uint64_t)(uint32_t)n->b, (uint64_t)(uint32_t)n->idx, bits};
  for (int i = 0; i < 5; i++) {
    h ^= parts[i];
    h *= 1099511628211ull;
    h ^= h >> 29;
  }
  h ^= h >> 33; /* mix the high bits down: constants differ there, and the table reads the low ones */
  h *= 0xff51afd7ed558ccdull;
  return h ^ (h >> 33);
}

static int same_node(const Node *x, const Node *y) {
  return x->op == y->op && x->a == y->a && x->b == y->b && x->idx == y->idx &&
         memcmp(&x->val, &y->val, sizeof x->val) == 0;
}

static void rehash(Dag *d) {
  int tcap = d->tcap * 2;
  int *table = arena_alloc((size_t)tcap * sizeof(int));
  memset(table, 0xff, (size_t)tcap * sizeof(int));
  for (int id = 0; id < d->n; id++) {
    uint64_t h = hash_node(&d->nodes[id]) & (uint64_t)(tcap - 1);
    while (table[h] >= 0) h = (h + 1) & (uint64_t)(tcap - 1);
    table[h] = id;
  }
  d->table = table;
  d->tcap = tcap;
}

static int saturate(long deg) { return deg > (1 << 20) ? (1 << 20) : (int)deg; }

// Polynomial degree of a new node in the inputs (parameters count as constants).
static int node_degree(const Dag *d, const Node *n) {
  int da = n->a >= 0 ? d->nodes[n->a].deg : 0;
  int db = n->b >= 0 ? d->nodes[n->b].deg : 0;
  switch ((Op)n->op) {
  case OP_CONST:
  case OP_PARAM:
    return 0;
  case OP_INPUT:
    return 1;
  case OP_ADD:
  case OP_SUB:
    return da < 0 || db < 0 ? DEG_NONPOLY : (da > db ? da : db);
  case OP_MUL:
    return da < 0 || db < 0 ? DEG_NONPOLY : saturate((long)da + db);
  case OP_DIV:
    return db == 0 ? da : DEG_NONPOLY;
  case OP_NEG:
  case OP_TROW:
    return da;
  case OP_VEC:
    return da < 0 || db < 0 ? DEG_NONPOLY : (da > db ? da : db);
  case OP_SSUM:
    return DEG_NONPOLY;
  case OP_POW: {
    const Node *e = &d->nodes[n->b];
    if (e->op == OP_CONST && e->val >= 0 && e->val == floor(e->val) && e->val <= (1 << 20))
      return da < 0 ? DEG_NONPOLY : saturate((long)da * (long)e->val);
    return da == 0 && db == 0 ? 0 : DEG_NONPOLY;
  }
  default:
    return da == 0 && db == 0 ? 0 : DEG_NONPOLY;
  }
}

// The slot of node *proto in the hash table: its id's, or the empty one
// where it would go.
static uint64_t slot_of(const Dag *d, const Node *proto) {
  uint64_t h = hash_node(proto) & (uint64_t)(d->tcap - 1);
  while (d->table[h] >= 0 && !same_node(&d->nodes[d->table[h]], proto)) h = (h + 1) & (uint64_t)(d->tcap - 1);
  return h;
}

// Find or create the node *proto; returns its id.
static int intern(Dag *d, Node proto) {
  uint64_t h = slot_of(d, &proto);
  if (d->table[h] >= 0) return d->table[h];
  if (d->n >= MAX_NODES)
    fatal_at(d->where, "the model needs more than %d expression nodes%s", MAX_NODES,
             d->where_note ? d->where_note : d->where.line ? " (the limit was reached building this statement)" : "");
  VEC_RESERVE(d->nodes, d->n, d->cap, d->n + 1);
  proto.flags = (unsigned char)((proto.a >= 0 ? d->nodes[proto.a].flags : 0) |
                                (proto.b >= 0 ? d->nodes[proto.b].flags : 0) | (proto.op == OP_INPUT ? DEP_INPUT : 0));
  proto.deg = node_degree(d, &proto);
  int id = d->n++;
  d->nodes[id] = proto;
  d->table[h] = id;
  if (2 * d->n > d->tcap) rehash(d);
  return id;
}

static Node leaf(Op op) {
  Node n;
  memset(&n, 0, sizeof n);
  n.op = (unsigned char)op;
  n.a = n.b = -1;
  return n;
}

// The node op(a, b) if the DAG has it, else -1 (nothing is created).
static int existing(const Dag *d, Op op, int a, int b) {
  Node n = leaf(op);
  n.a = a;
  n.b = b;
  return d->table[slot_of(d, &n)];
}

int dag_const(Dag *d, double v) {
  if (v == 0 && d->zero >= 0) return d->zero; /* the most asked-for node */
  Node n = leaf(OP_CONST);
  n.val = v == 0 ? 0.0 : v; /* one zero */
  return intern(d, n);
}

int dag_input(Dag *d, int slot) {
  Node n = leaf(OP_INPUT);
  n.idx = slot;
  return intern(d, n);
}

int dag_param(Dag *d, int idx) {
  Node n = leaf(OP_PARAM);
  n.idx = idx;
  return intern(d, n);
}

int dag_is_const(const Dag *d, int id, double v) {
  return d->nodes[id].op == OP_CONST && d->nodes[id].val == v;
}

int dag_is_zero(const Dag *d, int id) { return dag_is_const(d, id, 0.0); }

// The value of op applied to constants (b unused for unary operations).
double op_apply(Op op, double a, double b) {
  switch (op) {
  case OP_ADD: return a + b;
  case OP_SUB: return a - b;
  case OP_MUL: return a * b;
  case OP_DIV: return a / b;
  case OP_NEG: return -a;
  case OP_POW: return pow(a, b);
  case OP_SIN: return sin(a);
  case OP_COS: return cos(a);
  case OP_TAN: return tan(a);
  case OP_ASIN: return asin(a);
  case OP_ACOS: return acos(a);
  case OP_ATAN: return atan(a);
  case OP_ATAN2: return atan2(a, b);
  case OP_SINH: return sinh(a);
  case OP_COSH: return cosh(a);
  case OP_TANH: return tanh(a);
  case OP_EXP: return exp(a);
  case OP_LOG: return log(a);
  case OP_SQRT: return sqrt(a);
  case OP_ABS: return fabs(a);
  case OP_SIGN: return (a > 0) - (a < 0);
  case OP_MIN: return fmin(a, b);
  case OP_MAX: return fmax(a, b);
  case OP_FLOOR: return floor(a);
  default: internal_error("op_apply on %s", op_name(op));
  }
  return 0;
}

static int is_neg(const Dag *d, int id) { return d->nodes[id].op == OP_NEG; }

// c1 * c2 when that product is exact (so merging two constant factors
// changes no rounding), else 0.
static double exact_product(double c1, double c2) {
  double p = c1 * c2;
  return isfinite(p) && p != 0 && fma(c1, c2, -p) == 0 && fabs(p) >= 0x1p-1000 ? p : 0;
}

// c * (c2 * x) -> (c * c2) * x when c * c2 is exact; -1 otherwise.
static int merge_factors(Dag *d, int c, int prod) {
  const Node *pn = &d->nodes[prod];
  if (pn->op != OP_MUL) return -1;
  int k = d->nodes[pn->a].op == OP_CONST ? pn->a : d->nodes[pn->b].op == OP_CONST ? pn->b : -1;
  if (k < 0) return -1;
  double p = exact_product(d->nodes[c].val, d->nodes[k].val);
  if (p == 0) return -1;
  return dag_op(d, OP_MUL, dag_const(d, p), k == pn->a ? pn->b : pn->a);
}

// When node id is 2^e * x (a product with a constant power of two), sets
// *scale to 2^e and *x and returns 1; else returns 0.
static int pow2_scaled(const Dag *d, int id, double *scale, int *x) {
  const Node *n = &d->nodes[id];
  if (n->op != OP_MUL) return 0;
  int k = d->nodes[n->a].op == OP_CONST ? n->a : d->nodes[n->b].op == OP_CONST ? n->b : -1;
  int e;
  if (k < 0 || fabs(frexp(d->nodes[k].val, &e)) != 0.5) return 0;
  *scale = d->nodes[k].val;
  *x = k == n->a ? n->b : n->a;
  return 1;
}

// (2^e x) * y -> 2^e (x * y), for either factor or both: multiplying by a
// power of two commutes with rounding (exact while no intermediate over- or
// underflows), so such a factor floats up the products until it cancels
// (the 2 of d(x^2)/dx against a 1/2) or merges into a constant (a weight,
// merge_factors), and its own multiplication is gone. -1 when neither factor
// is scaled, or when the two scales' product would leave the normal range
// (2^1000 * 2^1000: no constant may be infinite, and none subnormal).
static int float_pow2(Dag *d, int a, int b) {
  double sa = 1, sb = 1;
  int xa = a, xb = b, fa = pow2_scaled(d, a, &sa, &xa), fb = pow2_scaled(d, b, &sb, &xb);
  if (!fa && !fb) return -1;
  double scale = sa * sb;
  if (!isfinite(scale) || fabs(scale) < 0x1p-1000) return -1;
  return dag_op(d, OP_MUL, dag_const(d, scale), dag_op(d, OP_MUL, xa, xb));
}

// (2^e x) +- (2^e y) -> 2^e (x +- y): the common power of two floats on
// (exact, as in float_pow2). -1 unless both terms carry the same one.
static int float_pow2_sum(Dag *d, Op op, int a, int b) {
  double sa, sb;
  int xa, xb;
  if (!pow2_scaled(d, a, &sa, &xa) || !pow2_scaled(d, b, &sb, &xb) || fabs(sa) != fabs(sb)) return -1;
  if (sa != sb) { // opposite signs: 2^e x + (-2^e) y = 2^e (x - y)
    op = op == OP_ADD ? OP_SUB : OP_ADD;
  }
  return dag_op(d, OP_MUL, dag_const(d, sa), dag_op(d, op, xa, xb));
}

// Algebraic identities; returns the simplified node or -1 when none applies.
static int simplify(Dag *d, Op op, int a, int b) {
  switch (op) {
  case OP_ADD:
    if (dag_is_zero(d, a)) return b;
    if (dag_is_zero(d, b)) return a;
    if (is_neg(d, b)) return dag_op(d, OP_SUB, a, d->nodes[b].a);
    if (is_neg(d, a)) return dag_op(d, OP_SUB, b, d->nodes[a].a);
    return float_pow2_sum(d, op, a, b);
  case OP_SUB: {
    if (dag_is_zero(d, b)) return a;
    if (dag_is_zero(d, a)) return dag_op(d, OP_NEG, b, -1);
    if (a == b) return dag_const(d, 0);
    if (is_neg(d, b)) return dag_op(d, OP_ADD, a, d->nodes[b].a);
    if (is_neg(d, a)) return dag_op(d, OP_NEG, dag_op(d, OP_ADD, d->nodes[a].a, b), -1); /* -a - b = -(a + b) */
    int reverse = existing(d, OP_SUB, b, a);
    if (reverse >= 0) return dag_op(d, OP_NEG, reverse, -1); /* a - b = -(b - a), shared */
    return float_pow2_sum(d, op, a, b);
  }
  case OP_MUL:
    if (dag_is_zero(d, a) || dag_is_zero(d, b)) return dag_const(d, 0);
    if (dag_is_const(d, a, 1)) return b;
    if (dag_is_const(d, b, 1)) return a;
    if (dag_is_const(d, a, -1)) return dag_op(d, OP_NEG, b, -1);
    if (dag_is_const(d, b, -1)) return dag_op(d, OP_NEG, a, -1);
    if (is_neg(d, a) && is_neg(d, b)) return dag_op(d, OP_MUL, d->nodes[a].a, d->nodes[b].a);
    if (is_neg(d, a)) return dag_op(d, OP_NEG, dag_op(d, OP_MUL, d->nodes[a].a, b), -1);
    if (is_neg(d, b)) return dag_op(d, OP_NEG, dag_op(d, OP_MUL, a, d->nodes[b].a), -1);
    if (d->nodes[a].op == OP_CONST) return merge_factors(d, a, b);
    if (d->nodes[b].op == OP_CONST) return merge_factors(d, b, a);
    return float_pow2(d, a, b);
  case OP_DIV:
    if (dag_is_const(d, b, 1)) return a;
    if (dag_is_const(d, a, -1)) return dag_op(d, OP_NEG, dag_op(d, OP_DIV, dag_const(d, 1), b), -1); /* exact */
    if (dag_is_const(d, b, -1)) return dag_op(d, OP_NEG, a, -1);
    if (dag_is_zero(d, a) && !dag_is_zero(d, b)) return a;
    if (is_neg(d, a)) return dag_op(d, OP_NEG, dag_op(d, OP_DIV, d->nodes[a].a, b), -1);
    if (d->nodes[b].op == OP_CONST && exact_product(1 / d->nodes[b].val, d->nodes[b].val) == 1)
      return dag_op(d, OP_MUL, a, dag_const(d, 1 / d->nodes[b].val)); /* x/2 -> 0.5*x: exact */
    return -1;
  case OP_NEG:
    if (is_neg(d, a)) return d->nodes[a].a;
    if (dag_is_zero(d, a)) return a;
    return -1;
  case OP_MIN:
  case OP_MAX:
    return a == b ? a : -1;
  case OP_POW:
    if (dag_is_const(d, b, 1)) return a;
    if (dag_is_zero(d, b) || dag_is_const(d, a, 1)) return dag_const(d, 1);
    if (dag_is_const(d, b, 0.5)) return dag_op(d, OP_SQRT, a, -1);
    return -1;
  default:
    return -1;
  }
}

// Build op(a, b): fold constants, simplify, share. b is -1 for unary ops.
int dag_op(Dag *d, Op op, int a, int b) {
  ASSERT(a >= 0 && a < d->n && (op_arity(op) == 1 ? b < 0 : b >= 0 && b < d->n));
  ASSERT(op != OP_VEC && op != OP_TROW && op != OP_SSUM); /* built by their constructors only */
  const Node *na = &d->nodes[a], *nb = b >= 0 ? &d->nodes[b] : NULL;
  if (na->op == OP_CONST && (!nb || nb->op == OP_CONST)) {
    double v = op_apply(op, na->val, nb ? nb->val : 0);
    if (isfinite(v) && !(v == 0 && signbit(v))) return dag_const(d, v);
  }
  int s = simplify(d, op, a, b);
  if (s >= 0) return s;
  if ((op == OP_ADD || op == OP_MUL || op == OP_MIN || op == OP_MAX) && a > b) {
    int t = a;
    a = b;
    b = t;
  }
  Node n = leaf(op);
  n.a = a;
  n.b = b;
  return intern(d, n);
}

int dag_add(Dag *d, int a, int b) { return dag_op(d, OP_ADD, a, b); }
int dag_sub(Dag *d, int a, int b) { return dag_op(d, OP_SUB, a, b); }
int dag_mul(Dag *d, int a, int b) { return dag_op(d, OP_MUL, a, b); }
int dag_div(Dag *d, int a, int b) { return dag_op(d, OP_DIV, a, b); }
int dag_neg(Dag *d, int a) { return dag_op(d, OP_NEG, a, -1); }

// Register a constant table (rows x cols, row-major; v must outlive the
// Dag) for dag_table_row; returns its number.
int dag_table(Dag *d, const char *name, const double *v, int rows, int cols) {
  VEC_RESERVE(d->tables, d->ntables, d->tabcap, d->ntables + 1);
  d->tables[d->ntables] = (DagTable){name, v, rows, cols};
  return d->ntables++;
}

// The vector v[0..n-1] as a chain of VEC nodes (see hbvmgen.h); returns
// its last node. Equal vectors give the same chain.
static int dag_vector_link(Dag *d, int entry, int prev, int j) {
  Node x = leaf(OP_VEC);
  x.a = entry;
  x.b = prev;
  x.idx = j;
  return intern(d, x);
}

int dag_vector(Dag *d, const int *v, int n) {
  int vec = -1;
  ASSERT(n >= 1);
  for (int j = 0; j < n; j++) vec = dag_vector_link(d, v[j], vec, j);
  return vec;
}

int dag_vector_len(const Dag *d, int vec) { return d->nodes[vec].idx + 1; }

void dag_vector_entries(const Dag *d, int vec, int *out) {
  for (int id = vec; id >= 0; id = d->nodes[id].b) out[d->nodes[id].idx] = d->nodes[id].a;
}

// Row row of table times the vector whose chain ends at vec.
int dag_table_row(Dag *d, int table, int row, int vec) {
  ASSERT(table >= 0 && table < d->ntables && row >= 0 && row < d->tables[table].rows &&
         d->nodes[vec].op == OP_VEC && dag_vector_len(d, vec) == d->tables[table].cols);
  Node x = leaf(OP_TROW);
  x.a = vec;
  x.idx = row;
  x.val = table;
  return intern(d, x);
}

// Register a stage loop (copied; its arrays must outlive the Dag).
int dag_loop(Dag *d, const DagLoop *loop) {
  VEC_RESERVE(d->loops, d->nloops, d->loopcap, d->nloops + 1);
  d->loops[d->nloops] = *loop;
  return d->nloops++;
}

int dag_stage_sum(Dag *d, int loop, int j, int r) {
  const DagLoop *lp = &d->loops[loop];
  ASSERT(loop >= 0 && loop < d->nloops && j >= 0 && j < lp->s && r >= 0 && r < lp->nroots);
  Node x = leaf(OP_SSUM);
  x.a = lp->h;
  x.idx = j * lp->nroots + r;
  x.val = loop;
  return intern(d, x);
}

// The value of an SSUM node at the inputs: the loop's
// stage points, its roots at each, summed as the emitted loop sums them.
static double stage_sum_value(const Dag *d, const Node *n, const double *inputs, const double *params) {
  const DagLoop *lp = &d->loops[(int)n->val];
  int j = n->idx / lp->nroots, r = n->idx % lp->nroots;
  double *in = xmalloc((size_t)(lp->m + 1) * sizeof *in), acc = 0; /* the coordinates: Q_l */
  double h = inputs[d->nodes[lp->h].idx];
  for (int l = 0; l < lp->k; l++) {
    for (int i = 0; i < lp->m; i++) {
      double a = lp->Ihat[l * lp->s] * inputs[d->nodes[lp->gam[i]].idx];
      for (int t = 1; t < lp->s; t++) a += lp->Ihat[l * lp->s + t] * inputs[d->nodes[lp->gam[t * lp->m + i]].idx];
      in[i] = inputs[d->nodes[lp->q0[i]].idx] + h * a;
    }
    acc += lp->W[l * lp->s + j] * dag_eval(d, lp->roots[r], in, params);
  }
  free(in);
  return acc;
}

// The value of a TROW node from the values v[] of its vector's entries,
// summed in the order the emitted loop sums them.
static double table_row_value(const Dag *d, const Node *n, const double *v) {
  const DagTable *t = &d->tables[(int)n->val];
  int *e = xmalloc((size_t)t->cols * sizeof *e);
  dag_vector_entries(d, n->a, e);
  const double *row = t->v + (size_t)n->idx * (size_t)t->cols;
  double acc = row[0] * v[e[0]];
  for (int j = 1; j < t->cols; j++) acc += row[j] * v[e[j]];
  free(e);
  return acc;
}

// Start a labelled section: nodes created from now on belong to it (for
// the comments of the emitted code).
void dag_section(Dag *d, const char *label) {
  VEC_RESERVE(d->labels, d->nlabels, d->labcap, d->nlabels + 1);
  intvec_push(&d->marks, d->n);
  d->labels[d->nlabels++] = label;
}

// Mark every node reachable from the roots (mark has room for all ids).
void dag_reach(const Dag *d, const int *roots, int nroots, unsigned char *mark) {
  IntVec stack = {0};
  for (int i = 0; i < nroots; i++)
    if (roots[i] >= 0 && !mark[roots[i]]) {
      mark[roots[i]] = 1;
      intvec_push(&stack, roots[i]);
    }
  while (stack.n) {
    const Node *n = &d->nodes[stack.v[--stack.n]];
    int kids[2] = {n->a, n->b};
    for (int k = 0; k < 2; k++)
      if (kids[k] >= 0 && !mark[kids[k]]) {
        mark[kids[k]] = 1;
        intvec_push(&stack, kids[k]);
      }
  }
}

// The operations reachable from the roots: nodes with an operand, so no
// input, parameter or constant.
long dag_count_ops(const Dag *d, const int *roots, int nroots) {
  unsigned char *mark = xcalloc((size_t)d->n + 1, 1);
  dag_reach(d, roots, nroots, mark);
  long ops = 0;
  for (int id = 0; id < d->n; id++) ops += mark[id] && d->nodes[id].a >= 0;
  free(mark);
  return ops;
}

// Evaluate the roots at the given inputs and parameter values.
void dag_eval_many(const Dag *d, const int *roots, int nroots, const double *inputs, const double *params,
                   double *out) {
  int top = -1;
  for (int i = 0; i < nroots; i++)
    if (roots[i] > top) top = roots[i];
  if (top < 0) return;
  double *v = xmalloc((size_t)(top + 1) * sizeof *v);
  unsigned char *mark = xcalloc((size_t)top + 1, 1);
  dag_reach(d, roots, nroots, mark);
  for (int id = 0; id <= top; id++) {
    if (!mark[id]) continue;
    const Node *n = &d->nodes[id];
    switch ((Op)n->op) {
    case OP_CONST: v[id] = n->val; break;
    case OP_INPUT: v[id] = inputs[n->idx]; break;
    case OP_PARAM: v[id] = params[n->idx]; break;
    case OP_VEC: v[id] = 0; break;
    case OP_TROW: v[id] = table_row_value(d, n, v); break;
    case OP_SSUM: v[id] = stage_sum_value(d, n, inputs, params); break;
    default: v[id] = op_apply((Op)n->op, v[n->a], n->b >= 0 ? v[n->b] : 0);
    }
  }
  for (int i = 0; i < nroots; i++) out[i] = v[roots[i]];
  free(v);
  free(mark);
}

double dag_eval(const Dag *d, int root, const double *inputs, const double *params) {
  double out;
  dag_eval_many(d, &root, 1, inputs, params, &out);
  return out;
}

// Rebuild the roots with input slot i replaced by node map[i] (for
// i < nmap; other inputs stay). out[r] receives the image of roots[r].
void dag_subst(Dag *d, const int *roots, int nroots, const int *map, int nmap, int *out) {
  int top = -1;
  for (int i = 0; i < nroots; i++)
    if (roots[i] > top) top = roots[i];
  if (top < 0) return;
  unsigned char *mark = xcalloc((size_t)top + 1, 1);
  int *img = xmalloc((size_t)(top + 1) * sizeof *img);
  d->work += top + 1;
  dag_reach(d, roots, nroots, mark);
  for (int id = 0; id <= top; id++) {
    if (!mark[id]) continue;
    Node n = d->nodes[id];
    if (n.op == OP_INPUT && n.idx < nmap)
      img[id] = map[n.idx];
    else if (n.a < 0)
      img[id] = id;
    else if (n.op == OP_VEC) /* rebuilt link by link: the chain of the images */
      img[id] = dag_vector_link(d, img[n.a], n.b >= 0 ? img[n.b] : -1, n.idx);
    else if (n.op == OP_TROW)
      img[id] = dag_table_row(d, (int)n.val, n.idx, img[n.a]);
    else if (n.op == OP_SSUM) /* over its own stage points: no coordinate of the DAG */
      img[id] = id;
    else
      img[id] = dag_op(d, (Op)n.op, img[n.a], n.b >= 0 ? img[n.b] : -1);
  }
  for (int i = 0; i < nroots; i++) out[i] = img[roots[i]];
  free(mark);
  free(img);
}
