/* check_newton.c - Check suite for --iteration newton (gen/step_newton.c,
 * gen/emit_newton.c) on the stiff Fermi-Pasta-Ulam chain, models/fpu.ham
 * (Hairer, Lubich, Wanner, GNI I.5 and XIII), HBVM(4,2):
 *
 *   matrix     the method's matrix A of the Newton matrix I + h^2 A (x) M^-1 J
 *              is the Jacobian of the sweep: for a quadratic U (J constant)
 *              the sweep's finite differences are -h^2 A (x) M^-1 J to
 *              round-off; and A = T Lambda T^-1, the eigenbasis the solve uses.
 *   converge   every step converges at h omega = 10, 100 and 1000, in a
 *              bounded number of iterations and factorisations, with H at
 *              round-off (a random walk of a few ulps of (1 + h omega) H a step).
 *   slow       the slow motion (the soft springs' centres x0) at T = 2 against
 *              the fixed-point step at h omega = 0.1, within the bound measured
 *              with margin (docs/method-newton.md).
 *   adiabatic  the oscillatory energy I = sum (p1^2 + omega^2 x1^2) / 2 stays
 *              within 0.1 of its start over T = 1000 at h omega = 10 (GNI XIII:
 *              an adiabatic invariant, whose variation stays bounded).
 *   rollback   a step that fails leaves the state byte-identical.
 *   refused    what --iteration newton does not handle yet is an error.
 * With a constraint (--multiplier const), on the pendulum with a stiff
 * two-mass bob, models/stiff_bob.ham, HBVM(16,2):
 *   bob        every step converges at h omega = 10 (k = 1e4 and 1e6) and
 *              100 (k = 1e6) in a bounded number of iterations, g and H at
 *              round-off; the bob's centre of mass at T = 10 against the
 *              fixed-point step at h omega = 1/4; a failed step rolls back.
 * The suite is newton_suite(); the project's runner adds it. */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fpu_fixed_k4s2.h"
#include "fpu_newton_k4s2.h"
#include "stiff_bob_fixed_k16s2.h"
#include "stiff_bob_newton_k16s2.h"
#include "generate.h"
#include "hbvmgen.h"
#include "step.h"

Suite *newton_suite(void);

#define T_SLOW 2.0

/* ---- the method's matrix against the sweep ---- */

/* A model with a constant Hessian and a non-identity M, analysed in-process. */
static Model *quadratic_model(void) {
  static const char src[] = "variables x, y, z\nM = diag(2, 1, 3)\n"
                            "U = 3 * x^2 + x * y + 5 * y^2 + 2 * y * z + z^2 / 2\nq0 = [0.1, 0.2, 0.3]\np0 = [1, -1, 0.5]\n";
  diag_begin("quadratic.ham", src, strlen(src));
  Stmt *prog = parse_model(src, strlen(src));
  Model *mod = analyse("quadratic.ham", prog);
  ck_assert_ptr_nonnull(mod);
  model_differentiate(mod);
  return mod;
}

/* The sweep's new gamma at the input gamma gam (q0, p0 the model's, h). */
static void sweep_at(const Model *mod, const Step *st, const double *gam, double h, double *out) {
  double in[256] = {0};
  const Slots *g = step_block(st, K_SWEEP, "gam");
  for (int i = 0; i < mod->m; i++) {
    in[st->in[IN_Q0].first + i] = mod->q0[i];
    in[st->in[IN_P0].first + i] = mod->p0[i];
  }
  for (int i = 0; i < st->s * mod->m; i++) in[st->in[IN_GAM].first + i] = gam[i];
  in[st->in[IN_H].first] = h;
  dag_eval_many(mod->dag, g->nodes, g->len, in, NULL, out);
}

START_TEST(test_matrix_is_the_sweeps_jacobian) {
  static const double J[9] = {6, 1, 0, 1, 10, 2, 0, 2, 1}, minv[3] = {0.5, 1, 1.0 / 3};
  for (int s = 1; s <= 4; s++) {
    Model *mod = quadratic_model();
    int m = mod->m, n = s * m;
    Method *me = method_new(s + 1, s, MULT_CONST);
    me->iteration = ITER_NEWTON;
    Step *st = step_build(mod, me);
    double A[16], h = 0.3, gam[12] = {0}, base[12], pert[12];
    newton_method_matrix(me, A);
    for (int i = 0; i < n; i++) gam[i] = 0.1 * (i + 1);
    sweep_at(mod, st, gam, h, base);
    for (int c = 0; c < n; c++) { /* column c of the sweep's Jacobian: exact for a linear sweep */
      gam[c] += 1;
      sweep_at(mod, st, gam, h, pert);
      gam[c] -= 1;
      int r = c / m, b = c % m;
      for (int i = 0; i < n; i++) {
        int j = i / m, a = i % m;
        double want = -h * h * A[j * s + r] * minv[a] * J[a * m + b];
        ck_assert_msg(fabs(pert[i] - base[i] - want) <= 1e-13, "s=%d d gam[%d] / d gam[%d] = %.17g, want %.17g", s, i,
                      c, pert[i] - base[i], want);
      }
    }
    NewtonBasis nb;
    newton_basis(me, &nb);
    for (int i = 0; i < s; i++) /* T Lambda T^-1 = A */
      for (int c = 0; c < s; c++) {
        double acc = 0;
        for (int q = 0; q < nb.nblocks; q++) {
          const NewtonBlock *bk = &nb.blk[q];
          int k0 = bk->col;
          if (!bk->pair) {
            acc += nb.T[i * s + k0] * bk->a * nb.Tinv[k0 * s + c];
            continue;
          }
          double t0 = nb.T[i * s + k0], t1 = nb.T[i * s + k0 + 1];
          acc += (t0 * bk->a - t1 * bk->b) * nb.Tinv[k0 * s + c] + (t0 * bk->b + t1 * bk->a) * nb.Tinv[(k0 + 1) * s + c];
        }
        ck_assert_msg(fabs(acc - A[i * s + c]) <= 1e-15, "s=%d: (T L T^-1)[%d][%d] = %.17g, A = %.17g", s, i, c, acc,
                      A[i * s + c]);
      }
    diag_end();
    arena_free_all();
  }
}
END_TEST

/* ---- runs on the FPU chain ---- */

/* Iterations and factorisations over a run: sums, then averages, and maxima. */
typedef struct {
  int steps, failed, max_iters, max_factors;
  double iters, factors;
} Tally;

static void tally_step(Tally *t, int iters, int factors) {
  t->iters += iters;
  t->factors += factors;
  if (iters > t->max_iters) t->max_iters = iters;
  if (factors > t->max_factors) t->max_factors = factors;
}

static void tally_end(Tally *t) {
  t->iters /= t->steps;
  t->factors /= t->steps;
}

typedef struct {
  Tally n;
  double dH, x0[3], I_dev;
} Run;

/* The oscillatory energy of the stiff springs. */
static double stiff_energy(const double *q, const double *p, double omega) {
  double I = 0;
  for (int i = 3; i < 6; i++) I += (p[i] * p[i] + omega * omega * q[i] * q[i]) / 2;
  return I;
}

/* The Newton step from the model's start at omega, to T in steps of h. */
static Run run_newton(double omega, double h, double T) {
  fpu_newton_k4s2_params prm;
  fpu_newton_k4s2_state x;
  Run r = {0};
  fpu_newton_k4s2_params_default(&prm);
  prm.omega = omega;
  fpu_newton_k4s2_init_params(&x, NULL, NULL, &prm);
  double H0 = fpu_newton_k4s2_energy(&x, &prm), I0 = stiff_energy(x.q, x.p, omega);
  r.n.steps = (int)lround(T / h);
  for (int n = 0; n < r.n.steps; n++) {
    fpu_newton_k4s2_stats st;
    if (fpu_newton_k4s2_step(&x, h, &prm, &st) != fpu_newton_k4s2_OK) {
      r.n.failed++;
      break;
    }
    tally_step(&r.n, st.iters, st.factors);
    r.dH = fmax(r.dH, fabs(fpu_newton_k4s2_energy(&x, &prm) - H0));
    r.I_dev = fmax(r.I_dev, fabs(stiff_energy(x.q, x.p, omega) - I0));
  }
  tally_end(&r.n);
  memcpy(r.x0, x.q, sizeof r.x0);
  return r;
}

/* Converged at every step, in at most 12 iterations and 2 factorisations
 * (measured: 4.0, 6.1 and 5.8 iterations a step on average, one
 * factorisation), H within 8 ulps of (1 + h omega) H0 per step as a random
 * walk (sqrt(steps)). */
START_TEST(test_converges_at_long_steps) {
  static const struct {
    double omega, h;
  } cases[] = {{1000, 0.01}, {1000, 0.1}, {1e4, 0.1}, {50, 0.2}};
  for (int c = 0; c < 3; c++) {
    Run r = run_newton(cases[c].omega, cases[c].h, T_SLOW);
    double hw = cases[c].omega * cases[c].h, bound = 8 * DBL_EPSILON * (1 + hw) * 2 * sqrt(r.n.steps);
    ck_assert_msg(!r.n.failed, "h omega = %g: a step failed", hw);
    ck_assert_msg(r.n.max_iters <= 12 && r.n.max_factors <= 2, "h omega = %g: %d iterations, %d factorisations", hw,
                  r.n.max_iters, r.n.max_factors);
    ck_assert_msg(r.dH <= bound, "h omega = %g: |H - H0| = %.3g > %.3g", hw, r.dH, bound);
  }
}
END_TEST

/* The slow motion at T = 2 (omega = 1000) against the fixed-point step at
 * h omega = 0.1: measured 1.1e-6 (h omega = 10) and 6.5e-6 (100); the
 * bounds are 4x that. */
START_TEST(test_slow_motion) {
  fpu_fixed_k4s2_params prm;
  fpu_fixed_k4s2_state x;
  fpu_fixed_k4s2_params_default(&prm);
  prm.omega = 1000;
  fpu_fixed_k4s2_init_params(&x, NULL, NULL, &prm);
  for (int n = 0; n < 20000; n++) ck_assert_int_eq(fpu_fixed_k4s2_step(&x, 1e-4, &prm, NULL), fpu_fixed_k4s2_OK);
  static const double h[2] = {0.01, 0.1}, bound[2] = {4.5e-6, 2.6e-5};
  for (int c = 0; c < 2; c++) {
    Run r = run_newton(1000, h[c], T_SLOW);
    double err = 0;
    for (int i = 0; i < 3; i++) err = fmax(err, fabs(r.x0[i] - x.q[i]));
    ck_assert_msg(err <= bound[c], "h omega = %g: slow error %.3g > %.3g", 1000 * h[c], err, bound[c]);
  }
}
END_TEST

/* The adiabatic invariant over T = 1000 (5000 steps at h omega = 10, omega
 * = 50): measured max |I - I0| 0.073 (0.086 over T = 10^4, no drift); the
 * fixed-point step at h omega = 0.5 gives 0.076, so that is the flow's own. */
START_TEST(test_adiabatic_invariant) {
  Run r = run_newton(50, 0.2, 1000);
  ck_assert_msg(!r.n.failed, "a step failed");
  ck_assert_msg(r.I_dev <= 0.1, "max |I - I0| = %.3g", r.I_dev);
}
END_TEST

/* A step too long for the soft springs' nonlinearity (h = 20) fails; the
 * state, compensations and history included, is unchanged to the byte. */
START_TEST(test_failed_step_rolls_back) {
  fpu_newton_k4s2_state x, before;
  fpu_newton_k4s2_params prm;
  fpu_newton_k4s2_params_default(&prm);
  memset(&x, 0, sizeof x);
  fpu_newton_k4s2_init_params(&x, NULL, NULL, &prm);
  for (int n = 0; n < 3; n++) ck_assert_int_eq(fpu_newton_k4s2_step(&x, 0.1, &prm, NULL), fpu_newton_k4s2_OK);
  memcpy(&before, &x, sizeof x);
  int rc = fpu_newton_k4s2_step(&x, 20, &prm, NULL);
  ck_assert_int_ne(rc, fpu_newton_k4s2_OK);
  ck_assert_msg(!memcmp(&before, &x, sizeof x), "the failed step (%s) changed the state", fpu_newton_k4s2_strerror(rc));
}
END_TEST

/* ---- with a constraint: the stiff bob ---- */

typedef struct {
  Tally n;
  double dH, g, H0, com[2];
} BobRun;

/* The Newton step from the model's start at spring stiffness k, to T in
 * steps of h omega / omega, omega = sqrt(2 k). */
static BobRun run_bob(double k, double hw, double T) {
  stiff_bob_newton_k16s2_params prm;
  stiff_bob_newton_k16s2_state x;
  BobRun r = {0};
  stiff_bob_newton_k16s2_params_default(&prm);
  prm.k = k;
  stiff_bob_newton_k16s2_init_params(&x, NULL, NULL, &prm);
  r.H0 = stiff_bob_newton_k16s2_energy(&x, &prm);
  r.n.steps = (int)lround(T * sqrt(2 * k) / hw);
  for (int n = 0; n < r.n.steps; n++) {
    stiff_bob_newton_k16s2_stats st;
    double g;
    if (stiff_bob_newton_k16s2_step(&x, T / r.n.steps, &prm, &st) != stiff_bob_newton_k16s2_OK) {
      r.n.failed++;
      break;
    }
    tally_step(&r.n, st.iters, st.factors);
    stiff_bob_newton_k16s2_constraints(&x, &prm, &g);
    r.g = fmax(r.g, fabs(g));
    r.dH = fmax(r.dH, fabs(stiff_bob_newton_k16s2_energy(&x, &prm) - r.H0));
  }
  tally_end(&r.n);
  r.com[0] = (x.q[0] + x.q[2]) / 2;
  r.com[1] = (x.q[1] + x.q[3]) / 2;
  return r;
}

/* Converged at every step over T = 10 (measured, iterations a step on
 * average (max): k = 1e4, h omega = 10: 9.1 (11); k = 1e6, h omega = 10:
 * 6.2 (8), 100: 13.1 (31), with 1.0, 0.9 and 1.4 factorisations), in at
 * most 60 iterations and NAME_REFRESH = 4 factorisations; g within 2 ulps
 * of its scale 1 (measured 1); H as on the FPU chain. */
START_TEST(test_bob_converges) {
  static const struct {
    double k, hw;
  } cases[] = {{1e4, 10}, {1e6, 10}, {1e6, 100}};
  for (int c = 0; c < 3; c++) {
    BobRun r = run_bob(cases[c].k, cases[c].hw, 10);
    double hw = cases[c].hw, bound = 8 * DBL_EPSILON * (1 + hw) * fabs(r.H0) * sqrt(r.n.steps);
    ck_assert_msg(!r.n.failed, "k = %g, h omega = %g: a step failed", cases[c].k, hw);
    ck_assert_msg(r.n.max_iters <= 60 && r.n.max_factors <= 4, "k = %g, h omega = %g: %d iterations, %d factorisations",
                  cases[c].k, hw, r.n.max_iters, r.n.max_factors);
    ck_assert_msg(r.g <= 2 * DBL_EPSILON, "k = %g, h omega = %g: |g| = %.3g", cases[c].k, hw, r.g);
    ck_assert_msg(r.dH <= bound, "k = %g, h omega = %g: |H - H0| = %.3g > %.3g", cases[c].k, hw, r.dH, bound);
  }
}
END_TEST

/* At the longest step of the benchmark's bob line (k = 1e4, T = 10 in 34
 * steps, h omega = 41.6), where a J frozen over the step fits stages that
 * the turning spring makes differ: Anderson's acceleration of the update
 * (NAME_anderson) takes the iteration from 31.4 iterations a step on average
 * (60 at most) down to 16.5 (24) with 1.9 factorisations (measured);
 * bounds 20 (30): the old update fails them. Every step converged, H and g
 * as in test_bob_converges. */
START_TEST(test_bob_long_step_iterations) {
  double hw = 10 * sqrt(2e4) / 34;
  BobRun r = run_bob(1e4, hw, 10);
  double bound = 8 * DBL_EPSILON * (1 + hw) * fabs(r.H0) * sqrt(r.n.steps);
  ck_assert_int_eq(r.n.steps, 34);
  ck_assert_msg(!r.n.failed, "a step failed");
  ck_assert_msg(r.n.iters <= 20 && r.n.max_iters <= 30, "%.1f iterations a step, %d at most", r.n.iters,
                r.n.max_iters);
  ck_assert_msg(r.g <= 2 * DBL_EPSILON, "|g| = %.3g", r.g);
  ck_assert_msg(r.dH <= bound, "|H - H0| = %.3g > %.3g", r.dH, bound);
}
END_TEST

/* The bob's centre of mass at T = 10 (k = 1e4) against the fixed-point step
 * at h omega = 1/4: measured 4.2e-5 (h omega = 10) and 2.7e-5 (30); the
 * bounds are 4x that. */
START_TEST(test_bob_slow_motion) {
  stiff_bob_fixed_k16s2_params prm;
  stiff_bob_fixed_k16s2_state x;
  stiff_bob_fixed_k16s2_params_default(&prm);
  stiff_bob_fixed_k16s2_init_params(&x, NULL, NULL, &prm);
  int n_ref = (int)lround(10 * sqrt(2 * prm.k) / 0.25);
  for (int n = 0; n < n_ref; n++)
    ck_assert_int_eq(stiff_bob_fixed_k16s2_step(&x, 10.0 / n_ref, &prm, NULL), stiff_bob_fixed_k16s2_OK);
  double com[2] = {(x.q[0] + x.q[2]) / 2, (x.q[1] + x.q[3]) / 2};
  static const double hw[2] = {10, 30}, bound[2] = {1.7e-4, 1.1e-4};
  for (int c = 0; c < 2; c++) {
    BobRun r = run_bob(prm.k, hw[c], 10);
    ck_assert_msg(!r.n.failed, "h omega = %g: a step failed", hw[c]);
    double err = fmax(fabs(r.com[0] - com[0]), fabs(r.com[1] - com[1]));
    ck_assert_msg(err <= bound[c], "h omega = %g: slow error %.3g > %.3g", hw[c], err, bound[c]);
  }
}
END_TEST

/* A step too long for the Newton iteration (h omega = 100 at k = 1e4, h =
 * 0.71: the spring turns too far over it for a J frozen at one point)
 * fails; the state is unchanged to the byte. */
START_TEST(test_bob_failed_step_rolls_back) {
  stiff_bob_newton_k16s2_state x, before;
  stiff_bob_newton_k16s2_params prm;
  stiff_bob_newton_k16s2_params_default(&prm);
  memset(&x, 0, sizeof x);
  stiff_bob_newton_k16s2_init_params(&x, NULL, NULL, &prm);
  for (int n = 0; n < 3; n++)
    ck_assert_int_eq(stiff_bob_newton_k16s2_step(&x, 0.07, &prm, NULL), stiff_bob_newton_k16s2_OK);
  memcpy(&before, &x, sizeof x);
  int rc = stiff_bob_newton_k16s2_step(&x, 0.71, &prm, NULL);
  ck_assert_int_ne(rc, stiff_bob_newton_k16s2_OK);
  ck_assert_msg(!memcmp(&before, &x, sizeof x), "the failed step (%s) changed the state",
                stiff_bob_newton_k16s2_strerror(rc));
}
END_TEST

START_TEST(test_refused) {
  static const struct {
    const char *args, *says;
  } cases[] = {
      {"--iteration newton --wide-step --check ../models/fpu.ham", "error: --iteration newton cannot be used with --wide-step"},
      {"--iteration newton -s 9 --check ../models/fpu.ham", "error: --iteration newton needs a smaller -s (s=9 > 8)"},
      {"--iteration newtn --check ../models/fpu.ham", "error: --iteration needs 'auto', 'fixed' or 'newton', got 'newtn'"},
  };
  char out[4096];
  for (int c = 0; c < 3; c++) {
    ck_assert_msg(generator_output(cases[c].args, out, sizeof out) != 0, "%s: accepted", cases[c].args);
    ck_assert_msg(strstr(out, cases[c].says) != NULL, "%s said:\n%s", cases[c].args, out);
  }
  ck_assert_int_eq(generator_output("--iteration newton --check ../models/fpu.ham", out, sizeof out), 0);
  ck_assert_msg(strstr(out, "iteration: newton") != NULL, "--check said:\n%s", out);
  /* with --batch (refused before its lanes took the scalar step: tests/check_batch.c) */
  ck_assert_int_eq(generator_output("--iteration newton --batch 2 --check ../models/fpu.ham", out, sizeof out), 0);
  ck_assert_int_eq(generator_output("--batch 2 --check ../models/stiff_bob.ham", out, sizeof out), 0);
  ck_assert_msg(strstr(out, "iteration: auto: sweeps, then newton") != NULL, "auto with --batch said:\n%s", out);
  ck_assert_int_eq(generator_output("--iteration newton --multiplier const --check ../models/pendulum.ham", out, sizeof out), 0);
  /* the poly family, the default with constraints (refused before it had Newton) */
  ck_assert_int_eq(generator_output("--iteration newton --check ../models/pendulum.ham", out, sizeof out), 0);
  ck_assert_msg(strstr(out, "iteration: newton") != NULL, "--check said:\n%s", out);
}
END_TEST

Suite *newton_suite(void) {
  Suite *s = suite_create("newton");
  TCase *tc = tcase_create("stiff FPU");
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, test_matrix_is_the_sweeps_jacobian);
  tcase_add_test(tc, test_converges_at_long_steps);
  tcase_add_test(tc, test_slow_motion);
  tcase_add_test(tc, test_adiabatic_invariant);
  tcase_add_test(tc, test_failed_step_rolls_back);
  tcase_add_test(tc, test_refused);
  suite_add_tcase(s, tc);
  TCase *bob = tcase_create("stiff bob");
  tcase_set_timeout(bob, 120);
  tcase_add_test(bob, test_bob_converges);
  tcase_add_test(bob, test_bob_long_step_iterations);
  tcase_add_test(bob, test_bob_slow_motion);
  tcase_add_test(bob, test_bob_failed_step_rolls_back);
  suite_add_tcase(s, bob);
  return s;
}
