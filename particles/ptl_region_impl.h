/* SPDX-License-Identifier: MIT */
/* ptl_region_impl.h — for the implementations of ptl_region.h only (cd_region.c): the model's
 * table of functions, and the first member of a region and of its parameters. ptl_region.c
 * dispatches the public calls through it. */
#ifndef MSCALE_PTL_REGION_IMPL_H
#define MSCALE_PTL_REGION_IMPL_H

#include "ptl_region.h"

struct ptl_region_params {
  const ptl_region_model *model;
};
struct ptl_region {
  const ptl_region_model *model;
};

struct ptl_region_model {
  const char *name;
  ptl_region_params *(*read)(dk_doc *doc, const dk_node *section, dk_errors *e);
  void (*params_destroy)(ptl_region_params *pp);
  const char *(*notes)(const ptl_region_params *pp);
  ptl_region_estimate (*estimate)(const ptl_region_params *pp, double depth);
  ms_status (*create)(const ptl_region_params *pp, const ms_ctx *ctx, const eos_t *sample,
                      double x_drive, double depth, ptl_region **out);
  void (*destroy)(ptl_region *r);
  ptl_region_geometry (*geometry)(const ptl_region *r);
  ptl_state *(*state)(ptl_region *r);
  double (*time)(const ptl_region *r);
  void (*set_piston)(ptl_region *r, size_t n, const double *t, const double *u,
                     const double dir[3]);
  void (*hold_piston)(ptl_region *r, double u, double span);
  /* NULL: the model has no piston by columns (ptl_region_set_piston_columns refuses) */
  ms_status (*set_piston_columns)(ptl_region *r, size_t ncol, const double *ycol, size_t n,
                                  const double *t, const double *ux, const double *uy);
  void (*set_dt)(ptl_region *r, double dt);
  void (*distribute)(ptl_region *r, const ms_ctx *ctx);
  ms_status (*init)(ptl_region *r);
  ms_status (*step)(ptl_region *r);
  const char *(*error)(const ptl_region *r);
  double (*driven_force)(const ptl_region *r);
  double (*free_surface_velocity)(const ptl_region *r);
  void (*energy)(ptl_region *r, ptl_region_energy *out);
  void (*refresh_ghosts)(ptl_region *r);
  void (*ghost_owners)(const ptl_region *r, int32_t *owner);
  /* optional (NULL: the coupling's distance criterion): ptl_region_links */
  bool (*links)(ptl_region *r, const size_t **start, const int32_t **nbr);
  /* optional (NULL: the model has no fracture): ptl_region_failures */
  bool (*failures)(const ptl_region *r, long count[3]);
  ms_status (*write_snapshot)(ptl_region *r, const char *path, const char *material);
  ms_status (*refresh)(ptl_region *r);
  ms_status (*checkpoint_write)(const ptl_region *r, ms_h5 *h, const ms_ctx *ctx);
  ms_status (*restore)(ptl_region *r, ms_h5r *h, const ms_ctx *ctx, long *step, dk_errors *e);
};

#endif
