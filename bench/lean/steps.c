/* steps.c - run N steps of a generated solver (compiled with -DP=prefix and
 * -include prefix.h) and print the mean iterations per step; the program the
 * instruction counts of bench/lean/run.sh are taken on. */
#include <stdio.h>
#include <stdlib.h>

#define CAT2(a, b) a##b
#define CAT(a, b) CAT2(a, b)
#define F(name) CAT(P, name)

int main(int argc, char **argv) {
  long n = argc > 1 ? atol(argv[1]) : 100;
  double h = argc > 2 ? atof(argv[2]) : 0.01;
  F(_state) x;
  F(_stats) st;
  long iters = 0;
  F(_init)(&x, NULL, NULL);
  for (long i = 0; i < n; i++) {
    int rc = F(_step)(&x, h, NULL, &st);
    if (rc) {
      fprintf(stderr, "step %ld failed: %s\n", i, F(_strerror)(rc));
      return 2;
    }
    iters += st.iters;
  }
  printf("%.3f\n", (double)iters / (double)n);
  return 0;
}
