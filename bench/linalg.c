/* linalg.c - small dense linear algebra for the peers (n <= a few dozen). */
#include "linalg.h"

#include <math.h>

#define SINGULAR 1e-13

int dense_solve(int n, double *A, double *b)
{
  int i, j, k;
  for (k = 0; k < n; k++) {
    int piv = k;
    double colmax = 0;
    for (i = k; i < n; i++) {
      if (fabs(A[i * n + k]) > fabs(A[piv * n + k])) piv = i;
      colmax = fmax(colmax, fabs(A[i * n + k]));
    }
    if (!(fabs(A[piv * n + k]) > 0) || fabs(A[piv * n + k]) < SINGULAR * colmax) return -1;
    if (piv != k) {
      double t;
      for (j = k; j < n; j++) {
        t = A[k * n + j];
        A[k * n + j] = A[piv * n + j];
        A[piv * n + j] = t;
      }
      t = b[k];
      b[k] = b[piv];
      b[piv] = t;
    }
    for (i = k + 1; i < n; i++) {
      double f = A[i * n + k] / A[k * n + k];
      if (f == 0) continue;
      for (j = k + 1; j < n; j++) A[i * n + j] -= f * A[k * n + j];
      b[i] -= f * b[k];
    }
  }
  for (i = n - 1; i >= 0; i--) {
    double acc = b[i];
    for (j = i + 1; j < n; j++) acc -= A[i * n + j] * b[j];
    b[i] = acc / A[i * n + i];
  }
  return 0;
}

void gram(int m, int na, int nb, const double *X, int sx, const double *w, const double *Y, int sy,
          double *C)
{
  int i, a, c;
  for (a = 0; a < na * nb; a++) C[a] = 0;
  for (i = 0; i < m; i++)
    for (a = 0; a < na; a++) {
      double xa = X[i * sx + a] * w[i];
      if (xa == 0) continue;
      for (c = 0; c < nb; c++) C[a * nb + c] += xa * Y[i * sy + c];
    }
}

double maxdiff(int n, const double *x, const double *y)
{
  double e = 0;
  int i;
  for (i = 0; i < n; i++) e = fmax(e, fabs(x[i] - y[i]));
  return e;
}

double maxabs(int n, const double *x)
{
  double e = 0;
  int i;
  for (i = 0; i < n; i++) e = fmax(e, fabs(x[i]));
  return e;
}
