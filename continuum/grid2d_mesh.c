/* SPDX-License-Identifier: MIT */
/* grid2d_mesh.c — logical-rectangle mesh builders for the 2D grid (cont2d.h). */
#include "cont2d.h"

#include <math.h>

void c2d_mesh_rect(size_t ni, size_t nj, double x0, double x1, double y0, double y1, double *x,
                   double *y) {
  for (size_t j = 0; j <= nj; ++j)
    for (size_t i = 0; i <= ni; ++i) {
      size_t n = i + (ni + 1) * j;
      x[n] = x0 + (x1 - x0) * (double)i / (double)ni;
      y[n] = y0 + (y1 - y0) * (double)j / (double)nj;
    }
}

void c2d_mesh_saltzman(size_t ni, size_t nj, double *x, double *y) {
  const double dx = 1.0 / (double)ni, dy = 0.1 / (double)nj;
  for (size_t j = 0; j <= nj; ++j)
    for (size_t i = 0; i <= ni; ++i) {
      size_t n = i + (ni + 1) * j;
      x[n] = (double)i * dx + (double)(nj - j) * dy * sin(3.14159265358979323846 * (double)i * dx);
      y[n] = (double)j * dy;
    }
}

void c2d_mesh_polar(size_t ni, size_t nj, double r0, double r1, double th0, double th1, double *x,
                    double *y) {
  for (size_t j = 0; j <= nj; ++j)
    for (size_t i = 0; i <= ni; ++i) {
      size_t n = i + (ni + 1) * j;
      double r = r0 + (r1 - r0) * (double)i / (double)ni;
      double th = th0 + (th1 - th0) * (double)j / (double)nj;
      double cs = cos(th), sn = sin(th);
      /* exact zeros on the axes (cos(π/2) ≈ 6e-17 would put an "axis" node off the axis) */
      x[n] = fabs(cs) < 1e-15 ? 0.0 : r * cs;
      y[n] = fabs(sn) < 1e-15 ? 0.0 : r * sn;
    }
}
