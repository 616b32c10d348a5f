/* driver.c - the entry points of a generated driver (hbvmrt.h).
 *
 * hbvmrt_main and hbvmrt_main_batch send --ensemble and --sweep to
 * ensemble.c and every other run to run.c (hbvmrt_run). This file is the
 * one above both: run.c and ensemble.c never call each other. */
#include "hbvmrt_internal.h"

/* The standalone driver: an ensemble (ensemble.c), or one run (run.c). */
int hbvmrt_main(const hbvmrt_model *model, int argc, char **argv)
{
  if (hbvmrt_ensemble_wanted(argc, argv))
    return hbvmrt_ensemble_main(model, NULL, argc, argv);   /* ensemble.c */
  return hbvmrt_run(model, argc, argv);                      /* run.c */
}

int hbvmrt_main_batch(const hbvmrt_model *model, const hbvmrt_batch *batch, int argc, char **argv)
{
  if (hbvmrt_ensemble_wanted(argc, argv))
    return hbvmrt_ensemble_main(model, batch, argc, argv);
  return hbvmrt_main(model, argc, argv);
}
