/* SPDX-License-Identifier: MIT */
/* Point sets for the fragment-finder tests (tests/coupling/test_fragments.c,
 * tests/mpi/test_frag_mpi.c): structure-of-arrays positions, velocities, masses, skip flags and
 * gids, and the finder's view of them. */
#ifndef MSCALE_FRAG_POINTS_H
#define MSCALE_FRAG_POINTS_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

#include "cpl.h"

typedef struct frag_points {
  size_t n;
  double *x, *y, *z, *vx, *vy, *vz, *m;
  uint8_t *skip;
  int64_t *gid;
} frag_points;

/* n zeroed points (at least one element allocated), gid[i] = i. */
static inline void frag_points_alloc(frag_points *c, size_t n) {
  const size_t k = n ? n : 1;
  c->n = n;
  c->x = ms_calloc(k, sizeof(double));
  c->y = ms_calloc(k, sizeof(double));
  c->z = ms_calloc(k, sizeof(double));
  c->vx = ms_calloc(k, sizeof(double));
  c->vy = ms_calloc(k, sizeof(double));
  c->vz = ms_calloc(k, sizeof(double));
  c->m = ms_calloc(k, sizeof(double));
  c->skip = ms_calloc(k, 1);
  c->gid = ms_calloc(k, sizeof(int64_t));
  for (size_t i = 0; i < n; i++) c->gid[i] = (int64_t)i;
}

static inline void frag_points_free(frag_points *c) {
  free(c->x);
  free(c->y);
  free(c->z);
  free(c->vx);
  free(c->vy);
  free(c->vz);
  free(c->m);
  free(c->skip);
  free(c->gid);
}

/* The finder's view: skip flags, z and gids only when asked for (NULL: none, 2D, index order). */
static inline cpl_particles frag_points_view(const frag_points *c, bool use_skip, bool use_z,
                                             bool use_gid) {
  cpl_particles p = {c->n,  c->x,  c->y, use_z ? c->z : NULL,       c->vx,
                     c->vy, c->vz, c->m, use_skip ? c->skip : NULL, use_gid ? c->gid : NULL};
  return p;
}

/* Minimum image of a coordinate difference on an axis of period `period` (0: open). */
static inline double frag_min_image(double d, double period) {
  return period > 0 ? d - period * nearbyint(d / period) : d;
}

#endif
