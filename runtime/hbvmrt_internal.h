/* hbvmrt_internal.h - what the runtime's files share; not installed, not
 * seen by generated code.  One section per file: args.c parses the driver
 * options into an hbvmrt_opts, csv.c writes the header and rows, run.c
 * (hbvmrt_run) ties them to the loop of one run, ensemble.c to many;
 * driver.c (hbvmrt_main) chooses between the two. */
#ifndef HBVMRT_INTERNAL_H
#define HBVMRT_INTERNAL_H

#include <stdio.h>

#include "hbvmrt.h"

#if defined(__GNUC__)
#define HBVMRT_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define HBVMRT_PRINTF(f, a)
#endif

/* args.c */

#define HBVMRT_DEFAULT_H 0.01   /* step when -h is not given */
#define HBVMRT_DEFAULT_T 10.0   /* time span when neither -T nor -N is given */
/* Initial values whose projection onto the constraints moves q or p by more
 * than this, relative to max|q|, max|p|, are refused without --project (or
 * 64 ulps of the solver's real type, if that is more: float). */
#define HBVMRT_CONSISTENCY_TOL 1e-10
/* A failed step of the fixed h is retried as two halves, each of which may
 * be halved again, this many times deep (h / 256) before the run stops. */
#define HBVMRT_HALVINGS 8
/* Per-step messages (a failed step retried as halves) written per run; the
 * rest are counted in one line at the end. */
#define HBVMRT_MAX_SAID 10
/* A step whose relative energy defect (hbvmrt_stats.defect) is above the
 * square root of the solver's precision (1.5e-8 in double, 3.5e-4 in float)
 * lost half the digits of H in one step: flagged in the summary, exit
 * status 3 (run.c). */
/* A run whose largest local error estimate is above this times
 * 1 + max|q| is warned about (run.c). */
#define HBVMRT_ERR_EST_WARN 1e-3
/* A fixed step cut on more switching points than this (a chattering
 * contact) takes the rest of its h across them (run.c). */
#define HBVMRT_MAX_CUTS 1000
/* The most lanes of a batch (hbvmgen --batch W: W <= 64). */
#define HBVMRT_MAX_LANES 64
/* The most CSV rows --dt may ask for (span / DT), and the most trajectories
 * of --sweep or --ensemble (their results are kept until all are done). */
#define HBVMRT_MAX_ROWS 1e9
#ifndef HBVMRT_MAX_TRAJ   /* (smaller in the fuzz build: tests/fuzz/run_runtime.sh) */
#define HBVMRT_MAX_TRAJ 10000000L
#endif

/* The driver options once parsed and checked. */
typedef struct {
  double h;            /* step, nonzero, may be negative */
  long nsteps;         /* N >= 0 (from -N, or from -T and h) */
  double T;            /* with to_T: the span, hit exactly (last step shortened) */
  int to_T;            /* the span came from -T or its default, not -N */
  double tol;          /* --tol: adaptive steps within it (h the first); 0: fixed h */
  long every;          /* K >= 1: a CSV row every K steps */
  double *q0, *p0;     /* m values each; NULL when the option was not given */
  double *param_val;   /* nparams values from --param ... */
  char *param_set;     /* ... nonzero where one was given */
  const char *csv;     /* NULL: no CSV; "-": stdout */
  int quiet;           /* no progress line */
  int project;         /* --project: move q0, p0 onto the constraints */
  double dt;           /* --dt: CSV rows on this grid of t, steps from the step's start (0: per step) */
  const char *events;  /* --events FILE: the events CSV ("-": stdout), or NULL */
  int stop_event;      /* --stop-at: the event that ends the run, or -1 */
  long stop_count;     /* ... at its stop_count-th occurrence */
  int no_switch;       /* --no-switch: steps not ended on the switching points */
  double t0;           /* --t0 (or --restart's row): the time of the initial state */
  double hmax;         /* --hmax: the largest adaptive step (0: none) */
  long max_steps;      /* --max-steps: the run stops with status 2 after that many (0: none) */
  /* --atol/--rtol: each step within atol + rtol max|q| (per unit time); 0, 0: tol (1 + max|q|).
   * Under --tol-per run these and tol are divided by the span T once parsed. */
  double atol, rtol;
  int tol_per_run;     /* --tol-per run: the tolerance is on the error at T, not per unit time */
} hbvmrt_opts;

/* What hbvmrt_parse_args tells the caller to do next. */
enum {
  HBVMRT_ARGS_RUN,     /* options fine: run */
  HBVMRT_ARGS_DONE,    /* --help printed: exit 0 */
  HBVMRT_ARGS_ERROR    /* error printed: exit 1 */
};

int hbvmrt_parse_args(const hbvmrt_model *md, int argc, char **argv,
                      hbvmrt_opts *o);
void hbvmrt_opts_free(hbvmrt_opts *o);
void hbvmrt_apply_params(const hbvmrt_model *md, const hbvmrt_opts *o,
                         void *prm);
void hbvmrt_error(const hbvmrt_model *md, const char *fmt, ...)
  HBVMRT_PRINTF(2, 3);

/* csv.c: both return 0, or -1 once the stream is in error. */

int hbvmrt_csv_header(FILE *f, const hbvmrt_model *md);
int hbvmrt_csv_row(FILE *f, const hbvmrt_model *md, const void *x, double H,
                   const double *g, const double *hc);

/* csv.c: the events CSV, event,t,x..,p_x..; opening and closing an output */

FILE *hbvmrt_out_open(const char *path);
int hbvmrt_out_close(FILE *f, int err);

int hbvmrt_csv_event_header(FILE *f, const hbvmrt_model *md);
int hbvmrt_csv_event_row(FILE *f, const hbvmrt_model *md, const char *name, const void *x);

/* events.c: the model's events inside the steps (--events, --stop-at) */

typedef struct {
  const hbvmrt_model *md;   /* NULL: events not wanted */
  const void *prm;
  double *v0, *v1, *vt;     /* the values at the step's start, end, scratch */
  double *theta;            /* per event found in the step: where */
  int *found;               /* the events found in the step, in time order */
  long *count;              /* occurrences so far, per event */
  void *y, *z;              /* scratch states: dense output, the event's state */
  int stop_event;           /* --stop-at, or -1 */
  long stop_count;
  FILE *f;                  /* --events, or NULL */
  const char *path;
  int ferr;                 /* errno of the first failed write, or 0 */
} hbvmrt_events;

/* Set up for --events / --stop-at (nothing when neither is given) at the
 * initial state x: 0, or -1 after reporting (an event not a number at x). */
int hbvmrt_events_open(hbvmrt_events *ev, const hbvmrt_model *md, const hbvmrt_opts *o, const void *prm,
                       const void *x);
/* After a step h from x0 to x: the events inside it written in time order;
 * returns 1 when the --stop-at event occurred (x is then the state at it),
 * 2 after reporting an event that is not a number at x (the run fails
 * there), -1 once writing failed, else 0. */
int hbvmrt_events_step(hbvmrt_events *ev, const void *x0, void *x, double h);
/* Close the events CSV: 0, or -1 after reporting a write error. */
int hbvmrt_events_close(hbvmrt_events *ev);
/* The state at theta inside the step from x0 to x into z: a step of the
 * method of size hsub (theta times the step) from a copy of x0, as accurate
 * as the run's steps, or, where theta <= 0, hsub = 0 or that step fails, the
 * dense output of x at theta (at least 0). Returns 0 for the step, 1 for
 * the dense output. */
int hbvmrt_state_within(const hbvmrt_model *md, const void *prm, const void *x0, const void *x, double theta,
                        double hsub, void *z);

/* switch.c: steps ended on the points where U or g is not smooth (the
 * model's switching functions; --no-switch turns it off) */

typedef struct {
  const hbvmrt_model *md;   /* NULL: off (a smooth model, or --no-switch) */
  const hbvmrt_switching *fn;
  const void *prm;
  double *v0, *v1;          /* values of the functions: scratch */
  double *side;             /* per function: the side it is on (-1, 1; 0 on the point), for floor its cell */
  void *z[4];               /* scratch states of the search */
  long crossed;             /* switching points crossed */
  int cut;                  /* the last step searched ended on a point */
  int pending;              /* the next step restarts (NAME_restart) */
} hbvmrt_switch;

/* Set up at the initial state x (nothing when off): 0, or -1 after
 * reporting. */
int hbvmrt_switch_open(hbvmrt_switch *sw, const hbvmrt_model *md, const hbvmrt_switching *fn,
                       const hbvmrt_opts *o, const void *prm, const void *x);
/* A step of at most h from x0 (x a copy of it) that ends on the first
 * switching point inside it: the step h when it crosses none (0: x that
 * step, st its figures), else a step to the point located to 1e-13 (1 + |t|)
 * by steps of the method from x0, the first of them at guess h when guess
 * is in (0, 1) (1: x that step, st its figures, sw->cut set, the point's
 * side flipped, and the next step restarts). A step that does not converge
 * counts as one past a point; when the steps fail but not at a point, the
 * first step's code, x unchanged (-1: a point that could not be located). */
int hbvmrt_switch_find(hbvmrt_switch *sw, const void *x0, void *x, double h, double guess, hbvmrt_stats *st);
/* Whether a switching point is predicted within the step h from x by the
 * last step's polynomials (dense output) carried on; *guess where, as a
 * fraction of h. */
int hbvmrt_switch_predicted(hbvmrt_switch *sw, const void *x, double h, double *guess);
/* hbvmrt_adaptive_step from x0 (x a copy of it) ended on the first
 * switching point inside the step: found by the last step's polynomials
 * carried on before it is tried, or after it crossed one or failed
 * (hbvmrt_switch_find, from the step tried). The step's code; *h stays the
 * proposal after a step cut on a point. */
int hbvmrt_switch_adaptive(hbvmrt_switch *sw, const hbvmrt_opts *o, const void *x0, void *x, double *h,
                           hbvmrt_stats *st, int *at_end);
/* Before a step from x: after a cut, the step's history is forgotten. */
void hbvmrt_switch_before(hbvmrt_switch *sw, void *x);
void hbvmrt_switch_close(hbvmrt_switch *sw);

/* span.c: stepping to the end of the span, hit exactly, and halving a failed
 * fixed step (run.c, ensemble.c) */

/* The time of the state x (its rounded value). */
double hbvmrt_state_time(const hbvmrt_model *md, const void *x);
/* The end of the span: T in the direction of h. */
double hbvmrt_span_end(const hbvmrt_opts *o);
/* The number of fixed steps of |h| over the span T >= 0 (0 for T = 0), or
 * -1 when there are too many to count (2^53 or more). */
long hbvmrt_span_steps(double T, double h);
/* The state x of a run of -T that ended within round-off of the span's end:
 * its t set to that end exactly. */
void hbvmrt_span_land(const hbvmrt_model *md, const hbvmrt_opts *o, void *x);
/* Step n of N of a fixed-step run from x: h, the last shortened to end on T. */
double hbvmrt_fixed_step(const hbvmrt_model *md, const hbvmrt_opts *o, long n, const void *x);
/* The tolerance per unit time of the next adaptive step from x: o->tol, or
 * (atol + rtol max|q|) / (1 + max|q|) under --atol/--rtol. */
double hbvmrt_step_tol(const hbvmrt_model *md, const hbvmrt_opts *o, const void *x);
/* One adaptive step toward the span's end from x, of at most *h and --hmax
 * (the last shortened to end on it); the step's code, the next h in *h,
 * *at_end when on it. */
int hbvmrt_adaptive_step(const hbvmrt_model *md, const hbvmrt_opts *o, void *x, double *h, const void *prm,
                         hbvmrt_stats *st, int *at_end);
/* Set the time of the state x to t (--t0): 0, or -1 when the driver cannot. */
int hbvmrt_set_time(const hbvmrt_model *md, void *x, double t);

/* What the caller of hbvmrt_advance hears: before each try (may be NULL),
 * after each step taken (its stats and size; nonzero: stop there), after
 * each failed try (may be NULL). */
typedef struct {
  void (*before)(void *ctx);
  int (*taken)(void *ctx, const hbvmrt_stats *st, double h);
  void (*failed)(void *ctx, double h, int code, int depth);
  void *ctx;
} hbvmrt_steps;
/* Advance x by the fixed step h, a failed step retried as halves
 * (HBVMRT_HALVINGS deep); 0 or the last failed step's code. */
int hbvmrt_advance(const hbvmrt_model *md, void *x, const void *prm, double h, int depth, const hbvmrt_steps *cb,
                   int *stopped);
/* The halves of a step h that failed with code at depth, as hbvmrt_advance. */
int hbvmrt_halve(const hbvmrt_model *md, void *x, const void *prm, double h, int code, int depth,
                 const hbvmrt_steps *cb, int *stopped);

/* run.c: one run of the standalone driver (hbvmrt_main without an ensemble) */

/* The progress line's estimate of the time left, "ETA 1m05s", into buf:
 * from the seconds elapsed and the share done (0 < done <= 1); "" before. */
void hbvmrt_eta(double elapsed, double done, char *buf, size_t n);

int hbvmrt_run(const hbvmrt_model *md, const hbvmrt_switching *sw, int argc, char **argv);

/* table.c: a CSV table of numbers (--ensemble FILE) */

typedef struct {
  char *text;          /* the file, which the names point into */
  int ncol;
  char **names;        /* the ncol column names of the header */
  int *name_col;       /* ... and the column (byte) where each starts */
  long header_line;
  long nrow;
  double *val;         /* nrow x ncol, row by row */
} hbvmrt_table;

/* Read path into *tb (which hbvmrt_table_free releases in every case): 0,
 * or -1 after an error naming the file, line and column; at most max_rows
 * rows, and at least one. */
int hbvmrt_table_read(const hbvmrt_model *md, const char *path, long max_rows, hbvmrt_table *tb);
void hbvmrt_table_free(hbvmrt_table *tb);

/* restart.c: --restart FILE[:ROW], the initial state from a row of the driver's CSV */

/* Set o->t0, o->q0, o->p0 from row ROW (1-based, default the last) of the
 * CSV named by val: 0, or -1 after reporting. */
int hbvmrt_restart(const hbvmrt_model *md, const char *val, hbvmrt_opts *o);

/* ensemble.c: --ensemble FILE / --sweep NAME=A:B:N, many trajectories */

int hbvmrt_ensemble_wanted(int argc, char **argv);
int hbvmrt_ensemble_main(const hbvmrt_model *md, const hbvmrt_batch *bt, int argc, char **argv);

#endif
