/* fixedstep.c - the step loop shared by the fixed-step methods. */
#include "bench.h"

int fixedstep_run(const Stepper *sp, const Setting *set, Observer *ob, Outcome *out)
{
  long n;
  out->steps = out->iters = 0;
  out->itmax = 0;
  if (ob) {
    sp->get(sp->state, out->q, out->p);
    observer_start(ob, set->pb, out->q, out->p);
  }
  for (n = 0; n < set->nsteps; n++) {
    int it = 0;
    if (sp->step(sp->state, set->h, &it) != 0) return -2;
    out->iters += it;
    if (it > out->itmax) out->itmax = it;
    if (ob) {
      sp->get(sp->state, out->q, out->p);
      observer_point(ob, out->q, out->p);
    }
  }
  out->steps = set->nsteps;
  sp->get(sp->state, out->q, out->p);
  return 0;
}
