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
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emit.h"
#include "roll.h"
#include "step.h"

// $P_roll_hess(q, v, prm, out): out[HT i + t] = the t-th structural nonzero
// of row i of Hess U (0 where the row has fewer), one loop per run of each
// t's family; and the tables of the band: where row i's entries go (hoff)
// and, where the rows are reordered, row i's place (npos). With constraints
// row i's entries are those of Hess U and of each Hess g_a on it (hlam: a,
// whose lambda_a the factor applies), hoff their place in the saddle
// point's band, and krow, kcon its rows (roll_newton.c).
static void emit_hessian_family(Emitter *e) {
  const Roll *r = e->roll;
  int m = e->mod->m;
  if (r->nu) {
    tmpl(e, "\n/* Where row i's t-th entry of J = Hess(U + lambda' g) goes in the band of its row (the\n"
      " * saddle point's row of coordinate i), or -1; the constraint a whose lambda_a it takes, or -1 */\n");
    rolled_int_table(e, "short", "hoff", r->hoff, m * r->ht); /* (2 KHB + 1 <= 193: roll_newton.c) */
    rolled_int_table(e, "int", "hlam", r->hlam, m * r->ht);
    tmpl(e, "/* The saddle point's rows: coordinate i's S unknowns from krow[i], constraint a's row kcon[a] */\n");
    rolled_int_table(e, "int", "krow", r->krow, m);
    rolled_int_table(e, "int", "kcon", r->kcon, r->nu);
    tmpl(e, "\n/* Hess U and Hess g: out[$P_HT * i + t] = row i's t-th structural nonzero (hlam: of which\n"
      " * constraint, lambda not applied), 0 where it has fewer */\n");
  } else {
    tmpl(e, "\n/* Where row i's t-th entry of Hess U goes in the band of its row, or -1 */\n");
    rolled_int_table(e, "signed char", "hoff", r->hoff, m * r->ht); /* (2 HB + 1 <= 33: roll_newton.c) */
    if (r->hpos) {
      tmpl(e, "/* The place of coordinate i among the band's rows (Cuthill-McKee: a narrower band) */\n");
      rolled_int_table(e, "int", "npos", r->hpos, m);
      tmpl(e, "#define $P_NPOS(i) $P_npos[i]\n");
    } else {
      tmpl(e, "#define $P_NPOS(i) (i)  /* the band's rows in the natural order */\n");
    }
    tmpl(e, "\n/* Hess U: out[$P_HT * i + t] = row i's t-th structural nonzero, 0 where it has fewer */\n");
  }
  tmpl(e, "static void $P_roll_hess(const $R *q, const $R *v, const $P_params *prm, $R *out)\n{\n"
          "  int u = 0;\n  (void)q; (void)v; (void)prm; (void)u;\n");
  for (int t = 0; t < r->ht; t++)
    for (int i = 0; i < r->hess[t].nruns; i++) rolled_run(e, &r->hess[t].runs[i], r->ht, t);
  out(e, "}\n");
}

// The real band LU without pivoting of an N x N matrix and its solve, as
// $P_NAME_factor, $P_NAME_solve: band storage A[i * W + c - i + HB] (n, w, hb
// the macros of N, W and HB; dim N's name in the comment).
static void emit_real_band_lu(Emitter *e, const char *name, const char *n, const char *w, const char *hb, const char *dim) {
  static const char text[] =
      "\n/* A (@D x @D, band storage A[i * @W + c - i + @H]) = L U without pivoting, in place. */\n"
      "static void $P_@F_factor($R *A, $R *pivot, $R *adiag)\n{\n"
      "  int k, d, c;\n"
      "  for (k = 0; k < @N; k++) adiag[k] = A[k * @W + @H];\n"
      "  for (k = 0; k < @N; k++) {\n"
      "    $R *Ak = A + k * @W + @H;  /* Ak[c] = A[k][k + c] */\n"
      "    const $R inv = 1 / Ak[0];\n"
      "    pivot[k] = Ak[0];\n"
      "    const int nd = @N - 1 - k < @H ? @N - 1 - k : @H;  /* the band's rows below k */\n"
      "    Ak[0] = inv;\n"
      "    for (d = 1; d <= nd; d++) {\n"
      "      $R *Ai = A + (k + d) * @W + @H - d;  /* Ai[c] = A[k + d][k + c] */\n"
      "      const $R f = Ai[0] * inv;\n"
      "      Ai[0] = f;\n"
      "      for (c = 1; c <= nd; c++) Ai[c] -= f * Ak[c];\n"
      "    }\n  }\n}\n\n"
      "/* x = A^-1 x for A factored by $P_@F_factor. */\n"
      "static void $P_@F_solve(const $R *A, $R *x)\n{\n"
      "  int k, d;\n"
      "  for (k = 0; k < @N; k++) {\n"
      "    const int nd = @N - 1 - k < @H ? @N - 1 - k : @H;  /* the band's rows below k */\n"
      "    for (d = 1; d <= nd; d++) x[k + d] -= A[(k + d) * @W + @H - d] * x[k];\n  }\n"
      "  for (k = @N - 1; k >= 0; k--) {\n"
      "    const int nd = @N - 1 - k < @H ? @N - 1 - k : @H;\n"
      "    $R acc = x[k];\n"
      "    for (d = 1; d <= nd; d++) acc -= A[k * @W + @H + d] * x[k + d];\n"
      "    x[k] = acc * A[k * @W + @H];\n  }\n}\n";
  const char *from[] = {"@F", "@N", "@W", "@H", "@D"}, *to[] = {name, n, w, hb, dim};
  size_t len = 0;
  char *buf = xmalloc(4 * sizeof text);
  for (const char *c = text; *c;) {
    int k = 0;
    while (k < 5 && strncmp(c, from[k], 2)) k++;
    if (k < 5) {
      len += (size_t)sprintf(buf + len, "%s", to[k]);
      c += 2;
    } else {
      buf[len++] = *c++;
    }
  }
  buf[len] = 0;
  tmpl(e, buf);
  free(buf);
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
    emit_real_band_lu(e, "nband", "$P_M", "$P_NW", "$P_NHB", "M");
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

// "SUM_j T[j][c] rho_j" (ct: the constraint row's coefficient of z_c) or
// "SUM_j TINV[c][j] v_j" (vt) for the s locals x0.. / v0.. of a coordinate.
static void basis_col(Emitter *e, const double *mat, int c, int transpose, const char *var, char *buf, size_t size) {
  int s = e->me->s, n = 0;
  for (int j = 0; j < s; j++)
    n += snprintf(buf + n, size - (size_t)n, "%s%s * %s%d", j ? " + " : "", rolled_lit(e, transpose ? mat[j * s + c] : mat[c * s + j]),
                  var, j);
}

// The identity's share (delta) or an entry b of h^2 M^-1 J (entry) of
// block q in the saddle point's band, rows Ar + c KW (re) and Ar + (c + 1) KW
// (im) of coordinate i, at offset o of the column: a real eigenvalue's a b;
// a pair's complex alpha (e^{-i phi} for the identity, r e^{i phi} b for J)
// in real form [[Re, -Im], [Im, Re]] over the columns (x, y).
static void emit_block_entry(Emitter *e, const NewtonBlock *blk, int entry, const char *o, const char *pad) {
  int c = blk->col;
  if (!blk->pair) {
    if (entry) out(e, "%sAr[%d * %s_KW + %s] += %s * b;\n", pad, c, e->P, o, rolled_lit(e, blk->a));
    else out(e, "%sAr[%d * %s_KW + %s] += 1;\n", pad, c, e->P, o);
    return;
  }
  double phi = pair_phi(blk), r = hypot(blk->a, blk->b);
  const char *re = rolled_lit(e, entry ? r * cos(phi) : cos(phi)), *im = rolled_lit(e, entry ? r * sin(phi) : -sin(phi));
  const char *f = entry ? " * b" : "";
  out(e, "%sAr[%d * %s_KW + %s] += %s%s;\n", pad, c, e->P, o, re, f);
  out(e, "%sAr[%d * %s_KW + %s + 1] -= %s%s;\n", pad, c, e->P, o, im, f);
  out(e, "%sAr[%d * %s_KW + %s - 1] += %s%s;\n", pad, c + 1, e->P, o, im, f);
  out(e, "%sAr[%d * %s_KW + %s] += %s%s;\n", pad, c + 1, e->P, o, re, f);
}

// The kernel "newton_factor" with constraints (the constant family): the
// saddle point [[D, Vt], [Ct, 0]] of roll_newton.c as one real band in out
// (KN KW reals), rho_j after it (what newton_solve needs for C r), factored
// by LU without pivoting over the band; the coordinates' pivots and diagonal
// into pivot, adiag (S M), the constraints' pivots and scale sum_k
// |Ct_ak| |Vt_ka| into spivot, sadiag (NU).
static void emit_factor_kkt(Emitter *e, const NewtonBasis *nb) {
  const Roll *r = e->roll;
  int s = e->me->s, m = e->mod->m, nu = e->mod->nu, T = r->T, mt = m * T, ht = r->ht > 0 ? r->ht : 1;
  int poly = e->me->family == MULT_POLY, nrc = poly ? s : 1;
  char x[2048];
  if (poly) {
    tmplf(e, "  $R qm[%d], Hs[%d], cs[%d];\n  $R *A = out, *R = out + $P_KN * $P_KW;\n  int i, j, t;\n"
             "  /* the moments R_jr of the stage Jacobians at gam, as the sweep takes them */\n"
             "  $P_roll_moments(q0, gam, h, prm, R);\n", m, m * ht, nu * nrc);
  } else {
    tmplf(e, "  $R qm[%d], Hs[%d], Q[%d], F[%d], hX[%d], psi[%d], J[%d], cs[%d];\n"
             "  $R *A = out, *R = out + $P_KN * $P_KW;\n"
             "  int i, j = 0, t;\n  (void)Q; (void)F; (void)hX; (void)J; (void)j; (void)psi;\n",
          m, m * ht, m, m, s * m, s * m, mt, nu);
    out(e, "  /* rho_j at gam, as the sweep takes them */\n");
    rolled_projections(e, 1);
  }
  int n = 0;
  for (int j = 0; j < s; j++)
    n += snprintf(x + n, sizeof x - (size_t)n, "%s%s * gam[%d + i]", j ? " + " : "", rolled_lit(e, newton_midpoint_weight(e->me, j)), j * m);
  tmplf(e, "  for (i = 0; i < $P_M; i++) qm[i] = q0[i] + h * (%s);\n", x);
  if (r->ht) tmpl(e, "  $P_roll_hess(qm, 0, prm, Hs);\n");
  else tmpl(e, "  Hs[0] = 0;\n");
  tmplf(e, "  for (i = 0; i < $P_KN * $P_KW; i++) A[i] = 0;\n"
           "  for (i = 0; i < %d; i++) cs[i] = 0;\n", nu * nrc);
  tmpl(e, "  for (i = 0; i < $P_M; i++) {  /* the blocks I + h^2 a M^-1 J, e^{-i phi} (I + h^2 (a + ib) M^-1 J) */\n"
          "    $R *Ar = A + $P_krow[i] * $P_KW;\n");
  char khb[64];
  snprintf(khb, sizeof khb, "%s_KHB", e->P);
  for (int q = 0; q < nb->nblocks; q++) emit_block_entry(e, &nb->blk[q], 0, khb, "    ");
  tmpl(e, "    for (t = 0; t < $P_HT; t++) {\n"
          "      const int o = $P_hoff[i * $P_HT + t], a = $P_hlam[i * $P_HT + t];\n"
          "      if (o < 0) continue;\n"
          "      const $R b = h * h * ($P_MINV(i) ((a >= 0 ? lam[a] : 1) * Hs[i * $P_HT + t]));\n");
  for (int q = 0; q < nb->nblocks; q++) emit_block_entry(e, &nb->blk[q], 1, "o", "      ");
  tmpl(e, "    }\n  }\n"
          "  for (i = 0; i < $P_M; i++)  /* V (column kcon[a]) and C (row kcon[a]) of each constraint a on i */\n"
          "    for (t = 0; t < $P_RT; t++) {\n"
          "      const int a = $P_tcon[$P_RT * i + t];\n"
          "      if (a < 0) continue;\n"
          "      $R *Ar = A + $P_krow[i] * $P_KW, *Ac = A + $P_kcon[a] * $P_KW;\n"
          "      const int dv = $P_kcon[a] - $P_krow[i] + $P_KHB, dc = $P_krow[i] - $P_kcon[a] + $P_KHB;\n");
  for (int rr = 0; rr < nrc; rr++) { /* the constraint's rows: 1, or the poly family's coefficient r = rr */
    const char *pad = poly ? "  " : "";
    if (poly) out(e, "      {  /* coefficient %d: rho_j = R_j%d */\n", rr, rr);
    for (int j = 0; j < s; j++)
      tmplf(e, "%s      const $R x%d = R[%d + %d * i + t];\n", pad, j, (poly ? rolled_poly_pair(s, j, rr) : j) * mt, T);
    for (int j = 0; j < s; j++) { /* V = (X (x) M^-1) rho: X's row j is xi_j x_j-1 - xi_j+1 x_j+1 (xi_0 x_0 for j = 0) */
      int n = snprintf(x, sizeof x, "%s * x%d", rolled_lit(e, e->me->xi[j]), j ? j - 1 : 0);
      if (j + 1 < s) snprintf(x + n, sizeof x - (size_t)n, " - %s * x%d", rolled_lit(e, e->me->xi[j + 1]), j + 1);
      tmplf(e, "%s      const $R v%d = $P_MINV(i) (%s);\n", pad, j, x);
    }
    for (int c = 0; c < s; c++) {
      basis_col(e, nb->Tinv, c, 0, "v", x, sizeof x);
      tmplf(e, "%s      const $R vt%d = %s;\n", pad, c, x);
      basis_col(e, nb->T, c, 1, "x", x, sizeof x);
      tmplf(e, "%s      const $R ct%d = %s;\n", pad, c, x);
    }
    char cs[32];
    snprintf(cs, sizeof cs, poly ? "cs[%d * %s_NU + a]" : "cs[a]", rr, e->P);
    for (int q = 0; q < nb->nblocks; q++) {
      const NewtonBlock *blk = &nb->blk[q];
      int c = blk->col;
      if (!blk->pair) {
        tmplf(e, "%s      Ar[%d * $P_KW + dv + %d] += vt%d;\n%s      Ac[%d * $P_KW + dc + %d] += ct%d;\n", pad, c, rr - c, c, pad, rr,
              c - rr, c);
        tmplf(e, "%s      %s += fabs$f(vt%d * ct%d);\n", pad, cs, c, c);
        continue;
      }
      double phi = pair_phi(blk);
      const char *cp = rolled_lit(e, cos(phi)), *sp = rolled_lit(e, sin(phi));
      tmplf(e, "%s      Ar[%d * $P_KW + dv + %d] += %s * vt%d - %s * vt%d;  /* e^{-i phi} (Vt_c - i Vt_c+1) */\n", pad, c, rr - c,
            cp, c, sp, c + 1);
      tmplf(e, "%s      Ar[%d * $P_KW + dv + %d] -= %s * vt%d + %s * vt%d;\n", pad, c + 1, rr - c - 1, sp, c, cp, c + 1);
      tmplf(e, "%s      Ac[%d * $P_KW + dc + %d] += ct%d;\n%s      Ac[%d * $P_KW + dc + %d] -= ct%d;  /* z_c = x, z_c+1 = -y */\n",
            pad, rr, c - rr, c, pad, rr, c + 1 - rr, c + 1);
      tmplf(e, "%s      %s += fabs$f(vt%d * ct%d) + fabs$f(vt%d * ct%d);\n", pad, cs, c, c, c + 1, c + 1);
    }
    if (poly) out(e, "      }\n");
  }
  tmpl(e, "    }\n");
  /* the factor's pivots in the band's rows into a scratch of KN, then to their places */
  tmpl(e, "  {\n    $R kp[2 * $P_KN];  /* the band's pivots and diagonal, in its rows */\n"
          "    $P_kkt_factor(A, kp, kp + $P_KN);\n"
          "    for (i = 0; i < $P_M; i++)\n"
          "      for (j = 0; j < $P_S; j++) {\n"
          "        out[$[newton_factor.pivot]0 + j * $P_M + i] = kp[$P_krow[i] + j];\n"
          "        out[$[newton_factor.adiag]0 + j * $P_M + i] = kp[$P_KN + $P_krow[i] + j];\n      }\n"
          "    for (i = 0; i < $P_NU; i++)\n");
  tmplf(e, "      for (j = 0; j < %d; j++) {  /* the constraint's rows: coefficient j */\n"
           "        out[$[newton_factor.spivot]0 + j * $P_NU + i] = kp[$P_kcon[i] + j];\n"
           "        out[$[newton_factor.sadiag]0 + j * $P_NU + i] = cs[j * $P_NU + i];\n      }\n  }\n", nrc);
}

// The kernel "newton_solve" with constraints: the right-hand side w = (T^-1
// (x) I) r (a pair's rotated by e^{-i phi}) in the coordinates' rows and
// C r = sum_j rho_j' r_j in the constraints', the band solve, and dgam =
// (T (x) I) z from the coordinates' rows (the multiplier's mu unused).
static void emit_solve_kkt(Emitter *e, const NewtonBasis *nb) {
  int s = e->me->s, m = e->mod->m, mt = m * e->roll->T, poly = e->me->family == MULT_POLY, nrc = poly ? s : 1;
  char x[2048];
  tmplf(e, "  $R w[%d], z[$P_KN];\n  const $R *R = lu + $P_KN * $P_KW;\n  int i, t;\n"
           "  for (i = 0; i < $P_M; i++) {  /* w = (T^-1 (x) I) r */\n", s * m);
  for (int j = 0; j < s; j++) {
    basis_row(e, nb->Tinv, j, "gam", x, sizeof x);
    out(e, "    w[%d + i] = %s;\n", j * m, x);
  }
  tmpl(e, "  }\n  for (i = 0; i < $P_M; i++) {\n    $R *zi = z + $P_krow[i];\n");
  for (int q = 0; q < nb->nblocks; q++) {
    const NewtonBlock *blk = &nb->blk[q];
    int c = blk->col;
    if (!blk->pair) {
      out(e, "    zi[%d] = w[%d + i];\n", c, c * m);
      continue;
    }
    double phi = pair_phi(blk);
    const char *cp = rolled_lit(e, cos(phi)), *sp = rolled_lit(e, sin(phi));
    out(e, "    zi[%d] = %s * w[%d + i] - %s * w[%d + i];  /* e^{-i phi} (w_c - i w_c+1) */\n", c, cp, c * m, sp, (c + 1) * m);
    out(e, "    zi[%d] = -(%s * w[%d + i] + %s * w[%d + i]);\n", c + 1, sp, c * m, cp, (c + 1) * m);
  }
  tmplf(e, "  }\n  for (i = 0; i < $P_NU; i++)\n    for (t = 0; t < %d; t++) z[$P_kcon[i] + t] = 0;\n"
           "  for (i = 0; i < $P_M; i++)  /* C r */\n"
           "    for (t = 0; t < $P_RT; t++) {\n"
           "      const int a = $P_tcon[$P_RT * i + t];\n"
           "      if (a < 0) continue;\n", nrc);
  for (int rr = 0; rr < nrc; rr++) {
    int n = 0;
    for (int j = 0; j < s; j++)
      n += snprintf(x + n, sizeof x - (size_t)n, "%sR[%d + $P_RT * i + t] * gam[%d + i]", j ? " + " : "",
                    (poly ? rolled_poly_pair(s, j, rr) : j) * mt, j * m);
    tmplf(e, "      z[$P_kcon[a] + %d] += %s;\n", rr, x);
  }
  tmpl(e, "    }\n  $P_kkt_solve(lu, z);\n");
  if (poly)
    tmplf(e, "  for (i = 0; i < $P_NU; i++)  /* the coefficients move by mu / h */\n"
             "    for (t = 0; t < %d; t++) out[$[newton_solve.dlam]0 + t * $P_NU + i] = z[$P_kcon[i] + t] / h;\n", nrc);
  tmpl(e, "  for (i = 0; i < $P_M; i++) {\n    const $R *zi = z + $P_krow[i];\n");
  for (int q = 0; q < nb->nblocks; q++) {
    const NewtonBlock *blk = &nb->blk[q];
    int c = blk->col;
    if (!blk->pair) out(e, "    w[%d + i] = zi[%d];\n", c * m, c);
    else out(e, "    w[%d + i] = zi[%d];\n    w[%d + i] = -zi[%d];\n", c * m, c, (c + 1) * m, c + 1);
  }
  out(e, "  }\n  for (i = 0; i < %d; i++) {  /* dgam = (T (x) I) z */\n", m);
  for (int j = 0; j < s; j++) {
    basis_row(e, nb->T, j, "w", x, sizeof x);
    tmplf(e, "    out[$[newton_solve.dgam]%d + i] = %s;\n", j * m, x);
  }
  out(e, "  }\n");
}

void rolled_newton_kernel(Emitter *e, KernelId id) {
  NewtonBasis nb;
  int nu = e->mod->nu;
  newton_basis(e->me, &nb);
  if (!(e->roll_helpers & 2) && nu) {
    tmplf(e, "\n/* The Newton matrix with the multiplier as one band of $P_KN rows, $P_KHB each side\n"
             " * (emit_rolled_newton.c). */\n"
             "#define $P_KN %d\n#define $P_KHB %d\n#define $P_KW (2 * $P_KHB + 1)\n"
             "#define $P_HT %d  /* entries of a row of Hess(U + lambda' g), at most */\n",
          e->roll->kn, e->roll->khb, e->roll->ht > 0 ? e->roll->ht : 1);
    emit_hessian_family(e);
    emit_real_band_lu(e, "kkt", "$P_KN", "$P_KW", "$P_KHB", "KN");
    e->roll_helpers |= 2;
  } else if (!(e->roll_helpers & 2)) {
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
  if (id == K_NFACTOR) (nu ? emit_factor_kkt : emit_factor)(e, &nb);
  else (nu ? emit_solve_kkt : emit_solve)(e, &nb);
  out(e, "}\n");
}
