/* SPDX-License-Identifier: MIT */
/* coupled_deck.c — the `coupled` deck section (docs/input-coupled.md): the grid (read twice:
 * one copy runs first through the continuum problem's loop, the other supplies the gas during
 * the particle phase), the drive, the particle region (its model's own reader,
 * ptl_region_params_read), time, fragments, drag and transport; then the consistency of the
 * drive tags, the sample and the gas layer with the grid, and the check-time memory estimate. */
#include "coupled_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *const cpl_drive_mode_names[] = {"velocity", "transmitting", "two_way", NULL};

const cpl_run_summary *cpl_problem_summary(const cpl_problem *p) { return &p->sum; }

static size_t find_tag(const cont_grid *g, const char *name) {
  for (size_t i = 0; i < cont_grid_ntags(g); i++)
    if (!strcmp(cont_grid_history(g, i).name, name)) return i;
  return (size_t)-1;
}

/* The particle region: `model` (cluster_dynamics) and that model's keys; `depth` (two-way: the
 * region's extent beyond the grid's last node) is the coupling's. */
static void read_particles(cpl_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *P = dk_get(sec, "particles");
  if (!P) {
    dk_error(e, doc, sec, "coupled: a 'particles:' section is required");
    return;
  }
  if (!dk_expect_map(e, doc, P, "particles")) return;
  int model = 0;
  dk_read_enum(e, doc, P, "model", false, 0, ptl_region_model_names, &model);
  p->model = ptl_region_model_find(ptl_region_model_names[model]);
  dk_read_double(e, doc, P, "depth", MS_DIM_LENGTH, false, 0.0, 0.0, INFINITY, &p->depth);
  p->region = ptl_region_params_read(p->model, doc, P, e);
}

/* Check-time memory estimate (docs/reliability.md §4): the particle region over the sample's
 * initial depth (its model's estimate), plus the grid's cells (both copies, which
 * cont_problem_read has allocated already: counted so the total is right). */
static void memory_check(const cpl_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const cont_grid *g = cont_problem_grid(p->grid_out);
  cont_view v = cont_grid_view(g);
  double depth = p->drive_mode == DRIVE_TWO_WAY ? p->depth
                                                : v.x[cont_grid_history(g, p->tag_fs).node] -
                                                      v.x[cont_grid_history(g, p->tag_drive).node];
  const ptl_region_estimate est = ptl_region_params_estimate(p->region, depth);
  ms_mem_estimate m;
  ms_mem_init(&m);
  ms_mem_add(&m, est.at, "coupled particles", est.particles, est.bytes_per_particle);
  ms_mem_add(&m, dk_get(sec, "grid"), "coupled grid cells (2 copies)", 2.0 * (double)v.ncells,
             (double)cont_grid_bytes_per_cell());
  ms_mem_check(&m, ms_mem_limit(), 1, 1, e, doc);
  ms_mem_free(&m);
}

/* The gas the fragments fly through (material, layer of its grid); drag needs its viscosity. */
static void set_gas(cpl_problem *p, int material, int layer, dk_errors *e, dk_doc *doc,
                    const dk_node *at) {
  p->gas_mat = material;
  p->gas_layer = layer;
  const eos_material *gm = &p->mats->m[material];
  if (p->drag_law != CPL_DRAG_NONE && !(gm->viscosity > 0))
    dk_error(e, doc, at,
             "drag needs the gas viscosity: give material '%s' a 'viscosity' "
             "(air: 1.8e-9 g/(cm*10us) = 1.8e-5 Pa*s), or set drag.law: none",
             gm->name);
}

/* The grid (read twice: one copy runs first, the other supplies the gas) and the two-way gas
 * grid. */
static void read_grids(cpl_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  /* the grid first: the continuum reader checks the error count it started with */
  const dk_node *G = dk_get(sec, "grid");
  if (!G) {
    dk_error(e, doc, sec,
             "coupled: a 'grid:' section (the keys of a continuum section) is "
             "required");
  } else {
    p->grid_out = cont_problem_read(doc, G, p->mats, e);
    if (p->grid_out) {
      dk_errors scratch; /* the second read repeats the first one's (already empty) findings */
      dk_errors_init(&scratch);
      p->grid_live = cont_problem_read(doc, G, p->mats, &scratch);
      dk_errors_free(&scratch);
    }
  }
  /* two-way only: the gas beyond the particles' free surface, a grid of its own */
  const dk_node *Gs = dk_get(sec, "gas");
  if (Gs) p->gas_grid = cont_problem_read(doc, Gs, p->mats, e);
}

static const dk_node *read_drive(cpl_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e,
                                 const char **drive_tag, const char **fs_tag) {
  const dk_node *D = dk_get(sec, "drive");
  if (!D)
    dk_error(e, doc, sec,
             "coupled: a 'drive:' section is required (the tag whose U(t) drives "
             "the particles)");
  else if (dk_expect_map(e, doc, D, "drive")) {
    dk_read_string(e, doc, D, "tag", true, NULL, drive_tag);
    dk_read_string(e, doc, D, "free_surface_tag", false, "", fs_tag);
    p->drive_mode = 1;
    dk_read_enum(e, doc, D, "mode", false, 1, cpl_drive_mode_names, &p->drive_mode);
    dk_read_double(e, doc, D, "impedance", MS_DIM_NONE, false, 0.0, 0.0, INFINITY, &p->impedance);
    /* 0: depth/c0, shorter than the round trip of the release to the piston and back */
    dk_read_double(e, doc, D, "check_window", MS_DIM_TIME, false, 0.0, 0.0, INFINITY,
                   &p->check_window);
  }
  return D;
}

/* time, fragments, drag, transport */
static void read_options(cpl_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *T = dk_get(sec, "time");
  if (!T)
    dk_error(e, doc, sec,
             "coupled: a 'time:' section with 'end' (end of the particle phase) is "
             "required");
  else if (dk_expect_map(e, doc, T, "time")) {
    dk_read_positive(e, doc, T, "end", MS_DIM_TIME, true, 0, &p->t_end);
    dk_read_int(e, doc, T, "outputs", false, 4, 1, 1000, &p->n_out);
    dk_read_checkpoint_interval(e, doc, T, "time.", "particle steps", &p->checkpoint_every,
                                &p->checkpoint_time);
    /* wall-clock seconds (not simulated time), like LAMMPS's `timer timeout` */
    dk_read_double(e, doc, T, "wall_limit", MS_DIM_NONE, false, 0.0, 0.0, INFINITY, &p->wall_limit);
  }
  const dk_node *F = dk_get(sec, "fragments");
  p->bond = 1.2;
  p->jet_margin = 0.1;
  p->frag_every = 100;
  if (F && dk_expect_map(e, doc, F, "fragments")) {
    dk_read_double(e, doc, F, "bond", MS_DIM_NONE, false, 1.2, 0.5, 3.0, &p->bond);
    dk_read_int(e, doc, F, "every", false, 100, 1, 1000000, &p->frag_every);
    dk_read_double(e, doc, F, "jet_margin", MS_DIM_NONE, false, 0.1, 0.0, 10.0, &p->jet_margin);
  }
  const dk_node *R = dk_get(sec, "drag");
  p->drag_law = CPL_DRAG_SCHILLER_NAUMANN;
  if (R && dk_expect_map(e, doc, R, "drag")) {
    dk_read_enum(e, doc, R, "law", false, 0, cpl_drag_law_names, &p->drag_law);
    dk_read_bool(e, doc, R, "gas_return", false, false, &p->gas_return);
  }
  const dk_node *X = dk_get(sec, "transport");
  if (X && dk_expect_map(e, doc, X, "transport")) {
    dk_read_positive(e, doc, X, "detector", MS_DIM_LENGTH, true, 0, &p->det_distance);
    dk_read_positive(e, doc, X, "end", MS_DIM_TIME, true, 0, &p->transport_end);
    dk_read_int(e, doc, X, "windows", false, 200, 1, 100000, &p->transport_windows);
  }
}

/* Two-way: the grid ends at the interface node; the particles continue it, with the gas grid of
 * `gas:` beyond them (if any). */
static void check_two_way(cpl_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e,
                          const dk_node *at, const char *drive_tag, size_t nd, cont_view v) {
  const dk_node *X = dk_get(sec, "transport"), *R = dk_get(sec, "drag");
  if (nd != v.ncells)
    dk_error(e, doc, at,
             "drive.mode two_way: drive.tag '%s' must be the grid's last node (%zu), "
             "with `right: {type: free}`: the particles replace what lies beyond it",
             drive_tag, v.ncells);
  if (!(p->depth > 0))
    dk_error(e, doc, dk_get(sec, "particles") ? dk_get(sec, "particles") : sec,
             "drive.mode two_way needs particles.depth (the particle region's length "
             "beyond the interface, cm)");
  p->sample_mat = v.material[nd ? nd - 1 : 0];
  if (!p->gas_grid) {
    if (X)
      dk_error(e, doc, X,
               "drive.mode two_way without a 'gas:' section has no gas: remove "
               "'transport' (or add the gas beyond the particles as 'gas:')");
    p->drag_law = CPL_DRAG_NONE;
  } else {
    cont_view gv = cont_grid_view(cont_problem_grid(p->gas_grid));
    set_gas(p, gv.material[0], gv.layer[0], e, doc, R ? R : sec);
  }
}

/* One-way: the sample between the drive tag and the free-surface tag, one material, with the
 * gas layer beyond it. */
static void check_one_way(cpl_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e,
                          const dk_node *at, const char *drive_tag, const char *fs_tag, size_t nd,
                          const cont_grid *g) {
  const dk_node *D = dk_get(sec, "drive"), *Gs = dk_get(sec, "gas"), *R = dk_get(sec, "drag");
  cont_view v = cont_grid_view(g);
  size_t nf = v.ncells;
  if (Gs)
    dk_error(e, doc, Gs,
             "'gas:' is for drive.mode two_way; the one-way grid carries its own gas layer "
             "beyond free_surface_tag");
  if (p->have_fs) {
    p->tag_fs = find_tag(g, fs_tag);
    if (p->tag_fs == (size_t)-1) {
      dk_error(e, doc, dk_get(D, "free_surface_tag"),
               "drive.free_surface_tag: no tag named '%s' in grid.tags", fs_tag);
      p->have_fs = false;
    } else {
      nf = cont_grid_history(g, p->tag_fs).node;
    }
  }
  if (!p->have_fs) {
    dk_error(e, doc, D,
             "drive.free_surface_tag is required: it marks the sample's free "
             "surface, where the particle region ends");
  } else if (nd >= nf) {
    dk_error(e, doc, at,
             "drive.tag '%s' (node %zu) must lie left of the free surface '%s' "
             "(node %zu)",
             drive_tag, nd, fs_tag, nf);
  } else {
    p->sample_mat = v.material[nd];
    for (size_t c = nd; c < nf; c++)
      if (v.material[c] != p->sample_mat) {
        dk_error(e, doc, at,
                 "the cells between drive.tag '%s' and the free surface '%s' "
                 "must be one material (the particle region's)",
                 drive_tag, fs_tag);
        break;
      }
    if (nf >= v.ncells) {
      dk_error(e, doc, dk_get(D, "free_surface_tag"),
               "the free surface '%s' is the grid's last node: the gas layer beyond it is "
               "missing",
               fs_tag);
    } else {
      set_gas(p, v.material[nf], v.layer[nf], e, doc, R ? R : sec);
    }
    if (!p->mats->m[p->sample_mat].eos)
      dk_error(e, doc, at, "the sample material has no equation of state");
  }
}

cpl_problem *cpl_problem_read(dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                              dk_errors *e) {
  size_t nerr0 = e->n;
  cpl_problem *p = ms_calloc(1, sizeof *p);
  p->sum.check.rel_diff = NAN;
  p->mats = mats;
  read_grids(p, doc, sec, e);
  const char *drive_tag = NULL, *fs_tag = NULL;
  const dk_node *D = read_drive(p, doc, sec, e, &drive_tag, &fs_tag);
  read_particles(p, doc, sec, e);
  read_options(p, doc, sec, e);
  /* consistency with the grid: tags, the sample between them, the gas beyond */
  if (p->grid_out && drive_tag) {
    const cont_grid *g = cont_problem_grid(p->grid_out);
    p->tag_drive = find_tag(g, drive_tag);
    const dk_node *at = dk_get(D, "tag");
    if (p->tag_drive == (size_t)-1) {
      dk_error(e, doc, at, "drive.tag: no tag named '%s' in grid.tags", drive_tag);
    } else {
      p->have_fs = fs_tag && fs_tag[0];
      const size_t nd = cont_grid_history(g, p->tag_drive).node;
      if (p->drive_mode == DRIVE_TWO_WAY)
        check_two_way(p, doc, sec, e, at, drive_tag, nd, cont_grid_view(g));
      else check_one_way(p, doc, sec, e, at, drive_tag, fs_tag, nd, g);
    }
  }
  if (e->n == nerr0 && p->grid_out) /* before the region allocates its lattice */
    memory_check(p, doc, sec, e);
  if (e->n != nerr0) {
    cpl_problem_destroy(&p);
    return NULL;
  }
  /* the wall-time limit may change between a run and its continuation (chained batch jobs) */
  static const char *const hash_skip[] = {"coupled.time.wall_limit", NULL};
  p->deck_hash = dk_hash(doc, hash_skip);
  return p;
}

static void cpl_problem_free(cpl_problem *p) {
  if (!p) return;
  cont_problem_destroy(&p->grid_out);
  cont_problem_destroy(&p->grid_live);
  cont_problem_destroy(&p->gas_grid);
  ptl_region_params_destroy(&p->region);
  free(p);
}

void cpl_problem_destroy(cpl_problem **p) {
  if (!p) return;
  cpl_problem_free(*p);
  *p = NULL;
}
