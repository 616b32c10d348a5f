/* mq_common.h - what the two files of suite mq share (tests/check_mq.c, M(q)
 * without constraints; tests/check_mq_fourbar.c, with): a generated solver
 * behind one interface, with its model's reference, and the tests that read
 * only that interface (tests/mq_common.c): order 2s, the error estimate
 * against the true local error, adaptive steps that follow the tolerance. */
#ifndef HBVM_TESTS_MQ_COMMON_H
#define HBVM_TESTS_MQ_COMMON_H

#define MQ_MAXM 3 /* the most coordinates of suite mq's models */

typedef struct MqSolver MqSolver;
struct MqSolver {
  const char *name, *model; /* the solver's (messages), its model's (HBVM_MQ_TABLE's lines) */
  int s, m;
  /* (q, p) at t0 carried to t, in place, by rk8pd at 1e-14 on the model's
   * ODE; data: the model's, for it */
  void (*reference)(const void *data, double t0, double t, double *q, double *p);
  const void *data;
  void (*init)(void *x, const double *q, const double *p); /* NULL q, p: the model's */
  int (*step)(void *x, double h, double *est);             /* est: the step's error estimate */
  int (*adaptive)(void *x, double *h, double tol);
  void (*get)(const void *x, double *t, double *q, double *p);
  void (*set)(void *x, const double *q, const double *p); /* the state's q, p, the polynomials kept */
};

/* The callbacks of MqSolver for generated solver P (double or float). */
#define MQ_WRAP(P)                                                                                 \
  static void P##_i(void *x, const double *q, const double *p) {                                  \
    P##_real qq[P##_M], pp[P##_M];                                                                 \
    for (int i = 0; i < P##_M && q; i++) {                                                         \
      qq[i] = (P##_real)q[i];                                                                      \
      pp[i] = (P##_real)p[i];                                                                      \
    }                                                                                              \
    P##_init(x, q ? qq : NULL, q ? pp : NULL);                                                     \
  }                                                                                                \
  static int P##_s(void *x, double h, double *est) {                                               \
    P##_stats st;                                                                                  \
    int rc = P##_step(x, (P##_real)h, 0, &st);                                                     \
    *est = st.err_est;                                                                             \
    return rc;                                                                                     \
  }                                                                                                \
  static int P##_a(void *x, double *h, double tol) {                                               \
    P##_real hh = (P##_real)*h;                                                                    \
    int rc = P##_step_adaptive(x, &hh, (P##_real)tol, 0, 0);                                       \
    *h = hh;                                                                                       \
    return rc;                                                                                     \
  }                                                                                                \
  static void P##_g(const void *x, double *t, double *q, double *p) {                             \
    const P##_state *y = x;                                                                        \
    *t = y->t;                                                                                     \
    for (int i = 0; i < P##_M; i++) {                                                              \
      q[i] = y->q[i];                                                                              \
      p[i] = y->p[i];                                                                              \
    }                                                                                              \
  }                                                                                                \
  static void P##_t(void *x, const double *q, const double *p) {                                   \
    P##_state *y = x;                                                                              \
    for (int i = 0; i < P##_M; i++) {                                                              \
      y->q[i] = (P##_real)q[i];                                                                    \
      y->p[i] = (P##_real)p[i];                                                                    \
      y->qc[i] = y->pc[i] = 0;                                                                     \
    }                                                                                              \
  }
#define MQ_SOLVER(P, model, s, ref, data) {#P, model, s, P##_M, ref, data, P##_i, P##_s, P##_a, P##_g, P##_t}

int mq_table(void); /* HBVM_MQ_TABLE=1: print the measured figures */

/* The solver's start: NAME_init at the model's q0, p0, read back. */
void mq_start(const MqSolver *sv, void *x, double *q, double *p);

/* max |(q, p) - reference| over n steps of h from the start. */
double mq_run_error(const MqSolver *sv, void *x, double h, int n);

/* The max error over a run to T at h and h/2: its rate is 2s. */
void mq_check_order(const MqSolver *sv, void *x, double h, double T);

/* True local error / NAME_stats.err_est over 30 steps of h from the
 * reference: within [1/10, 10] in geometric mean. */
void mq_check_errest(const MqSolver *sv, void *x, double h);

/* NAME_step_adaptive to T at tol 1e-6, 1e-8, 1e-10: the global error within
 * [1e-3, 10] tol and falling with tol; at_end (or NULL) checks the state at
 * T for each tol. */
void mq_check_adaptive(const MqSolver *sv, void *x, double T, void (*at_end)(const MqSolver *sv, const void *x, double tol));

/* In float: max |H - H0| over n steps of h from the start, in float ulps of
 * |K| + |U| at its largest over the run (U from the model's closed form,
 * H from the solver). The bound, from the end of the step: the rescale puts
 * H at H0 to a few ulps, or is skipped near rest only where H is within 4
 * TOL (8 ulps) of H0 already (emit_mq_near_rest_band); with H's own
 * evaluation, 16 ulps at most, whatever n. */
double mq_float_drift(const MqSolver *sv, void *x, double (*energy)(const void *x), double (*potential)(const double *q),
                      double h, int n);

#endif
