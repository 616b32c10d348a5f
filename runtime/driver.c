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
  return hbvmrt_run(model, NULL, argc, argv);                /* run.c */
}

/* A model with switching functions: a run ends its steps on their points
 * (run.c, switch.c); an ensemble runs as without them. */
int hbvmrt_main_switching(const hbvmrt_model *model, const hbvmrt_switching *sw, const hbvmrt_batch *batch,
                          int argc, char **argv)
{
  if (hbvmrt_ensemble_wanted(argc, argv))
    return hbvmrt_ensemble_main(model, batch, argc, argv);
  return hbvmrt_run(model, sw, argc, argv);
}

int hbvmrt_main_batch(const hbvmrt_model *model, const hbvmrt_batch *batch, int argc, char **argv)
{
  if (hbvmrt_ensemble_wanted(argc, argv))
    return hbvmrt_ensemble_main(model, batch, argc, argv);
  return hbvmrt_main(model, argc, argv);
}
