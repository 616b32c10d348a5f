/* step_newton.c - the kernels of --iteration newton: the step's equations
 * solved by simplified Newton instead of fixed-point sweeps.
 *
 * The sweep of step.c is the map gamma -> Phi(gamma) whose fixed point the
 * step needs. Newton solves F(gamma) = Phi(gamma) - gamma = 0 with the
 * residual the sweep already computes (its result gam minus its input) and
 * the Jacobian of F, to first order in the variation of grad U over the step,
 *     -(I + h^2 A (x) M^-1 J),  J = Hess U at one point of the step,
 *     A[j][r] = sum_i X[j][i] sum_l b_l P_i(c_l) Ihat[l][r]    (s x s),
 * A computed here from the quadrature (it is X_s^2 whenever k >= s). The
 * sm x sm system is never factored: A = T Lambda T^-1 with Lambda real block
 * diagonal (1 x 1 blocks for real eigenvalues, [[a, b], [-b, a]] for a pair
 * a +- ib), so that the system splits into one m x m system
 * I + h^2 lambda M^-1 J per real eigenvalue and one complex one
 * I + h^2 (a + ib) M^-1 J per pair, solved as the real 2m x 2m system of its
 * real and imaginary parts (the transformation of Radau5, Hairer & Wanner
 * IV.8). Each pair's equation is first multiplied by exp(-i arg(lambda) / 2),
 * which makes the symmetric part of its real form positive definite wherever
 * J is positive semidefinite and M diagonal, so that lu.c's factorisation
 * without pivoting is safe there for any h (s >= 4 has pairs with a < 0).
 * docs/method-newton.md says why this and not the blended iteration.
 *
 * Two kernels: "newton_factor" (J at the midpoint of the step's current
 * polynomial, the blocks' LU factors, their pivots) and "newton_solve"
 * (the correction dgam = (I + h^2 A (x) M^-1 J)^-1 r for the residual r,
 * passed as the input gam, with the factor's entries as the input lu). */
#include <complex.h>
#include <math.h>
#include <string.h>

#include "step.h"

// A (s x s) of the method from its quadrature, in long double.
static void method_matrix_ld(const Method *me, long double *A) {
  int s = me->s, k = me->k;
  long double *Y = arena_alloc((size_t)s * s * sizeof(long double)); /* Y[i][r] = sum_l W[l][i] Ihat[l][r] */
  for (int i = 0; i < s; i++)
    for (int r = 0; r < s; r++) {
      long double acc = 0;
      for (int l = 0; l < k; l++) acc += (long double)me->W[l * s + i] * me->Ihat[l * s + r];
      Y[i * s + r] = acc;
    }
  for (int j = 0; j < s; j++)
    for (int r = 0; r < s; r++) { /* row j of X: xi_0 at (0,0); xi_j at (j,j-1); -xi_{j+1} at (j,j+1) */
      long double acc = j == 0 ? (long double)me->xi[0] * Y[r] : (long double)me->xi[j] * Y[(j - 1) * s + r];
      if (j + 1 < s) acc -= (long double)me->xi[j + 1] * Y[(j + 1) * s + r];
      A[j * s + r] = acc;
    }
}

void newton_method_matrix(const Method *me, double *A) {
  long double *a = arena_alloc((size_t)me->s * me->s * sizeof(long double));
  method_matrix_ld(me, a);
  for (int i = 0; i < me->s * me->s; i++) A[i] = (double)a[i];
}

// det(mu I - X_s) by the three-term recurrence of the tridiagonal X_s:
// p_0 = 1, p_1 = mu - xi_0, p_{j+1} = mu p_j + xi_j^2 p_{j-1}.
static long double complex charpoly_x(const Method *me, long double complex mu) {
  long double complex pm = 1, p = mu - me->xi[0];
  for (int j = 1; j < me->s; j++) {
    long double complex next = mu * p + (long double)me->xi[j] * me->xi[j] * pm;
    pm = p;
    p = next;
  }
  return p;
}

// The s eigenvalues of X_s (Durand-Kerner on its monic characteristic
// polynomial); A's are their squares.
static void eigenvalues_x(const Method *me, long double complex *mu) {
  int s = me->s;
  long double complex z = 1;
  for (int i = 0; i < s; i++) mu[i] = (z *= 0.4L + 0.9L * I) * 0.5L;
  for (int it = 0; it < 2000; it++) {
    long double change = 0;
    for (int i = 0; i < s; i++) {
      long double complex den = 1;
      for (int j = 0; j < s; j++)
        if (j != i) den *= mu[i] - mu[j];
      long double complex step = charpoly_x(me, mu[i]) / den;
      mu[i] -= step;
      if (cabsl(step) > change) change = cabsl(step);
    }
    if (change < 1e-30L) break;
  }
}

// Solve (A - shift I) x = b (n x n, complex, partial pivoting), in place on a copy.
static void complex_solve(const long double *A, long double complex shift, int n, long double complex *b) {
  long double complex *M = arena_alloc((size_t)n * n * sizeof *M);
  for (int i = 0; i < n * n; i++) M[i] = A[i] - (i % (n + 1) == 0 ? shift : 0);
  for (int k = 0; k < n; k++) {
    int p = k;
    for (int i = k + 1; i < n; i++)
      if (cabsl(M[i * n + k]) > cabsl(M[p * n + k])) p = i;
    for (int c = 0; c < n; c++) {
      long double complex t = M[k * n + c];
      M[k * n + c] = M[p * n + c];
      M[p * n + c] = t;
    }
    long double complex t = b[k];
    b[k] = b[p];
    b[p] = t;
    if (M[k * n + k] == 0) M[k * n + k] = 1e-40L;
    for (int i = k + 1; i < n; i++) {
      long double complex f = M[i * n + k] / M[k * n + k];
      for (int c = k; c < n; c++) M[i * n + c] -= f * M[k * n + c];
      b[i] -= f * b[k];
    }
  }
  for (int k = n - 1; k >= 0; k--) {
    for (int c = k + 1; c < n; c++) b[k] -= M[k * n + c] * b[c];
    b[k] /= M[k * n + k];
  }
}

// The inverse of the real n x n matrix T (Gauss-Jordan, partial pivoting),
// long double. Returns 0 when it is singular.
static int invert_ld(const long double *T, int n, long double *Tinv) {
  long double *M = arena_alloc((size_t)n * 2 * n * sizeof *M);
  for (int i = 0; i < n; i++)
    for (int c = 0; c < 2 * n; c++) M[i * 2 * n + c] = c < n ? T[i * n + c] : c - n == i;
  for (int k = 0; k < n; k++) {
    int p = k;
    for (int i = k + 1; i < n; i++)
      if (fabsl(M[i * 2 * n + k]) > fabsl(M[p * 2 * n + k])) p = i;
    if (M[p * 2 * n + k] == 0) return 0;
    for (int c = 0; c < 2 * n; c++) {
      long double t = M[k * 2 * n + c];
      M[k * 2 * n + c] = M[p * 2 * n + c];
      M[p * 2 * n + c] = t;
    }
    for (int i = 0; i < n; i++) {
      if (i == k) continue;
      long double f = M[i * 2 * n + k] / M[k * 2 * n + k];
      for (int c = 0; c < 2 * n; c++) M[i * 2 * n + c] -= f * M[k * 2 * n + c];
    }
  }
  for (int i = 0; i < n; i++)
    for (int c = 0; c < n; c++) Tinv[i * n + c] = M[i * 2 * n + n + c] / M[i * 2 * n + i];
  return 1;
}

// A = T Lambda T^-1 with Lambda real block diagonal (NewtonBasis), from
// the eigenvalues mu^2 of X_s (A = X_s^2 when the quadrature is exact for
// it) refined by inverse iteration on A itself, each eigenvector scaled so
// that its largest entry is 1. Checked: |A T - T Lambda| and |T T^-1 - I|
// small, or an internal error.
void newton_basis(const Method *me, NewtonBasis *nb) {
  int s = me->s;
  long double *A = arena_alloc((size_t)s * s * sizeof *A), *T = arena_alloc((size_t)s * s * sizeof *T);
  long double *Ti = arena_alloc((size_t)s * s * sizeof *Ti), *Lam = arena_alloc((size_t)s * s * sizeof *Lam);
  long double complex *mu = arena_alloc((size_t)s * sizeof *mu), *v = arena_alloc((size_t)s * sizeof *v);
  method_matrix_ld(me, A);
  eigenvalues_x(me, mu);
  nb->s = s;
  nb->nblocks = 0;
  nb->blk = arena_alloc((size_t)s * sizeof *nb->blk);
  int col = 0;
  for (int e = 0; e < s; e++) {
    long double complex lam = mu[e] * mu[e];
    int pair = cimagl(mu[e]) != 0 && fabsl(cimagl(lam)) > 1e-12L * cabsl(lam);
    if (pair && cimagl(lam) < 0) continue; /* one of each conjugate pair */
    if (!pair) lam = creall(lam);
    for (int i = 0; i < s; i++) v[i] = 1;
    long double complex shift = lam * (1 + 1e-15L);
    for (int it = 0; it < 3; it++) {
      complex_solve(A, shift, s, v);
      int big = 0;
      for (int i = 1; i < s; i++)
        if (cabsl(v[i]) > cabsl(v[big])) big = i;
      long double complex scale = v[big];
      for (int i = 0; i < s; i++) v[i] /= scale;
    }
    int big = 0; /* the eigenvalue from the refined vector: (A v)_big / v_big, v_big = 1 */
    for (int i = 1; i < s; i++)
      if (cabsl(v[i]) > cabsl(v[big])) big = i;
    lam = 0;
    for (int c = 0; c < s; c++) lam += A[big * s + c] * v[c];
    if (!pair) lam = creall(lam);
    NewtonBlock *b = &nb->blk[nb->nblocks++];
    b->col = col;
    b->pair = pair;
    b->a = (double)creall(lam);
    b->b = (double)cimagl(lam);
    for (int i = 0; i < s; i++) T[i * s + col] = creall(v[i]);
    if (pair)
      for (int i = 0; i < s; i++) T[i * s + col + 1] = cimagl(v[i]);
    col += pair ? 2 : 1;
  }
  ASSERT(col == s);
  memset(Lam, 0, (size_t)s * s * sizeof *Lam);
  for (int q = 0; q < nb->nblocks; q++) {
    const NewtonBlock *b = &nb->blk[q];
    Lam[b->col * s + b->col] = b->a;
    if (!b->pair) continue;
    Lam[b->col * s + b->col + 1] = b->b;
    Lam[(b->col + 1) * s + b->col] = -b->b;
    Lam[(b->col + 1) * s + b->col + 1] = b->a;
  }
  if (!invert_ld(T, s, Ti)) internal_error("the eigenvectors of the Newton method's matrix are dependent");
  long double res = 0, ortho = 0;
  for (int i = 0; i < s; i++)
    for (int c = 0; c < s; c++) {
      long double at = 0, tl = 0, tt = 0;
      for (int r = 0; r < s; r++) {
        at += A[i * s + r] * T[r * s + c];
        tl += T[i * s + r] * Lam[r * s + c];
        tt += T[i * s + r] * Ti[r * s + c];
      }
      if (fabsl(at - tl) > res) res = fabsl(at - tl);
      if (fabsl(tt - (i == c)) > ortho) ortho = fabsl(tt - (i == c));
    }
  if (res > 1e-15L || ortho > 1e-13L)
    internal_error("the Newton method's matrix at s=%d: |A T - T L| = %Lg, |T T^-1 - I| = %Lg", s, res, ortho);
  nb->T = arena_alloc((size_t)s * s * sizeof(double));
  nb->Tinv = arena_alloc((size_t)s * s * sizeof(double));
  for (int i = 0; i < s * s; i++) {
    nb->T[i] = (double)T[i];
    nb->Tinv[i] = (double)Ti[i];
  }
}

// int_0^{1/2} P_j: 1/2 for j = 0, else xi_{j+1} P_{j+1}(1/2) - xi_j P_{j-1}(1/2)
// (METHOD.md), with P_j(1/2) = sqrt(2j+1) L_j(0).
static double half_integral(const Method *me, int j) {
  if (j == 0) return 0.5;
  double l0[64] = {1, 0}; /* L_n(0) */
  for (int n = 1; n + 1 <= j + 1 && n + 1 < 64; n++) l0[n + 1] = -(double)n * l0[n - 1] / (n + 1);
  double pp = sqrt(2.0 * (j + 1) + 1) * l0[j + 1], pm = sqrt(2.0 * (j - 1) + 1) * l0[j - 1];
  return me->xi[j + 1] * pp - me->xi[j] * pm;
}

// The Hessian of U as dense m x m nodes at the point q.
static int *hessian_at(Build *b, const int *q) {
  Dag *d = b->d;
  int m = b->m, nnz = 0, z = dag_const(d, 0);
  SparseVec *rows = arena_alloc((size_t)m * sizeof *rows);
  for (int i = 0; i < m; i++) {
    ad_gradient_sparse(d, b->mod->gradU[i], m, &rows[i]);
    nnz += rows[i].n;
  }
  int *roots = step_nodes(nnz), *img = step_nodes(nnz), *J = step_nodes(m * m);
  for (int i = 0, t = 0; i < m; i++)
    for (int e = 0; e < rows[i].n; e++) roots[t++] = rows[i].e[e].node;
  dag_subst(d, roots, nnz, q, m, img); /* every entry in one pass */
  for (int i = 0; i < m * m; i++) J[i] = z;
  for (int i = 0, t = 0; i < m; i++)
    for (int e = 0; e < rows[i].n; e++) J[i * m + rows[i].e[e].coord] = img[t++];
  return J;
}

// The matrix of one block of the Newton system over B = M^-1 J (m x m):
// I + h^2 lambda B for a real eigenvalue; for a pair, the real form
// [[C, -D], [D, C]] of C + iD = e^{-i phi} (I + h^2 (a + ib) B), phi =
// arg(a + ib) / 2.
static int *block_matrix(Build *b, const NewtonBlock *blk, const int *B, int hh, int *n_out) {
  Dag *d = b->d;
  int m = b->m, n = blk->pair ? 2 * m : m, *N = step_nodes(n * n);
  double r = hypot(blk->a, blk->b), phi = blk->pair ? atan2(blk->b, blk->a) / 2 : 0;
  double cr = blk->pair ? r * cos(phi) : blk->a, ci = r * sin(phi); /* e^{-i phi} (a + ib) */
  int kr = dag_mul(d, dag_const(d, cr), hh), ki = dag_mul(d, dag_const(d, ci), hh);
  for (int i = 0; i < m; i++)
    for (int c = 0; c < m; c++) {
      int C = dag_mul(d, kr, B[i * m + c]);
      if (i == c) C = dag_add(d, C, dag_const(d, cos(phi)));
      N[i * n + c] = C;
      if (!blk->pair) continue;
      int D = dag_mul(d, ki, B[i * m + c]);
      if (i == c) D = dag_sub(d, D, dag_const(d, sin(phi)));
      N[(i + m) * n + c + m] = C;
      N[i * n + c + m] = dag_neg(d, D);
      N[(i + m) * n + c] = D;
    }
  *n_out = n;
  return N;
}

// The kernel "newton_factor": J = Hess U at q0 + h sum_j gamma_j int_0^{1/2} P_j
// (the midpoint of the step's polynomial at the input gamma), B = M^-1 J, and
// each block's LU factor (lu.c, minimum-degree order, no pivoting); results
// lu (the factors' structural nonzeros), pivot and adiag (S*M each: the
// blocks' sizes add up to s m). The factors' nonzeros become the input lu of
// "newton_solve"; fac[q] receives block q's factor over those inputs.
static LuFactor *build_factor(Build *b, const NewtonBasis *nb) {
  Dag *d = b->d;
  Step *st = b->st;
  int m = b->m, s = b->s;
  b->owners = 1u << K_NFACTOR;
  step_section(b, "Newton matrix: Hess U at the midpoint of the step, B = M^-1 J, the blocks I + h^2 lambda B");
  int *qm = step_nodes(m), *J, *B = step_nodes(m * m), *col = step_nodes(m), *bcol = step_nodes(m);
  for (int i = 0; i < m; i++) {
    int acc = dag_const(d, 0);
    for (int j = 0; j < s; j++) acc = dag_add(d, acc, dag_mul(d, dag_const(d, half_integral(b->me, j)), step_in(b, IN_GAM, j * m + i)));
    qm[i] = dag_add(d, step_in(b, IN_Q0, i), dag_mul(d, b->h, acc));
  }
  J = hessian_at(b, qm);
  for (int c = 0; c < m; c++) {
    for (int i = 0; i < m; i++) col[i] = J[i * m + c];
    minv_apply(b->mod, d, col, bcol);
    for (int i = 0; i < m; i++) B[i * m + c] = bcol[i];
  }
  int hh = dag_mul(d, b->h, b->h), nlu = 0, npiv = 0;
  int *lu = step_nodes(4 * m * m * nb->nblocks), *pivot = step_nodes(s * m), *adiag = step_nodes(s * m);
  LuFactor *in = arena_alloc((size_t)nb->nblocks * sizeof *in);
  for (int q = 0; q < nb->nblocks; q++) {
    int n, *N = block_matrix(b, &nb->blk[q], B, hh, &n);
    step_section(b, nb->blk[q].pair ? "LU of a complex pair's block (its real form)" : "LU of a real eigenvalue's block");
    LuFactor f;
    lu_factor(d, N, n, &f, pivot + npiv, adiag + npiv);
    npiv += n;
    in[q] = (LuFactor){n, f.perm, step_nodes(n * n)};
    for (int t = 0; t < n * n; t++) {
      in[q].F[t] = f.F[t];
      if (dag_is_zero(d, f.F[t])) continue;
      lu[nlu] = f.F[t];
      in[q].F[t] = dag_input(d, st->in[IN_LU].first + nlu);
      nlu++;
    }
  }
  st->in[IN_LU].len = st->in[IN_LU].coef = nlu;
  step_result(st, K_NFACTOR, "lu", SZ_ONE, nlu, nlu, lu);
  step_result(st, K_NFACTOR, "pivot", SZ_SM, 1, s * m, pivot);
  step_result(st, K_NFACTOR, "adiag", SZ_SM, 1, s * m, adiag);
  st->kern[K_NFACTOR].what = "The Newton matrix I + h^2 A (x) M^-1 J, J = Hess U at the midpoint of the step's\n"
                             " * polynomial gam, as the blocks of A's eigenbasis, factored: out = their LU factors,\n"
                             " * pivots (S*M), diagonal (S*M).";
  return in;
}

// The kernel "newton_solve": dgam = (T (x) I) Lambda-blocks^-1 (T^-1 (x) I) r,
// r the residual Phi(gamma) - gamma passed as the input gam.
static void build_solve(Build *b, const NewtonBasis *nb, const LuFactor *fac) {
  Dag *d = b->d;
  int m = b->m, s = b->s;
  b->owners = 1u << K_NSOLVE;
  step_section(b, "Newton correction: w = (T^-1 (x) I) r, the blocks solved, dgam = (T (x) I) z");
  int *w = step_nodes(s * m), *z = step_nodes(s * m), *dg = step_nodes(s * m);
  int *rhs = step_nodes(2 * m), *x = step_nodes(2 * m);
  for (int j = 0; j < s; j++)
    for (int i = 0; i < m; i++) {
      int acc = dag_const(d, 0);
      for (int r = 0; r < s; r++)
        acc = dag_add(d, acc, dag_mul(d, dag_const(d, nb->Tinv[j * s + r]), step_in(b, IN_GAM, r * m + i)));
      w[j * m + i] = acc;
    }
  for (int q = 0; q < nb->nblocks; q++) {
    const NewtonBlock *blk = &nb->blk[q];
    int c = blk->col;
    if (!blk->pair) {
      lu_apply(d, &fac[q], w + c * m, z + c * m);
      continue;
    }
    /* e^{-i phi} (w_c - i w_{c+1}) in real and imaginary parts; z_c = x, z_{c+1} = -y */
    double phi = atan2(blk->b, blk->a) / 2;
    int cp = dag_const(d, cos(phi)), sp = dag_const(d, sin(phi));
    for (int i = 0; i < m; i++) {
      int u = w[c * m + i], v = w[(c + 1) * m + i];
      rhs[i] = dag_sub(d, dag_mul(d, cp, u), dag_mul(d, sp, v));
      rhs[m + i] = dag_neg(d, dag_add(d, dag_mul(d, sp, u), dag_mul(d, cp, v)));
    }
    lu_apply(d, &fac[q], rhs, x);
    for (int i = 0; i < m; i++) {
      z[c * m + i] = x[i];
      z[(c + 1) * m + i] = dag_neg(d, x[m + i]);
    }
  }
  for (int j = 0; j < s; j++)
    for (int i = 0; i < m; i++) {
      int acc = dag_const(d, 0);
      for (int r = 0; r < s; r++) acc = dag_add(d, acc, dag_mul(d, dag_const(d, nb->T[j * s + r]), z[r * m + i]));
      dg[j * m + i] = acc;
    }
  step_result(b->st, K_NSOLVE, "dgam", SZ_SM, 1, s * m, dg);
  b->st->kern[K_NSOLVE].what = "The Newton correction for the residual r = (new gamma) - gamma given as gam, with the\n"
                               " * factors lu of newton_factor: out = (I + h^2 A (x) M^-1 J)^-1 r (S*M).";
}

// The kernels of --iteration newton (after the sweep: it reuses the sweep's
// inputs, and its input lu is laid out last).
void build_newton(Build *b) {
  NewtonBasis nb;
  newton_basis(b->me, &nb);
  LuFactor *fac = build_factor(b, &nb);
  build_solve(b, &nb, fac);
}
