/* check_cluster.c - Check suite for a cluster of rigid molecules with a pair
 * potential (issue 29): tests/models/cluster4.ham, N = 4 diatomics in space,
 * one bond constraint each, all atoms of different molecules interacting by
 * a pair sum over i < j (a polynomial pair potential, so H is a polynomial),
 * in a weak harmonic trap.
 *
 *   conserve  H and g at round-off over many steps, in the default (poly)
 *             family and the paper's (const) one;
 *   order     the default family's order 2s = 4 against a tiny-step
 *             reference (the same solver at h / 16);
 *   rolled    --rolled on (U's pair sum as one double loop over the pairs,
 *             two pairs a pass, what reads only the outer index and the
 *             gradient there kept out of the inner loop; grad U scattered
 *             from it: gen/roll_pair.c, emit_rolled_pairs.c) against
 *             straight-line: the same trajectory up to the reordering of
 *             sums (docs/rolled.md);
 *   size      the rolled cluster's C as N grows: the same loops at N = 16
 *             and 64, only the data grows (bytes, no timing:
 *             bench/rolled/cluster.sh measures time);
 *   choose    --rolled auto rolls the cluster of 8 and keeps those of 4 and
 *             6 straight-line (gen/roll.h, ROLL_AUTO_PAIR_ITEMS).
 * The suite is cluster_suite(); the project's runner adds it. */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cluster_k4s2.h"
#include "cluster_rolled_k4s2.h"
#include "cluster_straight_k4s2.h"
#include "generate.h"
#include "side_by_side.h"

Suite *cluster_suite(void);
static char *cluster_model(int n, int side);

#define CLUSTER_STEPS 4000

/* U has degree 4 and g degree 2: k = 4 nodes at s = 2 integrate both
 * exactly (METHOD.md), so what is left is round-off, asserted with the
 * project's bound of issue 10 (1e-13, tests/check_poly.c) on g and on H
 * relative to its terms (|U| about 10 here). */
START_TEST(test_conservation)
{
  double dH = 0, dg = 0, dHc = 0, dgc = 0;
  SOLVER_DRIFT(cluster_k4s2, 0.02, CLUSTER_STEPS, dH, dg);
  SOLVER_DRIFT(cluster_straight_k4s2, 0.02, CLUSTER_STEPS, dHc, dgc);
  printf("cluster: %d steps of 0.02: |H - H0| %.3g (poly), %.3g (const); |g| %.3g, %.3g\n", CLUSTER_STEPS, dH, dHc, dg,
         dgc);
  ck_assert_msg(dH <= 1e-13 && dHc <= 1e-13, "H off round-off: %.3g %.3g", dH, dHc);
  ck_assert_msg(dg <= 1e-13 && dgc <= 1e-13, "g off round-off: %.3g %.3g", dg, dgc);
}
END_TEST

/* The state (q, p) of the default solver after n steps of h from q0, p0. */
static void run_to(double h, int n, double *qp)
{
  cluster_k4s2_state x;
  cluster_k4s2_init(&x, NULL, NULL);
  for (int k = 0; k < n; k++) ck_assert_int_eq(cluster_k4s2_step(&x, h, NULL, NULL), 0);
  memcpy(qp, x.q, sizeof x.q);
  memcpy(qp + cluster_k4s2_M, x.p, sizeof x.p);
}

/* Order 2s = 4 in q and p (the poly family, METHOD.md): the error at T = 1.6
 * against the solver at h / 16 falls 16-fold per halving of h = 0.1, 0.05,
 * 0.025 (the reference's own error is 16^4 times smaller). Asserted: each
 * observed order within 0.4 of 4. */
START_TEST(test_order)
{
  enum { NQP = 2 * cluster_k4s2_M };
  double ref[NQP], x[NQP], err[3];
  run_to(0.025 / 16, 64 * 16, ref);
  for (int r = 0; r < 3; r++) {
    int n = 16 << r;
    run_to(1.6 / n, n, x);
    err[r] = max_diff(0, x, ref, NQP);
  }
  double p1 = log2(err[0] / err[1]), p2 = log2(err[1] / err[2]);
  printf("cluster: errors at T = 1.6, h = 0.1, 0.05, 0.025: %.3g %.3g %.3g; orders %.2f %.2f\n", err[0], err[1], err[2], p1,
         p2);
  ck_assert_msg(fabs(p1 - 4) <= 0.4 && fabs(p2 - 4) <= 0.4, "orders %.2f %.2f, not 4", p1, p2);
}
END_TEST

/* The reordering bound of docs/rolled.md (tests/check_reroll.c): a few ulps
 * of the step's largest terms a step, spread by the motion. */
START_TEST(test_rolled)
{
  char *text = cluster_model(4, 2), *src = generate_source(text, "--multiplier const --rolled on");
  const char *inner = src ? strstr(src, "for (c = b + 1; c + 1 <= 3; c += 2) {") : NULL, *end;
  ck_assert_msg(inner, "the cluster of 4 has no loop over its pairs, two a pass");
  end = strstr(inner, "\n    }\n");
  ck_assert_ptr_nonnull(end);
  /* what reads only b (q[b + o]) and the gradient at b are out of the inner loop */
  const char *at_b = strstr(inner, "[b");
  ck_assert_msg(!at_b || at_b > end, "the inner pair loop reads or adds at b: %.40s", at_b);
  free(src);
  free(text);
  SAME_TRAJECTORY(cluster_rolled_k4s2, cluster_straight_k4s2, 0.02, 1e-9, "cluster 4, rolled vs straight-line");
}
END_TEST

/* tests/models/cluster4.ham with N molecules on a grid of side L (malloc'd). */
static char *cluster_model(int n, int side)
{
  static const char *const sizes = "\nN  = 4\nL  = 2\n";
  char *text = read_text("models/cluster4.ham"), *at;
  ck_assert_ptr_nonnull(text);
  at = strstr(text, sizes);
  ck_assert_ptr_nonnull(at);
  char *out = malloc(strlen(text) + 32);
  ck_assert_ptr_nonnull(out);
  *at = 0;
  sprintf(out, "%s\nN  = %d\nL  = %d\n%s", text, n, side, at + strlen(sizes));
  free(text);
  return out;
}

/* The rolled C of the cluster of n molecules (malloc'd). */
static char *rolled_cluster(int n, int side)
{
  char *text = cluster_model(n, side), *src = generate_source(text, "--multiplier const --rolled on");
  ck_assert_msg(src != NULL, "the cluster of %d was not rolled", n);
  free(text);
  return src;
}

/* How many times needle occurs in s. */
static int count(const char *s, const char *needle)
{
  int n = 0;
  for (const char *p = strstr(s, needle); p; p = strstr(p + 1, needle)) n++;
  return n;
}

/* The trap and the pair sum are two runs whatever N when 2N is a multiple of 8
 * (measured 56 KB at N = 4, 65 KB at 16, 79 KB at 64, against 1.5 MB of
 * straight-line C at 16): the loops are
 * the same at N = 16 and 64, and what grows is q0, p0 and the table tcon:
 * two %.17g literals (up to 25 bytes each with the separator) and one int a
 * coordinate, 64 bytes at most (measured 48). */
START_TEST(test_size)
{
  char *a = rolled_cluster(16, 3), *b = rolled_cluster(64, 4);
  size_t na = strlen(a), nb = strlen(b);
  double per_coordinate = (double)(nb - na) / (6.0 * (64 - 16));
  int loops_a = count(a, "for ("), loops_b = count(b, "for (");
  printf("cluster: rolled, %zu bytes at N = 16, %zu at N = 64 (%.1f a coordinate); %d loops, %d pair loops\n", na, nb,
         per_coordinate, loops_b, count(b, "for (c = b"));
  /* two runs: the trap's 32 terms as 4 items of 8 (one loop over the atoms), the pairs as one */
  ck_assert_msg(strstr(a, "U's pair sums as 2 runs"), "U of the cluster of 16 is not two runs");
  /* a trap of 12 terms, no whole number of the pair body's 8: its own period (gen/roll_pair.c) */
  char *six = rolled_cluster(6, 2);
  ck_assert_msg(strstr(six, "U's pair sums as 2 runs"), "U of the cluster of 6 is not two runs");
  free(six);
  ck_assert_msg(loops_a == loops_b, "%d loops at N = 16, %d at N = 64", loops_a, loops_b);
  ck_assert_msg(per_coordinate <= 64, "the rolled cluster grows by %.1f bytes a coordinate", per_coordinate);
  free(a);
  free(b);
}
END_TEST

/* --rolled auto's rule for pair sums (gen/roll.h, ROLL_AUTO_PAIR_ITEMS): the
 * cluster of 8 (30 items in 2 runs) rolls in both families, the clusters of
 * 4 (7 items) and 6 (18: 3 of its trap, 15 pairs) stay straight-line (the
 * rolled step of 6 measured 1.17 times the straight-line one). */
START_TEST(test_choose)
{
  static const struct {
    int n, side, rolled;
  } cases[] = {{4, 2, 0}, {6, 2, 0}, {8, 2, 1}};
  static const char *const families[] = {"--multiplier const", ""};
  for (size_t c = 0; c < sizeof cases / sizeof *cases; c++)
    for (int f = 0; f < 2; f++) {
      char *text = cluster_model(cases[c].n, cases[c].side), *src = generate_source(text, families[f]);
      ck_assert_ptr_nonnull(src);
      ck_assert_msg((strstr(src, "(rolled)") != NULL) == cases[c].rolled, "--rolled auto %s the cluster of %d (%s)",
                    cases[c].rolled ? "did not roll" : "rolled", cases[c].n, f ? "poly" : "const");
      free(src);
      free(text);
    }
}
END_TEST

Suite *cluster_suite(void)
{
  Suite *s = suite_create("cluster");
  TCase *tc = tcase_create("cluster");
  tcase_set_tags(tc, "sanlong"); /* the generated arithmetic: sanitized in check-long */
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, test_conservation);
  tcase_add_test(tc, test_order);
  tcase_add_test(tc, test_rolled);
  tcase_add_test(tc, test_size);
  tcase_add_test(tc, test_choose);
  suite_add_tcase(s, tc);
  return s;
}
