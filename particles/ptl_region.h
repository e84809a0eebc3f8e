/* SPDX-License-Identifier: MIT */
/* ptl_region.h — the particle-region interface (docs/design.md §6, docs/developing.md "The
 * particle-region interface"): what the coupling needs from a particle model, and nothing of
 * its internals. A region is a slab of the sample between a driven face at x_drive and a free
 * surface depth beyond it, periodic across (y, z), with a layer of driven (piston) particles at
 * x_drive. The coupled problem reads the model's deck section, builds the region, drives its
 * piston, advances it, asks for the driven layer's force and the free-surface velocity, finds
 * fragments in its particle state, and checkpoints it, all through the calls below.
 *
 * Cluster dynamics (particles/cd/cd_region.c) and the finite-deformation discrete model
 * (particles/dm/dm_region.c) implement it; ptl_region_model_find (in the mscale_regions
 * library, particles/regions.c) names the implementations by their deck name.
 * Units are internal (docs/design.md §2): g, cm, 10 µs, km/s, kJ. */
#ifndef MSCALE_PTL_REGION_H
#define MSCALE_PTL_REGION_H

#include "ptl.h"

typedef struct ptl_region ptl_region;               /* a built region (opaque) */
typedef struct ptl_region_params ptl_region_params; /* a model's deck section, read (opaque) */
typedef struct ptl_region_model ptl_region_model;   /* an implementation (opaque) */

/* The model whose deck name is `name` ("cluster_dynamics", "discrete_model"); NULL if there is
 * none. */
const ptl_region_model *ptl_region_model_find(const char *name);
/* The known names, NULL-terminated (for the deck's enum and its messages). */
extern const char *const ptl_region_model_names[];

/* Read the model's section (every problem a located deck error, e the list). NULL on errors. */
ptl_region_params *ptl_region_params_read(const ptl_region_model *m, dk_doc *doc,
                                          const dk_node *section, dk_errors *e);
void ptl_region_params_destroy(ptl_region_params **pp);
/* Notes the reader collected for the log (deprecated key names), one per line; "" if none. */
const char *ptl_region_params_notes(const ptl_region_params *pp);
/* Check-time memory estimate of a region `depth` long: particles and bytes per particle, and
 * the deck node to point at if it is too large. */
typedef struct ptl_region_estimate {
  double particles, bytes_per_particle;
  const dk_node *at;
} ptl_region_estimate;
ptl_region_estimate ptl_region_params_estimate(const ptl_region_params *pp, double depth);

/* What a built region is. */
typedef struct ptl_region_geometry {
  int dim;              /* 2 (plane strain) or 3 */
  double spacing;       /* lattice spacing a, cm */
  double rho0, c0;      /* the sample's reference density (g/cm³) and bulk sound speed (km/s) */
  double x_drive;       /* driven face, cm */
  double x_top;         /* nominal free surface of the lattice, cm */
  double surface_depth; /* peak-to-valley depth of a profiled free surface (0: flat), cm */
  double period[3];     /* periodic extents ([0] = 0: the drive axis is open), cm */
  double area;          /* cross-section that the grid's per-cm² quantities stand for, cm² */
  double dt;            /* the model's own time step, 10 µs */
  size_t particles;     /* in the whole region (all ranks) */
} ptl_region_geometry;

/* The energy terms of the region (kJ), as the checkpoint stores them (the same order). */
typedef struct ptl_region_energy {
  double kinetic, potential, dissipated, broken, piston_work, wall_work, total, momentum[3];
} ptl_region_energy;

/* Build the region of `sample` between x_drive and x_drive + depth (every rank builds the
 * whole region; ptl_region_distribute then keeps each rank's share). Logs what it built. */
ms_status ptl_region_create(const ptl_region_params *pp, const ms_ctx *ctx, const eos_t *sample,
                            double x_drive, double depth, ptl_region **out);
void ptl_region_destroy(ptl_region **r);

ptl_region_geometry ptl_region_get_geometry(const ptl_region *r);
/* The particles: [0, nlocal) owned, then ghosts (after ptl_region_refresh_ghosts). The pointer
 * changes on restore. Velocities may be changed between steps (drag kicks). */
ptl_state *ptl_region_state(ptl_region *r);
double ptl_region_time(const ptl_region *r); /* the region's clock, from 0 */

/* Piston: every driven particle moves with u(t)·dir, u piecewise linear through (t_k, u_k) on
 * the region's clock, constant beyond the ends (arrays copied). */
void ptl_region_set_piston(ptl_region *r, size_t n, const double *t, const double *u,
                           const double dir[3]);
/* Piston velocity u over the next `span` of the region's clock (a transmitting or two-way
 * piston, set before each step or sub-cycle). */
void ptl_region_hold_piston(ptl_region *r, double u, double span);
/* Piston by columns (a 2D drive along a grid's node line, one-way): column c at transverse
 * position ycol[c] (along period[1]; strictly increasing) moves with velocity (ux_c, uy_c)(t)
 * along the region's (x, y) — uy NULL: along x only —, each piecewise linear through
 * (t[k], ux[k·ncol + c]) on the region's clock (row k = time k, the layout of a tagged grid
 * line's history), constant beyond the ends. A driven particle at reference y takes the linear
 * interpolation between the two columns around it (the nearest column's beyond the ends); over
 * each step it moves with the step's mean, so it follows the interpolated displacement exactly.
 * Replaces the piston until the next set_piston or hold_piston (arrays copied). MS_ERR_INPUT
 * for bad arrays, or if the model has none (cluster dynamics keeps the single piston). */
ms_status ptl_region_set_piston_columns(ptl_region *r, size_t ncol, const double *ycol, size_t n,
                                        const double *t, const double *ux, const double *uy);
void ptl_region_set_dt(ptl_region *r, double dt); /* sub-cycling a grid step */

/* MPI: keep each rank's share (the model's default decomposition). Serial: nothing. */
void ptl_region_distribute(ptl_region *r, const ms_ctx *ctx);
ms_status ptl_region_init(ptl_region *r); /* forces at t = 0 (not after a restore) */
ms_status ptl_region_step(ptl_region *r); /* one step; MPI: the same status on every rank */
const char *ptl_region_error(const ptl_region *r); /* the guard's finding after MS_ERR_UNSTABLE */

/* Σ f·x̂ over this rank's driven particles (the piston layer's force, this rank's share). */
double ptl_region_driven_force(const ptl_region *r);
/* Mean velocity along x of the free-surface layer (all ranks). */
double ptl_region_free_surface_velocity(const ptl_region *r);
void ptl_region_energy_get(ptl_region *r, ptl_region_energy *out);

/* Fragment search on MPI ranks: ghost copies within the model's reach, and their owner ranks
 * (owner[j] for particle nlocal + j). */
void ptl_region_refresh_ghosts(ptl_region *r);
void ptl_region_ghost_owners(const ptl_region *r, int32_t *owner);

/* The model's own connectivity for the fragments, if it has one: a CSR list over the view's
 * particles [0, n), the particles linked to i being nbr[start[i] .. start[i + 1]) (view
 * indices), valid until the next step; fragments are then its connected components. false
 * (*start = *nbr = NULL) if the model has none: the coupling's distance criterion
 * |r_i − r_k| ≤ b·a (cluster dynamics). The discrete model links the unbroken bonds. */
bool ptl_region_links(ptl_region *r, const size_t **start, const int32_t **nbr);

/* Particles failed so far in this process (not carried by checkpoints), by cause: the
 * material's criterion, isolated (too few intact family members), degenerate F — the discrete
 * model's fracture (docs/particles-dm.md "Fracture"). false (counts 0) if the model has none. */
bool ptl_region_failures(const ptl_region *r, long count[3]);

/* The model's own HDF5 snapshot of its state (a run that went unstable), in the layout of every
 * particle snapshot (ptl.h); `material` names the sample's material (material 0) for the
 * snapshot's material_names (NULL: none). */
ms_status ptl_region_write_snapshot(ptl_region *r, const char *path, const char *material);
/* Checkpoint: bring the state to what a restore reproduces (before writing), write it into the
 * open checkpoint h, and restore from one (replacing the particles; *step: the region's step). */
ms_status ptl_region_refresh(ptl_region *r);
ms_status ptl_region_checkpoint_write(const ptl_region *r, ms_h5 *h, const ms_ctx *ctx);
ms_status ptl_region_restore(ptl_region *r, ms_h5r *h, const ms_ctx *ctx, long *step, dk_errors *e);

#endif /* MSCALE_PTL_REGION_H */
