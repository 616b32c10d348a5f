/* emit_newton.c - C text of the step's iteration under --iteration newton,
 * and under --iteration auto on a stiff model.
 *
 * In place of the fixed-point loop of emit_step.c: simplified Newton on
 * F(gamma) = Phi(gamma) - gamma, Phi the sweep kernel (its result gam is
 * Phi at its input). The Newton matrix I + h^2 A (x) M^-1 J is factored by
 * the kernel "newton_factor" at the predicted polynomial, and again at the
 * current one where the increments fall by less than half (the rule of
 * Radau5 and IDA, within the step); "newton_solve" gives the correction.
 * Across steps the factor is kept in the state while h is the same and the
 * last step contracted below NAME_REUSE (Radau5's rule across steps).
 * Under auto (emit_auto_iteration) the step first runs the fixed-point
 * loop of emit_iterate.c, which ends early where it is slow
 * (emit_auto_slow), and Newton restarts from the predicted gamma.
 *
 * Stopping: on the scaled increment |h dgamma| / (max |q| + |h gamma_0|): far
 * below an ulp (TOL / 256), or within 2 ulps and no longer falling 4x
 * (round-off noise; the constant family's sweeps judge that per coordinate,
 * emit_iterate.c, and Newton, which contracts fast, ends far below an ulp);
 * in the poly family, whose end of step projects p1 and rescales it to H0,
 * below an eighth of an ulp (TOL / 16) where the constant family goes to
 * TOL / 256 (g(q1), which the end does not restore, stays within 2 ulps; at
 * TOL it reached 64 ulps on the stiff bob); a stall (STALL iterations
 * without a new smallest increment) is converged only at round-off
 * (NOISETOL). The poly family's loop starts from the one-step start, not
 * the two-step one the sweeps take (emit_predict.c). The step commits the gamma the last sweep
 * was evaluated at (not Phi of it, which in a stiff component magnifies
 * gamma's round-off by (h omega)^2), with p1 - p0 from that same sweep: the
 * discrete energy balance then holds up to the residual's round-off. So the
 * error left is that gamma's, the last increment itself, and the shortcut
 * of the polynomial family's test, rho inc / (1 - rho) (the error of the
 * next iterate, which has no sweep), does not apply: with it the stiff FPU
 * chain (omega = 1000, h omega = 10) lost 1e-12 of H a step. */
#include "emit.h"

int emit_is_newton(const Emitter *e) { return e->st->kern[K_NSOLVE].nout > 0; }

// Whether the Newton loop carries the polynomial family's multiplier
// coefficients (mlam) and its sweep's frozen factor (mfa).
static int newton_poly(const Emitter *e) { return e->st->kern[K_FACTOR].nout > 0; }

// NAME_newton_factor: the kernel "newton_factor" at gam, its pivots checked
// (with constraints also those of the multiplier's Schur complement, and J
// takes the multiplier lam).
static void emit_factor_checked(Emitter *e) {
  int nu = e->mod->nu;
  tmpl(e, "#ifndef $P_REFRESH\n#define $P_REFRESH 4  /* factorisations of the Newton matrix a step, at most */\n#endif\n");
  /* (the accelerated iteration contracts at about 1/2 on the stiff bob with J frozen for
   * the step, and a fresh J there buys few iterations: refreshed only where it stalls) */
  tmplf(e, "#ifndef $P_SLOW\n#define $P_SLOW %s$f  /* a contraction above this refreshes J */\n#endif\n",
        newton_poly(e) ? "0.5" : "0.9");
  tmpl(e, ""
          "/* The Newton matrix I + h^2 A (x) M^-1 J at the polynomial gam, factored into nf.\n");
  if (nu) tmpl(e, " * J = Hess(U + lam' g), lam the multiplier (its first $P_NU entries are read).\n");
  tmpl(e, " * Returns $P_OK, $P_ENONFINITE, or $P_ENOCONV for a singular matrix (a pivot below\n"
          " * $P_SINGTOL of its diagonal entry: h too long for a J with negative curvature). */\n");
  tmpl(e, nu ? "static int $P_newton_factor_checked(const $P_state *x, const $R *gam, const $R *lam, $R h, "
               "const $P_params *prm, $R *nf)\n{\n  int i;\n  $(newton_factor q0=x->q gam=gam h=h lam=lam out=nf);\n"
             : "static int $P_newton_factor_checked(const $P_state *x, const $R *gam, $R h, const $P_params *prm, $R *nf)\n"
               "{\n  int i;\n  $(newton_factor q0=x->q gam=gam h=h out=nf);\n");
  tmpl(e, "  for (i = 0; i < $P_S * $P_M; i++) {\n"
          "    $R piv = nf[$[newton_factor.pivot]i], dia = nf[$[newton_factor.adiag]i];\n"
          "    if (!isfinite(piv) || !isfinite(dia)) return $P_ENONFINITE;\n"
          "    if (!(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) return $P_ENOCONV;\n  }\n");
  if (nu)
    tmpl(e, newton_poly(e) ? "  for (i = 0; i < $P_S * $P_NU; i++) {  /* the multiplier's Schur complement */\n"
                           : "  for (i = 0; i < $P_NU; i++) {  /* the multiplier's Schur complement */\n");
  if (nu)
    tmpl(e, "    $R piv = nf[$[newton_factor.spivot]i], dia = nf[$[newton_factor.sadiag]i];\n"
            "    if (!isfinite(piv) || !isfinite(dia)) return $P_ENONFINITE;\n"
            "    if (!(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) return $P_ENOCONV;\n  }\n");
  tmpl(e, "  return $P_OK;  /* (a factor not finite elsewhere makes the correction so: ENONFINITE) */\n}\n\n");
  if (!newton_poly(e)) return;
  tmpl(e, "/* The poly family's multiplier matrix (its sweep's frozen factor) at the polynomial gam,\n"
          " * factored into fa. Returns $P_OK, $P_ENONFINITE, or $P_ESINGULAR for a singular matrix. */\n"
          "static int $P_mult_factor_checked(const $P_state *x, const $R *gam, $R h, const $P_params *prm, $R *fa)\n"
          "{\n  int j;\n  $(factor q0=x->q gam=gam h=h out=fa);\n"
          "  for (j = 0; j < $P_S * $P_NU; j++) {\n"
          "    $R piv = fa[$[factor.pivot]j], dia = fa[$[factor.adiag]j];\n"
          "    if (!isfinite(piv) || !isfinite(dia)) return $P_ENONFINITE;\n"
          "    if (!(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) return $P_ESINGULAR;\n  }\n"
          "  return $P_OK;\n}\n\n");
}

// NAME_anderson: the next iterate of the simplified Newton iteration,
// Anderson-accelerated (depth 2, "type II"), for the loop of the constant
// family and of models without constraints (the poly family's multiplier
// coefficients move with the sweep, and it keeps the plain update).
static void emit_anderson(Emitter *e) {
  tmpl(e, "/* The next Newton iterate from x and its correction dx, Anderson-accelerated (depth 2):\n"
          " * x + dx - sum_a theta_a (DX_a + DF_a), DX_a and DF_a the last two changes of the iterate\n"
          " * and of its correction, theta the least-squares fit of dx by the DF_a. A Newton matrix\n"
          " * frozen over the step (one J for every stage: on the stiff bob a spring that turns\n"
          " * during the step) leaves an error that decays slowly and turns from one iteration to\n"
          " * the next; the fit removes most of it. h (4 rows of S M: the last x, its dx, and the\n"
          " * last DX, DF) and *nh (0, 1 or 2 changes known) carry the history, kept across a\n"
          " * refresh of J (measured: fewer iterations than with the history dropped). */\n"
          "static void $P_anderson($R *x, const $R *dx, $R *h, int *nh)\n{\n"
          "  enum { N = $P_S * $P_M };\n"
          "  $R *xp = h, *fp = h + N, *dx1 = h + 2 * N, *df1 = h + 3 * N, dx0[N], df0[N], t0 = 0, t1 = 0;\n"
          "  $R g00 = 0, g01 = 0, g11 = 0, r0 = 0, r1 = 0, det;\n"
          "  int i, n = *nh;\n"
          "  for (i = 0; i < N; i++) {\n"
          "    dx0[i] = n ? x[i] - xp[i] : 0;\n    df0[i] = n ? dx[i] - fp[i] : 0;\n"
          "    g00 += df0[i] * df0[i];\n    r0 += df0[i] * dx[i];\n"
          "    if (n == 2) {  /* (dx1, df1 unset before) */\n"
          "      g01 += df0[i] * df1[i];\n      g11 += df1[i] * df1[i];\n      r1 += df1[i] * dx[i];\n    }\n  }\n"
          "  det = g00 * g11 - g01 * g01;\n"
          "  if (n == 2 && det > sqrt$f($P_TOL) * g00 * g11) {  /* two columns, well conditioned */\n"
          "    t0 = (r0 * g11 - r1 * g01) / det;\n"
          "    t1 = (g00 * r1 - g01 * r0) / det;\n"
          "  } else if (n >= 1 && g00 > 0) {\n    t0 = r0 / g00;\n  }\n"
          "  if (!isfinite(t0) || !isfinite(t1)) t0 = t1 = 0;\n"
          "  for (i = 0; i < N; i++) {\n"
          "    $R next = x[i] + dx[i] - t0 * (dx0[i] + df0[i]);\n"
          "    if (n == 2) next -= t1 * (dx1[i] + df1[i]);\n"
          "    xp[i] = x[i];\n    fp[i] = dx[i];\n"
          "    if (n) {\n      dx1[i] = dx0[i];\n      df1[i] = df0[i];\n    }\n"
          "    x[i] = next;\n  }\n"
          "  *nh = n < 2 ? n + 1 : 2;\n}\n\n");
}

// What NAME_step_within needs before its body: the checked factorisation,
// NAME_REUSE (and under --iteration auto the limit of the sweeps, NAME_SWITCH).
void emit_newton_helpers(Emitter *e) {
  tmpl(e, "#ifndef $P_REUSE\n#define $P_REUSE 1e-3$f  /* a factor kept across steps while it contracts below this */\n#endif\n");
  if (emit_is_auto(e))
    tmpl(e, "#ifndef $P_SWITCH\n#define $P_SWITCH 12  /* sweeps foreseen above which Newton takes over (auto) */\n#endif\n");
  emit_factor_checked(e);
  if (!newton_poly(e)) emit_anderson(e);
}

// The Newton loop of NAME_step_within: from gam to the converged gamma,
// leaving sw the sweep at it (sw[gam] replaced by gam itself), it the
// iterations, nfac the factorisations, rate the contraction, d1 the first
// correction. The factor is the state's, x->nf, where it was taken at this
// h and the last step that used it contracted by less than NAME_REUSE (the
// rule of Radau5 and IDA across steps), else a fresh one into nf; fac
// points at the one in use. Assumes nf, res, dg, nfac, rate and fac
// declared (emit_newton_locals), rc NAME_ENOCONV and inc, inc_min, stall as
// the step's head sets them.
static void emit_newton_loop(Emitter *e) {
  int nu = e->mod->nu, poly = newton_poly(e);
  if (poly)
    tmpl(e, "  /* the poly family: its multiplier's coefficients from 0, the sweep's frozen factor of\n"
            "   * the multiplier matrix at the predicted stages (again with each fresh Newton matrix) */\n"
            "  for (i = 0; i < $P_S * $P_NU; i++) mlam[i] = 0;\n"
            "  rc = $P_mult_factor_checked(x, gam, h, prm, mfa);\n"
            "  if (rc != $P_OK) return rc;\n");
  tmpl(e, "  rate = 0;\n"
          "  if (x->nfh == h && x->nfrate < $P_REUSE) {\n"
          "    fac = x->nf;  /* the last step's factor, at this h, contracted fast: kept */\n"
          "  } else {\n");
  tmpl(e, nu ? "    rc = $P_newton_factor_checked(x, gam, x->lambda, h, prm, nf);\n"
             : "    rc = $P_newton_factor_checked(x, gam, h, prm, nf);\n");
  tmpl(e, "    nfac++;\n"
          "    if (rc != $P_OK) return rc;\n"
          "  }\n"
          "  rc = $P_ENOCONV;\n"
          "  for (it = 1; it <= $P_MAXITER; it++) {\n");
  tmpl(e, poly ? "    $(sweep q0=x->q p0=x->p gam=gam h=h g0=g0 lam=mlam lu=mfa out=sw);\n"
         : nu ? "    $(sweep q0=x->q p0=x->p gam=gam h=h g0=g0 out=sw);\n"
              : "    $(sweep q0=x->q p0=x->p gam=gam h=h out=sw);\n");
  if (poly)
    tmpl(e, "    for (i = 0; i < $<sweep.theta>; i++)\n      if (!isfinite(sw[i])) rc = $P_ENONFINITE;\n");
  else if (nu) /* as the fixed-point sweep: a zero pivot makes lambda 0/0 */
    tmpl(e, "    for (i = 0; i < $P_NU; i++) {\n"
            "      $R piv = sw[$[sweep.pivot]i], dia = sw[$[sweep.adiag]i];\n"
            "      if (isfinite(piv) && isfinite(dia) && !(fabs$f(piv) > $P_SINGTOL * fabs$f(dia))) rc = $P_ESINGULAR;\n"
            "    }\n"
            "    if (rc == $P_ESINGULAR) break;\n");
  if (!poly) tmpl(e, "    for (i = 0; i < $<sweep.pivot>; i++)\n      if (!isfinite(sw[i])) rc = $P_ENONFINITE;\n");
  tmpl(e, "    if (rc == $P_ENONFINITE) break;\n"
          "    for (i = 0; i < $P_S * $P_M; i++) res[i] = sw[$[sweep.gam]i] - gam[i];\n");
  tmpl(e, poly ? "    $(newton_solve gam=res h=h lu=fac out=dg);\n" : "    $(newton_solve gam=res lu=fac out=dg);\n");
  tmpl(e, ""
          "    /* increment: max |h dgamma| over max |q| + |h gamma_0| */\n"
          "    inc_old = inc;\n    inc = 0;\n    scale = 0;\n"
          "    for (i = 0; i < $P_M; i++) {\n"
          "      $R v = fabs$f(x->q[i]) + fabs$f(h * gam[i]);\n"
          "      if (v > scale) scale = v;\n    }\n"
          "    for (i = 0; i < $P_S * $P_M; i++)  /* (a NaN becomes inc: the factor is not finite) */\n"
          "      if (!(fabs$f(h * dg[i]) <= inc)) inc = fabs$f(h * dg[i]);\n"
          "    if (it == 1) d1 = inc;  /* the predictor's error, for $P_err_est */\n"
          "    if (scale > 0) inc /= scale;\n"
          "    if (!isfinite(inc)) { rc = $P_ENONFINITE; break; }\n"
          "    if (it > 1 && inc > $P_NOISETOL && inc > rate * inc_old) rate = inc / inc_old;  /* above round-off */\n"
          "    /* converged at the gamma of this sweep (whose error is this increment): the\n");
  tmpl(e, poly ? "     * increment below an eighth of an ulp (g(q1) within an ulp or two: the end of the\n"
                 "     * step restores H and the hidden constraint, not g), or within 2 ulps and no longer\n"
                 "     * falling 4x (noise) */\n"
                 "    if (inc <= $P_TOL / 16 || (inc <= $P_TOL && 4 * inc > inc_old)) {\n"
               : "     * increment far below an ulp, or within 2 ulps and no longer falling 4x (noise) */\n"
                 "    if (inc <= $P_TOL / 256 || (inc <= $P_TOL && 4 * inc > inc_old)) {\n");
  tmpl(e, "      rc = $P_OK;\n      break;\n    }\n"
          "    /* a stall ($P_STALL iterations without a new smallest increment): converged only at\n"
          "     * round-off ($P_NOISETOL) */\n"
          "    if (inc < inc_min) {\n      inc_min = inc;\n      stall = 0;\n    } else if (++stall >= $P_STALL) {\n"
          "      rc = inc_min <= $P_NOISETOL ? $P_OK : $P_ENOCONV;\n      break;\n    }\n"
          "");
  tmpl(e, poly ? "    for (i = 0; i < $P_S * $P_M; i++) gam[i] += dg[i];\n"
               : "    $P_anderson(gam, dg, ah, &na);  /* gam += dg, accelerated */\n");
  if (poly)
    tmpl(e, "    /* the coefficients the sweep took, moved by Newton's change of the multiplier */\n"
            "    for (i = 0; i < $P_S * $P_NU; i++) mlam[i] = sw[$[sweep.lam]i] + dg[$[newton_solve.dlam]i];\n");
  tmpl(e, "    /* contracting slowly (rho > $P_SLOW) above round-off: J refreshed at the\n"
          "     * current polynomial */\n"
          "    if (it > 1 && inc > $P_SLOW * inc_old && inc > $P_NOISETOL && nfac < $P_REFRESH) {\n");
  tmpl(e, poly ? "      int rf = $P_newton_factor_checked(x, gam, mlam, h, prm, nf);  /* lambda_0: the mean */\n"
         : nu ? "      int rf = $P_newton_factor_checked(x, gam, sw + $[sweep.lambda]0, h, prm, nf);  /* the last lambda */\n"
              : "      int rf = $P_newton_factor_checked(x, gam, h, prm, nf);\n");
  tmpl(e, "      fac = nf;\n      nfac++;\n"
          "      if (rf != $P_OK) { rc = rf; break; }\n");
  if (poly) tmpl(e, "      if ((rf = $P_mult_factor_checked(x, gam, h, prm, mfa)) != $P_OK) { rc = rf; break; }\n");
  tmpl(e, "    }\n  }\n"
          "  /* the step is the one at the gamma the sweep was evaluated at */\n"
          "  for (i = 0; i < $P_S * $P_M; i++) sw[$[sweep.gam]i] = gam[i];\n");
}

double newton_factor_bytes(const Step *st, int single) {
  return (double)kernel_size(&st->kern[K_NFACTOR]) * (single ? sizeof(float) : sizeof(double));
}

// Whether the factor being made is the state's scratch nfw rather than a
// local of the step (NEWTON_LOCAL_MAX_BYTES): the rolled polymer of 1000
// beads at s = 4 has a factor of 15 MB, whose local overflowed the 8 MB
// stack (a segmentation fault on the first step).
static int factor_in_state(const Emitter *e) {
  return newton_factor_bytes(e->st, e->single) > NEWTON_LOCAL_MAX_BYTES;
}

// The Newton iteration's locals, and its counts in the stats zeroed (a
// step may return before it writes them). rate < 0: Newton did not run.
static void emit_newton_locals(Emitter *e) {
  int poly = newton_poly(e);
  if (poly) tmpl(e, "  $R mfa[$<factor> + 1], mlam[$P_S * $P_NU];  /* the poly family's sweep: its factor, lam */\n");
  tmpl(e, "  $R ");
  tmpl(e, factor_in_state(e) ? "*nf = x->nfw" : "nf[$<newton_factor> + 1]");
  /* (dg: in the poly family the correction of gamma, then of the multiplier's coefficients) */
  tmpl(e, poly ? ", res[$P_S * $P_M], dg[$<newton_solve>], rate = -1;\n"
               : ", res[$P_S * $P_M], dg[$P_S * $P_M], rate = -1;\n"
                 "  $R ah[4 * $P_S * $P_M];  /* $P_anderson's history */\n"
                 "  int na = 0;\n");
  tmpl(e, ""
          "  const $R *fac = nf;  /* the factor in use: nf, or the state's */\n"
          "  int nfac = 0;\n"
          "  if (st) st->newton = st->factors = st->jacobians = 0;\n");
}

// The counts of the Newton iteration into the stats: nit iterations, nfac
// factorisations, each with its own J.
static void emit_newton_counts(Emitter *e, const char *nit) {
  out(e, "  if (st) {\n    st->newton = %s;\n    st->factors = st->jacobians = nfac;\n  }\n", nit);
}

// --iteration newton: the loop of NAME_step_within, simplified Newton from
// the predicted gam (emit_newton_loop).
void emit_newton_iteration(Emitter *e) {
  tmpl(e, "  /* simplified Newton on Phi(gamma) - gamma = 0 (Phi: the sweep), the Newton matrix\n"
          "   * factored at the predicted polynomial, again where the iteration slows down */\n");
  emit_newton_locals(e);
  emit_newton_loop(e);
  emit_newton_counts(e, "it");
}

int emit_is_auto(const Emitter *e) { return e->me->iteration == ITER_AUTO; }

int emit_has_sweeps(const Emitter *e) { return !emit_is_newton(e) || emit_is_auto(e); }

// What NAME_ENOCONV says did not converge.
const char *emit_iteration_name(const Emitter *e) {
  return emit_is_auto(e) ? "fixed-point and Newton iterations" : emit_is_newton(e) ? "Newton iteration"
                                                                                     : "fixed-point iteration";
}

// --iteration auto on a stiff model: the fixed-point sweeps of emit_iterate.c
// from the predicted gamma; where they are slow (emit_auto_slow) or fail,
// simplified Newton from the same start. Newton directly when |h| is at
// least x->hnewton, the shortest step whose sweeps were slow (kept in the
// state at the end of the step, emit_newton_commit). it: the sweeps plus
// the Newton iterations.
void emit_auto_iteration(Emitter *e) {
  tmpl(e, "  /* --iteration auto: fixed-point sweeps first; simplified Newton where they are slow\n"
          "   * or fail (from the same predicted gamma), or directly from a step as long as one\n"
          "   * whose sweeps were slow (x->hnewton) */\n"
          "  $R gpred[$P_S * $P_M], inc_pp = HUGE_VAL, hnewton = x->hnewton;\n"
          "  int sweeps = 0;\n");
  emit_newton_locals(e);
  tmpl(e, newton_poly(e) ? "  for (i = 0; i < $P_S * $P_M; i++) gpred[i] = two ? ref[i] : gam[i];  /* the one-step start */\n"
                         : "  for (i = 0; i < $P_S * $P_M; i++) gpred[i] = gam[i];\n");
  tmpl(e, ""
          "  if (!(hnewton > 0 && fabs$f(h) >= hnewton)) {\n");
  emit_fixed_point(e);
  tmpl(e, "  sweeps = it > $P_MAXITER ? $P_MAXITER : it;\n"
          "  if (rc != $P_OK && (!(hnewton > 0) || fabs$f(h) < hnewton)) hnewton = fabs$f(h);\n"
          "  }\n"
          "  if (rc != $P_OK) {  /* simplified Newton from the predicted gamma */\n"
          "  for (i = 0; i < $P_S * $P_M; i++) gam[i] = gpred[i];\n"
          "  inc = inc_min = HUGE_VAL;\n  stall = 0;\n");
  emit_newton_loop(e);
  emit_newton_counts(e, "it");
  tmpl(e, "  it += sweeps;\n  }\n");
}

// In the fixed-point loop of --iteration auto, after the tests for
// convergence: the sweeps are slow where the increment, falling by
// rho2 = inc / inc_pp over two sweeps, would take more than NAME_SWITCH
// sweeps in all to reach NAME_TOL / 256, or does not fall (it >= 3). The loop
// then ends with rc not NAME_OK, and Newton takes over.
void emit_auto_slow(Emitter *e) {
  tmpl(e, "    /* slow: more than $P_SWITCH sweeps foreseen at the contraction of the last two */\n"
          "    if (it >= 3 && !(inc < inc_pp && it + 2 * log$f(inc * 256 / $P_TOL) / log$f(inc_pp / inc) <= $P_SWITCH)) {\n"
          "      rc = $P_ENOCONV;\n      break;\n    }\n"
          "    inc_pp = inc_old;\n");
}

// The end of a step with Newton: a fresh factor into the state with its h,
// the contraction of the step that used it, and under --iteration auto the
// shortest slow h.
void emit_newton_commit(Emitter *e) {
  if (!emit_is_newton(e)) return;
  tmpl(e, "  if (nfac) {  /* a fresh factor: kept for the next steps at this h */\n"
          "    for (i = 0; i < $<newton_factor>; i++) x->nf[i] = nf[i];\n"
          "    x->nfh = h;\n  }\n"
          "  if (rate >= 0) x->nfrate = rate;\n");
  if (emit_is_auto(e)) tmpl(e, "  x->hnewton = hnewton;\n");
}

// The state's fields of the Newton iteration: its factor kept across steps.
void emit_newton_state(Emitter *e) {
  tmpl(e, "  $R nf[$<newton_factor> + 1];  /* the Newton matrix's factor kept across steps ... */\n"
          "  $R nfh, nfrate;  /* ... taken at h = nfh (0: none); the last contraction with it */\n");
  if (factor_in_state(e))
    tmpl(e, "  $R nfw[$<newton_factor> + 1];  /* the factor being made: the step's scratch, which a failed\n"
            "                                    step may change (too large for the step's stack) */\n");
  if (emit_is_auto(e)) tmpl(e, "  $R hnewton;  /* the shortest |h| whose sweeps were slow: Newton from it on (0: none) */\n");
}

// Their values after NAME_init: no factor.
void emit_newton_init(Emitter *e) {
  tmpl(e, "  x->nfh = x->nfrate = 0;\n  for (i = 0; i <= $<newton_factor>; i++) x->nf[i] = 0;\n");
  if (factor_in_state(e)) tmpl(e, "  for (i = 0; i <= $<newton_factor>; i++) x->nfw[i] = 0;\n");
  if (emit_is_auto(e)) tmpl(e, "  x->hnewton = 0;\n");
}

// The fields of NAME_stats the Newton iteration adds.
void emit_newton_stats(Emitter *e) {
  tmpl(e, "  int newton;        /* iterations of simplified Newton (iters counts them too) */\n"
          "  int factors;       /* factorisations of the Newton matrix */\n"
          "  int jacobians;     /* evaluations of its J = Hess(U + lambda' g) (one a factorisation) */\n");
}
