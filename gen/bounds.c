/* bounds.c - what interval arithmetic can prove about a node.
 *
 * dag_positive tells whether a node's value is positive for every value of
 * the inputs and params, by bounds propagated over the nodes it reaches in
 * creation order (children first): a constant is its value, an input or a
 * param anything, sin and cos within [-1, 1], sums, differences, products
 * and squares (x * x is never negative) by their interval rules, sqrt and
 * exp monotone; any other operation is unbounded. A NaN anywhere is no
 * concern of the bounds: it propagates to the result. The factorisation of
 * an M(q) (mass_ldl) uses it to drop the guard of a pivot that cannot be
 * zero or negative: 1 - cos(th1 - th2)^2 / 2 of the double pendulum in
 * angles lies in [0.5, 1]. */
#include <math.h>
#include <stdlib.h>

#include "hbvmgen.h"

typedef struct {
  double lo, hi;
} Bounds;

static const Bounds unbounded = {-INFINITY, INFINITY};

// The product's bounds: the extremes of the four corner products, or
// unbounded where one of them is NaN (0 times an infinite bound).
static Bounds product(Bounds a, Bounds b) {
  double c[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
  Bounds r = {c[0], c[0]};
  for (int i = 0; i < 4; i++) {
    if (isnan(c[i])) return unbounded;
    if (c[i] < r.lo) r.lo = c[i];
    if (c[i] > r.hi) r.hi = c[i];
  }
  return r;
}

// x * x: from 0 where the interval holds 0, else from the smaller square.
static Bounds square(Bounds a) {
  double l = a.lo * a.lo, h = a.hi * a.hi;
  Bounds r = {a.lo <= 0 && a.hi >= 0 ? 0 : fmin(l, h), fmax(l, h)};
  return r;
}

// Bounds of node n from those of its children (b[]).
static Bounds node_bounds(const Node *n, const Bounds *b) {
  Bounds r = unbounded;
  switch ((Op)n->op) {
  case OP_CONST: r.lo = r.hi = n->val; break;
  case OP_SIN:
  case OP_COS: r.lo = -1, r.hi = 1; break;
  case OP_ADD: r.lo = b[n->a].lo + b[n->b].lo, r.hi = b[n->a].hi + b[n->b].hi; break;
  case OP_SUB: r.lo = b[n->a].lo - b[n->b].hi, r.hi = b[n->a].hi - b[n->b].lo; break;
  case OP_NEG: r.lo = -b[n->a].hi, r.hi = -b[n->a].lo; break;
  case OP_MUL: r = n->a == n->b ? square(b[n->a]) : product(b[n->a], b[n->b]); break;
  case OP_SQRT: r.lo = sqrt(fmax(b[n->a].lo, 0)), r.hi = sqrt(fmax(b[n->a].hi, 0)); break;
  case OP_EXP: r.lo = exp(b[n->a].lo), r.hi = exp(b[n->a].hi); break;
  default: break;
  }
  if (isnan(r.lo) || isnan(r.hi)) r = unbounded; /* inf - inf */
  return r;
}

// 1 when node x is positive wherever it is not NaN, whatever the inputs
// and params: its lower bound is above 0 by more than the rounding the
// computation of the nodes it reaches can add (1e-8 of their largest
// finite bound, far beyond a few ulps of each operation; an unbounded
// node, such as an input under a cosine, adds no rounding to the bound).
int dag_positive(const Dag *d, int x) {
  unsigned char *mark = xcalloc((size_t)x + 1, 1);
  Bounds *b = xmalloc(((size_t)x + 1) * sizeof *b);
  double size = 0;
  dag_reach(d, &x, 1, mark);
  for (int id = 0; id <= x; id++) {
    if (!mark[id]) continue;
    b[id] = node_bounds(&d->nodes[id], b);
    if (isfinite(b[id].lo) && isfinite(b[id].hi)) size = fmax(size, fmax(fabs(b[id].lo), fabs(b[id].hi)));
  }
  int positive = b[x].lo > 1e-8 * size;
  free(mark);
  free(b);
  return positive;
}
