/* errest.h - what check_errest.c shares with the adaptive-step tests. */
#ifndef HBVM_TESTS_ERREST_H
#define HBVM_TESTS_ERREST_H

typedef struct {
  double mean, lo, hi; /* geometric mean, smallest, largest of true / estimate */
  int n;               /* steps measured */
} Ratios;

/* A solver stepped N times by h on a problem with a reference (below). */
typedef struct {
  const char *problem, *solver;
  double h;
  long N;
} StepCase;

/* Kepler, e = 0.6 (models/kepler.ham), exactly at time t. */
void kepler_exact(double t, double *q, double *p);
/* The reference at t_n = n h, n = 0..N: tests/ref.c, or Kepler's closed form. */
int errest_reference(const char *problem, double h, long N, int m, double *q, double *p);

#endif
