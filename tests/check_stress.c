/* check_stress.c - stress tests of the generated solvers' failure contract
 * (docs/api.md, "Functions": a failed step returns a nonzero code and
 * leaves the state exactly as it was, byte for byte; a step never leaves a
 * NaN or an infinity in the state).
 *
 *   sweep      every committed solver (generated/LIST) and every test-only
 *              solver (tests/models/LIST, double precision): from the
 *              model's initial values h grows geometrically until a step
 *              fails, every step checked against the contract. Then: a
 *              state holding a NaN or an infinity must be refused
 *              (ENONFINITE); absurd step sizes (0, inf, NaN: EBADSTEP;
 *              1e300, 1e-300, negative, ...) must succeed or fail cleanly;
 *              a step after a step a million times smaller (an extreme
 *              warm-start extrapolation) must converge where a cold start
 *              does. The largest convergent h of each solver is printed
 *              ("stress: ..." lines) and, when the environment variable
 *              HBVM_STRESS_LOG names a file, appended to it as CSV
 *              (solver,k,s,h_ok,h_fail,code).
 *   singular   dependent constraints (tests/models/redundant.ham) and a
 *              constraint Jacobian losing rank at a reachable point
 *              (tests/models/viviani.ham: the double point of Viviani's
 *              curve): clean failures, and a retry with a smaller h passes.
 *   domain     a model whose solution leaves the domain of U (cliff.ham,
 *              U = x^1.5: ENONFINITE), one that falls into a singularity
 *              (logwall.ham, U = log x: a clean failure), and a finite
 *              state whose step overflows (ENONFINITE).
 *   embedded   tests/arm_build.sh: every committed solver compiles for a
 *              Cortex-M4 with -ffreestanding -Werror and needs nothing but
 *              <math.h> and compiler helpers; --real float needs no double
 *              function. tests/clang_build.sh: the committed solvers and
 *              drivers and the generator's other forms are warning-free
 *              under clang -Wall -Wextra -pedantic -Werror too.
 *
 * The suite is stress_suite(); the project's runner (check_main.c) adds it.
 * It runs from tests/, in about 8 s. */
#define _POSIX_C_SOURCE 200809L

#include <check.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "solvers.h"

#include "cliff_k6s2.h"
#include "logwall_k6s2.h"
#include "pendulum_angle_k6s3.h"
#include "redundant_k2s2.h"
#include "viviani_k2s2.h"
#include "viviani_const_k2s2.h"
#include "polywide_k3s3.h"
#include "polyplain_k3s3.h"
#include "chain_poly_k2s2.h"
#include "kepler_k16s2.h"
#include "oscillator_k2s2.h"

Suite *stress_suite(void);

/* The return codes are the same for every generated solver. */
enum { OK = 0, ENOCONV = 1, ENONFINITE = 2, ESINGULAR = 3, EBADSTEP = 4 };

#define SWEEP_H0 1e-3       /* first step size of the sweep */
#define SWEEP_RATIO 1.189207115002721 /* 2^(1/4): four sizes per octave */
#define SWEEP_HMAX 1e4      /* the sweep gives up above this */
#define SWEEP_STEPS 10      /* steps per size: the first cold, the rest warm-started */

/* ---- solvers not in tests/solvers.c: the test-only models and the
 * committed solver that only the driver tests use ---- */

#define TEST_ONLY_SOLVERS(X)                                                                          \
  X(redundant_k2s2) X(viviani_k2s2) X(viviani_const_k2s2) X(cliff_k6s2) X(logwall_k6s2) X(polywide_k3s3) \
  X(polyplain_k3s3) X(chain_poly_k2s2)
#define LOCAL_SOLVERS(X) TEST_ONLY_SOLVERS(X) X(pendulum_angle_k6s3)

#define CODES_AGREE(P)                                                                                    \
  typedef char P##_codes_agree[(P##_OK == OK && P##_ENOCONV == ENOCONV && P##_ENONFINITE == ENONFINITE &&   \
                                P##_ESINGULAR == ESINGULAR && P##_EBADSTEP == EBADSTEP)                     \
                                   ? 1                                                                      \
                                   : -1];
#define LOCAL_ADAPT(P) CODES_AGREE(P) SOLVER_ADAPT(P)
LOCAL_SOLVERS(LOCAL_ADAPT)

static const Solver local_solvers[] = {LOCAL_SOLVERS(SOLVER_ENTRY)}; /* the test-only ones first */
#define LOCAL_NAME(P) #P,
static const char *const test_only_names[] = {TEST_ONLY_SOLVERS(LOCAL_NAME)};
#define NTEST_ONLY (sizeof test_only_names / sizeof test_only_names[0])

/* The solver of that name from tests/solvers.c or the local table, or NULL. */
static const Solver *find_solver(const char *name) {
  const Solver *sv = solver_find(name);
  for (size_t i = 0; !sv && i < sizeof local_solvers / sizeof local_solvers[0]; i++)
    if (!strcmp(local_solvers[i].name, name)) sv = &local_solvers[i];
  return sv;
}

/* The solver names MODEL_kKsS of a list file ("MODEL K S [FLAGS]" lines,
 * '#' comments); returns their number (at most max). */
#define NAME_SIZE 96
static int read_list(const char *path, char names[][NAME_SIZE], int max) {
  FILE *f = fopen(path, "r");
  ck_assert_msg(f != NULL, "cannot open %s (the suite runs from tests/)", path);
  char line[256], model[64];
  int n = 0, k, s;
  while (fgets(line, sizeof line, f))
    if (line[0] != '#' && sscanf(line, "%63s %d %d", model, &k, &s) == 3) {
      ck_assert_msg(n < max, "%s: more than %d solvers", path, max);
      model[strcspn(model, ":")] = 0; /* NAME:FILE names the solver NAME */
      snprintf(names[n++], NAME_SIZE, "%s_k%ds%d", model, k, s);
    }
  fclose(f);
  return n;
}

/* ---- the contract of one step ---- */

typedef struct {
  const Solver *sv;
  void *x;      /* the state */
  void *before; /* its copy before the last step */
} Run;

static Run run_new(const Solver *sv, const double *q0, const double *p0) {
  Run r = {sv, malloc(sv->state_size), malloc(sv->state_size)};
  ck_assert(r.x && r.before);
  memset(r.x, 0, sv->state_size); /* padding too: memcmp compares every byte */
  sv->init(r.x, q0, p0);
  return r;
}

static void run_free(Run *r) {
  free(r->x);
  free(r->before);
}

/* Whether every value of the state (all of its fields are doubles) is finite. */
static int state_finite(const Run *r) {
  const double *v = r->x;
  for (size_t i = 0; i < r->sv->state_size / sizeof(double); i++)
    if (!isfinite(v[i])) return 0;
  return 1;
}

/* One step of size h, checked against the contract: a known code; on
 * failure the state byte for byte as before, on success every value of it
 * finite. Returns the code. */
static int step_checked(Run *r, double h) {
  memcpy(r->before, r->x, r->sv->state_size);
  int rc = r->sv->step(r->x, h, NULL);
  ck_assert_msg(rc >= OK && rc <= EBADSTEP, "%s, h=%g: unknown return code %d", r->sv->name, h, rc);
  if (rc != OK)
    ck_assert_msg(memcmp(r->before, r->x, r->sv->state_size) == 0,
                  "%s, h=%g, t=%g: the step failed with code %d but changed the state", r->sv->name, h,
                  *solver_t(r->sv, r->before), rc);
  else
    ck_assert_msg(state_finite(r), "%s, h=%g: the step succeeded but left a NaN or infinity in the state",
                  r->sv->name, h);
  return rc;
}

/* ---- (a) the sweep ---- */

static const char *code_name(int rc) {
  static const char *const names[] = {"OK", "ENOCONV", "ENONFINITE", "ESINGULAR", "EBADSTEP"};
  return rc >= OK && rc <= EBADSTEP ? names[rc] : "?";
}

typedef struct {
  double h_ok;   /* largest h of the grid at which SWEEP_STEPS steps succeed (0: none) */
  double h_fail; /* the first h at which a step failed (INFINITY: none up to SWEEP_HMAX) */
  int code;      /* its code */
  int step;      /* and which of the SWEEP_STEPS steps it was (1-based) */
} Sweep;

/* Step sizes no solver can take: zero, not finite. */
static const double bad_h[] = {0.0, -0.0, INFINITY, -INFINITY, NAN};

/* Step sizes a solver must survive one way or the other (success with a
 * finite state, or a clean failure): far too large, tiny, negative. */
static const double wild_h[] = {1e10, -1e10, 1e300, -1e300, DBL_MAX, -DBL_MAX, 1e-300, 4.9e-324, -1e-3};

/* After a first failure at h_fail: a few larger sizes, then absurd ones,
 * each from a warm state (one small step taken). */
static void abuse(const Solver *sv, double h_fail) {
  Run r = run_new(sv, NULL, NULL);
  int warm = step_checked(&r, SWEEP_H0) == OK;
  double larger[] = {2 * h_fail, 10 * h_fail, 1000 * h_fail};
  for (size_t i = 0; i < sizeof larger / sizeof larger[0]; i++)
    if (isfinite(larger[i])) step_checked(&r, larger[i]);
  for (size_t i = 0; i < sizeof wild_h / sizeof wild_h[0]; i++) {
    Run w = run_new(sv, NULL, NULL);
    if (warm) step_checked(&w, SWEEP_H0);
    step_checked(&w, wild_h[i]);
    run_free(&w);
  }
  for (size_t i = 0; i < sizeof bad_h / sizeof bad_h[0]; i++)
    ck_assert_msg(step_checked(&r, bad_h[i]) == EBADSTEP, "%s: h=%g must give EBADSTEP", sv->name, bad_h[i]);
  run_free(&r);
}

/* Grow h from SWEEP_H0 by SWEEP_RATIO, SWEEP_STEPS checked steps from the
 * initial values at each size, until a step fails. */
static Sweep sweep(const Solver *sv) {
  Sweep res = {0, INFINITY, OK, 0};
  for (double h = SWEEP_H0; h <= SWEEP_HMAX && res.code == OK; h *= SWEEP_RATIO) {
    Run r = run_new(sv, NULL, NULL);
    for (int n = 1; n <= SWEEP_STEPS && res.code == OK; n++)
      if ((res.code = step_checked(&r, h)) != OK) {
        res.h_fail = h;
        res.step = n;
      }
    if (res.code == OK) res.h_ok = h;
    run_free(&r);
  }
  return res;
}

/* Print (and append to $HBVM_STRESS_LOG) the result of a sweep. */
static void report_sweep(const Solver *sv, const Sweep *res) {
  char fail[96] = "none up to the largest h tried";
  if (res->code != OK)
    snprintf(fail, sizeof fail, "h = %.4g, step %d: %s", res->h_fail, res->step, code_name(res->code));
  printf("stress: %-22s k=%d s=%d  largest convergent h = %.4g  (first failure: %s)\n", sv->name, sv->k, sv->s,
         res->h_ok, fail);
  fflush(stdout);
  const char *path = getenv("HBVM_STRESS_LOG");
  FILE *f = path && *path ? fopen(path, "a") : NULL;
  if (f) {
    fprintf(f, "%s,%d,%d,%.6g,%.6g,%s\n", sv->name, sv->k, sv->s, res->h_ok, res->h_fail, code_name(res->code));
    fclose(f);
  }
}

/* The warm start extrapolates the last step's polynomial to the next
 * step: after a tiny step (ratio h / h_previous = 1e6) the prediction must
 * not spoil a step that converges from a cold start. */
static void ratio_jump(const Solver *sv, double h) {
  Run r = run_new(sv, NULL, NULL);
  ck_assert_int_eq(step_checked(&r, h * 1e-6), OK);
  int rc = step_checked(&r, h);
  ck_assert_msg(rc == OK, "%s: h=%g converges from a cold start but not after a step of h*1e-6: %s", sv->name, h,
                code_name(rc));
  run_free(&r);
}

/* A state the caller filled with a NaN or an infinity (in q or in p) must
 * be refused (ENONFINITE), not stepped. */
static void poisoned_state(const Solver *sv) {
  static const double poison[] = {NAN, INFINITY, -INFINITY};
  for (size_t i = 0; i < sizeof poison / sizeof poison[0]; i++)
    for (int which = 0; which < 2; which++) {
      Run r = run_new(sv, NULL, NULL);
      (which ? solver_p : solver_q)(sv, r.x)[sv->m - 1] = poison[i];
      int rc = r.sv->step(r.x, SWEEP_H0, NULL);
      ck_assert_msg(rc != OK || state_finite(&r), "%s: %s[%d] = %g in the state: OK, and the state is not finite",
                    sv->name, which ? "p" : "q", sv->m, poison[i]);
      ck_assert_msg(rc == ENONFINITE, "%s: %s[%d] = %g in the state: %s, want ENONFINITE", sv->name,
                    which ? "p" : "q", sv->m, poison[i], code_name(rc));
      run_free(&r);
    }
}

/* Sweep one solver, report, then abuse it with absurd step sizes. */
static void sweep_and_abuse(const Solver *sv) {
  Sweep res = sweep(sv);
  report_sweep(sv, &res);
  poisoned_state(sv);
  abuse(sv, res.code == OK ? SWEEP_HMAX : res.h_fail);
  if (res.h_ok > 0) ratio_jump(sv, res.h_ok / 2); /* at the very edge of convergence it may tip over */
}

/* Every committed solver: generated/LIST, all of them in double precision. */
START_TEST(sweep_committed_solvers) {
  char names[64][NAME_SIZE];
  int n = read_list("../generated/LIST", names, 64);
  ck_assert_msg(n > 0, "generated/LIST lists no solver");
  for (int i = 0; i < n; i++) {
    const Solver *sv = find_solver(names[i]);
    ck_assert_msg(sv != NULL, "no adapter for %s (add it to tests/solvers.c or LOCAL_SOLVERS)", names[i]);
    sweep_and_abuse(sv);
  }
}
END_TEST

/* The test-only solvers of this file (tests/models/LIST). */
START_TEST(sweep_test_only_solvers) {
  for (size_t i = 0; i < NTEST_ONLY; i++) sweep_and_abuse(find_solver(test_only_names[i]));
}
END_TEST

/* ---- the stopping rule, on both sides of convergence ---- */

/* Every accepted step has converged: its last increment is at round-off
 * (NOISETOL, 64 ulps), also near the iteration's limit, where it stops
 * contracting. Kepler (k = 16, s = 2, e = 0.6) over h = 0.40 .. 0.80: an
 * earlier rule accepted stalls up to 1e-10 there. */
START_TEST(accepted_steps_have_converged) {
  int accepted = 0, failed = 0;
  for (double h = 0.40; h <= 0.80; h += 0.02) {
    kepler_k16s2_state x;
    kepler_k16s2_stats st;
    kepler_k16s2_init(&x, NULL, NULL);
    for (int n = 0; n < 40; n++) {
      int rc = kepler_k16s2_step(&x, h, NULL, &st);
      if (rc) {
        ck_assert_msg(rc == ENOCONV, "kepler h=%g: %s", h, code_name(rc));
        failed++;
        break;
      }
      accepted++;
      ck_assert_msg(st.increment <= 1.4210854715202004e-14 /* NOISETOL */, "kepler h=%g step %d accepted at increment %.2e", h, n,
                    st.increment);
    }
  }
  printf("stress: stopping rule, kepler_k16s2 h = 0.40..0.80: %d steps accepted (all at round-off), %d runs "
         "stopped by ENOCONV\n", accepted, failed);
  fflush(stdout);
  ck_assert_int_gt(accepted, 0);
  ck_assert_int_gt(failed, 0);
}
END_TEST

/* A converging iteration is not cut off: for two harmonic oscillators
 * (frequencies 1 and sqrt 2) the sweep's increments do not fall
 * monotonically for h omega above about 2 (X_s^2 has complex eigenvalues),
 * yet it converges up to h omega = 2.8 (h = 2). An earlier rule failed
 * from h = 1.6. Each accepted step keeps H (quadratic: exact) at round-off. */
START_TEST(converging_iteration_not_cut_off) {
  for (double h = 1.0; h <= 2.0; h += 0.2) {
    oscillator_k2s2_state x;
    oscillator_k2s2_init(&x, NULL, NULL);
    double H0 = oscillator_k2s2_energy(&x, NULL);
    for (int n = 0; n < 20; n++) {
      int rc = oscillator_k2s2_step(&x, h, NULL, NULL);
      ck_assert_msg(rc == OK, "oscillator h=%g step %d: %s", h, n, code_name(rc));
    }
    ck_assert_msg(fabs(oscillator_k2s2_energy(&x, NULL) - H0) <= 1e-14, "oscillator h=%g: |dH| %.2e", h,
                  fabs(oscillator_k2s2_energy(&x, NULL) - H0));
  }
}
END_TEST

/* ---- (b) dependent constraints, and a Jacobian that loses rank ---- */

/* g = [g1, 2 g1]: A is singular at every point, whatever h. The step must
 * say so with a failure (ESINGULAR; ENONFINITE when the zero pivot of the
 * LU of A is exactly zero and lambda = 0/0 is met before the pivot test),
 * never succeed, and keep the state. */
START_TEST(redundant_constraints_fail_cleanly) {
  const Solver *sv = find_solver("redundant_k2s2");
  static const double hs[] = {1e-6, 1e-4, 1e-2, 0.1, 1.0, 10.0};
  for (size_t i = 0; i < sizeof hs / sizeof hs[0]; i++) {
    Run r = run_new(sv, NULL, NULL);
    int rc = step_checked(&r, hs[i]);
    ck_assert_msg(rc == ESINGULAR || rc == ENONFINITE, "redundant constraints, h=%g: %s, want ESINGULAR", hs[i],
                  code_name(rc));
    run_free(&r);
  }
}
END_TEST

/* Distance from q to the double point (1, 0, 0) of Viviani's curve. */
static double from_double_point(const double *q) { return sqrt((q[0] - 1) * (q[0] - 1) + q[1] * q[1] + q[2] * q[2]); }

/* A free particle on Viviani's curve at unit speed through the double point,
 * where grad g has rank 1. The fixed-step run must fail there, and only
 * there, cleanly. With the constant multiplier, halving h on failure (a
 * caller's usual strategy) carries it through with g, the hidden
 * constraints and H = 1/2 conserved. The polynomial multiplier's system,
 * s times larger, is too ill-conditioned there for the iteration to reach
 * round-off: it must refuse (ENOCONV) rather than accept a step that has
 * not converged, and every step it accepts must conserve as well. */
START_TEST(rank_loss_at_double_point) {
  /* both families: the polynomial one's (s nu) x (s nu) system, nearly
   * singular there, passes on a little more round-off to g */
  static const char *const names[2] = {"viviani_const_k2s2", "viviani_k2s2"};
  const Solver *sv = find_solver(names[_i]);
  const double H_BIG = 0.01, T_END = 12.0;
  Run r = run_new(sv, NULL, NULL);
  double h = H_BIG, g[2], hc[2], worst_g = 0, worst_hc = 0, worst_H = 0;
  int failures = 0, near = 0, steps = 0;
  while (*solver_t(sv, r.x) < T_END) {
    ck_assert_msg(++steps < 100000, "Viviani: no progress at t=%g", *solver_t(sv, r.x));
    int rc = step_checked(&r, h);
    if (rc != OK) {
      failures++;
      near += from_double_point(solver_q(sv, r.x)) < 0.05;
      ck_assert_msg(rc == ENOCONV || rc == ESINGULAR, "Viviani, t=%g: %s", *solver_t(sv, r.x), code_name(rc));
      if (_i && h <= 1e-6) break; /* the polynomial family does not pass it */
      ck_assert_msg(h > 1e-6, "Viviani: cannot pass the double point even at h=%g", h);
      h /= 2;
      continue;
    }
    if (h < H_BIG && steps % 4 == 0) h *= 2;
    sv->constraints(r.x, g);
    sv->hidden(r.x, hc);
    for (int a = 0; a < 2; a++) {
      worst_g = fmax(worst_g, fabs(g[a]));
      worst_hc = fmax(worst_hc, fabs(hc[a]));
    }
    worst_H = fmax(worst_H, fabs(sv->energy(r.x) - 0.5));
  }
  printf("stress: %s through the double point: %d failed steps (%d near it), max |g| = %.2e, "
         "max |hc| = %.2e, max |H - H0| = %.2e\n", names[_i], failures, near, worst_g, worst_hc, worst_H);
  fflush(stdout);
  ck_assert_msg(near >= 1, "Viviani: no step failed at the double point (rank of grad g drops there)");
  ck_assert_msg(near == failures, "Viviani: %d of %d failures away from the double point", failures - near, failures);
  ck_assert_msg(worst_g <= 1e-13, "Viviani: |g| = %.2e", worst_g);
  ck_assert_msg(_i || *solver_t(sv, r.x) >= T_END, "Viviani: stopped at t = %g", *solver_t(sv, r.x));
  ck_assert_msg(worst_hc <= 1e-3, "Viviani: hidden constraint %.2e", worst_hc);
  ck_assert_msg(worst_H <= 1e-13, "Viviani: |H - H0| = %.2e", worst_H); /* H = |p|^2/2 is quadratic: exact */
  run_free(&r);
}
END_TEST

/* ---- (c) leaving the domain of U ---- */

/* March with a fixed h until a step fails (at most max_steps); returns the
 * code, the state left at the last successful step. */
static int march(Run *r, double h, int max_steps) {
  int rc = OK;
  for (int n = 0; n < max_steps && rc == OK; n++) rc = step_checked(r, h);
  return rc;
}

/* U = x^1.5 (x >= 0), x0 = 1, p0 = -2: the particle reaches x = 0 with
 * finite speed sqrt(6) at t* = 0.4408 and the exact solution leaves the domain. At
 * every h the run must stop there with ENONFINITE, the last state inside. */
START_TEST(leaving_domain_gives_enonfinite) {
  const Solver *sv = find_solver("cliff_k6s2");
  static const double hs[] = {1e-3, 1e-2, 0.05, 0.1, 0.3};
  for (size_t i = 0; i < sizeof hs / sizeof hs[0]; i++) {
    Run r = run_new(sv, NULL, NULL);
    int rc = march(&r, hs[i], 100000);
    double t = *solver_t(sv, r.x), x = solver_q(sv, r.x)[0];
    ck_assert_msg(rc == ENONFINITE, "cliff, h=%g: %s at t=%g, want ENONFINITE", hs[i], code_name(rc), t);
    ck_assert_msg(x >= 0 && t > 0.4408 - hs[i] - 0.01 && t < 0.4408 + 1e-3, "cliff, h=%g: stopped at t=%g, x=%g", hs[i], t, x);
    ck_assert_msg(isfinite(sv->energy(r.x)), "cliff, h=%g: H not finite at the last state", hs[i]);
    run_free(&r);
  }
  /* a single step whose stage points all lie beyond the edge */
  Run r = run_new(sv, (const double[]){0.01}, (const double[]){-10});
  ck_assert_int_eq(step_checked(&r, 0.1), ENONFINITE);
  run_free(&r);
}
END_TEST

/* A finite state whose step overflows: q0 = p0 = 1e308 in U = log x. The
 * force 1/x vanishes out there, so the iteration converges at once, but
 * q1 = q0 + h gamma_0 is no longer a double: the step must fail, not
 * return OK with an infinity in the state. */
START_TEST(overflow_fails_cleanly) {
  const Solver *sv = find_solver("logwall_k6s2");
  Run r = run_new(sv, (const double[]){1e308}, (const double[]){1e308});
  int rc = step_checked(&r, 1.0);
  ck_assert_msg(rc == ENONFINITE, "logwall from q0 = p0 = 1e308: %s, want ENONFINITE", code_name(rc));
  run_free(&r);
}
END_TEST

/* U = log x pulls the particle into x = 0 (at t* = int_0^1 dx / sqrt(1 - 2 log x) = 0.6557), with
 * unbounded speed. The run must stop there with a clean failure (the
 * iteration diverges near the singularity, or a stage lands beyond it). */
START_TEST(singularity_fails_cleanly) {
  const Solver *sv = find_solver("logwall_k6s2");
  static const double hs[] = {1e-3, 1e-2, 0.05};
  for (size_t i = 0; i < sizeof hs / sizeof hs[0]; i++) {
    Run r = run_new(sv, NULL, NULL);
    int rc = march(&r, hs[i], 100000);
    double t = *solver_t(sv, r.x);
    ck_assert_msg(rc == ENOCONV || rc == ENONFINITE, "logwall, h=%g: %s at t=%g", hs[i], code_name(rc), t);
    ck_assert_msg(t > 0.6557 - hs[i] - 0.05 && t < 0.6557 + 1e-3, "logwall, h=%g: stopped at t=%g, the collision is at 0.6557", hs[i], t);
    run_free(&r);
  }
  /* One step across the pole. grad U = 1/x is finite beyond it, so the
   * stage points do not see that U is not: the step may only succeed with a
   * finite state. It does today, landing at x < 0 where H is NaN (only a
   * test of H(q1, p1) in the step would catch that): say so in the log. */
  Run r = run_new(sv, (const double[]){0.01}, (const double[]){-10});
  int rc = step_checked(&r, 0.01);
  ck_assert_msg(rc == OK || rc == ENONFINITE, "logwall across the pole: %s", code_name(rc));
  if (rc == OK && !isfinite(sv->energy(r.x))) {
    printf("stress: note: logwall_k6s2, one step across the pole of U = log x: OK, but x = %g is outside the "
           "domain of U (H = %g)\n", solver_q(sv, r.x)[0], sv->energy(r.x));
    fflush(stdout);
  }
  run_free(&r);
}
END_TEST

/* ---- (d) the embedded build, and the second compiler ---- */

#define BUILD_SKIP 77 /* the script's compiler is not installed */

// Run a build check script of tests/ (arm_build.sh, clang_build.sh): it
// passes, or says it was skipped because its compiler is missing (exit 77,
// the line names the package set of scripts/deps.sh to install).
static void run_build_check(const char *script, const char *what, const char *deps) {
  char cmd[64];
  snprintf(cmd, sizeof cmd, "sh %s", script);
  int status = system(cmd);
  ck_assert_msg(status != -1 && WIFEXITED(status), "cannot run tests/%s", script);
  if (WEXITSTATUS(status) == BUILD_SKIP) {
    printf("stress: %s skipped: its compiler is not installed (scripts/deps.sh %s)\n", what, deps);
    fflush(stdout);
    return;
  }
  ck_assert_msg(WEXITSTATUS(status) == 0, "tests/%s failed (see its output above)", script);
}

START_TEST(embedded_build) { run_build_check("arm_build.sh", "embedded build", "embedded"); }
END_TEST

// The generated C is warning-free under clang too (tests/clang_build.sh).
START_TEST(clang_build) { run_build_check("clang_build.sh", "clang build", "clang"); }
END_TEST

Suite *stress_suite(void) {
  Suite *s = suite_create("stress");
  TCase *tc = tcase_create("contract");
  tcase_set_tags(tc, "sanlong"); /* the generated arithmetic: sanitized in check-long */
  tcase_set_timeout(tc, 60);
  tcase_add_test(tc, sweep_committed_solvers);
  tcase_add_test(tc, sweep_test_only_solvers);
  tcase_add_test(tc, redundant_constraints_fail_cleanly);
  tcase_add_loop_test(tc, rank_loss_at_double_point, 0, 2);
  tcase_add_test(tc, accepted_steps_have_converged);
  tcase_add_test(tc, converging_iteration_not_cut_off);
  tcase_add_test(tc, leaving_domain_gives_enonfinite);
  tcase_add_test(tc, singularity_fails_cleanly);
  tcase_add_test(tc, overflow_fails_cleanly);
  suite_add_tcase(s, tc);
  TCase *arm = tcase_create("embedded"); /* make check-long */
  tcase_set_tags(arm, "long");
  tcase_set_timeout(arm, 120);
  tcase_add_test(arm, embedded_build);
  tcase_add_test(arm, clang_build);
  suite_add_tcase(s, arm);
  return s;
}
