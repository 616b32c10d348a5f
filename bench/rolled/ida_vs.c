/* ida_vs.c - the rolled solver against IDA (ida_vs.h). */
#include "ida_vs.h"

#include <stdio.h>
#include <stdlib.h>

#include "linalg.h"
#include "timing.h"

#define MAXREPS 64
#define MAXTOLS 8
#define MAXH 8

/* Parse up to max numbers separated by commas from s into v; their count. */
static int numbers(const char *s, double *v, int max)
{
  int k = 0;
  char *end;
  while (k < max) {
    v[k++] = strtod(s, &end);
    if (*end != ',') break;
    s = end + 1;
  }
  return k;
}

/* The max norm of (q, p) - (qr, pr), m coordinates each. */
static double error_of(int m, const double *q, const double *p, const double *qr, const double *pr)
{
  double eq = maxdiff(m, q, qr), ep = maxdiff(m, p, pr);
  return eq > ep ? eq : ep;
}

/* Runs and timings (see ida_vs.h); w holds 6 arrays of m reals. */
static int compare(const IdaVs *v, double T, const double *hs, int nh, const double *tol, int ntol, int reps, double *w)
{
  static double tr[MAXH][MAXREPS], ti[MAXTOLS][MAXREPS];
  double *q = w, *p = w + v->m, *qr = w + 2 * v->m, *pr = w + 3 * v->m, *qh = w + 4 * v->m, *ph = w + 5 * v->m;
  double er[MAXH], e[MAXTOLS], t0;
  long n[MAXH], steps[MAXTOLS];
  int r, j, k, m = v->m;
  for (k = 0; k < nh; k++) n[k] = (long)(T / hs[k] + 0.5);
  /* the reference: Richardson on the rolled solver's order 2 from ref_h / 4
   * and ref_h / 8, checked against IDA at ref_tol (on stderr) */
  if (v->rolled(v->ref_h / 8, (long)(8 * T / v->ref_h + 0.5), qr, pr) ||
      v->rolled(v->ref_h / 4, (long)(4 * T / v->ref_h + 0.5), qh, ph))
    return 1;
  for (j = 0; j < m; j++) {
    qr[j] += (qr[j] - qh[j]) / 3;
    pr[j] += (pr[j] - ph[j]) / 3;
  }
  if (v->ida(T, v->ref_tol, qh, ph, &steps[0])) /* a check only: go on */
    fprintf(stderr, "%s: N = %d: IDA failed at %g, the reference is not checked\n", v->prog, v->n, v->ref_tol);
  else
    fprintf(stderr, "%s: N = %d: the reference against IDA at %g: %.2g\n", v->prog, v->n, v->ref_tol,
            error_of(m, qh, ph, qr, pr));
  for (k = 0; k < nh; k++) {
    if (v->rolled(hs[k], n[k], q, p)) return 1;
    er[k] = error_of(m, q, p, qr, pr);
  }
  for (j = 0; j < ntol; j++) {
    if (v->ida(T, tol[j], q, p, &steps[j])) {
      fprintf(stderr, "%s: IDA failed at tolerance %g\n", v->prog, tol[j]);
      return 1;
    }
    e[j] = error_of(m, q, p, qr, pr);
  }
  for (r = 0; r < reps; r++) {
    for (k = 0; k < nh; k++) {
      t0 = cpu_seconds();
      if (v->rolled(hs[k], n[k], q, p)) return 1;
      tr[k][r] = cpu_seconds() - t0;
    }
    for (j = 0; j < ntol; j++) {
      t0 = cpu_seconds();
      if (v->ida(T, tol[j], q, p, &steps[j])) return 1;
      ti[j][r] = cpu_seconds() - t0;
    }
  }
  for (k = 0; k < nh; k++) {
    double md = median(tr[k], reps);
    printf("%d,rolled,%g,%g,%ld,%.1f,%.1f,%.2g\n", v->n, T, hs[k], n[k], md / (double)n[k] * 1e9, md / T * 1e6, er[k]);
  }
  for (j = 0; j < ntol; j++) {
    double md = median(ti[j], reps);
    printf("%d,%s,%g,%g,%ld,%.1f,%.1f,%.2g\n", v->n, v->label, T, tol[j], steps[j], md / (double)steps[j] * 1e9,
           md / T * 1e6, e[j]);
  }
  return 0;
}

int ida_vs_main(const IdaVs *v, int argc, char **argv)
{
  double hs[MAXH], tol[MAXTOLS], *w;
  int reps, nh, ntol, rc;
  if (argc != 5) {
    fprintf(stderr, "usage: %s T h,... reps tol,...\n", v->prog);
    return 2;
  }
  nh = numbers(argv[2], hs, MAXH);
  reps = atoi(argv[3]);
  ntol = numbers(argv[4], tol, MAXTOLS);
  if (reps < 1 || reps > MAXREPS) reps = MAXREPS;
  w = malloc(6 * (size_t)v->m * sizeof *w);
  rc = !w || compare(v, atof(argv[1]), hs, nh, tol, ntol, reps, w);
  if (rc) fprintf(stderr, "%s: a run failed\n", v->prog);
  free(w);
  return rc;
}

int ida_vs_run(IdaSystem *sys, int per, int ndiff, double alg_atol, double *w, double *y, const double *yd, double T,
               long *steps)
{
  int i;
  for (i = 0; i < sys->n; i++) {
    w[i] = i % per < ndiff;
    w[sys->n + i] = i % per < ndiff ? sys->rtol : alg_atol;
  }
  sys->id = w;
  sys->atol = w + sys->n;
  return ida_run(sys, y, yd, T, 10000000, steps) != 0;
}
