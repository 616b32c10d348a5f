/* emit_predict.c - the step's polynomial before and after the step:
 * NAME_predict (the warm start) and NAME_dense (the dense output).
 *
 * NAME_predict extrapolates gamma for the next step from what the state
 * keeps of the last ones (x->gam, x->gam2, x->hprev, x->hprev2): the
 * two-step start where the last two steps had the same size (polynomial
 * family), else the one-step start E[j][i](r) gamma_i, else (first step,
 * or cold) gamma_0 = M^-1 p. The coefficients are printed as literals,
 * summed in the order the tables' loops sum them, so that the batch's
 * table loops (emit_batch.c, which reuses emit_two_step_start and the
 * tables' same-size coefficients) give the same bits. NAME_add, the
 * compensated sum, is printed with NAME_predict, before the step that
 * uses it. NAME_dense evaluates the last step's polynomials inside it. */
#include <stdio.h>
#include <string.h>

#include "emit.h"

// E[j][i](1), t = j*S + i, the warm start's coefficient for a step as long as
// the last one: summed as the step's Horner loop at r = 1 sums it, in the
// solver's type, so that unrolled or tabled it changes no bit.
double same_size_coefficient(const Emitter *e, int t) {
  const Method *me = e->me;
  double sum = 0;
  float fsum = 0;
  for (int d = me->s - 1; d >= 0; d--) {
    sum = sum * 1.0 + me->E[t * me->s + d];
    fsum = fsum * 1.0f + (float)me->E[t * me->s + d];
  }
  return e->single ? (double)fsum : sum;
}

// One term of the warm start, to[j] += c from_i (from: the previous
// step's coefficients, x->gam for gamma), with c a literal: without the
// product where c is 1 (the same sum); ind: the line's indent.
static void emit_warm_term(Emitter *e, const char *ind, const char *to, const char *from, int j, int i, double c) {
  char lit[40] = "";
  if (c != 1) {
    format_real(e, lit, sizeof lit, c);
    strcat(lit, " * ");
  }
  out(e, "%sfor (l = 0; l < %s_M; l++) %s[%d * %s_M + l] += %s%s[%d * %s_M + l];\n", ind, e->P, to, j, e->P, lit,
      from, i, e->P);
}

// The two-step start into gam, each value summed from 0 over the S steps
// in that order, E2's coefficients as literals, one loop a row: gamma_j =
// sum_i E2[j][i] gamma_i + E2[j][S + i] gamma_prev_i, row the length of a
// row of x->gam (M for the step, M W for --batch's lanes). ind: the indent.
void emit_two_step_start(Emitter *e, const char *ind, const char *row) {
  int s = e->me->s;
  for (int j = 0; j < s; j++) {
    out(e, "%sfor (l = 0; l < %s; l++) {\n%s  %s b = 0;\n", ind, row, ind, real_type(e, 0));
    for (int i = 0; i < s; i++) {
      char a[40], b[40];
      format_real(e, a, sizeof a, e->me->E2[2 * s * j + i]);
      format_real(e, b, sizeof b, e->me->E2[2 * s * j + s + i]);
      out(e, "%s  b += %s * x->gam[%d * %s + l] + %s * x->gam2[%d * %s + l];\n", ind, a, i, row, b, i, row);
    }
    out(e, "%s  gam[%d * %s + l] = b;\n%s}\n", ind, j, row, ind);
  }
}

// The warm start of a step as long as the last one, into to:
// to_j += E[j][i](1) from_i, the zero terms left out.
static void emit_predict_same_size(Emitter *e, const char *ind, const char *to, const char *from) {
  for (int t = 0; t < e->me->s * e->me->s; t++) {
    double c = same_size_coefficient(e, t);
    if (c != 0) emit_warm_term(e, ind, to, from, t / e->me->s, t % e->me->s, c);
  }
}

// The warm start of a step whose size differs from the last one's (every
// step of NAME_step_adaptive): to_j += E_ji(r) from_i over the last
// step's coefficients from_i (gamma_i: to gam, from x->gam), r = h / h_previous, each E_ji(r) = sum_d E[(j*S+i)*S+d] r^d
// by Horner's rule from its highest nonzero coefficient, unrolled with the
// coefficients as literals and the (j, i) whose polynomial is zero left
// out. The same sums as the table's loop (0 r + c = c and e r + 0 = e r
// exactly) without its S^3 loads and tests: the loop took 690 of the
// pendulum's 5540 instructions an adaptive step ((4,4), 2026-11-26).
static void emit_predict_resized(Emitter *e, const char *to, const char *from) {
  int s = e->me->s, n = s * s * s, degree = 0;
  for (int t = 0; t < n; t++)
    if (e->me->E[t] != 0 && t % s > degree) degree = t % s;
  if (degree > 0) tmpl(e, "    const $R r = h / x->hprev;\n    $R e;\n");
  for (int j = 0; j < s; j++)
    for (int i = 0; i < s; i++) {
      const double *c = e->me->E + (j * s + i) * s;
      int d = s - 1;
      char lit[40];
      while (d >= 0 && c[d] == 0) d--;
      if (d < 0) continue;
      if (d == 0) { /* a constant: 0 r + c = c */
        emit_warm_term(e, "    ", to, from, j, i, c[0]);
        continue;
      }
      format_real(e, lit, sizeof lit, c[d]);
      out(e, "    e = %s;\n", lit);
      for (d--; d >= 0; d--) {
        if (c[d] == 0) {
          out(e, "    e = e * r;\n");
          continue;
        }
        format_real(e, lit, sizeof lit, c[d]);
        out(e, "    e = e * r + %s;\n", lit);
      }
      out(e, "    for (l = 0; l < %s_M; l++) %s[%d * %s_M + l] += e * %s[%d * %s_M + l];\n", e->P, to, j, e->P, from,
          i, e->P);
    }
}

// The one-step warm start of to (S*M) from the last step's coefficients
// from, added into to (zeroed by the caller): the literals of
// E[j][i](1) where h is the last step's size, else E[j][i](r) by Horner's
// rule, as NAME_predict extrapolates gamma (M(q): Theta, emit_mq.c).
void emit_warm_extrapolation(Emitter *e, const char *to, const char *from) {
  tmpl(e, "  if (h == x->hprev) {\n");
  emit_predict_same_size(e, "    ", to, from);
  tmpl(e, "  } else {\n");
  emit_predict_resized(e, to, from);
  tmpl(e, "  }\n");
}

// NAME_predict (the warm start) and NAME_add (the compensated sum) for the step.
void emit_predict(Emitter *e) {
  tmpl(e, "\n/* gamma for a step of size h: extrapolated from the last two steps' polynomials\n"
          " * when they had size h (polynomial family), else from the previous step's, or gamma_0 = M^-1 p,\n"
          " * gamma_j = 0 (j > 0) on the first step or when cold. */\n");
  int poly = e->st->kern[K_FACTOR].nout > 0;
  if (poly)
    tmpl(e, "/* Returns 1 when gam is the two-step start, ref then the one-step one (whose error\n"
            " * $P_err_est needs; not computed when ref is 0, as in a fixed step without\n"
            " * statistics), else 0. */\n"
            "$P_OUT_OF_LINE int $P_predict(const $P_state *x, $R h, int cold, const $P_params *prm, $R *gam, $R *ref)\n"
            "{\n");
  else
    tmpl(e, "$P_OUT_OF_LINE void $P_predict(const $P_state *x, $R h, int cold, const $P_params *prm, $R *gam)\n{\n");
  tmpl(e, "  int i, l;\n");
  if (poly && !emit_has_sweeps(e)) tmpl(e, "  (void)ref;  /* (the one-step start always: --iteration newton) */\n");
  /* The two-step start saves 7-25% of the sweeps (bench/README.md), in the
   * polynomial family only: it changes where the iteration stops, and the
   * constant family's |H - H0| then drifted 2.3x further over 10^7 steps
   * (pendulum, h = 0.1); the polynomial family restores H every step.
   * Not under --iteration newton, whose loop starts from the one-step start
   * (emit_newton.c: the two-step start's coefficients, up to 166 at s = 3,
   * magnify the stiff motion a long step does not resolve). */
  if (poly && emit_has_sweeps(e)) {
    tmpl(e, "  if (!cold && x->hprev != 0 && h == x->hprev && h == x->hprev2) { /* from the last two steps:\n"
            "      * gamma_j = sum_i E2[j][i] gamma_i + E2[j][S + i] gamma_prev_i, every gamma_j written once */\n"
            "    if (ref) {  /* the one-step start, for the estimate */\n"
            "      for (i = 0; i < $P_S * $P_M; i++) ref[i] = 0;\n");
    emit_predict_same_size(e, "      ", "ref", "x->gam");
    tmpl(e, "    }\n");
    char row[80];
    snprintf(row, sizeof row, "%s_M", e->P);
    emit_two_step_start(e, "    ", row);
    tmpl(e, "    return 1;\n  }\n");
  }
  /* the other starts add into gam, or set gamma_0 alone */
  tmpl(e, "  for (i = 0; i < $P_S * $P_M; i++) gam[i] = 0;\n");
  tmpl(e, poly ? "  if (cold || x->hprev == 0) {\n    $(minv_p q0=x->q p0=x->p out=gam);\n    return 0;\n  }\n"
               : "  if (cold || x->hprev == 0) {\n    $(minv_p q0=x->q p0=x->p out=gam);\n    return;\n  }\n");
  tmpl(e, "  if (h == x->hprev) {  /* gamma_j += E[j][i](1) gamma_i, the zero terms left out */\n");
  emit_predict_same_size(e, "    ", "gam", "x->gam");
  tmpl(e, "  } else {\n");
  emit_predict_resized(e, "gam", "x->gam");
  tmpl(e, "  }\n");
  if (poly) tmpl(e, "  return 0;\n");
  tmpl(e, "}\n\n");
  if (e->compensated)
    tmpl(e, "/* a += b with the rounding error carried in *c (Kahan). */\n"
            "static void $P_add($R *a, $R *c, $R b)\n{\n"
            "  $R y = b - *c, t = *a + y;\n  *c = (t - *a) - y;\n  *a = t;\n}\n\n");
  else
    tmpl(e, "/* a += b, plainly (generated with --plain-sum: no compensated summation). */\n"
            "static void $P_add($R *a, $R *c, $R b)\n{\n  (void)c;\n  *a += b;\n}\n\n");
}

// NAME_dense: q and p inside the last step from its polynomials, written
// from the end of the step backwards so that theta = 1 gives the state
// exactly. q(c) = q0 + h sum_j gamma_j int_0^c P_j and p(c) = p0 + pinc_0 c -
// h sum_{j>=1} Theta_j int_0^c P_j (pinc_0 = p1 - p0, then the Theta_j) are
// the step's polynomials of degree S (uniformly of order S+1); with
// int_0^c P_j = (L_{j+1} - L_{j-1}) (2c-1) / (2 sqrt(2j+1))
// for j >= 1 (Legendre L_j), which vanishes at c = 0 and 1. The poly family's
// projection and rescale of p1 (pcorr) is spread linearly over the step, so
// theta = 0 gives the previous state: it is of the size of the local error.
void emit_dense(Emitter *e) {
  tmpl(e, "\nvoid $P_dense(const $P_state *x, $P_real theta, $P_real *q, $P_real *p)\n{\n"
          "  $R L[$P_S + 1], w[$P_S], u = 2 * theta - 1;\n  int i, j;\n"
          "  /* w_j = int_theta^1 P_j: 1 - theta, and (L_{j-1} - L_{j+1}) / (2 sqrt(2j+1)) */\n"
          "  L[0] = 1;\n  L[1] = u;\n"
          "  for (j = 1; j < $P_S; j++) L[j + 1] = ((2 * j + 1) * u * L[j] - j * L[j - 1]) / (j + 1);\n"
          "  w[0] = 1 - theta;\n"
          "  for (j = 1; j < $P_S; j++) w[j] = (L[j - 1] - L[j + 1]) / (2 * sqrt$f(($R)(2 * j + 1)));\n"
          "  for (i = 0; i < $P_M; i++) {\n    $R dq = w[0] * x->gam[i], dp = 0;\n"
          "    for (j = 1; j < $P_S; j++) {\n"
          "      dq += w[j] * x->gam[j * $P_M + i];\n      dp += w[j] * x->pinc[j * $P_M + i];\n    }\n"
          "    q[i] = x->q[i] - x->hprev * dq;\n");
  tmpl(e, e->st->kern[K_FACTOR].nout
              ? "    p[i] = x->p[i] - (w[0] * x->pinc[i] - x->hprev * dp) - (1 - theta) * x->pcorr[i];\n  }\n}\n"
              : "    p[i] = x->p[i] - (w[0] * x->pinc[i] - x->hprev * dp);\n  }\n}\n");
}
