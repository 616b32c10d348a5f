/* dihedral.h - the dihedral angle of four points, used by the stiff suite
 * (tests/check_stiff.c) and the stiff benchmark (bench/stiff.c) as the slow
 * motion of models/butane.ham. Header-only: both include it. */
#ifndef HBVM_TESTS_DIHEDRAL_H
#define HBVM_TESTS_DIHEDRAL_H

#include <math.h>

/* The dihedral angle of r1..r4 (q = r1, r2, r3, r4 in R^3): atan2 of the
 * normals of the planes (r1, r2, r3) and (r2, r3, r4). */
static double dihedral(const double *q) {
  double b[3][3], n1[3], n2[3], m1[3];
  for (int j = 0; j < 3; j++)
    for (int c = 0; c < 3; c++) b[j][c] = q[3 * (j + 1) + c] - q[3 * j + c];
#define DIHEDRAL_CROSS(o, u, v) \
  (o[0] = u[1] * v[2] - u[2] * v[1], o[1] = u[2] * v[0] - u[0] * v[2], o[2] = u[0] * v[1] - u[1] * v[0])
  DIHEDRAL_CROSS(n1, b[0], b[1]);
  DIHEDRAL_CROSS(n2, b[1], b[2]);
  DIHEDRAL_CROSS(m1, n1, b[1]);
#undef DIHEDRAL_CROSS
  double len = sqrt(b[1][0] * b[1][0] + b[1][1] * b[1][1] + b[1][2] * b[1][2]);
  double x = n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2], y = (m1[0] * n2[0] + m1[1] * n2[1] + m1[2] * n2[2]) / len;
  return atan2(y, x);
}

#endif
