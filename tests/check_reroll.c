/* check_reroll.c - Check suite for the rolled form (--rolled, gen/roll.c,
 * gen/emit_rolled.c, docs/rolled.md): the model's index kept as loops.
 *
 *   same      the chain of 8 pendula (s = 4), of 32 (s = 2), the chain with
 *             masses and a second-neighbour spring whose force is not affine
 *             (the stage loop, M^-1 a table) and the unconstrained FPU chain
 *             (params), rolled against straight-line: the same trajectories
 *             up to the reordering of sums (docs/rolled.md, "Same results"),
 *             and at the start the same H, g, hidden constraint and
 *             consistent multiplier to round-off;
 *   float     --real float rolled against straight-line, to float's bound;
 *   adaptive  NAME_step_adaptive, NAME_dense and NAME_project on the rolled
 *             kernels follow the straight-line ones to the reordering bound;
 *   poly      the poly family rolled (gen/emit_rolled_poly.c) against
 *             straight-line on the chains of 8 (s = 4) and 32 (s = 2) and
 *             the chain with springs, to the same reordering bound, and H
 *             and g of the rolled poly chains at round-off;
 *   conserve  H and g of the rolled chains stay at round-off;
 *   events    the chain with events (tests/models/chain_events.ham) through
 *             the driver, rolled and straight-line, fixed and adaptive
 *             steps: the same events at the same t, located as precisely;
 *             --stop-at ends both on the event's state;
 *   size      the C of the rolled chain (s = 4, const) as a function of N:
 *             the loops are the same at N = 250 and 1000, only the data grows
 *             (bytes per coordinate bounded), N = 1000 is under 300 KB; bytes,
 *             no timing (bench/rolled/run.sh measures time);
 *   lean      the generator's peak memory on the rolled chain of 1000 and
 *             4000 (s = 4): it builds the layout of the step only, not
 *             the straight-line step beside it, so memory grows linearly
 *             with N (generous bounds on max RSS, no timing);
 *   choose    --rolled auto keeps a small chain straight-line and rolls a
 *             large one, in both families; --rolled on refuses what the
 *             form does not cover (--iteration newton, a model not uniform in its index), auto
 *             falls back to straight-line there; variables x[30000], refused
 *             as 37.6 MB of straight-line C, is rolled by default.
 * The suite is reroll_suite(); the project's runner adds it. */
#define _POSIX_C_SOURCE 200809L
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "chain32_rolled_k2s2.h"
#include "chain32_straight_k2s2.h"
#include "chain32f_rolled_k2s2.h"
#include "chain32f_straight_k2s2.h"
#include "chain32p_rolled_k2s2.h"
#include "chain32p_straight_k2s2.h"
#include "chain_rolled_k4s4.h"
#include "chain_straight_k4s4.h"
#include "chainp_rolled_k4s4.h"
#include "chainp_straight_k4s4.h"
#include "fpu_rolled_k2s2.h"
#include "fpu_straight_k2s2.h"
#include "chainev_rolled_k4s4.h"
#include "chainev_straight_k4s4.h"
#include "driver_adapters.h"
#include "generate.h"
#include "side_by_side.h"
#include "spring_rolled_k2s2.h"
#include "spring_straight_k2s2.h"
#include "springp_rolled_k2s2.h"
#include "springp_straight_k2s2.h"

Suite *reroll_suite(void);

/* The reordering bound of docs/rolled.md: the two forms round the same sums
 * in another order, a few ulps of the step's largest terms a step (about
 * 1e-15 of values up to 50), and the chain's motion spreads a difference by
 * at most a factor 10^3 over the NSTEPS steps (measured 1e-11 at most). */
#define REORDER_TOL 1e-9

START_TEST(test_same_trajectory)
{
  SAME_TRAJECTORY(chain_rolled_k4s4, chain_straight_k4s4, 0.01, REORDER_TOL, "chain 8, s = 4, rolled vs straight-line");
  SAME_TRAJECTORY(chain32_rolled_k2s2, chain32_straight_k2s2, 0.01, REORDER_TOL, "chain 32, s = 2, rolled vs straight-line");
  SAME_TRAJECTORY(spring_rolled_k2s2, spring_straight_k2s2, 0.01, REORDER_TOL, "chain with springs, rolled vs straight-line");
  SAME_TRAJECTORY(fpu_rolled_k2s2, fpu_straight_k2s2, 0.002, REORDER_TOL, "FPU, rolled vs straight-line");
}
END_TEST

/* The poly family (the default with constraints at s >= 2): its moments,
 * band-factored multiplier matrix and end-of-step projection as loops
 * (gen/emit_rolled_poly.c) follow the straight-line solver to the same
 * reordering bound (measured 3e-13 at most over the NSTEPS steps): the
 * chain of 8 at s = 4, of 32 at s = 2, and the chain with masses and a
 * curved second-neighbour spring. */
START_TEST(test_same_trajectory_poly)
{
  SAME_TRAJECTORY(chainp_rolled_k4s4, chainp_straight_k4s4, 0.01, REORDER_TOL, "poly chain 8, s = 4, rolled vs straight-line");
  SAME_TRAJECTORY(chain32p_rolled_k2s2, chain32p_straight_k2s2, 0.01, REORDER_TOL, "poly chain 32, s = 2, rolled vs straight-line");
  SAME_TRAJECTORY(springp_rolled_k2s2, springp_straight_k2s2, 0.01, REORDER_TOL, "poly chain with springs, rolled vs straight-line");
}
END_TEST

/* Adaptive steps, dense output and NAME_project work on the kernels, so the
 * rolled chain with springs follows the straight-line one under
 * NAME_step_adaptive too: the error estimates agree to round-off, so do the
 * steps chosen (a relative 1e-16 of h), and the trajectories to the
 * reordering bound. */
START_TEST(test_adaptive_dense)
{
  spring_rolled_k2s2_state a;
  spring_straight_k2s2_state b;
  double ha = 0.05, hb = 0.05, qa[spring_rolled_k2s2_M], pa[spring_rolled_k2s2_M], qb[spring_rolled_k2s2_M],
         pb[spring_rolled_k2s2_M], worst = 0;
  spring_rolled_k2s2_init(&a, NULL, NULL);
  spring_straight_k2s2_init(&b, NULL, NULL);
  for (int n = 0; n < 100; n++) {
    ck_assert_int_eq(spring_rolled_k2s2_step_adaptive(&a, &ha, 1e-8, NULL, NULL), 0);
    ck_assert_int_eq(spring_straight_k2s2_step_adaptive(&b, &hb, 1e-8, NULL, NULL), 0);
    spring_rolled_k2s2_dense(&a, 0.5, qa, pa);
    spring_straight_k2s2_dense(&b, 0.5, qb, pb);
    worst = fmax(worst, fabs(a.t - b.t));
    worst = max_diff(max_diff(worst, qa, qb, spring_rolled_k2s2_M), pa, pb, spring_rolled_k2s2_M);
    worst = max_diff(max_diff(worst, a.q, b.q, spring_rolled_k2s2_M), a.p, b.p, spring_rolled_k2s2_M);
  }
  ck_assert_int_eq(spring_rolled_k2s2_project(&a, NULL, NULL, NULL), 0);
  ck_assert_int_eq(spring_straight_k2s2_project(&b, NULL, NULL, NULL), 0);
  worst = max_diff(max_diff(worst, a.q, b.q, spring_rolled_k2s2_M), a.p, b.p, spring_rolled_k2s2_M);
  printf("reroll: chain with springs, adaptive steps to t = %.3f, dense output, project: rolled vs straight-line %.3g\n",
         a.t, worst);
  ck_assert_msg(worst <= REORDER_TOL, "adaptive: the trajectories differ by %.3g", worst);
}
END_TEST

/* --real float: the reordering bound in float's precision, a few ulps
 * (6e-8) of values up to 50 a step, spread at most 300-fold: 1e-3
 * (measured 1.1e-5); H and g of the rolled solver within what the
 * straight-line float solver keeps (1.1e-4 and 3.8e-6 measured). */
START_TEST(test_float)
{
  chain32f_rolled_k2s2_state a;
  chain32f_straight_k2s2_state b;
  chain32f_rolled_k2s2_init(&a, NULL, NULL);
  chain32f_straight_k2s2_init(&b, NULL, NULL);
  float H0 = chain32f_rolled_k2s2_energy(&a, NULL), g[chain32f_rolled_k2s2_NU];
  double worst = 0, dH = 0, dg = 0;
  for (int n = 0; n < NSTEPS; n++) {
    ck_assert_int_eq(chain32f_rolled_k2s2_step(&a, 0.01f, NULL, NULL), 0);
    ck_assert_int_eq(chain32f_straight_k2s2_step(&b, 0.01f, NULL, NULL), 0);
    for (int i = 0; i < chain32f_rolled_k2s2_M; i++) worst = fmax(worst, fmax(fabs(a.q[i] - b.q[i]), fabs(a.p[i] - b.p[i])));
    dH = fmax(dH, fabs(chain32f_rolled_k2s2_energy(&a, NULL) - H0));
    chain32f_rolled_k2s2_constraints(&a, NULL, g);
    for (int i = 0; i < chain32f_rolled_k2s2_NU; i++) dg = fmax(dg, fabs(g[i]));
  }
  printf("reroll: float chain 32, rolled vs straight-line: %.3g; |H - H0| %.3g, |g| %.3g\n", worst, dH, dg);
  ck_assert_msg(worst <= 1e-3, "float: the trajectories differ by %.3g", worst);
  ck_assert_msg(dH <= 1e-3 && dg <= 4e-5, "float: H or g drift %.3g %.3g", dH, dg);
}
END_TEST

/* The functions of the state outside the step (NAME_energy, the kernels g
 * and hidden, the consistent multiplier of NAME_init) at a moving state of
 * the chain with springs: equal to round-off in both forms. */
START_TEST(test_same_state_functions)
{
  spring_rolled_k2s2_state a;
  spring_straight_k2s2_state b;
  spring_rolled_k2s2_init(&a, NULL, NULL);
  spring_straight_k2s2_init(&b, NULL, NULL);
  for (int n = 0; n < 50; n++) {
    ck_assert_int_eq(spring_rolled_k2s2_step(&a, 0.01, NULL, NULL), 0);
    ck_assert_int_eq(spring_straight_k2s2_step(&b, 0.01, NULL, NULL), 0);
  }
  memcpy(b.q, a.q, sizeof a.q); /* the same state in both */
  memcpy(b.p, a.p, sizeof a.p);
  spring_rolled_k2s2_init(&a, a.q, a.p);
  spring_straight_k2s2_init(&b, b.q, b.p);
  double ga[spring_rolled_k2s2_NU], gb[spring_rolled_k2s2_NU], ha[spring_rolled_k2s2_NU], hb[spring_rolled_k2s2_NU];
  spring_rolled_k2s2_constraints(&a, NULL, ga);
  spring_straight_k2s2_constraints(&b, NULL, gb);
  spring_rolled_k2s2_hidden(&a, NULL, ha);
  spring_straight_k2s2_hidden(&b, NULL, hb);
  double dH = fabs(spring_rolled_k2s2_energy(&a, NULL) - spring_straight_k2s2_energy(&b, NULL));
  double dg = max_diff(0, ga, gb, spring_rolled_k2s2_NU), dh = max_diff(0, ha, hb, spring_rolled_k2s2_NU);
  double dl = max_diff(0, a.lambda, b.lambda, spring_rolled_k2s2_NU), lmax = 0;
  for (int i = 0; i < spring_rolled_k2s2_NU; i++) lmax = fmax(lmax, fabs(b.lambda[i]));
  printf("reroll: state functions, rolled vs straight-line: H %.3g, g %.3g, hidden %.3g, lambda %.3g of %.3g\n", dH, dg, dh,
         dl, lmax);
  ck_assert_msg(dH <= 1e-13 && dg <= 1e-14 && dh <= 1e-13, "H, g or hidden differ: %.3g %.3g %.3g", dH, dg, dh);
  ck_assert_msg(dl <= 1e-12 * fmax(1, lmax), "the consistent multiplier differs by %.3g", dl);
}
END_TEST

/* H is linear in y plus the kinetic energy and g quadratic, so k = s
 * nodes conserve both exactly (METHOD.md): what is left is round-off, a
 * few ulps of U's terms (|y| <= N) a step. The rolled poly family keeps
 * them at round-off too (its end of step rescales p to H0, its iteration
 * drives g(q1) to round-off: measured |H - H0| 1.4e-14 and 2e-13, |g|
 * 2e-15 and 7e-15, as the const family). */
START_TEST(test_conservation)
{
  double dH[4] = {0, 0, 0, 0}, dg[4] = {0, 0, 0, 0};
  SOLVER_DRIFT(chain_rolled_k4s4, 0.01, NSTEPS, dH[0], dg[0]);
  SOLVER_DRIFT(chain32_rolled_k2s2, 0.01, NSTEPS, dH[1], dg[1]);
  SOLVER_DRIFT(chainp_rolled_k4s4, 0.01, NSTEPS, dH[2], dg[2]);
  SOLVER_DRIFT(chain32p_rolled_k2s2, 0.01, NSTEPS, dH[3], dg[3]);
  for (int f = 0; f < 4; f += 2) {
    printf("reroll: rolled %s chains: |H - H0| %.3g (8), %.3g (32); |g| %.3g, %.3g\n", f ? "poly" : "const", dH[f],
           dH[f + 1], dg[f], dg[f + 1]);
    ck_assert_msg(dH[f] <= 1e-13 && dH[f + 1] <= 1e-12, "H off round-off: %.3g %.3g", dH[f], dH[f + 1]);
    ck_assert_msg(dg[f] <= 1e-14 && dg[f + 1] <= 1e-13, "g off round-off: %.3g %.3g", dg[f], dg[f + 1]);
  }
}
END_TEST

/* The text of the chain of n pendula (models/chain8.ham). malloc'd. */
static char *chain_model(int n)
{
  char *text = malloc(512);
  ck_assert_ptr_nonnull(text);
  snprintf(text, 512, "N = %d\nvariables x[N], y[N]\nU = sum(i in 1..N, y[i])\n"
                      "g = [x[1]^2 + y[1]^2 - 1, [(x[i] - x[i-1])^2 + (y[i] - y[i-1])^2 - 1 for i in 2..N]]\n"
                      "q0 = [[i for i in 1..N], [0 for i in 1..N]]\np0 = [0 for i in 1..2*N]\n", n);
  return text;
}

/* How many times needle occurs in s. */
static int count(const char *s, const char *needle)
{
  int n = 0;
  for (const char *p = strstr(s, needle); p; p = strstr(p + 1, needle)) n++;
  return n;
}

START_TEST(test_size)
{
  static const int ns[] = {250, 1000};
  char *src[2];
  for (int i = 0; i < 2; i++) {
    char *text = chain_model(ns[i]);
    src[i] = generate_source(text, "--multiplier const -s 4 --rolled on");
    free(text);
    ck_assert_msg(src[i] != NULL, "generation failed at N = %d", ns[i]);
  }
  size_t a = strlen(src[0]), b = strlen(src[1]);
  double per_coordinate = (double)(b - a) / (2.0 * (ns[1] - ns[0]));
  int loops0 = count(src[0], "for ("), loops1 = count(src[1], "for (");
  printf("reroll: rolled chain, s = 4: %zu bytes at N = 250, %zu at N = 1000 (%.1f bytes per coordinate); %d loops\n", a, b,
         per_coordinate, loops1);
  ck_assert_msg(b <= 300000, "the rolled chain of 1000 is %zu bytes of C, above 300 KB", b);
  ck_assert_msg(loops0 == loops1, "the rolled chain has %d loops at N = 250 and %d at N = 1000", loops0, loops1);
  /* what grows is data: q0, p0 (two literals a coordinate) and tcon (two ints) */
  ck_assert_msg(per_coordinate <= 32, "the rolled chain grows by %.1f bytes a coordinate", per_coordinate);
  free(src[0]);
  free(src[1]);
}
END_TEST

/* Issue 29, the chain of 8 at 1.32 times the straight-line step: the sweep's
 * loops over the coordinates read the constraints on each from the table
 * tcon, with a branch per constraint. Now a chain's constraints are affine
 * in i on four segments of coordinates (x and y, the last of each apart),
 * and the sweep is printed per segment with the constraint indices as i +
 * offset: no table, no test of a constraint's presence. */
START_TEST(test_sweep_segments)
{
  char *text = chain_model(250), *src = generate_source(text, "--multiplier const -s 4 --rolled on");
  free(text);
  ck_assert_ptr_nonnull(src);
  char *sweep = strstr(src, "_sweep(const double *q0");
  ck_assert_ptr_nonnull(sweep);
  char *end = strstr(sweep, "\n}\n");
  ck_assert_ptr_nonnull(end);
  *end = 0;
  ck_assert_msg(!strstr(sweep, "_tcon["), "the rolled chain's sweep reads the table tcon");
  ck_assert_msg(!strstr(sweep, ">= 0)"), "the rolled chain's sweep tests a constraint's presence");
  ck_assert_int_eq(count(sweep, "/* coordinates 0..248 */"), 2); /* the system and Theta, x */
  ck_assert_int_eq(count(sweep, "/* coordinates 250..498 */"), 2); /* and y */
  free(src);
}
END_TEST

/* variables x[30000] with a sum of squares: 37.6 MB of straight-line C,
 * refused (tests/check_lean.c); rolled by default, a third of a megabyte,
 * most of it q0 and p0. */
START_TEST(test_many_coordinates)
{
  const char *text = "variables x[30000]\nM = identity\nU = sum(i in 1..30000, x[i]^2)\n"
                     "q0 = [1 for i in 1..30000]\np0 = [0 for i in 1..30000]\n";
  char *src = generate_source(text, "-s 2");
  ck_assert_msg(src != NULL, "x[30000] was not generated");
  printf("reroll: variables x[30000], sum of squares: %zu bytes of C\n", strlen(src));
  ck_assert_msg(strstr(src, "(rolled)") && strlen(src) <= 400000, "x[30000]: %zu bytes of C", strlen(src));
  free(src);
}
END_TEST

/* The generator's peak resident memory (KB) on the rolled chain of n,
 * s = 4, const; -1 when it fails. In a child process of its own, so that
 * ru_maxrss of its children is this run's alone. */
static long generator_peak_kb(int n)
{
  int fd[2];
  ck_assert_int_eq(pipe(fd), 0);
  pid_t pid = fork();
  ck_assert_int_ge(pid, 0);
  if (pid == 0) {
    char *text = chain_model(n), *src = generate_source(text, "--multiplier const -s 4 --rolled on");
    struct rusage ru;
    long kb = src && getrusage(RUSAGE_CHILDREN, &ru) == 0 ? ru.ru_maxrss : -1;
    _exit(write(fd[1], &kb, sizeof kb) == sizeof kb ? 0 : 1);
  }
  long kb = -1;
  close(fd[1]);
  if (read(fd[0], &kb, sizeof kb) != sizeof kb) kb = -1;
  close(fd[0]);
  waitpid(pid, NULL, 0);
  return kb;
}

/* Issue 29: the generator used to build the straight-line step beside the
 * rolled kernels, whose dense nu x nu node matrices took 179 MB at N = 1000
 * and 1.7 GB at N = 4000 (N^1.6); building the layout only it takes 18 and
 * 61 MB (plain build; the sanitizers add a constant share). The bounds are
 * generous: 400 MB at N = 4000, and 4000 / 1000 at most 8 times (linear is
 * 4, the old quadratic growth 9.5). */
START_TEST(test_generator_memory)
{
  long small = generator_peak_kb(1000), large = generator_peak_kb(4000);
  printf("reroll: generator peak memory, rolled chain s = 4: %.1f MB at N = 1000, %.1f MB at N = 4000\n", small / 1024.0,
         large / 1024.0);
  ck_assert_msg(small > 0 && large > 0, "the generator failed on the rolled chain");
  ck_assert_msg(large <= 400 * 1024, "the generator took %.0f MB on the rolled chain of 4000", large / 1024.0);
  ck_assert_msg(large <= 8 * small, "the generator's memory grows %.1f times from N = 1000 to 4000", (double)large / small);
}
END_TEST

static const char *const chain_names[] = {"x[1]", "x[2]", "x[3]", "x[4]", "x[5]", "x[6]", "x[7]", "x[8]",
                                          "y[1]", "y[2]", "y[3]", "y[4]", "y[5]", "y[6]", "y[7]", "y[8]"};
DRIVER_EVENTS_MODEL(chainev_rolled_k4s4, chain_names)
DRIVER_EVENTS_MODEL(chainev_straight_k4s4, chain_names)

#define MAXEV 64
#define EVCOLS (1 + 2 * chainev_rolled_k4s4_M) /* t, q, p */

/* Run the driver of md with args (words between spaces), its events CSV
 * read back: names[] and rows of t, q, p (at most MAXEV); returns their
 * number. t_end: the t of the CSV's last row. */
static int chain_events(const hbvmrt_model *md, const char *args, char names[][16], double *rows, double *t_end)
{
  char evpath[] = "/tmp/hbvm-rev-XXXXXX", csvpath[] = "/tmp/hbvm-rcsv-XXXXXX", cmd[512], line[4096], err[4096];
  int fe = mkstemp(evpath), fc = mkstemp(csvpath), n = 0;
  ck_assert(fe >= 0 && fc >= 0);
  close(fe);
  close(fc);
  snprintf(cmd, sizeof cmd, "%s --quiet --events %s --csv %s %s", md->name, evpath, csvpath, args);
  ck_assert_msg(driver_run_captured(md, NULL, cmd, err, sizeof err) == 0, "%s: %s", args, err);
  FILE *f = fopen(evpath, "r");
  ck_assert(f && fgets(line, sizeof line, f));
  while (n < MAXEV && fgets(line, sizeof line, f)) {
    char *c = strchr(line, ',');
    ck_assert(c && c - line < 16);
    snprintf(names[n], 16, "%.*s", (int)(c - line), line);
    for (int k = 0; k < EVCOLS; k++) rows[n * EVCOLS + k] = strtod(c + 1, &c);
    n++;
  }
  fclose(f);
  f = fopen(csvpath, "r");
  ck_assert(f != NULL);
  *t_end = NAN;
  while (fgets(line, sizeof line, f)) *t_end = strtod(line, NULL);
  fclose(f);
  unlink(evpath);
  unlink(csvpath);
  return n;
}

/* Events on the rolled form (issue 29): the events kernel stays
 * straight-line beside the rolled step, and the driver locates an event on
 * the step's dense output. The chain of 8 with the last mass crossing x = 4
 * (falling) and the first crossing y = -0.5, to T = 10, fixed steps and
 * --tol: the rolled and straight-line forms report the same events in the
 * same order, at the same t to 1e-12 (the reordering of sums, 1e-11 over
 * 400 steps, moves an event by about that over its crossing speed; measured
 * 3.6e-15 at most), and each is located as precisely: the event's function
 * at the reported state is below 1e-10 in both (the driver's location on the
 * dense output, as tests/check_events.c bounds it; measured 5.4e-13 at
 * most). --stop-at tip:1 ends both runs at the event's t. */
START_TEST(test_events)
{
  static const char *const runs[] = {"-h 0.01 -T 10", "--tol 1e-10 -h 0.01 -T 10", "-h 0.01 -T 10 --stop-at tip:1"};
  static char na[MAXEV][16], nb[MAXEV][16];
  static double ra[MAXEV * EVCOLS], rb[MAXEV * EVCOLS];
  for (int r = 0; r < 3; r++) {
    double ta, tb, dt = 0, off = 0;
    int n = chain_events(&chainev_rolled_k4s4_model, runs[r], na, ra, &ta);
    ck_assert_int_eq(chain_events(&chainev_straight_k4s4_model, runs[r], nb, rb, &tb), n);
    ck_assert_msg(n == (r == 2 ? 2 : 4), "%s: %d events", runs[r], n); /* first, tip (, first, first) */
    for (int i = 0; i < n; i++) {
      const double *a = ra + i * EVCOLS, *b = rb + i * EVCOLS;
      ck_assert_str_eq(na[i], nb[i]);
      dt = fmax(dt, fabs(a[0] - b[0]));
      int tip = !strcmp(na[i], "tip"); /* x[8] - 4, else y[1] + 0.5 */
      off = fmax(off, fmax(fabs(tip ? a[8] - 4 : a[9] + 0.5), fabs(tip ? b[8] - 4 : b[9] + 0.5)));
    }
    printf("reroll: chain events, %s: %d events, rolled vs straight-line t within %.2g, |event| at them %.2g\n",
           runs[r], n, dt, off);
    ck_assert_msg(dt <= 1e-12 && off <= 1e-10, "%s: events apart by %g in t, located to %g", runs[r], dt, off);
    if (r == 2)
      ck_assert_msg(ta == ra[EVCOLS] && tb == rb[EVCOLS], "--stop-at: the runs end at %.17g, %.17g, not at the event", ta, tb);
  }
}
END_TEST

START_TEST(test_choose)
{
  char *small = chain_model(8), *large = chain_model(64);
  char *a = generate_source(small, "--multiplier const -s 4");
  char *b = generate_source(large, "--multiplier const -s 4");
  char *c = generate_source(large, "-s 4"); /* the poly family */
  ck_assert_msg(a && b && c, "generation failed");
  ck_assert_msg(!strstr(a, "(rolled)"), "--rolled auto rolled the chain of 8");
  ck_assert_msg(strstr(b, "(rolled)"), "--rolled auto did not roll the chain of 64");
  ck_assert_msg(strstr(c, "(rolled)") && strstr(c, "_pband_factor"), "--rolled auto did not roll the poly chain of 64");
  ck_assert_msg(strlen(c) <= 200000, "the rolled poly chain of 64 is %zu bytes of C", strlen(c));
  char *e = generate_source(large, "-s 4 --batch 2"); /* --batch rolls too (tests/check_batch.c, the br* solvers) */
  ck_assert_msg(e && strstr(e, "(rolled): the scalar kernel"), "--rolled auto did not roll the batch chain of 64");
  free(e);
  char *n = generate_source(small, "-s 4 --iteration newton --rolled on"); /* Newton with constraints: the saddle point's band */
  ck_assert_msg(n && strstr(n, "_kkt_factor"), "--rolled on did not roll the chain of 8 under Newton");
  free(n);
  /* x[i]^i: a different expression at each i, not uniform in the index */
  const char *odd = "N = 80\nvariables x[N]\nU = sum(i in 1..N, x[i]^i)\nq0 = [0.5 for i in 1..N]\n"
                    "p0 = [0 for i in 1..N]\n";
  ck_assert_ptr_null(generate_source(odd, "-s 2 --rolled on"));
  char *d = generate_source(odd, "-s 2");
  ck_assert_msg(d && !strstr(d, "(rolled)"), "a model not uniform in its index was rolled");
  free(a);
  free(b);
  free(c);
  free(d);
  free(small);
  free(large);
}
END_TEST

Suite *reroll_suite(void)
{
  Suite *s = suite_create("reroll");
  TCase *tc = tcase_create("rolled form");
  tcase_set_tags(tc, "sanlong"); /* the generated arithmetic: sanitized in check-long */
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, test_same_trajectory);
  tcase_add_test(tc, test_same_trajectory_poly);
  tcase_add_test(tc, test_same_state_functions);
  tcase_add_test(tc, test_float);
  tcase_add_test(tc, test_adaptive_dense);
  tcase_add_test(tc, test_conservation);
  tcase_add_test(tc, test_events);
  tcase_add_test(tc, test_size);
  tcase_add_test(tc, test_sweep_segments);
  tcase_add_test(tc, test_many_coordinates);
  tcase_add_test(tc, test_generator_memory);
  tcase_add_test(tc, test_choose);
  suite_add_tcase(s, tc);
  return s;
}
