/* steps.c - run N steps of a generated solver (compiled with -DP=prefix and
 * -include prefix.h) and print the mean iterations per step and the largest
 * |H - H0| (0 when not asked for: argv[3] = "energy"); the program the
 * instruction counts of bench/lean/run.sh are taken on. Exit 2 if a step
 * fails. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CAT2(a, b) a##b
#define CAT(a, b) CAT2(a, b)
#define F(name) CAT(P, name)

int main(int argc, char **argv) {
  long n = argc > 1 ? atol(argv[1]) : 100;
  double h = argc > 2 ? atof(argv[2]) : 0.01;
  F(_state) x;
  F(_stats) st;
  long iters = 0;
  int energy = argc > 3 && !strcmp(argv[3], "energy");
  F(_init)(&x, NULL, NULL);
  double H0 = energy ? F(_energy)(&x, NULL) : 0, dH = 0;
  for (long i = 0; i < n; i++) {
    int rc = F(_step)(&x, h, NULL, &st);
    if (rc) {
      fprintf(stderr, "step %ld failed: %s\n", i, F(_strerror)(rc));
      return 2;
    }
    iters += st.iters;
    if (energy) dH = fmax(dH, fabs(F(_energy)(&x, NULL) - H0));
  }
  printf("%.3f %.3e\n", (double)iters / (double)n, dH);
  return 0;
}
