/* paper.c - the paper's experiments (section 6) on the generated solvers.
 *
 * tab0 (pendulum) and tab1 (conical pendulum) are measured against the
 * reference solutions of ref.c; tab2 and tab3 as the paper measured them,
 * against the same method with step h/2 sampled at t = 0, 0.1, ..., 10
 * (an independent implementation showed that this, not a converged
 * reference, reproduces their printed digits; see tests/data/README.md). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "paper.h"
#include "ref.h"
#include "solvers.h"

static const char *const problems[4] = {"pendulum", "conical", "modified", "satellites"};

const char *paper_problem(int table) { return problems[table]; }

int paper_k(int table, int s) { return table == 2 ? 3 * s : table == 3 ? 6 : s; }

static double period(void) { return pow(2, 0.75) * 3.14159265358979323846; }

double paper_h(int table, int n) { return table == 1 ? period() / n : 0.1 * ldexp(1, -n); }

long paper_steps(int table, int n) { return table == 1 ? 10L * n : 100L << n; }

const char *paper_measure(int table) {
  static const char *const measures[4] = {
      "e_s = max_n ||(q,p)_n - (q,p)(t_n)||_1; e_lambda = max_n |lambda_n - lambda(t_{n-1})|, lambda_n from the "
      "step t_{n-1} -> t_n",
      "e_s = max_k ||(q,p)(kT) error||_inf at whole periods; e_lambda = max_n |lambda_n - 2^-1/2|",
      "e_s = max_j ||(q,p)_h - (q,p)_{h/2}||_inf at t = 0.1j (difference from the h/2 run, as in the paper); "
      "e_lambda likewise at the steps ending at 0.1j + h",
      "as tab2; e_hc = max_n ||grad g' M^-1 p||_1"};
  return measures[table];
}

/* A run of a solver: states after every step. */
typedef struct {
  const Solver *sv;
  long N;
  double *q, *p, *lambda; /* (N+1) x m, (N+1) x m, (N+1) x nu */
  double e_H, e_g, e_hc, e_hc1;
  long iters;
  int iters_max;
} Run;

static double norm_inf(const double *v, int n) {
  double r = 0;
  for (int i = 0; i < n; i++) r = fmax(r, fabs(v[i]));
  return r;
}

static double norm_1(const double *v, int n) {
  double r = 0;
  for (int i = 0; i < n; i++) r += fabs(v[i]);
  return r;
}

static void measure_invariants(Run *r, void *x, double H0) {
  double g[16], hc[16];
  int nu = r->sv->nu;
  r->e_H = fmax(r->e_H, fabs(r->sv->energy(x) - H0));
  if (!nu) return;
  r->sv->constraints(x, g);
  r->sv->hidden(x, hc);
  r->e_g = fmax(r->e_g, norm_inf(g, nu));
  r->e_hc = fmax(r->e_hc, norm_inf(hc, nu));
  r->e_hc1 = fmax(r->e_hc1, norm_1(hc, nu));
}

// Run N steps of size h from the model's initial values, keeping every
// state and the running maxima. Returns 0 or the failing step's code.
static int run(Run *r, const Solver *sv, double h, long N) {
  memset(r, 0, sizeof *r);
  r->sv = sv;
  r->N = N;
  int m = sv->m, nu = sv->nu ? sv->nu : 1;
  r->q = malloc((size_t)(N + 1) * m * sizeof(double));
  r->p = malloc((size_t)(N + 1) * m * sizeof(double));
  r->lambda = calloc((size_t)(N + 1) * nu, sizeof(double));
  void *x = malloc(sv->state_size);
  if (!r->q || !r->p || !r->lambda || !x) abort();
  sv->init(x, NULL, NULL);
  double H0 = sv->energy(x);
  int rc = 0;
  for (long n = 0; n <= N; n++) {
    if (n > 0) {
      int it = 0;
      if ((rc = sv->step(x, h, &it))) break;
      r->iters += it;
      if (it > r->iters_max) r->iters_max = it;
    }
    memcpy(r->q + n * m, solver_q(sv, x), (size_t)m * sizeof(double));
    memcpy(r->p + n * m, solver_p(sv, x), (size_t)m * sizeof(double));
    memcpy(r->lambda + n * nu, solver_lambda(sv, x), (size_t)sv->nu * sizeof(double));
    measure_invariants(r, x, H0);
  }
  free(x);
  return rc;
}

static void run_free(Run *r) {
  free(r->q);
  free(r->p);
  free(r->lambda);
}

// ||(q,p)_a[n] - (q,p)_b[nb]|| in the 1- or inf-norm.
static double state_diff(const Run *a, long n, const double *qb, const double *pb, int one_norm) {
  int m = a->sv->m;
  double d[64];
  for (int i = 0; i < m; i++) {
    d[i] = a->q[n * m + i] - qb[i];
    d[m + i] = a->p[n * m + i] - pb[i];
  }
  return one_norm ? norm_1(d, 2 * m) : norm_inf(d, 2 * m);
}

// tab0 and tab1: errors against the reference solution at every step.
static void against_reference(int table, const Run *r, double h, PaperErrors *e) {
  const Solver *sv = r->sv;
  int m = sv->m, nu = sv->nu;
  long N = r->N;
  double *q = malloc((size_t)(N + 1) * m * sizeof(double)), *p = malloc((size_t)(N + 1) * m * sizeof(double));
  double *lam = malloc((size_t)(N + 1) * nu * sizeof(double));
  if (!q || !p || !lam || ref_solve(problems[table], h, N, q, p, lam)) abort();
  long per = table == 1 ? N / 10 : 1; /* tab1: whole periods only */
  for (long n = 0; n <= N; n += per)
    e->e_s = fmax(e->e_s, state_diff(r, n, q + n * m, p + n * m, table == 0));
  for (long n = 1; n <= N; n++)
    for (int a = 0; a < nu; a++) {
      double ref = table == 1 ? sqrt(0.5) : lam[(n - 1) * nu + a];
      e->e_lambda = fmax(e->e_lambda, fabs(r->lambda[n * nu + a] - ref));
    }
  free(q);
  free(p);
  free(lam);
}

// tab2 and tab3: differences from the run with step h/2 at t = 0.1 j.
static void against_half_step(const Run *r, const Run *half, long per, PaperErrors *e) {
  int m = r->sv->m, nu = r->sv->nu;
  for (long n = 0; n <= r->N; n += per) {
    e->e_s = fmax(e->e_s, state_diff(r, n, half->q + 2 * n * m, half->p + 2 * n * m, 0));
    if (n + 1 > r->N) continue;
    for (int a = 0; a < nu; a++)
      e->e_lambda = fmax(e->e_lambda, fabs(r->lambda[(n + 1) * nu + a] - half->lambda[(2 * n + 1) * nu + a]));
  }
}

int paper_row(int table, int s, int n, PaperErrors *e) {
  memset(e, 0, sizeof *e);
  const Solver *sv = solver_for(problems[table], paper_k(table, s), s);
  if (!sv) return -1;
  double h = paper_h(table, n);
  long N = paper_steps(table, n);
  Run r, half;
  int rc = run(&r, sv, h, N);
  if (!rc && table <= 1) against_reference(table, &r, h, e);
  if (!rc && table >= 2) {
    rc = run(&half, sv, h / 2, 2 * N);
    if (!rc) against_half_step(&r, &half, 1L << n, e);
    run_free(&half);
  }
  e->e_H = r.e_H;
  e->e_g = r.e_g;
  e->e_hc = table == 3 ? r.e_hc1 : r.e_hc;
  e->iters_mean = (double)r.iters / (double)N;
  e->iters_max = r.iters_max;
  run_free(&r);
  return rc;
}

int paper_read(const char *dir, int table, PaperRow *rows, int max) {
  char path[4096], line[512];
  snprintf(path, sizeof path, "%s/tab%d.csv", dir, table);
  FILE *f = fopen(path, "r");
  if (!f) return -1;
  int n = 0;
  if (!fgets(line, sizeof line, f)) n = -1; /* header */
  while (n >= 0 && n < max && fgets(line, sizeof line, f)) {
    PaperRow *r = &rows[n];
    if (sscanf(line, "%d,%d,%lf,%lf,%lf,%lf,%lf", &r->s, &r->n, &r->e_s, &r->e_lambda, &r->e_H, &r->e_g, &r->e_hc) == 7)
      n++;
  }
  fclose(f);
  return n;
}
