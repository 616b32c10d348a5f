/* bench/stiff/mincost.c - one Newton step of a generated solver whose
 * iteration is cut short, for callgrind (bench/stiff/bound.sh): compiled
 * with -DSOLVER=NAME -DSOLVER_H='"NAME.h"' against NAME.c built with
 * NAME_MAXITER = N (1 or 2), NAME_REUSE = -1 and NAME_REFRESH = 1, so that
 * the step from the model's initial values takes exactly one factorisation
 * and N iterations (sweep and solve), then fails and rolls back. Callgrind
 * counts one_step (--toggle-collect=one_step): the fewest work a Newton
 * step of this (k, s) can do, the end of an accepted step aside.
 * Usage: mincost H; prints rc, Newton iterations and factorisations. */
#include <stdio.h>
#include <stdlib.h>

#include SOLVER_H

#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
#define F(suffix) CAT(SOLVER, suffix)

/* The step counted: kept out of line so that callgrind can toggle on it. */
__attribute__((noinline)) int one_step(F(_state) * x, double h, F(_stats) * st) { return F(_step)(x, h, NULL, st); }

int main(int argc, char **argv)
{
  static F(_state) x;
  F(_stats) st;
  int rc;
  if (argc != 2) {
    fprintf(stderr, "usage: mincost H\n");
    return 2;
  }
  F(_init)(&x, NULL, NULL);
  rc = one_step(&x, atof(argv[1]), &st);
  printf("%d %d %d\n", rc, st.newton, st.factors);
  return 0;
}
