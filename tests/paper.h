/* paper.h - the experiments behind the paper's tables tab0..tab3, run on
 * the committed generated solvers and measured the way the paper measured
 * them (tests/data/README.md). Used by the tables test and `make tables`. */
#ifndef HBVM_TESTS_PAPER_H
#define HBVM_TESTS_PAPER_H

typedef struct {
  double e_s, e_lambda, e_H, e_g, e_hc;
  double iters_mean;
  int iters_max;
} PaperErrors;

/* One row of a table: HBVM(k,s) of the table's problem with the table's
 * step size for n. Returns 0, or the nonzero code of a failed step. */
int paper_row(int table, int s, int n, PaperErrors *e);

/* The problem name, the k of the method for s, the step size for n and
 * the number of steps of a table row. */
const char *paper_problem(int table);
int paper_k(int table, int s);
double paper_h(int table, int n);
long paper_steps(int table, int n);
/* How e_s (and e_lambda) of a table are measured, in words. */
const char *paper_measure(int table);

/* One row of a paper table as printed (tests/data/tabT.csv). */
typedef struct {
  int s, n;
  double e_s, e_lambda, e_H, e_g, e_hc;
} PaperRow;

/* Read tests/data/tabT.csv (relative to dir); returns the number of rows
 * stored in rows (at most max), or -1. */
int paper_read(const char *dir, int table, PaperRow *rows, int max);

#endif
