/* method.c - the constants of HBVM(k,s), the choice of k, and the advice
 * of --check on s and k.
 *
 * Gauss-Legendre nodes and weights on [0,1] come from GSL, refined by
 * Newton's method in long double; the shifted, normalised Legendre
 * polynomials P_j(x) = sqrt(2j+1) L_j(2x-1) from their three-term
 * recurrence; the integrals int_0^c P_j from the closed form of METHOD.md.
 * The tables of the stages (c, b, P_j(c), b P_j(c), int_0^c P_j) are
 * computed in long double and rounded once, so that a value that is exact,
 * such as P_1 = +-1 at the nodes of k = 2, is exact in the table and the
 * DAG folds its product away (GSL's nodes were up to a few ulps off); the
 * rounding is faithful, not always correct (a value within about 1e-19 of
 * a tie between two doubles may go either way). The warm start's E from
 * its closed form the same way, the two-step start's E2 from a linear
 * solve in long double. All are printed into the generated code with 17 significant
 * digits. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_integration.h>

#include "hbvmgen.h"

#define NONPOLY_EXTRA_K 12 /* k = 2s + 12 for a non-polynomial U or g */

// The Legendre polynomial L_j(t) on [-1,1] by its three-term recurrence,
// in long double; *prev gets L_{j-1}(t) (0 for j = 0).
static long double legendre_ld(int j, long double t, long double *prev) {
  long double lm1 = 0, l = 1;
  for (int n = 0; n < j; n++) {
    long double next = n == 0 ? t : ((2 * n + 1) * t * l - n * lm1) / (n + 1);
    lm1 = l;
    l = next;
  }
  if (prev) *prev = lm1;
  return l;
}

// P_j(x) = sqrt(2j+1) L_j(2x-1): orthonormal on [0,1]; long double in, long
// double out, so that the tables round the exact values once (P_1 at the
// nodes of k = 2 is exactly +-1, not 1 - 2^-53).
static long double pshift_ld(int j, long double x) { return sqrtl(2.0L * j + 1) * legendre_ld(j, 2 * x - 1, NULL); }

static long double xi_ld(int j) { return 1 / (2 * sqrtl(fabsl(4.0L * j * j - 1))); }

// The Gauss node c of k on [0,1] (GSL's, in double) refined by two Newton
// steps on L_k(2x-1) in long double, and its weight 1 / ((1 - t^2) L_k'(t)^2).
static long double gauss_node_ld(int k, double c, long double *weight) {
  long double t = 2.0L * c - 1, prev, l, dl = 1;
  for (int it = 0; it < 2; it++) {
    l = legendre_ld(k, t, &prev);
    dl = k * (t * l - prev) / (t * t - 1);
    t -= l / dl;
  }
  l = legendre_ld(k, t, &prev);
  dl = k * (t * l - prev) / (t * t - 1);
  *weight = 1 / ((1 - t * t) * dl * dl);
  return (1 + t) / 2;
}

static long double binomial_ld(int n, int k) {
  long double r = 1;
  for (int i = 1; i <= k; i++) r = r * (n - k + i) / i;
  return r;
}

// The smallest k for which k Gauss nodes integrate a function of degree deg
// along a step's degree-s polynomial exactly: s deg <= 2k.
static int exact_k(int s, int deg) { return (s * deg + 1) / 2; }

// Whether k Gauss nodes integrate H and g exactly along a step's degree-s
// polynomial: both polynomial, each within exact_k.
int method_quadrature_exact(int k, int s, int degU, int degg) {
  return degU != DEG_NONPOLY && degg != DEG_NONPOLY && exact_k(s, degU) <= k && exact_k(s, degg) <= k;
}

// The smallest k >= s for which the Gauss quadrature conserves H and g
// exactly: H and g polynomial of degree <= 2k/s (the kinetic energy has
// degree 2).
//
// For a non-polynomial U or g no k is exact. With the constant multiplier
// (and without constraints) we take k = 2s + 12, the smallest rule that kept
// max |H - H0| within a few tens of ulps at every step size at which the
// fixed point converged, for Kepler (e = 0.6), the tethered satellites and
// the pendulum in its angle, s = 1..3 (bench/lean/kauto.sh,
// bench/results/kauto.csv); k = max(2s, 6) did so only well below the
// convergence limit (Kepler, s = 2, h = T/16: 2e11 ulps). Near that limit
// k = 16 leaves 1e-12..2e-11 on Kepler (h = 0.55..0.70; k = 24: 1e-15).
//
// The polynomial family (fam == MULT_POLY, with constraints) restores H by
// its rescale whatever k is, and the non-polynomial parts need no more
// than Gauss collocation's k = s: measured on the satellites (U = -1/|q|,
// s = 2), k = 2 gives errors 5x smaller than k = 3..16 with H at 1e-16,
// and with g = sqrt(x^2 + y^2) - 1, k = s keeps |g| at 1e-16 where k = 3
// leaves 5e-12.
int method_auto_k(int s, int degU, int degg, MultFamily fam, const char **why) {
  int k = s;
  *why = "H and g are at most quadratic: k = s (Gauss collocation) conserves both";
  int degs[2] = {degU, degg};
  for (int i = 0; i < 2; i++) {
    if (degs[i] == DEG_NONPOLY) continue;
    int need = exact_k(s, degs[i]);
    if (need > k) {
      k = need;
      *why = "smallest k with deg <= 2k/s: the quadrature is exact for H and g";
    }
  }
  if ((degU == DEG_NONPOLY || degg == DEG_NONPOLY) && fam == MULT_POLY) {
    *why = "U or g is not a polynomial: k = s for it (the rescale keeps H; measured, docs/choosing.md), and "
           "the polynomial parts integrated exactly";
  } else if (degU == DEG_NONPOLY || degg == DEG_NONPOLY) {
    int need = 2 * s + NONPOLY_EXTRA_K;
    if (need > k) k = need;
    *why = "U or g is not a polynomial: k = 2s+12 keeps |H - H0| at round-off for every h at which the "
           "iteration converges but the last few percent below its limit (measured); a smaller -k is "
           "cheaper when h is well below that limit";
  }
  return k;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

// Solve A x = b in place for n unknowns (A row-major n x n, b into x) by
// Gaussian elimination with partial pivoting, in long double.
static void solve_ld(long double *A, long double *b, int n) {
  for (int c = 0; c < n; c++) {
    int p = c;
    for (int r = c + 1; r < n; r++)
      if (fabsl(A[r * n + c]) > fabsl(A[p * n + c])) p = r;
    for (int t = 0; t < n && p != c; t++) {
      long double a = A[c * n + t];
      A[c * n + t] = A[p * n + t];
      A[p * n + t] = a;
    }
    long double bb = b[c];
    b[c] = b[p];
    b[p] = bb;
    for (int r = c + 1; r < n; r++) {
      long double f = A[r * n + c] / A[c * n + c];
      for (int t = c; t < n; t++) A[r * n + t] -= f * A[c * n + t];
      b[r] -= f * b[c];
    }
  }
  for (int c = n - 1; c >= 0; c--) {
    for (int t = c + 1; t < n; t++) b[c] -= A[c * n + t] * b[t];
    b[c] /= A[c * n + c];
  }
}

// The two-step warm start for steps of equal size: the polynomial p of
// degree 2s-1 whose Legendre coefficients on the last step [0,1] and the one
// before [-1,0] are gamma and gamma_prev, projected on the next step [1,2]:
// gamma_next_j = sum_i E2[j][i] gamma_i + E2[j][s + i] gamma_prev_i. With
// p in the Legendre basis of [-1,2] (well conditioned), E2 = V C^-1 where
// C[i][d] = int_0^1 P_i(x) phi_d(x) dx (and phi_d(x - 1) for rows s + i),
// V[j][d] = int_0^1 P_j(x) phi_d(1 + x) dx, by Gauss with 2s nodes (exact),
// all in long double and rounded once (so that E2 for s = 2 holds -5.5, 6.5
// and 9.5, not values a few ulps off).
static double *two_step_table(int s) {
  int n = 2 * s;
  long double *C = calloc((size_t)n * n, sizeof *C), *V = calloc((size_t)s * n, sizeof *V);
  long double *row = malloc((size_t)n * sizeof *row);
  gsl_integration_glfixed_table *t = gsl_integration_glfixed_table_alloc((size_t)n);
  if (!C || !V || !row || !t) internal_error("cannot build the two-step warm start for s=%d", s);
  for (int l = 0; l < n; l++) {
    double x0, w0;
    gsl_integration_glfixed_point(0, 1, (size_t)l, &x0, &w0, t);
    long double w, x = gauss_node_ld(n, x0, &w);
    for (int d = 0; d < n; d++)
      for (int i = 0; i < s; i++) {
        long double Pi = pshift_ld(i, x) * w;
        C[d * n + i] += Pi * pshift_ld(d, (x + 1) / 3); /* C', row d */
        C[d * n + s + i] += Pi * pshift_ld(d, x / 3);
        V[i * n + d] += Pi * pshift_ld(d, (x + 2) / 3);
      }
  }
  double *E2 = arena_alloc((size_t)s * n * sizeof(double));
  long double *A = malloc((size_t)n * n * sizeof *A);
  if (!A) internal_error("cannot build the two-step warm start for s=%d", s);
  for (int j = 0; j < s; j++) { /* row j of V C^-1: C' y = V[j]' */
    for (int e = 0; e < n * n; e++) A[e] = C[e];
    for (int i = 0; i < n; i++) row[i] = V[j * n + i];
    solve_ld(A, row, n);
    for (int i = 0; i < n; i++) E2[j * n + i] = (double)row[i];
  }
  free(A);
  free(C);
  free(V);
  free(row);
  gsl_integration_glfixed_table_free(t);
  return E2;
}

// Fill the constants of HBVM(k,s).
Method *method_new(int k, int s, MultFamily family) {
  Method *me = arena_alloc(sizeof *me);
  me->k = k;
  me->s = s;
  me->family = family;
  me->c = arena_alloc((size_t)k * sizeof(double));
  me->b = arena_alloc((size_t)k * sizeof(double));
  gsl_integration_glfixed_table *t = gsl_integration_glfixed_table_alloc((size_t)k);
  double (*cb)[2] = malloc((size_t)k * sizeof *cb);
  if (!t || !cb) internal_error("cannot build the Gauss-Legendre table for k=%d", k);
  for (int l = 0; l < k; l++) gsl_integration_glfixed_point(0, 1, (size_t)l, &cb[l][0], &cb[l][1], t);
  qsort(cb, (size_t)k, sizeof *cb, cmp_double);
  for (int l = 0; l < k; l++) {
    me->c[l] = cb[l][0];
    me->b[l] = cb[l][1];
  }
  free(cb);
  gsl_integration_glfixed_table_free(t);
  me->Ihat = arena_alloc((size_t)k * s * sizeof(double));
  me->W = arena_alloc((size_t)k * s * sizeof(double));
  me->Phat = arena_alloc((size_t)k * s * sizeof(double));
  me->xi = arena_alloc((size_t)(s + 1) * sizeof(double));
  for (int j = 0; j <= s; j++) me->xi[j] = (double)xi_ld(j);
  for (int l = 0; l < k; l++) {
    long double b, c = gauss_node_ld(k, me->c[l], &b); /* each table entry rounded once */
    me->c[l] = (double)c;
    me->b[l] = (double)b;
    for (int j = 0; j < s; j++) {
      long double P = pshift_ld(j, c);
      me->Phat[l * s + j] = (double)P;
      me->W[l * s + j] = (double)(b * P);
      me->Ihat[l * s + j] =
          (double)(j == 0 ? c : xi_ld(j + 1) * pshift_ld(j + 1, c) - xi_ld(j) * pshift_ld(j - 1, c));
    }
  }
  /* Warm start: gamma_j of the next step (size r*h) from this step's
   * polynomial: E_ji(r) = int_0^1 P_j(x) P_i(1 + r x) dx = sum_d E_jid r^d,
   * with P_i(1 + y) = sqrt(2i+1) sum_d C(i,d) C(i+d,d) y^d and
   * int_0^1 P_j(x) x^d dx = sqrt(2j+1) d!^2 / ((d-j)! (d+j+1)!) for d >= j
   * (0 below): E_jid is 0 unless j <= d <= i, and E_jjj = 1, so a same-size
   * start takes gamma_j as it is (in long double, rounded once). */
  me->E = arena_alloc((size_t)s * s * s * sizeof(double));
  for (int j = 0; j < s; j++)
    for (int i = 0; i < s; i++)
      for (int d = 0; d < s; d++) {
        long double v = 0;
        if (j <= d && d <= i) {
          v = sqrtl((2.0L * i + 1) * (2.0L * j + 1)) * binomial_ld(i, d) * binomial_ld(i + d, d);
          for (int n = 1; n <= d; n++) v *= n; /* d!^2 / ((d-j)! (d+j+1)!) = d!/(d+j+1)! * d!/(d-j)! */
          for (int n = 1; n <= d + j + 1; n++) v /= n;
          for (int n = d - j + 1; n <= d; n++) v *= n;
        }
        me->E[(j * s + i) * s + d] = (double)v;
      }
  me->E2 = two_step_table(s);
  return me;
}

// The name of a function of the language with a kink or a jump that U or g
// uses, or NULL when they use none.
static const char *nonsmooth_function(const Model *mod) {
  static const struct {
    Op op;
    const char *name;
  } kinks[] = {{OP_ABS, "abs"}, {OP_SIGN, "sign"}, {OP_MIN, "min"}, {OP_MAX, "max"}, {OP_FLOOR, "floor or mod"}};
  const Dag *d = mod->dag;
  int *roots = xmalloc((size_t)(mod->nu + 1) * sizeof *roots);
  unsigned char *mark = xcalloc((size_t)d->n, 1);
  roots[0] = mod->U;
  if (mod->nu) memcpy(roots + 1, mod->g, (size_t)mod->nu * sizeof *roots);
  dag_reach(d, roots, mod->nu + 1, mark);
  const char *found = NULL;
  for (int id = 0; id < d->n && !found; id++)
    for (size_t i = 0; mark[id] && i < sizeof kinks / sizeof kinks[0]; i++)
      if (d->nodes[id].op == kinks[i].op) found = kinks[i].name;
  free(roots);
  free(mark);
  return found;
}

// --check's advice: the s and k measured best for this kind of model at
// errors of 1e-6 and below (docs/choosing.md, where the figures come from:
// the outer solar system, models/solar.ham, and the pendulum of
// bench/results/work_precision.csv), whether the options given are those,
// and what a kink, the constant multiplier or the step size limit of the
// fixed-point iteration mean for it.
void method_advise(FILE *f, const Model *mod, int s, int k, MultFamily fam, int rescale) {
  const char *kink = nonsmooth_function(mod);
  int smooth_poly = mod->degU != DEG_NONPOLY && mod->degg != DEG_NONPOLY;
  if (kink) {
    fprintf(f, "advice: U or g uses %s, which has a kink or a jump: the driver ends its steps on them (the "
               "switching functions above), which keeps the order of the smooth method; choose s and k as for a "
               "smooth model (docs/choosing.md, \"Kinks and jumps\")\n", kink);
  } else if (!mod->nu) {
    /* U not a polynomial: k = s with the rescale (--energy), 0.23-0.29x the time of k = 2s + 12 */
    int chosen = s == 6 && (smooth_poly ? method_quadrature_exact(k, s, mod->degU, 0) : k == s && rescale);
    fprintf(f, "advice: unconstrained and smooth: -s 6 -k auto (order 12%s)%s; on the outer solar system 24x (error "
               "1e-7) to 130x (1e-11) less work than -s 2 -k 16 (docs/choosing.md)\n",
            smooth_poly ? "" : "; k = s, the end of the step rescales p", chosen ? ", as chosen" : "");
  } else {
    fprintf(f, "advice: constrained and smooth: -s 4 -k auto --multiplier poly (order 8)%s; on the pendulum "
               "2.4x (error 1e-6) to 6x (1e-10) faster than -s 2 (docs/choosing.md)\n",
            s == 4 && fam == MULT_POLY ? ", as chosen" : "");
    if (fam == MULT_CONST)
      fprintf(f, "advice: --multiplier const has order %s with constraints; poly has order 2s\n",
              s >= 2 ? "2 in p" : "2");
  }
  /* the largest h omega at which 50 steps of a harmonic oscillator converge, s = 1..6 (s = 8, 10: 5.7) */
  static const double limit[] = {1.6, 2.8, 3.7, 4.7, 5.5, 5.7};
  fprintf(f, "advice: the fixed-point iteration converges while h times the fastest frequency stays below "
             "about %.1f (docs/choosing.md, \"Stiffness\")\n", limit[(s < 6 ? s : 6) - 1]);
}
