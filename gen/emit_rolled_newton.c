/* emit_rolled_newton.c - the kernels of --iteration newton (and auto) in the
 * rolled form: the Newton matrix as band loops.
 *
 * The straight-line kernels (step_newton.c) split the Newton matrix
 * I + h^2 A (x) M^-1 J by A's real eigenbasis into one m x m block
 * I + h^2 a M^-1 J per real eigenvalue a and one complex block
 * e^{-i phi} (I + h^2 (a + ib) M^-1 J) per pair a +- ib (phi = arg(a + ib)
 * / 2), factored by LU without pivoting. Here, on a model without
 * constraints whose Hess U is a band of HB each side once its rows are
 * ordered (roll_newton.c: a chain of pendula has HB = 1, the FPU chain 3),
 * the same blocks are bands:
 *   - "newton_factor": J at the midpoint of the step's polynomial from the
 *     families of Hess U's rows ($P_roll_hess: one loop per run, as every
 *     rolled family), scattered into band storage A[p * NW + c - p + HB]
 *     (p = NPOS(i) the row's place, c the column's; a pair's block in
 *     complex entries, re and im side by side) and factored by LU without pivoting over the band, the
 *     reciprocal pivots kept on the diagonal; a pair's pivots are checked by
 *     their modulus;
 *   - "newton_solve": w = (T^-1 (x) I) r, each block's forward and back
 *     substitution over the band (a pair's right-hand side rotated by
 *     e^{-i phi} as in step_newton.c), dgam = (T (x) I) z, loops over the
 *     coordinates with s unrolled.
 * The elimination is in the natural order (the chain's minimum-degree order
 * is the natural one) where lu.c orders by minimum degree over the real form,
 * and the complex block is eliminated in complex arithmetic: the same matrix
 * and solution, rounded in another order (docs/rolled.md, "Same results"). */
#include <math.h>

#include "emit.h"
#include "roll.h"
#include "step.h"

// $P_roll_hess(q, v, prm, out): out[HT i + t] = the t-th structural nonzero
// of row i of Hess U (0 where the row has fewer), one loop per run of each
// t's family; and the tables of the band: where row i's entries go (hoff)
// and, where the rows are reordered, row i's place (npos).
static void emit_hessian_family(Emitter *e) {
  const Roll *r = e->roll;
  int m = e->mod->m;
  tmpl(e, "\n/* Where row i's t-th entry of Hess U goes in the band of its row, or -1 */\n");
  rolled_int_table(e, "signed char", "hoff", r->hoff, m * r->ht); /* (2 HB + 1 <= 33: roll_newton.c) */
  if (r->hpos) {
    tmpl(e, "/* The place of coordinate i among the band's rows (Cuthill-McKee: a narrower band) */\n");
    rolled_int_table(e, "int", "npos", r->hpos, m);
    tmpl(e, "#define $P_NPOS(i) $P_npos[i]\n");
  } else {
    tmpl(e, "#define $P_NPOS(i) (i)  /* the band's rows in the natural order */\n");
  }
  tmpl(e, "\n/* Hess U: out[$P_HT * i + t] = row i's t-th structural nonzero, 0 where it has fewer */\n"
          "static void $P_roll_hess(const $R *q, const $R *v, const $P_params *prm, $R *out)\n{\n"
          "  int u = 0;\n  (void)q; (void)v; (void)prm; (void)u;\n");
  for (int t = 0; t < r->ht; t++)
    for (int i = 0; i < r->hess[t].nruns; i++) rolled_run(e, &r->hess[t].runs[i], r->ht, t);
  out(e, "}\n");
}

// The band LU without pivoting of an M x M block and its solve, real (the
// block of a real eigenvalue) and complex (a pair's: entries re, im side by
// side). The factor keeps L's multipliers below the diagonal, U above it and
// 1 / U's pivots on it; pivot[k] is the k-th pivot's modulus, adiag[k] the
// modulus of the diagonal entry it started from.
static void emit_band_lu(Emitter *e, const NewtonBasis *nb) {
  int real = 0, pair = 0;
  for (int q = 0; q < nb->nblocks; q++) {
    real |= !nb->blk[q].pair;
    pair |= nb->blk[q].pair;
  }
  if (real) /* (only odd s has a real eigenvalue) */
  tmpl(e, "\n/* A (M x M, band storage A[i * $P_NW + c - i + $P_NHB]) = L U without pivoting, in place. */\n"
          "static void $P_nband_factor($R *A, $R *pivot, $R *adiag)\n{\n"
          "  int k, d, c;\n"
          "  for (k = 0; k < $P_M; k++) adiag[k] = A[k * $P_NW + $P_NHB];\n"
          "  for (k = 0; k < $P_M; k++) {\n"
          "    $R *Ak = A + k * $P_NW + $P_NHB;  /* Ak[c] = A[k][k + c] */\n"
          "    const $R inv = 1 / Ak[0];\n"
          "    pivot[k] = Ak[0];\n"
          "    const int nd = $P_M - 1 - k < $P_NHB ? $P_M - 1 - k : $P_NHB;  /* the band's rows below k */\n"
          "    Ak[0] = inv;\n"
          "    for (d = 1; d <= nd; d++) {\n"
          "      $R *Ai = A + (k + d) * $P_NW + $P_NHB - d;  /* Ai[c] = A[k + d][k + c] */\n"
          "      const $R f = Ai[0] * inv;\n"
          "      Ai[0] = f;\n"
          "      for (c = 1; c <= nd; c++) Ai[c] -= f * Ak[c];\n"
          "    }\n  }\n}\n\n"
          "/* x = A^-1 x for A factored by $P_nband_factor. */\n"
          "static void $P_nband_solve(const $R *A, $R *x)\n{\n"
          "  int k, d;\n"
          "  for (k = 0; k < $P_M; k++) {\n"
          "    const int nd = $P_M - 1 - k < $P_NHB ? $P_M - 1 - k : $P_NHB;  /* the band's rows below k */\n"
          "    for (d = 1; d <= nd; d++) x[k + d] -= A[(k + d) * $P_NW + $P_NHB - d] * x[k];\n  }\n"
          "  for (k = $P_M - 1; k >= 0; k--) {\n"
          "    const int nd = $P_M - 1 - k < $P_NHB ? $P_M - 1 - k : $P_NHB;\n"
          "    $R acc = x[k];\n"
          "    for (d = 1; d <= nd; d++) acc -= A[k * $P_NW + $P_NHB + d] * x[k + d];\n"
          "    x[k] = acc * A[k * $P_NW + $P_NHB];\n  }\n}\n");
  if (pair) /* (every s >= 2) */
  tmpl(e, "\n/* The same for a complex A, entry (i, c) at A[2 (i * $P_NW + c - i + $P_NHB)] (re) and + 1 (im):\n"
          " * pivot and adiag the moduli. */\n"
          "static void $P_nband_factor_c($R *A, $R *pivot, $R *adiag)\n{\n"
          "  int k, d, c;\n"
          "  for (k = 0; k < $P_M; k++) {\n"
          "    const $R *a = A + 2 * (k * $P_NW + $P_NHB);\n"
          "    adiag[k] = sqrt$f(a[0] * a[0] + a[1] * a[1]);\n  }\n"
          "  for (k = 0; k < $P_M; k++) {\n"
          "    $R *Ak = A + 2 * (k * $P_NW + $P_NHB);  /* Ak[2 c], Ak[2 c + 1] = A[k][k + c] */\n"
          "    const $R nn = Ak[0] * Ak[0] + Ak[1] * Ak[1], ir = Ak[0] / nn, ii = -Ak[1] / nn;\n"
          "    pivot[k] = sqrt$f(nn);\n"
          "    const int nd = $P_M - 1 - k < $P_NHB ? $P_M - 1 - k : $P_NHB;\n"
          "    Ak[0] = ir;\n    Ak[1] = ii;\n"
          "    for (d = 1; d <= nd; d++) {\n"
          "      $R *Ai = A + 2 * ((k + d) * $P_NW + $P_NHB - d);  /* Ai[2 c] .. = A[k + d][k + c] */\n"
          "      const $R fr = Ai[0] * ir - Ai[1] * ii, fi = Ai[0] * ii + Ai[1] * ir;\n"
          "      Ai[0] = fr;\n      Ai[1] = fi;\n"
          "      for (c = 1; c <= nd; c++) {\n"
          "        Ai[2 * c] -= fr * Ak[2 * c] - fi * Ak[2 * c + 1];\n"
          "        Ai[2 * c + 1] -= fr * Ak[2 * c + 1] + fi * Ak[2 * c];\n"
          "      }\n    }\n  }\n}\n\n"
          "/* x = A^-1 x for A factored by $P_nband_factor_c, x complex (re, im side by side). */\n"
          "static void $P_nband_solve_c(const $R *A, $R *x)\n{\n"
          "  int k, d;\n"
          "  for (k = 0; k < $P_M; k++) {\n"
          "    const int nd = $P_M - 1 - k < $P_NHB ? $P_M - 1 - k : $P_NHB;\n"
          "    for (d = 1; d <= nd; d++) {\n"
          "      const $R *f = A + 2 * ((k + d) * $P_NW + $P_NHB - d);\n"
          "      x[2 * (k + d)] -= f[0] * x[2 * k] - f[1] * x[2 * k + 1];\n"
          "      x[2 * (k + d) + 1] -= f[0] * x[2 * k + 1] + f[1] * x[2 * k];\n    }\n  }\n"
          "  for (k = $P_M - 1; k >= 0; k--) {\n"
          "    const $R *Ak = A + 2 * (k * $P_NW + $P_NHB);\n"
          "    const int nd = $P_M - 1 - k < $P_NHB ? $P_M - 1 - k : $P_NHB;\n"
          "    $R re = x[2 * k], im = x[2 * k + 1];\n"
          "    for (d = 1; d <= nd; d++) {\n"
          "      re -= Ak[2 * d] * x[2 * (k + d)] - Ak[2 * d + 1] * x[2 * (k + d) + 1];\n"
          "      im -= Ak[2 * d] * x[2 * (k + d) + 1] + Ak[2 * d + 1] * x[2 * (k + d)];\n    }\n"
          "    x[2 * k] = re * Ak[0] - im * Ak[1];\n"
          "    x[2 * k + 1] = re * Ak[1] + im * Ak[0];\n  }\n}\n");
}

// The rotation of a pair's block: phi = arg(a + ib) / 2.
static double pair_phi(const NewtonBlock *blk) { return atan2(blk->b, blk->a) / 2; }

// The kernel "newton_factor": J at qm = q0 + h sum_j gam_j int_0^{1/2} P_j,
// then block by block (A's eigenbasis, step_newton.c) the band of
// I + h^2 a M^-1 J, or of e^{-i phi} + h^2 r e^{i phi} M^-1 J for a pair,
// factored into out (lu: S M NW reals in all), its pivots at the block's
// rows (a pair's M moduli twice).
static void emit_factor(Emitter *e, const NewtonBasis *nb) {
  int s = e->me->s, m = e->mod->m, W = 2 * e->roll->hb + 1, off = 0, row = 0;
  char x[1024];
  tmplf(e, "  $R qm[%d], J[%d], B[%d];\n  int i, t;\n", m, m * e->roll->ht, m * W);
  int n = 0;
  for (int j = 0; j < s; j++)
    n += snprintf(x + n, sizeof x - (size_t)n, "%s%s * gam[%d + i]", j ? " + " : "", rolled_lit(e, newton_midpoint_weight(e->me, j)), j * m);
  tmplf(e, "  for (i = 0; i < $P_M; i++) qm[i] = q0[i] + h * (%s);\n"
           "  $P_roll_hess(qm, 0, prm, J);\n"
           "  for (i = 0; i < $P_M * $P_NW; i++) B[i] = 0;\n"
           "  for (i = 0; i < $P_M; i++)  /* B = h^2 M^-1 J in band storage, its rows in the band's order */\n"
           "    for (t = 0; t < $P_HT; t++)\n"
           "      if ($P_hoff[i * $P_HT + t] >= 0) B[$P_NPOS(i) * $P_NW + $P_hoff[i * $P_HT + t]] = h * h * ($P_MINV(i) J[i * $P_HT + t]);\n", x);
  for (int q = 0; q < nb->nblocks; q++) {
    const NewtonBlock *blk = &nb->blk[q];
    if (!blk->pair) {
      tmplf(e, "  {  /* the real eigenvalue %s: I + h^2 a M^-1 J */\n"
               "    $R *A = out + %d;\n"
               "    for (i = 0; i < $P_M * $P_NW; i++) A[i] = %s * B[i];\n"
               "    for (i = 0; i < $P_M; i++) A[i * $P_NW + $P_NHB] += 1;\n"
               "    $P_nband_factor(A, out + $[newton_factor.pivot]%d, out + $[newton_factor.adiag]%d);\n  }\n",
            rolled_lit(e, blk->a), off, rolled_lit(e, blk->a), row, row);
      off += m * W;
      row += m;
      continue;
    }
    double phi = pair_phi(blk), r = hypot(blk->a, blk->b);
    tmplf(e, "  {  /* the pair %s +- i %s: e^{-i phi} (I + h^2 (a + ib) M^-1 J), phi = arg(a + ib) / 2 */\n"
             "    $R *A = out + %d;\n"
             "    for (i = 0; i < $P_M * $P_NW; i++) {\n"
             "      A[2 * i] = %s * B[i];\n      A[2 * i + 1] = %s * B[i];\n    }\n"
             "    for (i = 0; i < $P_M; i++) {\n"
             "      A[2 * (i * $P_NW + $P_NHB)] += %s;\n      A[2 * (i * $P_NW + $P_NHB) + 1] -= %s;\n    }\n",
          rolled_lit(e, blk->a), rolled_lit(e, blk->b), off, rolled_lit(e, r * cos(phi)), rolled_lit(e, r * sin(phi)),
          rolled_lit(e, cos(phi)), rolled_lit(e, sin(phi)));
    tmplf(e, "    $P_nband_factor_c(A, out + $[newton_factor.pivot]%d, out + $[newton_factor.adiag]%d);\n"
             "    for (i = 0; i < $P_M; i++) {  /* the modulus for both rows of the real form */\n"
             "      out[$[newton_factor.pivot]%d + i] = out[$[newton_factor.pivot]%d + i];\n"
             "      out[$[newton_factor.adiag]%d + i] = out[$[newton_factor.adiag]%d + i];\n    }\n  }\n",
          row, row, row + m, row, row + m, row);
    off += 2 * m * W;
    row += 2 * m;
  }
}

// "SUM_c MAT[j][c] SRC[c M + i]" for row j of the s x s matrix mat.
static void basis_row(Emitter *e, const double *mat, int j, const char *src, char *buf, size_t size) {
  int s = e->me->s, m = e->mod->m, n = 0;
  for (int c = 0; c < s; c++)
    n += snprintf(buf + n, size - (size_t)n, "%s%s * %s[%d + i]", c ? " + " : "", rolled_lit(e, mat[j * s + c]), src, c * m);
}

// The kernel "newton_solve": dgam = N^-1 r for the residual r (input gam)
// with the band factors lu of newton_factor.
static void emit_solve(Emitter *e, const NewtonBasis *nb) {
  int s = e->me->s, m = e->mod->m, W = 2 * e->roll->hb + 1, off = 0;
  char x[2048];
  tmplf(e, "  $R w[%d], z[%d];\n  int i;\n  for (i = 0; i < $P_M; i++) {  /* w = (T^-1 (x) I) r */\n", s * m, 2 * m);
  for (int j = 0; j < s; j++) {
    basis_row(e, nb->Tinv, j, "gam", x, sizeof x);
    out(e, "    w[%d + i] = %s;\n", j * m, x);
  }
  out(e, "  }\n");
  for (int q = 0; q < nb->nblocks; q++) {
    const NewtonBlock *blk = &nb->blk[q];
    int c = blk->col;
    if (!blk->pair) {
      tmplf(e, "  for (i = 0; i < $P_M; i++) z[$P_NPOS(i)] = w[%d + i];\n"
               "  $P_nband_solve(lu + %d, z);\n"
               "  for (i = 0; i < $P_M; i++) w[%d + i] = z[$P_NPOS(i)];\n", c * m, off, c * m);
      off += m * W;
      continue;
    }
    double phi = pair_phi(blk);
    const char *cp = rolled_lit(e, cos(phi)), *sp = rolled_lit(e, sin(phi));
    tmplf(e, "  for (i = 0; i < $P_M; i++) {  /* e^{-i phi} (w_c - i w_c+1) */\n"
             "    z[2 * $P_NPOS(i)] = %s * w[%d + i] - %s * w[%d + i];\n"
             "    z[2 * $P_NPOS(i) + 1] = -(%s * w[%d + i] + %s * w[%d + i]);\n  }\n"
             "  $P_nband_solve_c(lu + %d, z);\n"
             "  for (i = 0; i < $P_M; i++) {\n    w[%d + i] = z[2 * $P_NPOS(i)];\n    w[%d + i] = -z[2 * $P_NPOS(i) + 1];\n  }\n",
          cp, c * m, sp, (c + 1) * m, sp, c * m, cp, (c + 1) * m, off, c * m, (c + 1) * m);
    off += 2 * m * W;
  }
  out(e, "  for (i = 0; i < %d; i++) {  /* dgam = (T (x) I) z */\n", m);
  for (int j = 0; j < s; j++) {
    basis_row(e, nb->T, j, "w", x, sizeof x);
    tmplf(e, "    out[$[newton_solve.dgam]%d + i] = %s;\n", j * m, x);
  }
  out(e, "  }\n");
}

void rolled_newton_kernel(Emitter *e, KernelId id) {
  NewtonBasis nb;
  newton_basis(e->me, &nb);
  if (!(e->roll_helpers & 2)) {
    tmplf(e, "\n/* The Newton matrix's blocks as bands of $P_NHB each side (emit_rolled_newton.c). */\n"
             "#define $P_NHB %d\n#define $P_NW (2 * $P_NHB + 1)\n#define $P_HT %d  /* entries of a row of Hess U, at most */\n",
          e->roll->hb, e->roll->ht);
    emit_hessian_family(e);
    emit_band_lu(e, &nb);
    e->roll_helpers |= 2;
  }
  const Kernel *k = &e->st->kern[id];
  e->kid = id;
  out(e, "\n/* %s (rolled) */\n", k->what);
  kernel_signature(e, k, -1);
  if (id == K_NFACTOR) emit_factor(e, &nb);
  else emit_solve(e, &nb);
  out(e, "}\n");
}
