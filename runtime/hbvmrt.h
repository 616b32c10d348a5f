/* hbvmrt.h - the small runtime behind a standalone hbvmgen solver.
 *
 * A generated NAME_main.c describes its model with an hbvmrt_model (sizes,
 * parameter names, and adapter functions that call NAME_step and friends on
 * opaque state and parameter blocks) and hands argc/argv to hbvmrt_main.
 * The runtime parses the driver options (docs/api.md, "The driver"), runs the loop,
 * writes the CSV, keeps the running maxima and prints the summary line.
 * The generated step never needs this library. */
#ifndef HBVMRT_H
#define HBVMRT_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* What one step reports back to the driver. */
typedef struct {
  int iters;          /* fixed-point iterations of the step */
  double increment;   /* final scaled increment */
  /* Filled by drivers from hbvmgen with error control (0 from older ones). */
  double err_est;     /* the step's local error estimate */
  double h;           /* the step taken (step_adaptive) */
  int rejected;       /* tries rejected before it (step_adaptive) */
  /* The step's relative energy defect, |H1 - H0| / (|K| + |U|) (0 from
   * drivers generated before it, and where the step conserves H exactly). */
  double defect;
  /* The step's simplified Newton iterations, factorisations of the Newton
   * matrix and evaluations of its J (0 from drivers of solvers without
   * Newton: the runtime zeroes the stats before each step). */
  int newton, factors, jacobians;
} hbvmrt_stats;

/* One run-time parameter: its name and where it lives in the params block. */
typedef struct {
  const char *name;
  size_t offset;      /* byte offset of the double in the params block */
} hbvmrt_param;

/* Everything the driver needs to know about one generated model.
 * State and params are opaque blocks of state_size / params_size bytes;
 * t, q, p, lambda are found at the given byte offsets inside the state. */
typedef struct {
  const char *name;
  int m, nu, k, s;
  size_t state_size, params_size;
  size_t off_t, off_q, off_p, off_lambda;
  int nparams;
  const hbvmrt_param *params;
  const double *q0, *p0;                 /* model defaults, m values each */
  void (*init)(void *x, const double *q0, const double *p0);
  void (*params_default)(void *prm);
  int (*step)(void *x, double h, const void *prm, hbvmrt_stats *st);
  const char *(*strerror)(int code);     /* name of a nonzero step code */
  double (*energy)(const void *x, const void *prm);
  void (*constraints)(const void *x, const void *prm, double *g);
  void (*hidden)(const void *x, const void *prm, double *gp);
  /* The m coordinate names ("x", "x[3]") for the CSV header; NULL (as in
   * drivers from hbvmgen 0.1, which end before this field) gives the
   * numbered header q1..qm. */
  const char *const *names;
  /* Drivers generated before these fields leave them NULL, 0 and start as
   * before, unchecked.  Init at the run's params (q0, p0 NULL: the model's, which may
   * depend on them); the projection onto the constraints (NAME_project: 0 or a
   * step code, x unchanged on failure; dq, dp the largest change of a q, p);
   * the relative precision of the solver's real type (DBL_EPSILON,
   * FLT_EPSILON).  Add new fields after these. */
  void (*init_params)(void *x, const double *q0, const double *p0, const void *prm);
  int (*project)(void *x, const void *prm, double *dq, double *dp);
  double eps;
  /* NAME_step_adaptive (NULL in drivers generated before it: no --tol): a
   * step of at most *h within tol, *h the next step proposed on return. */
  int (*step_adaptive)(void *x, double *h, double tol, const void *prm, hbvmrt_stats *st);
  /* Dense output and events (NULL and 0 in drivers generated before them:
   * no --dt, --events, --stop-at).  dense: y (a state block) becomes x at
   * t - h (1 - theta), 0 <= theta <= 1, inside the last step h, its q and p
   * from NAME_dense (y is for the functions above, never stepped); events:
   * the nevents values of NAME_events at the state x; event_dirs: 0 any
   * sign change counts, 1 rising only, -1 falling only. */
  void (*dense)(const void *x, double theta, void *y);
  int nevents;
  const char *const *event_names;
  const int *event_dirs;
  void (*events)(const void *x, const void *prm, double *values);
  /* Set the time of the state x to t (--t0, --restart); NULL: a double
   * state's t is written at off_t (drivers generated before it, and double
   * solvers), and a float driver before it refuses --t0. */
  void (*set_time)(void *x, double t);
} hbvmrt_model;

/* Run the standalone driver: returns the process exit status
 * (0 success, 1 bad arguments, 2 a failed step, 3 steps that did not
 * conserve H). */
int hbvmrt_main(const hbvmrt_model *model, int argc, char **argv);

/* The switching functions of a model that is not smooth (NAME_switch,
 * docs/api.md, "Kinks and jumps"): n of them, their kinds (0 a kink or jump
 * where the value changes sign, 1 where it crosses an integer), the
 * function each comes from ("abs", "min/max", ...), their values at the
 * state x, and NAME_restart (the next step starts afresh). */
typedef struct {
  int n;
  const int *kinds;
  const char *const *what;
  void (*values)(const void *x, const void *prm, double *v);
  void (*restart)(void *x);
} hbvmrt_switching;

/* The batch step of a solver generated with --batch W, for the ensemble
 * runner (--ensemble, --sweep), which then steps W trajectories at a time.
 * The batch block is size bytes; lanes are moved in and out as state blocks;
 * step takes W params blocks one after another and writes W codes and
 * iteration counts; observe writes H (W values), g and hc (nu * W values
 * each, value a of lane l at a * W + l). */
typedef struct {
  int w;
  size_t size;
  void (*set)(void *b, int lane, const void *x);
  void (*get)(const void *b, int lane, void *x);
  void (*idle)(void *b, int lane, int idle);
  int (*step)(void *b, double h, const void *prm, int *code, int *iters);
  void (*observe)(const void *b, const void *prm, double *H, double *g, double *hc);
} hbvmrt_batch;

/* hbvmrt_main for a driver with a batch step. */
int hbvmrt_main_batch(const hbvmrt_model *model, const hbvmrt_batch *batch, int argc, char **argv);

/* hbvmrt_main (batch NULL) or hbvmrt_main_batch for a model with switching
 * functions: a run's steps end on the points where they change sign
 * (--no-switch: not); an ensemble's do not. */
int hbvmrt_main_switching(const hbvmrt_model *model, const hbvmrt_switching *sw, const hbvmrt_batch *batch,
                          int argc, char **argv);

#ifdef __cplusplus
}
#endif

#endif
