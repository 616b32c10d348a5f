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
 * same state. The sweep runs over all lanes while any of them iterates; a
 * lane that has stopped keeps its gamma, so the later sweeps repeat its last
 * one bitwise and the step ends with every lane's last sweep in sw[]. The
 * control between sweeps is loops over the lanes with selects, no per-lane
 * branch, which the compiler vectorises. A lane that fails is not written. */
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
  tmpl(e, "  unsigned char idle[$P_W];  /* nonzero: the lane is not stepped (cleared by $P_batch_set) */\n"
          "  /* private, per lane as in $P_state */\n"
          "  $P_real tc[$P_W], qc[$P_M * $P_W], pc[$P_M * $P_W], gam[$P_S * $P_M * $P_W], hprev[$P_W];\n"
          "  $P_real gam2[$P_S * $P_M * $P_W], hprev2[$P_W];\n"
          "  $P_real pinc[$P_S * $P_M * $P_W];\n");
  if (poly) tmpl(e, "  $P_real H0[$P_W], pcorr[$P_M * $P_W];\n");
  tmpl(e, "} $P_batch;\n\n"
          "typedef struct {\n"
          "  int code[$P_W];            /* the lane's return code, as $P_step's ($P_OK for idle lanes) */\n"
          "  int iters[$P_W];           /* fixed-point iterations (0: failed or idle before the first) */\n"
          "  $P_real increment[$P_W];  /* last scaled increment */\n"
          "} $P_batch_stats;\n\n"
          "/* Lane `lane` of x from / into a state; set also makes the lane active (idle 0). */\n"
          "void $P_batch_set($P_batch *x, int lane, const $P_state *s);\n"
          "void $P_batch_get(const $P_batch *x, int lane, $P_state *s);\n"
          "/* One step of size h on every active lane; prm: NULL (the defaults) or $P_W params, one\n"
          " * per lane; st may be NULL. Each lane is bitwise what $P_step would make of it; a lane\n"
          " * that fails is left unchanged. Returns the number of lanes that failed. */\n"
          "int $P_batch_step($P_batch *x, $P_real h, const $P_params *prm, $P_batch_stats *st);\n"
          "/* H (W values), g and the hidden constraints ($P_NU * $P_W values) of every lane. */\n"
          "void $P_batch_energy(const $P_batch *x, const $P_params *prm, $P_real *H);\n"
          "void $P_batch_constraints(const $P_batch *x, const $P_params *prm, $P_real *g);\n"
          "void $P_batch_hidden(const $P_batch *x, const $P_params *prm, $P_real *gp);\n\n");
}

// NAME_batch_set and NAME_batch_get: one lane to and from a NAME_state.
static void emit_set_get(Emitter *e) {
  static const char *const scalar[] = {"t", "tc", "hprev", "hprev2", "H0"}, *const array[][2] = {
      {"q", "$P_M"},   {"p", "$P_M"},   {"qc", "$P_M"}, {"pc", "$P_M"}, {"gam", "$P_S * $P_M"}, {"gam2", "$P_S * $P_M"},
      {"lambda", "$P_NU"}, {"pinc", "$P_S * $P_M"}, {"pcorr", "$P_M"}};
  int poly = e->st->kern[K_FACTOR].nout > 0;
  char line[160];
  for (int get = 0; get < 2; get++) {
    tmpl(e, get ? "void $P_batch_get(const $P_batch *x, int l, $P_state *s)\n{\n  int i;\n"
                : "void $P_batch_set($P_batch *x, int l, const $P_state *s)\n{\n  int i;\n");
    for (int f = 0; f < (poly ? 5 : 4); f++)
      out(e, get ? "  s->%s = x->%s[l];\n" : "  x->%s[l] = s->%s;\n", scalar[f], scalar[f]);
    for (int f = 0; f < (poly ? 9 : 8); f++) {
      const char *n = array[f][0];
      if (get) snprintf(line, sizeof line, "  for (i = 0; i < %s; i++) s->%s[i] = x->%s[i * $P_W + l];\n", array[f][1], n, n);
      else snprintf(line, sizeof line, "  for (i = 0; i < %s; i++) x->%s[i * $P_W + l] = s->%s[i];\n", array[f][1], n, n);
      tmpl(e, line);
    }
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

// $P_predict over the lanes with selects: every lane's one-step
// extrapolation (coefficients E1 when h is unchanged, else the polynomial in
// h / hprev), the polynomial family's two-step start, and the cold start
// (gamma_1 = M^-1 p) are all computed and the lane's own one chosen.
static void emit_predict(Emitter *e) {
  int poly = e->st->kern[K_FACTOR].nout > 0;
  tmpl(e, "static void $P_batch_predict(const $P_batch *restrict x, $R h, const $R *restrict par, $R *restrict gam)\n{\n"
          "  $R mp[$P_M * $P_W], r[$P_W], ec[$P_S * $P_S * $P_W];\n  $M cold[$P_W], two[$P_W], same[$P_W];\n"
          "  int i, j, l, m, d, all2 = $P_W > 0;\n"
          "  $(minv_p q0=x->q p0=x->p prm=par out=mp);\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    $R hp = x->hprev[l], hq = x->hprev2[l];\n"
          "    cold[l] = hp == 0;\n    same[l] = h == hp;\n    r[l] = h / (hp != 0 ? hp : 1);\n    (void)hq;\n");
  /* the polynomial family's two-step start, as $P_predict's */
  tmpl(e, poly ? "    two[l] = (hp != 0) & (h == hp) & (h == hq);\n  }\n" : "    two[l] = 0;\n  }\n");
  tmpl(e, ""
          "  for (l = 0; l < $P_W; l++) all2 &= (int)two[l];\n"
          "  if (!all2) /* the one-step coefficients, when a lane needs them */\n"
          "    for (j = 0; j < $P_S * $P_S; j++) {\n"
          "      $R c[$P_W];\n      for (l = 0; l < $P_W; l++) c[l] = 0;\n"
          "      for (d = $P_S - 1; d >= 0; d--)\n        for (l = 0; l < $P_W; l++) c[l] = c[l] * r[l] + $P_E[j * $P_S + d];\n"
          "      for (l = 0; l < $P_W; l++) ec[j * $P_W + l] = same[l] ? $P_E1[j] : c[l];\n    }\n"
          "  for (j = 0; j < $P_S; j++)\n    for (m = 0; m < $P_M; m++) {\n"
          "      $R a[$P_W], b[$P_W];\n"
          "      for (l = 0; l < $P_W; l++) a[l] = b[l] = 0;\n"
          "      for (i = 0; !all2 && i < $P_S; i++)\n        for (l = 0; l < $P_W; l++) {\n"
          "          $R ei = ec[(j * $P_S + i) * $P_W + l], t = a[l] + ei * x->gam[(i * $P_M + m) * $P_W + l];\n"
          "          a[l] = ei != 0 ? t : a[l];\n        }\n");
  if (poly)
    tmpl(e, "      for (i = 0; i < $P_S; i++)\n        for (l = 0; l < $P_W; l++)\n"
            "          b[l] += $P_E2[2 * $P_S * j + i] * x->gam[(i * $P_M + m) * $P_W + l] +\n"
            "                  $P_E2[2 * $P_S * j + $P_S + i] * x->gam2[(i * $P_M + m) * $P_W + l];\n");
  tmpl(e, "      for (l = 0; l < $P_W; l++) {\n");
  tmpl(e, poly ? "        $R c = two[l] ? b[l] : a[l];\n" : "        $R c = a[l];\n");
  tmpl(e, "        gam[(j * $P_M + m) * $P_W + l] = cold[l] ? (j == 0 ? mp[m * $P_W + l] : 0) : c;\n      }\n    }\n}\n\n");
}

// The iteration's tests after a sweep, as in $P_step, for every lane at
// once: loops over the lanes with selects (no per-lane branch, so they
// vectorise). act[l]: lane l iterates; a lane that stops gets rc[l] and
// iters[l] = it and keeps its gamma (and multiplier), so the sweeps that the
// other lanes still need recompute its last sweep bitwise. Returns the
// number of lanes that iterate on.
static void emit_lane_test(Emitter *e, int poly) {
  int nu = e->mod->nu;
  tmpl(e, "/* After a sweep: the increment and tests of $P_step in every lane that iterates (act);\n"
          " * a lane that stops gets rc, iters = it and keeps its gamma, so the next sweeps repeat\n"
          " * its last one. Returns the number of lanes that iterate on. */\n"
          "static int $P_batch_test(const $P_batch *restrict x, $R h, int it, const $R *restrict sw, $R *restrict gam,\n"
          "    $R *restrict lam, const $M *restrict act, $R *restrict inc, $R *restrict incp, $R *restrict inc_min,\n"
          "    int *restrict stall, int *restrict rc, int *restrict iters)\n{\n"
          "  $R scale[$P_W], incn[$P_W];\n"
          "  $M bad[$P_W], sing[$P_W], ok[$P_W], better[$P_W], noise[$P_W], run[$P_W];\n  int i, l, nrun = 0;\n  (void)lam;\n"
          "  for (l = 0; l < $P_W; l++) {\n    scale[l] = incn[l] = 0;\n    bad[l] = sing[l] = 0;\n  }\n"
          "  for (i = 0; i < $P_M; i++)\n    for (l = 0; l < $P_W; l++) {\n"
          "      $R v = fabs$f(x->q[i * $P_W + l]) + fabs$f(h * sw[($[sweep.gam]i) * $P_W + l]);\n"
          "      scale[l] = v > scale[l] ? v : scale[l];\n    }\n"
          "  for (i = 0; i < $P_S * $P_M; i++)\n    for (l = 0; l < $P_W; l++) {\n"
          "      $R v = fabs$f(h * (sw[($[sweep.gam]i) * $P_W + l] - gam[i * $P_W + l]));\n"
          "      incn[l] = v > incn[l] ? v : incn[l];\n    }\n");
  if (!poly && nu)
    tmpl(e, "  for (i = 0; i < $P_NU; i++)\n    for (l = 0; l < $P_W; l++) {\n"
            "      $R piv = sw[($[sweep.pivot]i) * $P_W + l], dia = sw[($[sweep.adiag]i) * $P_W + l];\n"
            "      sing[l] |= isfinite(piv) & isfinite(dia) & ((fabs$f(piv) > $P_SINGTOL * fabs$f(dia)) == 0);\n    }\n");
  tmpl(e, poly ? "  for (i = 0; i < $<sweep.theta>; i++)\n" : "  for (i = 0; i < $<sweep.pivot>; i++)\n");
  /* the floating-point tests in a loop of their own, the integer logic in a second: a
   * comparison the compiler could sink under a condition would be a branch (it may trap) */
  tmpl(e, "    for (l = 0; l < $P_W; l++) bad[l] |= !isfinite(sw[i * $P_W + l]);\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    $R s = scale[l] > 0 ? scale[l] : 1, in = incn[l] / s, old = inc[l];\n"
          "    bad[l] |= !isfinite(in);\n");
  tmpl(e, poly ? "    ok[l] = in <= $P_TOL;\n" : "    ok[l] = (in <= $P_TOL / 256) | ((in <= $P_TOL) & (4 * in > old));\n");
  tmpl(e, "    better[l] = in < inc_min[l];\n    noise[l] = inc_min[l] <= $P_NOISETOL;\n"
          "    incp[l] = act[l] ? old : incp[l];\n    inc[l] = act[l] ? in : old;\n"
          "    inc_min[l] = act[l] & better[l] ? in : inc_min[l];\n  }\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    int stl = better[l] ? 0 : stall[l] + 1;\n    $M a = act[l], okl = (bad[l] == 0) & ok[l];\n"
          "    $M stop = sing[l] | bad[l] | okl | (stl >= $P_STALL);\n"
          "    int code = sing[l] ? $P_ESINGULAR : bad[l] ? $P_ENONFINITE : okl | noise[l] ? $P_OK : $P_ENOCONV;\n"
          "    stall[l] = a ? stl : stall[l];\n    rc[l] = a & stop ? code : rc[l];\n"
          "    iters[l] = a & stop ? it : iters[l];\n    run[l] = a & (stop == 0);\n    nrun += (int)run[l];\n  }\n"
          "  for (i = 0; i < $P_S * $P_M; i++)\n    for (l = 0; l < $P_W; l++) {\n"
          "      $R s = sw[($[sweep.gam]i) * $P_W + l], g = gam[i * $P_W + l];\n      gam[i * $P_W + l] = run[l] ? s : g;\n    }\n");
  if (poly)
    tmpl(e, "  for (i = 0; i < $P_S * $P_NU; i++)\n    for (l = 0; l < $P_W; l++) {\n"
            "      $R s = sw[($[sweep.lam]i) * $P_W + l], g = lam[i * $P_W + l];\n      lam[i * $P_W + l] = run[l] ? s : g;\n    }\n");
  tmpl(e, "  return nrun;\n}\n\n");
}

// The end of the step for the lanes whose iteration converged (go[l]):
// the constant family's update, or the polynomial family's projection,
// rescale and multiplier (emit_end_poly in emit_step.c), lane by lane.
static void emit_commit(Emitter *e, int poly) {
  if (!poly) {
    tmpl(e, "  for (l = 0; l < $P_W; l++) {\n    if (!go[l]) continue;\n"
            "    for (i = 0; i < $P_M; i++)\n"
            "      if (!isfinite(x->q[i * $P_W + l] + h * sw[($[sweep.gam]i) * $P_W + l]) ||\n"
            "          !isfinite(x->p[i * $P_W + l] + sw[($[sweep.dp]i) * $P_W + l]) ||\n"
            "          !isfinite(x->qc[i * $P_W + l]) || !isfinite(x->pc[i * $P_W + l]))\n"
            "        rc[l] = $P_ENONFINITE;\n"
            "    if (rc[l] != $P_OK) continue;\n"
            "    for (i = 0; i < $P_M; i++) {\n"
            "      $P_add(&x->q[i * $P_W + l], &x->qc[i * $P_W + l], h * sw[($[sweep.gam]i) * $P_W + l]);\n"
            "      $P_add(&x->p[i * $P_W + l], &x->pc[i * $P_W + l], sw[($[sweep.dp]i) * $P_W + l]);\n    }\n"
            "    for (i = 0; i < $P_NU; i++) x->lambda[i * $P_W + l] = sw[($[sweep.lambda]i) * $P_W + l];\n"
            "    for (i = 0; i < $P_S * $P_M; i++) {\n      x->gam2[i * $P_W + l] = x->gam[i * $P_W + l];\n      x->gam[i * $P_W + l] = sw[($[sweep.gam]i) * $P_W + l];\n    }\n"
            "    for (i = 0; i < $P_M; i++) x->pinc[i * $P_W + l] = sw[($[sweep.dp]i) * $P_W + l];\n"
            "    for (i = 0; i < ($P_S - 1) * $P_M; i++)\n"
            "      x->pinc[($P_M + i) * $P_W + l] = sw[($[sweep.theta]i) * $P_W + l];\n"
            "    $P_add(&x->t[l], &x->tc[l], h);\n    x->hprev2[l] = x->hprev[l];\n    x->hprev[l] = h;\n  }\n");
    return;
  }
  tmpl(e, "  {\n"
          "    $R q1[$P_M * $P_W], p1[$P_M * $P_W], qc1[$P_M * $P_W], pc1[$P_M * $P_W];\n"
          "    $R pr[($<project_p1> + 1) * $P_W], Hn[$P_W], lam0[$P_NU * $P_W], pco[$P_M * $P_W];\n"
          "    $(energy_kernel q0=x->q p0=x->p prm=par out=Hn);\n"
          "    for (i = 0; i < $P_M * $P_W; i++) {\n"
          "      q1[i] = x->q[i];\n      qc1[i] = x->qc[i];\n      p1[i] = x->p[i];\n      pc1[i] = x->pc[i];\n    }\n"
          "    for (l = 0; l < $P_W; l++)\n      for (i = 0; go[l] && i < $P_M; i++) {\n"
          "        $P_add(&q1[i * $P_W + l], &qc1[i * $P_W + l], h * sw[($[sweep.gam]i) * $P_W + l]);\n"
          "        $P_add(&p1[i * $P_W + l], &pc1[i * $P_W + l], sw[($[sweep.dp]i) * $P_W + l]);\n      }\n"
          "    $(project_p1 q0=q1 p0=p1 prm=par out=pr);\n"
          "    for (l = 0; l < $P_W; l++) {\n"
          "      $R K, U1, H0, beta = 1;\n      if (!go[l]) continue;\n"
          "      for (i = 0; i < $P_NU; i++) {\n"
          "        $R piv = pr[($[project_p1.pivot]i) * $P_W + l], dia = pr[($[project_p1.adiag]i) * $P_W + l];\n"
          "        if (isfinite(piv) && isfinite(dia) && !(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) rc[l] = $P_ESINGULAR;\n"
          "      }\n"
          "      for (i = 0; rc[l] == $P_OK && i < $<project_p1>; i++)\n"
          "        if (!isfinite(pr[i * $P_W + l])) rc[l] = $P_ENONFINITE;\n"
          "      if (rc[l] != $P_OK) continue;\n"
          "      K = pr[($[project_p1.kin]0) * $P_W + l];\n      U1 = pr[($[project_p1.U]0) * $P_W + l];\n"
          "      H0 = x->hprev[l] != 0 && fabs$f(Hn[l] - x->H0[l]) <= 64 * $P_TOL * (K + fabs$f(U1)) ? x->H0[l] : Hn[l];\n"
          "      if (K > 0 && H0 - U1 > 0) beta = sqrt$f((H0 - U1) / K);\n"
          "      for (i = 0; i < $P_M; i++) {\n"
          "        $R d = pr[($[project_p1.dp]i) * $P_W + l], ph = p1[i * $P_W + l];\n"
          "        $P_add(&p1[i * $P_W + l], &pc1[i * $P_W + l], d + (beta - 1) * (p1[i * $P_W + l] + d));\n"
          "        pco[i * $P_W + l] = p1[i * $P_W + l] - ph;\n"
          "        if (!isfinite(q1[i * $P_W + l]) || !isfinite(p1[i * $P_W + l])) rc[l] = $P_ENONFINITE;\n"
          "      }\n"
          "      if (rc[l] != $P_OK) continue;\n"
          "      for (i = 0; i < $P_M; i++) {\n"
          "        x->q[i * $P_W + l] = q1[i * $P_W + l];\n        x->p[i * $P_W + l] = p1[i * $P_W + l];\n"
          "        x->qc[i * $P_W + l] = qc1[i * $P_W + l];\n        x->pc[i * $P_W + l] = pc1[i * $P_W + l];\n"
          "        x->pcorr[i * $P_W + l] = pco[i * $P_W + l];\n      }\n"
          "      for (i = 0; i < $P_S * $P_M; i++) {\n        x->gam2[i * $P_W + l] = x->gam[i * $P_W + l];\n        x->gam[i * $P_W + l] = sw[($[sweep.gam]i) * $P_W + l];\n      }\n"
          "      for (i = 0; i < $P_M; i++) x->pinc[i * $P_W + l] = sw[($[sweep.dp]i) * $P_W + l];\n"
          "      for (i = 0; i < ($P_S - 1) * $P_M; i++)\n"
          "        x->pinc[($P_M + i) * $P_W + l] = sw[($[sweep.theta]i) * $P_W + l];\n"
          "      x->H0[l] = H0;\n    }\n"
          "    /* the multiplier consistent with the new (q, p), for the lanes that moved */\n"
          "    $(lambda0 q0=x->q p0=x->p prm=par out=lam0);\n"
          "    for (l = 0; l < $P_W; l++) {\n      if (!go[l] || rc[l] != $P_OK) continue;\n"
          "      for (i = 0; i < $P_NU; i++)\n"
          "        x->lambda[i * $P_W + l] = isfinite(lam0[i * $P_W + l]) ? lam0[i * $P_W + l] : 0;\n"
          "      $P_add(&x->t[l], &x->tc[l], h);\n      x->hprev2[l] = x->hprev[l];\n      x->hprev[l] = h;\n    }\n  }\n");
}

// NAME_batch_step.
static void emit_batch_step(Emitter *e) {
  int poly = e->st->kern[K_FACTOR].nout > 0, nu = e->mod->nu;
  emit_lane_test(e, poly);
  tmpl(e, "int $P_batch_step($P_batch *x, $P_real h_, const $P_params *prm, $P_batch_stats *st)\n{\n"
          "  const $R h = ($R)h_;\n"
          "  $R par[($P_NPARAMS + 1) * $P_W], gam[$P_S * $P_M * $P_W];\n"
          "  $R sw[($<sweep> + 1) * $P_W];\n"
          "  $R inc[$P_W], incp[$P_W], inc_min[$P_W], lam[($P_S * $P_NU + 1) * $P_W];\n"
          "  int rc[$P_W], go[$P_W], stall[$P_W], iters[$P_W];\n  $M act[$P_W];\n"
          "  int it, i, l, nrun = 0, nfail = 0;\n"
          "  $P_batch_params(prm, par);\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    inc[l] = incp[l] = inc_min[l] = HUGE_VAL;\n    stall[l] = iters[l] = 0;\n"
          "    rc[l] = x->idle[l] ? $P_OK : !(h != 0 && isfinite(h)) ? $P_EBADSTEP : $P_ENOCONV;\n"
          "    go[l] = rc[l] == $P_ENOCONV;  /* first: the lane iterates */\n  }\n"
          "  for (i = 0; i < ($<sweep> + 1) * $P_W; i++) sw[i] = 0;\n"
          "  for (i = 0; i < ($P_S * $P_NU + 1) * $P_W; i++) lam[i] = 0;\n"
          "  $P_batch_predict(x, h, par, gam);\n");
  if (nu)
    tmpl(e, "  $R g0[$P_NU * $P_W];\n  $(g q0=x->q p0=x->p prm=par out=g0);\n"
            "  for (i = 0; i < $P_NU * $P_W; i++) g0[i] = fabs$f(g0[i]) <= $P_GTOL ? 0 : g0[i] / h;\n");
  if (poly)
    tmpl(e, "  $R fa[($<factor> + 1) * $P_W];\n"
            "  $(factor q0=x->q gam=gam h=h prm=par out=fa);\n"
            "  for (l = 0; l < $P_W; l++)\n    for (i = 0; go[l] && i < $P_S * $P_NU; i++) {\n"
            "      $R piv = fa[($[factor.pivot]i) * $P_W + l], dia = fa[($[factor.adiag]i) * $P_W + l];\n"
            "      if (!isfinite(piv) || !isfinite(dia)) rc[l] = $P_ENONFINITE;\n"
            "      else if (!(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) rc[l] = $P_ESINGULAR;\n"
            "      go[l] = rc[l] == $P_ENOCONV;\n    }\n");
  char call[160];
  snprintf(call, sizeof call, "    $(sweep q0=x->q p0=x->p gam=gam h=h%s%s prm=par out=sw);\n", nu ? " g0=g0" : "",
           poly ? " lam=lam lu=fa" : "");
  tmpl(e, "  for (l = 0; l < $P_W; l++) nrun += go[l];\n"
          "  /* the sweep over all lanes while any iterates; a lane that stops keeps its last sweep */\n"
          "  for (it = 1; it <= $P_MAXITER && nrun > 0; it++) {\n");
  if (poly) /* $P_step's refresh of the frozen factor, for the lanes that slow down */
    tmpl(e, "    if (it > 2) {\n"
            "      $R fb[($<factor> + 1) * $P_W];\n      int any = 0, fresh[$P_W];\n"
            "      for (l = 0; l < $P_W; l++) any |= fresh[l] = go[l] && !iters[l] && inc[l] > incp[l] / 8;\n"
            "      if (any) {\n"
            "        $(factor q0=x->q gam=gam h=h prm=par out=fb);\n"
            "        for (l = 0; l < $P_W; l++) {\n          if (!fresh[l]) continue;\n"
            "          for (i = 0; i < $<factor>; i++) fa[i * $P_W + l] = fb[i * $P_W + l];\n"
            "          for (i = 0; i < $P_S * $P_NU; i++) {\n"
            "            $R piv = fa[($[factor.pivot]i) * $P_W + l], dia = fa[($[factor.adiag]i) * $P_W + l];\n"
            "            if (!isfinite(piv) || !isfinite(dia)) rc[l] = $P_ENONFINITE;\n"
            "            else if (!(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) rc[l] = $P_ESINGULAR;\n          }\n"
            "          if (rc[l] != $P_ENOCONV) {  /* the lane stops here, failed */\n"
            "            iters[l] = it;\n            nrun--;\n          }\n"
            "        }\n      }\n    }\n");
  tmpl(e, call);
  tmpl(e, "    for (l = 0; l < $P_W; l++) act[l] = go[l] && !iters[l];\n"
          "    nrun = $P_batch_test(x, h, it, sw, gam, lam, act, inc, incp, inc_min, stall, rc, iters);\n  }\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    if (go[l] && !iters[l]) iters[l] = $P_MAXITER;  /* did not converge: rc[l] is $P_ENOCONV */\n"
          "    go[l] = go[l] && rc[l] == $P_OK;  /* now: the lane is committed */\n"
          "    if (go[l] && (!isfinite(x->t[l] + h) || !isfinite(x->tc[l]))) {\n"
          "      rc[l] = $P_ENONFINITE;\n      go[l] = 0;\n    }\n  }\n");
  emit_commit(e, poly);
  tmpl(e, "  for (l = 0; l < $P_W; l++) {\n"
          "    nfail += rc[l] != $P_OK;\n"
          "    if (!st) continue;\n"
          "    st->code[l] = rc[l];\n    st->iters[l] = iters[l];\n    st->increment[l] = iters[l] ? inc[l] : 0;\n"
          "  }\n  return nfail;\n}\n");
}

// The batch half of NAME.c: the kernels over lanes, then the functions.
void emit_batch_source(Emitter *e, int lanes) {
  static const KernelId used[] = {K_SWEEP, K_FACTOR, K_MINV_P, K_ENERGY, K_G, K_HIDDEN, K_PROJECT, K_LAMBDA0};
  int poly = e->st->kern[K_FACTOR].nout > 0; /* lambda0: only the polynomial family's step needs it */
  e->lanes = lanes;
  tmpl(e, "\n/* ---- --batch: the kernels above as loops over $P_W lanes; value i of lane l is\n"
          " * at [i * $P_W + l]. Each lane does the scalar kernel's operations in its order. ---- */\n");
  for (size_t i = 0; i < sizeof used / sizeof used[0]; i++)
    if (e->st->kern[used[i]].nout && (poly || used[i] != K_LAMBDA0)) emit_kernel(e, used[i]);
  out(e, "\n");
  emit_set_get(e);
  emit_params_observers(e);
  emit_predict(e);
  emit_batch_step(e);
  e->lanes = 0;
}
