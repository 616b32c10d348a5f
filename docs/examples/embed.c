/* embed.c - a generated solver in a C program (docs/embedding.md).
 *   hbvmgen -o out models/pendulum.ham
 *   cc -O2 -std=c99 -Iout embed.c out/pendulum.c -lm */
#include <math.h>
#include <stdio.h>

#include "pendulum.h"

int main(void)
{
  pendulum_state x;
  pendulum_stats st = {0};
  double h = 0.01, H0, g[pendulum_NU];
  int n, rc;

  pendulum_init(&x, NULL, NULL);             /* the model's q0 and p0 */
  H0 = pendulum_energy(&x, NULL);            /* NULL params: the defaults */
  for (n = 0; n < 1000; n++) {
    rc = pendulum_step(&x, h, NULL, &st);
    if (rc != pendulum_OK) {                 /* x is unchanged: retry smaller */
      fprintf(stderr, "t=%g: %s\n", x.t, pendulum_strerror(rc));
      return 1;
    }
  }
  pendulum_constraints(&x, NULL, g);
  printf("t=%.6f x=%.9f y=%.9f dH=%.1e g=%.1e iters=%d\n", x.t, x.q[0], x.q[1],
         fabs(pendulum_energy(&x, NULL) - H0), fabs(g[0]), st.iters);
  return 0;
}
