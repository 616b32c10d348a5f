/* check_switch.c - steps ended on the switching points (runtime/switch.c),
 * on solvers of tests/models/bounce.ham (abs: the force jumps) and
 * polymer_wall.ham (min and max with constraints: U is C^1) run through
 * hbvmrt_main as a generated driver runs them (the adapters below are
 * emit_main.c's).
 *
 *   bounce   the closed form (period 4 sqrt 2): at --tol 1e-6 .. 1e-10 the
 *            error at T = 10 is within TOL T (the tolerance's meaning,
 *            --help), 4 switches; before (--no-switch, as the driver was)
 *            every such run failed at the first bounce, t = sqrt 2, the
 *            steps falling to 1e-10 with "did not converge" (NAME_ETOL's
 *            message now);
 *   polymer  against the same model at s = 4 (order 8), fixed h = 2.5e-4
 *            with the switching (1e-14 from h = 5e-4): at --tol 1e-6 ..
 *            1e-10 within 10 TOL T; --no-switch ends 1e3 to 1e6 TOL off.
 *            Fixed steps with the switching are of order 4 = 2s again
 *            (error ratio 16 per halving of h, measured 15.9 and 16.0;
 *            without it 1.6 and 1.7);
 *   wells    floor (in mod): the closed form of tests/models/wells.ham; at
 *            --tol 1e-6, 1e-8, 1e-10 within TOL T, 7 switches; --no-switch
 *            fails at the first cusp;
 *   hard     the polymer on a hard wall (the force jumps, polymer_hard.ham)
 *            with --multiplier const: --no-switch stops at the first contact
 *            (t = 1.34), as issue 31 saw; with the switching it runs to T,
 *            within 10 TOL T of the reference (s = 4, h = 2.5e-4) at --tol
 *            1e-6 and 1e-7. */
#define _POSIX_C_SOURCE 200809L
#include <check.h>
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bounce_k16s2.h"
#include "driver_adapters.h"
#include "wells_k16s2.h"
#include "hbvmrt.h"
#include "polymer_hard4_k4s4.h"
#include "polymer_hard_c_k2s2.h"
#include "polymer_wall4_k4s4.h"
#include "polymer_wall_k2s2.h"

Suite *switch_suite(void);

/* The driver's adapters and model description of solver P with switching
 * functions (as emit_main.c writes them for a double solver). */
#define SW_MODEL(P)                                                                                                 \
  DRIVER_ADAPTERS(P)                                                                                                \
  static void P##_switch_(const void *x, const void *prm, double *v) { P##_switch(x, prm, v); }                     \
  static void P##_restart_(void *x) { P##_restart(x); }                                                             \
  static const hbvmrt_model P##_model = {                                                                           \
      #P, P##_M, P##_NU, P##_K, P##_S, sizeof(P##_state), sizeof(P##_params), offsetof(P##_state, t),               \
      offsetof(P##_state, q), offsetof(P##_state, p), offsetof(P##_state, lambda), 0, NULL, NULL, NULL, P##_init_,   \
      P##_pd_, P##_step_, P##_strerror, P##_energy_, P##_g_, P##_hc_, NULL, NULL, NULL, DBL_EPSILON, P##_adapt_,    \
      P##_dense_, 0, NULL, NULL, NULL, NULL};                                                                       \
  static const hbvmrt_switching P##_switching = {P##_NSWITCH, P##_switch_kinds, P##_switch_what, P##_switch_,        \
                                                 P##_restart_};

SW_MODEL(bounce_k16s2)
SW_MODEL(wells_k16s2)
SW_MODEL(polymer_wall_k2s2)
SW_MODEL(polymer_wall4_k4s4)
SW_MODEL(polymer_hard_c_k2s2)
SW_MODEL(polymer_hard4_k4s4)

#define MAXCOL 32

static char run_err[4096]; /* the stderr of the last run() */

/* Run the driver of md with the options in args (spaces between); the last
 * CSV row (ncol values) into last. Returns the exit status. */
static int run(const hbvmrt_model *md, const hbvmrt_switching *sw, const char *args, double *last, int ncol) {
  char csvpath[] = "/tmp/hbvm-switch-XXXXXX", line[4096], buf[512];
  int fc = mkstemp(csvpath);
  ck_assert(fc >= 0);
  close(fc);
  snprintf(buf, sizeof buf, "%s --quiet --csv %s %s", md->name, csvpath, args);
  int status = driver_run_captured(md, sw, buf, run_err, sizeof run_err);
  FILE *f = fopen(csvpath, "r");
  ck_assert(f != NULL);
  while (fgets(line, sizeof line, f)) {
    char *s = line;
    if (line[0] == 't') continue;
    for (int k = 0; k < ncol; k++) {
      last[k] = strtod(s, &s);
      if (*s == ',') s++;
    }
  }
  fclose(f);
  unlink(csvpath);
  return status;
}

/* The summary's count of switches crossed (-1 when it has none). */
static long switches(void) {
  const char *s = strstr(run_err, " switches=");
  return s ? strtol(s + 10, NULL, 10) : -1;
}

/* The bounce at t: y'' = -sign y from y = 1 at rest (x = cos t beside it). */
static void bounce_exact(double t, double *q, double *p) {
  double t1 = sqrt(2.0), tau = fmod(t, 4 * t1), u;
  q[0] = cos(t);
  p[0] = -sin(t);
  if (tau <= t1) {
    q[1] = 1 - tau * tau / 2;
    p[1] = -tau;
  } else if (tau <= 3 * t1) {
    u = tau - t1;
    q[1] = -t1 * u + u * u / 2;
    p[1] = -t1 + u;
  } else {
    u = tau - 3 * t1;
    q[1] = t1 * u - u * u / 2;
    p[1] = t1 - u;
  }
}

/* max |q - qr|, |p - pr| of a row (t, q[m], p[m], ...) against a reference row. */
static double row_error(const double *row, const double *ref, int m) {
  double e = 0;
  for (int i = 1; i <= 2 * m; i++) e = fmax(e, fabs(row[i] - ref[i]));
  return e;
}

static const double tols[] = {1e-6, 1e-7, 1e-8, 1e-9, 1e-10};

START_TEST(bounce_adaptive)
{
  double row[MAXCOL], ref[MAXCOL], T = 10, tol = tols[_i];
  char args[128];
  snprintf(args, sizeof args, "-T %g --tol %g", T, tol);
  ck_assert_msg(run(&bounce_k16s2_model, &bounce_k16s2_switching, args, row, 6) == 0, "%s: %s", args, run_err);
  ck_assert_double_eq(row[0], T);
  ref[0] = T;
  bounce_exact(T, ref + 1, ref + 3);
  double err = row_error(row, ref, 2);
  if (getenv("HBVM_SWITCH_TABLE")) printf("bounce --tol %g: error %.3e, switches %ld\n", tol, err, switches());
  ck_assert_int_eq(switches(), 4);
  ck_assert_msg(err <= tol * T, "%s: error %.3e above TOL T = %.1e", args, err, tol * T);
}
END_TEST

/* Before: the first bounce stopped every adaptive run. */
START_TEST(bounce_without_switching)
{
  double row[MAXCOL];
  ck_assert_int_eq(run(&bounce_k16s2_model, &bounce_k16s2_switching, "-T 10 --tol 1e-8 --no-switch", row, 6), 2);
  ck_assert_msg(strstr(run_err, "status=step_failed") && switches() == 0, "%s", run_err);
  ck_assert_msg(fabs(row[0] - sqrt(2.0)) < 1e-6, "failed at t = %.17g", row[0]);
}
END_TEST

/* A row of wells (tests/models/wells.ham) at t. */
static void wells_exact(double t, double *q, double *p) {
  double tau = 2 * asin(2.0 / 3), k = floor(t / tau + 0.5);
  q[0] = 1 + 2 * k + 1.5 * sin(t - k * tau);
  p[0] = 1.5 * cos(t - k * tau);
}

static const double wells_tols[] = {1e-6, 1e-8, 1e-10};

START_TEST(wells_adaptive)
{
  double row[MAXCOL], ref[MAXCOL], T = 10, tol = wells_tols[_i];
  char args[128];
  snprintf(args, sizeof args, "-T %g --tol %g", T, tol);
  ck_assert_msg(run(&wells_k16s2_model, &wells_k16s2_switching, args, row, 4) == 0, "%s: %s", args, run_err);
  wells_exact(T, ref + 1, ref + 2);
  double err = row_error(row, ref, 1);
  if (getenv("HBVM_SWITCH_TABLE")) printf("wells --tol %g: error %.3e, switches %ld\n", tol, err, switches());
  ck_assert_int_eq(switches(), 7);
  ck_assert_msg(err <= tol * T, "%s: error %.3e above TOL T", args, err);
  snprintf(args, sizeof args, "-T %g --tol %g --no-switch", T, tol);
  ck_assert_int_eq(run(&wells_k16s2_model, &wells_k16s2_switching, args, row, 4), 2);
}
END_TEST

/* The reference of the polymer at T = 5: s = 4, fixed steps with the switching. */
static const double *polymer_reference(void) {
  static double ref[MAXCOL];
  static int done;
  if (!done) {
    ck_assert_int_eq(run(&polymer_wall4_k4s4_model, &polymer_wall4_k4s4_switching, "-T 5 -h 0.00025", ref, 1 + 2 * 8), 0);
    ck_assert_int_eq(switches(), 12);
    done = 1;
  }
  return ref;
}

START_TEST(polymer_adaptive)
{
  double row[MAXCOL], T = 5, tol = tols[_i];
  const double *ref = polymer_reference();
  char args[128];
  snprintf(args, sizeof args, "-T %g --tol %g", T, tol);
  ck_assert_msg(run(&polymer_wall_k2s2_model, &polymer_wall_k2s2_switching, args, row, 17) == 0, "%s: %s", args, run_err);
  double err = row_error(row, ref, 8);
  long n = switches();
  snprintf(args, sizeof args, "-T %g --tol %g --no-switch", T, tol);
  ck_assert_int_eq(run(&polymer_wall_k2s2_model, &polymer_wall_k2s2_switching, args, row, 17), 0);
  double before = row_error(row, ref, 8);
  if (getenv("HBVM_SWITCH_TABLE"))
    printf("polymer --tol %g: error %.3e (--no-switch %.3e), switches %ld\n", tol, err, before, n);
  ck_assert_int_eq(n, 12);
  ck_assert_msg(err <= 10 * tol * T, "--tol %g: error %.3e above 10 TOL T", tol, err);
  ck_assert_msg(before > 100 * tol * T, "--tol %g --no-switch: error %.3e (the test would not fail before)", tol, before);
}
END_TEST

START_TEST(hard_wall_const)
{
  static const double tol[] = {1e-6, 1e-7};
  static double ref[MAXCOL];
  double row[MAXCOL], T = 5;
  char args[128];
  ck_assert_int_eq(run(&polymer_hard4_k4s4_model, &polymer_hard4_k4s4_switching, "-T 5 -h 0.00025", ref, 17), 0);
  ck_assert_int_eq(switches(), 17);
  snprintf(args, sizeof args, "-T %g --tol %g", T, tol[_i]);
  ck_assert_msg(run(&polymer_hard_c_k2s2_model, &polymer_hard_c_k2s2_switching, args, row, 17) == 0, "%s: %s", args,
                run_err);
  double err = row_error(row, ref, 8);
  if (getenv("HBVM_SWITCH_TABLE")) printf("hard wall, const, --tol %g: error %.3e, switches %ld\n", tol[_i], err, switches());
  ck_assert_int_eq(switches(), 17);
  ck_assert_msg(err <= 10 * tol[_i] * T, "%s: error %.3e above 10 TOL T", args, err);
  snprintf(args, sizeof args, "-T %g --tol %g --no-switch", T, tol[_i]);
  ck_assert_int_eq(run(&polymer_hard_c_k2s2_model, &polymer_hard_c_k2s2_switching, args, row, 17), 2);
  /* the step can only miss the tolerance at the kink: NAME_ETOL says so (it was
   * NAME_ENOCONV's "did not converge", which sent users to a smaller h) */
  ck_assert_msg(strstr(run_err, "error estimate over the tolerance down to the smallest step") && row[0] < 1.5,
                "t = %g: %s", row[0], run_err);
}
END_TEST

/* Fixed steps cut on the points are of order 2s = 4 again. */
START_TEST(polymer_fixed_order)
{
  static const char *const hs[] = {"-T 5 -h 0.004", "-T 5 -h 0.002", "-T 5 -h 0.001"};
  const double *ref = polymer_reference();
  double row[MAXCOL], err[3];
  for (int i = 0; i < 3; i++) {
    ck_assert_int_eq(run(&polymer_wall_k2s2_model, &polymer_wall_k2s2_switching, hs[i], row, 17), 0);
    ck_assert_int_eq(switches(), 12);
    err[i] = row_error(row, ref, 8);
  }
  if (getenv("HBVM_SWITCH_TABLE"))
    printf("polymer fixed h = 0.004, 0.002, 0.001: errors %.3e %.3e %.3e\n", err[0], err[1], err[2]);
  for (int i = 0; i < 2; i++)
    ck_assert_msg(err[i] / err[i + 1] > 12 && err[i] / err[i + 1] < 20, "%s: %.3e, half the step: %.3e (order 4: 16x)",
                  hs[i], err[i], err[i + 1]);
}
END_TEST

Suite *switch_suite(void) {
  Suite *s = suite_create("switch");
  TCase *tc = tcase_create("switch");
  tcase_set_timeout(tc, 300);
  tcase_add_loop_test(tc, bounce_adaptive, 0, 5);
  tcase_add_test(tc, bounce_without_switching);
  tcase_add_loop_test(tc, wells_adaptive, 0, 3);
  tcase_add_loop_test(tc, polymer_adaptive, 0, 5);
  tcase_add_test(tc, polymer_fixed_order);
  tcase_add_loop_test(tc, hard_wall_const, 0, 2);
  suite_add_tcase(s, tc);
  return s;
}
