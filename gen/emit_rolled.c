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
 *     tcon) into band storage, A[a][c] at A[a * W + c - a + BW], and factored
 *     and solved by LU without pivoting over the band (the same elimination
 *     lu.c prints unrolled: its symmetric part is positive definite).
 * The sums are those of the straight-line kernels, but some are taken in
 * another order (docs/rolled.md says which): results agree to round-off.
 * Work arrays are locals of the kernels: about (3 + 2T) S M + NU (2 BW + 4)
 * doubles of stack in the sweep. */
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "emit.h"
#include "roll.h"

#define NAME_SIZE 256

// tmpl of a printf format.
static void rtmpl(Emitter *e, const char *fmt, ...) {
  char buf[4096];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  tmpl(e, buf);
}

// The C name of node id inside a run's body: a literal, a parameter, an
// input at its offset from the base b, or the temporary rK of its place k.
static void body_name(Emitter *e, const RollRun *r, int id, char *buf, size_t size) {
  const Node *n = &e->mod->dag->nodes[id];
  int m = e->mod->m;
  switch ((Op)n->op) {
  case OP_CONST: format_real(e, buf, size, n->val); return;
  case OP_PARAM: snprintf(buf, size, "prm->%s", e->mod->params[n->idx].name); return;
  case OP_INPUT: {
    int off = n->idx % m - r->b0;
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
// = value, or with os = 0, acc += value.
static void emit_run(Emitter *e, const RollRun *r, int os, int oo) {
  const Dag *d = e->mod->dag;
  char a[NAME_SIZE], b[NAME_SIZE], rhs[8 * NAME_SIZE];
  if (r->n == 1) out(e, "  { /* item %d */\n    const int u = %d, b = %d;\n", r->u0, r->u0, r->b0);
  else if (r->stride == 1 && r->b0 == r->u0)
    out(e, "  for (u = %d; u < %d; u++) { /* items %d..%d */\n    const int b = u;\n", r->u0, r->u0 + r->n, r->u0, r->u0 + r->n - 1);
  else
    out(e, "  for (u = %d; u < %d; u++) { /* items %d..%d */\n    const int b = %d + %d * (u - %d);\n", r->u0, r->u0 + r->n,
        r->u0, r->u0 + r->n - 1, r->b0, r->stride, r->u0);
  out(e, "    (void)u; (void)b;\n");
  for (int k = 0; k < r->nbody; k++) {
    const Node *n = &d->nodes[r->body[k]];
    if (n->a < 0) continue; /* leaves are named where they are read */
    body_name(e, r, n->a, a, sizeof a);
    if (n->b >= 0) body_name(e, r, n->b, b, sizeof b);
    op_rhs(e, n, a, b, rhs, sizeof rhs);
    out(e, "    const double r%d = %s;\n", k, rhs);
  }
  body_name(e, r, r->body[r->nbody - 1], a, sizeof a);
  if (os) out(e, "    out[%d * u + %d] = %s;\n  }\n", os, oo, a);
  else out(e, "    acc += %s;\n  }\n", a);
}

// A family as the function $P_roll_NAME(q, v, prm, out): out[i] for its
// items, or with sum out[0] = the sum of them in order.
static void emit_family(Emitter *e, const char *name, const char *what, const RollFamily *f, int sum) {
  rtmpl(e, "\n/* %s */\nstatic void $P_roll_%s(const double *q, const double *v, const $P_params *prm, double *out)\n{\n"
           "  int u = 0;\n%s  (void)q; (void)v; (void)prm; (void)u;\n", what, name, sum ? "  double acc = 0;\n" : "");
  for (int i = 0; i < f->nruns; i++) emit_run(e, &f->runs[i], !sum, 0);
  out(e, sum ? "  out[0] = acc;\n}\n" : "}\n");
}

// The Jacobian's entries: out[T i + t] = d g_tcon[i,t] / dq_i, a family per t.
static void emit_jacobian(Emitter *e) {
  const Roll *r = e->roll;
  tmpl(e, "\n/* the Jacobian's entries: out[$P_RT * i + t] = d g_a / dq_i, a = $P_tcon[$P_RT * i + t] (0 where a < 0) */\n"
          "static void $P_roll_jac(const double *q, const double *v, const $P_params *prm, double *out)\n{\n"
          "  int u = 0;\n  (void)q; (void)v; (void)prm; (void)u;\n");
  for (int t = 0; t < r->T; t++)
    for (int i = 0; i < r->jac[t].nruns; i++) emit_run(e, &r->jac[t].runs[i], r->T, t);
  out(e, "}\n");
}

// A table of n reals (or ints) as a static const array, sixteen a line.
static void emit_array(Emitter *e, const char *type, const char *name, const double *v, const int *iv, int n) {
  char lit[64];
  rtmpl(e, "static const %s $P_%s[%d] = {", type, name, n > 0 ? n : 1);
  for (int i = 0; i < n; i++) {
    if (iv) snprintf(lit, sizeof lit, "%d", iv[i]);
    else format_real(e, lit, sizeof lit, v[i]);
    out(e, "%s%s%s", i ? "," : "", i % 16 ? " " : "\n  ", lit);
  }
  out(e, n > 0 ? "\n};\n" : "0};\n");
}

// The band LU of the multiplier system and of G' M^-1 G: factor in place
// (multipliers below the diagonal), pivots and the diagonal it started from;
// solve in place.
static void emit_band(Emitter *e) {
  tmpl(e, "\n/* A (NU x NU, band storage A[a * $P_RW + c - a + $P_RBW]) = L U without pivoting, in place:\n"
          " * pivot[k] the k-th pivot, adiag[k] the diagonal entry it started from. */\n"
          "static void $P_band_factor(double *A, double *pivot, double *adiag)\n{\n"
          "  int k, i, c;\n"
          "  for (k = 0; k < $P_NU; k++) adiag[k] = A[k * $P_RW + $P_RBW];\n"
          "  for (k = 0; k < $P_NU; k++) {\n"
          "    pivot[k] = A[k * $P_RW + $P_RBW];\n"
          "    for (i = k + 1; i <= k + $P_RBW && i < $P_NU; i++) {\n"
          "      const double f = A[i * $P_RW + k - i + $P_RBW] / A[k * $P_RW + $P_RBW];\n"
          "      A[i * $P_RW + k - i + $P_RBW] = f;\n"
          "      for (c = k + 1; c <= k + $P_RBW && c < $P_NU; c++) A[i * $P_RW + c - i + $P_RBW] -= f * A[k * $P_RW + c - k + $P_RBW];\n"
          "    }\n  }\n}\n\n"
          "/* x = A^-1 x for A factored by $P_band_factor. */\n"
          "static void $P_band_solve(const double *A, double *x)\n{\n"
          "  int k, i, c;\n"
          "  for (k = 0; k < $P_NU; k++)\n"
          "    for (i = k + 1; i <= k + $P_RBW && i < $P_NU; i++) x[i] -= A[i * $P_RW + k - i + $P_RBW] * x[k];\n"
          "  for (k = $P_NU - 1; k >= 0; k--) {\n"
          "    double acc = x[k];\n"
          "    for (c = k + 1; c <= k + $P_RBW && c < $P_NU; c++) acc -= A[k * $P_RW + c - k + $P_RBW] * x[c];\n"
          "    x[k] = acc / A[k * $P_RW + $P_RBW];\n  }\n}\n\n"
          "/* B = G' M^-1 G in band storage, G the Jacobian's entries J ($P_roll_jac). */\n"
          "static void $P_roll_gram(const double *J, double *B)\n{\n"
          "  int i, t, s;\n"
          "  for (i = 0; i < $P_NU * $P_RW; i++) B[i] = 0;\n"
          "  for (i = 0; i < $P_M; i++)\n"
          "    for (t = 0; t < $P_RT; t++) {\n"
          "      const int a = $P_tcon[i * $P_RT + t];\n"
          "      if (a < 0) continue;\n"
          "      for (s = 0; s < $P_RT; s++) {\n"
          "        const int c = $P_tcon[i * $P_RT + s];\n"
          "        if (c >= 0) B[a * $P_RW + c - a + $P_RBW] += J[i * $P_RT + t] * ($P_MINV(i) J[i * $P_RT + s]);\n"
          "      }\n    }\n}\n");
}

// Everything the rolled kernels share, printed before the first of them:
// the sizes, the tables (tcon, M^-1, the method's constants) and the
// family functions.
static void emit_helpers(Emitter *e) {
  const Roll *r = e->roll;
  const Method *me = e->me;
  int m = e->mod->m, k = me->k, s = me->s;
  rtmpl(e, "\n/* The rolled form (docs/rolled.md): the model's index kept as loops. T = most constraints\n"
           " * on one coordinate, BW = the half band of the multiplier system. */\n"
           "#define $P_RT %d\n#define $P_RBW %d\n#define $P_RW (2 * $P_RBW + 1)\n", r->T, r->bw);
  if (r->identity) tmpl(e, "#define $P_MINV(i) /* M = I */\n");
  else {
    emit_array(e, "double", "rminv", e->mod->minv_diag, NULL, m);
    tmpl(e, "#define $P_MINV(i) $P_rminv[i] *\n");
  }
  if (r->T) emit_array(e, "int", "tcon", NULL, r->tcon, m * r->T);
  double *xi = xmalloc((size_t)(s + 1) * sizeof(double));
  memcpy(xi, me->xi, (size_t)(s + 1) * sizeof(double));
  emit_array(e, "double", "rIhat", me->Ihat, NULL, k * s);
  emit_array(e, "double", "rW", me->W, NULL, k * s);
  emit_array(e, "double", "rxi", xi, NULL, s + 1);
  free(xi);
  emit_family(e, "gradU", "out[i] = dU/dq_i", &r->gradU, 0);
  emit_family(e, "U", "out[0] = U(q), its terms in the order of its sums", &r->U, 1);
  if (r->nu) {
    emit_family(e, "g", "out[a] = g_a(q)", &r->g, 0);
    emit_family(e, "hvv", "out[a] = v' Hess(g_a)(q) v", &r->hvv, 0);
    emit_jacobian(e);
    emit_band(e);
  }
  e->roll_helpers = 1;
}

// The sweep: stages, projections, multiplier system, new gamma.
static void emit_sweep(Emitter *e) {
  int nu = e->mod->nu, m = e->mod->m, s = e->me->s, T = e->roll->T, mt = m * T;
  rtmpl(e, "  double Q[%d], F[%d], psi[%d], th[%d];\n  int i, j, l, t = 0;\n  (void)t;\n", m, m, s * m, s * m);
  if (nu) rtmpl(e, "  double J[%d], R[%d], A[%d], r[%d];\n", mt, s * mt, nu * (2 * e->roll->bw + 1), nu);
  tmpl(e, "  for (i = 0; i < $P_S * $P_M; i++) psi[i] = 0;\n");
  if (nu) tmpl(e, "  for (i = 0; i < $P_S * $P_M * $P_RT; i++) R[i] = 0;\n");
  tmpl(e, "  /* the k stages: Q = q0 + h sum_j Ihat[l][j] gamma_j; grad U(Q) and grad g(Q), summed with b_l P_j(c_l) */\n"
          "  for (l = 0; l < $P_K; l++) {\n"
          "    for (i = 0; i < $P_M; i++) {\n"
          "      double acc = 0;\n"
          "      for (j = 0; j < $P_S; j++) acc += $P_rIhat[l * $P_S + j] * gam[j * $P_M + i];\n"
          "      Q[i] = q0[i] + h * acc;\n    }\n"
          "    $P_roll_gradU(Q, 0, prm, F);\n");
  if (nu) tmpl(e, "    $P_roll_jac(Q, 0, prm, J);\n");
  tmpl(e, "    for (j = 0; j < $P_S; j++) {\n"
          "      const double w = $P_rW[l * $P_S + j];\n"
          "      for (i = 0; i < $P_M; i++) psi[j * $P_M + i] += w * F[i];\n");
  if (nu) tmpl(e, "      for (i = 0; i < $P_M * $P_RT; i++) R[j * $P_M * $P_RT + i] += w * J[i];\n");
  tmpl(e, "    }\n  }\n");
  if (nu) {
    tmpl(e, "  /* the multiplier system A lambda = r (band): A = h [xi_0 rho_0' M^-1 rho_0 + sum_j xi_j (rho_j' M^-1 rho_j-1\n"
            "   * - rho_j-1' M^-1 rho_j)], r = rho_0' M^-1 (p0 - h xi_0 psi_0) - h sum_j xi_j (...) + g0, a sum over i */\n"
            "  for (i = 0; i < $P_NU * $P_RW; i++) A[i] = 0;\n"
            "  for (i = 0; i < $P_NU; i++) r[i] = 0;\n"
            "  for (i = 0; i < $P_M; i++)\n"
            "    for (t = 0; t < $P_RT; t++) {\n"
            "      const int a = $P_tcon[i * $P_RT + t], it = i * $P_RT + t;\n"
            "      const double *Ra = R + it;\n"
            "      double sk;\n"
            "      int u;\n"
            "      if (a < 0) continue;\n"
            "      sk = $P_rxi[0] * (Ra[0] * ($P_MINV(i) psi[i]));\n"
            "      for (j = 1; j < $P_S; j++)\n"
            "        sk += $P_rxi[j] * (Ra[j * $P_M * $P_RT] * ($P_MINV(i) psi[(j - 1) * $P_M + i])\n"
            "                       - Ra[(j - 1) * $P_M * $P_RT] * ($P_MINV(i) psi[j * $P_M + i]));\n"
            "      r[a] += Ra[0] * ($P_MINV(i) p0[i]) - h * sk;\n"
            "      for (u = 0; u < $P_RT; u++) {\n"
            "        const int c = $P_tcon[i * $P_RT + u];\n"
            "        const double *Rc = R + i * $P_RT + u;\n"
            "        if (c < 0) continue;\n"
            "        sk = $P_rxi[0] * (Ra[0] * ($P_MINV(i) Rc[0]));\n"
            "        for (j = 1; j < $P_S; j++)\n"
            "          sk += $P_rxi[j] * (Ra[j * $P_M * $P_RT] * ($P_MINV(i) Rc[(j - 1) * $P_M * $P_RT])\n"
            "                         - Ra[(j - 1) * $P_M * $P_RT] * ($P_MINV(i) Rc[j * $P_M * $P_RT]));\n"
            "        A[a * $P_RW + c - a + $P_RBW] += h * sk;\n"
            "      }\n    }\n"
            "  for (i = 0; i < $P_NU; i++) r[i] += g0[i];  /* g(q0) / h, or 0 */\n"
            "  $P_band_factor(A, out + $<sweep.pivot>, out + $<sweep.adiag>);\n"
            "  $P_band_solve(A, r);\n"
            "  for (i = 0; i < $P_NU; i++) out[$[sweep.lambda]i] = r[i];\n");
  }
  tmpl(e, "  /* Theta_j = psi_j + rho_j lambda */\n"
          "  for (j = 0; j < $P_S; j++)\n"
          "    for (i = 0; i < $P_M; i++) {\n"
          "      double acc = psi[j * $P_M + i];\n");
  if (nu)
    tmpl(e, "      for (t = 0; t < $P_RT; t++)\n"
            "        if ($P_tcon[i * $P_RT + t] >= 0) acc += R[j * $P_M * $P_RT + i * $P_RT + t] * r[$P_tcon[i * $P_RT + t]];\n");
  tmpl(e, "      th[j * $P_M + i] = acc;\n    }\n"
          "  /* new gamma_j = M^-1 [delta_j0 p0 - h sum_i X[j][i] Theta_i], p1 - p0 = -h Theta_0 */\n"
          "  for (j = 0; j < $P_S; j++)\n"
          "    for (i = 0; i < $P_M; i++) {\n"
          "      double x = $P_rxi[j] * th[(j ? j - 1 : 0) * $P_M + i];\n"
          "      if (j + 1 < $P_S) x -= $P_rxi[j + 1] * th[(j + 1) * $P_M + i];\n"
          "      x = h * x;\n"
          "      out[$[sweep.gam]j * $P_M + i] = $P_MINV(i) (j == 0 ? p0[i] - x : -x);\n    }\n"
          "  for (i = 0; i < $P_M; i++) out[$[sweep.dp]i] = -(h * th[i]);\n"
          "  for (i = 0; i < ($P_S - 1) * $P_M; i++) out[$[sweep.theta]i] = th[$P_M + i];\n");
}

// The consistent multiplier: (G' M^-1 G) lambda = [v' Hess(g_a) v]_a - G' M^-1 grad U.
static void emit_lambda0(Emitter *e) {
  int nu = e->mod->nu, m = e->mod->m, mt = m * e->roll->T;
  rtmpl(e, "  double J[%d], B[%d], gu[%d], v[%d], hv[%d], rr[%d], piv[%d], dia[%d];\n  int i, t;\n", mt,
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
  rtmpl(e, "  double J[%d], B[%d], y[%d], mu[%d];\n  int i, t;\n", mt, nu * (2 * e->roll->bw + 1), nu, nu);
  tmpl(e, "  $P_roll_jac(q0, 0, prm, J);\n  $P_roll_gram(J, B);\n"
          "  $P_band_factor(B, out + $<consistent.pivot>, out + $<consistent.adiag>);\n"
          "  $P_roll_g(q0, 0, prm, y);\n  $P_band_solve(B, y);\n"
          "  for (i = 0; i < $P_NU; i++) mu[i] = 0;\n"
          "  for (i = 0; i < $P_M; i++) {\n"
          "    double acc = 0;\n"
          "    for (t = 0; t < $P_RT; t++)\n"
          "      if ($P_tcon[i * $P_RT + t] >= 0) {\n"
          "        acc += J[i * $P_RT + t] * y[$P_tcon[i * $P_RT + t]];\n"
          "        mu[$P_tcon[i * $P_RT + t]] += J[i * $P_RT + t] * ($P_MINV(i) p0[i]);\n"
          "      }\n"
          "    out[$[consistent.dq]i] = -($P_MINV(i) acc);\n  }\n"
          "  $P_band_solve(B, mu);\n"
          "  for (i = 0; i < $P_M; i++) {\n"
          "    double acc = 0;\n"
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
    tmpl(e, "  double kin = 0, u;\n  int i;\n  for (i = 0; i < $P_M; i++) kin += p0[i] * ($P_MINV(i) p0[i]);\n"
            "  $P_roll_U(q0, 0, prm, &u);\n  out[0] = 0.5 * kin + u;\n");
    break;
  case K_G: tmpl(e, "  $P_roll_g(q0, 0, prm, out);\n"); break;
  case K_HIDDEN:
    rtmpl(e, "  double J[%d];\n  int i, t;\n", mt);
    tmpl(e, "  $P_roll_jac(q0, 0, prm, J);\n  for (i = 0; i < $P_NU; i++) out[i] = 0;\n"
            "  for (i = 0; i < $P_M; i++)\n    for (t = 0; t < $P_RT; t++)\n"
            "      if ($P_tcon[i * $P_RT + t] >= 0) out[$P_tcon[i * $P_RT + t]] += J[i * $P_RT + t] * ($P_MINV(i) p0[i]);\n");
    break;
  default: internal_error("no rolled kernel %d", (int)id);
  }
}

int emit_rolled_kernel(Emitter *e, KernelId id) {
  if (id != K_SWEEP && id != K_MINV_P && id != K_ENERGY && id != K_G && id != K_HIDDEN && id != K_LAMBDA0 &&
      id != K_CONSISTENT)
    return 0; /* the params' q0, p0 and the events stay straight-line: they are small or rare */
  if (!e->roll_helpers) emit_helpers(e);
  const Kernel *k = &e->st->kern[id];
  e->kid = id;
  out(e, "\n/* %s (rolled) */\n", k->what);
  kernel_signature(e, k, -1);
  if (id == K_SWEEP) emit_sweep(e);
  else if (id == K_LAMBDA0) emit_lambda0(e);
  else if (id == K_CONSISTENT) emit_consistent(e);
  else emit_state_kernel(e, id);
  out(e, "}\n");
  return 1;
}
