/* main.c - the benchmark driver; bench/run.sh calls it.
 *
 *   bench ref PROBLEM
 *       the reference at the problem's final time, as text (read by sweep)
 *   bench refcheck PROBLEM
 *       how accurate that reference is: other tolerances, the other
 *       integrator, the drift of g and H along it
 *   bench sweep PROBLEM METHOD OUTDIR REFFILE FROM:TO:FACTOR [options]
 *       one work-precision line, appended to OUTDIR/work_precision.csv,
 *       iterations.csv (HBVM) and overhead.csv (hbvm only); FROM:TO
 *       is the range of h, or of the tolerance for adaptive methods
 *       options: -k K -s S (HBVM: hbvm and hbvm-generic are the paper's
 *                --multiplier const, hbvm-poly --multiplier poly),
 *                --cap SECONDS, --floor ERR, --keep-going (past an
 *                error grown 4x: on the stiff problems the slow error
 *                is not monotone in h, and that is not round-off),
 *                --repeats N, --min SECONDS (of one timed repeat)
 *   bench count PROBLEM METHOD K S H WARMUP STEPS
 *       WARMUP steps, then STEPS steps inside count_steps() (for callgrind);
 *       prints "steps iters"
 *   bench ab PROBLEM ROUNDS METHOD:K:S:X METHOD:K:S:X [...]
 *       the points (X: h, or the tolerance) timed in alternation, ROUNDS
 *       rounds; a CSV row each: median seconds and the ratio to the first
 *       (abrun.c) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "bench.h"
#include "count.h"
#include "linalg.h"
#include "reference.h"
#include "sweep.h"

#define REF_TOL 1e-15

static void usage(void)
{
  fputs("usage: bench ref PROBLEM\n"
        "       bench refcheck PROBLEM\n"
        "       bench sweep PROBLEM METHOD OUTDIR REFFILE FROM:TO:FACTOR [-k K -s S] [--cap S] [--floor E] [--keep-going]\n"
        "                   [--repeats N] [--min S]\n"
        "       bench count PROBLEM METHOD K S H WARMUP STEPS\n"
        "       bench ab PROBLEM ROUNDS METHOD:K:S:X METHOD:K:S:X [...]\n",
        stderr);
  exit(1);
}

static const Problem *problem_arg(const char *name)
{
  const Problem *pb = problem_find(name);
  if (!pb) {
    fprintf(stderr, "bench: unknown problem '%s'\n", name);
    exit(1);
  }
  return pb;
}

static const MethodDef *method_arg(const char *name)
{
  const MethodDef *md = method_find(name);
  if (!md) {
    fprintf(stderr, "bench: unknown method '%s'\n", name);
    exit(1);
  }
  return md;
}

static void print_vector(const char *tag, int n, const double *v)
{
  int i;
  printf("%s", tag);
  for (i = 0; i < n; i++) printf(" %.17g", v[i]);
  printf("\n");
}

static int cmd_ref(const Problem *pb)
{
  double q[BENCH_MAXM], p[BENCH_MAXM];
  char how[256];
  if (reference_final(pb, pb->T, REF_TOL, q, p, how, sizeof how) != 0) {
    fprintf(stderr, "bench: no reference for %s\n", pb->name);
    return 1;
  }
  printf("# %s at T = %.17g: %s\n", pb->name, pb->T, how);
  print_vector("q", pb->m, q);
  print_vector("p", pb->m, p);
  return 0;
}

/* The reference against the index-1 integrator of reference.c at two
 * tolerances (for chain8, where that integrator is the reference, the
 * comparison is between its tolerances 1e-15, 1e-14 and 1e-13). */
static int cmd_refcheck(const Problem *pb)
{
  double q[BENCH_MAXM], p[BENCH_MAXM], q1[BENCH_MAXM], p1[BENCH_MAXM], dg, dH;
  const double tols[] = {1e-15, 1e-14, 1e-13};
  char how[256];
  int i, m = pb->m;
  if (reference_final(pb, pb->T, REF_TOL, q, p, how, sizeof how) != 0) return 1;
  printf("%s, T = %g, reference: %s\n", pb->name, pb->T, how);
  for (i = 0; i < 3; i++) {
    if (reference_index1(pb, pb->T, tols[i], q1, p1, &dg, &dH) != 0) return 1;
    printf("  index-1 rk8pd (bench/reference.c) tol %g: |(q,p) - reference| = %.2e, max|g| = %.2e, "
           "max|H-H0| = %.2e\n",
           tols[i], fmax(maxdiff(m, q, q1), maxdiff(m, p, p1)), dg, dH);
  }
  return 0;
}

/* Read the reference written by cmd_ref. */
static int read_ref(const char *file, const Problem *pb, double *q, double *p)
{
  FILE *f = fopen(file, "r");
  char line[4096];
  int got = 0;
  if (!f) return -1;
  while (fgets(line, sizeof line, f)) {
    double *v = line[0] == 'q' ? q : line[0] == 'p' ? p : NULL;
    char *s = line + 1, *end;
    int i;
    if (!v) continue;
    for (i = 0; i < pb->m; i++, s = end) {
      v[i] = strtod(s, &end);
      if (end == s) break;
    }
    got += i == pb->m;
  }
  fclose(f);
  return got == 2 ? 0 : -1;
}

/* Open OUTDIR/name for appending; write the header if it is empty. */
static FILE *open_csv(const char *dir, const char *name, const char *header)
{
  char path[1024];
  FILE *f;
  snprintf(path, sizeof path, "%s/%s", dir, name);
  f = fopen(path, "a");
  if (!f) {
    perror(path);
    exit(1);
  }
  if (ftell(f) == 0) fprintf(f, "%s\n", header);
  return f;
}

static int cmd_sweep(int argc, char **argv)
{
  Sweep sw;
  int i, rc;
  if (argc < 7) usage();
  memset(&sw, 0, sizeof sw);
  sw.pb = problem_arg(argv[2]);
  sw.md = method_arg(argv[3]);
  sw.T = sw.pb->T;
  sw.cap = 0.25;
  sw.floor = 0;
  sw.repeats = 5;
  sw.min_seconds = 0.05;
  if (read_ref(argv[5], sw.pb, sw.qref, sw.pref) != 0) {
    fprintf(stderr, "bench: cannot read the reference %s\n", argv[5]);
    return 1;
  }
  if (sscanf(argv[6], "%lf:%lf:%lf", &sw.from, &sw.to, &sw.factor) != 3 || !(sw.factor > 1) || !(sw.to > 0))
    usage();
  for (i = 7; i < argc; i++) {
    if (strcmp(argv[i], "--keep-going") == 0) { /* the one option without a value */
      sw.keep_going = 1;
      continue;
    }
    if (i + 1 >= argc) usage();
    if (strcmp(argv[i], "-k") == 0) sw.k = atoi(argv[++i]);
    else if (strcmp(argv[i], "-s") == 0) sw.s = atoi(argv[++i]);
    else if (strcmp(argv[i], "--cap") == 0) sw.cap = atof(argv[++i]);
    else if (strcmp(argv[i], "--floor") == 0) sw.floor = atof(argv[++i]);
    else if (strcmp(argv[i], "--repeats") == 0) sw.repeats = atoi(argv[++i]);
    else if (strcmp(argv[i], "--min") == 0) sw.min_seconds = atof(argv[++i]);
    else usage();
  }
  sw.wp = open_csv(argv[4], "work_precision.csv", sweep_wp_header);
  sw.iters = open_csv(argv[4], "iterations.csv", sweep_iters_header);
  sw.overhead = open_csv(argv[4], "overhead.csv", sweep_overhead_header);
  rc = sweep_run(&sw);
  fclose(sw.wp);
  fclose(sw.iters);
  fclose(sw.overhead);
  if (rc == -1) fprintf(stderr, "bench: %s does not apply to %s\n", sw.md->name, sw.pb->name);
  if (rc == -2) fprintf(stderr, "bench: %s on %s: no point succeeded\n", sw.md->name, sw.pb->name);
  return rc == 0 ? 0 : 2;
}

static int cmd_count(int argc, char **argv)
{
  Setting set;
  Stepper sp;
  long warm, n, iters;
  const MethodDef *md;
  if (argc != 9) usage();
  memset(&set, 0, sizeof set);
  set.pb = problem_arg(argv[2]);
  md = method_arg(argv[3]);
  set.k = atoi(argv[4]);
  set.s = atoi(argv[5]);
  set.h = atof(argv[6]);
  warm = atol(argv[7]);
  n = atol(argv[8]);
  if (!md->open || md->open(&set, &sp) != 0) {
    fprintf(stderr, "bench: count: %s does not apply\n", md->name);
    return 1;
  }
  for (; warm > 0; warm--) { /* outside count_steps: not counted */
    int it;
    if (sp.step(sp.state, set.h, &it) != 0) break;
  }
  if (warm > 0 || (iters = count_steps(&sp, set.h, n)) < 0) {
    fprintf(stderr, "bench: count: a step failed\n");
    return 2;
  }
  md->close(&sp);
  printf("%ld %ld\n", n, iters);
  return 0;
}

int main(int argc, char **argv)
{
  gsl_set_error_handler_off();
  if (argc < 3) usage();
  if (strcmp(argv[1], "ref") == 0) return cmd_ref(problem_arg(argv[2]));
  if (strcmp(argv[1], "refcheck") == 0) return cmd_refcheck(problem_arg(argv[2]));
  if (strcmp(argv[1], "sweep") == 0) return cmd_sweep(argc, argv);
  if (strcmp(argv[1], "count") == 0) return cmd_count(argc, argv);
  if (strcmp(argv[1], "ab") == 0) return cmd_ab(argc, argv);
  usage();
  return 1;
}
