/* SPDX-License-Identifier: MIT */
/* drive2d.c — a 2D particle region driven along a 2D grid's tagged node line, one piston column
 * per node (cpl.h, docs/coupling.md "Driving particles from a 2D node line"). The grid through
 * cont2d.h, the particles through ptl_region.h. */
#include "cont2d.h"
#include "cpl_impl.h"
#include "ptl_region.h"

#include <stdlib.h>

typedef struct column {
  double y;
  size_t node; /* index in the line */
  double sign; /* −1 on the mirrored side */
} column;

static int by_y(const void *a, const void *b) {
  const double ya = ((const column *)a)->y, yb = ((const column *)b)->y;
  return (ya > yb) - (ya < yb);
}

ms_status cpl_drive_from_line(struct ptl_region *r, const struct c2d_line_history *h,
                              const cpl_line_drive *d) {
  if (!h || h->n < 2 || h->nnodes < 1) return MS_ERR_INPUT;
  const size_t nl = h->nnodes;
  column *col = ms_calloc(2 * nl, sizeof *col);
  size_t nc = 0;
  for (size_t q = 0; q < nl; q++) {
    const double s = h->x[q] * d->across[0] + h->y[q] * d->across[1]; /* record 0: initial */
    col[nc++] = (column){d->y0 + s, q, 1.0};
    if (d->mirror && s != 0.0) col[nc++] = (column){d->y0 - s, q, -1.0};
  }
  qsort(col, nc, sizeof *col, by_y);
  size_t k0 = 0; /* the last record before t0, then all after */
  while (k0 + 1 < h->n && h->t[k0 + 1] <= d->t0) k0++;
  const size_t n = h->n - k0;
  double *t = ms_calloc(n, sizeof *t), *u = ms_calloc(n * nc, sizeof *u);
  double *w = ms_calloc(n * nc, sizeof *w);
  double *y = ms_calloc(nc, sizeof *y);
  for (size_t c = 0; c < nc; c++) y[c] = col[c].y;
  for (size_t k = 0; k < n; k++) {
    const size_t rec = k0 + k;
    t[k] = h->t[rec] - d->t0;
    for (size_t c = 0; c < nc; c++) {
      const size_t at = rec * nl + col[c].node;
      u[k * nc + c] = h->u[at] * d->dir[0] + h->v[at] * d->dir[1];
      /* across the line: y = y0 ± s, so the mirrored column moves the other way */
      w[k * nc + c] = col[c].sign * (h->u[at] * d->across[0] + h->v[at] * d->across[1]);
    }
  }
  const ms_status st = ptl_region_set_piston_columns(r, nc, y, n, t, u, d->lateral ? w : NULL);
  free(col), free(t), free(u), free(w), free(y);
  return st;
}
