/* count.h - steps taken inside a function callgrind can isolate. */
#ifndef BENCH_COUNT_H
#define BENCH_COUNT_H

#include "bench.h"

/* Take n steps of size h; the total iterations, or -1 if a step failed. */
long count_steps(const Stepper *sp, double h, long n);

#endif
