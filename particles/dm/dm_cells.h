/* SPDX-License-Identifier: MIT */
/* dm_cells.h — the hashed cell list of the discrete model's neighbour searches (dm_cells.c;
 * docs/particles-dm.md "Contact"): the short-range contact (dm_contact.c), the impact's contact
 * between bodies (dm_impact_contact.c) and the families' merge (dm_fin_local.c). Internal: reached
 * through dm_impl.h. */
#ifndef MSCALE_DM_CELLS_H
#define MSCALE_DM_CELLS_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core.h"

/* A cell list hashed into ≥ 2n + 1 buckets (a power of two; [Teschner2003]), cells of `size` (along a periodic
 * axis of box[a] > 0 a whole number ≥ 3 of them, no smaller), reach[a] = 1 along the dim axes.
 * dm_cells_init: MS_ERR_INPUT when a periodic box holds fewer than 3 cells (nothing allocated);
 * dm_cells_build: each particle's cell and the lists at x = X + w (serial, O(n)); when the
 * cells' bounding box has no more cells than buckets, the buckets are the cells themselves in
 * x-fastest order (memory locality: the hash scatters neighbouring cells over the table), else
 * hashed. Either way a bucket's list is walked for one cell's particles (dropping others'), in
 * the same order, so the candidates and their order do not depend on the mode. */
typedef struct dm_cells {
  double size[3], lo[3], box[3];
  long nper[3], reach[3];
  size_t nbucket, n;
  int dense;            /* the cells' bounding box fits the buckets: one bucket per cell */
  long base[3], ext[3]; /* that box (the last build's) */
  long *head, *next; /* the lists: first particle of a bucket, next particle of the same bucket */
  long *cidx;        /* [n][3] each particle's cell */
  bool periodic;     /* some nper[a] > 0 */
  long near[27][3];  /* the offsets of the cells a walk visits, in its order */
  int nnear;
} dm_cells;
ms_status dm_cells_init(dm_cells *c, size_t n, int dim, double size, const double lo[3],
                        const double box[3]);
void dm_cells_free(dm_cells *c);
void dm_cells_build(dm_cells *c, const double *X, const double *w);
static inline size_t dm_cells_bucket(const dm_cells *c, const long idx[3]) {
  if (c->dense) { /* neighbouring cells in neighbouring buckets; outside: the empty last one */
    const long i = idx[0] - c->base[0], j = idx[1] - c->base[1], k = idx[2] - c->base[2];
    if (i < 0 || j < 0 || k < 0 || i >= c->ext[0] || j >= c->ext[1] || k >= c->ext[2])
      return c->nbucket;
    return (size_t)((k * c->ext[1] + j) * c->ext[0] + i);
  }
  const uint64_t hsh = ((uint64_t)idx[0] * 73856093u) ^ ((uint64_t)idx[1] * 19349663u) ^
                       ((uint64_t)idx[2] * 83492791u);
  return (size_t)(hsh & (c->nbucket - 1)); /* nbucket: a power of two */
}
/* A cell index taken back into the box along periodic axes. */
static inline void dm_cells_wrap(const dm_cells *c, long idx[3]) {
  for (int a = 0; a < 3; ++a)
    if (c->nper[a] > 0) idx[a] = ((idx[a] % c->nper[a]) + c->nper[a]) % c->nper[a];
}
static inline void dm_cells_of(const dm_cells *c, const double x[3], long idx[3]) {
  for (int a = 0; a < 3; ++a) idx[a] = (long)floor((x[a] - c->lo[a]) / c->size[a]);
  dm_cells_wrap(c, idx);
}

/* The walk over the particles of the cells around cell `at`: the cells at the offsets
 * c->near[q], q < c->nnear (−reach … reach along each axis, x fastest, then y, then z; set by
 * dm_cells_init), wrapped along periodic axes (dm_cells_near); in each the list of its bucket
 * (dm_cells_list, then c->next[j]; −1 after the last), of which only the cell's own particles
 * count (dm_cells_holds: others may share a hashed bucket). That order is the order a pass sums
 * its pairs in, so every pass that walks this way keeps its bits. The particle whose cell is
 * `at` is among those walked: the caller drops it (and whatever else it does not pair; its
 * cheaper tests may come first, dm_cells_holds loads the cell indices).
 *   for (int q = 0; q < cells->nnear; ++q) {
 *     long cell[3];
 *     dm_cells_near(cells, at, q, cell);
 *     for (long j = dm_cells_list(cells, cell); j >= 0; j = cells->next[j])
 *       if (dm_cells_holds(cells, j, cell)) ...
 *   }
 * `at` is wrapped (as dm_cells_of gives it), so a neighbour is one step out at most. (A table of offsets rather than three
 * nested loops over ±reach: the impact's contact pass took 30 % longer than with its own
 * constant loops with the loops in a macro, 5 % with the table.) */
static inline void dm_cells_near(const dm_cells *c, const long at[3], int q, long cell[3]) {
  cell[0] = at[0] + c->near[q][0], cell[1] = at[1] + c->near[q][1], cell[2] = at[2] + c->near[q][2];
  if (c->periodic) /* at in [0, nper), one step out at most: dm_cells_wrap without its % */
    for (int a = 0; a < 3; ++a)
      if (c->nper[a] > 0)
        cell[a] += cell[a] < 0 ? c->nper[a] : cell[a] >= c->nper[a] ? -c->nper[a] : 0;
}
static inline long dm_cells_list(const dm_cells *c, const long cell[3]) {
  return c->head[dm_cells_bucket(c, cell)];
}
/* Is particle j (of the list of `cell`) in that cell? */
static inline bool dm_cells_holds(const dm_cells *c, long j, const long cell[3]) {
  const long *cj = &c->cidx[3 * j];
  return cj[0] == cell[0] && cj[1] == cell[1] && cj[2] == cell[2];
}

#endif
