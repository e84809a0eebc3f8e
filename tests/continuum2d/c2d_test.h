/* SPDX-License-Identifier: MIT */
/* Shared helpers of the 2D-grid tests (tests/continuum2d). */
#ifndef C2D_TEST_H
#define C2D_TEST_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "cont2d.h"

/* A mesh and uniform-material zone arrays owned by the test. */
typedef struct c2d_fixture {
  size_t ni, nj;
  double *x, *y, *u, *v, *rho, *e;
  const eos_t **eos;
} c2d_fixture;

static inline void fixture_init(c2d_fixture *f, size_t ni, size_t nj, const eos_t *eos) {
  size_t nn = (ni + 1) * (nj + 1), nz = ni * nj;
  f->ni = ni;
  f->nj = nj;
  f->x = calloc(nn, sizeof(double));
  f->y = calloc(nn, sizeof(double));
  f->u = calloc(nn, sizeof(double));
  f->v = calloc(nn, sizeof(double));
  f->rho = calloc(nz, sizeof(double));
  f->e = calloc(nz, sizeof(double));
  f->eos = calloc(nz, sizeof(eos_t *));
  for (size_t z = 0; z < nz; ++z) f->eos[z] = eos;
}

static inline void fixture_free(c2d_fixture *f) {
  free(f->x);
  free(f->y);
  free(f->u);
  free(f->v);
  free(f->rho);
  free(f->e);
  free(f->eos);
}

static inline void fixture_setup(const c2d_fixture *f, c2d_setup *s) {
  s->ni = f->ni;
  s->nj = f->nj;
  s->x = f->x;
  s->y = f->y;
  s->u = f->u;
  s->v = f->v;
  s->rho = f->rho;
  s->e = f->e;
  s->eos = f->eos;
}

/* Relative drift of internal + kinetic − boundary work against the initial total (or `scale`
 * if larger, for runs that start with nothing). */
static inline double energy_drift(const c2d_grid *g, double e0, double scale) {
  c2d_balance b = c2d_grid_balance(g);
  double tot = b.internal + b.kinetic - b.work;
  double ref = fabs(e0) > scale ? fabs(e0) : scale;
  return fabs(tot - e0) / ref;
}

static inline double energy_total(const c2d_grid *g) {
  c2d_balance b = c2d_grid_balance(g);
  return b.internal + b.kinetic - b.work;
}

#endif
