/* emit_batch_step.c - --batch W: NAME_batch_step, the control around the
 * lane kernels (emit_batch.c prints those and the rest of the batch API).
 *
 * NAME_batch_step runs the scalar step's algorithm (emit_step.c) in every
 * lane: the same prediction, the same sweeps until the lane's own increment
 * is at round-off, the same tests and the same compensated update, so each
 * lane is bitwise the scalar NAME_step from the same state. The sweep runs
 * over all lanes while any of them iterates; a lane that has stopped keeps
 * its gamma, so the later sweeps repeat its last one bitwise and the step
 * ends with every lane's last sweep in sw[]. All control between the kernels
 * is loops over the lanes with selects and masks as wide as the real type
 * ($M), no per-lane branch, which the compiler vectorises; only "does any
 * lane still iterate" is a branch. A lane that fails is not written. */
#include "emit.h"

// The factor's pivot tests of $P_step for the lanes in sel whose rc is still
// ENOCONV: the first pivot that is not finite or is small sets rc.
static void emit_pivots(Emitter *e) {
  tmpl(e, "/* The multiplier factor's pivot tests of $P_step, in the lanes of sel still iterating. */\n"
          "static void $P_batch_pivots(const $R *restrict fa, const $M *restrict sel, $M *restrict rc)\n{\n"
          "  $M bad[$P_W], any = 0;\n  int i, l;\n"
          "  /* first whether any pivot of any lane fails: mostly none, and then no more (a mask\n"
          "   * a lane, and one test of them at the end: no reduction across the lanes a pivot) */\n"
          "  for (l = 0; l < $P_W; l++) bad[l] = 0;\n"
          "  for (i = 0; i < $P_S * $P_NU; i++)\n    for (l = 0; l < $P_W; l++) {\n"
          "      $R piv = fa[($[factor.pivot]i) * $P_W + l], dia = fa[($[factor.adiag]i) * $P_W + l];\n"
          "      bad[l] |= !isfinite(piv) | !isfinite(dia) | ((fabs$f(piv) > $P_SINGTOL * fabs$f(dia)) == 0);\n    }\n"
          "  for (l = 0; l < $P_W; l++) any |= bad[l];\n"
          "  if (!any) return;\n"
          "  for (i = 0; i < $P_S * $P_NU; i++)\n    for (l = 0; l < $P_W; l++) {\n"
          "      $R piv = fa[($[factor.pivot]i) * $P_W + l], dia = fa[($[factor.adiag]i) * $P_W + l];\n"
          "      $M nf = !isfinite(piv) | !isfinite(dia), sg = (fabs$f(piv) > $P_SINGTOL * fabs$f(dia)) == 0;\n"
          "      $M code = nf ? $P_ENONFINITE : sg ? $P_ESINGULAR : $P_ENOCONV;\n"
          "      rc[l] = (sel[l] & (rc[l] == $P_ENOCONV)) ? code : rc[l];\n    }\n}\n\n");
}

// The iteration's tests after a sweep, as in $P_step, for every lane at
// once. The sweep read gam (and lam) and wrote sw, whose gamma (and
// multiplier) the next sweep reads: no copy while every lane iterates on.
// act[l]: lane l iterates (on return: in the next sweep; 0 or 1); a lane
// that stops gets rc[l] and iters[l] = it (iters counts its sweeps), and
// while other lanes iterate on (a next sweep follows), sw gets its gamma
// (and multiplier) back from gam (lam), so
// the sweeps that the other lanes still need recompute its last sweep
// bitwise and the last sweep leaves every lane's own results in sw (ngo:
// the number of lanes that iterate in this step, so that the common case,
// every one of them still iterating, is one comparison). The floating-point
// tests are in a loop of their own and the integer logic in a second, with
// & and | for && and ||: a comparison the compiler could sink under a
// condition would stay a branch (it may trap), and the loop scalar. The
// polynomial family's fresh[l] (whether any, in *nfresh): lane
// l iterates on with increments that fell by less than 8x, so its factor is
// refreshed before the next sweep, as in $P_step.
// In the lane test, NAME_settled's test (noise_per_coordinate, gen/emit_iterate.c)
// into settled[l], in the lanes whose increment falls by less than 4x (1 in
// the others): each coordinate's largest increment and its
// size over the step from sw and gam, summed in NAME_step's order.
static void emit_lane_settled(Emitter *e) {
  tmpl(e, "  $M settled[$P_W], cand = 0;\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    $R s = scale[l] > 0 ? scale[l] : 1, in = incn[l] / s;\n"
          "    cand |= (in > $P_TOL / 256) & (4 * in > inc[l]);\n"
          "    settled[l] = 1;\n  }\n"
          "  if (cand)  /* each coordinate: its largest increment d, its size over the step o */\n"
          "    for (int c = 0; c < $P_M; c++)\n      for (l = 0; l < $P_W; l++) {\n"
          "        $R o = fabs$f(x->q[c * $P_W + l]) + fabs$f(h * sw[($[sweep.gam]c) * $P_W + l]);\n"
          "        $R d = fabs$f(h * (sw[($[sweep.gam]c) * $P_W + l] - gam[c * $P_W + l]));\n"
          "        for (i = $P_M + c; i < $P_S * $P_M; i += $P_M) {\n"
          "          $R v = fabs$f(h * (sw[($[sweep.gam]i) * $P_W + l] - gam[i * $P_W + l]));\n"
          "          o += fabs$f(h * sw[($[sweep.gam]i) * $P_W + l]);\n"
          "          d = v > d ? v : d;\n        }\n"
          "        settled[l] &= (d <= $P_TOL * o) | (d <= $P_TOL / 256 * scale[l]);\n      }\n");
}

static void emit_lane_test(Emitter *e, int poly) {
  int mq = e->mod->mass_q != NULL; /* M(q): Theta in lam, the contraction test (emit_batch_mq.c) */
  tmpl(e, "/* After a sweep: the increment and tests of $P_step in every lane that iterates (act);\n"
          " * a lane that stops gets rc, iters = it and keeps its gamma, so the next sweeps repeat\n"
          " * its last one. Returns the number of lanes that iterate on. */\n"
          "$P_LANE_INLINE int $P_batch_test(const $P_batch *restrict x, $R h, int it, $R *restrict sw, const $R *restrict gam,\n"
          "    const $R *restrict lam, const $M *restrict go, $M *restrict act, $R *restrict inc, $R *restrict incp,\n"
          "    $R *restrict inc_min, $M *restrict stall, $M *restrict rc, $M *restrict iters");
  tmpl(e, poly ? ",\n    $R *restrict rho, $M *restrict fresh, int *restrict nfresh, int ngo" : ", int ngo");
  tmpl(e, itol_wanted(e) ? ", $R tol, $R *restrict itl)\n{\n" : ")\n{\n");
  if (!poly && !mq) tmpl(e, "  (void)incp;  /* for the refresh of a factor, which this family has not */\n");
  tmpl(e, "  $R scale[$P_W], incn[$P_W], nan[$P_W];\n"
          "  $M bad[$P_W], sing[$P_W], ok[$P_W], better[$P_W], noise[$P_W], run[$P_W], nr = 0;  /* nr: a wide sum */\n"
          "  int i, l, nrun;\n  (void)lam;\n"
          "  for (l = 0; l < $P_W; l++) bad[l] = sing[l] = 0;\n");
  /* a result is not finite where r - r is not 0 (inf - inf and NaN are NaN): their sum
   * over the results is one test a lane, in a loop the compiler vectorises */
  if (sweep_reduces(e)) /* the sweep took the three while its results were at hand */
    tmpl(e, "  (void)x;\n  (void)h;\n"
            "  for (l = 0; l < $P_W; l++) {\n    scale[l] = sw[($<sweep>) * $P_W + l];\n"
            "    incn[l] = sw[($<sweep> + 1) * $P_W + l];\n    nan[l] = sw[($<sweep> + 2) * $P_W + l];\n  }\n");
  else {
    tmpl(e, "  for (l = 0; l < $P_W; l++) scale[l] = incn[l] = nan[l] = 0;\n"
            "  for (i = 0; i < $P_M; i++)\n    for (l = 0; l < $P_W; l++) {\n"
            "      $R v = fabs$f(x->q[i * $P_W + l]) + fabs$f(h * sw[($[sweep.gam]i) * $P_W + l]);\n"
            "      scale[l] = v > scale[l] ? v : scale[l];\n    }\n"
            "  for (i = 0; i < $P_S * $P_M; i++)\n    for (l = 0; l < $P_W; l++) {  /* |h| max |d|: max |h d| (emit_lane_reductions) */\n"
            "      $R v = fabs$f(sw[($[sweep.gam]i) * $P_W + l] - gam[i * $P_W + l]);\n"
            "      incn[l] = v > incn[l] ? v : incn[l];\n    }\n"
            "  for (l = 0; l < $P_W; l++) incn[l] = fabs$f(h) * incn[l];\n");
    tmpl(e, poly ? "  for (i = 0; i < $<sweep.theta>; i++)\n" : "  for (i = 0; i < $<sweep.pivot>; i++)\n");
    tmpl(e, "    for (l = 0; l < $P_W; l++) nan[l] += sw[i * $P_W + l] - sw[i * $P_W + l];\n");
  }
  if (!poly && e->mod->nu)
    tmpl(e, "  for (i = 0; i < $P_NU; i++)\n    for (l = 0; l < $P_W; l++) {\n"
            "      $R piv = sw[($[sweep.pivot]i) * $P_W + l], dia = sw[($[sweep.adiag]i) * $P_W + l];\n"
            "      sing[l] |= isfinite(piv) & isfinite(dia) & ((fabs$f(piv) > $P_SINGTOL * fabs$f(dia)) == 0);\n    }\n");
  if (mq) emit_batch_mq_increment(e); /* emit_batch_mq.c */
  if (itol_wanted(e)) /* where $P_step_within stops: at its tolerance under $P_batch_step_adaptive */
    tmpl(e, "  if (itl && it == 1)  /* once a step, at the first sweep's scale (a loop of its own: a division) */\n"
            "    for (l = 0; l < $P_W; l++) itl[l] = $P_itol(tol, scale[l]);\n");
  if (noise_per_coordinate(e)) emit_lane_settled(e); /* (never poly or M(q)) */
  tmpl(e, "  for (l = 0; l < $P_W; l++) {\n"
          "    $R s = scale[l] > 0 ? scale[l] : 1, in = incn[l] / s, old = inc[l];\n");
  if (mq) tmpl(e, "    in = thi[l] > in ? thi[l] : in;  /* M(q): Theta's increment joins gamma's */\n");
  tmpl(e, "    bad[l] |= (nan[l] != 0) | !isfinite(in);\n");
  if (itol_wanted(e))
    tmpl(e, "    $R ti = itl ? itl[l] : $P_TOL;  /* the fixed step passes none: its test is $P_TOL's */\n"
            "    $R rh = $P_contraction(in, old, incp[l], it);\n"
            "    ok[l] = (in <= ti) | ((rh < 1) & (in * rh <= ti * (1 - rh)));  /* $P_converged, as masks */\n");
  else
    tmpl(e, poly || mq ? "    $R rh = $P_contraction(in, old, incp[l], it);\n"
                   "    ok[l] = (in <= $P_TOL) | ((rh < 1) & (in * rh <= $P_TOL * (1 - rh)));\n"
                 : noise_per_coordinate(e) ? "    ok[l] = (in <= $P_TOL / 256) | ((4 * in > old) & settled[l]);\n"
                                           : "    ok[l] = (in <= $P_TOL / 256) | ((in <= $P_TOL) & (4 * in > old));\n");
  tmpl(e, "    better[l] = in < inc_min[l];\n    noise[l] = inc_min[l] <= $P_NOISETOL;\n");
  if (poly)
    tmpl(e, "    incp[l] = act[l] ? old : incp[l];  /* for the factor's refresh (fresh) */\n"
            "    rho[l] = act[l] ? rh : rho[l];  /* for the test of the lanes' Newton steps */\n");
  else if (mq) tmpl(e, "    incp[l] = act[l] ? old : incp[l];  /* the increment before the last ($P_contraction) */\n");
  tmpl(e, "    inc[l] = act[l] ? in : old;\n"
          "    inc_min[l] = (act[l] & better[l]) ? in : inc_min[l];\n  }\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    $M stl = better[l] ? 0 : stall[l] + 1;\n    $M a = act[l], okl = (bad[l] == 0) & ok[l];\n"
          "    $M stop = sing[l] | bad[l] | okl | (stl >= $P_STALL);\n"
          "    $M code = sing[l] ? $P_ESINGULAR : bad[l] ? $P_ENONFINITE : (okl | noise[l]) ? $P_OK : $P_ENOCONV;\n"
          "    $M as = -(a & stop);  /* all ones or zero: the writes as blends, which vectorise */\n"
          "    stall[l] ^= (stall[l] ^ stl) & -a;\n    rc[l] ^= (rc[l] ^ code) & as;\n"
          "    iters[l] += a;  /* the sweeps it iterated: it, when it stops now */\n    run[l] = a & (stop == 0);\n  }\n"
          "  for (l = 0; l < $P_W; l++) {\n    nr += run[l];\n    act[l] = run[l];\n  }\n  nrun = (int)nr;\n");
  if (poly) /* read from the third sweep on */
    tmpl(e, "  *nfresh = 0;\n  if (nrun > 0 && it >= 2) {\n    $M any = 0;\n"
            "    for (l = 0; l < $P_W; l++) any |= fresh[l] = run[l] & (inc[l] > incp[l] / 8);\n"
            "    *nfresh = (int)any;\n  }\n");
  if (e->roll) { /* the rolled sweep copies a stopped lane's results (skip): nothing to restore */
    tmpl(e, "  (void)go;\n  (void)ngo;\n  (void)it;\n  return nrun;\n}\n\n");
    return;
  }
  tmpl(e, "  if (nrun > 0 && nrun < ngo && it < $P_MAXITER) {  /* the lanes that stopped keep their gamma for the next sweeps */\n"
          "    $M keep[$P_W], any = 0;\n"
          "    for (l = 0; l < $P_W; l++) any |= keep[l] = go[l] & (run[l] == 0);\n"
          "    if (any) {\n"
          "      for (i = 0; i < $P_S * $P_M; i++)\n        for (l = 0; l < $P_W; l++) {\n"
          "          $R s = sw[($[sweep.gam]i) * $P_W + l], g = gam[i * $P_W + l];\n"
          "          sw[($[sweep.gam]i) * $P_W + l] = keep[l] ? g : s;\n        }\n");
  if (poly)
    tmpl(e, "      for (i = 0; i < $P_S * $P_NU; i++)\n        for (l = 0; l < $P_W; l++) {\n"
            "          $R s = sw[($[sweep.lam]i) * $P_W + l], g = lam[i * $P_W + l];\n"
            "          sw[($[sweep.lam]i) * $P_W + l] = keep[l] ? g : s;\n        }\n");
  if (mq) emit_batch_mq_keep(e); /* emit_batch_mq.c */
  tmpl(e, "    }\n  }\n  return nrun;\n}\n\n");
}

// The writes both families make in a lane that commits (cm[l]): the history
// of gamma, p's polynomial for NAME_dense, t and the previous steps.
static void emit_commit_common(Emitter *e) {
  tmpl(e, "    $M all = 1;  /* mostly every lane commits: then plain copies, which vectorise */\n"
          "    for (l = 0; l < $P_W; l++) all &= cm[l];\n"
          "    if (all) {\n      for (i = 0; i < $P_S * $P_M * $P_W; i++) {\n"
          "        x->gam2[i] = x->gam[i];\n        x->gam[i] = sw[($[sweep.gam]0) * $P_W + i];\n      }\n"
          "      for (i = 0; i < $P_M * $P_W; i++) x->pinc[i] = sw[($[sweep.dp]0) * $P_W + i];\n"
          "      for (i = 0; i < ($P_S - 1) * $P_M * $P_W; i++) x->pinc[$P_M * $P_W + i] = sw[($[sweep.theta]0) * $P_W + i];\n"
          "    } else {\n"
          "    for (i = 0; i < $P_S * $P_M; i++)\n      for (l = 0; l < $P_W; l++) {\n"
          "        $R g = x->gam[i * $P_W + l], n = sw[($[sweep.gam]i) * $P_W + l];\n"
          "        x->gam2[i * $P_W + l] = cm[l] ? g : x->gam2[i * $P_W + l];\n        x->gam[i * $P_W + l] = cm[l] ? n : g;\n      }\n"
          "    for (i = 0; i < $P_M; i++)\n      for (l = 0; l < $P_W; l++)\n"
          "        x->pinc[i * $P_W + l] = cm[l] ? sw[($[sweep.dp]i) * $P_W + l] : x->pinc[i * $P_W + l];\n"
          "    for (i = 0; i < ($P_S - 1) * $P_M; i++)\n      for (l = 0; l < $P_W; l++)\n"
          "        x->pinc[($P_M + i) * $P_W + l] = cm[l] ? sw[($[sweep.theta]i) * $P_W + l] : x->pinc[($P_M + i) * $P_W + l];\n"
          "    }\n"
          "    for (l = 0; l < $P_W; l++) {\n"
          "      $R t = x->t[l], tc = x->tc[l], hp = x->hprev[l];\n      $P_add(&t, &tc, h);\n"
          "      x->t[l] = cm[l] ? t : x->t[l];\n      x->tc[l] = cm[l] ? tc : x->tc[l];\n"
          "      x->hprev2[l] = cm[l] ? hp : x->hprev2[l];\n      x->hprev[l] = cm[l] ? h : hp;\n    }\n  }\n");
}

// In NAME_batch_within, before the projection: the Newton steps of
// emit_end_poly (emit_end.c) onto g = 0 in the lanes whose iteration
// stopped at the tolerance above round-off (the test of NAME_step_within on
// its last increments: it met the tolerance's, not round-off's), each while
// its g(q1) is not at round-off, at most NAME_NEWTON; a failure's code nc[l]
// goes before the projection's, as the scalar step returns it first.
static void emit_lane_newton(Emitter *e) {
  tmpl(e, "    $M nc[$P_W];  /* the Newton steps' code, before the projection's */\n"
          "    {  /* the lanes whose iteration stopped at the tolerance: q1 onto g = 0 ($P_step_within) */\n"
          "      $R g1[$P_NU * $P_W], cs[($<consistent>) * $P_W];\n      $M ea[$P_W], off[$P_W], any = 0;\n      int n;\n"
          "      for (l = 0; l < $P_W; l++) {  /* the test on the last increment (inc) and contraction (rho) */\n"
          "        $R in = inc[l], rh = rho[l];  /* $P_converged at itl and at $P_TOL, as masks */\n"
          "        $M at = (in <= itl[l]) | ((rh < 1) & (in * rh <= itl[l] * (1 - rh)));\n"
          "        $M round = (in <= $P_TOL) | ((rh < 1) & (in * rh <= $P_TOL * (1 - rh)));\n"
          "        nc[l] = $P_OK;\n        ea[l] = go[l] & at & (round == 0);\n        any |= ea[l];\n      }\n"
          "      for (n = 0; n < $P_NEWTON && any; n++) {\n"
          "        $(g q0=q1 prm=par out=g1);\n"
          "        for (l = 0; l < $P_W; l++) off[l] = 0;\n"
          "        for (i = 0; i < $P_NU; i++)\n");
  tmpl(e, e->single ? "          for (l = 0; l < $P_W; l++) off[l] |= !(fabs$f(g1[i * $P_W + l]) <= $P_gtol(q1 + l, $P_W));\n"
                    : "          for (l = 0; l < $P_W; l++) off[l] |= !(fabs$f(g1[i * $P_W + l]) <= $P_GTOL);\n");
  tmpl(e, "        any = 0;\n        for (l = 0; l < $P_W; l++) any |= ea[l] &= off[l];\n"
          "        if (!any) break;\n"
          "        $(consistent q0=q1 p0=p1 prm=par out=cs);\n"
          "        for (i = 0; i < $P_NU; i++)\n          for (l = 0; l < $P_W; l++) {\n"
          "            $R piv = cs[($[consistent.pivot]i) * $P_W + l], dia = cs[($[consistent.adiag]i) * $P_W + l];\n"
          "            $M sg1 = isfinite(piv) & isfinite(dia) & ((fabs$f(piv) > $P_SINGTOL * fabs$f(dia)) == 0);\n"
          "            nc[l] = (ea[l] & sg1 & (nc[l] == $P_OK)) ? $P_ESINGULAR : nc[l];\n          }\n"
          "        for (i = 0; i < $P_M; i++)\n          for (l = 0; l < $P_W; l++) {\n"
          "            $R d = cs[($[consistent.dq]i) * $P_W + l], q = q1[i * $P_W + l], qc = qc1[i * $P_W + l];\n"
          "            $R g = sw[($[sweep.gam]i) * $P_W + l], gn = g + d / h;\n"
          "            nc[l] = (ea[l] & !isfinite(d) & (nc[l] == $P_OK)) ? $P_ENONFINITE : nc[l];\n"
          "            $P_add(&q, &qc, d);\n"
          "            q1[i * $P_W + l] = ea[l] ? q : q1[i * $P_W + l];\n"
          "            qc1[i * $P_W + l] = ea[l] ? qc : qc1[i * $P_W + l];\n"
          "            sw[($[sweep.gam]i) * $P_W + l] = ea[l] ? gn : g;  /* gamma_0 with it */\n          }\n"
          "        any = 0;  /* a lane that failed stops, as the scalar step returns */\n"
          "        for (l = 0; l < $P_W; l++) any |= ea[l] &= nc[l] == $P_OK;\n"
          "      }\n    }\n");
}

// The end of the step for the lanes whose iteration converged (go[l]):
// the constant family's update, or the polynomial family's projection,
// rescale and multiplier (emit_end_poly in emit_end.c), as masked loops
// over the lanes; every lane computes, only the lanes in cm[] are written.
static void emit_commit(Emitter *e, int poly, int adaptive) {
  if (!poly) {
    tmpl(e, "  {\n    $M nf[$P_W], cm[$P_W];\n");
    if (e->mod->mass_q) tmpl(e, "    $R Hn[$P_W];  /* H(q0, p0), for the rescale */\n    $(energy_kernel q0=x->q p0=x->p prm=par out=Hn);\n");
    tmpl(e, ""
            "    for (l = 0; l < $P_W; l++) nf[l] = 0;\n"
            "    for (i = 0; i < $P_M; i++)\n      for (l = 0; l < $P_W; l++)\n"
            "        nf[l] |= !isfinite(x->q[i * $P_W + l] + h * sw[($[sweep.gam]i) * $P_W + l]) |\n"
            "                 !isfinite(x->p[i * $P_W + l] + sw[($[sweep.dp]i) * $P_W + l]) |\n"
            "                 !isfinite(x->qc[i * $P_W + l]) | !isfinite(x->pc[i * $P_W + l]);\n"
            "    for (l = 0; l < $P_W; l++) {\n"
            "      rc[l] = (go[l] & nf[l]) ? $P_ENONFINITE : rc[l];\n      cm[l] = go[l] & (nf[l] == 0);\n    }\n"
            "    for (i = 0; i < $P_M; i++)\n      for (l = 0; l < $P_W; l++) {\n"
            "        $R q = x->q[i * $P_W + l], qc = x->qc[i * $P_W + l], p = x->p[i * $P_W + l], pc = x->pc[i * $P_W + l];\n"
            "        $P_add(&q, &qc, h * sw[($[sweep.gam]i) * $P_W + l]);\n"
            "        $P_add(&p, &pc, sw[($[sweep.dp]i) * $P_W + l]);\n"
            "        x->q[i * $P_W + l] = cm[l] ? q : x->q[i * $P_W + l];\n        x->qc[i * $P_W + l] = cm[l] ? qc : x->qc[i * $P_W + l];\n"
            "        x->p[i * $P_W + l] = cm[l] ? p : x->p[i * $P_W + l];\n        x->pc[i * $P_W + l] = cm[l] ? pc : x->pc[i * $P_W + l];\n      }\n"
            "    for (i = 0; i < $P_NU; i++)\n      for (l = 0; l < $P_W; l++)\n"
            "        x->lambda[i * $P_W + l] = cm[l] ? sw[($[sweep.lambda]i) * $P_W + l] : x->lambda[i * $P_W + l];\n");
    if (e->mod->mass_q) emit_batch_mq_rescale(e); /* emit_batch_mq.c */
    emit_commit_common(e);
    return;
  }
  tmpl(e, "  {\n"
          "    $R q1[$P_M * $P_W], p1[$P_M * $P_W], qc1[$P_M * $P_W], pc1[$P_M * $P_W], H0[$P_W], beta[$P_W];\n"
          "    $R pr[($<project_p1> + 1) * $P_W], Hn[$P_W], lam[$P_NU * $P_W], pco[$P_M * $P_W];\n"
          "    $M sg[$P_W], nf[$P_W], gd[$P_W], cm[$P_W];\n"
          "    $(energy_kernel q0=x->q p0=x->p prm=par out=Hn);\n"
          "    for (i = 0; i < $P_M; i++)\n      for (l = 0; l < $P_W; l++) {\n"
          "        $R q = x->q[i * $P_W + l], qc = x->qc[i * $P_W + l], p = x->p[i * $P_W + l], pc = x->pc[i * $P_W + l];\n"
          "        $P_add(&q, &qc, h * sw[($[sweep.gam]i) * $P_W + l]);\n"
          "        $P_add(&p, &pc, sw[($[sweep.dp]i) * $P_W + l]);\n"
          "        q1[i * $P_W + l] = q;\n        qc1[i * $P_W + l] = qc;\n        p1[i * $P_W + l] = p;\n        pc1[i * $P_W + l] = pc;\n      }\n"
          "    for (l = 0; l < $P_W; l++) sg[l] = nf[l] = gd[l] = 0;\n");
  if (adaptive && itol_wanted(e)) emit_lane_newton(e);
  /* as in NAME_step, the finiteness test stops before the multiplier's lamv, lamu */
  tmpl(e, "    $(project_p1 q0=q1 p0=p1 prm=par out=pr);\n"
          "    for (i = 0; i < $P_NU; i++)\n      for (l = 0; l < $P_W; l++) {\n"
          "        $R piv = pr[($[project_p1.pivot]i) * $P_W + l], dia = pr[($[project_p1.adiag]i) * $P_W + l];\n"
          "        sg[l] |= isfinite(piv) & isfinite(dia) & ((fabs$f(piv) > $P_SINGTOL * fabs$f(dia)) == 0);\n      }\n"
          "    {  /* any value not finite: x - x is 0 for the finite ones, NaN for the others */\n"
          "      $R z[$P_W];\n      for (l = 0; l < $P_W; l++) z[l] = 0;\n"
          "      for (i = 0; i < $<project_p1.lamv>; i++)\n"
          "        for (l = 0; l < $P_W; l++) z[l] += pr[i * $P_W + l] - pr[i * $P_W + l];\n"
          "      for (l = 0; l < $P_W; l++) nf[l] |= z[l] != 0;\n    }\n"
          "    for (l = 0; l < $P_W; l++) {\n"
          "      $R K = pr[($[project_p1.kin]0) * $P_W + l], U1 = pr[($[project_p1.U]0) * $P_W + l], ho = x->H0[l];\n"
          "      $M keep = (x->hprev[l] != 0) & (fabs$f(Hn[l] - ho) <= 64 * $P_TOL * (K + fabs$f(U1)));\n"
          "      $R H = keep ? ho : Hn[l], a = (H - U1) / (K > 0 ? K : 1);\n"
          "      $M up = (K > 0) & (H - U1 > 0);\n"
          "      $R b = sqrt$f(up ? a : 1);\n"
          "      H0[l] = H;\n      beta[l] = up ? b : 1;\n    }\n"
          "    for (i = 0; i < $P_M; i++)\n      for (l = 0; l < $P_W; l++) {\n"
          "        $R d = pr[($[project_p1.dp]i) * $P_W + l], ph = p1[i * $P_W + l], p = ph, pc = pc1[i * $P_W + l];\n"
          "        $P_add(&p, &pc, d + (beta[l] - 1) * (ph + d));\n"
          "        pco[i * $P_W + l] = p - ph;\n        p1[i * $P_W + l] = p;\n        pc1[i * $P_W + l] = pc;\n"
          "        nf[l] |= !isfinite(q1[i * $P_W + l]) | !isfinite(p);\n      }\n"
          "    for (i = 0; i < $P_NU; i++)  /* g(q1) above round-off: not converged (emit_end_poly) */\n"
          "      for (l = 0; l < $P_W; l++)\n"
          "        gd[l] |= !(fabs$f(pr[($[project_p1.g]i) * $P_W + l]) <= $P_GSTEP * pr[($[project_p1.gscale]i) * $P_W + l] + $P_GTOL);\n"
          "    for (l = 0; l < $P_W; l++) {\n"
          "      $M code = sg[l] ? $P_ESINGULAR : nf[l] ? $P_ENONFINITE : gd[l] ? $P_ENOCONV : $P_OK;\n");
  if (adaptive && itol_wanted(e)) tmpl(e, "      code = nc[l] != $P_OK ? nc[l] : code;  /* the Newton steps' first, as in $P_step_within */\n");
  tmpl(e, "      rc[l] = go[l] ? code : rc[l];\n      cm[l] = go[l] & (code == $P_OK);\n"
          "      x->H0[l] = cm[l] ? H0[l] : x->H0[l];\n    }\n"
          "    for (i = 0; i < $P_M; i++)\n      for (l = 0; l < $P_W; l++) {\n"
          "        x->q[i * $P_W + l] = cm[l] ? q1[i * $P_W + l] : x->q[i * $P_W + l];\n"
          "        x->p[i * $P_W + l] = cm[l] ? p1[i * $P_W + l] : x->p[i * $P_W + l];\n"
          "        x->qc[i * $P_W + l] = cm[l] ? qc1[i * $P_W + l] : x->qc[i * $P_W + l];\n"
          "        x->pc[i * $P_W + l] = cm[l] ? pc1[i * $P_W + l] : x->pc[i * $P_W + l];\n"
          "        x->pcorr[i * $P_W + l] = cm[l] ? pco[i * $P_W + l] : x->pcorr[i * $P_W + l];\n      }\n"
          "    /* the multiplier consistent with the new (q, p), for the lanes that moved (in a\n"
          "     * loop of its own: with the selects, GCC 12 left it scalar) */\n"
          "    for (i = 0; i < $P_NU; i++)\n      for (l = 0; l < $P_W; l++)\n"
          "        lam[i * $P_W + l] = beta[l] * beta[l] * pr[($[project_p1.lamv]i) * $P_W + l] - pr[($[project_p1.lamu]i) * $P_W + l];\n"
          "    for (i = 0; i < $P_NU; i++)\n      for (l = 0; l < $P_W; l++) {\n"
          "        $R v = lam[i * $P_W + l];\n"
          "        v = isfinite(v) ? v : 0;\n        x->lambda[i * $P_W + l] = cm[l] ? v : x->lambda[i * $P_W + l];\n      }\n");
  emit_commit_common(e);
}

// A lane's call of a scalar step function f(state, sw, h, prm) on the lane's
// state and its sweep's results, with the arguments `more` after prm
// (NAME_defect: ", 0", no relative defect; NAME_mult_err: ", 1", as under the adaptive step).
static void emit_lane_call(Emitter *e, const char *f, const char *more) {
  out(e, "/* Lane l's %s_%s, on its state and its sweep's results. */\n", e->P, f);
  out(e, "static %s %s_batch_%s(const %s_batch *x, const %s *sw, int l, %s h, const %s_params *prm)\n{\n",
      real_type(e, 0), e->P, f, e->P, real_type(e, 0), real_type(e, 0), e->P);
  tmpl(e, "  $P_state s;\n  $P_params dflt;\n  $R v[$<sweep> + 1];\n  int i;\n"
          "  if (!prm) $P_params_default(&dflt);\n"
          "  $P_batch_get(x, l, &s);\n"
          "  for (i = 0; i < $<sweep>; i++) v[i] = sw[i * $P_W + l];\n");
  out(e, "  return %s_%s(&s, v, h, prm ? &prm[l] : &dflt%s);\n}\n\n", e->P, f, more);
}

// The error estimate of one lane for NAME_batch_step_adaptive, by the
// scalar step's own functions on the lane's values (once or twice a step,
// not worth lanes): NAME_err_est on the gamma of sw with the lane's scale
// max |q0| + |h gamma_0|, and, where the scalar step adds them,
// NAME_mult_err and NAME_defect on the lane's state.
static void emit_lane_estimate(Emitter *e, int mult, int defect) {
  tmpl(e, "/* Lane l's error estimate, $P_err_est on the gamma of sw, and its scale max|q0| + |h gamma_0|\n"
          " * (as $P_step_within's from the same sweep). */\n"
          "static $R $P_batch_est(const $P_batch *x, const $R *sw, int l, $R h, $R d1, int cold, $R *scale)\n{\n"
          "  $R g[$P_S * $P_M], sc = 0;\n  int i;\n"
          "  for (i = 0; i < $P_S * $P_M; i++) g[i] = sw[($[sweep.gam]i) * $P_W + l];\n"
          "  for (i = 0; i < $P_M; i++) {\n"
          "    $R v = fabs$f(x->q[i * $P_W + l]) + fabs$f(h * g[i]);\n    if (v > sc) sc = v;\n  }\n"
          "  *scale = sc;\n  return $P_err_est(g, h, d1, cold);\n}\n\n");
  if (mult) emit_lane_call(e, "mult_err", ", 1");
  if (defect) emit_lane_call(e, "defect", ", 0");
}

// NAME_batch_step_adaptive's tests inside NAME_batch_within, as
// NAME_step_within's: after the first sweep, each lane's predictor error d1
// (against the one-step start where the two-step one was taken) and the
// early estimate, which rejects warm lanes only; after the iteration, that
// every active lane converged and its estimate (with the energy defect where
// the scalar step has it). A lane over tol (1 + its scale) makes the whole
// try a rejection.
static void emit_lane_tolerance(Emitter *e, int poly, int mult, int defect) {
  tmpl(e, "/* After the first sweep (tol > 0): each iterating lane's predictor error d1 and its\n"
          " * estimate; 1 when one is already over tol (1 + its scale), its code then $P_EREJECT. */\n"
          "static int $P_batch_first(const $P_batch *x, $R h, $R tol, const $R *sw, const $R *gam, const $R *ref,\n"
          "    const $M *two, const $M *go, const $M *cl, $R *d1, $R *est, $M *rc)\n{\n"
          "  int i, l, over = 0;\n");
  if (!poly) tmpl(e, "  (void)ref;\n  (void)two;  /* no two-step start in this family */\n");
  tmpl(e, "  for (l = 0; l < $P_W; l++) {\n    $R d = 0, sc;\n"
          "    d1[l] = est[l] = 0;\n    if (!go[l]) continue;\n"
          "    for (i = 0; i < $P_S * $P_M; i++) {\n");
  tmpl(e, poly ? "      $R v = fabs$f(h * (sw[($[sweep.gam]i) * $P_W + l] - (two[l] ? ref : gam)[i * $P_W + l]));\n"
               : "      $R v = fabs$f(h * (sw[($[sweep.gam]i) * $P_W + l] - gam[i * $P_W + l]));\n");
  tmpl(e, "      if (v > d) d = v;\n    }\n"
          "    d1[l] = d;\n    est[l] = $P_batch_est(x, sw, l, h, d, (int)cl[l], &sc);\n"
          "    if (!cl[l] && !(est[l] <= tol * (1 + sc))) {  /* warm lanes only, as $P_step_within */\n"
          "      rc[l] = $P_EREJECT;\n      over = 1;\n    }\n  }\n"
          "  return over;\n}\n\n"
          "/* After the iteration (tol > 0): -2 when an active lane did not converge, -1 when one's\n"
          " * estimate is over tol (1 + its scale), its code then $P_EREJECT, else 0. */\n"
          "static int $P_batch_last(const $P_batch *x, $R h, $R tol, const $R *sw, const $M *go, const $M *cl,\n"
          "    const $R *d1, const $P_params *prm, $R *est, $M *rc)\n{\n"
          "  int l, over = 0;\n");
  if (!defect && !mult) tmpl(e, "  (void)prm;  /* for the energy defect, which this model does not need */\n");
  tmpl(e, "  for (l = 0; l < $P_W; l++) {\n    $R sc;\n"
          "    est[l] = 0;\n    if (x->idle[l]) continue;\n    if (!go[l]) return -2;\n"
          "    est[l] = $P_batch_est(x, sw, l, h, d1[l], (int)cl[l], &sc);\n");
  if (mult)
    tmpl(e, "    {\n      $R em = $P_batch_mult_err(x, sw, l, h, prm);\n      if (em > est[l]) est[l] = em;\n    }\n");
  if (defect) tmpl(e, "    est[l] += $P_batch_defect(x, sw, l, h, prm);\n");
  tmpl(e, "    if (!(est[l] <= tol * (1 + sc))) {\n      rc[l] = $P_EREJECT;\n      over = 1;\n    }\n  }\n"
          "  return over ? -1 : 0;\n}\n\n");
}

// NAME_batch_step_adaptive: NAME_step_adaptive's controller on the lanes'
// largest error over its tolerance, every try one NAME_batch_within of the
// shared step hh: accepted when every active lane converged within its
// tolerance, else retried from the unchanged lanes, smaller (halved after a
// failure), cold after three tries over the tolerance. Below the smallest
// step every active lane fails: ETOL, or its own failure. A bad h or tol
// fails every active lane with EBADSTEP; the return value is then, as after
// any failure, the number of lanes that failed (never the -1, -2 of a try).
void emit_batch_adaptive(Emitter *e) {
  tmpl(e, "int $P_batch_step_adaptive($P_batch *x, $P_real *h, $P_real tol, const $P_params *prm, $P_batch_stats *st)\n{\n"
          "  $P_batch_stats own, *s = st ? st : &own;  /* no struct copies: no memcpy on a bare target */\n  $R hh = *h, err, fac, r, pq, rq, rp, pmax, ra = 1, grow = 2, tmax = 0;\n  int rc, rejected = 0, misses = 0, nact = 0, first = 1, i, l, l0 = 0;\n"
          "  if (!(tol > 0 && isfinite(tol))) hh = 0;  /* every active lane then fails with $P_EBADSTEP */\n"
          "  if (!(hh != 0 && isfinite(hh))) {  /* every active lane fails: say how many, as below */\n"
          "    $P_batch_within(x, hh, 0, 0, prm, s);\n"
          "    for (l = 0; l < $P_W; l++) nact += s->code[l] != $P_OK;\n"
          "    return nact;\n  }\n"
          "  tol *= $P_TOLC;\n"
          "  for (l = 0; l < $P_W; l++)\n    if (!x->idle[l]) {\n      if (!nact++) l0 = l;  /* the first active lane */\n"
          "      if (fabs$f(x->t[l]) > tmax) tmax = fabs$f(x->t[l]);\n"
          "      if (x->hprev[l] != 0) first = 0;\n"
          "      /* the lowest aim of the lanes (emit_step_factor; 1 for a lane not from $P_init) */\n"
          "      if (x->aim[l] > 0 && x->aim[l] < ra) ra = x->aim[l];\n    }\n"
          "  if (first) grow = 100;  /* every active lane's first step: from a guess, as $P_step_adaptive */\n"
          "  for (;;) {\n"
          "    rc = $P_batch_within(x, hh, tol * fabs$f(hh), misses >= 3, prm, s);\n"
          "    if (rc == -1) misses++;\n"
          "    if (rc != -2) {\n"
          "      /* the lanes' largest error over its tolerance tol |h| (1 + max|q|), as $P_step_adaptive */\n"
          "      err = pmax = 0;\n"
          "      for (l = 0; l < $P_W; l++) {\n        $R sc = 0, el;\n"
          "        if (x->idle[l] || (rc >= 0 && s->code[l] != $P_OK)) continue;\n"
          "        for (i = 0; i < $P_M; i++)\n"
          "          if (fabs$f(x->q[i * $P_W + l]) > sc) sc = fabs$f(x->q[i * $P_W + l]);\n"
          "        el = s->err_est[l] / (tol * fabs$f(hh) * (1 + sc));\n        if (el > err) err = el;\n");
  /* each lane keeps its own err^(1/p), bitwise NAME_step_adaptive's; the
   * prediction from the largest, where every lane took the same last steps */
  tmpl(e, "        if (rc < 0) continue;\n        ");
  emit_root(e, "rp", "el");
  tmpl(e, "        if (x->hprev2[l] != x->hprev2[l0] || x->hprev2[l] == 0) pmax = -1;\n"
          "        if (pmax >= 0 && x->errprev[l] > pmax) pmax = x->errprev[l];\n"
          "        x->errprev[l] = rp;\n      }\n"
          "      rq = rc >= 0 && pmax > 0 ? pmax : 0;\n      pq = rq > 0 ? rq * (hh / x->hprev2[l0]) : 0;\n");
  emit_step_factor(e);
  tmpl(e, "      if (rc >= 0) {\n        *h = hh * fac;\n        s->rejected = rejected;\n");
  emit_aim_restore(e, "        ", "ra");
  tmpl(e, "        for (l = 0; l < $P_W; l++)  /* the lanes stepped share the aim from now on */\n"
          "          if (!x->idle[l] && s->code[l] == $P_OK) x->aim[l] = ra;\n"
          "        return rc;\n      }\n"
          "      if (!first) {  /* over the tolerance: a lower aim, as $P_step_adaptive */\n");
  emit_aim_cut(e, "        ", "ra");
  tmpl(e, "      }\n    } else {\n      fac = ($R)0.5;\n    }\n"
          "    rejected++;\n    grow = 1;\n    hh *= fac;\n"
          "    if (fabs$f(hh) < $P_HMIN * (1 + tmax) || rejected >= $P_MAXTRIES) {\n"
          "      s->h = 0;\n      s->rejected = rejected;\n"
          "      for (l = 0; l < $P_W; l++)\n"
          "        if (!x->idle[l] && (s->code[l] == $P_OK || s->code[l] == $P_EREJECT)) s->code[l] = $P_ETOL;\n"
          "      return nact;\n    }\n  }\n}\n");
}

// The body of NAME_batch_step (adaptive 0) and of NAME_batch_within
// (adaptive 1, for NAME_batch_step_adaptive), printed from one template: the
// set-up, the factor, the sweeps while a lane iterates, then the commit, all
// as loops over the lanes. The adaptive one adds the tests of
// emit_lane_tolerance, which leave before the commit with no lane written:
// -1 when a lane is over its tolerance, -2 when one failed. The fixed step
// is printed without them, so that nothing of them costs it a cycle.
static void emit_step_body(Emitter *e, int adaptive) {
  int poly = e->st->kern[K_FACTOR].nout > 0, nu = e->mod->nu, mq = e->mod->mass_q != NULL;
  if (adaptive)
    tmpl(e, "/* One try of $P_batch_step_adaptive: $P_batch_step with the tests of $P_step_within at tol\n"
            " * > 0; -1 (a lane over tol) or -2 (a lane failed) with no lane written. cold: every lane\n"
            " * without its warm start. */\n"
            "static int $P_batch_within($P_batch *x, $R h, $R tol, int cold, const $P_params *prm, $P_batch_stats *st)\n{\n");
  else
    tmpl(e, "int $P_batch_step($P_batch *x, $P_real h_, const $P_params *prm, $P_batch_stats *st)\n{\n"
            "  const $R h = ($R)h_;\n");
  /* two buffers of the sweep's results (+ its reductions for the lane test), in turn
   * the sweep's input (gamma from the prediction, then from the last sweep) and output */
  tmpl(e, "  $R par[($P_NPARAMS + 1) * $P_W], swb[2][($<sweep> + 3) * $P_W];\n"
          "  $R *in = swb[0], *sw = swb[1];  /* the sweep reads gamma (and lam) in in, writes sw */\n"
          "  $R inc[$P_W], incp[$P_W], inc_min[$P_W];\n");
  if (adaptive) tmpl(e, "  $R ref[$P_S * $P_M * $P_W], d1[$P_W], est[$P_W];\n  $M two[$P_W], cl[$P_W];\n");
  if (e->roll) tmpl(e, "  $M skip[$P_W];  /* the lanes the rolled sweep does not repeat */\n");
  tmpl(e, "  $M rc[$P_W], stall[$P_W], iters[$P_W];  /* as wide as the reals, as the masks: vectorised with them */\n  $M go[$P_W], act[$P_W];\n"
          "  int it, i, l, nrun = 0, ngo, nfail = 0, idle = 0, bad_h = !(h != 0 && isfinite(h));\n"
          "  $M rc0 = bad_h ? $P_EBADSTEP : $P_ENOCONV;\n");
  if (mq) tmpl(e, "  $R *pin = in + ($[sweep.th0]0) * $P_W;  /* M(q): the Theta the sweep reads (emit_batch_mq.c) */\n");
  if (poly)
    tmpl(e, "  $R *lin = in + ($[sweep.lam]0) * $P_W;  /* the multiplier the sweep reads */\n"
            "  $R rho[$P_W];  /* each lane's contraction at its last test ($P_contraction) */\n"
            "  $M fresh[$P_W];\n  int nfresh = 0;\n");
  if (itol_wanted(e) && adaptive) tmpl(e, "  $R itl[$P_W];  /* where each lane's iteration stops ($P_itol) */\n");
  if (adaptive) tmpl(e, "  int early = 0, tried = 0;\n");
  tmpl(e, "  $P_batch_params(prm, par);\n"
          "  for (l = 0; l < $P_W; l++) {\n"
          "    inc[l] = incp[l] = inc_min[l] = HUGE_VAL;\n    stall[l] = iters[l] = 0;\n");
  if (poly) tmpl(e, "    rho[l] = 1;\n");
  if (adaptive) tmpl(e, "    est[l] = d1[l] = 0;\n    cl[l] = (cold != 0) | (x->hprev[l] == 0);\n");
  if (itol_wanted(e) && adaptive) tmpl(e, "    itl[l] = $P_TOL;\n");
  /* the idle lanes in a loop of their own: a byte's reduction in the loop above
   * kept gcc from vectorising its stores */
  tmpl(e, "    rc[l] = rc0;\n  }\n"
          "  for (l = 0; l < $P_W; l++) idle |= x->idle[l];\n"
          "  if (idle)  /* mostly none */\n    for (l = 0; l < $P_W; l++) rc[l] = x->idle[l] ? $P_OK : rc0;\n");
  if (poly) tmpl(e, "  for (i = 0; i < $P_S * $P_NU * $P_W; i++) lin[i] = 0;\n");
  tmpl(e, !adaptive ? "  $P_batch_predict(x, h, 0, par, in, 0, 0);\n"
          : poly    ? "  $P_batch_predict(x, h, cold, par, in, ref, two);\n"
                    : "  $P_batch_predict(x, h, cold, par, in, 0, two);\n");
  if (mq) tmpl(e, adaptive ? "  $P_batch_predict_theta(x, h, cold, pin);\n" : "  $P_batch_predict_theta(x, h, 0, pin);\n");
  if (nu) {
    tmpl(e, "  $R g0[$P_NU * $P_W];\n  $(g q0=x->q p0=x->p prm=par out=g0);\n");
    tmpl(e, e->single ? "  for (l = 0; l < $P_W; l++) {  /* (float: the threshold grows with g's round-off) */\n"
                        "    $R gt = $P_gtol(x->q + l, $P_W);\n"
                        "    for (i = 0; i < $P_NU; i++)\n"
                        "      g0[i * $P_W + l] = fabs$f(g0[i * $P_W + l]) <= gt ? 0 : g0[i * $P_W + l] / h;\n  }\n"
                      : "  for (i = 0; i < $P_NU * $P_W; i++) g0[i] = fabs$f(g0[i]) <= $P_GTOL ? 0 : g0[i] / h;\n");
  }
  if (poly)
    tmpl(e, "  $R fa[($<factor> + 1) * $P_W];\n"
            "  $(factor q0=x->q gam=in h=h prm=par out=fa);\n"
            "  for (l = 0; l < $P_W; l++) go[l] = 1;\n"
            "  $P_batch_pivots(fa, go, rc);\n");
  char call[160];
  snprintf(call, sizeof call, "    $(sweep q0=x->q p0=x->p gam=in h=h%s%s prm=par out=sw%s);\n", nu ? " g0=g0" : "",
           poly ? " lam=lin lu=fa" : mq ? " pth=pin" : "", e->roll ? " skip=skip" : "");
  tmpl(e, "  for (l = 0; l < $P_W; l++) {\n    go[l] = rc[l] == $P_ENOCONV;  /* first: the lane iterates */\n"
          "    act[l] = go[l];\n    nrun += (int)go[l];\n");
  tmpl(e, adaptive ? "    early |= (rc[l] != $P_OK) & !go[l];\n  }\n"
                     "  if (early) {  /* a lane failed before the first sweep */\n    tried = -2;\n    goto out;\n  }\n"
                   : "  }\n");
  tmpl(e, "  ngo = nrun;\n"
          "  if (nrun == 0)  /* no sweep: what the commit reads of sw is defined all the same */\n"
          "    for (i = 0; i < ($<sweep> + 3) * $P_W; i++) in[i] = 0;\n"
          "  /* the sweep over all lanes while any iterates; a lane that stops keeps its gamma */\n"
          "  for (it = 1; it <= $P_MAXITER && nrun > 0; it++) {\n");
  if (poly) /* $P_step's refresh of the frozen factor, for the lanes that slow down */
    tmpl(e, "    if (it > 2 && nfresh) {\n"
            "      $R fb[($<factor> + 1) * $P_W];\n"
            "      $(factor q0=x->q gam=in h=h prm=par out=fb);\n"
            "      for (i = 0; i < $<factor>; i++)\n"
            "        for (l = 0; l < $P_W; l++) fa[i * $P_W + l] = fresh[l] ? fb[i * $P_W + l] : fa[i * $P_W + l];\n"
            "      $P_batch_pivots(fa, fresh, rc);\n"
            "      for (l = 0; l < $P_W; l++) {  /* a lane whose factor fails stops here */\n"
            "        $M stop = fresh[l] & (rc[l] != $P_ENOCONV);\n"
            "        iters[l] = stop ? it : iters[l];\n        act[l] = stop ? 0 : act[l];\n        nrun -= (int)stop;\n"
            "      }\n    }\n");
  if (e->roll) /* the lanes that stopped in this step: the rolled sweep copies their results */
    tmpl(e, "    for (l = 0; l < $P_W; l++) skip[l] = go[l] & (act[l] == 0);\n");
  tmpl(e, call);
  if (adaptive)
    tmpl(e, "    if (it == 1 && $P_batch_first(x, h, tol, sw, in, ref, two, go, cl, d1, est, rc)) {\n"
            "      tried = -1;\n      goto out;\n    }\n");
  tmpl(e, poly ? "    nrun = $P_batch_test(x, h, it, sw, in, lin, go, act, inc, incp, inc_min, stall, rc, iters, rho, fresh, &nfresh, ngo"
               : mq ? "    nrun = $P_batch_test(x, h, it, sw, in, pin, go, act, inc, incp, inc_min, stall, rc, iters, ngo"
                    : "    nrun = $P_batch_test(x, h, it, sw, in, 0, go, act, inc, incp, inc_min, stall, rc, iters, ngo");
  tmpl(e, !itol_wanted(e) ? ");\n" : adaptive ? ", tol, itl);\n" : ", 0, 0);\n");
  tmpl(e, "    {  /* this sweep's results are the next one's input */\n      $R *t = in;\n      in = sw;\n      sw = t;\n    }\n");
  if (poly) tmpl(e, "    lin = in + ($[sweep.lam]0) * $P_W;\n");
  if (mq) tmpl(e, "    pin = in + ($[sweep.th0]0) * $P_W;\n");
  tmpl(e, "  }\n  sw = in;  /* the last sweep's results */\n"
          "  $R nan[$P_W];  /* the rest of p's polynomial finite, as in $P_step (see $P_batch_test) */\n"
          "  for (l = 0; l < $P_W; l++) nan[l] = 0;\n"
          "  for (i = 0; i < ($P_S - 1) * $P_M; i++)\n"
          "    for (l = 0; l < $P_W; l++) nan[l] += sw[($[sweep.theta]i) * $P_W + l] - sw[($[sweep.theta]i) * $P_W + l];\n"
          "  for (l = 0; l < $P_W; l++) {  /* a lane still iterating did not converge: rc is $P_ENOCONV */\n"
          "    $R t = x->t[l] + h, tc = x->tc[l];\n"
          "    $M ok = go[l] & (rc[l] == $P_OK), tbad = !isfinite(t) | !isfinite(tc);\n"
          "    tbad |= nan[l] != 0;\n"
          "    iters[l] = (go[l] & (iters[l] == 0)) ? $P_MAXITER : iters[l];\n"
          "    rc[l] = (ok & tbad) ? $P_ENONFINITE : rc[l];\n"
          "    go[l] = ok & (tbad == 0);  /* now: the lane is committed */\n  }\n");
  if (adaptive) tmpl(e, "  if ((tried = $P_batch_last(x, h, tol, sw, go, cl, d1, prm, est, rc)) != 0) goto out;\n");
  emit_commit(e, poly, adaptive);
  if (adaptive) tmpl(e, "out:\n");
  tmpl(e, "  {\n    $M n = 0;  /* a wide sum: it vectorises */\n"
          "    for (l = 0; l < $P_W; l++) n += rc[l] != $P_OK;\n    nfail = (int)n;\n  }\n"
          "  if (st) {\n"
          "    for (l = 0; l < $P_W; l++) {\n"
          "      st->code[l] = (int)rc[l];\n      st->iters[l] = (int)iters[l];\n"
          "      st->increment[l] = iters[l] ? inc[l] : 0;\n");
  tmpl(e, adaptive ? "      st->err_est[l] = est[l];\n    }\n"
                     "    st->h = tried ? 0 : h;\n    st->rejected = 0;\n  }\n"
                     "  return tried ? tried : nfail;\n}\n\n"
                   : "      st->err_est[l] = 0;\n    }\n"
                     "    st->h = h;\n    st->rejected = 0;\n  }\n"
                     "  return nfail;\n}\n\n");
}

// NAME_batch_step and NAME_batch_step_adaptive with what they call.
void emit_batch_step(Emitter *e) {
  int poly = e->st->kern[K_FACTOR].nout > 0, defect = energy_defect_wanted(e), mult = mult_err_wanted(e);
  if (poly) emit_pivots(e);
  emit_lane_test(e, poly);
  emit_step_body(e, 0);
  emit_lane_estimate(e, mult, defect);
  emit_lane_tolerance(e, poly, mult, defect);
  emit_step_body(e, 1);
  emit_batch_adaptive(e);
}
