/* abrun.c - `bench ab`: methods timed in alternation (A B C, B C A, C A B,
 * ...), one timed call per method a round, so that a drift of the machine's
 * speed falls on all of them alike; the medians over the rounds and their
 * ratios to the first. The stiff benchmark (bench/stiff/run.sh) runs it on
 * the points of equal error it compares. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "timing.h"

#define AB_MAX 8
#define AB_ROUNDS 64

/* One method at one point: METHOD:K:S:X, X the h of a fixed-step method or
 * the tolerance of an adaptive one. */
typedef struct {
  const MethodDef *md;
  Setting set;
  const char *text;
} Point;

static int parse_point(const Problem *pb, const char *spec, Point *pt)
{
  char buf[256], *f[4];
  int n = 0;
  pt->text = spec;
  snprintf(buf, sizeof buf, "%s", spec);
  for (char *s = strtok(buf, ":"); s && n < 4; s = strtok(NULL, ":")) f[n++] = s;
  if (n != 4 || !(pt->md = method_find(f[0]))) return -1;
  memset(&pt->set, 0, sizeof pt->set);
  pt->set.pb = pb;
  pt->set.k = atoi(f[1]);
  pt->set.s = atoi(f[2]);
  pt->set.T = pb->T;
  if (pt->md->integrate) {
    pt->set.tol = atof(f[3]);
    return 0;
  }
  pt->set.nsteps = lround(pb->T / atof(f[3]));
  pt->set.h = pb->T / (double)pt->set.nsteps;
  return pt->set.nsteps > 0 ? 0 : -1;
}

static int timed_point(void *ctx)
{
  Point *pt = ctx;
  Outcome out;
  return method_run(pt->md, &pt->set, NULL, &out);
}

int cmd_ab(int argc, char **argv)
{
  const Problem *pb;
  Point pts[AB_MAX];
  double t[AB_MAX][AB_ROUNDS], med[AB_MAX];
  int n = argc - 4, rounds;
  if (argc < 6 || n > AB_MAX || !(pb = problem_find(argv[2])) || (rounds = atoi(argv[3])) < 1 || rounds > AB_ROUNDS) {
    fputs("usage: bench ab PROBLEM ROUNDS METHOD:K:S:X METHOD:K:S:X [...] (X: h, or the tolerance)\n", stderr);
    return 1;
  }
  for (int i = 0; i < n; i++)
    if (parse_point(pb, argv[4 + i], &pts[i]) != 0) {
      fprintf(stderr, "bench ab: bad point '%s'\n", argv[4 + i]);
      return 1;
    }
  for (int r = 0; r < rounds; r++)
    for (int j = 0; j < n; j++) {
      int i = (r + j) % n;
      if (time_median(timed_point, &pts[i], 0.02, 1, &t[i][r], NULL) != 0) {
        fprintf(stderr, "bench ab: %s failed\n", pts[i].text);
        return 1;
      }
    }
  for (int i = 0; i < n; i++) {
    med[i] = median(t[i], rounds);
    printf("%s,%s,%d,%.6g,%.4g\n", pb->name, pts[i].text, rounds, med[i], med[i] / med[0]);
  }
  return 0;
}
