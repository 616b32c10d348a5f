/* methods.c - the table of methods, by the names of the CSV's method column. */
#include <string.h>

#include "bench.h"

static const MethodDef methods[] = {
    {"hbvm", hbvm_open, hbvm_close, NULL},
    {"hbvm-poly", hbvm_poly_open, hbvm_close, NULL},
    {"hbvm-newton", hbvm_newton_open, hbvm_close, NULL},
    {"hbvm-poly-newton", hbvm_poly_newton_open, hbvm_close, NULL},
    {"hbvm-generic", generic_open, generic_close, NULL},
    {"rattle", rattle_open, rattle_close, NULL},
    {"ida", NULL, NULL, ida_integrate},
    {"gsl-rk8pd", NULL, NULL, gsl_rk8pd_integrate},
    {"gsl-rk4imp", NULL, NULL, gsl_rk4imp_integrate},
    {"gsl-msbdf", NULL, NULL, gsl_msbdf_integrate},
    {"gsl-bsimp", NULL, NULL, gsl_bsimp_integrate},
    {"hbvm-adaptive", NULL, NULL, hbvm_adaptive_integrate},
    {"hbvm-poly-adaptive", NULL, NULL, hbvm_poly_adaptive_integrate},
};

const MethodDef *method_find(const char *name)
{
  size_t i;
  for (i = 0; i < sizeof methods / sizeof methods[0]; i++)
    if (strcmp(methods[i].name, name) == 0) return &methods[i];
  return NULL;
}

int method_run(const MethodDef *md, const Setting *set, Observer *ob, Outcome *out)
{
  Stepper sp;
  int rc;
  if (md->integrate) return md->integrate(set, ob, out);
  if (md->open(set, &sp) != 0) return -1;
  rc = fixedstep_run(&sp, set, ob, out);
  md->close(&sp);
  return rc;
}
