/* switch.c - the switching functions of a model: where U or g is not smooth.
 *
 * abs(a) and sign(a) have their kink or jump where a changes sign, min(a, b)
 * and max(a, b) where a - b does, floor(a) (and so mod, built from it) where
 * a crosses an integer. The arguments a (a - b for min and max) that depend
 * on a coordinate are the model's switching functions: one per distinct DAG
 * node and kind (hash-consing makes abs(x) and sign(x) share x, and the
 * sign(x) the derivative of abs(x) brings is the same node again), in the
 * order of the DAG, which is roughly that of the source. They are searched
 * in U, g, grad U and the Jacobian of g, so that a kink only the force has
 * counts as well. A function of the params alone never changes sign during a
 * run and is left out.
 *
 * The emitted solver evaluates them (NAME_switch) and the driver stops each
 * step at their sign changes (runtime/switch.c, docs/api.md). */
#include <stdio.h>
#include <stdlib.h>

#include "hbvmgen.h"

/* What the kind of a switching function is, from the op that has it. */
static int kind_of(Op op) { return op == OP_FLOOR ? SWITCH_INTEGER : SWITCH_SIGN; }

/* The function's C-free name in messages: abs, sign, min/max, floor. */
static const char *what_of(Op op) {
  switch (op) {
  case OP_ABS: return "abs";
  case OP_SIGN: return "sign";
  case OP_FLOOR: return "floor";
  default: return "min/max";
  }
}

/* The index of the switching function (node, kind) among the first n, or -1. */
static int find_switch(const Model *mod, int n, int node, int kind) {
  for (int i = 0; i < n; i++)
    if (mod->switch_nodes[i] == node && mod->switch_kinds[i] == kind) return i;
  return -1;
}

/* Mark (with bit) the nodes reachable from the n roots. */
static void reach_bit(const Dag *d, const int *roots, int n, unsigned char *mark, unsigned char bit) {
  unsigned char *here = xcalloc((size_t)d->n + 1, 1);
  dag_reach(d, roots, n, here);
  for (int id = 0; id < d->n; id++)
    if (here[id]) mark[id] |= bit;
  free(here);
}

/* Whether op has a kink or a jump. */
static int nonsmooth(Op op) { return op == OP_ABS || op == OP_SIGN || op == OP_MIN || op == OP_MAX || op == OP_FLOOR; }

// Fill mod->nswitch, switch_nodes, switch_kinds, switch_what and
// switch_in_U (call after model_differentiate).
void model_switches(Model *mod) {
  Dag *d = mod->dag;
  int top = d->n, most = 0, n = 0;
  unsigned char *mark = xcalloc((size_t)top + 1, 1);
  reach_bit(d, &mod->U, 1, mark, 1);
  reach_bit(d, mod->gradU, mod->m, mark, 1);
  reach_bit(d, mod->g, mod->nu, mark, 2);
  IntVec jac = {0}; /* the Jacobian's entries, reached in one pass (a pass an entry was quadratic) */
  for (int a = 0; a < mod->nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) intvec_push(&jac, mod->jac[a].e[e].node);
  reach_bit(d, jac.v, jac.n, mark, 2); /* (jac.v is the arena's) */
  for (int id = 0; id < top; id++) most += mark[id] && nonsmooth((Op)d->nodes[id].op);
  mod->switch_nodes = arena_alloc((size_t)(most + 1) * sizeof(int));
  mod->switch_kinds = arena_alloc((size_t)(most + 1) * sizeof(int));
  mod->switch_what = arena_alloc((size_t)(most + 1) * sizeof(char *));
  for (int id = 0; id < top; id++) {
    const Node *nd = &d->nodes[id];
    Op op = (Op)nd->op;
    if (!mark[id] || !nonsmooth(op)) continue;
    int arg = op == OP_MIN || op == OP_MAX ? dag_sub(d, nd->a, nd->b) : nd->a;
    if (!(d->nodes[arg].flags & DEP_INPUT) || find_switch(mod, n, arg, kind_of(op)) >= 0) continue;
    mod->switch_nodes[n] = arg;
    mod->switch_kinds[n] = kind_of(op);
    mod->switch_what[n] = what_of(op);
    mod->switch_in_U |= mark[id] & 1;
    n++;
  }
  mod->nswitch = n;
  free(mark);
}

// The generation-time warning of a model with switching functions: at U
// when U has one, else at the first constraint.
void switch_warn(const Model *mod) {
  if (!mod->nswitch) return;
  char list[64] = "";
  const char *seen[5];
  int nseen = 0;
  size_t len = 0;
  for (int i = 0; i < mod->nswitch && len < sizeof list - 16; i++) {
    int dup = 0;
    for (int j = 0; j < nseen; j++) dup |= seen[j] == mod->switch_what[i];
    if (dup || nseen == 5) continue;
    seen[nseen++] = mod->switch_what[i];
    len += (size_t)snprintf(list + len, sizeof list - len, "%s%s", len ? ", " : "", mod->switch_what[i]);
  }
  Loc at = mod->switch_in_U || !mod->nu ? mod->U_loc : mod->g_loc[0];
  warning_at(at, "%s not smooth (%s): %d switching function%s; the driver ends a step on each point where one "
             "changes sign (crosses an integer, for floor) and restarts there (--no-switch: off; docs/language.md, "
             "\"Kinks and jumps\")",
             mod->switch_in_U ? "U is" : "g is", list, mod->nswitch, mod->nswitch == 1 ? "" : "s");
}
