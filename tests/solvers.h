/* solvers.h - the committed generated solvers (generated/LIST) behind one
 * interface, so tests can run any of them by name. */
#ifndef HBVM_TESTS_SOLVERS_H
#define HBVM_TESTS_SOLVERS_H

#include <stddef.h>

typedef struct {
  const char *name;      /* e.g. "pendulum_k2s2" */
  int m, nu, k, s;
  size_t state_size;
  size_t off_t, off_q, off_p, off_lambda;
  void (*init)(void *x, const double *q0, const double *p0);
  int (*step)(void *x, double h, int *iters);
  double (*energy)(const void *x);
  void (*constraints)(const void *x, double *g);
  void (*hidden)(const void *x, double *hc);
  int (*step_est)(void *x, double h, double *err_est); /* a step, and its NAME_stats.err_est */
  void (*dense)(const void *x, double theta, double *q, double *p); /* NAME_dense */
} Solver;

/* The adapters of a generated solver with prefix P (its header included),
 * and its Solver table entry: SOLVER_ADAPT(P) at file scope, then
 * SOLVER_ENTRY(P) inside an initialiser. */
#define SOLVER_ADAPT(P)                                                                      \
  static void P##_init_(void *x, const double *q0, const double *p0) { P##_init(x, q0, p0); } \
  static int P##_step_(void *x, double h, int *iters) {                                      \
    P##_stats st;                                                                            \
    int rc = P##_step(x, h, NULL, &st);                                                      \
    if (iters) *iters = st.iters;                                                            \
    return rc;                                                                               \
  }                                                                                          \
  static double P##_energy_(const void *x) { return P##_energy(x, NULL); }                   \
  static void P##_g_(const void *x, double *g) { P##_constraints(x, NULL, g); }              \
  static void P##_hc_(const void *x, double *hc) { P##_hidden(x, NULL, hc); }                \
  static int P##_step_est_(void *x, double h, double *err_est) {                             \
    P##_stats st;                                                                            \
    int rc = P##_step(x, h, NULL, &st);                                                      \
    *err_est = st.err_est;                                                                   \
    return rc;                                                                               \
  }                                                                                          \
  static void P##_dense_(const void *x, double theta, double *q, double *p) {                \
    P##_dense(x, theta, q, p);                                                               \
  }
#define SOLVER_ENTRY(P)                                                                                         \
  {#P,           P##_M,       P##_NU,    P##_K,      P##_S,         sizeof(P##_state),                         \
   offsetof(P##_state, t), offsetof(P##_state, q), offsetof(P##_state, p), offsetof(P##_state, lambda),          \
   P##_init_,    P##_step_,   P##_energy_, P##_g_,   P##_hc_,      P##_step_est_, P##_dense_},

/* The solver of that name, or NULL. */
const Solver *solver_find(const char *name);
/* The solver for model (e.g. "pendulum") at (k, s), or NULL. */
const Solver *solver_for(const char *model, int k, int s);

/* Views into an opaque state. */
double *solver_t(const Solver *sv, void *x);
double *solver_q(const Solver *sv, void *x);
double *solver_p(const Solver *sv, void *x);
double *solver_lambda(const Solver *sv, void *x);

#endif
