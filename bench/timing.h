/* timing.h - CPU time, the median of timed repeats, and CSV fields. */
#ifndef BENCH_TIMING_H
#define BENCH_TIMING_H

#include <stdio.h>

/* CPU time of the process in seconds (CLOCK_PROCESS_CPUTIME_ID). */
double cpu_seconds(void);

/* The median of v[0..n) (n > 0), sorting v. */
double median(double *v, int n);

/* Something to time: returns 0 on success. */
typedef int (*TimedFn)(void *ctx);

/* The median over `repeats` timed repeats of the CPU time of one call of
 * fn, each repeat calling fn as many times as it takes to last at least
 * min_seconds and dividing. *calls (if not NULL) receives the calls per
 * repeat. 0, or fn's failure code. */
int time_median(TimedFn fn, void *ctx, double min_seconds, int repeats, double *seconds, long *calls);

/* Write the CSV field v to f with the printf format fmt, or an empty field
 * when v is NaN; then sep (',' or '\n'). */
void csv_num(FILE *f, const char *fmt, double v, char sep);

#endif
