/* check_lean.c - the generated code does only what the model needs: equal
 * mass matrices written differently give the same code, no multiplier code
 * without constraints, no force code without a potential; the float
 * variant keeps order and conservation at float round-off; and the
 * --wide-step variant computes the same steps as the double one and keeps
 * H at round-off over 10^5 steps, in double and in float. */
#define _POSIX_C_SOURCE 200809L
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "generate.h"
#include "pendulum_float_k2s2.h"
#include "pendulum_k2s2.h"
#include "pendulum_wide_k2s2.h"
#include "pendulum_floatwide_k2s2.h"

/* the sweep's temporaries: a function of its own, or inline in the fused step */
#define SWEEP_TEMPS(src) kernel_temporaries(src, strstr(src, "_sweep(") ? "_sweep(" : "the kernel sweep, inline")

START_TEST(equal_mass_matrices_give_equal_code) {
  static const char *const forms[] = {"M = [[2, 0], [0, 2]]", "M = diag(2, 2)", "M = 2", "M = diag(4/2, 2)"};
  char *first = NULL;
  for (size_t i = 0; i < sizeof forms / sizeof forms[0]; i++) {
    char text[256];
    snprintf(text, sizeof text, "variables x, y\n%s\nU = y\ng = x^2 + y^2 - 1\nq0 = [0, -1]\np0 = [1, 0]\n", forms[i]);
    char *src = generate_source(text, "-s 2");
    ck_assert_msg(src != NULL, "generation failed for %s", forms[i]);
    if (!first) first = src;
    else {
      ck_assert_msg(strcmp(first, src) == 0, "'%s' gives different code from '%s'", forms[i], forms[0]);
      free(src);
    }
  }
  ck_assert_msg(strstr(first, "0.5 *") || strstr(first, "* 0.5"), "M^-1 = 0.5 I should appear as a factor 0.5");
  free(first);
}
END_TEST

/* The text of an unconstrained model with m coordinates and the dense
 * constant M_ij = 2 delta_ij + 2^-|i-j| (symmetric positive definite).
 * malloc'd. */
static char *dense_mass_model(int m) {
  size_t cap = (size_t)m * (size_t)m * 24 + 4096, n = 0;
  char *text = malloc(cap);
  ck_assert_ptr_nonnull(text);
  n += (size_t)snprintf(text + n, cap - n, "N = %d\nvariables q[N]\nM = [", m);
  for (int i = 0; i < m; i++) {
    n += (size_t)snprintf(text + n, cap - n, "%s[", i ? ",\n  " : "");
    for (int j = 0; j < m; j++) n += (size_t)snprintf(text + n, cap - n, "%s%.17g", j ? ", " : "", (i == j ? 2 : 0) + ldexp(1, -abs(i - j)));
    n += (size_t)snprintf(text + n, cap - n, "]");
  }
  snprintf(text + n, cap - n, "]\nU = sum(i in 2..N, (q[i] - q[i-1])^2) / 2 + sum(i in 1..N, q[i]^4) / 4\n"
                              "q0 = [0.1 * i for i in 1..N]\np0 = [0 for i in 1..N]\n");
  return text;
}

/* Issue 13 item 4: a dense constant M of m coordinates used to cost m^2
 * lines per product M^-1 v (2.9 MB of C at m = 80, 11.6 MB at m = 160).
 * Past --mass-loop products it is a loop over the table of M^-1, so the C
 * is the table (m^2 literals, about 25 bytes each) plus O(m) lines per
 * product (its vector named entry by entry): under 100 m^2 bytes, against
 * 460 m^2 before. Timing-free: bytes of emitted C. The
 * straight-line form is still there below the threshold and on request. */
START_TEST(dense_mass_is_a_table) {
  static const int sizes[] = {80, 160};
  for (size_t c = 0; c < sizeof sizes / sizeof sizes[0]; c++) {
    int m = sizes[c];
    char *text = dense_mass_model(m);
    char *src = generate_source(text, "-s 2");
    ck_assert_msg(src != NULL, "m = %d: generation failed (or wrote more than 4 MiB)", m);
    size_t bytes = strlen(src);
    printf("lean: dense M, m = %d: %zu bytes of C\n", m, bytes);
    ck_assert_msg(bytes <= (size_t)100 * m * m, "m = %d: %zu bytes of C, more than 100 m^2", m, bytes);
    ck_assert_msg(strstr(src, "_minv[j][i] * v"), "m = %d: no loop over the table of M^-1", m);
    free(src);
    if (m == 80) { /* and the straight-line form on request: m^2 products a line each */
      src = generate_source(text, "-s 2 --mass-loop 1000000000");
      ck_assert_ptr_nonnull(src);
      ck_assert_msg(!strstr(src, "_minv[j][i]") && strlen(src) > (size_t)200 * m * m, "--mass-loop: %zu bytes",
                    strlen(src));
      free(src);
    }
    free(text);
  }
}
END_TEST

START_TEST(no_multiplier_code_without_constraints) {
  char *src = generate_source("variables x, y\nU = x^4 + y^4 + x*y\nq0 = [1, 0]\np0 = [0, 1]\n", "-s 2");
  ck_assert_ptr_nonnull(src);
  ck_assert_msg(!strstr(src, "A lambda = r"), "multiplier code in an unconstrained model");
  ck_assert_msg(!strstr(src, "g0["), "g(q0) used in an unconstrained model");
  ck_assert_msg(!strstr(src, "SINGTOL *"), "singularity test in an unconstrained model");
  free(src);
}
END_TEST

// A model without events has no event code (NAME_NEVENTS 0, no kernel,
// no tables); one event adds one kernel result and one function.
START_TEST(no_event_code_without_events) {
  const char *model = "variables x, y\nU = y\ng = x^2 + y^2 - 1\nq0 = [0, -1]\np0 = [1, 0]\n";
  char *src = generate_source(model, "-s 2");
  ck_assert_ptr_nonnull(src);
  ck_assert_msg(!strstr(src, "event"), "event code in a model without events");
  free(src);
  char with[256];
  snprintf(with, sizeof with, "%sevent cross = x + p[2]\n", model);
  src = generate_source(with, "-s 2");
  ck_assert_ptr_nonnull(src);
  ck_assert_msg(strstr(src, "_events(const") != NULL, "no NAME_events");
  ck_assert_msg(strstr(src, "q0[0] /* x */ + p0[1] /* p_y */"), "the event is not x + p_y");
  free(src);
}
END_TEST

START_TEST(no_force_code_without_potential) {
  /* a free particle: gamma_0 = p0, nothing to compute in the sweep */
  char *src = generate_source("variables x, y, z\nq0 = [0, 0, 0]\np0 = [1, 2, 3]\n", "-s 3");
  ck_assert_ptr_nonnull(src);
  ck_assert_int_eq(SWEEP_TEMPS(src), 0);
  free(src);
}
END_TEST

START_TEST(structural_zeros_never_multiplied) {
  /* a chain: each constraint touches 2 or 4 coordinates; the code may not
   * multiply by a literal 0 or 1 anywhere */
  char *src = generate_source("N = 6\nvariables x[N], y[N]\nU = sum(i in 1..N, y[i])\n"
                       "g = [x[1]^2 + y[1]^2 - 1, [(x[i] - x[i-1])^2 + (y[i] - y[i-1])^2 - 1 for i in 2..N]]\n"
                       "q0 = [[i for i in 1..N], [0 for i in 1..N]]\np0 = [0 for i in 1..2*N]\n",
                       "-s 2");
  ck_assert_ptr_nonnull(src);
  ck_assert_msg(!strstr(src, "* 0.0;") && !strstr(src, " 0.0 *"), "multiplication by zero in the code");
  ck_assert_msg(!strstr(src, "* 1.0;") && !strstr(src, " 1.0 *"), "multiplication by one in the code");
  free(src);
}
END_TEST

// A chain of 8 pendula whose constraints are listed in the given order.
static char *chain_in_order(const int order[8]) {
  char text[2048] = "N = 8\nvariables x[N], y[N]\nU = sum(i in 1..N, y[i])\ng = [";
  for (int k = 0; k < 8; k++) {
    char c[128];
    int i = order[k];
    if (i == 1) snprintf(c, sizeof c, "x[1]^2 + y[1]^2 - 1");
    else snprintf(c, sizeof c, "(x[%d] - x[%d])^2 + (y[%d] - y[%d])^2 - 1", i, i - 1, i, i - 1);
    strcat(text, c);
    strcat(text, k < 7 ? ", " : "]\n");
  }
  strcat(text, "q0 = [[i for i in 1..N], [0 for i in 1..N]]\np0 = [0 for i in 1..2*N]\n");
  return generate_source(text, "-s 2");
}

START_TEST(elimination_order_keeps_sparsity) {
  /* the multiplier matrix of a chain is tridiagonal in the natural order; in
   * a scrambled order, eliminating in the written order would create fill.
   * The minimum-degree order chosen by the generator makes both cost the same. */
  static const int natural[8] = {1, 2, 3, 4, 5, 6, 7, 8}, scrambled[8] = {1, 5, 3, 7, 2, 6, 4, 8};
  char *a = chain_in_order(natural), *b = chain_in_order(scrambled);
  ck_assert_ptr_nonnull(a);
  ck_assert_ptr_nonnull(b);
  ck_assert_int_eq(SWEEP_TEMPS(a), SWEEP_TEMPS(b));
  ck_assert_int_gt(SWEEP_TEMPS(a), 100);
  free(a);
  free(b);
}
END_TEST

// The float pendulum after n steps to t = 2, with the largest |H - H0|, |g|.
static void float_run(int n, double *dH, double *dg, pendulum_float_k2s2_state *out) {
  pendulum_float_k2s2_state x;
  pendulum_float_k2s2_init(&x, NULL, NULL);
  double H0 = pendulum_float_k2s2_energy(&x, NULL);
  *dH = *dg = 0;
  for (int i = 0; i < n; i++) {
    ck_assert_int_eq(pendulum_float_k2s2_step(&x, 2.0 / n, NULL, NULL), 0);
    pendulum_float_k2s2_real g;
    pendulum_float_k2s2_constraints(&x, NULL, &g);
    *dH = fmax(*dH, fabs(pendulum_float_k2s2_energy(&x, NULL) - H0));
    *dg = fmax(*dg, fabs(g));
  }
  *out = x;
}

START_TEST(float_order_and_conservation) {
  pendulum_float_k2s2_state a, b, c;
  double dH, dg;
  float_run(10, &dH, &dg, &a);
  float_run(20, &dH, &dg, &b);
  float_run(40, &dH, &dg, &c);
  /* Richardson: errors e(h) ~ C h^2, so (a - b) / (b - c) ~ 4 (p is of
   * order 2; the pendulum's q converges faster, as the paper's table shows) */
  double ratio = fabs(a.p[0] - b.p[0]) / fabs(b.p[0] - c.p[0]);
  ck_assert_msg(fabs(log2(ratio) - 2) < 0.2, "float HBVM(2,2): observed order %.2f", log2(ratio));
  const double eps = 1.1920928955078125e-07; /* FLT_EPSILON */
  ck_assert_msg(dH <= 8 * eps && dg <= 8 * eps, "float: |H - H0| = %.2e, |g| = %.2e (eps %.2e)", dH, dg, eps);
  ck_assert_msg(sizeof a.q[0] == sizeof(float), "the float solver's state is not float");
}
END_TEST

// --wide-step: every temporary and literal of the iteration's kernels (the
// sweep; with the polynomial multiplier also factor and project, which the
// iteration and the end of the step use), and no temporary elsewhere, is
// one precision wider than the state (long double for double, double for
// float). _i: 0 const, 1 poly; v: double, float.
START_TEST(wide_step_widens_only_the_iteration) {
  static const char *const flags[2][2] = {{"--wide-step --multiplier const", "--wide-step --real float --multiplier const"},
                                          {"--wide-step -s 3", "--wide-step --real float -s 3"}};
  static const char *const wide[2] = {"const long double t", "const double t"};
  static const char *const narrow[2] = {"const double t", "const float t"};
  static const char *const kernels[] = {"_sweep(", "_factor(", "_project_p1(", "_minv_p(", "_energy_kernel(", "_g(",
                                        "_hidden_kernel(", "_lambda0(", "_consistent("};
  int nwide = _i ? 3 : 1;
  for (int v = 0; v < 2; v++) {
    char *src = generate_source("variables x, y\nU = x^2 * y\ng = x^2 + y^2 - 1\nq0 = [0, -1]\np0 = [1, 0]\n", flags[_i][v]);
    ck_assert_ptr_nonnull(src);
    for (size_t k = 0; k < sizeof kernels / sizeof kernels[0]; k++) {
      const char *start = strstr(src, kernels[k]);
      ck_assert_msg(start || (!_i && k == 1) || (!_i && k == 2), "%s: no kernel %s", flags[_i][v], kernels[k]);
      if (!start) continue;
      const char *end = strstr(start, "\n}\n"), *w = strstr(start, wide[v]), *n = strstr(start, narrow[v]);
      ck_assert_ptr_nonnull(end);
      int is_wide = k < (size_t)nwide;
      ck_assert_msg(is_wide ? w && w < end : !w || w > end, "%s: %s %s", flags[_i][v], kernels[k],
                    is_wide ? "is not wide" : "has a wide temporary");
      ck_assert_msg(is_wide ? !n || n > end : 1, "%s: a %s inside %s", flags[_i][v], narrow[v], kernels[k]);
      for (const char *c = start; is_wide && c + 1 < end; c++) /* and its literals are wide too: no 0.5f */
        ck_assert_msg(!(c[0] >= '0' && c[0] <= '9' && c[1] == 'f'), "%s: a float literal in %s", flags[_i][v],
                      kernels[k]);
    }
    free(src);
  }
}
END_TEST

// The long-double sweep takes the same steps as the double one: after 1000
// steps of h = 0.05 the states agree to the round-off that accumulates
// (a few hundred ulps), and H and g are conserved as tightly.
START_TEST(wide_step_same_steps) {
  pendulum_k2s2_state a;
  pendulum_wide_k2s2_state b;
  pendulum_k2s2_init(&a, NULL, NULL);
  pendulum_wide_k2s2_init(&b, NULL, NULL);
  double H0 = pendulum_wide_k2s2_energy(&b, NULL), dH = 0, dg = 0, diff = 0;
  for (int i = 0; i < 1000; i++) {
    ck_assert_int_eq(pendulum_k2s2_step(&a, 0.05, NULL, NULL), 0);
    ck_assert_int_eq(pendulum_wide_k2s2_step(&b, 0.05, NULL, NULL), 0);
    double g;
    pendulum_wide_k2s2_constraints(&b, NULL, &g);
    dH = fmax(dH, fabs(pendulum_wide_k2s2_energy(&b, NULL) - H0));
    dg = fmax(dg, fabs(g));
    for (int j = 0; j < 2; j++) diff = fmax(diff, fmax(fabs(a.q[j] - b.q[j]), fabs(a.p[j] - b.p[j])));
  }
  const double eps = 2.220446049250313e-16;
  ck_assert_msg(diff <= 500 * eps, "double and wide step differ by %.2e after 1000 steps", diff);
  ck_assert_msg(dH <= 16 * eps && dg <= 64 * eps, "wide step: |H - H0| = %.2e, |g| = %.2e", dH, dg);
}
END_TEST

// Its round-off is a random walk at the scale of the long-double epsilon
// (1e-19): over 10^5 steps of h = 0.1, |H - H0| and |g| stay within the few
// ulps of evaluating H and g in double (measured: 3.3e-16 and 8.9e-16 over
// 10^7 steps, bench/results/longrun.txt). The double step drifts past this
// bound by 10^5 steps (max |H - H0| 1.8e-15 = 8 eps there).
START_TEST(wide_step_holds_H_at_roundoff) {
  pendulum_wide_k2s2_state x;
  pendulum_wide_k2s2_init(&x, NULL, NULL);
  double H0 = pendulum_wide_k2s2_energy(&x, NULL), dH = 0, dg = 0;
  for (long i = 0; i < 100000; i++) {
    ck_assert_int_eq(pendulum_wide_k2s2_step(&x, 0.1, NULL, NULL), 0);
    double g;
    pendulum_wide_k2s2_constraints(&x, NULL, &g);
    dH = fmax(dH, fabs(pendulum_wide_k2s2_energy(&x, NULL) - H0));
    dg = fmax(dg, fabs(g));
  }
  const double eps = 2.220446049250313e-16;
  ck_assert_msg(dH <= 4 * eps && dg <= 8 * eps, "wide step, 10^5 steps: |H - H0| = %.2e, |g| = %.2e", dH, dg);
}
END_TEST

// A float state stepped in double (--real float --wide-step) holds H within
// one float ulp over 10^5 steps of h = 0.1 (measured 0.5 eps to 10^6 steps);
// the float step drifts to 65 eps by then.
START_TEST(float_wide_step_holds_H) {
  pendulum_floatwide_k2s2_state x;
  pendulum_floatwide_k2s2_init(&x, NULL, NULL);
  double H0 = pendulum_floatwide_k2s2_energy(&x, NULL), dH = 0;
  for (long i = 0; i < 100000; i++) {
    ck_assert_int_eq(pendulum_floatwide_k2s2_step(&x, 0.1, NULL, NULL), 0);
    dH = fmax(dH, fabs(pendulum_floatwide_k2s2_energy(&x, NULL) - H0));
  }
  const double eps = 1.1920928955078125e-07; /* FLT_EPSILON */
  ck_assert_msg(dH <= 2 * eps, "float state, double step, 10^5 steps: |H - H0| = %.2e (eps %.2e)", dH, eps);
  ck_assert_msg(sizeof x.q[0] == sizeof(float), "the state is not float");
}
END_TEST

/* Every model of the fuzzing seeds that the generator accepts gives C that
 * compiles warning-free (-std=c99 -pedantic -Werror), in double with its
 * driver and in float (tests/fuzz/compile_corpus.sh; tests/fuzz/run.sh runs
 * it on the whole fuzzing corpus). It found a kernel split in parts with
 * no value crossing them, which declared the empty array w[0]. */
START_TEST(corpus_models_compile) {
  int rc = system("cd .. && tests/fuzz/compile_corpus.sh tests/fuzz/corpus");
  ck_assert_msg(rc == 0, "a model the generator accepts gives C that does not compile (see above)");
}
END_TEST

/* The iteration's limits are #ifndef-guarded macros that -D sets when the
 * solver is compiled (docs/api.md): with pendulum_k2s2_MAXITER=1 no step can
 * converge, so the first returns NAME_ENOCONV (1); with the default it
 * succeeds (0). */
START_TEST(limits_settable_with_D) {
  static const char *const prog = "#include \"pendulum_k2s2.h\"\n"
                                  "int main(void) { pendulum_k2s2_state x; pendulum_k2s2_init(&x, 0, 0);\n"
                                  "  return pendulum_k2s2_step(&x, 0.1, 0, 0); }\n";
  char dir[] = "/tmp/hbvm-limits-XXXXXX", cmd[1024];
  ck_assert(mkdtemp(dir) != NULL);
  snprintf(cmd, sizeof cmd, "%s/main.c", dir);
  FILE *f = fopen(cmd, "w");
  ck_assert(f != NULL);
  fputs(prog, f);
  fclose(f);
  static const char *const defs[2] = {"", "-Dpendulum_k2s2_MAXITER=1"};
  for (int v = 0; v < 2; v++) {
    snprintf(cmd, sizeof cmd, "cc -std=c99 -Wall -Werror %s -I../generated -o %s/a %s/main.c ../generated/pendulum_k2s2.c -lm",
             defs[v], dir, dir);
    ck_assert_msg(system(cmd) == 0, "%s failed", cmd);
    snprintf(cmd, sizeof cmd, "%s/a", dir);
    int rc = system(cmd);
    ck_assert_msg(WIFEXITED(rc) && WEXITSTATUS(rc) == v, "%s: step returned %d, want %d", defs[v],
                  WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, v);
  }
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  ck_assert_int_eq(system(cmd), 0);
}
END_TEST

/* NAME.c refuses to compile under -ffast-math and under -ffinite-math-only
 * alone (issue 30, item 9: with the latter, a step of h = inf returned 0 and
 * NaN in q), unless NAME_ALLOW_FAST_MATH is defined; plain flags compile. */
START_TEST(unsafe_math_refused) {
  static const struct { const char *flags; int ok; } cases[] = {
      {"", 1}, {"-ffast-math", 0}, {"-ffinite-math-only", 0}, {"-ffinite-math-only -Dpendulum_k2s2_ALLOW_FAST_MATH", 1}};
  char cmd[512];
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    snprintf(cmd, sizeof cmd, "cc -std=c99 %s -I../generated -fsyntax-only ../generated/pendulum_k2s2.c 2>/dev/null",
             cases[i].flags);
    int rc = system(cmd);
    ck_assert_msg((rc == 0) == cases[i].ok, "cc %s: exit %d, want %s", cases[i].flags, rc,
                  cases[i].ok ? "success" : "an #error");
  }
}
END_TEST

/* A model whose C would pass MAX_C_BYTES (32 MB) is refused with a message
 * naming the size and --stage-loop / --mass-loop, and nothing is written
 * (issue 30, item 10: variables x[100000] wrote 124 MB that no compiler
 * finished); 30000 coordinates would write 37.6 MB of straight-line code
 * (--rolled off: by default it is rolled, 0.3 MB, tests/check_reroll.c). */
START_TEST(huge_c_refused) {
  char dir[] = "/tmp/hbvm-huge-XXXXXX", cmd[1024];
  ck_assert(mkdtemp(dir) != NULL);
  snprintf(cmd, sizeof cmd, "%s/big.ham", dir);
  FILE *f = fopen(cmd, "w");
  ck_assert(f != NULL);
  fputs("variables x[30000]\nM = identity\nU = sum(i in 1..30000, x[i]^2)\n"
        "q0 = [1 for i in 1..30000]\np0 = [0 for i in 1..30000]\n", f);
  fclose(f);
  snprintf(cmd, sizeof cmd, "../gen/hbvmgen --rolled off -o %s %s/big.ham 2> %s/err", dir, dir, dir);
  int rc = system(cmd);
  ck_assert_msg(WIFEXITED(rc) && WEXITSTATUS(rc) == 1, "%s: exit %d, want 1", cmd, rc);
  snprintf(cmd, sizeof cmd, "%s/err", dir);
  char *err = read_text(cmd);
  ck_assert_msg(err && strstr(err, "would be 37.6 MB of C") && strstr(err, "--stage-loop"), "message: %s", err);
  free(err);
  snprintf(cmd, sizeof cmd, "test ! -e %s/big.c && test ! -e %s/big.h && rm -rf %s", dir, dir, dir);
  ck_assert_msg(system(cmd) == 0, "a file was written, or %s could not be removed", dir);
}
END_TEST

Suite *lean_suite(void) {
  Suite *s = suite_create("lean");
  TCase *tc = tcase_create("structure");
  tcase_set_timeout(tc, 180);
  tcase_add_test(tc, equal_mass_matrices_give_equal_code);
  tcase_add_test(tc, dense_mass_is_a_table);
  tcase_add_test(tc, no_event_code_without_events);
  tcase_add_test(tc, unsafe_math_refused);
  tcase_add_test(tc, huge_c_refused);
  tcase_add_test(tc, limits_settable_with_D);
  tcase_add_test(tc, no_multiplier_code_without_constraints);
  tcase_add_test(tc, no_force_code_without_potential);
  tcase_add_test(tc, structural_zeros_never_multiplied);
  tcase_add_test(tc, elimination_order_keeps_sparsity);
  tcase_add_test(tc, float_order_and_conservation);
  tcase_add_loop_test(tc, wide_step_widens_only_the_iteration, 0, 2);
  tcase_add_test(tc, wide_step_same_steps);
  tcase_add_test(tc, wide_step_holds_H_at_roundoff);
  tcase_add_test(tc, float_wide_step_holds_H);
  suite_add_tcase(s, tc);
  TCase *corpus = tcase_create("corpus"); /* make check-long */
  tcase_set_tags(corpus, "long");
  tcase_set_timeout(corpus, 180); /* ~20 s, more under the sanitizers */
  tcase_add_test(corpus, corpus_models_compile);
  suite_add_tcase(s, corpus);
  return s;
}
