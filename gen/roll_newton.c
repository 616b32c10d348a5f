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
 * generator's own AD of grad U, as for the straight-line Newton matrix.
 *
 * With constraints (the constant family) J = Hess(U + lambda' g): row i also
 * has, for each constraint a on coordinate i, the row of Hess g_a (the AD of
 * d g_a / dq_i), an entry of its own that the kernel multiplies by lambda_a.
 * The multiplier's column V and row C couple the blocks of A's eigenbasis
 * (one constant lambda for the whole step), and its Schur complement
 * C N^-1 V, which the straight-line step forms, is dense on a chain (N^-1 of
 * a band is full). So the rolled step factors the whole saddle point
 *     [[D, Vt], [Ct, 0]],  D = the blocks of A's eigenbasis (step_newton.c),
 * Vt = (T^-1 (x) I) V rotated as each pair's block, Ct = C (T (x) I),
 * as one real band (kkt_rows): the rows in the order of the coordinates (the
 * band order, here of Hess J together with the coupling of two coordinates by
 * a constraint), coordinate i's s unknowns (one per real eigenvalue, re and
 * im per pair) side by side, and each constraint's row right after the last
 * coordinate it reads. That is a band of a few times s each side on a chain,
 * and LU without pivoting over it is safe where the straight-line factor is:
 *   - the pivots of a coordinate's rows are those of a leading block of D
 *     bordered by complete constraints. D's leading blocks are principal
 *     submatrices of the blocks, whose symmetric part (rows scaled by M) is
 *     positive definite wherever J is positive semidefinite (step_newton.c);
 *     the constraints before them do not read these coordinates;
 *   - the pivot of constraint a's row comes after every coordinate a reads,
 *     so the leading block is the saddle point of the sub-chain of the
 *     coordinates so far (the others held), and its last pivot is a diagonal
 *     entry of that sub-problem's Schur complement C_k N_k^-1 V_k: as h -> 0
 *     the multiplier matrix of its constraints, whose symmetric part xi_0
 *     rho_0' M^-1 rho_0 is positive definite for independent constraints;
 *     for long steps it is nonsingular under the condition the straight-line
 *     step's S needs.
 * Every pivot is still checked at run time against its row's scale (a
 * constraint row's: sum_k |C_ak V_ka|, its diagonal being 0), and a small
 * one makes the factorisation fail (NAME_ENOCONV) as in the straight-line
 * step. */
#include <stdlib.h>
#include <string.h>

#include "roll.h"
#include "step.h"

/* A band wider than this (each side) is not printed as a band: the matrix
 * is then not really banded (a pair sum is full), and the band's storage,
 * S M (2 HB + 1) reals, would approach the dense one's. */
#define NEWTON_MAX_HB 16
/* ... and the saddle point's band (with constraints) wider than this, whose
 * storage is S M + NU rows of 2 KHB + 1 reals. */
#define NEWTON_MAX_KHB 96

/* The structure of the rolled Newton matrix (newton_pattern): J's rows
 * (rows[i], an entry per structural nonzero of Hess U's row i, then of each
 * constraint's Hess g_a row i; lam[i][e] = a for those, else -1), the band's
 * order (pos, hb, permuted), and with constraints the saddle point's rows
 * (kkt_rows: krow, kcon, kn, khb) and T, the most constraints on one
 * coordinate. */
typedef struct {
  SparseVec *rows;
  int **lam;
  int *pos, hb, permuted;
  int *krow, *kcon, kn, khb, T;
} NewtonPattern;

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

// The rows of J = Hess(U + lambda' g) (with constraints): each row i of
// Hess U followed by, for each constraint a on coordinate i (in increasing
// a), the structural nonzeros of d (d g_a / dq_i) / dq, lam[i][e] = a.
static void lagrangian_rows(Model *mod, NewtonPattern *np) {
  int m = mod->m;
  np->lam = arena_alloc((size_t)m * sizeof *np->lam);
  IntVec *con = arena_alloc((size_t)m * sizeof *con), *nodes = arena_alloc((size_t)m * sizeof *nodes);
  for (int a = 0; a < mod->nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) {
      intvec_push(&con[mod->jac[a].e[e].coord], a);
      intvec_push(&nodes[mod->jac[a].e[e].coord], mod->jac[a].e[e].node);
    }
  for (int i = 0; i < m; i++) {
    if (con[i].n > np->T) np->T = con[i].n;
    SparseVec *hg = arena_alloc((size_t)(con[i].n + 1) * sizeof *hg);
    int n = np->rows[i].n;
    for (int t = 0; t < con[i].n; t++) {
      ad_gradient_sparse(mod->dag, nodes[i].v[t], m, &hg[t]);
      n += hg[t].n;
    }
    Entry *all = arena_alloc((size_t)(n + 1) * sizeof *all);
    np->lam[i] = step_nodes(n + 1);
    memcpy(all, np->rows[i].e, (size_t)np->rows[i].n * sizeof *all);
    for (int k = 0; k < np->rows[i].n; k++) np->lam[i][k] = -1;
    for (int t = 0, k = np->rows[i].n; t < con[i].n; t++)
      for (int e = 0; e < hg[t].n; e++, k++) {
        all[k] = hg[t].e[e];
        np->lam[i][k] = con[i].v[t];
      }
    np->rows[i].e = all;
    np->rows[i].n = n;
  }
}

// The pattern the band's order is chosen on: J's rows, and with
// constraints also every coordinate a constraint on coordinate i reads (the
// multiplier couples them: its row and column must fit in the band).
static SparseVec *order_rows(const Model *mod, const NewtonPattern *np) {
  int m = mod->m;
  if (!mod->nu) return np->rows;
  IntVec *adj = arena_alloc((size_t)m * sizeof *adj);
  for (int i = 0; i < m; i++)
    for (int e = 0; e < np->rows[i].n; e++) intvec_push(&adj[i], np->rows[i].e[e].coord);
  for (int a = 0; a < mod->nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++)
      for (int f = 0; f < mod->jac[a].n; f++) intvec_push(&adj[mod->jac[a].e[e].coord], mod->jac[a].e[f].coord);
  SparseVec *o = arena_alloc((size_t)m * sizeof *o);
  for (int i = 0; i < m; i++) {
    o[i].n = adj[i].n;
    o[i].e = arena_alloc((size_t)(adj[i].n + 1) * sizeof *o[i].e);
    for (int k = 0; k < adj[i].n; k++) o[i].e[k].coord = adj[i].v[k];
  }
  return o;
}

// The saddle point's rows (the file's comment): in the band's order, the s
// rows of each coordinate, then those of the constraints whose last
// coordinate it is, nrc a constraint (1, or the poly family's s
// coefficients); its half band, with pair (A has a complex pair) the pair's
// re row one further from its im column.
static void kkt_rows(const Model *mod, int s, int pair, int nrc, NewtonPattern *np) {
  int m = mod->m, nu = mod->nu, *order = step_nodes(m), *last = step_nodes(nu + 1), row = 0;
  IntVec *after = arena_alloc((size_t)m * sizeof *after);
  for (int i = 0; i < m; i++) order[np->pos[i]] = i;
  for (int a = 0; a < nu; a++) {
    last[a] = 0;
    for (int e = 0; e < mod->jac[a].n; e++)
      if (np->pos[mod->jac[a].e[e].coord] > last[a]) last[a] = np->pos[mod->jac[a].e[e].coord];
    intvec_push(&after[last[a]], a);
  }
  np->krow = step_nodes(m);
  np->kcon = step_nodes(nu + 1);
  for (int p = 0; p < m; p++) {
    np->krow[order[p]] = row;
    row += s;
    for (int k = 0; k < after[p].n; k++, row += nrc) np->kcon[after[p].v[k]] = row;
  }
  np->kn = row;
  np->khb = 0;
  for (int i = 0; i < m; i++)
    for (int e = 0; e < np->rows[i].n; e++) {
      int d = abs(np->krow[np->rows[i].e[e].coord] - np->krow[i]) + pair;
      if (d > np->khb) np->khb = d;
    }
  for (int a = 0; a < nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) {
      int d = np->kcon[a] + nrc - 1 - np->krow[mod->jac[a].e[e].coord]; /* > 0: the rows come after its coordinates */
      if (d > np->khb) np->khb = d;
    }
}

// Whether A (the method's matrix) has a complex pair: every s >= 2.
static int has_pair(const Method *me) {
  NewtonBasis nb;
  newton_basis(me, &nb);
  for (int q = 0; q < nb.nblocks; q++)
    if (nb.blk[q].pair) return 1;
  return 0;
}

// The rolled Newton matrix's structure (NewtonPattern) of mod at the method me.
static void newton_pattern(Model *mod, const Method *me, NewtonPattern *np) {
  int m = mod->m;
  memset(np, 0, sizeof *np);
  np->rows = arena_alloc((size_t)m * sizeof *np->rows);
  np->pos = step_nodes(m);
  hessian_rows(mod, np->rows);
  if (mod->nu) lagrangian_rows(mod, np);
  np->hb = band_order(order_rows(mod, np), m, np->pos, &np->permuted);
  if (mod->nu) kkt_rows(mod, me->s, has_pair(me), me->family == MULT_POLY ? me->s : 1, np);
}

int roll_hessian(Model *mod, const Method *me, Roll *r, const char **why) {
  int m = mod->m;
  NewtonPattern np;
  newton_pattern(mod, me, &np);
  if (r->pairs && np.hb >= m - 1) { /* (U's terms rolled as pairs, yet local: a polymer's angles, its band) */
    *why = "--iteration newton or auto: the Newton matrix of a pair sum is full, not a band";
    return -1;
  }
  SparseVec *rows = np.rows;
  int *pos = np.pos, permuted = np.permuted;
  r->hb = np.hb;
  if (r->hb > NEWTON_MAX_HB) {
    static char msg[200];
    snprintf(msg, sizeof msg, "--iteration newton or auto: Hess U is a band of %d each side at best (Cuthill-McKee); "
             "the rolled Newton matrix takes at most %d", r->hb, NEWTON_MAX_HB);
    *why = msg;
    return -1;
  }
  if (mod->nu && np.khb > NEWTON_MAX_KHB) {
    static char msg[200];
    snprintf(msg, sizeof msg, "--iteration newton or auto: the Newton matrix with the multiplier is a band of %d each "
             "side; the rolled form takes at most %d", np.khb, NEWTON_MAX_KHB);
    *why = msg;
    return -1;
  }
  r->hpos = permuted ? pos : NULL;
  r->hlam = NULL;
  r->krow = np.krow;
  r->kcon = np.kcon;
  r->kn = np.kn;
  r->khb = np.khb;
  r->ht = 0;
  for (int i = 0; i < m; i++)
    if (rows[i].n > r->ht) r->ht = rows[i].n;
  int ht = r->ht, zero = dag_const(mod->dag, 0), *items = step_nodes(m), *base = step_nodes(m);
  r->hoff = step_nodes(m * ht + 1);
  r->hess = arena_alloc((size_t)(ht + 1) * sizeof *r->hess);
  if (mod->nu) r->hlam = step_nodes(m * ht + 1);
  for (int i = 0; i < m; i++) {
    base[i] = i;
    for (int t = 0; t < ht; t++) {
      int c = t < rows[i].n ? rows[i].e[t].coord : -1;
      if (!mod->nu) r->hoff[i * ht + t] = c >= 0 ? pos[c] - pos[i] + r->hb : -1;
      else r->hoff[i * ht + t] = c >= 0 ? np.krow[c] - np.krow[i] + np.khb : -1;
      if (mod->nu) r->hlam[i * ht + t] = c >= 0 ? np.lam[i][t] : -1;
    }
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
// M rows, a pair's complex block M rows of re, im; with constraints the
// saddle point's band factor, KN (2 KHB + 1) reals, and rho_j, S M T), pivot
// and adiag (S M: a pair's modulus twice, so that the checks read S M entries
// as for the straight-line factor; with constraints the real pivots of the
// coordinates' rows), with constraints spivot and sadiag (NU: the pivots of
// the constraints' rows and their scale), and newton_solve's dgam (S M). The
// lu input of newton_solve is that factor; with constraints the input lam (S
// NU, the first NU read) comes before it, as in build_newton.
void layout_newton_rolled(Build *b) {
  Step *st = b->st;
  int m = b->m, s = b->s, nu = b->nu;
  NewtonPattern np;
  newton_pattern(b->mod, b->me, &np);
  int poly = nu && b->me->family == MULT_POLY, nc = poly ? s * nu : nu;
  int nlu = nu ? np.kn * (2 * np.khb + 1) + (poly ? s * (s + 1) / 2 : s) * m * np.T : s * m * (2 * np.hb + 1);
  if (nu && !poly) {
    st->in[IN_LAM].len = s * nu;
    st->in[IN_LU].first = st->in[IN_LAM].first + st->in[IN_LAM].len;
  }
  if (!poly || st->in[IN_LU].len < nlu) st->in[IN_LU].len = st->in[IN_LU].coef = nlu; /* (the poly sweep's lu shares it) */
  step_placeholder(b, K_NFACTOR, "lu", SZ_ONE, nlu, nlu);
  step_placeholder(b, K_NFACTOR, "pivot", SZ_SM, 1, s * m);
  step_placeholder(b, K_NFACTOR, "adiag", SZ_SM, 1, s * m);
  if (nu) {
    step_placeholder(b, K_NFACTOR, "spivot", poly ? SZ_SNU : SZ_NU, 1, nc);
    step_placeholder(b, K_NFACTOR, "sadiag", poly ? SZ_SNU : SZ_NU, 1, nc);
  }
  st->kern[K_NFACTOR].what =
      nu ? "The Newton matrix I + h^2 A (x) M^-1 J, J = Hess(U + lam' g) at the midpoint of the step's\n"
           " * polynomial gam, as the blocks of A's eigenbasis, with the multiplier's column V and row C:\n"
           " * the saddle point [[D, Vt], [Ct, 0]] as one band, factored by LU without pivoting: out = its\n"
           " * factor and rho_j (what newton_solve reads as lu), pivots (S*M), diagonal (S*M), the\n"
           " * constraints' pivots (NU) and scale (NU)."
         : "The Newton matrix I + h^2 A (x) M^-1 J, J = Hess U at the midpoint of the step's\n"
           " * polynomial gam, as the blocks of A's eigenbasis in band storage, factored by LU\n"
           " * without pivoting over the band: out = their factors, pivots (S*M), diagonal (S*M).";
  step_placeholder(b, K_NSOLVE, "dgam", SZ_SM, 1, s * m);
  if (poly) step_placeholder(b, K_NSOLVE, "dlam", SZ_SNU, 1, nc);
  if (poly)
    st->kern[K_NFACTOR].what =
        "The Newton matrix I + h^2 A (x) M^-1 J, J = Hess(U + lam_0' g) at the midpoint of the step's\n"
        " * polynomial gam, as the blocks of A's eigenbasis, with the polynomial multiplier's columns V and\n"
        " * rows C (S a constraint): the saddle point [[D, Vt], [Ct, 0]] as one band, factored by LU without\n"
        " * pivoting: out = its factor and the moments R_jr (what newton_solve reads as lu), pivots (S*M),\n"
        " * diagonal (S*M), the constraints' pivots (S*NU) and scale (S*NU).";
  st->kern[K_NSOLVE].what =
      poly ? "The Newton correction for the residual r = (new gamma) - gamma given as gam, with\n"
             " * what newton_factor left in lu: out = dgam, N dgam + V mu = r, C dgam = C r (S*M),\n"
             " * and the multiplier's coefficients' change mu / h (S*NU)."
      : nu ? "The Newton correction for the residual r = (new gamma) - gamma given as gam, with\n"
           " * what newton_factor left in lu: out = dgam, N dgam + V mu = r, C dgam = C r (S*M)."
         : "The Newton correction for the residual r = (new gamma) - gamma given as gam, with the\n"
           " * band factors lu of newton_factor: out = (I + h^2 A (x) M^-1 J)^-1 r (S*M).";
}
