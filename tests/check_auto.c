/* check_auto.c - Check suite for --iteration auto, the default
 * (gen/main.c's rule on gen/stiffness.c's estimate; gen/emit_newton.c's
 * sweeps that hand over to Newton):
 *
 *   decision  a model that is not stiff by the rule (omega_fast / omega_slow
 *             below 75 at q0: the paper's four models, Kepler, the FPU chain
 *             at its default omega = 50) and a stiff one Newton cannot take
 *             (a stiff chain of m = 40 > 32) get the code of --iteration
 *             fixed, byte for byte; --check says which ran.
 *   fpu       the FPU chain at omega = 1000 (tests/models/fpu_stiff.ham),
 *             HBVM(4,2): at h omega = 0.1 the sweeps converge fast, Newton
 *             never runs and the trajectory is the fixed-point solver's bit
 *             for bit; at h omega = 10 and 100 the first step's sweeps are
 *             slow, Newton takes over and, from the second step on, runs
 *             alone (x->hnewton), converging in a bounded number of
 *             iterations with H at round-off.
 *   bob       the stiff bob (--multiplier const) at h omega = 10: converges,
 *             g and H at round-off. In the default poly family: at h omega =
 *             1/4 the fixed-point solver's trajectory bit for bit; at 10
 *             Newton in every step, g, H and the hidden constraint at
 *             round-off; a failed step rolls back byte-exact.
 *   reuse     the Newton matrix's factor kept across steps at one h while
 *             the iteration contracts fast; refreshed at a new h.
 *   rollback  a step that fails after both iterations leaves the state
 *             byte-identical (the kept factor included); NAME_strerror
 *             names both iterations.
 * The suite is auto_suite(); the project's runner adds it. */
#define _POSIX_C_SOURCE 200809L /* mkstemp */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bob_auto_k16s2.h"
#include "bob_polyauto_k16s2.h"
#include "stiff_bob_polyfixed_k16s2.h"
#include "fpu_stiff_fixed_k4s2.h"
#include "fpu_stiff_k4s2.h"
#include "generate.h"

Suite *auto_suite(void);

/* ---- the decision at generation time ---- */

/* Default (auto) against --iteration fixed: the same NAME.c, to the byte.
 * Fails on a generator that emits the Newton-capable step for them. */
START_TEST(test_not_stiff_is_fixed) {
  static const char *const models[] = {"pendulum", "conical", "modified", "satellites", "kepler", "fpu"};
  for (int i = 0; i < 6; i++) {
    char path[64];
    snprintf(path, sizeof path, "../models/%s.ham", models[i]);
    char *text = read_text(path);
    ck_assert_ptr_nonnull(text);
    char *a = generate_source(text, "-s 2"), *b = generate_source(text, "-s 2 --iteration fixed");
    ck_assert_ptr_nonnull(a);
    ck_assert_ptr_nonnull(b);
    ck_assert_msg(!strcmp(a, b), "%s: auto's code is not --iteration fixed's", models[i]);
    free(a);
    free(b);
    free(text);
  }
}
END_TEST

/* A stiff model above m = 32 (a chain of 40 stiff springs, omega_fast /
 * omega_slow about 2000) gets the fixed-point code too: Newton's unrolled
 * factorisation would grow like m^3. Fails without the cap. */
START_TEST(test_large_stiff_is_fixed) {
  static const char text[] = "N = 40\nvariables q[N]\n"
                             "U = 1e6 * sum(i in 2..N, (q[i] - q[i-1])^2) / 2 + sum(i in 1..N, q[i]^2) / 2\n"
                             "q0 = [0.01 * i for i in 1..N]\np0 = [0 for i in 1..N]\n";
  char *a = generate_source(text, "-s 2"), *b = generate_source(text, "-s 2 --iteration fixed");
  ck_assert_ptr_nonnull(a);
  ck_assert_ptr_nonnull(b);
  ck_assert_msg(!strcmp(a, b), "m = 40: auto's code is not --iteration fixed's");
  free(a);
  free(b);
}
END_TEST

/* Above m = 32 the rolled form's band loops take Newton (no constraints):
 * the FPU chain of 500 pairs at omega = 1000 (m = 1000), whose frequencies
 * at q0 split at 1000 / 1.98, gets the auto step with the rolled Newton
 * kernels, not the fixed-point code. Fails on a generator that does not
 * estimate m > 200 or caps auto at m = 32. */
START_TEST(test_large_rolled_stiff_is_auto) {
  char out[8192];
  ck_assert_int_eq(generator_output("--check models/fpu_n500.ham", out, sizeof out), 0);
  ck_assert_msg(strstr(out, "iteration: auto: sweeps, then newton where they contract slowly, in the rolled form's band "
                            "loops (stiff: the frequencies at q0 split at 1e+03 / 1.98 = 504 >= 75") != NULL,
                "said:\n%s", out);
  char *text = read_text("models/fpu_n500.ham");
  ck_assert_ptr_nonnull(text);
  char *a = generate_source(text, "-s 2"), *b = generate_source(text, "-s 2 --iteration fixed");
  ck_assert_ptr_nonnull(a);
  ck_assert_ptr_nonnull(b);
  ck_assert_msg(strstr(a, "_nband_factor_c(") && strstr(a, "_anderson("), "no rolled Newton kernels under auto");
  ck_assert_ptr_null(strstr(b, "_nband_factor_c("));
  free(a);
  free(b);
  free(text);
}
END_TEST

/* A long chain of equal soft springs (m = 600, the rolled form's size) has
 * omega_fast / omega_slow of about 2 m / pi = 380, but no gap between its
 * frequencies wider than 2: not stiff, the code of --iteration fixed byte
 * for byte, and --check says why. A 25 x 25 lattice of stiff springs is
 * stiff (its frequencies split at 126 / 1) but its Hess U is a band of about
 * 25 each side at best, over the rolled Newton's 16: the form does not take
 * its Newton matrix and auto falls back to the fixed-point code, with a
 * note (the straight-line Newton would be 4 MB of C). */
START_TEST(test_large_wide_spectrum_is_fixed) {
  static const char soft[] = "N = 600\nvariables q[N]\n"
                             "U = sum(i in 2..N, (q[i] - q[i-1])^2) / 2 + q[1]^2 / 2\n"
                             "q0 = [0.001 * i for i in 1..N]\np0 = [0 for i in 1..N]\n";
  static const char wide[] =
      "N = 25\nvariables q[N * N]\n"
      "U = 1e6 * sum(i in 1..N, j in 1..N - 1, (q[N * (i - 1) + j + 1] - q[N * (i - 1) + j])^2) / 2\n"
      "  + 1e6 * sum(i in 1..N - 1, j in 1..N, (q[N * i + j] - q[N * (i - 1) + j])^2) / 2 + sum(i in 1..N * N, q[i]^2) / 2\n"
      "q0 = [0.001 * i for i in 1..N * N]\np0 = [0 for i in 1..N * N]\n";
  const char *const texts[] = {soft, wide};
  for (int t = 0; t < 2; t++) {
    char *a = generate_source(texts[t], "-s 2"), *b = generate_source(texts[t], "-s 2 --iteration fixed");
    ck_assert_ptr_nonnull(a);
    ck_assert_ptr_nonnull(b);
    ck_assert_msg(!strcmp(a, b), "chain %d: auto's code is not --iteration fixed's", t);
    free(a);
    free(b);
  }
  char path[] = "/tmp/hbvm-chain-XXXXXX", args[128], out[8192];
  int fd = mkstemp(path);
  ck_assert_int_ge(fd, 0);
  close(fd);
  FILE *f = fopen(path, "w");
  ck_assert_ptr_nonnull(f);
  fputs(soft, f);
  fclose(f);
  snprintf(args, sizeof args, "--check %s", path);
  int rc = generator_output(args, out, sizeof out);
  remove(path);
  ck_assert_int_eq(rc, 0);
  ck_assert_msg(strstr(out, "iteration: auto: fixed (fixed-point sweeps; not stiff: the widest gap between the "
                            "frequencies at q0 is ") && strstr(out, "wide without a gap)"), "said:\n%s", out);
}
END_TEST

/* --check names the solver, and the reason. */
START_TEST(test_check_says) {
  static const struct {
    const char *args, *says;
  } cases[] = {
      {"--check ../models/satellites.ham", "iteration: auto: fixed (fixed-point sweeps; not stiff: omega_fast / "
                                           "omega_slow = 0.637 / 0.0114 = 55.8 < 75 at q0)"},
      {"--check ../models/stiff_bob.ham", "iteration: auto: sweeps, then newton where they contract slowly (stiff: "
                                          "omega_fast / omega_slow = 100 / 0.937 = 107 >= 75 at q0"},
      {"--check --multiplier const ../models/stiff_bob.ham", "iteration: auto: sweeps, then newton where they "
                                                             "contract slowly (stiff: omega_fast / omega_slow = 100 / "
                                                             "0.937 = 107 >= 75 at q0"},
      {"--check models/fpu_stiff.ham", "iteration: auto: sweeps, then newton"},
      {"--check --iteration fixed models/fpu_stiff.ham", "iteration: fixed (fixed-point sweeps, given with --iteration "
                                                         "fixed)"},
  };
  char out[8192];
  for (int c = 0; c < 5; c++) {
    ck_assert_msg(generator_output(cases[c].args, out, sizeof out) == 0, "%s: refused:\n%s", cases[c].args, out);
    ck_assert_msg(strstr(out, cases[c].says) != NULL, "%s said:\n%s", cases[c].args, out);
  }
}
END_TEST

/* ---- the FPU chain at omega = 1000 ---- */

typedef struct {
  int steps, failed, max_iters, max_newton, max_factors, newton_steps, sweeps_after_first;
  double newton, factors, dH;
  fpu_stiff_k4s2_state x;
} Run;

/* The auto step from the model's start (omega = 1000) to T in steps of h. */
static Run run_auto(double h, double T) {
  fpu_stiff_k4s2_params prm;
  Run r = {0};
  fpu_stiff_k4s2_params_default(&prm);
  fpu_stiff_k4s2_init_params(&r.x, NULL, NULL, &prm);
  double H0 = fpu_stiff_k4s2_energy(&r.x, &prm);
  r.steps = (int)lround(T / h);
  for (int n = 0; n < r.steps; n++) {
    fpu_stiff_k4s2_stats st;
    if (fpu_stiff_k4s2_step(&r.x, h, &prm, &st) != fpu_stiff_k4s2_OK) {
      r.failed = n + 1;
      break;
    }
    r.newton += st.newton;
    r.factors += st.factors;
    r.newton_steps += st.newton > 0;
    if (n > 0) r.sweeps_after_first += st.iters - st.newton;
    if (st.iters > r.max_iters) r.max_iters = st.iters;
    if (st.newton > r.max_newton) r.max_newton = st.newton;
    if (st.factors > r.max_factors) r.max_factors = st.factors;
    ck_assert_int_eq(st.jacobians, st.factors);
    r.dH = fmax(r.dH, fabs(fpu_stiff_k4s2_energy(&r.x, &prm) - H0));
  }
  r.newton /= r.steps;
  r.factors /= r.steps;
  return r;
}

/* h omega = 0.1: the sweeps converge (measured 5.0 a step), Newton never runs,
 * and q, p are the fixed-point solver's to the bit. */
START_TEST(test_fast_sweeps_stay) {
  Run r = run_auto(1e-4, 0.2);
  fpu_stiff_fixed_k4s2_state y;
  fpu_stiff_fixed_k4s2_init(&y, NULL, NULL);
  for (int n = 0; n < r.steps; n++) ck_assert_int_eq(fpu_stiff_fixed_k4s2_step(&y, 1e-4, NULL, NULL), 0);
  ck_assert_msg(!r.failed, "step %d failed", r.failed);
  ck_assert_msg(r.newton_steps == 0, "Newton ran in %d steps", r.newton_steps);
  ck_assert_msg(r.x.hnewton == 0, "hnewton = %g", r.x.hnewton);
  ck_assert_msg(!memcmp(r.x.q, y.q, sizeof y.q) && !memcmp(r.x.p, y.p, sizeof y.p), "not the fixed-point trajectory");
}
END_TEST

/* h omega = 10, 100: Newton in every step (the sweeps only in the first:
 * from then on |h| >= hnewton), at most 12 Newton iterations and 2
 * factorisations a step (measured 4.0 and 6.1 iterations, 1 factorisation),
 * H within the round-off bound of check_newton.c. */
START_TEST(test_stiff_steps_take_newton) {
  static const double hs[2] = {0.01, 0.1};
  for (int c = 0; c < 2; c++) {
    double hw = 1000 * hs[c];
    Run r = run_auto(hs[c], 2);
    double bound = 8 * DBL_EPSILON * (1 + hw) * 2 * sqrt(r.steps);
    ck_assert_msg(!r.failed, "h omega = %g: step %d failed", hw, r.failed);
    ck_assert_msg(r.newton_steps == r.steps, "h omega = %g: Newton in %d of %d steps", hw, r.newton_steps, r.steps);
    ck_assert_msg(r.sweeps_after_first == 0, "h omega = %g: %d sweeps after the first step", hw, r.sweeps_after_first);
    ck_assert_msg(r.x.hnewton == hs[c], "h omega = %g: hnewton = %g", hw, r.x.hnewton);
    ck_assert_msg(r.max_newton <= 12 && r.max_factors <= 2, "h omega = %g: %d iterations, %d factorisations", hw,
                  r.max_newton, r.max_factors);
    ck_assert_msg(r.dH <= bound, "h omega = %g: |H - H0| = %.3g > %.3g", hw, r.dH, bound);
  }
}
END_TEST

/* The factor is kept across steps at the same h while the iteration
 * contracts below NAME_REUSE (measured at h omega = 10: 2 factorisations in
 * 200 steps, 4.9 Newton iterations a step against 4.0 with a fresh factor
 * every step), and taken afresh when h changes. Fails where every step
 * factors (the first version). */
START_TEST(test_factor_reuse) {
  Run r = run_auto(0.01, 2);
  ck_assert_msg(!r.failed, "step %d failed", r.failed);
  ck_assert_msg(r.factors * r.steps <= 10, "%g factorisations in %d steps", r.factors * r.steps, r.steps);
  ck_assert_msg(r.newton <= 6, "%g Newton iterations a step", r.newton);
  ck_assert_msg(r.x.nfh == 0.01 && r.x.nfrate < 1e-3 /* NAME_REUSE */, "nfh %g, nfrate %g", r.x.nfh, r.x.nfrate);
  fpu_stiff_k4s2_stats st;
  ck_assert_int_eq(fpu_stiff_k4s2_step(&r.x, 0.011, NULL, &st), fpu_stiff_k4s2_OK);
  ck_assert_msg(st.factors >= 1 && r.x.nfh == 0.011, "at a new h: %d factorisations, nfh %g", st.factors, r.x.nfh);
}
END_TEST

/* A step that neither iteration can take (h = 20) fails, the state (hnewton
 * included) unchanged to the byte, after a sweep-only history and after a
 * Newton one; NAME_strerror names both iterations. */
START_TEST(test_failed_step_rolls_back) {
  static const double warm[2] = {1e-4, 0.01};
  for (int c = 0; c < 2; c++) {
    fpu_stiff_k4s2_state x, before;
    memset(&x, 0, sizeof x);
    fpu_stiff_k4s2_init(&x, NULL, NULL);
    for (int n = 0; n < 3; n++) ck_assert_int_eq(fpu_stiff_k4s2_step(&x, warm[c], NULL, NULL), fpu_stiff_k4s2_OK);
    memcpy(&before, &x, sizeof x);
    int rc = fpu_stiff_k4s2_step(&x, 20, NULL, NULL);
    ck_assert_int_ne(rc, fpu_stiff_k4s2_OK);
    ck_assert_msg(!memcmp(&before, &x, sizeof x), "the failed step (%s) changed the state", fpu_stiff_k4s2_strerror(rc));
  }
  ck_assert_str_eq(fpu_stiff_k4s2_strerror(fpu_stiff_k4s2_ENOCONV), "fixed-point and Newton iterations did not converge");
  ck_assert_str_eq(fpu_stiff_fixed_k4s2_strerror(fpu_stiff_fixed_k4s2_ENOCONV), "fixed-point iteration did not converge");
}
END_TEST

/* ---- with a constraint: the stiff bob, --multiplier const ---- */

/* k = 1e4, h omega = 10 over T = 10: every step converges, Newton in every
 * step, g within 2 ulps of its scale and H within the bound of check_newton.c. */
START_TEST(test_bob) {
  bob_auto_k16s2_params prm;
  bob_auto_k16s2_state x;
  bob_auto_k16s2_params_default(&prm);
  bob_auto_k16s2_init_params(&x, NULL, NULL, &prm);
  double H0 = bob_auto_k16s2_energy(&x, &prm), dH = 0, gmax = 0, hw = 10;
  int steps = (int)lround(10 * sqrt(2 * prm.k) / hw), newton_steps = 0;
  for (int n = 0; n < steps; n++) {
    bob_auto_k16s2_stats st;
    double g;
    ck_assert_msg(bob_auto_k16s2_step(&x, 10.0 / steps, &prm, &st) == bob_auto_k16s2_OK, "step %d failed", n + 1);
    newton_steps += st.newton > 0;
    bob_auto_k16s2_constraints(&x, &prm, &g);
    gmax = fmax(gmax, fabs(g));
    dH = fmax(dH, fabs(bob_auto_k16s2_energy(&x, &prm) - H0));
  }
  double bound = 8 * DBL_EPSILON * (1 + hw) * fabs(H0) * sqrt(steps);
  ck_assert_msg(newton_steps == steps, "Newton in %d of %d steps", newton_steps, steps);
  ck_assert_msg(gmax <= 2 * DBL_EPSILON, "|g| = %.3g", gmax);
  ck_assert_msg(dH <= bound, "|H - H0| = %.3g > %.3g", dH, bound);
}
END_TEST

/* ---- the stiff bob in the default poly family ---- */

/* h omega = 1/4 over T = 1 (566 steps): the sweeps converge (3.0 a step), and
 * q, p are those of the poly family's --iteration fixed to the bit. Fails on
 * a generator whose auto step changes what converging sweeps commit. */
START_TEST(test_bob_poly_fast_sweeps) {
  bob_polyauto_k16s2_params prm;
  bob_polyauto_k16s2_state x;
  stiff_bob_polyfixed_k16s2_state y;
  bob_polyauto_k16s2_params_default(&prm);
  bob_polyauto_k16s2_init_params(&x, NULL, NULL, &prm);
  stiff_bob_polyfixed_k16s2_init(&y, NULL, NULL);
  int steps = (int)lround(sqrt(2 * prm.k) / 0.25);
  for (int n = 0; n < steps; n++) {
    bob_polyauto_k16s2_stats st;
    ck_assert_int_eq(bob_polyauto_k16s2_step(&x, 1.0 / steps, &prm, &st), bob_polyauto_k16s2_OK);
    ck_assert_int_eq(st.newton, 0);
    ck_assert_int_eq(stiff_bob_polyfixed_k16s2_step(&y, 1.0 / steps, NULL, NULL), stiff_bob_polyfixed_k16s2_OK);
  }
  ck_assert_msg(!memcmp(x.q, y.q, sizeof x.q) && !memcmp(x.p, y.p, sizeof x.p), "auto left the fixed-point trajectory");
}
END_TEST

/* k = 1e4, h omega = 10 over T = 10 (measured 13.5 (17) Newton iterations a
 * step): Newton in every step, g and the hidden constraint within 2 ulps of
 * their scales, H within the bound of check_newton.c; then a step of h = 0.71
 * (h omega = 100) fails after both iterations and leaves the state, the kept
 * factor and hnewton included, byte-identical. Fails on a generator whose
 * auto keeps the sweeps for the poly family (every step fails there). */
START_TEST(test_bob_poly) {
  bob_polyauto_k16s2_params prm;
  bob_polyauto_k16s2_state x, before;
  bob_polyauto_k16s2_params_default(&prm);
  memset(&x, 0, sizeof x);
  bob_polyauto_k16s2_init_params(&x, NULL, NULL, &prm);
  double H0 = bob_polyauto_k16s2_energy(&x, &prm), dH = 0, gmax = 0, hcmax = 0, hw = 10;
  int steps = (int)lround(10 * sqrt(2 * prm.k) / hw), newton_steps = 0;
  for (int n = 0; n < steps; n++) {
    bob_polyauto_k16s2_stats st;
    double g, gp;
    ck_assert_msg(bob_polyauto_k16s2_step(&x, 10.0 / steps, &prm, &st) == bob_polyauto_k16s2_OK, "step %d failed", n + 1);
    newton_steps += st.newton > 0;
    bob_polyauto_k16s2_constraints(&x, &prm, &g);
    bob_polyauto_k16s2_hidden(&x, &prm, &gp);
    gmax = fmax(gmax, fabs(g));
    hcmax = fmax(hcmax, fabs(gp));
    dH = fmax(dH, fabs(bob_polyauto_k16s2_energy(&x, &prm) - H0));
  }
  double bound = 8 * DBL_EPSILON * (1 + hw) * fabs(H0) * sqrt(steps);
  ck_assert_msg(newton_steps == steps, "Newton in %d of %d steps", newton_steps, steps);
  ck_assert_msg(gmax <= 2 * DBL_EPSILON && hcmax <= 2 * DBL_EPSILON, "|g| = %.3g, hidden %.3g", gmax, hcmax);
  ck_assert_msg(dH <= bound, "|H - H0| = %.3g > %.3g", dH, bound);
  memcpy(&before, &x, sizeof x);
  int rc = bob_polyauto_k16s2_step(&x, 0.71, &prm, NULL);
  ck_assert_int_ne(rc, bob_polyauto_k16s2_OK);
  ck_assert_msg(!memcmp(&before, &x, sizeof x), "the failed step (%s) changed the state", bob_polyauto_k16s2_strerror(rc));
}
END_TEST

Suite *auto_suite(void) {
  Suite *s = suite_create("auto");
  TCase *tc = tcase_create("decision");
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, test_not_stiff_is_fixed);
  tcase_add_test(tc, test_large_stiff_is_fixed);
  tcase_add_test(tc, test_large_rolled_stiff_is_auto);
  tcase_add_test(tc, test_large_wide_spectrum_is_fixed);
  tcase_add_test(tc, test_check_says);
  suite_add_tcase(s, tc);
  TCase *fpu = tcase_create("fpu");
  tcase_set_timeout(fpu, 60);
  tcase_add_test(fpu, test_fast_sweeps_stay);
  tcase_add_test(fpu, test_stiff_steps_take_newton);
  tcase_add_test(fpu, test_factor_reuse);
  tcase_add_test(fpu, test_failed_step_rolls_back);
  tcase_add_test(fpu, test_bob);
  tcase_add_test(fpu, test_bob_poly_fast_sweeps);
  tcase_add_test(fpu, test_bob_poly);
  suite_add_tcase(s, fpu);
  return s;
}
