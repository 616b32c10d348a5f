/* adaptive.c - NAME_batch_step_adaptive (the lanes share h) against
 * NAME_step_adaptive per trajectory, over a span (bench/batch/run.sh builds
 * one per model with -DP=prefix -DHDR='"prefix.h"').
 *
 * NT trajectories (the model's initial values, momenta scaled by
 * 1 + j / 1000 for trajectory j: close, as a narrow sweep), from t = 0 to T
 * at tolerance TOL from the first step T / 1000: once each with
 * NAME_step_adaptive, once in NT / W batches. The two alternate REPS times;
 * printed: the medians in ns per trajectory and unit of time, their ratio,
 * and the steps a trajectory took each way (the batch takes the smallest
 * step any of its lanes needs). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>

#include "lanes.h"

int main(int argc, char **argv) {
  double T = argc > 1 ? atof(argv[1]) : 10, tol = argc > 2 ? atof(argv[2]) : 1e-8, ts[REPS], tb[REPS];
  static F(_state) s0[NT], s[NT];
  static F(_batch) b[NT / F(_W)];
  long steps_s = 0, steps_b = 0;
  int j, r, bad = 0;
  initial_states(s0);
  for (r = 0; r < REPS; r++) {
    double t = now();
    memcpy(s, s0, sizeof s);
    steps_s = steps_b = 0;
    for (j = 0; j < NT; j++) {
      F(_real) h = (F(_real))(T / 1000);
      while (!bad && s[j].t < T) {
        F(_real) hn = s[j].t + h > T ? (F(_real))(T - s[j].t) : h;
        bad |= F(_step_adaptive)(&s[j], &hn, (F(_real))tol, NULL, NULL) != 0;
        h = hn;
        steps_s++;
      }
    }
    ts[r] = (now() - t) / (NT * T) * 1e9;
    t = now();
    for (j = 0; j < NT; j++) F(_batch_set)(&b[j / F(_W)], j % F(_W), &s0[j]);
    for (j = 0; j < NT / F(_W); j++) {
      F(_real) h = (F(_real))(T / 1000);
      while (!bad && b[j].t[0] < T) {
        F(_real) hn = b[j].t[0] + h > T ? (F(_real))(T - b[j].t[0]) : h;
        bad |= F(_batch_step_adaptive)(&b[j], &hn, (F(_real))tol, NULL, NULL) != 0;
        h = hn;
        steps_b += F(_W);
      }
    }
    tb[r] = (now() - t) / (NT * T) * 1e9;
  }
  qsort(ts, REPS, sizeof ts[0], cmp);
  qsort(tb, REPS, sizeof tb[0], cmp);
  printf("%.1f,%.1f,%.2f,%.1f,%.1f\n", ts[REPS / 2], tb[REPS / 2], ts[REPS / 2] / tb[REPS / 2], (double)steps_s / NT,
         (double)steps_b / NT);
  if (bad) fprintf(stderr, "adaptive: a step failed\n");
  return bad;
}
