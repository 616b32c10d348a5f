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
 * passed as the input gam, with the factor's entries as the input lu).
 * With constraints the multiplier is eliminated from the correction by a
 * Schur complement (build_schur): the constant family's nu values, or the
 * poly family's s nu Legendre coefficients, whose columns are the moments
 * R_jr of step_poly.c (MultCols). */
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
// it) refined by inverse iteration on A itself (shifted 1e-9 off: a shift
// of 1e-15 left A - shift singular where long double is double, under
// valgrind), each eigenvector scaled so that its largest entry is 1.
// Checked: |A T - T Lambda| and |T T^-1 - I| small (the bounds hold in
// double too), or an internal error.
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
    long double complex shift = lam * (1 + 1e-9L);
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
  if (res > 1e-13L || ortho > 1e-12L)
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

double newton_midpoint_weight(const Method *me, int j) { return half_integral(me, j); }

// The Hessian of the Lagrangian U + lambda' g as dense m x m nodes at the
// point q, lambda the input lam (the first nu entries: the state's
// multiplier; none without constraints, where it is Hess U).
static int *hessian_at(Build *b, const int *q) {
  Dag *d = b->d;
  const Model *mod = b->mod;
  int m = b->m, nnz = 0, z = dag_const(d, 0);
  int *grad = step_nodes(m);
  for (int i = 0; i < m; i++) grad[i] = mod->gradU[i];
  for (int a = 0; a < b->nu; a++)
    for (int e = 0; e < mod->jac[a].n; e++) {
      int i = mod->jac[a].e[e].coord;
      grad[i] = dag_add(d, grad[i], dag_mul(d, step_in(b, IN_LAM, a), mod->jac[a].e[e].node));
    }
  SparseVec *rows = arena_alloc((size_t)m * sizeof *rows);
  for (int i = 0; i < m; i++) {
    ad_gradient_sparse(d, grad[i], m, &rows[i]);
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

// The multiplier's unknowns in the Newton correction: nc of them, nu for
// the constant family, s nu for the polynomial one (c = r nu + a, the
// layout of its coefficients lam). Column c belongs to constraint con[c]
// and has s sparse vectors K[c][j] over the entries of jac[con[c]]: the
// multiplier's force on gamma is V = (X (x) M^-1) K, the conditions it
// enforces C dgamma = sum_j K[c][j]' dgamma_j (K[a][j] = rho_j[:, a] for
// the constant family; K[(r,a)][j] = R_jr[:, a], the moments of step_poly.c,
// for the polynomial one, whose conditions C_i are sum_j R_ij' gamma_j).
// vK[c][j] = M^-1 K[c][j], dense.
typedef struct {
  int nc, *con;
  int ***K, ***vK;
} MultCols;

// What newton_solve reads of newton_factor's results, as its input lu: the
// blocks' factors; with constraints also W = N^-1 V (s m x nc, column c at
// c s m), the vectors K of the factorisation (nc x s x the entries of
// jac[con[c]]) and the factor of the Schur complement S (nc x nc).
typedef struct {
  LuFactor *blk;
  int *W;
  int ***K;
  LuFactor S;
  MultCols mc;
} NewtonFactor;

// The input of newton_solve standing for the factor's node v: v itself
// where it is a structural zero, else the next entry of lu.
static int stash(Build *b, int v, int *lu, int *nlu) {
  if (dag_is_zero(b->d, v)) return v;
  lu[*nlu] = v;
  return dag_input(b->d, b->st->in[IN_LU].first + (*nlu)++);
}

// The same for a factor: a copy of f over the inputs.
static LuFactor stash_factor(Build *b, const LuFactor *f, int *lu, int *nlu) {
  LuFactor in = {f->n, f->perm, step_nodes(f->n * f->n)};
  for (int t = 0; t < f->n * f->n; t++) in.F[t] = stash(b, f->F[t], lu, nlu);
  return in;
}

// x = N^-1 r = (T (x) I) Lambda-blocks^-1 (T^-1 (x) I) r (s m nodes each)
// with the blocks' factors fac: their own nodes (in newton_factor) or the
// inputs standing for them (in newton_solve).
static void newton_apply(Build *b, const NewtonBasis *nb, const LuFactor *fac, const int *r, int *dg) {
  Dag *d = b->d;
  int m = b->m, s = b->s;
  int *w = step_nodes(s * m), *z = step_nodes(s * m), *rhs = step_nodes(2 * m), *x = step_nodes(2 * m);
  for (int j = 0; j < s; j++)
    for (int i = 0; i < m; i++) {
      int acc = dag_const(d, 0);
      for (int c = 0; c < s; c++) acc = dag_add(d, acc, dag_mul(d, dag_const(d, nb->Tinv[j * s + c]), r[c * m + i]));
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
      for (int c = 0; c < s; c++) acc = dag_add(d, acc, dag_mul(d, dag_const(d, nb->T[j * s + c]), z[c * m + i]));
      dg[j * m + i] = acc;
    }
}

// sum_j K[c][j]' v_j over the entries of jac[con[c]] (K: nc x s x entries).
static int cols_dot(Build *b, const MultCols *mc, int ***K, int c, const int *v) {
  Dag *d = b->d;
  const SparseVec *col = &b->mod->jac[mc->con[c]];
  int acc = dag_const(d, 0);
  for (int j = 0; j < b->s; j++)
    for (int e = 0; e < col->n; e++) acc = dag_add(d, acc, dag_mul(d, K[c][j][e], v[j * b->m + col->e[e].coord]));
  return acc;
}

// The multiplier's columns at the factorisation: the constant family's
// rho_j (step.c) as they are; the polynomial family's moments R_jr of the
// stage Jacobians at the input gamma, with M^-1 of each.
static void mult_cols(Build *b, MultCols *mc) {
  Dag *d = b->d;
  int m = b->m, s = b->s, nu = b->nu, poly = b->me->family == MULT_POLY;
  int ****R = poly ? poly_jacobian_moments(b, poly_stage_jacobians(b), 0) : NULL, *dense = step_nodes(m);
  mc->nc = poly ? s * nu : nu;
  mc->con = step_nodes(mc->nc);
  mc->K = arena_alloc((size_t)mc->nc * sizeof *mc->K);
  mc->vK = arena_alloc((size_t)mc->nc * sizeof *mc->vK);
  for (int c = 0; c < mc->nc; c++) {
    int a = c % nu, r = c / nu;
    const SparseVec *col = &b->mod->jac[a];
    mc->con[c] = a;
    mc->K[c] = arena_alloc((size_t)s * sizeof *mc->K[c]);
    mc->vK[c] = arena_alloc((size_t)s * sizeof *mc->vK[c]);
    for (int j = 0; j < s; j++) {
      if (!poly) {
        mc->K[c][j] = b->rho[j][a];
        mc->vK[c][j] = b->vrho[j][a];
        continue;
      }
      mc->K[c][j] = R[j][r][a];
      for (int i = 0; i < m; i++) dense[i] = dag_const(d, 0);
      for (int e = 0; e < col->n; e++) dense[col->e[e].coord] = R[j][r][a][e];
      mc->vK[c][j] = step_nodes(m);
      minv_apply(b->mod, d, dense, mc->vK[c][j]);
    }
  }
}

// The multiplier in the Newton correction. The sweep's multiplier makes
// the conditions hold at its new gamma, C gamma_new = -g0 / h (C the rows
// of K), so the Newton system for the correction dg and an auxiliary mu
// (nc: the change of h lambda) is
//     N dg + V mu = r,   C dg = C r,   V = (X (x) M^-1) K,
// K and C frozen with J. Eliminating mu: W = N^-1 V (nc extra right-hand
// sides of the blocks), S = C W (nc x nc), factored here; the solve is
// z = N^-1 r, mu = S^-1 C (z - r), dg = z - W mu. Results: W, K (for C)
// and S's factor into lu, S's pivots and diagonal into spivot, sadiag (nc).
static void build_schur(Build *b, const NewtonBasis *nb, const LuFactor *fac, const MultCols *mc, int *lu, int *nlu,
                        NewtonFactor *nf, int *spivot, int *sadiag) {
  Dag *d = b->d;
  int m = b->m, s = b->s, nc = mc->nc, sm = s * m;
  step_section(b, b->me->family == MULT_POLY
                      ? "the multiplier's columns W = N^-1 (X (x) M^-1) R_(.r) and S = [R_i0' .. R_i,s-1'] W, factored"
                      : "the multiplier's columns W = N^-1 (X (x) M^-1) rho_a and S = [rho_0' .. rho_{s-1}'] W, factored");
  int *V = step_nodes(sm), *W = step_nodes(sm * nc), *S = step_nodes(nc * nc);
  for (int c = 0; c < nc; c++) {
    for (int j = 0; j < s; j++)
      for (int i = 0; i < m; i++) V[j * m + i] = step_apply_x(b, j, i, mc->vK[c]);
    newton_apply(b, nb, fac, V, W + c * sm);
  }
  for (int a = 0; a < nc; a++)
    for (int c = 0; c < nc; c++) S[a * nc + c] = cols_dot(b, mc, mc->K, a, W + c * sm);
  LuFactor sf;
  lu_factor(d, S, nc, &sf, spivot, sadiag);
  nf->W = step_nodes(sm * nc);
  for (int t = 0; t < sm * nc; t++) nf->W[t] = stash(b, W[t], lu, nlu);
  nf->K = arena_alloc((size_t)nc * sizeof *nf->K);
  for (int c = 0; c < nc; c++) nf->K[c] = arena_alloc((size_t)s * sizeof *nf->K[c]);
  for (int j = 0; j < s; j++)
    for (int c = 0; c < nc; c++) {
      int n = b->mod->jac[mc->con[c]].n;
      nf->K[c][j] = step_nodes(n);
      for (int e = 0; e < n; e++) nf->K[c][j][e] = stash(b, mc->K[c][j][e], lu, nlu);
    }
  nf->S = stash_factor(b, &sf, lu, nlu);
}

// The kernel "newton_factor": J = Hess(U + lambda' g) at q0 + h sum_j
// gamma_j int_0^{1/2} P_j (the midpoint of the step's polynomial at the
// input gamma; lambda the input lam), B = M^-1 J, and each block's LU
// factor (lu.c, minimum-degree order, no pivoting); with constraints the
// Schur complement of the multiplier (build_schur). Results lu (what
// newton_solve reads: the factors' structural nonzeros, and W, rho), pivot
// and adiag (S*M each: the blocks' sizes add up to s m), and with
// constraints spivot, sadiag (NU). nf receives the factor over the inputs
// of newton_solve.
static void build_factor(Build *b, const NewtonBasis *nb, NewtonFactor *nf) {
  Dag *d = b->d;
  Step *st = b->st;
  int m = b->m, s = b->s, nu = b->nu;
  b->owners = 1u << K_NFACTOR;
  step_section(b, nu ? "Newton matrix: Hess(U + lambda' g) at the midpoint of the step, B = M^-1 J, the blocks I + h^2 lambda B"
                     : "Newton matrix: Hess U at the midpoint of the step, B = M^-1 J, the blocks I + h^2 lambda B");
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
  MultCols mc = {0, NULL, NULL, NULL};
  if (nu) mult_cols(b, &mc);
  int nc = mc.nc, nmax = 4 * m * m * nb->nblocks + nc * (s * m + nc);
  for (int c = 0; c < nc; c++) nmax += s * b->mod->jac[mc.con[c]].n;
  int *lu = step_nodes(nmax), *pivot = step_nodes(s * m), *adiag = step_nodes(s * m);
  LuFactor *fac = arena_alloc((size_t)nb->nblocks * sizeof *fac);
  nf->blk = arena_alloc((size_t)nb->nblocks * sizeof *nf->blk);
  for (int q = 0; q < nb->nblocks; q++) {
    int n, *N = block_matrix(b, &nb->blk[q], B, hh, &n);
    step_section(b, nb->blk[q].pair ? "LU of a complex pair's block (its real form)" : "LU of a real eigenvalue's block");
    lu_factor(d, N, n, &fac[q], pivot + npiv, adiag + npiv);
    npiv += n;
    nf->blk[q] = stash_factor(b, &fac[q], lu, &nlu);
  }
  int *spivot = step_nodes(nc), *sadiag = step_nodes(nc);
  if (nu) build_schur(b, nb, fac, &mc, lu, &nlu, nf, spivot, sadiag);
  nf->mc = mc;
  if (st->in[IN_LU].len < nlu) st->in[IN_LU].len = st->in[IN_LU].coef = nlu; /* (the poly sweep's lu shares it) */
  step_result(st, K_NFACTOR, "lu", SZ_ONE, nlu, nlu, lu);
  step_result(st, K_NFACTOR, "pivot", SZ_SM, 1, s * m, pivot);
  step_result(st, K_NFACTOR, "adiag", SZ_SM, 1, s * m, adiag);
  if (nu) {
    SizeSym sym = nc == nu ? SZ_NU : SZ_SNU;
    step_result(st, K_NFACTOR, "spivot", sym, 1, nc, spivot);
    step_result(st, K_NFACTOR, "sadiag", sym, 1, nc, sadiag);
  }
  st->kern[K_NFACTOR].what =
      nc > nu ? "The Newton matrix N = I + h^2 A (x) M^-1 J, J = Hess(U + lam_0' g) at the midpoint of the step's\n"
                " * polynomial gam, as the blocks of A's eigenbasis, factored, with the polynomial multiplier's\n"
                " * columns W = N^-1 V and the Schur complement S = C W: out = the factors, W, C and S's factor\n"
                " * (what newton_solve reads as lu), pivots (S*M), diagonal (S*M), S's pivots (S*NU), diagonal (S*NU)."
      : nu ? "The Newton matrix N = I + h^2 A (x) M^-1 J, J = Hess(U + lam' g) at the midpoint of the step's\n"
           " * polynomial gam, as the blocks of A's eigenbasis, factored, with the multiplier's columns\n"
           " * W = N^-1 V and the Schur complement S = C W: out = the factors, W, C and S's factor (what\n"
           " * newton_solve reads as lu), pivots (S*M), diagonal (S*M), S's pivots (NU), diagonal (NU)."
         : "The Newton matrix I + h^2 A (x) M^-1 J, J = Hess U at the midpoint of the step's\n"
           " * polynomial gam, as the blocks of A's eigenbasis, factored: out = their LU factors,\n"
           " * pivots (S*M), diagonal (S*M).";
}

// The kernel "newton_solve": dgam = N^-1 r, r the residual Phi(gamma) -
// gamma passed as the input gam; with constraints dgam = z - W mu, z = N^-1 r,
// mu = S^-1 C (z - r) (build_schur).
static void build_solve(Build *b, const NewtonBasis *nb, const NewtonFactor *nf) {
  Dag *d = b->d;
  int m = b->m, s = b->s, nu = b->nu, sm = s * m;
  b->owners = 1u << K_NSOLVE;
  step_section(b, "Newton correction: w = (T^-1 (x) I) r, the blocks solved, dgam = (T (x) I) z");
  int *r = step_nodes(sm), *dg = step_nodes(sm);
  for (int i = 0; i < sm; i++) r[i] = step_in(b, IN_GAM, i);
  newton_apply(b, nb, nf->blk, r, dg);
  int nc = nf->mc.nc, *mu = step_nodes(nc);
  if (nu) {
    step_section(b, "the multiplier eliminated: mu = S^-1 C (z - r), dgam = z - W mu");
    int *zr = step_nodes(sm), *t = step_nodes(nc);
    for (int i = 0; i < sm; i++) zr[i] = dag_sub(d, dg[i], r[i]);
    for (int c = 0; c < nc; c++) t[c] = cols_dot(b, &nf->mc, nf->K, c, zr);
    lu_apply(d, &nf->S, t, mu);
    for (int i = 0; i < sm; i++)
      for (int c = 0; c < nc; c++) dg[i] = dag_sub(d, dg[i], dag_mul(d, nf->W[c * sm + i], mu[c]));
  }
  step_result(b->st, K_NSOLVE, "dgam", SZ_SM, 1, sm, dg);
  if (nu && b->me->family == MULT_POLY) { /* the multiplier's coefficients move by mu / h with it */
    for (int c = 0; c < nc; c++) mu[c] = dag_div(d, mu[c], b->h);
    step_result(b->st, K_NSOLVE, "dlam", SZ_SNU, 1, nc, mu);
  }
  b->st->kern[K_NSOLVE].what = nc > nu ? "The Newton correction for the residual r = (new gamma) - gamma given as gam, with\n"
                                         " * what newton_factor left in lu: out = dgam, N dgam + V mu = r, C dgam = C r (S*M),\n"
                                         " * and the multiplier's coefficients' change mu / h (S*NU)."
                              : nu ? "The Newton correction for the residual r = (new gamma) - gamma given as gam, with\n"
                                    " * what newton_factor left in lu: out = dgam, N dgam + V mu = r, C dgam = C r (S*M)."
                                  : "The Newton correction for the residual r = (new gamma) - gamma given as gam, with the\n"
                                    " * factors lu of newton_factor: out = (I + h^2 A (x) M^-1 J)^-1 r (S*M).";
}

// The kernels of --iteration newton (after the sweep: it reuses the sweep's
// inputs, and its input lu is laid out last). With constraints in the
// constant family the input lam (S*NU, of which the first NU are read: the
// multiplier in J) is laid out before lu; the poly family's sweep has both
// already (lam its coefficients, lu the slots its factor shares with
// newton_factor's, each kernel called with its own array).
void build_newton(Build *b) {
  NewtonBasis nb;
  NewtonFactor nf;
  if (b->nu && b->me->family == MULT_CONST) { /* (the poly family's sweep has lam and lu already) */
    b->st->in[IN_LAM].len = b->s * b->nu;
    b->st->in[IN_LU].first = b->st->in[IN_LAM].first + b->st->in[IN_LAM].len;
  }
  newton_basis(b->me, &nb);
  build_factor(b, &nb, &nf);
  build_solve(b, &nb, &nf);
}
