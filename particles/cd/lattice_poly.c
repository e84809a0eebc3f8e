/* SPDX-License-Identifier: MIT */
/* lattice_poly.c — Voronoi polycrystal packings ([Davydov] §2, docs/design.md §5.1).
 *
 * Grains: `ngrains` seed points uniform in the box; grain g owns the points nearer to its seed
 * than to any other (a Voronoi cell) and is filled with the close-packed lattice (fcc in 3D,
 * triangular in 2D) rotated by a uniformly random rotation (3D: random unit quaternion; 2D: random
 * angle about z) and anchored at its seed. Where two grains meet, lattice sites closer than
 * dmin·r0 to a site of another grain are removed (the later grain in seed order loses it), which
 * leaves the grain boundaries slightly porous; the residual porosity is
 * 1 − N·V_site / V_box. Deterministic for a given seed.
 *
 * Periodic axes (`periodic`, may be NULL): the Voronoi distances and the overlap test use the
 * minimum image, and a grain's lattice point is kept at its position wrapped into the box when
 * it lies within half a period of the seed (its own minimum image: no point of a grain is taken
 * twice). Without this the two faces of the box would meet with sites of different grains
 * arbitrarily close across the periodic boundary. A grain reaching half a period from its seed
 * meets its own image there: such a seam is a grain boundary too (pairs of one grain count as
 * lattice pairs only when their unwrapped separation is their minimum-image one).
 */
#include "cd.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void random_rotation(int dim, uint64_t seed, int g, double R[9]) {
  double u1 = ptl_splitmix64_uniform(seed, 3 * (uint64_t)g + 100),
         u2 = ptl_splitmix64_uniform(seed, 3 * (uint64_t)g + 101),
         u3 = ptl_splitmix64_uniform(seed, 3 * (uint64_t)g + 102);
  const double two_pi = 6.283185307179586;
  if (dim == 2) {
    double c = cos(two_pi * u1), s = sin(two_pi * u1);
    double M[9] = {c, -s, 0, s, c, 0, 0, 0, 1};
    memcpy(R, M, sizeof M);
    return;
  }
  /* Shoemake's uniform random unit quaternion */
  double a = sqrt(1 - u1), b = sqrt(u1);
  double q0 = a * sin(two_pi * u2), q1 = a * cos(two_pi * u2), q2 = b * sin(two_pi * u3),
         q3 = b * cos(two_pi * u3);
  double M[9] = {
      1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 - q0 * q3),     2 * (q1 * q3 + q0 * q2),
      2 * (q1 * q2 + q0 * q3),     1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 - q0 * q1),
      2 * (q1 * q3 - q0 * q2),     2 * (q2 * q3 + q0 * q1),     1 - 2 * (q1 * q1 + q2 * q2)};
  memcpy(R, M, sizeof M);
}

/* component a of x − y, to the nearest image along a periodic axis */
static double image_delta(double d, double L, bool per) {
  return per ? d - L * nearbyint(d / L) : d;
}

/* Overlap removal across grain boundaries: a site closer than dmin·r0 to a kept site of
 * another grain (or of its own grain across a seam) is removed, the sites taken in generation
 * (grain) order; the kept sites are packed to the front of xyz and grain. Returns their count. */
static size_t remove_overlaps(int nd, double r0, double dmin, const double lo[3],
                              const double len[3], const bool per_ax[3], size_t n, double *xyz,
                              const double *unwrapped, int32_t *grain) {
  /* cell grid of width >= dmin·r0 (a periodic axis holds a whole number of cells, so the grid
   * wraps) */
  const double w = dmin * r0;
  long nc[3] = {1, 1, 1};
  double cw[3] = {w, w, w};
  for (int a = 0; a < nd; a++) {
    nc[a] = per_ax[a] ? (long)fmax(1.0, floor(len[a] / w)) : (long)floor(len[a] / w) + 1;
    if (per_ax[a]) cw[a] = len[a] / (double)nc[a];
  }
  /* neighbour cells −1..1, fewer where a wrapped axis has under 3 cells (no cell twice) */
  long dlo[3] = {0, 0, 0}, dhi[3] = {0, 0, 0};
  for (int a = 0; a < nd; a++) {
    dlo[a] = per_ax[a] && nc[a] < 3 ? 0 : -1;
    dhi[a] = per_ax[a] && nc[a] < 3 ? nc[a] - 1 : 1;
  }
  size_t ncell = (size_t)(nc[0] * nc[1] * nc[2]);
  int32_t *head = ms_calloc(ncell, sizeof *head), *next = ms_calloc(n + 1, sizeof *next);
  for (size_t c = 0; c < ncell; c++) head[c] = -1;
  bool *dead = ms_calloc(n + 1, sizeof *dead);
  size_t kept = 0, q = 0;
  for (size_t i = 0; i < n; i++) { /* sites in generation (grain) order: earlier grains win */
    long k[3] = {0, 0, 0};
    for (int a = 0; a < nd; a++) k[a] = (long)fmin((xyz[3 * i + a] - lo[a]) / cw[a], nc[a] - 1);
    for (long dz = dlo[2]; dz <= dhi[2] && !dead[i]; dz++)
      for (long dy = dlo[1]; dy <= dhi[1] && !dead[i]; dy++)
        for (long dx = dlo[0]; dx <= dhi[0] && !dead[i]; dx++) {
          long c[3] = {k[0] + dx, k[1] + dy, k[2] + dz};
          bool outside = false;
          for (int a = 0; a < 3; a++) {
            if (per_ax[a]) c[a] = (c[a] + nc[a]) % nc[a];
            outside |= c[a] < 0 || c[a] >= nc[a];
          }
          if (outside) continue;
          for (int32_t j = head[(c[2] * nc[1] + c[1]) * nc[0] + c[0]]; j >= 0; j = next[j]) {
            double d2 = 0, seam = 0;
            for (int a = 0; a < nd; a++) {
              const double d = image_delta(xyz[3 * i + a] - xyz[3 * j + a], len[a], per_ax[a]);
              d2 += d * d;
              seam += fabs(d - (unwrapped[3 * i + a] - unwrapped[3 * j + a]));
            }
            if (grain[j] == grain[i] && seam < 1e-6 * r0) continue; /* a lattice pair */
            if (d2 < w * w) {
              dead[i] = true;
              break;
            }
          }
        }
    if (dead[i]) continue;
    size_t c = (size_t)((k[2] * nc[1] + k[1]) * nc[0] + k[0]);
    next[i] = head[c];
    head[c] = (int32_t)i;
    kept++;
  }
  for (size_t i = 0; i < n; i++)
    if (!dead[i]) {
      memmove(xyz + 3 * q, xyz + 3 * i, 3 * sizeof *xyz);
      grain[q++] = grain[i];
    }
  free(head);
  free(next);
  free(dead);
  return kept;
}

size_t cd_polycrystal(int dim, double r0, double thickness, const double lo[3], const double hi[3],
                      const bool periodic[3], int ngrains, uint64_t seed, double dmin,
                      cd_site_filter keep, void *user, double **xyz_out, int32_t **grain_out,
                      double *porosity) {
  const int nd = dim == 2 ? 2 : 3;
  bool per_ax[3] = {false, false, false};
  double len[3];
  for (int a = 0; a < 3; a++) {
    per_ax[a] = periodic && a < nd && periodic[a];
    len[a] = hi[a] - lo[a];
  }
  double *seeds = ms_calloc((size_t)3 * ngrains, sizeof *seeds);
  double vbox = 1.0;
  for (int a = 0; a < nd; a++) vbox *= hi[a] - lo[a];
  for (int g = 0; g < ngrains; g++)
    for (int a = 0; a < nd; a++)
      seeds[3 * g + a] =
          lo[a] + (hi[a] - lo[a]) * ptl_splitmix64_uniform(seed, 3 * (uint64_t)g + a);
  /* typical grain radius and the half-size of the lattice block generated around each seed */
  const double rtyp =
      dim == 2 ? sqrt(vbox / ngrains / 3.14159) : cbrt(vbox / ngrains * 0.75 / 3.14159);
  const double half = 3.0 * rtyp + 2.0 * r0;
  const double fcc[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  const double tri[2][3] = {{0, 0, 0}, {0.5, 0.5, 0}};
  const double per[3] = {dim == 2 ? r0 : sqrt(2.0) * r0, dim == 2 ? sqrt(3.0) * r0 : sqrt(2.0) * r0,
                         sqrt(2.0) * r0};
  const int nb = dim == 2 ? 2 : 4;
  size_t n = 0, cap = 1024;
  double *xyz = ms_calloc(3 * cap, sizeof *xyz), *unwrapped = ms_calloc(3 * cap, sizeof *unwrapped);
  int32_t *grain = ms_calloc(cap, sizeof *grain);
  for (int g = 0; g < ngrains; g++) {
    double R[9];
    random_rotation(dim, seed, g, R);
    long m[3];
    for (int a = 0; a < 3; a++) m[a] = a < nd ? (long)ceil(half / per[a]) + 1 : 0;
    for (long iz = -m[2]; iz <= m[2]; iz++)
      for (long iy = -m[1]; iy <= m[1]; iy++)
        for (long ix = -m[0]; ix <= m[0]; ix++)
          for (int b = 0; b < nb; b++) {
            const double *bs = dim == 2 ? tri[b] : fcc[b];
            double l[3] = {(ix + bs[0]) * per[0], (iy + bs[1]) * per[1],
                           dim == 2 ? 0.0 : (iz + bs[2]) * per[2]};
            double x[3];
            for (int a = 0; a < 3; a++)
              x[a] = seeds[3 * g + a] + R[3 * a] * l[0] + R[3 * a + 1] * l[1] + R[3 * a + 2] * l[2];
            if (dim == 2) x[2] = 0.0;
            double xu[3] = {x[0], x[1], x[2]};
            bool in = true;
            for (int a = 0; a < nd; a++) {
              if (per_ax[a]) {
                if (fabs(x[a] - seeds[3 * g + a]) >= 0.5 * len[a]) in = false; /* another image */
                x[a] -= len[a] * floor((x[a] - lo[a]) / len[a]);
                if (x[a] >= hi[a]) x[a] = lo[a]; /* rounding of the wrap */
              }
              if (x[a] < lo[a] || x[a] >= hi[a]) in = false;
            }
            if (!in) continue;
            /* Voronoi: g must be the nearest seed */
            double d2g = 0;
            for (int a = 0; a < nd; a++) {
              const double d = image_delta(x[a] - seeds[3 * g + a], len[a], per_ax[a]);
              d2g += d * d;
            }
            bool mine = true;
            for (int h = 0; h < ngrains && mine; h++) {
              if (h == g) continue;
              double d2 = 0;
              for (int a = 0; a < nd; a++) {
                const double d = image_delta(x[a] - seeds[3 * h + a], len[a], per_ax[a]);
                d2 += d * d;
              }
              if (d2 < d2g || (d2 == d2g && h < g)) mine = false;
            }
            if (!mine || (keep && !keep(user, x))) continue;
            if (n == cap) {
              cap *= 2;
              xyz = ms_realloc(xyz, 3 * cap, sizeof *xyz);
              unwrapped = ms_realloc(unwrapped, 3 * cap, sizeof *unwrapped);
              grain = ms_realloc(grain, cap, sizeof *grain);
            }
            memcpy(xyz + 3 * n, x, sizeof x);
            memcpy(unwrapped + 3 * n, xu, sizeof xu);
            grain[n++] = g;
          }
  }
  const size_t kept = remove_overlaps(nd, r0, dmin, lo, len, per_ax, n, xyz, unwrapped, grain);
  const double vsite =
      cd_cluster_volume(dim == 2 ? CD_LATTICE_TRI2D : CD_LATTICE_FCC, r0, thickness);
  *porosity = 1.0 - (double)kept * vsite / (vbox * (dim == 2 ? thickness : 1.0));
  *xyz_out = xyz;
  *grain_out = grain;
  free(seeds);
  free(unwrapped);
  return kept;
}
