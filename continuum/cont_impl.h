/* SPDX-License-Identifier: MIT */
/* cont_impl.h — private layout of the continuum grid (for the continuum sources only). */
#ifndef MSCALE_CONT_IMPL_H
#define MSCALE_CONT_IMPL_H

#include "cont.h"

/* A material region: contiguous cells [first, first + n) with one EOS. */
typedef struct cont_region {
  size_t first, n;
  const eos_t *eos;
  int material;
} cont_region;

/* The step sweeps the grid in chunks of CONT_CHUNK nodes (step.c). Its scratch arrays are
 * chunk-local windows of CONT_WINDOW entries: global index j lives at [j + CONT_HALO − origin],
 * and the last CONT_HALO entries are carried into the next window, so scratch data never
 * travels to main memory. */
enum { CONT_CHUNK = 1024, CONT_HALO = 4, CONT_WINDOW = CONT_CHUNK + 2 * CONT_HALO };

typedef struct cont_tag {
  char *name;
  size_t node;
  size_t n, cap;
  double *t, *x, *u, *p_left, *rho_left, *p_right, *rho_right;
} cont_tag;

struct cont_grid {
  cont_geometry geometry;
  int area_power; /* face area A(x) = x^area_power: 0 planar, 1 cylindrical, 2 spherical */
  size_t ncells, nnodes;

  /* Nodes (structure of arrays, 64-byte aligned). */
  double *x, *u;        /* state at tⁿ */
  double *inv_mass;     /* 1 / nodal mass (½ of each neighbouring cell) */
  double *u_pred_mean;  /* window: predictor ½(uⁿ + u*) */
  double *area_mid;     /* window: face area between xⁿ and x* (mean-value form, see step.c) */
  double *u_mean;       /* window: corrector ½(uⁿ + uⁿ⁺¹) */
  double *ext_traction; /* coupling: extra force per face area (0 = none) */
  double *ext_velocity; /* coupling: prescribed velocity (NAN = free) */
  double *reaction;     /* coupling: constraint force per face area in the last step */
  double *force;        /* scratch: nodal force of the current phase */

  /* Cells. */
  double *mass, *inv_cell_mass, *rho, *e, *p, *q, *c;
  double *rho_half, *e_half, *p_half, *q_half; /* windows: predictor state at t^{n+1/2} */
  size_t win_origin;                           /* global index at window entry CONT_HALO */
  int *material, *layer;

  size_t nregions;
  cont_region *regions;

  cont_bc left, right;
  double q_quad, q_lin, cfl, dt_max, dt_min, dt_growth;

  double t, dt_last, dt_next; /* dt_next: stability constraint from the end of the last step */
  double land_time;           /* if a step is clipped to reach this time, t becomes it exactly */
  long step;
  bool any_ext; /* some node has an external force/velocity: take the slow path */

  /* Energy and momentum budget. */
  double work, impulse;
  double src_energy, src_momentum; /* the part of work/impulse from cont_grid_add_cell_source */

  size_t ntags, tag_cap;
  cont_tag *tags;

  char err[512];
};

/* Phase functions used outside the step too (step.c; grid set-up); ranges are half-open. */
void cont_eval_eos_for_cells(cont_grid *g, size_t lo, size_t hi, const double *rho, const double *e,
                             double *p, double *c, size_t *bad, ms_status *st);
void cont_calc_q_for_cells(const cont_grid *g, size_t lo, size_t hi, const double *rho,
                           const double *u, const double *c, double *q);
double cont_calc_time_constraint(const cont_grid *g, size_t lo, size_t hi);
double cont_cell_volume(const cont_grid *g, double xl, double xr);
/* Cell sizes of a layer (uniform or graded), dx[ncells]. */
void cont_layer_sizes(const cont_layer_spec *L, double *dx);
/* Record the current state into every tag's history. */
void cont_record_tags(cont_grid *g);
/* A boundary history from deck map m: exactly one of value, table, file, pulse
 * (docs/input-continuum.md); `what` names it in messages (deck.c; the 1D and 2D decks). */
bool cont_fn_read(dk_errors *e, dk_doc *doc, const dk_node *m, const char *what, ms_dim vdim,
                  cont_fn *fn);

#endif
