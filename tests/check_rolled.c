/* check_rolled.c - Check suite for the k stages printed as one loop
 * (--stage-loop, gen/step.c and gen/emit_kernel.c: OP_SSUM, DagLoop).
 *
 *   same      the loop sums the same terms in the same order as the
 *             straight-line stages: Kepler at k = 16 (unconstrained) and
 *             tests/models/swing.ham (grad U and grad g both at the stages)
 *             in both multiplier families follow the straight-line solver
 *             to round-off, and keep H (and g) at round-off; the float
 *             --wide-step variant follows the double one to float accuracy.
 *   size      issue 14 "Large models": a 12-atom cluster with a pair
 *             potential at k = 16 emits C whose size does not grow with k,
 *             against k times the gradient before (bytes, not seconds).
 * The batch variants of both (bloop, bswing) are in tests/check_batch.c.
 * The suite is rolled_suite(); the project's runner adds it. */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "generate.h"
#include "kepler_k16s2.h"
#include "kepler_loop_fw_k16s2.h"
#include "kepler_loop_k16s2.h"
#include "side_by_side.h"
#include "swing_c_k6s2.h"
#include "swing_k6s2.h"
#include "swing_loop_c_k6s2.h"
#include "swing_loop_k6s2.h"

Suite *rolled_suite(void);

START_TEST(test_same_trajectory)
{
  SAME_TRAJECTORY(kepler_loop_k16s2, kepler_k16s2, 0.03, 1e-13, "Kepler k = 16, stage loop vs straight-line");
  SAME_TRAJECTORY(swing_loop_k6s2, swing_k6s2, 0.02, 1e-13, "swing, poly, stage loop vs straight-line");
  SAME_TRAJECTORY(swing_loop_c_k6s2, swing_c_k6s2, 0.02, 1e-13, "swing, const, stage loop vs straight-line");
}
END_TEST

/* H of Kepler and H, g of the swing stay at round-off with the loop; the
 * float --wide-step Kepler follows the double one to float accuracy. */
START_TEST(test_conservation)
{
  kepler_loop_k16s2_state x;
  kepler_loop_fw_k16s2_state y;
  swing_loop_c_k6s2_state w;
  double g[1], dH = 0, dHw = 0, dg = 0, dq = 0;
  kepler_loop_k16s2_init(&x, NULL, NULL);
  kepler_loop_fw_k16s2_init(&y, NULL, NULL);
  swing_loop_c_k6s2_init(&w, NULL, NULL);
  double H0 = kepler_loop_k16s2_energy(&x, NULL), Hw0 = swing_loop_c_k6s2_energy(&w, NULL);
  for (int n = 0; n < NSTEPS; n++) {
    ck_assert_int_eq(kepler_loop_k16s2_step(&x, 0.03, NULL, NULL), 0);
    ck_assert_int_eq(kepler_loop_fw_k16s2_step(&y, 0.03f, NULL, NULL), 0);
    ck_assert_int_eq(swing_loop_c_k6s2_step(&w, 0.02, NULL, NULL), 0);
    swing_loop_c_k6s2_constraints(&w, NULL, g);
    dH = fmax(dH, fabs(kepler_loop_k16s2_energy(&x, NULL) - H0));
    dHw = fmax(dHw, fabs(swing_loop_c_k6s2_energy(&w, NULL) - Hw0));
    dg = fmax(dg, fabs(g[0]));
    for (int i = 0; i < 2; i++) dq = fmax(dq, fabs(x.q[i] - (double)y.q[i]));
  }
  printf("rolled: |H - H0| Kepler %.3g, swing %.3g, |g| %.3g; float --wide-step vs double %.3g\n", dH, dHw, dg, dq);
  ck_assert_msg(dH <= 1e-14 && dHw <= 1e-14 && dg <= 1e-14, "H or g off round-off: %.3g %.3g %.3g", dH, dHw, dg);
  ck_assert_msg(dq <= 1e-4, "float --wide-step with the stage loop is %.3g from double", dq);
}
END_TEST

/* The text of a cluster of n atoms with a Morse pair potential, on a
 * jittered cubic lattice, at rest but for a small push. malloc'd. */
static char *cluster_model(int n)
{
  size_t cap = 4096 + (size_t)n * 120, len = 0;
  char *text = malloc(cap);
  ck_assert_ptr_nonnull(text);
  len += (size_t)snprintf(text, cap, "N = %d\nvariables x[N], y[N], z[N]\n"
                          "U = sum(i in 1..N, sum(j in i+1..N, (1 - exp(1 - sqrt((x[i]-x[j])^2 + (y[i]-y[j])^2 + "
                          "(z[i]-z[j])^2)))^2))\nq0 = [", n);
  for (int c = 0; c < 3; c++)
    for (int i = 0; i < n; i++) {
      int at[3] = {i % 3, i / 3 % 3, i / 9};
      len += (size_t)snprintf(text + len, cap - len, "%s%.3f", c || i ? ", " : "", 1.05 * at[c] + 0.01 * (i % 5) * (c == 0));
    }
  len += (size_t)snprintf(text + len, cap - len, "]\np0 = [0.1");
  for (int i = 1; i < 3 * n; i++) len += (size_t)snprintf(text + len, cap - len, ", 0");
  snprintf(text + len, cap - len, "]\n");
  return text;
}

/* A 12-atom cluster (m = 36): the straight-line stages are k copies of the
 * gradient, so k = 16 takes about 8 times the C of k = 2 that way; as one
 * loop the C of k = 16 is about that of k = 2 (the gradient once, plus the
 * k x s tables). Bytes of C, no timing. */
START_TEST(test_size)
{
  char *text = cluster_model(12);
  /* --rolled off: the pair sum would otherwise roll (docs/rolled.md, "Pair sums") */
  char *k2 = generate_source(text, "-k 2 -s 2 --stage-loop 1000000000 --rolled off");
  char *loop = generate_source(text, "-k 16 -s 2 --rolled off");
  char *flat = generate_source(text, "-k 16 -s 2 --stage-loop 1000000000 --rolled off");
  ck_assert_msg(k2 && loop && flat, "generation failed (or wrote more than 4 MiB)");
  size_t b2 = strlen(k2), bl = strlen(loop), bf = strlen(flat);
  printf("rolled: 12-atom cluster: k = 2 %zu bytes; k = 16 straight-line %zu, as a loop %zu\n", b2, bf, bl);
  ck_assert_msg(strstr(loop, "st < 16; st++"), "k = 16 by default is not a loop over the stages");
  ck_assert_msg(bl <= 2 * b2, "the stage loop at k = 16 takes %zu bytes, more than twice k = 2 (%zu)", bl, b2);
  ck_assert_msg(bf >= 4 * b2, "straight-line k = 16 takes only %zu bytes against %zu at k = 2", bf, b2);
  free(k2);
  free(loop);
  free(flat);
  free(text);
}
END_TEST

Suite *rolled_suite(void)
{
  Suite *s = suite_create("rolled");
  TCase *tc = tcase_create("stage loop");
  tcase_set_tags(tc, "sanlong"); /* the generated arithmetic: sanitized in check-long */
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, test_same_trajectory);
  tcase_add_test(tc, test_conservation);
  tcase_add_test(tc, test_size);
  suite_add_tcase(s, tc);
  return s;
}
