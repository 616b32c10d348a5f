/* emit_rolled.c - the kernels of the rolled form: loops over the model's index.
 *
 * With e->roll (roll_choose, roll.c) the kernels of the step keep their
 * signatures and result blocks, so that everything the other emitters print
 * around them (the iteration, the error control, dense output, events,
 * NAME_project) is unchanged, but their bodies are loops whose length does
 * not grow the C:
 *   - each family of the model (dU/dq_i, the Jacobian entries, g, the terms
 *     of U, the curvatures) is one function with a loop per run of roll.c:
 *     the run's expression printed once, with q[b + offset] for its inputs;
 *     runs of one item (the boundary terms) print straight-line;
 *   - the stages, the Legendre projections, the update of gamma and the
 *     products with M^-1 (diagonal) are loops over the coordinates;
 *   - G' M^-1 G and the multiplier system of the paper are assembled by a
 *     loop over the coordinates and the constraints on each (the table
 *     tcon; in the sweep one loop per segment of coordinates whose
 *     constraints are affine in i, emit_rolled_tcon.c) into band storage,
 *     A[a][c] at A[a * W + c - a + BW], and factored
 *     and solved by LU without pivoting over the band (the same elimination
 *     lu.c prints unrolled: its symmetric part is positive definite).
 * The sums are those of the straight-line kernels, but some are taken in
 * another order (docs/rolled.md says which): results agree to round-off.
 * Work arrays are locals of the kernels: 2 (S + 1) M + (S + 1) T M + NU (2 BW
 * + 2) reals of stack in the sweep. */
#include <stdlib.h>
#include <string.h>

#include "emit.h"
#include "roll.h"

#define NAME_SIZE 256

// The C name of node id inside a run's body: a literal, a parameter, an
// input at its offset from the base b (the second array's shifted by
// vshift), or the temporary rK of its place k.
static void body_name(Emitter *e, const RollRun *r, int id, int vshift, char *buf, size_t size) {
  const Node *n = &e->mod->dag->nodes[id];
  int m = e->mod->m;
  switch ((Op)n->op) {
  case OP_CONST: format_real(e, buf, size, n->val); return;
  case OP_PARAM: snprintf(buf, size, "prm->%s", e->mod->params[n->idx].name); return;
  case OP_INPUT: {
    int off = n->idx % m - r->b0 + (n->idx < m ? 0 : vshift);
    snprintf(buf, size, off ? "%s[b %c %d]" : "%s[b]", n->idx < m ? "q" : "v", off < 0 ? '-' : '+', off < 0 ? -off : off);
    return;
  }
  default:
    for (int k = r->nbody - 1; k >= 0; k--)
      if (r->body[k] == id) {
        snprintf(buf, size, "r%d", k);
        return;
      }
    internal_error("a rolled body reads node %d outside it", id);
  }
}

// One run of a family: its items' loop (or one block for a single item),
// the body once, and what is done with the root's value: out[U * os + oo]
// = value, or with os = 0, acc += value. With reps > 1 the body is printed
// reps times in the loop, the j-th in a block of its own with the second
// array read at vstride j further on and out at ostride j further on (the s
// projections of the linear part in one loop), out[] = for j >= 1 with set.
static void emit_run(Emitter *e, const RollRun *r, int os, int oo, int reps, int vstride, int ostride, int set) {
  const Dag *d = e->mod->dag;
  char a[NAME_SIZE], b[NAME_SIZE], rhs[8 * NAME_SIZE];
  if (r->n == 1) out(e, "  { /* item %d */\n    const int u = %d, b = %d;\n", r->u0, r->u0, r->b0);
  else if (r->stride == 1 && r->b0 == r->u0)
    out(e, "  for (u = %d; u < %d; u++) { /* items %d..%d */\n    const int b = u;\n", r->u0, r->u0 + r->n, r->u0, r->u0 + r->n - 1);
  else
    out(e, "  for (u = %d; u < %d; u++) { /* items %d..%d */\n    const int b = %d + %d * (u - %d);\n", r->u0, r->u0 + r->n,
        r->u0, r->u0 + r->n - 1, r->b0, r->stride, r->u0);
  out(e, "    (void)u; (void)b;\n");
  for (int j = 0; j < reps; j++) {
    const char *in = reps > 1 ? "  " : "";
    if (reps > 1) out(e, "    {\n");
    for (int k = 0; k < r->nbody; k++) {
      const Node *n = &d->nodes[r->body[k]];
      if (n->a < 0) continue; /* leaves are named where they are read */
      body_name(e, r, n->a, j * vstride, a, sizeof a);
      if (n->b >= 0) body_name(e, r, n->b, j * vstride, b, sizeof b);
      op_rhs(e, n, a, b, rhs, sizeof rhs);
      out(e, "    %sconst %s r%d = %s;\n", in, real_type(e, 0), k, rhs);
    }
    body_name(e, r, r->body[r->nbody - 1], j * vstride, a, sizeof a);
    if (os) out(e, "    %sout[%d * u + %d] %s= %s;\n", in, os < 0 ? -os : os, oo + j * ostride, os < 0 && !(set && j) ? "+" : "", a);
    else out(e, "    %sacc += %s;\n", in, a);
    if (reps > 1) out(e, "    }\n");
  }
  out(e, "  }\n");
}

void rolled_run(Emitter *e, const RollRun *r, int os, int oo) { emit_run(e, r, os, oo, 1, 0, 0, 0); }

// A family as the function $P_roll_NAME(q, v, prm, out): out[i] for its
// items; with mode 1 out[0] = the sum of them in order, with mode -1 out[i]
// += item i.
static void emit_family(Emitter *e, const char *name, const char *what, const RollFamily *f, int mode) {
  tmplf(e, "\n/* %s */\nstatic void $P_roll_%s(const $R *q, const $R *v, const $P_params *prm, $R *out)\n{\n"
           "  int u = 0;\n%s  (void)q; (void)v; (void)prm; (void)u;\n", what, name, mode == 1 ? "  $R acc = 0;\n" : "");
  for (int i = 0; i < f->nruns; i++) emit_run(e, &f->runs[i], mode == 1 ? 0 : mode ? -1 : 1, 0, 1, 0, 0, 0);
  out(e, mode == 1 ? "  out[0] = acc;\n}\n" : "}\n");
}

// Whether the runs of the T families fams[t] cover every coordinate's item.
static int tfamily_covers(const Roll *r, const RollFamily *const *fams) {
  for (int t = 0; t < r->T; t++) {
    int n = 0;
    for (int i = 0; i < fams[t]->nruns; i++) n += fams[t]->runs[i].n;
    if (n != r->m) return 0;
  }
  return 1;
}

// A family per t of the Jacobian's entries (fams[t]) as the function
// $P_roll_NAME: out[T i + t] = item i of family t. With add (the linear
// part), out[j M T + T i + t] += item i at v + j M, for the s projections j
// at once (one loop per run, not s); where its runs cover every item, =
// for j >= 1 (the sweep does not zero them first: lin_sets).
static void emit_tfamily(Emitter *e, const char *name, const char *what, const RollFamily *const *fams, int add) {
  int T = e->roll->T, m = e->mod->m, reps = add ? e->me->s : 1, set = add && tfamily_covers(e->roll, fams);
  tmplf(e, "\n/* %s: out[$P_RT * i + t] for a = $P_tcon[$P_RT * i + t] (0 where a < 0)%s */\n"
           "static void $P_roll_%s(const $R *q, const $R *v, const $P_params *prm, $R *out)\n{\n"
           "  int u = 0;\n  (void)q; (void)v; (void)prm; (void)u;\n", what,
        add ? (set ? ", at v + j M into out + j M T for j = 0..S-1 (= for j >= 1)" : ", at v + j M into out + j M T for j = 0..S-1") : "",
        name);
  for (int t = 0; t < T; t++)
    for (int i = 0; i < fams[t]->nruns; i++) emit_run(e, &fams[t]->runs[i], add ? -T : T, t, reps, m, m * T, set);
  out(e, "}\n");
}

// Which part of a split family: the whole, or its affine, linear or curved items.
enum { PART_ALL, PART_AFFINE, PART_LIN, PART_CURVED };

static const RollFamily *jac_part(const Roll *r, int t, int part) {
  return part == PART_ALL ? &r->jac[t] : part == PART_AFFINE ? &r->jac_s[t].affine : part == PART_LIN ? &r->jac_s[t].lin
                                                                                                      : &r->jac_s[t].curved;
}

// Whether part of the Jacobian has a nonzero item.
static int jac_used(const Roll *r, int part) {
  int used = 0;
  for (int t = 0; t < r->T; t++) used |= !jac_part(r, t, part)->zero;
  return used;
}

// Whether $P_roll_jac_lin sets rho_j for j >= 1 (emit_tfamily), so that the
// sweep of the const family need not zero them.
static int lin_sets(const Roll *r) {
  const RollFamily **f = xmalloc((size_t)(r->T + 1) * sizeof *f);
  for (int t = 0; t < r->T; t++) f[t] = &r->jac_s[t].lin;
  int set = jac_used(r, PART_LIN) && tfamily_covers(r, f);
  free(f);
  return set;
}

// The Jacobian's families: the whole, and the parts the sweep uses.
static void emit_jacobians(Emitter *e) {
  static const char *const name[] = {"jac", "jac_affine", "jac_lin", "jac_curved"};
  static const char *const what[] = {"the Jacobian's entries d g_a / dq_i", "its affine entries (else 0)",
                                     "out += the linear part sum_k d^2 g_a / dq_i dq_k v_k of its affine entries",
                                     "its curved entries (else 0)"};
  const Roll *r = e->roll;
  const RollFamily **f = xmalloc((size_t)(r->T + 1) * sizeof *f);
  for (int part = PART_ALL; part <= PART_CURVED; part++) {
    if (part != PART_ALL && (!jac_used(r, part) || e->me->family == MULT_POLY)) continue; /* (poly: moments of the whole) */
    for (int t = 0; t < r->T; t++) f[t] = jac_part(r, t, part);
    emit_tfamily(e, name[part], what[part], f, part == PART_LIN);
  }
  free(f);
}

// A table of n reals (or ints) as a static const array, sixteen a line.
static void emit_array(Emitter *e, const char *type, const char *name, const double *v, const int *iv, int n) {
  char lit[64];
  tmplf(e, "static const %s $P_%s[%d] = {", type, name, n > 0 ? n : 1);
  for (int i = 0; i < n; i++) {
    if (iv) snprintf(lit, sizeof lit, "%d", iv[i]);
    else format_real(e, lit, sizeof lit, v[i]);
    out(e, "%s%s%s", i ? "," : "", i % 16 ? " " : "\n  ", lit);
  }
  out(e, n > 0 ? "\n};\n" : "0};\n");
}

void rolled_int_table(Emitter *e, const char *type, const char *name, const int *v, int n) { emit_array(e, type, name, NULL, v, n); }

// B = G' M^-1 G in band storage from the Jacobian's entries, one loop over
// the coordinates with the T constraints on each unrolled.
static void emit_gram(Emitter *e) {
  const Roll *r = e->roll;
  int T = r->T, W = 2 * r->bw + 1;
  tmpl(e, "/* B = G' M^-1 G in band storage, G the Jacobian's entries J ($P_roll_jac). */\n"
          "static void $P_roll_gram(const $R *J, $R *B)\n{\n"
          "  int i;\n"
          "  for (i = 0; i < $P_NU * $P_RW; i++) B[i] = 0;\n");
  out(e, "  for (i = 0; i < %d; i++) {\n", r->m);
  for (int t = 0; t < T; t++) out(e, "    const int a%d = %s_tcon[%d * i + %d];\n", t, e->P, T, t);
  for (int t = 0; t < T; t++)
    for (int u = 0; u < T; u++)
      out(e, "    if (a%d >= 0 && a%d >= 0) B[a%d * %d + a%d - a%d + %d] += J[%d * i + %d] * (%s%sJ[%d * i + %d]);\n", t, u, t, W,
          u, t, r->bw, T, t, r->identity ? "" : e->P, r->identity ? "" : "_rminv[i] * ", T, u);
  out(e, "  }\n}\n");
}

// The band LU of the multiplier system and of G' M^-1 G: factor in place
// (multipliers below the diagonal), pivots and the diagonal it started from;
// solve in place.
static void emit_band(Emitter *e) {
  int bw = e->roll->bw;
  tmpl(e, "\n/* A (NU x NU, band storage A[a * $P_RW + c - a + $P_RBW]) = L U without pivoting, in place:\n"
          " * pivot[k] the k-th pivot, adiag[k] the diagonal entry it started from. The band's\n"
          " * offsets are unrolled. */\n"
          "static void $P_band_factor($R *A, $R *pivot, $R *adiag)\n{\n"
          "  int k;\n"
          "  for (k = 0; k < $P_NU; k++) adiag[k] = A[k * $P_RW + $P_RBW];\n"
          "  for (k = 0; k < $P_NU; k++) {\n"
          "    const $R *Ak = A + k * $P_RW + $P_RBW;  /* Ak[c - k] = A[k][c] */\n"
          "    pivot[k] = Ak[0];\n");
  for (int d = 1; d <= bw; d++) {
    tmplf(e, "    if (k + %d < $P_NU) {\n"
             "      $R *Ai = A + (k + %d) * $P_RW + $P_RBW - %d;  /* Ai[c - k] = A[k + %d][c] */\n"
             "      const $R f = Ai[0] / Ak[0];\n"
             "      Ai[0] = f;\n", d, d, d, d);
    for (int c = 1; c <= bw; c++) tmplf(e, "      if (k + %d < $P_NU) Ai[%d] -= f * Ak[%d];\n", c, c, c);
    out(e, "    }\n");
  }
  tmpl(e, "  }\n}\n\n"
          "/* x = A^-1 x for A factored by $P_band_factor. */\n"
          "static void $P_band_solve(const $R *A, $R *x)\n{\n"
          "  int k;\n");
  if (bw) tmpl(e, "  for (k = 0; k < $P_NU; k++) {\n    const $R xk = x[k];\n");
  for (int d = 1; d <= bw; d++) tmplf(e, "    if (k + %d < $P_NU) x[k + %d] -= A[(k + %d) * $P_RW + $P_RBW - %d] * xk;\n", d, d, d, d);
  if (bw) tmpl(e, "  }\n");
  tmpl(e, "  for (k = $P_NU - 1; k >= 0; k--) {\n"
          "    $R acc = x[k];\n");
  for (int c = 1; c <= bw; c++) tmplf(e, "    if (k + %d < $P_NU) acc -= A[k * $P_RW + $P_RBW + %d] * x[k + %d];\n", c, c, c);
  tmpl(e, "    x[k] = acc / A[k * $P_RW + $P_RBW];\n  }\n}\n\n");
  emit_gram(e);
}

// Everything the rolled kernels share, printed before the first of them:
// the sizes, the tables (tcon, M^-1, the method's constants) and the
// family functions.
static void emit_helpers(Emitter *e) {
  const Roll *r = e->roll;
  int m = e->mod->m;
  tmplf(e, "\n/* The rolled form (docs/rolled.md): the model's index kept as loops. T = most constraints\n"
           " * on one coordinate, BW = the half band of the multiplier system. */\n"
           "#define $P_RT %d\n#define $P_RBW %d\n#define $P_RW (2 * $P_RBW + 1)\n", r->T, r->bw);
  if (r->identity) tmpl(e, "#define $P_MINV(i) /* M = I */\n");
  else {
    emit_array(e, real_type(e, 0), "rminv", e->mod->minv_diag, NULL, m);
    tmpl(e, "#define $P_MINV(i) $P_rminv[i] *\n");
  }
  if (r->T) emit_array(e, "int", "tcon", NULL, r->tcon, m * r->T);
  if (!r->gradU_s.affine.zero) emit_family(e, "gradU_affine", "out[i] = dU/dq_i where it is affine in q, else 0", &r->gradU_s.affine, 0);
  if (!r->gradU_s.lin.zero) emit_family(e, "gradU_lin", "out[i] += sum_k d^2U/dq_i dq_k v_k where dU/dq_i is affine", &r->gradU_s.lin, -1);
  if (r->pairs) emit_roll_pairs(e, "gradU_curved", "out[i] = dU/dq_i", 0);
  else if (!r->gradU_s.curved.zero) emit_family(e, "gradU_curved", "out[i] = dU/dq_i where it is not affine in q, else 0", &r->gradU_s.curved, 0);
  if (r->pairs) emit_roll_pairs(e, "U", "out[0] = U(q)", 1);
  else emit_family(e, "U", "out[0] = U(q), its terms in the order of its sums", &r->U, 1);
  if (r->nu) {
    if (r->pairs) tmpl(e, "#define $P_roll_gradU $P_roll_gradU_curved /* the same pair loops */\n");
    else emit_family(e, "gradU", "out[i] = dU/dq_i", &r->gradU, 0);
    emit_family(e, "g", "out[a] = g_a(q)", &r->g, 0);
    emit_family(e, "hvv", "out[a] = v' Hess(g_a)(q) v", &r->hvv, 0);
    emit_jacobians(e);
    emit_band(e);
    if (e->me->family == MULT_POLY) rolled_poly_helpers(e);
  }
  e->roll_helpers = 1;
}

// A real literal of the method's constants.
const char *rolled_lit(Emitter *e, double v) {
  static char buf[8][48];
  static int next;
  char *b = buf[next++ % 8];
  format_real(e, b, 48, v);
  return b;
}

// Print "DST = SRC-combination" of X row j (METHOD.md): xi_j v_{j-1} -
// xi_{j+1} v_{j+1} (v_0 for j = 0, the second term absent for j = s-1),
// v_r read as fmt with r * stride (an offset) and name.
void rolled_x_row(Emitter *e, int j, const char *name, int stride, char *buf, size_t size) {
  const double *xi = e->me->xi;
  int n = snprintf(buf, size, "%s * %s[%d + i]", rolled_lit(e, xi[j]), name, (j ? j - 1 : 0) * stride);
  if (j + 1 < e->me->s) snprintf(buf + n, size - (size_t)n, " - %s * %s[%d + i]", rolled_lit(e, xi[j + 1]), name, (j + 1) * stride);
}

// The projections psi_j = sum_l b_l P_j(c_l) grad U(Q_l) and, with jac,
// rho_j (R[j M T + i T + t], the Jacobian's entries) of the sweep: the
// affine entries in closed form, the curved ones summed over the k stages
// (unrolled: k and s are small; the loops are over the coordinates).
void rolled_projections(Emitter *e, int jac) {
  const Roll *r = e->roll;
  const Method *me = e->me;
  int nu = jac ? e->mod->nu : 0, m = e->mod->m, s = me->s, mt = m * r->T;
  char x[512];
  out(e, "  /* entries affine in q, projected in closed form: delta_j0 f(q0) + f_lin(h (X gamma)_j) */\n");
  if (!r->gradU_s.affine.zero) tmpl(e, "  $P_roll_gradU_affine(q0, 0, prm, psi);\n");
  tmplf(e, "  for (i = %d; i < %d; i++) psi[i] = 0;\n", r->gradU_s.affine.zero ? 0 : m, s * m);
  if (nu && jac_used(r, PART_AFFINE)) tmpl(e, "  $P_roll_jac_affine(q0, 0, prm, R);\n");
  if (nu && !lin_sets(r)) tmplf(e, "  for (i = %d; i < %d; i++) R[i] = 0;\n", jac_used(r, PART_AFFINE) ? mt : 0, s * mt);
  if (!r->gradU_s.lin.zero || (nu && jac_used(r, PART_LIN))) {
    out(e, "  for (i = 0; i < %d; i++) {\n", m);
    for (int j = 0; j < s; j++) {
      rolled_x_row(e, j, "gam", m, x, sizeof x);
      out(e, "    hX[%d + i] = h * (%s);\n", j * m, x);
    }
    out(e, "  }\n");
    if (!r->gradU_s.lin.zero)
      tmplf(e, "  for (j = 0; j < %d; j++) $P_roll_gradU_lin(0, hX + j * %d, prm, psi + j * %d);\n", s, m, m);
    if (nu && jac_used(r, PART_LIN)) tmpl(e, "  $P_roll_jac_lin(0, hX, prm, R);\n");
  }
  if (r->gradU_s.curved.zero && !(nu && jac_used(r, PART_CURVED))) return;
  out(e, "  /* the other entries at the k stages: Q = q0 + h sum_j Ihat[l][j] gamma_j, summed with b_l P_j(c_l) */\n");
  for (int l = 0; l < me->k; l++) {
    out(e, "  /* stage %d of %d */\n  for (i = 0; i < %d; i++) Q[i] = q0[i] + h * (", l + 1, me->k, m);
    for (int j = 0; j < s; j++) out(e, "%s%s * gam[%d + i]", j ? " + " : "", rolled_lit(e, me->Ihat[l * s + j]), j * m);
    out(e, ");\n");
    if (!r->gradU_s.curved.zero) {
      tmpl(e, "  $P_roll_gradU_curved(Q, 0, prm, F);\n");
      out(e, "  for (i = 0; i < %d; i++) {\n", m);
      for (int j = 0; j < s; j++) out(e, "    psi[%d + i] += %s * F[i];\n", j * m, rolled_lit(e, me->W[l * s + j]));
      out(e, "  }\n");
    }
    if (nu && jac_used(r, PART_CURVED)) {
      tmpl(e, "  $P_roll_jac_curved(Q, 0, prm, J);\n");
      out(e, "  for (i = 0; i < %d; i++) {\n", mt);
      for (int j = 0; j < s; j++) out(e, "    R[%d + i] += %s * J[i];\n", j * mt, rolled_lit(e, me->W[l * s + j]));
      out(e, "  }\n");
    }
  }
}

// Whether psi_j = 0 for j >= 1 (grad U is affine with no linear part: constant).
static int psi_zero(const Roll *r) {
  return r->gradU_s.lin.zero && r->gradU_s.curved.zero;
}

// R[j M T + T i + t]: rho_j at coordinate i, constraint slot t.
static void rho(char *buf, size_t size, int j, int t, int mt, int T) {
  snprintf(buf, size, "R[%d + %d * i]", j * mt + t, T);
}

// The right-hand side's share of coordinate i, slot t (in a segment's loop):
// Y_k = M^-1 times the coefficient of y_k in B(x, y) = xi_0 x_0 y_0 + sum_j
// xi_j (x_j y_j-1 - x_j-1 y_j), x = rho[i, t], and r[a] += rho_0 M^-1 p0 - h
// Y'psi (only Y_0 when psi_j = 0 for j >= 1).
static void emit_system_rhs(Emitter *e, const TconSeg *g, int t, int psi_const) {
  const Roll *r = e->roll;
  const double *xi = e->me->xi;
  int m = e->mod->m, s = e->me->s, T = r->T, mt = m * T;
  const char *gt = rolled_tcon_guard(g, t), *minv = r->identity ? "" : "_rminv[i] * ";
  char a[64], b[64];
  if (!gt) return;
  out(e, "    %s{\n", gt);
  for (int k = 0; k < (psi_const ? 1 : s); k++) {
    char y[256];
    int n = 0;
    if (k + 1 < s) rho(b, sizeof b, k + 1, t, mt, T), n = snprintf(y, sizeof y, "%s * %s", rolled_lit(e, xi[k + 1]), b);
    rho(a, sizeof a, k ? k - 1 : 0, t, mt, T);
    if (k == 0) snprintf(y + n, sizeof y - (size_t)n, "%s%s * %s", n ? " + " : "", rolled_lit(e, xi[0]), a);
    else snprintf(y + n, sizeof y - (size_t)n, "%s%s * %s", n ? " - " : "-", rolled_lit(e, xi[k]), a);
    out(e, "      const %s Y%d = %s%s(%s);\n", real_type(e, 0), k, r->identity ? "" : e->P, minv, y);
  }
  out(e, "      r[a%d] += R[%d + %d * i] * (%s%sp0[i]) - h * (", t, t, T, r->identity ? "" : e->P, minv);
  for (int k = 0; k < (psi_const ? 1 : s); k++) out(e, "%sY%d * psi[%d + i]", k ? " + " : "", k, k * m);
  out(e, ");\n    }\n");
}

// A's share of coordinate i (in a segment's loop), h B(rho[i, t], rho[i, u])
// M^-1_i into A[a_t][a_u]: on the diagonal B(x, x) = xi_0 x_0^2 (the skew
// part cancels), and for a pair t < u the symmetric part S = xi_0 x_0 y_0
// and the skew part K = sum_j xi_j (x_j y_j-1 - x_j-1 y_j) once, A[a_t][a_u]
// += h (S + K), A[a_u][a_t] += h (S - K).
static void emit_system_matrix(Emitter *e, const TconSeg *g) {
  const Roll *r = e->roll;
  const double *xi = e->me->xi;
  int s = e->me->s, T = r->T, mt = e->mod->m * T, W = 2 * r->bw + 1;
  char pre[64], x0[64], y0[64], xj[64], xl[64], yj[64], yl[64];
  snprintf(pre, sizeof pre, "%s%s", r->identity ? "" : e->P, r->identity ? "" : "_rminv[i] * ");
  for (int t = 0; t < T; t++) {
    const char *gt = rolled_tcon_guard(g, t);
    if (!gt) continue;
    rho(x0, sizeof x0, 0, t, mt, T);
    out(e, *pre ? "    %sA[a%d * %d + %d] += h * (%s(%s * %s * %s));\n" : "    %sA[a%d * %d + %d] += h * (%s%s * %s * %s);\n", gt, t, W,
        r->bw, pre, rolled_lit(e, xi[0]), x0, x0);
  }
  for (int t = 0; t < T; t++)
    for (int u = t + 1; u < T; u++) {
      int table = g->off[t] == TCON_TABLE;
      if (!rolled_tcon_guard(g, t) || !rolled_tcon_guard(g, u)) continue;
      out(e, table ? "    if (a%d >= 0 && a%d >= 0) {\n" : "    {\n", t, u);
      rho(x0, sizeof x0, 0, t, mt, T);
      rho(y0, sizeof y0, 0, u, mt, T);
      out(e, *pre ? "      const %s S = %s(%s * %s * %s);\n" : "      const %s S = %s%s * %s * %s;\n", real_type(e, 0), pre,
          rolled_lit(e, xi[0]), x0, y0);
      out(e, "      const %s K = %s(", real_type(e, 0), pre);
      for (int j = 1; j < s; j++) {
        rho(xj, sizeof xj, j, t, mt, T), rho(xl, sizeof xl, j - 1, t, mt, T);
        rho(yj, sizeof yj, j, u, mt, T), rho(yl, sizeof yl, j - 1, u, mt, T);
        out(e, "%s%s * (%s * %s - %s * %s)", j > 1 ? " + " : "", rolled_lit(e, xi[j]), xj, yl, xl, yj);
      }
      out(e, s > 1 ? ");\n" : "0);\n");
      out(e, "      A[a%d * %d + a%d - a%d + %d] += h * (S + K);\n", t, W, u, t, r->bw);
      out(e, "      A[a%d * %d + a%d - a%d + %d] += h * (S - K);\n    }\n", u, W, t, u, r->bw);
    }
}

// The multiplier system, assembled by one loop over the coordinates (per
// segment of rolled_tcon_segments): r (emit_system_rhs) and A
// (emit_system_matrix), in band storage.
static void emit_system(Emitter *e) {
  const Roll *r = e->roll;
  int T = r->T;
  int psi_const = psi_zero(r);
  tmpl(e, "  /* the multiplier system A lambda = r (band): A = h [xi_0 rho_0' M^-1 rho_0 + sum_j xi_j (rho_j' M^-1 rho_j-1\n"
          "   * - rho_j-1' M^-1 rho_j)], r = rho_0' M^-1 (p0 - h xi_0 psi_0) - h sum_j xi_j (...) + g0, a sum over i */\n"
          "  for (i = 0; i < $P_NU * $P_RW; i++) A[i] = 0;\n"
          "  for (i = 0; i < $P_NU; i++) r[i] = 0;\n");
  int nseg;
  TconSeg *seg = rolled_tcon_segments(r, &nseg);
  for (int g = 0; g < nseg; g++) {
    rolled_tcon_open(e, &seg[g], 0);
    for (int t = 0; t < T; t++) emit_system_rhs(e, &seg[g], t, psi_const);
    emit_system_matrix(e, &seg[g]);
    out(e, "  }\n");
  }
  rolled_tcon_free(seg);
  tmpl(e, "  for (i = 0; i < $P_NU; i++) r[i] += g0[i];  /* g(q0) / h, or 0 */\n"
          "  $P_band_factor(A, out + $<sweep.pivot>, out + $<sweep.adiag>);\n"
          "  $P_band_solve(A, r);\n"
          "  r[$P_NU] = 0;  /* read where a coordinate has fewer than T constraints */\n"
          "  for (i = 0; i < $P_NU; i++) out[$[sweep.lambda]i] = r[i];\n");
}

// The sweep: projections, multiplier system, then per coordinate Theta_j =
// psi_j + rho_j lambda, gamma_j = M^-1 [delta_j0 p0 - h sum_i X[j][i] Theta_i]
// and p1 - p0 = -h Theta_0.
static void emit_sweep(Emitter *e) {
  const Roll *r = e->roll;
  int nu = e->mod->nu, m = e->mod->m, s = e->me->s, T = r->T, mt = m * T;
  tmplf(e, "  $R Q[%d], F[%d], hX[%d], psi[%d];\n  int i, j = 0;\n  (void)Q; (void)F; (void)hX; (void)j;\n", m, m,
        s * m, s * m);
  if (nu) tmplf(e, "  $R J[%d], R[%d], A[%d], r[%d];\n  (void)J;\n", mt, s * mt, nu * (2 * r->bw + 1), nu + 1);
  rolled_projections(e, 1);
  if (nu) emit_system(e);
  int nseg;
  TconSeg *seg = rolled_tcon_segments(r, &nseg);
  for (int g = 0; g < nseg; g++) {
    rolled_tcon_open(e, &seg[g], 1);
    out(e, "    %s th[%d];\n", real_type(e, 0), s);
    for (int j = 0; j < s; j++) { /* (psi_j = 0 for j >= 1 is not read) */
      int terms = j == 0 || !psi_zero(r);
      out(e, terms ? "    th[%d] = psi[%d + i]" : "    th[%d] =", j, j * m);
      for (int t = 0; t < T; t++)
        if (rolled_tcon_guard(&seg[g], t)) out(e, "%sR[%d + %d * i] * r[a%d]", terms++ ? " + " : " ", j * mt + t, T, t);
      out(e, terms ? ";\n" : " 0;\n");
    }
    rolled_gamma(e, 1);
    out(e, "  }\n");
  }
  rolled_tcon_free(seg);
}

// Inside a loop over the coordinates i with th[j] = Theta_j at i: gamma_j =
// M^-1 [delta_j0 p0 - h sum_r X[j][r] Theta_r] into the sweep's result gam,
// with p1 - p0 = -h Theta_0 and Theta_1.. (results 1), or into the local
// array gm (results 0).
void rolled_gamma(Emitter *e, int results) {
  int m = e->mod->m, s = e->me->s;
  char x[512];
  for (int j = 0; j < s; j++) {
    rolled_x_row(e, j, "th", 1, x, sizeof x);
    /* th is a local array here: th[r + i] would be wrong, so name its entries */
    char *p;
    while ((p = strstr(x, " + i]"))) memmove(p, p + 4, strlen(p + 4) + 1);
    tmplf(e, results ? "    out[$[sweep.gam]%d + i] = $P_MINV(i) (%s(h * (%s)));\n" : "    gm[%d + i] = $P_MINV(i) (%s(h * (%s)));\n",
          j * m, j ? "-" : "p0[i] - ", x);
  }
  if (!results) return;
  tmpl(e, "    out[$[sweep.dp]i] = -(h * th[0]);\n");
  for (int j = 1; j < s; j++) tmplf(e, "    out[$[sweep.theta]%d + i] = th[%d];\n", (j - 1) * m, j);
}

// The consistent multiplier: (G' M^-1 G) lambda = [v' Hess(g_a) v]_a - G' M^-1 grad U.
static void emit_lambda0(Emitter *e) {
  int nu = e->mod->nu, m = e->mod->m, mt = m * e->roll->T;
  tmplf(e, "  $R J[%d], B[%d], gu[%d], v[%d], hv[%d], rr[%d], piv[%d], dia[%d];\n  int i, t;\n", mt,
        nu * (2 * e->roll->bw + 1), m, m, nu, nu, nu, nu);
  tmpl(e, "  $P_roll_jac(q0, 0, prm, J);\n  $P_roll_gram(J, B);\n  $P_roll_gradU(q0, 0, prm, gu);\n"
          "  for (i = 0; i < $P_M; i++) v[i] = $P_MINV(i) p0[i];\n"
          "  $P_roll_hvv(q0, v, prm, hv);\n"
          "  for (i = 0; i < $P_NU; i++) rr[i] = 0;\n"
          "  for (i = 0; i < $P_M; i++)\n"
          "    for (t = 0; t < $P_RT; t++)\n"
          "      if ($P_tcon[i * $P_RT + t] >= 0) rr[$P_tcon[i * $P_RT + t]] += J[i * $P_RT + t] * ($P_MINV(i) gu[i]);\n"
          "  for (i = 0; i < $P_NU; i++) rr[i] = hv[i] - rr[i];\n"
          "  $P_band_factor(B, piv, dia);\n  $P_band_solve(B, rr);\n"
          "  for (i = 0; i < $P_NU; i++) out[$[lambda0.lambda]i] = rr[i];\n");
}

// NAME_project's Newton step onto g = 0 and projection of p.
static void emit_consistent(Emitter *e) {
  int nu = e->mod->nu, m = e->mod->m, mt = m * e->roll->T;
  tmplf(e, "  $R J[%d], B[%d], y[%d], mu[%d];\n  int i, t;\n", mt, nu * (2 * e->roll->bw + 1), nu, nu);
  tmpl(e, "  $P_roll_jac(q0, 0, prm, J);\n  $P_roll_gram(J, B);\n"
          "  $P_band_factor(B, out + $<consistent.pivot>, out + $<consistent.adiag>);\n"
          "  $P_roll_g(q0, 0, prm, y);\n  $P_band_solve(B, y);\n"
          "  for (i = 0; i < $P_NU; i++) mu[i] = 0;\n"
          "  for (i = 0; i < $P_M; i++) {\n"
          "    $R acc = 0;\n"
          "    for (t = 0; t < $P_RT; t++)\n"
          "      if ($P_tcon[i * $P_RT + t] >= 0) {\n"
          "        acc += J[i * $P_RT + t] * y[$P_tcon[i * $P_RT + t]];\n"
          "        mu[$P_tcon[i * $P_RT + t]] += J[i * $P_RT + t] * ($P_MINV(i) p0[i]);\n"
          "      }\n"
          "    out[$[consistent.dq]i] = -($P_MINV(i) acc);\n  }\n"
          "  $P_band_solve(B, mu);\n"
          "  for (i = 0; i < $P_M; i++) {\n"
          "    $R acc = 0;\n"
          "    for (t = 0; t < $P_RT; t++)\n"
          "      if ($P_tcon[i * $P_RT + t] >= 0) acc -= J[i * $P_RT + t] * mu[$P_tcon[i * $P_RT + t]];\n"
          "    out[$[consistent.dp]i] = acc;\n  }\n");
}

// The functions of the state outside the step.
static void emit_state_kernel(Emitter *e, KernelId id) {
  int mt = e->mod->m * e->roll->T;
  switch (id) {
  case K_MINV_P: tmpl(e, "  int i;\n  for (i = 0; i < $P_M; i++) out[i] = $P_MINV(i) p0[i];\n"); break;
  case K_ENERGY:
    tmplf(e, "  $R kin = 0, u;\n  int i;\n  for (i = 0; i < $P_M; i++) kin += p0[i] * ($P_MINV(i) p0[i]);\n"
             "  $P_roll_U(q0, 0, prm, &u);\n  out[0] = %s * kin + u;\n", rolled_lit(e, 0.5));
    break;
  case K_G: tmpl(e, "  $P_roll_g(q0, 0, prm, out);\n"); break;
  case K_HIDDEN:
    tmplf(e, "  $R J[%d];\n  int i, t;\n", mt);
    tmpl(e, "  $P_roll_jac(q0, 0, prm, J);\n  for (i = 0; i < $P_NU; i++) out[i] = 0;\n"
            "  for (i = 0; i < $P_M; i++)\n    for (t = 0; t < $P_RT; t++)\n"
            "      if ($P_tcon[i * $P_RT + t] >= 0) out[$P_tcon[i * $P_RT + t]] += J[i * $P_RT + t] * ($P_MINV(i) p0[i]);\n");
    break;
  default: internal_error("no rolled kernel %d", (int)id);
  }
}

int emit_rolled_kernel(Emitter *e, KernelId id) {
  int poly = e->me->family == MULT_POLY && e->mod->nu;
  if (id != K_SWEEP && id != K_MINV_P && id != K_ENERGY && id != K_G && id != K_HIDDEN && id != K_LAMBDA0 &&
      id != K_CONSISTENT && !(poly && (id == K_FACTOR || id == K_PROJECT)) && id != K_NFACTOR && id != K_NSOLVE)
    return 0; /* the params' q0, p0 and the events stay straight-line: they are small or rare */
  if (e->lanes) { /* --batch: the scalar kernel above in each lane (emit_rolled_batch.c) */
    emit_rolled_lane_kernel(e, id);
    return 1;
  }
  if (!e->roll_helpers) emit_helpers(e);
  if (id == K_NFACTOR || id == K_NSOLVE) return rolled_newton_kernel(e, id), 1; /* emit_rolled_newton.c */
  const Kernel *k = &e->st->kern[id];
  e->kid = id;
  out(e, "\n/* %s (rolled) */\n", k->what);
  kernel_signature(e, k, -1);
  if (poly && (id == K_SWEEP || id == K_FACTOR || id == K_PROJECT)) rolled_poly_kernel(e, id);
  else if (id == K_SWEEP) emit_sweep(e);
  else if (id == K_LAMBDA0) emit_lambda0(e);
  else if (id == K_CONSISTENT) emit_consistent(e);
  else emit_state_kernel(e, id);
  out(e, "}\n");
  return 1;
}
