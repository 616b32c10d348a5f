/* driver_adapters.h - the adapters a generated driver (emit_main.c) writes
 * for a double solver P, for the tests that run hbvmrt_main on solvers of
 * their own (check_events.c, check_switch.c): P##_init_, P##_pd_, P##_step_,
 * P##_adapt_, P##_energy_, P##_g_, P##_hc_, P##_dense_ (their statistics:
 * iters, err_est, and h, rejected of the adaptive step). */
#ifndef HBVM_TESTS_DRIVER_ADAPTERS_H
#define HBVM_TESTS_DRIVER_ADAPTERS_H

#include <check.h>
#include <float.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "hbvmrt.h"

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

/* The driver's adapters and model description P##_model of solver P with
 * events (as emit_main.c writes them for a double solver without
 * parameters), its coordinates named by NAMES (check_events.c,
 * check_reroll.c). */
#define DRIVER_EVENTS_MODEL(P, NAMES)                                                                               \
  DRIVER_ADAPTERS(P)                                                                                                \
  static void P##_events_(const void *x, const void *prm, double *v) { P##_events(x, prm, v); }                     \
  static const hbvmrt_model P##_model = {                                                                           \
      #P, P##_M, P##_NU, P##_K, P##_S, sizeof(P##_state), sizeof(P##_params), offsetof(P##_state, t),               \
      offsetof(P##_state, q), offsetof(P##_state, p), offsetof(P##_state, lambda), 0, NULL, NULL, NULL, P##_init_,   \
      P##_pd_, P##_step_, P##_strerror, P##_energy_, P##_g_, P##_hc_, NAMES, NULL, NULL, DBL_EPSILON, P##_adapt_,   \
      P##_dense_, P##_NEVENTS, P##_event_names, P##_event_dirs, P##_events_, NULL};

/* Run the driver of md (hbvmrt_main, or hbvmrt_main_switching where sw is
 * not NULL) on the command line cmd (words between single spaces, the
 * first the program's name), its stderr (the summary line, the errors) into
 * err (n bytes, NUL-terminated). Returns the exit status. */
static int driver_run_captured(const hbvmrt_model *md, const hbvmrt_switching *sw, char *cmd, char *err, size_t n) {
  char *argv[32];
  int argc = 0;
  for (char *tok = strtok(cmd, " "); tok && argc < 31; tok = strtok(NULL, " ")) argv[argc++] = tok;
  argv[argc] = NULL;
  FILE *saved = tmpfile();
  ck_assert(saved != NULL);
  int fd = dup(2);
  dup2(fileno(saved), 2);
  int status = sw ? hbvmrt_main_switching(md, sw, NULL, argc, argv) : hbvmrt_main(md, argc, argv);
  fflush(stderr);
  dup2(fd, 2);
  close(fd);
  rewind(saved);
  err[fread(err, 1, n - 1, saved)] = 0;
  fclose(saved);
  return status;
}

#endif
