/* driver_adapters.h - the adapters a generated driver (emit_main.c) writes
 * for a double solver P, for the tests that run hbvmrt_main on solvers of
 * their own (check_events.c, check_switch.c): P##_init_, P##_pd_, P##_step_,
 * P##_adapt_, P##_energy_, P##_g_, P##_hc_, P##_dense_ (their statistics:
 * iters, err_est, and h, rejected of the adaptive step). */
#ifndef HBVM_TESTS_DRIVER_ADAPTERS_H
#define HBVM_TESTS_DRIVER_ADAPTERS_H

#define DRIVER_ADAPTERS(P)                                                                                          \
  static void P##_init_(void *x, const double *q0, const double *p0) { P##_init(x, q0, p0); }                        \
  static void P##_pd_(void *prm) { P##_params_default(prm); }                                                       \
  static int P##_step_(void *x, double h, const void *prm, hbvmrt_stats *st) {                                      \
    P##_stats s;                                                                                                    \
    int rc = P##_step(x, h, prm, &s);                                                                               \
    st->iters = s.iters;                                                                                            \
    st->err_est = s.err_est;                                                                                        \
    return rc;                                                                                                      \
  }                                                                                                                 \
  static int P##_adapt_(void *x, double *h, double tol, const void *prm, hbvmrt_stats *st) {                        \
    P##_stats s;                                                                                                    \
    int rc = P##_step_adaptive(x, h, tol, prm, &s);                                                                 \
    st->iters = s.iters;                                                                                            \
    st->err_est = s.err_est;                                                                                        \
    st->h = s.h;                                                                                                    \
    st->rejected = s.rejected;                                                                                      \
    return rc;                                                                                                      \
  }                                                                                                                 \
  static double P##_energy_(const void *x, const void *prm) { return P##_energy(x, prm); }                          \
  static void P##_g_(const void *x, const void *prm, double *g) { P##_constraints(x, prm, g); }                     \
  static void P##_hc_(const void *x, const void *prm, double *g) { P##_hidden(x, prm, g); }                         \
  static void P##_dense_(const void *x, double theta, void *y) {                                                    \
    const P##_state *a = x;                                                                                         \
    P##_state *b = y;                                                                                               \
    *b = *a;                                                                                                        \
    P##_dense(a, theta, b->q, b->p);                                                                                \
    b->t = a->t - a->hprev * (1 - theta);                                                                           \
  }

#endif
