/* step.h - what the step builders share (step.c, step_const.c, step_poly.c, lu.c).
 *
 * step.c builds what every method family has: the stage points, the model
 * derivatives at the stages and their Legendre projections, the update of
 * gamma, and the functions of the state outside the step. The family's
 * file builds the multiplier: build_const_multiplier (the paper's constant
 * one) or build_poly_multiplier (a polynomial of degree s-1). */
#ifndef STEP_H
#define STEP_H

#include "hbvmgen.h"

typedef struct {
  Model *mod;
  const Method *me;
  Dag *d;
  Step *st;
  int m, nu, s, k;
  int h;          /* node of the step size */
  unsigned owners; /* the kernels (1 << KernelId) the nodes being built are for */
  int **psi;      /* s x m: sum_l b_l P_j(c_l) grad U(Q_l) */
  int ***rho;     /* s x nu x (entries of jac[a]): the same with grad g_a */
  int ***vrho;    /* s x nu x m: M^-1 rho_j[:, a], dense */
  int **vpsi;     /* s x m: M^-1 psi_j */
  int **theta;    /* s x m: the force's coefficients Theta_j of the sweep's result */
  int lean;       /* step_build_layout: the rolled kernels' results as layout only */
} Build;

void step_section(Build *b, const char *label);       /* dag_section, labelled for b->owners */
int step_in(Build *b, int block, int i);              /* input node i of an input block */
int step_apply_x(Build *b, int j, int i, int **v);     /* sum_r X[j][r] v[r][i] */
void step_stage_point(Build *b, int l, int *Q);       /* Q_l, m nodes */
void step_gamma(Build *b, int **theta, int *gam, int *dp); /* gamma_j and p1 - p0 from Theta_i */
void step_gamma_update(Build *b, int **theta);        /* the same, as the sweep's results */
void step_theta_result(Build *b);                      /* the sweep's last result: Theta_1.. for NAME_dense */
int **step_jacobian_at(Build *b, const int *q);       /* dense columns of grad g at q */
void step_gram(Build *b, int **G, int *B);            /* B = G' M^-1 G */
void step_project_momenta(Build *b, int **G, const int *B, const int *p, int *dp, int *pivot, int *adiag);
int step_dot_col(Build *b, int j, int a, const int *v);
void step_curvature(Build *b, const int *q, const int *v, int *hvv); /* v' Hess(g_a)(q) v */
void step_force_along(Build *b, const int *q, int **G, int *gmu);    /* grad g_a(q)' M^-1 grad U(q) */
int step_coupled(Build *b, const IntVec *touch, int *pair, int a, int *out); /* constraints coupled with a */
void step_result(Step *st, KernelId k, const char *name, SizeSym sym, int coef, int len, const int *nodes);
void step_placeholder(Build *b, KernelId k, const char *name, SizeSym sym, int coef, int len); /* zeros: layout only */

void build_const_multiplier(Build *b);
void layout_const_multiplier(Build *b); /* its results' layout only (step_build_layout) */
void build_poly_multiplier(Build *b);
void build_mq_sweep(Build *b);       /* step_mq.c: M(q), no constraints */
void build_mq_constrained(Build *b); /* step_mq.c: M(q) with constraints */
/* step_poly.c, shared with build_mq_constrained and step_newton.c */
typedef struct LuFactor LuFactor;
int ***build_poly_factor(Build *b, LuFactor *in, int *****Rout); /* the kernel "factor", G at the stages */
int **force_coefficients(Build *b, int ***G, int ****R, const int *lam); /* Theta_j(lambda) */
int *conditions(Build *b, int ***G, int ****R, const int *gam);         /* C_i at gamma */
void build_projection(Build *b);                                        /* the kernel "project_p1" */
int ***poly_stage_jacobians(Build *b);                        /* grad g at the stages: [l][a][entry] */
int ****poly_jacobian_moments(Build *b, int ***G, int closed); /* R_jr = sum_l b_l P_j P_r G_l: [j][r][a][entry] */
void layout_poly_multiplier(Build *b); /* the rolled form's layout only (step_build_layout) */

/* step_newton.c: --iteration newton. A = T Lambda T^-1, the method's matrix
 * A[j][r] = sum_i X[j][i] sum_l b_l P_i(c_l) Ihat[l][r] in a real eigenbasis:
 * Lambda block diagonal, a block per real eigenvalue a (b = 0) or pair a +- ib
 * (columns col, col + 1 of T). */
typedef struct {
  int col, pair;
  double a, b;
} NewtonBlock;

typedef struct {
  int s, nblocks;
  NewtonBlock *blk;
  double *T, *Tinv; /* s x s */
} NewtonBasis;

void newton_method_matrix(const Method *me, double *A); /* s x s */
void newton_basis(const Method *me, NewtonBasis *nb);
double newton_midpoint_weight(const Method *me, int j); /* int_0^{1/2} P_j: J's point in the step */
void build_newton(Build *b);
void layout_newton_rolled(Build *b); /* roll_newton.c: the rolled Newton kernels' layout */

/* lu.c: linear systems of DAG nodes, solved at generation time in structure */
void lu_solve_ordered(Dag *d, const int *A, const int *r, int n, int *x, int *pivot, int *diag);

struct LuFactor {
  int n;
  int *perm;  /* the elimination order */
  int *F;     /* n x n: L's multipliers below the diagonal, U above, 1 / U's pivots on it */
};

void lu_factor(Dag *d, const int *A, int n, LuFactor *f, int *pivot, int *diag);
void lu_apply(Dag *d, const LuFactor *f, const int *r, int *x);

#endif
