/* check_batch.c - hbvmgen --batch W: every lane of NAME_batch_step is bitwise
 * NAME_step from the same state, for both multiplier families and a mass
 * matrix M(q) (its Theta carried in the lanes, p1 rescaled), float and
 * double, with params per lane, lanes that fail (left byte-identical while
 * the others advance) and idle lanes (tests/models/LIST, the b* solvers);
 * every lane of an accepted NAME_batch_step_adaptive is NAME_step_adaptive's
 * step of that size, and a failed one writes no lane. */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bchain_k2s2.h"
#include "bconst_k2s2.h"
#include "bfloat_k2s2.h"
#include "bfloatpoly_k2s2.h"
#include "barm_k3s3.h"
#include "barmk_k18s3.h"
#include "bdpa_k2s2.h"
#include "bdpafloat_k2s2.h"
#include "bkepler_k16s2.h"
#include "bmass_k2s2.h"
#include "bdense_k2s2.h"
#include "bloop_k16s2.h"
#include "bswing_k6s2.h"
#include "bplain_k3s3.h"
#include "bpoly_k3s3.h"
#include "bsat_k6s2.h"
#include "bsatpoly_k6s2.h"
#include "brchain_k4s4.h"
#include "brchainp_k4s4.h"
#include "brchain32_k2s2.h"
#include "brchain32p_k2s2.h"
#include "brchain32f_k2s2.h"
#include "brfpu_k2s2.h"
#include "bfpu_k4s2.h"
#include "bnbob_k16s2.h"
#include "bnbobauto_k16s2.h"
#include "bnbobpoly_k16s2.h"
#include "bnfpu_k4s2.h"
#include "bfb_k2s2.h"

/* Lane l starts from the model's initial values after l scalar steps of
 * h (1 + l / 8), so the lanes differ in state and in the previous step (lane
 * 0 has none); the last lane's momenta are then made 1e4 times larger plus
 * PLUS (with LARGE_P; else q 1e6 times smaller), a step that cannot converge, and lane
 * 1 is idle for the first steps. NSTEP batch steps of h, then NSTEP of 1.5 h,
 * each compared lane by lane with NAME_step: the code, the iterations and the
 * state's bytes. With params, each lane's first param is scaled by 1 + l / 4.
 * BATCH_TEST: LARGE_P with constraints (Kepler's small q: near the singularity). */
#define BATCH_TEST(P, HSTEP, NSTEP) BATCH_TEST_FAIL(P, HSTEP, NSTEP, P##_NU)
#define BATCH_TEST_FAIL(P, HSTEP, NSTEP, LARGE_P) BATCH_TEST_LANE(P, HSTEP, NSTEP, LARGE_P, 1e3f, (void)0)
/* LANE: a statement after each active lane's scalar step (rc, ss its code and stats, bs the
 * batch's); it may count Newton's factor decisions in fresh and kept (NEWTON_LANE). */
#define BATCH_TEST_LANE(P, HSTEP, NSTEP, LARGE_P, PLUS, LANE)                                            \
  START_TEST(test_##P) {                                                                             \
    P##_batch b;                                                                                     \
    P##_state s[P##_W], y;                                                                           \
    P##_params prm[P##_W];                                                                           \
    P##_batch_stats bs;                                                                              \
    P##_stats ss;                                                                                    \
    P##_real *first;                                                                                 \
    int l, n, i, ok = 0, failed = 0, fresh, kept, mixed = 0, newton = 0;                             \
    memset(&b, 0xA5, sizeof b); /* garbage where nothing is set */                                 \
    for (l = 0; l < P##_W; l++) {                                                                    \
      P##_params_default(&prm[l]);                                                                   \
      first = (P##_real *)(void *)&prm[l];                                                          \
      if (P##_NPARAMS) *first *= (P##_real)(1 + l / 4.0);                                           \
      P##_init_params(&s[l], NULL, NULL, &prm[l]);                                                   \
      for (n = 0; n < l; n++) ck_assert_int_eq(P##_step(&s[l], (P##_real)((HSTEP) * (1 + l / 8.0)), &prm[l], NULL), 0); \
      if (l == P##_W - 1 && l > 0)                                                                   \
        for (i = 0; i < P##_M; i++) {                                                                \
          if (LARGE_P) s[l].p[i] = s[l].p[i] * 1e4f + (PLUS);                                       \
          else s[l].q[i] *= 1e-6f; /* Kepler: near the singularity */                              \
        }                                                                                            \
      P##_batch_set(&b, l, &s[l]);                                                                   \
    }                                                                                                \
    if (P##_W > 2) b.idle[1] = 1;                                                                    \
    for (n = 0; n < 2 * (NSTEP); n++) {                                                              \
      P##_real h = (P##_real)((HSTEP) * (n < (NSTEP) ? 1 : 1.5));                                        \
      int nf = P##_batch_step(&b, h, prm, &bs), nf2 = 0;                                             \
      if (n == (NSTEP) / 2) b.idle[1] = 0;                                                           \
      fresh = kept = 0;                                                                              \
      for (l = 0; l < P##_W; l++) {                                                                  \
        int rc = 0;                                                                                  \
        if (!(P##_W > 2 && l == 1 && n <= (NSTEP) / 2)) {                                            \
          rc = P##_step(&s[l], h, &prm[l], &ss);                                                     \
          if (bs.iters[l]) ck_assert_int_eq(bs.iters[l], ss.iters);                                 \
          LANE;                                                                                      \
        } else                                                                                       \
          ck_assert_int_eq(bs.iters[l], 0);                                                          \
        ck_assert_msg(bs.code[l] == rc, #P " step %d lane %d: code %d, scalar %d", n, l, bs.code[l], rc); \
        nf2 += rc != 0;                                                                              \
        ok += rc == 0;                                                                               \
        failed += rc != 0;                                                                           \
        P##_batch_get(&b, l, &y);                                                                    \
        ck_assert_msg(!memcmp(&y, &s[l], sizeof y), #P " step %d lane %d: the state differs", n, l); \
      }                                                                                              \
      ck_assert_int_eq(nf, nf2);                                                                     \
      mixed += fresh > 0 && kept > 0; /* lanes of one step that factored and that kept theirs */     \
      newton += fresh + kept;                                                                        \
    }                                                                                                \
    ck_assert_msg(ok > 0 && (P##_W == 1 || failed > 0), #P ": %d lane steps ok, %d failed", ok, failed); \
    ck_assert_msg(!newton || mixed > 0, #P ": no step where lanes decided differently on the factor"); \
    {                                                                                                \
      P##_real H[P##_W], g[(P##_NU + 1) * P##_W], gs[P##_NU + 1];                                    \
      P##_batch_energy(&b, prm, H);                                                                  \
      P##_batch_constraints(&b, prm, g);                                                             \
      for (l = 0; l < P##_W; l++) {                                                                  \
        P##_real e = P##_energy(&s[l], &prm[l]);                                                     \
        ck_assert(!memcmp(&H[l], &e, sizeof e));                                                     \
        P##_constraints(&s[l], &prm[l], gs);                                                         \
        for (i = 0; i < P##_NU; i++) ck_assert(!memcmp(&g[i * P##_W + l], &gs[i], sizeof gs[i]));    \
      }                                                                                              \
    }                                                                                                \
  }                                                                                                  \
  END_TEST

/* Newton (the lanes take the scalar step): its counts as NAME_step's; fresh counts the lanes
 * that factored the Newton matrix, kept those that iterated on the last step's factor */
#define NEWTON_LANE(P)                                                                                 \
  do {                                                                                               \
    if (rc == 0) {                                                                                   \
      ck_assert_int_eq(bs.newton[l], ss.newton);                                                     \
      ck_assert_int_eq(bs.factors[l], ss.factors);                                                   \
      ck_assert_int_eq(bs.jacobians[l], ss.jacobians);                                               \
      fresh += ss.factors > 0;                                                                       \
      kept += ss.factors == 0 && ss.newton > 0;                                                      \
    }                                                                                                \
  } while (0)
/* (momenta of 1e4: the bob's lane at 1e3 converges since Newton's update is accelerated) */
#define BATCH_TEST_NEWTON(P, HSTEP, NSTEP) BATCH_TEST_LANE(P, HSTEP, NSTEP, 1, 1e4f, NEWTON_LANE(P))

BATCH_TEST(bconst_k2s2, 0.05, 12)
BATCH_TEST(bpoly_k3s3, 0.1, 12)
BATCH_TEST(bfloat_k2s2, 0.05, 12)
BATCH_TEST(bfloatpoly_k2s2, 0.05, 12)
BATCH_TEST(bchain_k2s2, 0.005, 8)
BATCH_TEST(bsat_k6s2, 0.05, 8)
BATCH_TEST(bsatpoly_k6s2, 0.05, 8) /* the multiplier force from the moments R_jr */
BATCH_TEST(bkepler_k16s2, 0.03, 12)
BATCH_TEST(bmass_k2s2, 0.05, 12)
BATCH_TEST(bdense_k2s2, 0.005, 8)
BATCH_TEST(bloop_k16s2, 0.03, 12)
BATCH_TEST(bswing_k6s2, 0.02, 12)
BATCH_TEST(bplain_k3s3, 0.1, 12)
/* M(q): from rest, the failing lane with momenta of 1e3 */
BATCH_TEST_FAIL(bdpa_k2s2, 0.05, 12, 1)
BATCH_TEST_FAIL(bdpafloat_k2s2, 0.05, 12, 1)
BATCH_TEST_FAIL(barm_k3s3, 0.05, 12, 1)
BATCH_TEST_FAIL(barmk_k18s3, 0.05, 8, 1) /* the sweep in parts: the lane test's own reductions */
/* M(q) with constraints (the four-bar in angles): the lanes take the scalar step, each with
 * its own ground link l0 x (1 + l / 4) and its loop closed there */
BATCH_TEST_FAIL(bfb_k2s2, 0.05, 12, 1)
/* the rolled form (--rolled on, docs/rolled.md): the scalar rolled kernels in each lane */
BATCH_TEST(brchain_k4s4, 0.005, 8)
BATCH_TEST(brchainp_k4s4, 0.005, 8)
BATCH_TEST(brchain32_k2s2, 0.005, 8)
BATCH_TEST(brchain32p_k2s2, 0.005, 8)
BATCH_TEST(brchain32f_k2s2, 0.005, 8)
BATCH_TEST_FAIL(brfpu_k2s2, 0.01, 12, 1) /* params per lane, no constraints */
/* the sweep's reductions of the round-off test per coordinate: the stiff x1 = 1 / omega at h omega
 * 1-1.75, where it decides how many sweeps a step takes */
BATCH_TEST_FAIL(bfpu_k4s2, 0.02, 12, 1)

/* NAME_batch_step_adaptive, lanes sharing h: from the model's initial values
 * with lane l's momenta scaled by 1 + l / 16 (lane 1 idle), NSTEP steps at
 * TOL from the first step H0, large enough to be rejected. Every accepted
 * step is, lane by lane, what NAME_step_adaptive makes of the lane's state
 * given that step: accepted at once, bitwise the same state and estimate
 * (when the batch's try was not a cold one, after three rejections), but
 * for the controller's aim, which the lanes share and the batch's rejected
 * tries lower (emit_step_factor); the
 * idle lane is untouched; H stays at round-off where the family restores it.
 * Then a lane that cannot step (q NaN): every active lane fails, none is
 * written. ADAPTIVE_TEST_MQ (VARY 1), for M(q) from rest: lane l's
 * coordinates are scaled by 1 + l / 16 too, and H stays at round-off (the
 * rescale); VARY 2, for a model with constraints from rest (the stiff bob):
 * lane l's first param is scaled by 1 + l / 4 instead. */
#define ADAPTIVE_TEST(P, H0, TOL, NSTEP) ADAPTIVE_TEST_MQ(P, H0, TOL, NSTEP, 0)
#define ADAPTIVE_TEST_MQ(P, H0, TOL, NSTEP, VARY)                                                        \
  START_TEST(test_adaptive_##P) {                                                                      \
    P##_batch b, c;                                                                                    \
    P##_state s[P##_W], y, z;                                                                          \
    P##_params prm[P##_W];                                                                             \
    P##_batch_stats bs;                                                                                \
    P##_stats ss;                                                                                      \
    P##_real h = (P##_real)(H0), hs, hmin = 1e30f, hmax = 0, H[P##_W], q[P##_M], p[P##_M];               \
    int l, n, i, rejected = 0, compared = 0;                                                          \
    memset(&b, 0, sizeof b);                                                                           \
    for (l = 0; l < P##_W; l++) {                                                                      \
      P##_params_default(&prm[l]);                                                                     \
      if ((VARY) == 2 && P##_NPARAMS) *(P##_real *)(void *)&prm[l] *= (P##_real)(1 + l / 4.0);          \
      P##_init_params(&s[l], NULL, NULL, &prm[l]);                                                     \
      for (i = 0; i < P##_M; i++) {                                                                    \
        q[i] = s[l].q[i] * (P##_real)((VARY) == 1 ? 1 + l / 16.0 : 1);                                 \
        p[i] = s[l].p[i] * (P##_real)(1 + l / 16.0);                                                   \
      }                                                                                                \
      P##_init_params(&s[l], q, p, &prm[l]);                                                           \
      H[l] = P##_energy(&s[l], &prm[l]);                                                               \
      P##_batch_set(&b, l, &s[l]);                                                                     \
    }                                                                                                  \
    if (P##_W > 2) b.idle[1] = 1;                                                                      \
    for (n = 0; n < (NSTEP); n++) {                                                                    \
      for (l = 0; l < P##_W; l++) P##_batch_get(&b, l, &s[l]);                                         \
      ck_assert_int_eq(P##_batch_step_adaptive(&b, &h, (P##_real)(TOL), prm, &bs), 0);                  \
      ck_assert(bs.h != 0 && h != 0);                                                                  \
      rejected += bs.rejected;                                                                         \
      hmin = fabs(bs.h) < hmin ? (P##_real)fabs(bs.h) : hmin;                                          \
      hmax = fabs(bs.h) > hmax ? (P##_real)fabs(bs.h) : hmax;                                          \
      for (l = 0; l < P##_W; l++) {                                                                    \
        P##_batch_get(&b, l, &y);                                                                      \
        if (P##_W > 2 && l == 1) {                                                                     \
          ck_assert_msg(!memcmp(&y, &s[l], sizeof y), #P " step %d: the idle lane moved", n);         \
          continue;                                                                                    \
        }                                                                                              \
        ck_assert_int_eq(bs.code[l], 0);                                                               \
        if (bs.rejected >= 3) continue; /* the accepted try may have been cold */                      \
        z = s[l];                                                                                      \
        hs = bs.h;                                                                                     \
        ck_assert_int_eq(P##_step_adaptive(&z, &hs, (P##_real)(TOL), &prm[l], &ss), 0);                 \
        ck_assert_msg(ss.rejected == 0 && ss.h == bs.h, #P " step %d lane %d: the scalar step rejects it", n, l); \
        z.aim = y.aim; /* the controller's aim: the lanes' lowest, after the batch's rejections */    \
        ck_assert_msg(!memcmp(&z, &y, sizeof y), #P " step %d lane %d: the state differs", n, l);       \
        ck_assert_msg(!memcmp(&ss.err_est, &bs.err_est[l], sizeof ss.err_est), #P " step %d lane %d: estimate", n, l); \
        compared++;                                                                                    \
      }                                                                                                \
    }                                                                                                  \
    ck_assert_msg(rejected > 0 && hmin < hmax && compared > (NSTEP), #P ": rejected %d, h %g..%g, compared %d", \
                  rejected, (double)hmin, (double)hmax, compared);                                      \
    if ((P##_NU || VARY) && sizeof(P##_real) == sizeof(double))                                        \
      for (l = 0; l < P##_W; l++) {                                                                    \
        P##_batch_get(&b, l, &y);                                                                      \
        ck_assert_msg(fabs(P##_energy(&y, &prm[l]) - H[l]) <= 1e-13, #P " lane %d: H moved", l);       \
      }                                                                                                \
    b.q[P##_W - 1] = (P##_real)NAN; /* coordinate 0 of the last lane */                                \
    memcpy(&c, &b, sizeof b);                                                                          \
    ck_assert_int_eq(P##_batch_step_adaptive(&b, &h, (P##_real)(TOL), prm, &bs), P##_W > 2 ? P##_W - 1 : P##_W); \
    for (l = 0; l < P##_W; l++) { /* every lane's bytes (not Newton's scratch, x->next) */             \
      P##_batch_get(&b, l, &y);                                                                        \
      P##_batch_get(&c, l, &z);                                                                        \
      ck_assert_msg(!memcmp(&y, &z, sizeof y), #P ": lane %d was written by a failed step", l);         \
    }                                                                                                  \
    ck_assert(!memcmp(b.idle, c.idle, sizeof b.idle));                                                 \
    ck_assert(bs.h == 0 && bs.code[0] != 0 && bs.code[P##_W - 1] != 0);                                \
  }                                                                                                    \
  END_TEST

ADAPTIVE_TEST(bpoly_k3s3, 0.5, 1e-8, 30)
ADAPTIVE_TEST(bconst_k2s2, 0.5, 1e-6, 30)
ADAPTIVE_TEST(bkepler_k16s2, 0.5, 1e-8, 30)
ADAPTIVE_TEST(bchain_k2s2, 0.05, 1e-6, 20)
ADAPTIVE_TEST(bsat_k6s2, 0.5, 1e-6, 20)
ADAPTIVE_TEST(bsatpoly_k6s2, 0.5, 1e-6, 20)
ADAPTIVE_TEST(bfloatpoly_k2s2, 0.5, 1e-4, 20)
ADAPTIVE_TEST_MQ(bdpa_k2s2, 0.5, 1e-8, 30, 1)
ADAPTIVE_TEST_MQ(barm_k3s3, 0.5, 1e-8, 30, 1)
ADAPTIVE_TEST_MQ(bdpafloat_k2s2, 0.5, 1e-4, 20, 1)
ADAPTIVE_TEST(bfb_k2s2, 0.5, 1e-8, 30)
ADAPTIVE_TEST(brchain_k4s4, 0.05, 1e-6, 20)
ADAPTIVE_TEST(brchainp_k4s4, 0.5, 1e-8, 20)
ADAPTIVE_TEST(brchain32p_k2s2, 0.05, 1e-6, 20)
ADAPTIVE_TEST(brfpu_k2s2, 0.05, 1e-6, 20)

/* Newton in the lanes (each the scalar step, its own factor kept or refreshed): the stiff bob
 * (k = 1e4 x (1 + l / 4), omega = 141 x sqrt(1 + l / 4)) at h omega of about 7-12 in both
 * families and under auto (its sweeps slow there), the FPU chain (omega = 50 x (1 + l / 4))
 * at h omega = 10-17 */
BATCH_TEST_NEWTON(bnbob_k16s2, 0.02, 12)
BATCH_TEST_NEWTON(bnbobpoly_k16s2, 0.05, 12)
BATCH_TEST_NEWTON(bnbobauto_k16s2, 0.02, 12)
BATCH_TEST_NEWTON(bnfpu_k4s2, 0.2, 12)
ADAPTIVE_TEST_MQ(bnbob_k16s2, 0.5, 1e-6, 20, 2)
ADAPTIVE_TEST_MQ(bnbobpoly_k16s2, 0.5, 1e-6, 20, 2)
ADAPTIVE_TEST_MQ(bnbobauto_k16s2, 0.5, 1e-6, 20, 2)
ADAPTIVE_TEST(bnfpu_k4s2, 0.5, 1e-6, 20)

/* prm NULL is the defaults in every lane; an all-idle batch is untouched. */
START_TEST(test_defaults_and_idle) {
  bconst_k2s2_batch b, c;
  bconst_k2s2_state s;
  bconst_k2s2_params prm[bconst_k2s2_W];
  int l;
  memset(&b, 0, sizeof b);
  bconst_k2s2_init(&s, NULL, NULL);
  for (l = 0; l < bconst_k2s2_W; l++) {
    bconst_k2s2_params_default(&prm[l]);
    bconst_k2s2_batch_set(&b, l, &s);
  }
  memcpy(&c, &b, sizeof b);
  ck_assert_int_eq(bconst_k2s2_batch_step(&b, 0.05, NULL, NULL), 0);
  ck_assert_int_eq(bconst_k2s2_batch_step(&c, 0.05, prm, NULL), 0);
  ck_assert(!memcmp(&b, &c, sizeof b));
  for (l = 0; l < bconst_k2s2_W; l++) b.idle[l] = 1;
  memcpy(&c, &b, sizeof b);
  ck_assert_int_eq(bconst_k2s2_batch_step(&b, 0.05, NULL, NULL), 0);
  ck_assert(!memcmp(&b, &c, sizeof b));
  for (l = 0; l < bconst_k2s2_W; l++) b.idle[l] = 0;
  ck_assert_int_eq(bconst_k2s2_batch_step(&b, 0, NULL, NULL), bconst_k2s2_W); /* EBADSTEP in every lane */
  /* the adaptive step too: a bad h or tol fails every active lane, and says how many */
  {
    static const double bad[][2] = {{0, 1e-6}, {NAN, 1e-6}, {0.05, 0}, {0.05, -1}, {0.05, NAN}, {INFINITY, 1e-6}};
    bconst_k2s2_batch_stats bs;
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
      double h = bad[k][0];
      memcpy(&c, &b, sizeof b);
      b.idle[2] = 1;
      ck_assert_int_eq(bconst_k2s2_batch_step_adaptive(&b, &h, bad[k][1], NULL, &bs), bconst_k2s2_W - 1);
      ck_assert_int_eq(bs.code[0], bconst_k2s2_EBADSTEP);
      ck_assert_int_eq(bs.code[2], bconst_k2s2_OK);
      ck_assert(bs.h == 0);
      ck_assert_int_eq(bconst_k2s2_batch_step_adaptive(&b, &h, bad[k][1], NULL, NULL), bconst_k2s2_W - 1);
      b.idle[2] = 0;
      ck_assert(!memcmp(&b, &c, sizeof b));
    }
  }
}
END_TEST

Suite *batch_suite(void) {
  Suite *s = suite_create("batch");
  TCase *tc = tcase_create("lanes");
  tcase_set_tags(tc, "sanlong"); /* the generated arithmetic: sanitized in check-long */
  tcase_set_timeout(tc, 60);
  tcase_add_test(tc, test_bconst_k2s2);
  tcase_add_test(tc, test_bpoly_k3s3);
  tcase_add_test(tc, test_bfloat_k2s2);
  tcase_add_test(tc, test_bfloatpoly_k2s2);
  tcase_add_test(tc, test_bchain_k2s2);
  tcase_add_test(tc, test_bsat_k6s2);
  tcase_add_test(tc, test_bsatpoly_k6s2);
  tcase_add_test(tc, test_bkepler_k16s2);
  tcase_add_test(tc, test_bmass_k2s2);
  tcase_add_test(tc, test_bdense_k2s2);
  tcase_add_test(tc, test_bloop_k16s2);
  tcase_add_test(tc, test_bswing_k6s2);
  tcase_add_test(tc, test_bplain_k3s3);
  tcase_add_test(tc, test_defaults_and_idle);
  tcase_add_test(tc, test_adaptive_bpoly_k3s3);
  tcase_add_test(tc, test_adaptive_bconst_k2s2);
  tcase_add_test(tc, test_adaptive_bkepler_k16s2);
  tcase_add_test(tc, test_adaptive_bchain_k2s2);
  tcase_add_test(tc, test_adaptive_bsat_k6s2);
  tcase_add_test(tc, test_adaptive_bsatpoly_k6s2);
  tcase_add_test(tc, test_adaptive_bfloatpoly_k2s2);
  tcase_add_test(tc, test_bdpa_k2s2);
  tcase_add_test(tc, test_bdpafloat_k2s2);
  tcase_add_test(tc, test_barm_k3s3);
  tcase_add_test(tc, test_barmk_k18s3);
  tcase_add_test(tc, test_adaptive_bdpa_k2s2);
  tcase_add_test(tc, test_adaptive_barm_k3s3);
  tcase_add_test(tc, test_adaptive_bdpafloat_k2s2);
  tcase_add_test(tc, test_bfb_k2s2);
  tcase_add_test(tc, test_adaptive_bfb_k2s2);
  tcase_add_test(tc, test_brchain_k4s4);
  tcase_add_test(tc, test_brchainp_k4s4);
  tcase_add_test(tc, test_brchain32_k2s2);
  tcase_add_test(tc, test_brchain32p_k2s2);
  tcase_add_test(tc, test_brchain32f_k2s2);
  tcase_add_test(tc, test_brfpu_k2s2);
  tcase_add_test(tc, test_bfpu_k4s2);
  tcase_add_test(tc, test_adaptive_brchain_k4s4);
  tcase_add_test(tc, test_adaptive_brchainp_k4s4);
  tcase_add_test(tc, test_adaptive_brchain32p_k2s2);
  tcase_add_test(tc, test_adaptive_brfpu_k2s2);
  suite_add_tcase(s, tc);
  TCase *tn = tcase_create("newton");
  tcase_set_tags(tn, "sanlong");
  tcase_set_timeout(tn, 60);
  tcase_add_test(tn, test_bnbob_k16s2);
  tcase_add_test(tn, test_bnbobpoly_k16s2);
  tcase_add_test(tn, test_bnbobauto_k16s2);
  tcase_add_test(tn, test_bnfpu_k4s2);
  tcase_add_test(tn, test_adaptive_bnbob_k16s2);
  tcase_add_test(tn, test_adaptive_bnbobpoly_k16s2);
  tcase_add_test(tn, test_adaptive_bnbobauto_k16s2);
  tcase_add_test(tn, test_adaptive_bnfpu_k4s2);
  suite_add_tcase(s, tn);
  return s;
}
