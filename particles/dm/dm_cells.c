/* SPDX-License-Identifier: MIT */
/* dm_cells.c — the hashed cell list (dm_cells.h; docs/particles-dm.md "Contact"): cells of a
 * given size, hashed into 2n + 1 or more buckets (a power of two) ([Teschner2003]: memory O(n)
 * however far the particles fly; two cells sharing a bucket only add candidates, which the
 * cell-index test drops), periodic axes wrapped (a whole number of cells along the box), rebuilt
 * at every force evaluation into arrays allocated once. */
#include "dm_impl.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

ms_status dm_cells_init(dm_cells *c, size_t n, int dim, double size, const double lo[3],
                        const double box[3]) {
  memset(c, 0, sizeof *c);
  for (int a = 0; a < 3; ++a) {
    c->lo[a] = lo ? lo[a] : 0.0;
    c->size[a] = size, c->reach[a] = a < dim ? 1 : 0;
    c->box[a] = box ? box[a] : 0.0;
    if (c->box[a] > 0 && a < dim) { /* a whole number of cells, at least 3, none below size */
      c->nper[a] = (long)floor(c->box[a] / size);
      if (c->nper[a] < 3) return MS_ERR_INPUT;
      c->size[a] = c->box[a] / (double)c->nper[a];
      c->periodic = true;
    }
  }
  for (long dz = -c->reach[2]; dz <= c->reach[2]; ++dz) /* the walk's order: x fastest */
    for (long dy = -c->reach[1]; dy <= c->reach[1]; ++dy)
      for (long dx = -c->reach[0]; dx <= c->reach[0]; ++dx, ++c->nnear)
        c->near[c->nnear][0] = dx, c->near[c->nnear][1] = dy, c->near[c->nnear][2] = dz;
  c->n = n, c->nbucket = 1; /* a power of two ≥ 2n + 1: the bucket is a mask, not a division */
  while (c->nbucket < 2 * n + 1) c->nbucket *= 2;
  c->head = ms_calloc(c->nbucket + 1, sizeof(long)); /* + the always empty one */
  c->next = ms_calloc(n ? n : 1, sizeof(long));
  c->cidx = ms_calloc(3 * (n ? n : 1), sizeof(long));
  return MS_OK;
}

void dm_cells_free(dm_cells *c) {
  free(c->head), free(c->next), free(c->cidx);
  memset(c, 0, sizeof *c);
}

void dm_cells_build(dm_cells *c, const double *X, const double *w) {
  for (size_t q = 0; q <= c->nbucket; ++q) c->head[q] = -1;
  long lo[3] = {LONG_MAX, LONG_MAX, LONG_MAX}, hi[3] = {LONG_MIN, LONG_MIN, LONG_MIN};
  for (size_t i = 0; i < c->n; ++i) {
    double x[3];
    for (int a = 0; a < 3; ++a) x[a] = X[3 * i + a] + w[3 * i + a];
    long *idx = &c->cidx[3 * i];
    dm_cells_of(c, x, idx);
    for (int a = 0; a < 3; ++a)
      lo[a] = idx[a] < lo[a] ? idx[a] : lo[a], hi[a] = idx[a] > hi[a] ? idx[a] : hi[a];
  }
  double cells = 1.0;
  for (int a = 0; a < 3; ++a) {
    c->base[a] = c->n ? lo[a] : 0, c->ext[a] = c->n ? hi[a] - lo[a] + 1 : 1;
    cells *= (double)c->ext[a];
  }
  c->dense = cells <= (double)c->nbucket;
  for (size_t i = 0; i < c->n; ++i) { /* serial: the lists' order is thread-count independent */
    const size_t q = dm_cells_bucket(c, &c->cidx[3 * i]);
    c->next[i] = c->head[q], c->head[q] = (long)i;
  }
}
