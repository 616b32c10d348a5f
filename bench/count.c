/* count.c - the steps whose instructions callgrind counts
 * (valgrind --tool=callgrind --toggle-collect=count_steps). Kept in a file
 * of its own so that the compiler cannot inline it into the caller. */
#include "count.h"

long count_steps(const Stepper *sp, double h, long n)
{
  long i, iters = 0;
  for (i = 0; i < n; i++) {
    int it = 0;
    if (sp->step(sp->state, h, &it) != 0) return -1;
    iters += it;
  }
  return iters;
}
