/* linalg.h - the small dense kernels the peers share. */
#ifndef BENCH_LINALG_H
#define BENCH_LINALG_H

/* Solve the n x n system A x = b in place (A row-major, destroyed; b
 * overwritten by x) by Gaussian elimination with partial pivoting.
 * 0, or -1 when a pivot is below 1e-13 times the largest entry of its
 * column (singular to working precision). */
int dense_solve(int n, double *A, double *b);

/* C = X' diag(w) Y for X (m x na) and Y (m x nb), row-major with the
 * given row strides; C is na x nb, row-major. */
void gram(int m, int na, int nb, const double *X, int sx, const double *w, const double *Y, int sy,
          double *C);

/* max_i |x_i - y_i|. */
double maxdiff(int n, const double *x, const double *y);

/* max_i |x_i|. */
double maxabs(int n, const double *x);

#endif
