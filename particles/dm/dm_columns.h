/* SPDX-License-Identifier: MIT */
/* dm_columns.h — private to the discrete model's region (dm_region.c, dm_columns.c): the piston by
 * columns of ptl_region_set_piston_columns (a 2D drive along a grid's node line). */
#ifndef MSCALE_DM_COLUMNS_H
#define MSCALE_DM_COLUMNS_H

#include "dm.h"

typedef struct dm_columns dm_columns;

/* Column c at transverse position ycol[c] (strictly increasing) moves with velocity
 * (ux_c(t), uy_c(t)) along the region's (x, y) (uy NULL: 0), each piecewise linear through
 * (t[k], ux[k·ncol + c]) on the region's clock, constant beyond the ends. Every prescribed particle i of s (bc DM_PRESCRIBED) gets the columns around its
 * reference y = X[3i+1] and its weight (linear in y; the nearest column's beyond the ends).
 * MS_ERR_INPUT (*out NULL) for bad arrays (n or ncol 0, times not increasing, non-finite). */
ms_status dm_columns_create(size_t ncol, const double *ycol, size_t n, const double *t,
                            const double *ux, const double *uy, const dm_state *s,
                            dm_columns **out);
void dm_columns_destroy(dm_columns **c); /* NULL-safe */
/* The prescribed particles' velocities for the step [a, b]: each column's mean velocity over it
 * (so the driven layer moves by exactly the history's displacement, as the single piston), at
 * the particle's y by the weights; no allocation. */
void dm_columns_drive(dm_columns *c, double a, double b, dm_state *s);

#endif
