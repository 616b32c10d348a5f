/* timing.c - CPU timing by median of repeats, and CSV output. */
#define _POSIX_C_SOURCE 200809L
#include "timing.h"

#include <math.h>
#include <stdlib.h>
#include <time.h>

#define MAXREPEATS 64

double cpu_seconds(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

double median(double *v, int n)
{
  qsort(v, (size_t)n, sizeof v[0], cmp_double);
  return v[n / 2];
}

/* Call fn n times; the CPU time they took in *dt. */
static int timed_calls(TimedFn fn, void *ctx, long n, double *dt)
{
  double t0 = cpu_seconds();
  long i;
  for (i = 0; i < n; i++) {
    int rc = fn(ctx);
    if (rc != 0) return rc;
  }
  *dt = cpu_seconds() - t0;
  return 0;
}

/* Calibrate the calls per repeat on the first repeats (until one lasts
 * min_seconds), then take the median of `repeats` repeats. */
int time_median(TimedFn fn, void *ctx, double min_seconds, int repeats, double *seconds, long *calls)
{
  double t[MAXREPEATS], dt;
  long n = 1;
  int r, rc;
  if (repeats > MAXREPEATS) repeats = MAXREPEATS;
  for (;;) {
    if ((rc = timed_calls(fn, ctx, n, &dt)) != 0) return rc;
    if (dt >= min_seconds) break;
    n = dt > 0 ? (long)ceil(n * 1.2 * min_seconds / dt) : 10 * n;
  }
  t[0] = dt / (double)n;
  for (r = 1; r < repeats; r++) {
    if ((rc = timed_calls(fn, ctx, n, &dt)) != 0) return rc;
    t[r] = dt / (double)n;
  }
  qsort(t, (size_t)repeats, sizeof t[0], cmp_double);
  *seconds = repeats % 2 ? t[repeats / 2] : 0.5 * (t[repeats / 2 - 1] + t[repeats / 2]);
  if (calls) *calls = n;
  return 0;
}

void csv_num(FILE *f, const char *fmt, double v, char sep)
{
  if (!isnan(v)) fprintf(f, fmt, v);
  fputc(sep, f);
}
