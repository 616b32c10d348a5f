/* emit_main.c - C text of NAME_main.c, the standalone driver.
 *
 * The driver is a thin description of the model for the runtime library
 * (runtime/hbvmrt.h): sizes, parameter names and offsets, default initial
 * values, and adapters from the runtime's opaque pointers to the typed
 * functions of NAME.h. Options, the loop, CSV and the summary live in the
 * runtime, so every generated driver behaves the same. */
#include <string.h>

#include "hbvmgen.h"

static void emit_values(FILE *f, const char *name, const double *v, int n) {
  fprintf(f, "static const double %s[%d] = {", name, n);
  for (int i = 0; i < n; i++) fprintf(f, "%s%.17g", i ? ", " : "", v[i]);
  fprintf(f, "};\n");
}

// Adapters from the runtime's opaque pointers to the double solver's
// typed functions: the runtime reads and writes its state directly.
// The Newton iteration's counts copied from s to the runtime's st, where
// the solver has them (--iteration newton, or auto on a stiff model).
static const char *newton_copy(const Method *me) {
  return me->iteration == ITER_FIXED ? "" : "  st->newton = s.newton;\n  st->factors = s.factors;\n  st->jacobians = s.jacobians;\n";
}

static void emit_adapters(FILE *f, const char *P, const Method *me) {
  fprintf(f, "static void init(void *x, const double *q0, const double *p0) { %s_init(x, q0, p0); }\n", P);
  fprintf(f, "static void init_params(void *x, const double *q0, const double *p0, const void *prm)\n"
             "{\n  %s_init_params(x, q0, p0, prm);\n}\n", P);
  fprintf(f, "static void params_default(void *prm) { %s_params_default(prm); }\n", P);
  fprintf(f, "static double energy(const void *x, const void *prm) { return %s_energy(x, prm); }\n", P);
  fprintf(f, "static void constraints(const void *x, const void *prm, double *g) { %s_constraints(x, prm, g); }\n", P);
  fprintf(f, "static void hidden(const void *x, const void *prm, double *gp) { %s_hidden(x, prm, gp); }\n", P);
  fprintf(f, "static int project(void *x, const void *prm, double *dq, double *dp) { return %s_project(x, prm, dq, dp); }\n\n",
          P);
  fprintf(f, "static int step(void *x, double h, const void *prm, hbvmrt_stats *st)\n{\n");
  fprintf(f, "  %s_stats s;\n  int rc = %s_step(x, h, prm, &s);\n", P, P);
  fprintf(f, "  st->iters = s.iters;\n  st->increment = s.increment;\n  st->err_est = s.err_est;\n  st->defect = s.defect;\n%s"
             "  return rc;\n}\n\n", newton_copy(me));
  fprintf(f, "static int step_adaptive(void *x, double *h, double tol, const void *prm, hbvmrt_stats *st)\n{\n");
  fprintf(f, "  %s_stats s;\n  int rc = %s_step_adaptive(x, h, tol, prm, &s);\n", P, P);
  fprintf(f, "  st->iters = s.iters;\n  st->increment = s.increment;\n  st->err_est = s.err_est;\n  st->defect = s.defect;\n"
             "  st->h = s.h;\n  st->rejected = s.rejected;\n%s  return rc;\n}\n\n", newton_copy(me));
}

// The adapter `name` of a function of the state with n values (n the
// macro NAME_count), NAME_fn: in float, converted to double.
static void emit_values_adapter(FILE *f, const char *P, int single, const char *name, const char *fn, const char *count) {
  fprintf(f, "static void %s(const void *x, const void *prm, double *values)\n{\n", name);
  if (single)
    fprintf(f, "  %s_params r;\n  %s_real v[%s_%s];\n  int i;\n  to_real(prm, &r);\n"
               "  %s_%s(&((const view *)x)->s, &r, v);\n  for (i = 0; i < %s_%s; i++) values[i] = v[i];\n}\n\n",
            P, P, P, count, P, fn, P, count);
  else
    fprintf(f, "  %s_%s(x, prm, values);\n}\n\n", P, fn);
}

// The adapters of dense output and events (events only when the model has
// some): dense gives a state block y, x at theta inside its last step, for
// the runtime's functions of a state (double solver: its own state; float:
// the view, its double fields synchronised).
static void emit_dense_adapters(FILE *f, const Model *mod, const char *P, int single) {
  fprintf(f, "static void dense(const void *x, double theta, void *y)\n{\n");
  if (single)
    fprintf(f, "  const %s_state *a = &((const view *)x)->s;\n  %s_state *b = &((view *)y)->s;\n"
               "  *b = *a;\n  %s_dense(a, (%s_real)theta, b->q, b->p);\n  b->t = a->t - a->hprev * (1 - (%s_real)theta);\n"
               "  sync(y);\n}\n\n", P, P, P, P, P);
  else
    fprintf(f, "  const %s_state *a = x;\n  %s_state *b = y;\n  *b = *a;\n  %s_dense(a, theta, b->q, b->p);\n"
               "  b->t = a->t - a->hprev * (1 - theta);\n}\n\n", P, P, P);
  if (!mod->nevents) return;
  emit_values_adapter(f, P, single, "events", "events", "NEVENTS");
}

// The adapters of the switching functions and of NAME_restart (only when
// the model has switching functions).
static void emit_switch_adapters(FILE *f, const Model *mod, const char *P, int single) {
  if (!mod->nswitch) return;
  emit_values_adapter(f, P, single, "switches", "switch", "NSWITCH");
  fprintf(f, "static void restart(void *x) { %s_restart(%s); }\n\n", P, single ? "&((view *)x)->s" : "x");
}

// The same for a float solver: the runtime works in double, so it is given
// a view (the state's public fields in double beside the float state, and
// the params in double), converted at every call.
static void emit_float_adapters(FILE *f, const Model *mod, const char *P, const Method *me) {
  int nu1 = mod->nu ? mod->nu : 1;
  fprintf(f, "/* The runtime reads and writes doubles: it sees this view of the float state and\n"
             " * params, converted at every call. */\n");
  fprintf(f, "typedef struct {\n  double t, q[%s_M], p[%s_M], lambda[%d];\n  %s_state s;\n} view;\n\n", P, P, nu1, P);
  fprintf(f, "typedef struct {\n");
  for (int i = 0; i < mod->nparams; i++) fprintf(f, "  double %s;\n", mod->params[i].name);
  if (!mod->nparams) fprintf(f, "  char unused_;\n");
  fprintf(f, "} view_params;\n\n");
  fprintf(f, "static void to_real(const void *prm, %s_params *r)\n{\n  const view_params *d = prm;\n", P);
  for (int i = 0; i < mod->nparams; i++)
    fprintf(f, "  r->%s = (%s_real)d->%s;\n", mod->params[i].name, P, mod->params[i].name);
  fprintf(f, mod->nparams ? "}\n\n" : "  (void)d;\n  r->unused_ = 0;\n}\n\n");
  fprintf(f, "static void params_default(void *prm)\n{\n  view_params *d = prm;\n  %s_params r;\n"
             "  %s_params_default(&r);\n", P, P);
  for (int i = 0; i < mod->nparams; i++) fprintf(f, "  d->%s = r.%s;\n", mod->params[i].name, mod->params[i].name);
  fprintf(f, mod->nparams ? "}\n\n" : "  d->unused_ = r.unused_;\n}\n\n");
  fprintf(f, "static void sync(view *v)\n{\n  int i;\n  v->t = v->s.t;\n"
             "  for (i = 0; i < %s_M; i++) {\n    v->q[i] = v->s.q[i];\n    v->p[i] = v->s.p[i];\n  }\n"
             "  for (i = 0; i < %d; i++) v->lambda[i] = v->s.lambda[i];\n}\n\n", P, nu1);
  fprintf(f, "/* --t0: the float state's time (its compensation cleared) */\n"
             "static void set_time(void *x, double t)\n{\n  view *v = x;\n"
             "  v->s.t = (%s_real)t;\n  v->s.tc = 0;\n  v->t = v->s.t;\n}\n\n", P);
  fprintf(f, "static void init_params(void *x, const double *q0, const double *p0, const void *prm)\n{\n"
             "  %s_real q[%s_M], p[%s_M];\n  %s_params r;\n  int i;\n"
             "  for (i = 0; i < %s_M; i++) {\n    q[i] = q0 ? (%s_real)q0[i] : 0;\n"
             "    p[i] = p0 ? (%s_real)p0[i] : 0;\n  }\n"
             "  to_real(prm, &r);\n  %s_init_params(&((view *)x)->s, q0 ? q : NULL, p0 ? p : NULL, &r);\n"
             "  sync(x);\n}\n\n", P, P, P, P, P, P, P, P);
  fprintf(f, "static void init(void *x, const double *q0, const double *p0)\n{\n  view_params d;\n"
             "  params_default(&d);\n  init_params(x, q0, p0, &d);\n}\n\n");
  fprintf(f, "static int step(void *x, double h, const void *prm, hbvmrt_stats *st)\n{\n"
             "  %s_params r;\n  %s_stats s;\n  int rc;\n  to_real(prm, &r);\n"
             "  rc = %s_step(&((view *)x)->s, (%s_real)h, &r, &s);\n"
             "  st->iters = s.iters;\n  st->increment = s.increment;\n  st->err_est = s.err_est;\n  st->defect = s.defect;\n%s"
             "  sync(x);\n  return rc;\n}\n\n", P, P, P, P, newton_copy(me));
  fprintf(f, "static int step_adaptive(void *x, double *h, double tol, const void *prm, hbvmrt_stats *st)\n{\n"
             "  %s_params r;\n  %s_stats s;\n  %s_real hr = (%s_real)*h;\n  int rc;\n  to_real(prm, &r);\n"
             "  rc = %s_step_adaptive(&((view *)x)->s, &hr, (%s_real)tol, &r, &s);\n  *h = hr;\n"
             "  st->iters = s.iters;\n  st->increment = s.increment;\n  st->err_est = s.err_est;\n  st->defect = s.defect;\n"
             "  st->h = s.h;\n  st->rejected = s.rejected;\n%s  sync(x);\n  return rc;\n}\n\n", P, P, P, P, P, P,
          newton_copy(me));
  fprintf(f, "static double energy(const void *x, const void *prm)\n{\n  %s_params r;\n  to_real(prm, &r);\n"
             "  return %s_energy(&((const view *)x)->s, &r);\n}\n\n", P, P);
  static const char *const fun[2] = {"constraints", "hidden"};
  for (int k = 0; k < 2; k++)
    fprintf(f, "static void %s(const void *x, const void *prm, double *out)\n{\n  %s_params r;\n  %s_real v[%d];\n"
               "  int i;\n  to_real(prm, &r);\n  %s_%s(&((const view *)x)->s, &r, v);\n"
               "  for (i = 0; i < %s_NU; i++) out[i] = v[i];\n}\n\n", fun[k], P, P, nu1, P, fun[k], P);
  fprintf(f, "static int project(void *x, const void *prm, double *dq, double *dp)\n{\n  %s_params r;\n"
             "  %s_real a = 0, b = 0;\n  int rc;\n  to_real(prm, &r);\n  rc = %s_project(&((view *)x)->s, &r, &a, &b);\n"
             "  if (dq) *dq = a;\n  if (dp) *dp = b;\n  sync(x);\n  return rc;\n}\n\n", P, P, P);
}

// With --batch: adapters of NAME_batch_* for the runtime's ensemble runner
// (the state blocks it moves in and out of lanes are views in float).
static void emit_batch_adapters(FILE *f, const char *P, int single) {
  const char *in = single ? "&((const view *)x)->s" : "x", *outx = single ? "&((view *)x)->s" : "x";
  fprintf(f, "static void batch_set(void *b, int lane, const void *x) { %s_batch_set(b, lane, %s); }\n", P, in);
  fprintf(f, "static void batch_get(const void *b, int lane, void *x)\n{\n  %s_batch_get(b, lane, %s);%s\n}\n", P,
          outx, single ? "\n  sync(x);" : "");
  fprintf(f, "static void batch_idle(void *b, int lane, int idle) { ((%s_batch *)b)->idle[lane] = idle != 0; }\n\n", P);
  if (single)
    fprintf(f, "static void batch_params(const void *prm, %s_params *r)\n{\n  int l;\n"
               "  for (l = 0; l < %s_W; l++) to_real((const view_params *)prm + l, &r[l]);\n}\n\n", P, P);
  fprintf(f, "static int batch_step(void *b, double h, const void *prm, int *code, int *iters)\n{\n"
             "  %s_batch_stats s;\n  int l, rc;\n", P);
  if (single) fprintf(f, "  %s_params r[%s_W];\n  batch_params(prm, r);\n  rc = %s_batch_step(b, (%s_real)h, r, &s);\n", P, P, P, P);
  else fprintf(f, "  rc = %s_batch_step(b, h, prm, &s);\n", P);
  fprintf(f, "  for (l = 0; l < %s_W; l++) {\n    code[l] = s.code[l];\n    iters[l] = s.iters[l];\n  }\n"
             "  return rc;\n}\n\n", P);
  fprintf(f, "static void batch_observe(const void *b, const void *prm, double *H, double *g, double *hc)\n{\n"
             "  %s_real e[%s_W], v[(%s_NU + 1) * %s_W], w[(%s_NU + 1) * %s_W];\n  int i;\n", P, P, P, P, P, P);
  if (single) fprintf(f, "  %s_params r[%s_W];\n  batch_params(prm, r);\n  prm = r;\n", P, P);
  fprintf(f, "  %s_batch_energy(b, prm, e);\n  %s_batch_constraints(b, prm, v);\n  %s_batch_hidden(b, prm, w);\n"
             "  for (i = 0; i < %s_W; i++) H[i] = e[i];\n"
             "  for (i = 0; i < %s_NU * %s_W; i++) {\n    g[i] = v[i];\n    hc[i] = w[i];\n  }\n}\n\n", P, P, P, P, P, P);
}

// Write NAME_main.c to f. Returns 0, or -1 on a write error.
int emit_driver(FILE *f, const Model *mod, const Method *me, const EmitOptions *o) {
  const char *P = o->name;
  fprintf(f, "/* %s_main.c - generated by hbvmgen %s from %s: do not edit.\n", P, HBVMGEN_VERSION, o->model_file);
  fprintf(f, " * Standalone driver: cc -O2 -std=c99 -Iruntime -Igenerated generated/%s.c generated/%s_main.c\n", P, P);
  fprintf(f, " *   runtime/libhbvmrt.a -lm; run ./%s --help for its options. */\n", P);
  fprintf(f, "#include <float.h>\n#include <stddef.h>\n\n#include \"hbvmrt.h\"\n#include \"%s.h\"\n\n", P);
  if (o->single) emit_float_adapters(f, mod, P, me);
  else emit_adapters(f, P, me);
  emit_dense_adapters(f, mod, P, o->single);
  emit_switch_adapters(f, mod, P, o->single);
  if (o->batch) emit_batch_adapters(f, P, o->single);
  /* what the runtime sees: the solver's state and params, or their double view */
  size_t n = strlen(P) + 16;
  char *st = arena_alloc(n), *pt = arena_alloc(n);
  snprintf(st, n, "%s_state", P);
  snprintf(pt, n, "%s_params", P);
  if (o->single) strcpy(st, "view"), strcpy(pt, "view_params");
  fprintf(f, "static const hbvmrt_param params[] = {\n");
  for (int i = 0; i < mod->nparams; i++) fprintf(f, "  {\"%s\", offsetof(%s, %s)},\n", mod->params[i].name, pt, mod->params[i].name);
  if (!mod->nparams) fprintf(f, "  {NULL, 0},\n");
  fprintf(f, "};\n");
  fprintf(f, "static const char *const names[] = {");
  for (int i = 0; i < mod->m; i++) fprintf(f, "%s\"%s\"", i ? ", " : "", mod->coord_names[i]);
  fprintf(f, "};\n");
  emit_values(f, "q0", mod->q0, mod->m);
  emit_values(f, "p0", mod->p0, mod->m);
  fprintf(f, "\nint main(int argc, char **argv)\n{\n  static const hbvmrt_model model = {\n");
  fprintf(f, "    \"%s\", %s_M, %s_NU, %s_K, %s_S,\n", P, P, P, P, P);
  fprintf(f, "    sizeof(%s), sizeof(%s),\n", st, pt);
  fprintf(f, "    offsetof(%s, t), offsetof(%s, q), offsetof(%s, p), offsetof(%s, lambda),\n", st, st, st, st);
  fprintf(f, "    %d, params, q0, p0,\n", mod->nparams);
  fprintf(f, "    init, params_default, step, %s_strerror, energy, constraints, hidden, names,\n", P);
  fprintf(f, "    init_params, project, %s,\n    step_adaptive,\n", o->single ? "FLT_EPSILON" : "DBL_EPSILON");
  /* the float view sets its solver's t (--t0); a double state's t the runtime writes itself */
  if (mod->nevents)
    fprintf(f, "    dense, %s_NEVENTS, %s_event_names, %s_event_dirs, events,\n", P, P, P);
  else
    fprintf(f, "    dense, 0, NULL, NULL, NULL,\n");
  fprintf(f, "    %s,\n  };\n", o->single ? "set_time" : "NULL");
  if (o->batch)
    fprintf(f, "  static const hbvmrt_batch batch = {\n    %s_W, sizeof(%s_batch), batch_set, batch_get, batch_idle, "
               "batch_step, batch_observe,\n  };\n", P, P);
  if (mod->nswitch) { /* (a block of its own: the drivers of smooth models stay as they were) */
    fprintf(f, "  static const hbvmrt_switching switching = {\n    %s_NSWITCH, %s_switch_kinds, %s_switch_what, switches, "
               "restart,\n  };\n", P, P, P);
    fprintf(f, "  return hbvmrt_main_switching(&model, &switching, %s, argc, argv);\n}\n", o->batch ? "&batch" : "NULL");
  } else if (o->batch) {
    fprintf(f, "  return hbvmrt_main_batch(&model, &batch, argc, argv);\n}\n");
  } else {
    fprintf(f, "  return hbvmrt_main(&model, argc, argv);\n}\n");
  }
  return ferror(f) ? -1 : 0;
}
