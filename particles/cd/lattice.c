/* SPDX-License-Identifier: MIT */
/* lattice.c — perfect close-packed lattices (fcc in 3D, triangular in 2D). */
#include "cd.h"

#include <math.h>

size_t cd_lattice_fcc(ptl_state *s, int nx, int ny, int nz, const double shift[3],
                      const double origin[3], double r0, double mass, int mat) {
  static const double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  const double a = sqrt(2.0) * r0;
  size_t added = 0;
  for (int iz = 0; iz < nz; iz++)
    for (int iy = 0; iy < ny; iy++)
      for (int ix = 0; ix < nx; ix++)
        for (int b = 0; b < 4; b++) {
          double x = (ix + basis[b][0] + shift[0]) * a + origin[0];
          double y = (iy + basis[b][1] + shift[1]) * a + origin[1];
          double z = (iz + basis[b][2] + shift[2]) * a + origin[2];
          if (ptl_state_add(s, x, y, z, mass, mat) == (size_t)-1) return added;
          added++;
        }
  return added;
}

size_t cd_lattice_tri(ptl_state *s, int nx, int ny, const double shift[2], const double origin[2],
                      double r0, double mass, int mat) {
  /* rectangular cell r0 × √3 r0 with basis (0,0), (½, √3/2)·r0 */
  const double hy = sqrt(3.0) * r0;
  size_t added = 0;
  for (int iy = 0; iy < ny; iy++)
    for (int ix = 0; ix < nx; ix++)
      for (int b = 0; b < 2; b++) {
        double x = (ix + 0.5 * b + shift[0]) * r0 + origin[0];
        double y = (iy + 0.5 * b + shift[1]) * hy + origin[1];
        if (ptl_state_add(s, x, y, 0.0, mass, mat) == (size_t)-1) return added;
        added++;
      }
  return added;
}
