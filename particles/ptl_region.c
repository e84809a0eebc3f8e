/* SPDX-License-Identifier: MIT */
/* ptl_region.c — the public calls of ptl_region.h, dispatched to the region's model. */
#include "ptl_region_impl.h"

#include <stdlib.h>

ptl_region_params *ptl_region_params_read(const ptl_region_model *m, dk_doc *doc,
                                          const dk_node *section, dk_errors *e) {
  ptl_region_params *pp = m->read(doc, section, e);
  if (pp) pp->model = m;
  return pp;
}
void ptl_region_params_destroy(ptl_region_params **pp) {
  if (!pp || !*pp) return;
  (*pp)->model->params_destroy(*pp);
  *pp = NULL;
}
const char *ptl_region_params_notes(const ptl_region_params *pp) { return pp->model->notes(pp); }
ptl_region_estimate ptl_region_params_estimate(const ptl_region_params *pp, double depth) {
  return pp->model->estimate(pp, depth);
}

ms_status ptl_region_create(const ptl_region_params *pp, const ms_ctx *ctx, const eos_t *sample,
                            double x_drive, double depth, ptl_region **out) {
  *out = NULL;
  ms_status st = pp->model->create(pp, ctx, sample, x_drive, depth, out);
  if (st == MS_OK) (*out)->model = pp->model;
  return st;
}
void ptl_region_destroy(ptl_region **r) {
  if (!r || !*r) return;
  (*r)->model->destroy(*r);
  *r = NULL;
}

ptl_region_geometry ptl_region_get_geometry(const ptl_region *r) { return r->model->geometry(r); }
ptl_state *ptl_region_state(ptl_region *r) { return r->model->state(r); }
double ptl_region_time(const ptl_region *r) { return r->model->time(r); }
void ptl_region_set_piston(ptl_region *r, size_t n, const double *t, const double *u,
                           const double dir[3]) {
  r->model->set_piston(r, n, t, u, dir);
}
void ptl_region_hold_piston(ptl_region *r, double u, double span) {
  r->model->hold_piston(r, u, span);
}
ms_status ptl_region_set_piston_columns(ptl_region *r, size_t ncol, const double *ycol, size_t n,
                                        const double *t, const double *ux, const double *uy) {
  if (!r->model->set_piston_columns) return MS_ERR_INPUT;
  return r->model->set_piston_columns(r, ncol, ycol, n, t, ux, uy);
}
void ptl_region_set_dt(ptl_region *r, double dt) { r->model->set_dt(r, dt); }
void ptl_region_distribute(ptl_region *r, const ms_ctx *ctx) { r->model->distribute(r, ctx); }
ms_status ptl_region_init(ptl_region *r) { return r->model->init(r); }
ms_status ptl_region_step(ptl_region *r) { return r->model->step(r); }
const char *ptl_region_error(const ptl_region *r) { return r->model->error(r); }
double ptl_region_driven_force(const ptl_region *r) { return r->model->driven_force(r); }
double ptl_region_free_surface_velocity(const ptl_region *r) {
  return r->model->free_surface_velocity(r);
}
void ptl_region_energy_get(ptl_region *r, ptl_region_energy *out) { r->model->energy(r, out); }
void ptl_region_refresh_ghosts(ptl_region *r) { r->model->refresh_ghosts(r); }
void ptl_region_ghost_owners(const ptl_region *r, int32_t *owner) {
  r->model->ghost_owners(r, owner);
}
ms_status ptl_region_write_snapshot(ptl_region *r, const char *path, const char *material) {
  return r->model->write_snapshot(r, path, material);
}
bool ptl_region_failures(const ptl_region *r, long count[3]) {
  count[0] = count[1] = count[2] = 0;
  return r->model->failures && r->model->failures(r, count);
}
bool ptl_region_links(ptl_region *r, const size_t **start, const int32_t **nbr) {
  if (r->model->links) return r->model->links(r, start, nbr);
  *start = NULL, *nbr = NULL;
  return false;
}
ms_status ptl_region_refresh(ptl_region *r) { return r->model->refresh(r); }
ms_status ptl_region_checkpoint_write(const ptl_region *r, ms_h5 *h, const ms_ctx *ctx) {
  return r->model->checkpoint_write(r, h, ctx);
}
ms_status ptl_region_restore(ptl_region *r, ms_h5r *h, const ms_ctx *ctx, long *step,
                             dk_errors *e) {
  return r->model->restore(r, h, ctx, step, e);
}
