/* SPDX-License-Identifier: MIT */
/* cont_run.h — the deck problem's private state (deck.c reads it, run.c runs it). */
#ifndef MSCALE_CONT_RUN_H
#define MSCALE_CONT_RUN_H

#include "cont_impl.h"

struct cont_problem {
  cont_setup setup;
  cont_layer_spec *layers;
  cont_tag_spec *tags;
  cont_grid *grid;
  double t_end;
  long max_steps;    /* 0: no limit */
  double *out_times; /* profile times */
  size_t n_out;
  long history_stride; /* history files keep every k-th step (memory keeps all) */
  long xt_frames;      /* x–t diagram frames over [0, t_end] */
  int xt_quantity;     /* 0 density, 1 pressure (what tools/plot_xt.py shows by default) */
};

/* Output writers (output.c). */
ms_status cont_write_profile(const ms_ctx *ctx, const cont_grid *g, const char *stem);
/* The units of a cell's mass and of the grid's energies in its geometry: per unit area in
 * planar ("g/cm^2", "kJ/cm^2"), per radian and unit length in cylindrical, per steradian in
 * spherical geometry (cont.h). */
const char *cont_mass_unit(cont_geometry geometry);
const char *cont_energy_unit(cont_geometry geometry);
ms_status cont_write_histories(const ms_ctx *ctx, const cont_grid *g, long stride);

#endif
