/* hbvm_adaptive.c - the methods "hbvm-adaptive" and "hbvm-poly-adaptive": a
 * generated solver (--multiplier const or poly) stepped by its own
 * NAME_step_adaptive at the tolerance set->tol from 0 to set->T, the last
 * step shortened to end on T exactly, as the driver's --tol does. */
#include <stdlib.h>

#include "bench.h"
#include "hbvm.h"

static int run(const Setting *set, Observer *ob, Outcome *out, GenFamily family)
{
  const GenSolver *gs = gen_solver_find(set->pb->name, set->k, set->s, family);
  double q0[BENCH_MAXM], p0[BENCH_MAXM], t = 0, h = 1e-3 * set->T;
  void *x;
  int rc = 0;
  if (!gs || gs->m != set->pb->m || gs->nu != set->pb->nu) return -1;
  if (!(x = malloc(gs->size))) return -2;
  set->pb->init(q0, p0);
  gs->init(x, q0, p0);
  out->steps = out->iters = 0;
  out->itmax = 0;
  if (ob) observer_start(ob, set->pb, q0, p0);
  while (t < set->T) {
    double rest = set->T - t, hn = h >= rest * (1 - 1e-12) ? rest : h, taken;
    int it = 0;
    if (gs->adaptive(x, &hn, set->tol, &taken, &it) != 0) {
      rc = -2;
      break;
    }
    t = taken == rest ? set->T : t + taken;
    if (taken != rest) h = hn; /* the shortened last step proposes nothing */
    out->steps++;
    out->iters += it;
    if (it > out->itmax) out->itmax = it;
    if (ob) {
      gs->get(x, out->q, out->p);
      observer_point(ob, out->q, out->p);
    }
  }
  gs->get(x, out->q, out->p);
  free(x);
  return rc;
}

int hbvm_adaptive_integrate(const Setting *set, Observer *ob, Outcome *out) { return run(set, ob, out, GEN_CONST); }

int hbvm_poly_adaptive_integrate(const Setting *set, Observer *ob, Outcome *out)
{
  return run(set, ob, out, GEN_POLY);
}
