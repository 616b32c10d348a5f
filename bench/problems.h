/* problems.h - the benchmark problems, hand-written: sizes, initial values,
 * potential, gradient, constraints, their Jacobian and the contracted
 * constraint Hessians. Every peer that needs the model (hbvm-generic,
 * RATTLE, IDA, the chain8 reference, the overhead timing) calls these; the
 * generated solvers carry their own kernels, derived by hbvmgen from
 * models/NAME.ham, which compute the same functions.
 *
 * All problems are separable, H = p' M^-1 p / 2 + U(q), with a constant
 * diagonal M (the identity in every model of models/), constraints g(q) = 0
 * with nu components, and
 *     q' = M^-1 p,   p' = -grad U(q) - G(q) lambda,   G = grad g (m x nu). */
#ifndef BENCH_PROBLEMS_H
#define BENCH_PROBLEMS_H

#define BENCH_MAXM 16  /* largest m (chain8) */
#define BENCH_MAXNU 8  /* largest nu (chain8) */

typedef struct {
  const char *name;   /* as in models/NAME.ham */
  int m, nu;
  double T;           /* final time of the benchmark runs */
  const double *minv; /* the diagonal of M^-1 */
  void (*init)(double *q0, double *p0);
  double (*pot)(const double *q);
  void (*grad)(const double *q, double *gu);  /* gu = grad U(q) */
  void (*cons)(const double *q, double *g);   /* g(q), nu values */
  void (*jac)(const double *q, double *G);    /* G[i*nu + a] = d g_a / d q_i */
  /* hq[a] = v' Hess(g_a)(q) v: the second derivative of g_a along q' = v */
  void (*hessq)(const double *q, const double *v, double *hq);
} Problem;

/* The problem called name, or NULL. */
const Problem *problem_find(const char *name);

/* The error of (q, p) against the reference (qref, pref): max norm of
 * (q, p), or of the slow quantities on the stiff problems (stiff.h). */
double problem_error(const Problem *pb, const double *q, const double *p, const double *qref, const double *pref);

/* H(q, p). */
double problem_energy(const Problem *pb, const double *q, const double *p);

/* max_a |g_a(q)|; 0 without constraints. */
double problem_gmax(const Problem *pb, const double *q);

/* The multiplier of the index-1 formulation at (q, p), from
 *   (G' M^-1 G) lambda = [v' Hess(g_a) v]_a - G' M^-1 grad U,  v = M^-1 p.
 * Also returns grad U and G when gu, G are not NULL. 0, or -1 if the
 * matrix is singular. */
int problem_lambda(const Problem *pb, const double *q, const double *p, double *lambda,
                   double *gu, double *G);

/* Running maxima of |H - H0| and |g| along a trajectory. */
typedef struct {
  const Problem *pb;
  double H0, dH, dg;
} Observer;

/* Start observing at the initial point (q, p). */
void observer_start(Observer *ob, const Problem *pb, const double *q, const double *p);
/* Account for one more point of the trajectory. */
void observer_point(Observer *ob, const double *q, const double *p);

#endif
