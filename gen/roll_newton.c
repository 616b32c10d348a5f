/* roll_newton.c - the Newton matrix of the rolled form: Hess U as band
 * families, and the layout of the rolled Newton kernels.
 *
 * On a model without constraints whose U couples each coordinate only to
 * a few others (a chain), Hess U is banded once its rows are put in the
 * right order (the natural one, or Cuthill-McKee's: band_order), and so is
 * every block I + h^2 lambda M^-1 J of the Newton matrix in A's eigenbasis
 * (step_newton.c). The t-th structural nonzero of each row is a family of
 * items (one per coordinate i) that roll.c splits into runs, so the rolled
 * kernels (emit_rolled_newton.c) evaluate J at the step's midpoint by one
 * loop per run, scatter it into the band through a table of offsets, and
 * factor each block by LU without pivoting over the band. The second derivatives are the
 * generator's own AD of grad U, as for the straight-line Newton matrix. */
#include "roll.h"
#include "step.h"

/* A band wider than this (each side) is not printed as a band: the matrix
 * is then not really banded (a pair sum is full), and the band's storage,
 * S M (2 HB + 1) reals, would approach the dense one's. */
#define NEWTON_MAX_HB 16

// The structural nonzeros of Hess U, row i from the AD of dU/dq_i (in
// column order), into rows (m of them).
static void hessian_rows(Model *mod, SparseVec *rows) {
  for (int i = 0; i < mod->m; i++) ad_gradient_sparse(mod->dag, mod->gradU[i], mod->m, &rows[i]);
}

// The half band of the pattern rows with row i at pos[i].
static int band_of(const SparseVec *rows, int m, const int *pos) {
  int hb = 0;
  for (int i = 0; i < m; i++)
    for (int e = 0; e < rows[i].n; e++) {
      int d = pos[rows[i].e[e].coord] - pos[i];
      if (d > hb) hb = d;
      if (-d > hb) hb = -d;
    }
  return hb;
}

// The order of the Newton matrix's rows: pos[i] the place of coordinate i,
// the natural one unless Cuthill-McKee's (breadth first from a coordinate
// of least degree, neighbours by increasing degree, each component in turn)
// gives a narrower band: variables x0[N], x1[N] coupled at each i (the FPU
// chain) are N apart in the natural order and 1 in that one. Returns the
// half band, *permuted whether pos is not the natural order.
static int band_order(const SparseVec *rows, int m, int *pos, int *permuted) {
  int *order = step_nodes(m), *seen = step_nodes(m), n = 0;
  for (int i = 0; i < m; i++) pos[i] = i;
  int natural = band_of(rows, m, pos);
  while (n < m) {
    int root = -1;
    for (int i = 0; i < m; i++)
      if (!seen[i] && (root < 0 || rows[i].n < rows[root].n)) root = i;
    seen[root] = 1;
    order[n++] = root;
    for (int h = n - 1; h < n; h++) {
      int first = n, v = order[h];
      for (int e = 0; e < rows[v].n; e++) {
        int c = rows[v].e[e].coord;
        if (seen[c]) continue;
        seen[c] = 1;
        int at = n++; /* insertion by degree, stable */
        while (at > first && rows[order[at - 1]].n > rows[c].n) order[at] = order[at - 1], at--;
        order[at] = c;
      }
    }
  }
  for (int k = 0; k < m; k++) pos[order[k]] = k;
  int cm = band_of(rows, m, pos);
  *permuted = cm < natural;
  if (*permuted) return cm;
  for (int i = 0; i < m; i++) pos[i] = i;
  return natural;
}

int roll_hessian(Model *mod, Roll *r, const char **why) {
  int m = mod->m, permuted;
  if (r->pairs) {
    *why = "--iteration newton or auto: the Newton matrix of a pair sum is full, not a band";
    return -1;
  }
  SparseVec *rows = arena_alloc((size_t)m * sizeof *rows);
  int *pos = step_nodes(m);
  hessian_rows(mod, rows);
  r->hb = band_order(rows, m, pos, &permuted);
  if (r->hb > NEWTON_MAX_HB) {
    static char msg[200];
    snprintf(msg, sizeof msg, "--iteration newton or auto: Hess U is a band of %d each side at best (Cuthill-McKee); "
             "the rolled Newton matrix takes at most %d", r->hb, NEWTON_MAX_HB);
    *why = msg;
    return -1;
  }
  r->hpos = permuted ? pos : NULL;
  r->ht = 0;
  for (int i = 0; i < m; i++)
    if (rows[i].n > r->ht) r->ht = rows[i].n;
  int ht = r->ht, zero = dag_const(mod->dag, 0), *items = step_nodes(m), *base = step_nodes(m);
  r->hoff = step_nodes(m * ht + 1);
  r->hess = arena_alloc((size_t)(ht + 1) * sizeof *r->hess);
  for (int i = 0; i < m; i++) {
    base[i] = i;
    for (int t = 0; t < ht; t++) r->hoff[i * ht + t] = t < rows[i].n ? pos[rows[i].e[t].coord] - pos[i] + r->hb : -1;
  }
  for (int t = 0; t < ht; t++) {
    for (int i = 0; i < m; i++) items[i] = t < rows[i].n ? rows[i].e[t].node : zero;
    if (roll_family(mod->dag, m, &r->hess[t], items, base, m)) {
      *why = "--iteration newton or auto: Hess U is not uniform in the index (more than 64 runs of one expression)";
      return -1;
    }
  }
  return 0;
}

// The layout of the rolled Newton kernels (step_build_layout): newton_factor's
// results lu (the blocks' band factors, S M (2 HB + 1) reals: a real block
// M rows, a pair's complex block M rows of re, im), pivot and adiag (S M: a
// pair's modulus twice, so that the checks read S M entries as for the
// straight-line factor), and newton_solve's dgam (S M). The lu input of
// newton_solve is that factor.
void layout_newton_rolled(Build *b) {
  Step *st = b->st;
  int m = b->m, s = b->s, permuted, *pos = step_nodes(m);
  SparseVec *rows = arena_alloc((size_t)m * sizeof *rows);
  hessian_rows(b->mod, rows);
  int nlu = s * m * (2 * band_order(rows, m, pos, &permuted) + 1);
  ASSERT(!b->nu);
  st->in[IN_LU].len = st->in[IN_LU].coef = nlu;
  step_placeholder(b, K_NFACTOR, "lu", SZ_ONE, nlu, nlu);
  step_placeholder(b, K_NFACTOR, "pivot", SZ_SM, 1, s * m);
  step_placeholder(b, K_NFACTOR, "adiag", SZ_SM, 1, s * m);
  st->kern[K_NFACTOR].what = "The Newton matrix I + h^2 A (x) M^-1 J, J = Hess U at the midpoint of the step's\n"
                             " * polynomial gam, as the blocks of A's eigenbasis in band storage, factored by LU\n"
                             " * without pivoting over the band: out = their factors, pivots (S*M), diagonal (S*M).";
  step_placeholder(b, K_NSOLVE, "dgam", SZ_SM, 1, s * m);
  st->kern[K_NSOLVE].what = "The Newton correction for the residual r = (new gamma) - gamma given as gam, with the\n"
                            " * band factors lu of newton_factor: out = (I + h^2 A (x) M^-1 J)^-1 r (S*M).";
}
