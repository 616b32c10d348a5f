/* sweep.c - work-precision points of one method on one problem.
 *
 * Each point is one untimed run with the observer (the error at T, the
 * maxima of |H - H0| and |g| over every step, the iterations), then the
 * median CPU time of `repeats` timed runs without it. Points go from the
 * coarsest h (loosest tolerance) to the finest and stop early once the
 * error is at the reference's level or one run exceeds the time cap, so a
 * sweep's cost stays bounded; they also stop once an error below 1e-7 has
 * grown to 4 times its smallest value (round-off dominates: finer steps
 * only make it worse). A point whose run fails (the fixed-point
 * iteration does not converge at a large h, IDA gives up at a loose
 * tolerance) is reported on stderr and skipped. */
#include "sweep.h"

#include <math.h>
#include <string.h>

#include "linalg.h"
#include "timing.h"

const char *const sweep_wp_header = "problem,method,k,s,h,steps,seconds,err_q,err_H,err_g";
const char *const sweep_iters_header = "problem,method,k,s,h,steps,iters_per_step,iters_max";
const char *const sweep_overhead_header = "problem,k,s,h,iters_per_step,step_ns,grad_ns,ratio";

/* What a timed run needs. */
typedef struct {
  const MethodDef *md;
  const Setting *set;
  Outcome out;
} TimedRun;

static int timed_run(void *ctx)
{
  TimedRun *tr = ctx;
  return method_run(tr->md, tr->set, NULL, &tr->out);
}

/* The i-th point's setting; 0, or -1 past the end of the range. */
static int point(const Sweep *sw, int i, Setting *set)
{
  memset(set, 0, sizeof *set);
  set->pb = sw->pb;
  set->k = sw->k;
  set->s = sw->s;
  set->T = sw->T;
  if (sw->md->integrate) {
    set->tol = sw->from / pow(sw->factor, i);
    return set->tol < sw->to * (1 - 1e-9) ? -1 : 0;
  }
  set->nsteps = lround(ceil(sw->T / sw->from - 1e-9) * pow(sw->factor, i));
  set->h = sw->T / (double)set->nsteps;
  return set->h < sw->to * (1 - 1e-9) ? -1 : 0;
}

/* One point: the rows of the three CSV files. */
static void write_rows(const Sweep *sw, const Setting *set, const Outcome *out, const Observer *ob, double seconds,
                       double err, double grad_ns)
{
  const double none = NAN;
  int hbvm = sw->k > 0, fixed = !sw->md->integrate;
  double h = fixed ? set->h : set->tol, ips = (double)out->iters / (double)out->steps;
  fprintf(sw->wp, "%s,%s,", sw->pb->name, sw->md->name);
  csv_num(sw->wp, "%.0f", hbvm ? sw->k : none, ',');
  csv_num(sw->wp, "%.0f", hbvm ? sw->s : none, ',');
  fprintf(sw->wp, "%.10g,%ld,%.6g,%.4e,%.4e,", h, out->steps, seconds, err, ob->dH);
  csv_num(sw->wp, "%.4e", sw->pb->nu ? ob->dg : none, '\n');
  if (hbvm) {
    fprintf(sw->iters, "%s,%s,%d,%d,%.10g,%ld,%.4f,%d\n", sw->pb->name, sw->md->name, sw->k, sw->s, h, out->steps, ips,
            out->itmax);
  }
  if (hbvm && sw->overhead && strcmp(sw->md->name, "hbvm") == 0) {
    double step_ns = 1e9 * seconds / (double)out->steps;
    fprintf(sw->overhead, "%s,%d,%d,%.10g,%.4f,%.2f,%.3f,%.3f\n", sw->pb->name, sw->k, sw->s, h, ips, step_ns, grad_ns,
            step_ns / (ips * sw->k * grad_ns));
  }
  fflush(NULL);
}

int sweep_run(const Sweep *sw)
{
  Setting set;
  int i, done = 0;
  double grad_ns = NAN, best = HUGE_VAL;
  if (sw->overhead && sw->k > 0) grad_ns = gradient_ns(sw->pb, sw->min_seconds, sw->repeats);
  for (i = 0; point(sw, i, &set) == 0; i++) {
    Observer ob;
    TimedRun tr;
    double t0 = cpu_seconds(), t1, seconds, err;
    int rc = method_run(sw->md, &set, &ob, &tr.out);
    t1 = cpu_seconds() - t0;
    if (rc == -1) return -1;
    err = problem_error(sw->pb, tr.out.q, tr.out.p, sw->qref, sw->pref);
    if (rc != 0 || !isfinite(err)) {
      fprintf(stderr, "bench: %s %s k=%d s=%d h=%g tol=%g: run failed, point skipped\n", sw->pb->name, sw->md->name,
              sw->k, sw->s, set.h, set.tol);
      if (t1 > sw->cap) break;
      continue;
    }
    tr.md = sw->md;
    tr.set = &set;
    if (time_median(timed_run, &tr, sw->min_seconds, sw->repeats, &seconds, NULL) != 0) continue;
    write_rows(sw, &set, &tr.out, &ob, seconds, err, grad_ns);
    done++;
    best = fmin(best, err);
    /* at the reference's accuracy, past the round-off floor, or too slow */
    if (err < sw->floor || (!sw->keep_going && best < 1e-7 && err > 4 * best) || seconds > sw->cap) break;
  }
  return done ? 0 : -2;
}

/* ---------------------------------------------------- the gradient's cost */

typedef struct {
  const Problem *pb;
  double q[BENCH_MAXM], gu[BENCH_MAXM], G[BENCH_MAXM * BENCH_MAXNU], sink;
} GradRun;

#define GRAD_CALLS 1000

/* GRAD_CALLS evaluations of grad U and grad g at points that move a
 * little each time (so nothing can be hoisted), their results summed. */
static int grad_calls(void *ctx)
{
  GradRun *gr = ctx;
  const Problem *pb = gr->pb;
  int n;
  for (n = 0; n < GRAD_CALLS; n++) {
    gr->q[n % pb->m] += 1e-12;
    pb->grad(gr->q, gr->gu);
    if (pb->nu) pb->jac(gr->q, gr->G);
    gr->sink += gr->gu[0] + gr->G[0];
  }
  return 0;
}

double gradient_ns(const Problem *pb, double min_seconds, int repeats)
{
  GradRun gr;
  double p[BENCH_MAXM], seconds;
  memset(&gr, 0, sizeof gr);
  gr.pb = pb;
  pb->init(gr.q, p);
  time_median(grad_calls, &gr, min_seconds, repeats, &seconds, NULL);
  if (gr.sink == 12345.678) fputc(' ', stderr); /* keep the results live */
  return 1e9 * seconds / GRAD_CALLS;
}
