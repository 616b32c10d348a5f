/* ref.h - independent reference solutions of the four test problems of the
 * paper (section 6 of paper/hbvm-holonomic-constraints.tex) and of the
 * double pendulum, used to measure the errors of the generated HBVM(k,s)
 * solvers.
 *
 * All problems have unit masses (M = identity), H = p'p/2 + U(q), constraints
 * g(q) = 0 with nu components, and
 *     q' = p,   p' = -grad U(q) - grad g(q) lambda.
 *
 *   "pendulum"    m=2, nu=1, U = y, g = x^2+y^2-1, q0=(0,-1), p0=(1,0).
 *                 Solved through theta'' = -sin theta (x = sin th, y = -cos th,
 *                 lambda = (th'^2 + cos th)/2) with GSL rk8pd.
 *   "conical"     m=3, nu=1, U = z, g = |q|^2-1, q0=(2^-1/2,0,-2^-1/2),
 *                 p0=(0,2^-1/4,0).  Exact: uniform circular motion, angular
 *                 speed 2^(1/4), period T = 2^(3/4) pi, lambda = 2^-1/2.
 *   "modified"    m=3, nu=1, U = z^4, g = x^6+y^4+z^2-0.625, q0, p0 as conical.
 *   "satellites"  m=9, nu=3, q = (q1,q2,q3), U = -sum 1/|q_i|,
 *                 g = (|q1-q2|^2-1, |q2-q3|^2-1, |q3-q1|^2-1),
 *                 q1=(0,1/2,20), q2=(0,-1/2,20), q3=(0,0,20-sqrt(3)/2),
 *                 p1=p2=0, p3=(v0,0,0) with v0 = sqrt(2 sum 1/|q_i(0)|) (H=0).
 *   "double_pendulum"  m=4, nu=2, q = (x1,y1,x2,y2), U = y1 + y2,
 *                 g = (x1^2+y1^2-1, (x2-x1)^2+(y2-y1)^2-1), at rest with
 *                 angles th1 = 0.5, th2 = -0.3 from the downward vertical
 *                 (models/double_pendulum.ham).  Solved through the
 *                 Euler-Lagrange equations of the angles with GSL rk8pd;
 *                 lambda by the index-1 formula below at each point.
 *   "modified" and "satellites" have no closed form: they are integrated in
 *   the index-1 formulation q' = p, p' = -grad U - G lambda(q,p), where
 *   G = grad g (m x nu) and (G'G) lambda = [p' Hess(g_i) p]_i - G' grad U,
 *   by GSL rk8pd (one driver over all output times, no restart), with the
 *   integrator's state holding q - q0 (the satellites are near z = 20).
 *
 * Accuracy, measured by tests/check_ref.c and by varying the integrator
 * tolerance and the output grid, on [0,10] with h = 0.1 (default absolute
 * and relative tolerance 1e-15):
 *   pendulum    q, p, lambda within ~1e-14 of the exact solution: the theta
 *               run agrees with a run on a 4x finer output grid to 5e-15,
 *               with a run at tolerance 1e-13 to 2e-14 and with the generic
 *               index-1 integrator to 1e-14; |g|, |G'p| <= 2e-16,
 *               |H - H0| <= 4e-16.
 *   conical     exact to round-off (closed form).  The generic index-1
 *               integrator run on it stays within 2e-14 (q, p) and 5e-15
 *               (lambda) of the closed form on [0,10], and within 4e-13 over
 *               10 periods with output step T/10.
 *   modified    q, p within ~3e-13, lambda within ~5e-13 (finer output grid:
 *               2.4e-13 / 4.1e-13; tolerance 1e-13: 1.6e-12 / 2.8e-12);
 *               drift of H 8e-16, of g 3e-15, of G'p 2e-15.
 *   satellites  q, p within ~2e-14 (coordinates of size 20), lambda
 *               (max 6.8e-2) within ~2e-14: output grids h = 0.1 and
 *               0.0125 agree to 7e-15 at t = 10, tolerance 1e-14 moves
 *               the result by 7e-15; drift of H 1e-15, of g 1.4e-14, of
 *               G'p 4e-15.  (Integrating q itself instead of q - q0 left
 *               8e-14 between those grids: round-off at size 20.)
 *   double_pendulum  q, p within ~2e-14, lambda within ~3e-14: the
 *               generic index-1 integrator agrees with the angle run to
 *               1.6e-14 (q, p) and 3e-14 (lambda) over [0,10] with
 *               h = 0.1, 2.7e-15 with h = 0.0125; |H - H0| <= 9e-16,
 *               |g| <= 4.4e-16, |G'p| <= 2.2e-16 along the run.
 * All far below the paper's printed errors (smallest: 7.4e-13 in tab1,
 * which uses the closed form; otherwise >= 2.4e-9).
 * Note: the paper's tab2/tab3 e_s and e_lambda are not errors against such
 * a reference but differences from the same method run with step h/2
 * (sampled at t = 0, 0.1, ..., 10); see tests/data/README.md.
 */
#ifndef HBVM_TESTS_REF_H
#define HBVM_TESTS_REF_H

/* Fill q[(N+1)*m], p[(N+1)*m], lambda[(N+1)*nu] with the exact/reference
 * solution at t_n = n*h, n = 0..N, of the named problem (point n at
 * q + n*m, p + n*m, lambda + n*nu), at tolerance 1e-15; returns 0 on
 * success, -1 for an unknown problem or bad arguments, -2 if the
 * integrator failed.  One integration serves all N+1 points (the driver
 * stops at each t_n without restarting), so the reference at every step
 * point of a run costs about as much as the reference at its end:
 * h = 0.0125, N = 800 takes 0.4 ms (pendulum) to 2.3 ms (satellites). */
int ref_solve(const char *problem, double h, long N, double *q, double *p,
              double *lambda);

/* Dimensions of the named problem: 0 on success, -1 unknown. */
int ref_dims(const char *problem, int *m, int *nu);

/* As ref_solve, with the integrator's absolute and relative tolerance
 * given (ref_solve uses 1e-15); ignored for the closed-form "conical". */
int ref_solve_tol(const char *problem, double h, long N, double tol,
                  double *q, double *p, double *lambda);

/* As ref_solve_tol, but always through the generic index-1 integrator,
 * also for "pendulum" and "conical" (to check that integrator against
 * solutions obtained in another way). */
int ref_solve_index1(const char *problem, double h, long N, double tol,
                     double *q, double *p, double *lambda);

/* The consistent initial values q0[m], p0[m] of the named problem;
 * 0 on success, -1 unknown. */
int ref_initial(const char *problem, double *q0, double *p0);

/* Invariants at one point: H(q,p), the constraints g[nu] and the hidden
 * constraints hc[nu] = grad g(q)' p.  Any output may be NULL.  0 on
 * success, -1 unknown problem. */
int ref_invariants(const char *problem, const double *q, const double *p,
                   double *H, double *g, double *hc);

/* Potential gradient gu[m] = grad U(q) and constraint Jacobian
 * G[m*nu] (row-major, G[i*nu+j] = d g_j / d q_i) of the named problem;
 * 0 on success, -1 unknown. */
int ref_gradients(const char *problem, const double *q, double *gu,
                  double *G);

/* The multiplier of the index-1 formulation at (q,p), i.e. the solution of
 * (G'G) lambda = [p' Hess(g_i) p]_i - G' grad U; 0 on success, -1 unknown
 * problem, -2 singular G'G. */
int ref_lambda(const char *problem, const double *q, const double *p,
               double *lambda);

/* Errors of a computed trajectory against the reference: over the points
 * n = 0..N at t_n = n*h, *err_qp = max |q_n - q(t_n)|, |p_n - p(t_n)| and
 * *err_lambda = max |lambda_n - lambda(t_n)| (max norms over components;
 * a NaN in the input gives a NaN error).  q, p hold (N+1)*m values,
 * lambda (N+1)*nu or is NULL (then *err_lambda is not written; err_lambda
 * may be NULL too).  One ref_solve call.  0 on success, -1 bad arguments
 * or unknown problem, -2 integrator failure, -3 no memory. */
int ref_max_error(const char *problem, double h, long N, const double *q,
                  const double *p, const double *lambda, double *err_qp,
                  double *err_lambda);

#endif
