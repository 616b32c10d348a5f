/* emit_batch.c - --batch W: the step over W trajectories in SIMD lanes.
 *
 * NAME_batch holds W states in struct-of-arrays form: value i of lane l at
 * [i * NAME_W + l]. The kernels are printed a second time as loops over the
 * lanes around the same straight-line body (emit_kernel.c with e->lanes),
 * which gcc and clang vectorise: one vector register holds one temporary of
 * W lanes. Around them, NAME_batch_step runs the scalar step's algorithm
 * (emit_step.c) lane by lane: the same prediction, the same sweeps until the
 * lane's own increment is at round-off, the same tests and the same
 * compensated update, so each lane is bitwise the scalar NAME_step from the
 * same state (NAME_batch_step: emit_batch_step.c). With Newton, and where
 * M depends on q and there are constraints, the lanes take the scalar step
 * itself in turn (emit_batch_by_lane.c), and only the observers' kernels are
 * printed over lanes. */
#include "emit.h"

// The batch declarations of NAME.h.
void emit_batch_header(Emitter *e, int lanes) {
  int poly = e->st->kern[K_FACTOR].nout > 0, nu1 = e->mod->nu ? e->mod->nu : 1;
  out(e, "/* --batch %d: %d trajectories stepped together (docs/api.md, \"Batches\"). Struct of\n", lanes, lanes);
  tmpl(e, " * arrays: value i of lane l is at [i * $P_W + l], q[i * $P_W + l] the coordinate i\n"
          " * of trajectory l. */\n");
  out(e, "#define %s_W %d\n\n", e->P, lanes);
  tmpl(e, "typedef struct {\n  $P_real t[$P_W], q[$P_M * $P_W], p[$P_M * $P_W], lambda[");
  out(e, "%d * %s_W];\n", nu1, e->P);
  tmpl(e, "  /* private, per lane as in $P_state */\n"
          "  $P_real tc[$P_W], qc[$P_M * $P_W], pc[$P_M * $P_W], gam[$P_S * $P_M * $P_W], hprev[$P_W];\n"
          "  $P_real gam2[$P_S * $P_M * $P_W], hprev2[$P_W], errprev[$P_W], aim[$P_W];\n"
          "  $P_real pinc[$P_S * $P_M * $P_W];\n");
  if (poly) tmpl(e, "  $P_real H0[$P_W], pcorr[$P_M * $P_W];\n");
  else if (e->mod->mass_q) tmpl(e, "  $P_real H0[$P_W];  /* M(q): the energy the step keeps */\n");
  if (emit_batch_by_lane(e)) emit_batch_by_lane_fields(e); /* emit_batch_by_lane.c */
  /* idle last: every array before it starts at a multiple of W reals, so a
   * vector of one value's lanes never straddles two cache lines more than
   * the struct's own alignment makes it */
  tmpl(e, "  unsigned char idle[$P_W];  /* nonzero: the lane is not stepped (cleared by $P_batch_set) */\n"
          "} $P_batch;\n\n"
          "typedef struct {\n"
          "  int code[$P_W];            /* the lane's return code, as $P_step's ($P_OK for idle lanes) */\n"
          "  int iters[$P_W];           /* fixed-point iterations (0: failed or idle before the first) */\n"
          "  $P_real increment[$P_W];  /* last scaled increment */\n"
          "  $P_real err_est[$P_W];    /* $P_batch_step_adaptive: the lane's local error estimate */\n"
          "  $P_real h;                 /* the step taken (0: none) */\n"
          "  int rejected;              /* $P_batch_step_adaptive: tries rejected before it */\n");
  if (emit_is_newton(e)) emit_batch_newton_stats(e);
  tmpl(e, "} $P_batch_stats;\n\n"
          "/* Lane `lane` of x from / into a state; set also makes the lane active (idle 0). */\n"
          "void $P_batch_set($P_batch *x, int lane, const $P_state *s);\n"
          "void $P_batch_get(const $P_batch *x, int lane, $P_state *s);\n"
          "/* One step of size h on every active lane; prm: NULL (the defaults) or $P_W params, one\n"
          " * per lane; st may be NULL. Each lane is bitwise what $P_step would make of it; a lane\n"
          " * that fails is left unchanged. Returns the number of lanes that failed. */\n"
          "int $P_batch_step($P_batch *x, $P_real h, const $P_params *prm, $P_batch_stats *st);\n"
          "/* One step of at most *h shared by every active lane, within tol as $P_step_adaptive's\n"
          " * in each lane: a try with a lane over its tolerance, or failing, is retried smaller\n"
          " * with no lane written; *h is the next step proposed. Each lane of an accepted step is\n"
          " * bitwise $P_step_adaptive's step of that size (after three tries over the tolerance,\n"
          " * its cold one), but for the controller's aim, the lanes' lowest, which they then\n"
          " * share. Returns the number of lanes that failed: below the smallest step\n"
          " * every active lane, none written. */\n"
          "int $P_batch_step_adaptive($P_batch *x, $P_real *h, $P_real tol, const $P_params *prm, $P_batch_stats *st);\n"
          "/* H (W values), g and the hidden constraints ($P_NU * $P_W values) of every lane. */\n"
          "void $P_batch_energy(const $P_batch *x, const $P_params *prm, $P_real *H);\n"
          "void $P_batch_constraints(const $P_batch *x, const $P_params *prm, $P_real *g);\n"
          "void $P_batch_hidden(const $P_batch *x, const $P_params *prm, $P_real *gp);\n\n");
}

// NAME_batch_set and NAME_batch_get: one lane to and from a NAME_state.
static void emit_set_get(Emitter *e) {
  static const char *const scalar[] = {"t", "tc", "hprev", "hprev2", "errprev", "aim", "H0"}, *const array[][2] = {
      {"q", "$P_M"},   {"p", "$P_M"},   {"qc", "$P_M"}, {"pc", "$P_M"}, {"gam", "$P_S * $P_M"}, {"gam2", "$P_S * $P_M"},
      {"lambda", "$P_NU"}, {"pinc", "$P_S * $P_M"}, {"pcorr", "$P_M"}};
  int poly = e->st->kern[K_FACTOR].nout > 0;
  char line[160];
  for (int get = 0; get < 2; get++) {
    tmpl(e, get ? "void $P_batch_get(const $P_batch *x, int l, $P_state *s)\n{\n  int i;\n"
                : "void $P_batch_set($P_batch *x, int l, const $P_state *s)\n{\n  int i;\n");
    for (int f = 0; f < (poly || e->mod->mass_q ? 7 : 6); f++) /* H0 last */
      out(e, get ? "  s->%s = x->%s[l];\n" : "  x->%s[l] = s->%s;\n", scalar[f], scalar[f]);
    for (int f = 0; f < (poly ? 9 : 8); f++) {
      const char *n = array[f][0];
      if (get) snprintf(line, sizeof line, "  for (i = 0; i < %s; i++) s->%s[i] = x->%s[i * $P_W + l];\n", array[f][1], n, n);
      else snprintf(line, sizeof line, "  for (i = 0; i < %s; i++) x->%s[i * $P_W + l] = s->%s[i];\n", array[f][1], n, n);
      tmpl(e, line);
    }
    if (emit_is_newton(e)) emit_batch_newton_set_get(e, get);
    if (get && !e->mod->nu) tmpl(e, "  s->lambda[0] = 0;\n");
    tmpl(e, get ? "}\n\n" : "  x->idle[l] = 0;\n}\n\n");
  }
}

// The params of the lanes transposed for the kernels (par[k * W + l]), the
// defaults when prm is NULL; and the public functions of the state.
static void emit_params_observers(Emitter *e) {
  tmpl(e, "static void $P_batch_params(const $P_params *prm, $R *par)\n{\n"
          "  $P_params dflt;\n  int l;\n  (void)par;\n"
          "  if (!prm) $P_params_default(&dflt);\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    const $P_params *r = prm ? &prm[l] : &dflt;\n    (void)r;\n");
  for (int i = 0; i < e->mod->nparams; i++) out(e, "    par[%d * %s_W + l] = r->%s;\n", i, e->P, e->mod->params[i].name);
  tmpl(e, "  }\n}\n\n"
          "void $P_batch_energy(const $P_batch *x, const $P_params *prm, $P_real *H)\n{\n"
          "  $R par[($P_NPARAMS + 1) * $P_W];\n"
          "  $P_batch_params(prm, par);\n"
          "  $(energy_kernel q0=x->q p0=x->p prm=par out=H);\n}\n\n");
  if (e->mod->nu)
    tmpl(e, "void $P_batch_constraints(const $P_batch *x, const $P_params *prm, $P_real *g)\n{\n"
            "  $R par[($P_NPARAMS + 1) * $P_W];\n  $P_batch_params(prm, par);\n"
            "  $(g q0=x->q p0=x->p prm=par out=g);\n}\n\n"
            "void $P_batch_hidden(const $P_batch *x, const $P_params *prm, $P_real *gp)\n{\n"
            "  $R par[($P_NPARAMS + 1) * $P_W];\n  $P_batch_params(prm, par);\n"
            "  $(hidden_kernel q0=x->q p0=x->p prm=par out=gp);\n}\n\n");
  else
    tmpl(e, "void $P_batch_constraints(const $P_batch *x, const $P_params *prm, $P_real *g)\n{\n"
            "  (void)x; (void)prm; (void)g;\n}\n\n"
            "void $P_batch_hidden(const $P_batch *x, const $P_params *prm, $P_real *gp)\n{\n"
            "  (void)x; (void)prm; (void)gp;\n}\n\n");
}

// The prediction when every lane comes from the same last steps (hprev and
// hprev2 equal in all lanes, none cold: lanes that share h, or a run of fixed
// steps): the coefficients once, and loops over whole rows of M W values
// with no selects, each value summed in $P_predict's order (the two-step sum
// written out over the S steps). Bitwise the general path's values.
static void emit_predict_uniform(Emitter *e, int poly) {
  tmpl(e, "  for (l = 0; l < $P_W; l++)\n"
          "    uni &= (x->hprev[l] == x->hprev[0]) & (x->hprev2[l] == x->hprev2[0]) & (x->hprev[l] != 0);\n"
          "  if (uni) {  /* every lane from the same last steps: one set of coefficients */\n"
          "    $R hp = x->hprev[0], r0 = h / hp;\n");
  tmpl(e, poly ? "    int two0 = (h == hp) & (h == x->hprev2[0]);\n" : "    int two0 = 0;  /* no two-step start in this family */\n");
  tmpl(e, "    if (twos)\n      for (l = 0; l < $P_W; l++) twos[l] = two0;\n"
          "    if (!two0 || ref)  /* the one-step start */\n"
          "      for (j = 0; j < $P_S; j++) {\n"
          "        $R *restrict a = (two0 ? ref : gam) + j * $P_M * $P_W;\n"
          "        for (l = 0; l < $P_M * $P_W; l++) a[l] = 0;\n"
          "        for (i = 0; i < $P_S; i++) {\n"
          "          $R c = 0;\n"
          "          if (h == hp)\n            c = $P_E1[j * $P_S + i];\n"
          "          else\n            for (d = $P_S - 1; d >= 0; d--) c = c * r0 + $P_E[(j * $P_S + i) * $P_S + d];\n"
          "          if (c != 0)\n            for (l = 0; l < $P_M * $P_W; l++) a[l] += c * x->gam[i * $P_M * $P_W + l];\n"
          "        }\n      }\n");
  if (poly) {
    char row[80];
    snprintf(row, sizeof row, "%s_M * %s_W", e->P, e->P);
    tmpl(e, "    if (two0) {  /* the two-step start, its coefficients E2 as literals */\n");
    emit_two_step_start(e, "      ", row);
    tmpl(e, "    } else if (ref)\n");
  } else
    tmpl(e, "    if (ref)\n");
  tmpl(e, "      for (l = 0; l < $P_S * $P_M * $P_W; l++) ref[l] = gam[l];\n"
          "    return;\n  }\n");
}

// $P_predict over the lanes with selects: every lane's one-step
// extrapolation (coefficients E1 when h is unchanged, else the polynomial in
// h / hprev), the polynomial family's two-step start, and the cold start
// (gamma_1 = M^-1 p; every lane's with cold_all) are all computed and the
// lane's own one chosen. Lanes that all take the two-step start come from the
// same last steps, so they take the uniform path above, never this one. For the adaptive step, ref (when not NULL) gets the
// one-step start and twos (when not NULL) the lanes that took the two-step.
static void emit_batch_predict(Emitter *e) {
  int poly = e->st->kern[K_FACTOR].nout > 0;
  tmpl(e, "$P_LANE_INLINE void $P_batch_predict(const $P_batch *restrict x, $R h, int cold_all, const $R *restrict par,\n"
          "    $R *restrict gam, $R *restrict ref, $M *restrict twos)\n{\n"
          "  $R mp[$P_M * $P_W], r[$P_W], ec[$P_S * $P_S * $P_W];\n  $M cold[$P_W], two[$P_W], same[$P_W];\n"
          "  int i, j, l, m, d;\n  $M uni = !cold_all;  /* as wide as the reals: its reduction vectorises */\n");
  emit_predict_uniform(e, poly);
  tmpl(e, "  $(minv_p q0=x->q p0=x->p prm=par out=mp);\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    $R hp = x->hprev[l], hq = x->hprev2[l];\n"
          "    cold[l] = (hp == 0) | cold_all;\n    same[l] = h == hp;\n    r[l] = h / (hp != 0 ? hp : 1);\n    (void)hq;\n");
  /* the polynomial family's two-step start, as $P_predict's */
  tmpl(e, poly ? "    two[l] = (hp != 0) & (h == hp) & (h == hq) & (cold_all == 0);\n  }\n" : "    two[l] = 0;\n  }\n");
  tmpl(e, "  if (twos)\n    for (l = 0; l < $P_W; l++) twos[l] = two[l];\n"
          "  for (j = 0; j < $P_S * $P_S; j++) {  /* the one-step coefficients */\n"
          "    $R c[$P_W];\n    for (l = 0; l < $P_W; l++) c[l] = 0;\n"
          "    for (d = $P_S - 1; d >= 0; d--)\n      for (l = 0; l < $P_W; l++) c[l] = c[l] * r[l] + $P_E[j * $P_S + d];\n"
          "    for (l = 0; l < $P_W; l++) ec[j * $P_W + l] = same[l] ? $P_E1[j] : c[l];\n  }\n"
          "  for (j = 0; j < $P_S; j++)\n    for (m = 0; m < $P_M; m++) {\n"
          "      $R a[$P_W], b[$P_W];\n"
          "      for (l = 0; l < $P_W; l++) a[l] = b[l] = 0;\n"
          "      for (i = 0; i < $P_S; i++)\n        for (l = 0; l < $P_W; l++) {\n"
          "          $R ei = ec[(j * $P_S + i) * $P_W + l], t = a[l] + ei * x->gam[(i * $P_M + m) * $P_W + l];\n"
          "          a[l] = ei != 0 ? t : a[l];\n        }\n"
          "      if (ref)\n        for (l = 0; l < $P_W; l++) ref[(j * $P_M + m) * $P_W + l] = a[l];\n");
  if (poly)
    tmpl(e, "      for (i = 0; i < $P_S; i++)\n        for (l = 0; l < $P_W; l++)\n"
            "          b[l] += $P_E2[2 * $P_S * j + i] * x->gam[(i * $P_M + m) * $P_W + l] +\n"
            "                  $P_E2[2 * $P_S * j + $P_S + i] * x->gam2[(i * $P_M + m) * $P_W + l];\n");
  tmpl(e, "      for (l = 0; l < $P_W; l++) {\n");
  tmpl(e, poly ? "        $R c = two[l] ? b[l] : a[l], g = j == 0 ? mp[m * $P_W + l] : 0;\n"
               : "        $R c = a[l], g = j == 0 ? mp[m * $P_W + l] : 0;\n");
  tmpl(e, "        gam[(j * $P_M + m) * $P_W + l] = cold[l] ? g : c;\n      }\n    }\n}\n\n");
}

// Whether the batch step calls kernel id: those of the step and its
// diagnostics (where the lanes take the scalar step, emit_batch_by_lane, only
// those of the observers); consistent only for the Newton step after an adaptive
// iteration stopped at its tolerance (itol_wanted). (The multiplier after a
// step comes from the sweep, or from project_p1's factors: no lambda0.)
static int batch_kernel_wanted(const Emitter *e, KernelId id) {
  if (!e->st->kern[id].nout) return 0;
  if (emit_batch_by_lane(e)) return id == K_ENERGY || id == K_G || id == K_HIDDEN; /* the observers' only */
  return id == K_CONSISTENT ? itol_wanted(e) : 1;
}

// The batch half of NAME.c: the kernels over lanes, then the functions.
void emit_batch_source(Emitter *e, int lanes) {
  static const KernelId used[] = {K_SWEEP, K_FACTOR, K_MINV_P, K_ENERGY, K_G, K_HIDDEN, K_PROJECT, K_CONSISTENT};
  e->lanes = lanes;
  tmpl(e, "\n/* ---- --batch: the kernels above as loops over $P_W lanes; value i of lane l is\n"
          " * at [i * $P_W + l]. Each lane does the scalar kernel's operations in its order. ---- */\n\n"
          "/* The sweep, the prediction, the tests and the kernels other than the factor, which\n"
          " * $P_batch_step and the tries of $P_batch_step_adaptive each call once, inlined into both\n"
          " * (gcc, clang) as a function called once would be: the fixed step keeps its code. */\n"
          "#if defined(__GNUC__)\n#define $P_LANE_INLINE static inline __attribute__((always_inline))\n"
          "#else\n#define $P_LANE_INLINE static\n#endif\n");
  for (size_t i = 0; i < sizeof used / sizeof used[0]; i++)
    if (batch_kernel_wanted(e, used[i])) emit_kernel(e, used[i]);
  out(e, "\n");
  emit_set_get(e);
  emit_params_observers(e);
  if (emit_batch_by_lane(e)) { /* the scalar step lane by lane: emit_batch_by_lane.c */
    emit_batch_by_lane_step(e);
    emit_batch_adaptive(e);
    e->lanes = 0;
    return;
  }
  emit_batch_predict(e);
  if (e->mod->mass_q) emit_batch_mq_predict(e); /* emit_batch_mq.c */
  emit_batch_step(e);
  e->lanes = 0;
}
