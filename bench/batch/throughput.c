/* throughput.c - per-trajectory throughput of NAME_batch_step against
 * NAME_step of the same solver (bench/batch/run.sh builds one per model and
 * W with -DP=prefix -DHDR='"prefix.h"').
 *
 * NT trajectories (the model's initial values, momenta scaled by 1 + j/1000
 * for trajectory j), NSTEP steps of h each: once with NAME_step per
 * trajectory, once in NT/W batches. The two alternate REPS times (side by
 * side, so a shared core's load hits both alike); printed: the medians in ns
 * per trajectory-step and their ratio. Exits 1 if a lane ever differs from
 * the scalar run at the end. */
#define _POSIX_C_SOURCE 200809L

#include "lanes.h"

int main(int argc, char **argv) {
  double h = argc > 1 ? atof(argv[1]) : 0.01, ts[REPS], tb[REPS];
  long nstep = argc > 2 ? atol(argv[2]) : 1000;
  static F(_state) s0[NT], s[NT], y;
  static F(_batch) b[NT / F(_W)];
  int j, r, bad = 0;
  long n;
  initial_states(s0);
  for (r = 0; r < REPS; r++) {
    double t = now();
    memcpy(s, s0, sizeof s);
    for (j = 0; j < NT; j++)
      for (n = 0; n < nstep; n++) bad |= F(_step)(&s[j], h, NULL, NULL) != 0;
    ts[r] = (now() - t) / ((double)NT * nstep) * 1e9;
    t = now();
    for (j = 0; j < NT; j++) F(_batch_set)(&b[j / F(_W)], j % F(_W), &s0[j]);
    for (j = 0; j < NT / F(_W); j++)
      for (n = 0; n < nstep; n++) bad |= F(_batch_step)(&b[j], h, NULL, NULL) != 0;
    tb[r] = (now() - t) / ((double)NT * nstep) * 1e9;
  }
  for (j = 0; j < NT; j++) {
    F(_batch_get)(&b[j / F(_W)], j % F(_W), &y);
    bad |= memcmp(&y, &s[j], sizeof y) != 0;
  }
  qsort(ts, REPS, sizeof ts[0], cmp);
  qsort(tb, REPS, sizeof tb[0], cmp);
  printf("%.1f,%.1f,%.2f\n", ts[REPS / 2], tb[REPS / 2], ts[REPS / 2] / tb[REPS / 2]);
  if (bad) fprintf(stderr, "throughput: a step failed or a lane differs from NAME_step\n");
  return bad;
}
