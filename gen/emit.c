/* emit.c - C text of NAME.h and NAME.c.
 *
 * Every computation of the generated solver is a "kernel": a static
 * function printed from a set of DAG outputs as straight-line code, one
 * operation a line, each intermediate a named const temporary, a comment
 * where a new section of the method starts, constants with 17 significant
 * digits. All kernels share one signature (q0, p0, gamma, h, g0, params ->
 * out[]) so that the input slots of the DAG map to the same C names
 * everywhere. Around the kernels the iteration, warm start, compensated
 * update and failure handling of the step are printed as ordinary C. */
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

typedef struct {
  FILE *f;
  const Model *mod;
  const Method *me;
  const Step *st;
  const char *P;   /* prefix */
  int *temp;       /* temporary number per node, -1 if none */
} Emitter;

static void out(Emitter *e, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vfprintf(e->f, fmt, ap);
  va_end(ap);
}

// A double literal that reads back exactly and is a C floating constant.
static void format_double(char *buf, size_t size, double v) {
  char tmp[40];
  snprintf(tmp, sizeof tmp, "%.17g", v);
  if (!strpbrk(tmp, ".eEn")) strcat(tmp, ".0");
  snprintf(buf, size, v < 0 ? "(%s)" : "%s", tmp);
}

// The C expression that names node id inside a kernel.
static void ref(Emitter *e, int id, char *buf, size_t size) {
  const Node *n = &e->mod->dag->nodes[id];
  const Step *st = e->st;
  switch ((Op)n->op) {
  case OP_CONST: format_double(buf, size, n->val); return;
  case OP_PARAM: snprintf(buf, size, "prm->%s", e->mod->params[n->idx].name); return;
  case OP_INPUT:
    if (n->idx >= st->in_g0) snprintf(buf, size, "g0[%d]", n->idx - st->in_g0);
    else if (n->idx == st->in_h) snprintf(buf, size, "h");
    else if (n->idx >= st->in_gam) snprintf(buf, size, "gam[%d]", n->idx - st->in_gam);
    else if (n->idx >= st->in_p0) snprintf(buf, size, "p0[%d]", n->idx - st->in_p0);
    else if (n->idx >= st->in_q0) snprintf(buf, size, "q0[%d]", n->idx - st->in_q0);
    else internal_error("model coordinate %d reached a kernel", n->idx);
    return;
  default: snprintf(buf, size, "t%d", e->temp[id]); return;
  }
}

// x^n for a small integer n as products, so no pow() call is needed.
static int power_expr(char *buf, size_t size, const char *x, double n) {
  static const char *const forms[] = {NULL, "%s", "%s * %s", "%s * %s * %s", "(%s * %s) * (%s * %s)",
                                      "(%s * %s) * (%s * %s) * %s", "(%s * %s * %s) * (%s * %s * %s)"};
  int k = (int)fabs(n);
  if (n != floor(n) || k < 2 || k > 6) return 0;
  char prod[512];
  snprintf(prod, sizeof prod, forms[k], x, x, x, x, x, x);
  if (n < 0) snprintf(buf, size, "1.0 / (%s)", prod);
  else snprintf(buf, size, "%s", prod);
  return 1;
}

// One line computing node id into its temporary.
static void emit_node(Emitter *e, int id) {
  const Node *n = &e->mod->dag->nodes[id];
  char a[128], b[128], rhs[640];
  ref(e, n->a, a, sizeof a);
  if (n->b >= 0) ref(e, n->b, b, sizeof b);
  switch ((Op)n->op) {
  case OP_ADD: snprintf(rhs, sizeof rhs, "%s + %s", a, b); break;
  case OP_SUB: snprintf(rhs, sizeof rhs, "%s - %s", a, b); break;
  case OP_MUL: snprintf(rhs, sizeof rhs, "%s * %s", a, b); break;
  case OP_DIV: snprintf(rhs, sizeof rhs, "%s / %s", a, b); break;
  case OP_NEG: snprintf(rhs, sizeof rhs, "-%s", a); break;
  case OP_SIGN: snprintf(rhs, sizeof rhs, "(double)((%s > 0) - (%s < 0))", a, a); break;
  case OP_POW: {
    const Node *ex = &e->mod->dag->nodes[n->b];
    if (ex->op == OP_CONST && power_expr(rhs, sizeof rhs, a, ex->val)) break;
    snprintf(rhs, sizeof rhs, "pow(%s, %s)", a, b);
    break;
  }
  default:
    if (n->b >= 0) snprintf(rhs, sizeof rhs, "%s(%s, %s)", op_cfun((Op)n->op), a, b);
    else snprintf(rhs, sizeof rhs, "%s(%s)", op_cfun((Op)n->op), a);
  }
  out(e, "  const double t%d = %s;\n", e->temp[id], rhs);
}

// Print the body of a kernel computing outs[] into out[0..nouts-1].
static void emit_kernel(Emitter *e, const char *name, const char *what, const int *outs, int nouts) {
  const Dag *d = e->mod->dag;
  out(e, "\n/* %s */\nstatic void %s_%s(const double *q0, const double *p0, const double *gam, double h,\n", what, e->P,
      name);
  out(e, "    const double *g0, const %s_params *prm, double *out)\n{\n", e->P);
  out(e, "  (void)q0; (void)p0; (void)gam; (void)h; (void)g0; (void)prm;\n");
  int top = -1;
  for (int i = 0; i < nouts; i++)
    if (outs[i] > top) top = outs[i];
  unsigned char *mark = calloc((size_t)top + 2, 1);
  if (!mark) internal_error("out of memory");
  dag_reach(d, outs, nouts, mark);
  int ntemp = 0, sec = -1, shown = -1;
  for (int id = 0; id <= top; id++) {
    if (!mark[id] || d->nodes[id].a < 0) continue;
    while (sec + 1 < d->marks.n && d->marks.v[sec + 1] <= id) sec++;
    if (sec >= 0 && sec != shown) {
      out(e, "  /* %s */\n", d->labels[sec]);
      shown = sec;
    }
    e->temp[id] = ntemp++;
    emit_node(e, id);
  }
  for (int i = 0; i < nouts; i++) {
    char r[128];
    ref(e, outs[i], r, sizeof r);
    out(e, "  out[%d] = %s;\n", i, r);
  }
  out(e, "}\n");
  free(mark);
}

/* ---- the header ---- */

static void emit_header(Emitter *e, const EmitOptions *o) {
  const Model *mod = e->mod;
  const char *P = o->name;
  int m = mod->m, nu = mod->nu, s = e->me->s;
  out(e, "/* %s.h - generated by hbvmgen %s from %s: do not edit.\n", P, HBVMGEN_VERSION, o->model_file);
  out(e, " * HBVM(k=%d, s=%d) for a Hamiltonian system with %d coordinates and %d constraints. */\n", e->me->k, s, m, nu);
  out(e, "#ifndef %s_H\n#define %s_H\n\n", P, P);
  out(e, "#define %s_M %d      /* coordinates */\n#define %s_NU %d     /* constraints */\n", P, m, P, nu);
  out(e, "#define %s_K %d      /* Gauss-Legendre nodes */\n#define %s_S %d      /* polynomial degree */\n", P, e->me->k, P, s);
  out(e, "#define %s_NPARAMS %d\n\n", P, mod->nparams);
  out(e, "/* Return codes of %s_step; on any nonzero code the state is unchanged. */\n", P);
  out(e, "#define %s_OK 0\n#define %s_ENOCONV 1     /* the fixed-point iteration did not converge: reduce h */\n", P, P);
  out(e, "#define %s_ENONFINITE 2  /* a non-finite value (outside a function's domain?) */\n", P);
  out(e, "#define %s_ESINGULAR 3   /* the multiplier system is singular (dependent constraints?) */\n", P);
  out(e, "#define %s_EBADSTEP 4    /* h is zero or not finite */\n\n", P);
  out(e, "typedef struct {\n  double t, q[%d], p[%d], lambda[%d];\n", m, m, nu ? nu : 1);
  out(e, "  /* private: compensated-summation errors and the last step's polynomial */\n");
  out(e, "  double tc, qc[%d], pc[%d], gam[%d], hprev;\n} %s_state;\n\n", m, m, s * m, P);
  out(e, "typedef struct {\n");
  for (int i = 0; i < mod->nparams; i++) {
    char v[40];
    format_double(v, sizeof v, mod->params[i].value);
    out(e, "  double %s;   /* default %s */\n", mod->params[i].name, v);
  }
  if (!mod->nparams) out(e, "  char unused_; /* the model has no parameters */\n");
  out(e, "} %s_params;\n\n", P);
  out(e, "typedef struct {\n  int iters;         /* fixed-point iterations */\n");
  out(e, "  double increment;  /* last scaled increment of the iteration */\n} %s_stats;\n\n", P);
  out(e, "/* q0, p0 NULL: the model's initial values. */\n");
  out(e, "void %s_init(%s_state *x, const double *q0, const double *p0);\n", P, P);
  out(e, "void %s_params_default(%s_params *prm);\n", P, P);
  out(e, "/* One step of size h; prm and st may be NULL. Returns %s_OK or an error code. */\n", P);
  out(e, "int %s_step(%s_state *x, double h, const %s_params *prm, %s_stats *st);\n", P, P, P, P);
  out(e, "const char *%s_strerror(int code);\n", P);
  out(e, "double %s_energy(const %s_state *x, const %s_params *prm);\n", P, P, P);
  out(e, "void %s_constraints(const %s_state *x, const %s_params *prm, double *g);\n", P, P, P);
  out(e, "void %s_hidden(const %s_state *x, const %s_params *prm, double *gp);\n", P, P, P);
  out(e, "\n#endif\n");
}

/* ---- the source ---- */

static void emit_array(Emitter *e, const char *name, const double *v, int n) {
  out(e, "static const double %s_%s[%d] = {", e->P, name, n > 0 ? n : 1);
  for (int i = 0; i < n; i++) {
    char b[40];
    format_double(b, sizeof b, v[i]);
    out(e, "%s%s", i ? ", " : "", b);
  }
  out(e, "%s};\n", n > 0 ? "" : "0.0");
}

static void emit_prelude(Emitter *e, const EmitOptions *o) {
  const char *P = e->P;
  const Method *me = e->me;
  out(e, "/* %s.c - generated by hbvmgen %s from %s: do not edit.\n", P, HBVMGEN_VERSION, o->model_file);
  out(e, " * HBVM(k=%d, s=%d): line-integral method for Hamiltonian systems with holonomic\n", me->k, me->s);
  out(e, " * constraints (Brugnano, Gurioli, Iavernaro, Weinmueller). Needs only <math.h>. */\n");
  out(e, "#include <math.h>\n#include <string.h>\n\n#include \"%s.h\"\n\n", P);
  out(e, "#define M %s_M\n#define NU %s_NU\n#define S %s_S\n", P, P, P);
  out(e, "#define MAXITER 100       /* fixed-point iterations before giving up */\n");
  out(e, "#define TOL 4.4408920985006262e-16  /* converged: increment within 2 ulps */\n");
  out(e, "#define STAGTOL 1e-10     /* an increment that stops decreasing above this is divergence */\n");
  out(e, "#define SINGTOL 1e-13     /* pivot / diagonal of A below this: singular */\n\n");
  out(e, "/* Gauss-Legendre nodes c_l and weights b_l on [0,1], k = %d (the kernels below use\n", me->k);
  out(e, " * their products with P_j and int_0^c P_j, folded into the code):\n");
  for (int l = 0; l < me->k; l++) out(e, " *   c_%d = %.17g   b_%d = %.17g\n", l + 1, me->c[l], l + 1, me->b[l]);
  out(e, " */\n");
  out(e, "/* Warm start: E[j][i](r) = sum_d E[(j*S+i)*S+d] r^d, r = h / h_previous. */\n");
  emit_array(e, "E", me->E, me->s * me->s * me->s);
  out(e, "/* Model defaults for q0 and p0. */\n");
  emit_array(e, "q0", e->mod->q0, e->mod->m);
  emit_array(e, "p0", e->mod->p0, e->mod->m);
  (void)o;
}

static void emit_kernels(Emitter *e) {
  const Step *st = e->st;
  int m = e->mod->m, nu = e->mod->nu, s = e->me->s;
  int nsweep = s * m + m + 3 * nu;
  int *sweep = malloc((size_t)nsweep * sizeof(int));
  if (!sweep) internal_error("out of memory");
  memcpy(sweep, st->gam_new, (size_t)(s * m) * sizeof(int));
  memcpy(sweep + s * m, st->dp, (size_t)m * sizeof(int));
  memcpy(sweep + s * m + m, st->lambda, (size_t)nu * sizeof(int));
  memcpy(sweep + s * m + m + nu, st->pivot, (size_t)nu * sizeof(int));
  memcpy(sweep + s * m + m + 2 * nu, st->adiag, (size_t)nu * sizeof(int));
  emit_kernel(e, "sweep",
              "One fixed-point sweep: out = new gamma (S*M), p1 - p0 (M), lambda (NU),\n"
              " * pivots of the LU of A (NU), diagonal of A (NU).",
              sweep, nsweep);
  free(sweep);
  emit_kernel(e, "minv_p", "out = M^-1 p0: the first step's prediction of gamma_0", st->predict0, m);
  emit_kernel(e, "energy_kernel", "out[0] = H(q0, p0) = p0' M^-1 p0 / 2 + U(q0)", st->energy, 1);
  if (nu) {
    emit_kernel(e, "g", "out = g(q0)", st->g_at_q0, nu);
    emit_kernel(e, "hidden_kernel", "out = grad g(q0)' M^-1 p0", st->hidden, nu);
  }
}

static void emit_public(Emitter *e) {
  const char *P = e->P;
  int nu = e->mod->nu;
  out(e, "\nvoid %s_params_default(%s_params *prm)\n{\n", P, P);
  for (int i = 0; i < e->mod->nparams; i++) {
    char v[40];
    format_double(v, sizeof v, e->mod->params[i].value);
    out(e, "  prm->%s = %s;\n", e->mod->params[i].name, v);
  }
  if (!e->mod->nparams) out(e, "  prm->unused_ = 0;\n");
  out(e, "}\n\nvoid %s_init(%s_state *x, const double *q0, const double *p0)\n{\n", P, P);
  out(e, "  memset(x, 0, sizeof *x);\n  memcpy(x->q, q0 ? q0 : %s_q0, sizeof x->q);\n", P);
  out(e, "  memcpy(x->p, p0 ? p0 : %s_p0, sizeof x->p);\n}\n\n", P);
  out(e, "const char *%s_strerror(int code)\n{\n  switch (code) {\n", P);
  out(e, "  case %s_OK: return \"ok\";\n  case %s_ENOCONV: return \"fixed-point iteration did not converge\";\n", P, P);
  out(e, "  case %s_ENONFINITE: return \"non-finite value\";\n", P);
  out(e, "  case %s_ESINGULAR: return \"singular multiplier system\";\n", P);
  out(e, "  case %s_EBADSTEP: return \"step size zero or not finite\";\n  }\n  return \"unknown error\";\n}\n\n", P);
  out(e, "#define DEFAULT_PARAMS(prm) %s_params dflt_; if (!prm) { %s_params_default(&dflt_); prm = &dflt_; }\n\n", P, P);
  out(e, "double %s_energy(const %s_state *x, const %s_params *prm)\n{\n  double H;\n  DEFAULT_PARAMS(prm)\n", P, P, P);
  out(e, "  %s_energy_kernel(x->q, x->p, NULL, 0, NULL, prm, &H);\n  return H;\n}\n\n", P);
  out(e, "void %s_constraints(const %s_state *x, const %s_params *prm, double *g)\n{\n", P, P, P);
  if (nu) out(e, "  DEFAULT_PARAMS(prm)\n  %s_g(x->q, x->p, NULL, 0, NULL, prm, g);\n}\n\n", P);
  else out(e, "  (void)x; (void)prm; (void)g;\n}\n\n");
  out(e, "void %s_hidden(const %s_state *x, const %s_params *prm, double *gp)\n{\n", P, P, P);
  if (nu) out(e, "  DEFAULT_PARAMS(prm)\n  %s_hidden_kernel(x->q, x->p, NULL, 0, NULL, prm, gp);\n}\n", P);
  else out(e, "  (void)x; (void)prm; (void)gp;\n}\n");
}

// The warm start, iteration and compensated update around the sweep kernel.
static void emit_step(Emitter *e) {
  const char *P = e->P;
  int nu = e->mod->nu;
  out(e, "\n/* gamma for a step of size h: extrapolated from the previous step's polynomial,\n");
  out(e, " * or gamma_0 = M^-1 p, gamma_j = 0 (j > 0) on the first step. */\n");
  out(e, "static void %s_predict(const %s_state *x, double h, const %s_params *prm, double *gam)\n{\n", P, P, P);
  out(e, "  int i, j, l, d;\n  if (x->hprev == 0) {\n    memset(gam, 0, S * M * sizeof *gam);\n");
  out(e, "    %s_minv_p(x->q, x->p, NULL, 0, NULL, prm, gam);\n    return;\n  }\n", P);
  out(e, "  for (j = 0; j < S; j++) {\n    for (l = 0; l < M; l++) gam[j * M + l] = 0;\n");
  out(e, "    for (i = 0; i < S; i++) {\n      double r = h / x->hprev, e = 0;\n");
  out(e, "      for (d = S - 1; d >= 0; d--) e = e * r + %s_E[(j * S + i) * S + d];\n", P);
  out(e, "      if (e != 0)\n        for (l = 0; l < M; l++) gam[j * M + l] += e * x->gam[i * M + l];\n");
  out(e, "    }\n  }\n}\n\n");
  out(e, "/* a += b with the rounding error carried in *c (Kahan). */\n");
  out(e, "static void %s_kahan(double *a, double *c, double b)\n{\n", P);
  out(e, "  double y = b - *c, t = *a + y;\n  *c = (t - *a) - y;\n  *a = t;\n}\n\n");
  out(e, "/* One step of HBVM(%d,%d). Iterates the sweep until the increment reaches round-off\n", e->me->k, e->me->s);
  out(e, " * or stops decreasing; commits to *x only on success. */\n");
  out(e, "int %s_step(%s_state *x, double h, const %s_params *prm, %s_stats *st)\n{\n", P, P, P, P);
  out(e, "  double gam[S * M], sw[S * M + M + 3 * NU + 1], g0[NU + 1];\n");
  out(e, "  double inc = HUGE_VAL, inc_old, scale;\n  int it, i, rc = %s_ENOCONV;\n  DEFAULT_PARAMS(prm)\n", P);
  out(e, "  if (!(h != 0 && isfinite(h))) return %s_EBADSTEP;\n", P);
  out(e, "  %s_predict(x, h, prm, gam);\n", P);
  if (nu) out(e, "  %s_g(x->q, x->p, NULL, 0, NULL, prm, g0);\n", P);
  else out(e, "  g0[0] = 0;\n");
  out(e, "  for (it = 1; it <= MAXITER; it++) {\n");
  out(e, "    %s_sweep(x->q, x->p, gam, h, g0, prm, sw);\n", P);
  out(e, "    /* increment: max |h (gamma_new - gamma)| over max |q| + |h gamma_0| */\n");
  out(e, "    inc_old = inc;\n    inc = 0;\n    scale = 0;\n");
  out(e, "    for (i = 0; i < M; i++) scale = fmax(scale, fabs(x->q[i]) + fabs(h * sw[i]));\n");
  out(e, "    for (i = 0; i < S * M; i++) {\n");
  out(e, "      inc = fmax(inc, fabs(h * (sw[i] - gam[i])));\n");
  out(e, "      gam[i] = sw[i];\n    }\n");
  out(e, "    if (scale > 0) inc /= scale;\n");
  out(e, "    for (i = 0; i < S * M + M + NU; i++)\n      if (!isfinite(sw[i])) rc = %s_ENONFINITE;\n", P);
  out(e, "    if (rc == %s_ENONFINITE || !isfinite(inc)) { rc = %s_ENONFINITE; break; }\n", P, P);
  if (nu) {
    out(e, "    for (i = 0; i < NU; i++)\n");
    out(e, "      if (!(fabs(sw[S * M + M + NU + i]) > SINGTOL * fabs(sw[S * M + M + 2 * NU + i]))) rc = %s_ESINGULAR;\n", P);
    out(e, "    if (rc == %s_ESINGULAR) break;\n", P);
  }
  out(e, "    if (inc <= TOL) { rc = %s_OK; break; }\n", P);
  out(e, "    if (it > 1 && inc >= inc_old) { rc = inc <= STAGTOL ? %s_OK : %s_ENOCONV; break; }\n  }\n", P, P);
  out(e, "  if (st) { st->iters = it > MAXITER ? MAXITER : it; st->increment = inc; }\n");
  out(e, "  if (rc != %s_OK) return rc;\n", P);
  out(e, "  for (i = 0; i < M; i++) {\n    %s_kahan(&x->q[i], &x->qc[i], h * sw[i]);\n", P);
  out(e, "    %s_kahan(&x->p[i], &x->pc[i], sw[S * M + i]);\n  }\n", P);
  out(e, "  for (i = 0; i < NU; i++) x->lambda[i] = sw[S * M + M + i];\n");
  out(e, "  %s_kahan(&x->t, &x->tc, h);\n  memcpy(x->gam, gam, sizeof x->gam);\n  x->hprev = h;\n  return %s_OK;\n}\n", P, P);
}

// Write NAME.h to hf and NAME.c to cf. Returns 0, or -1 on a write error.
int emit_solver(FILE *hf, FILE *cf, const Model *mod, const Method *me, const Step *st, const EmitOptions *o) {
  Emitter e = {hf, mod, me, st, o->name, NULL};
  e.temp = malloc((size_t)mod->dag->n * sizeof(int));
  if (!e.temp) internal_error("out of memory");
  emit_header(&e, o);
  e.f = cf;
  emit_prelude(&e, o);
  emit_kernels(&e);
  emit_public(&e);
  emit_step(&e);
  free(e.temp);
  return ferror(hf) || ferror(cf) ? -1 : 0;
}
