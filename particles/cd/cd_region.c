/* SPDX-License-Identifier: MIT */
/* cd_region.c — cluster dynamics as a particle region of the coupled problem (ptl_region.h,
 * docs/input-coupled.md "particles"): the deck section, the lattice slab with its surface
 * profile, piston and surface layers, and the interface's calls on a cd_sim.
 *
 * The section uses the cluster_dynamics problem's model keys (cd_model_keys.c: r0, courant,
 * damping, ...) with the coupled problem's own defaults (courant 0.05, damping J = 50: the
 * values its decks were validated with), and the region keys lattice, width, width_z,
 * piston_rows and surface {profile, depth | amplitude, wavelength, seed}. */
#include "cd_impl.h"
#include "ptl_region_impl.h"

#include <stdlib.h>

enum { SURF_FLAT = 0, SURF_SINE, SURF_RANDOM };
static const char *const surface_names[] = {"flat", "sine", "random", NULL};
static const char *const surface_old_names[] = {"flat", "grooves", "random", NULL};
static const char *const lattice_names[] = {"tri2d", "fcc", NULL};

typedef struct cd_region_params {
  ptl_region_params base;
  cd_model_keys k;
  int lattice; /* 0 tri2d, 1 fcc */
  double width, width_z;
  long piston_rows;
  int surface;
  double surf_depth, surf_wavelength; /* peak to valley, period (cm) */
  long seed;
  const dk_node *at; /* the section (memory estimate) */
  const dk_node *at_r0;
  char notes[1024];
} cd_region_params;

typedef struct cd_region {
  ptl_region base;
  cd_sim *sim;
  ptl_region_geometry geo;
} cd_region;

/* ---------------------------------------------------------------------------------------- */
/* The deck section                                                                           */

static void read_surface(cd_region_params *p, dk_doc *doc, const dk_node *S, dk_errors *e) {
  const char *w = "particles.surface";
  if (dk_get(S, "type")) { /* the old name of `profile`, with `grooves` for `sine` */
    cd_key_or_alias(e, doc, S, "profile", "type", w, p->notes, sizeof p->notes);
    dk_read_enum(e, doc, S, "type", false, 0, surface_old_names, &p->surface);
  } else {
    dk_read_enum(e, doc, S, "profile", false, 0, surface_names, &p->surface);
  }
  bool need = p->surface != SURF_FLAT;
  /* the height as peak-to-valley `depth` (Rz) or as `amplitude` a0 = depth/2 ([Davydov] §4.2,
   * docs/design.md §6), one of the two */
  const dk_node *amplitude_node = dk_get(S, "amplitude");
  if (amplitude_node) {
    if (dk_get(S, "depth"))
      dk_error(e, doc, amplitude_node,
               "particles.surface: give depth (peak to valley) or amplitude (half of it), "
               "not both");
    double amplitude = 0.0;
    dk_read_double(e, doc, S, "amplitude", MS_DIM_LENGTH, need, 0.0, 0.0, INFINITY, &amplitude);
    p->surf_depth = 2.0 * amplitude;
  } else {
    dk_read_double(e, doc, S, "depth", MS_DIM_LENGTH, need, 0.0, 0.0, INFINITY, &p->surf_depth);
  }
  dk_read_double(e, doc, S, "wavelength", MS_DIM_LENGTH, need, 0.0, 0.0, INFINITY,
                 &p->surf_wavelength);
  dk_read_int(e, doc, S, "seed", false, 1, 0, 1L << 40, &p->seed);
  if (need && !(p->surf_wavelength > 0))
    dk_error(e, doc, S, "particles.surface: wavelength must be > 0 for %s surfaces",
             surface_names[p->surface]);
}

static ptl_region_params *region_read(dk_doc *doc, const dk_node *P, dk_errors *e) {
  const size_t nerr0 = e->n;
  cd_region_params *p = ms_calloc(1, sizeof *p);
  p->at = P;
  dk_read_enum(e, doc, P, "lattice", false, 0, lattice_names, &p->lattice);
  const cd_model_defaults defaults = {"particles", 0.05, 50.0};
  p->at_r0 = dk_get(P, dk_get(P, "spacing") ? "spacing" : "r0");
  cd_model_keys_read(e, doc, P, p->lattice == 1 ? 3 : 2, &defaults, &p->k, p->notes,
                     sizeof p->notes);
  dk_read_positive(e, doc, P, "width", MS_DIM_LENGTH, true, 0, &p->width);
  if (p->lattice == 1)
    dk_read_double(e, doc, P, "width_z", MS_DIM_LENGTH, false, 4 * sqrt(2.0) * p->k.r0, 0.0,
                   INFINITY, &p->width_z);
  dk_read_int(e, doc, P, "piston_rows", false, 2, 1, 100, &p->piston_rows);
  const dk_node *S = dk_get(P, "surface");
  p->surface = SURF_FLAT;
  if (S && dk_expect_map(e, doc, S, "particles.surface")) read_surface(p, doc, S, e);
  if (p->surface != SURF_FLAT && p->surf_wavelength > 0 && p->width > 0 &&
      p->surf_wavelength > p->width * (1 + 1e-9))
    dk_error(e, doc, dk_get(P, "width"),
             "particles.width (%g cm) must hold at least one surface wavelength (%g cm)", p->width,
             p->surf_wavelength);
  if (e->n != nerr0) {
    free(p);
    return NULL;
  }
  return &p->base;
}

static void region_params_destroy(ptl_region_params *pp) { free(pp); }
static const char *region_notes(const ptl_region_params *pp) {
  return ((const cd_region_params *)pp)->notes;
}

/* Lattice counts of a slab `depth` long: tri2d with close-packed rows along y (row spacing
 * √3/2 a in x), fcc cubic cells √2 a. */
static void lattice_counts(const cd_region_params *p, double depth, int n[3], double cell[2]) {
  const bool fcc = p->lattice == 1;
  const double a = p->k.r0;
  cell[0] = fcc ? sqrt(2.0) * a : sqrt(3.0) * a;
  cell[1] = fcc ? sqrt(2.0) * a : a;
  n[0] = (int)fmax(2.0, nearbyint(depth / cell[0]));
  n[1] = (int)fmax(2.0, nearbyint(p->width / cell[1]));
  n[2] = fcc ? (int)fmax(2.0, nearbyint(p->width_z / cell[1])) : 1;
}

/* Check-time memory estimate (docs/reliability.md §4) over the sample's initial depth
 * (compression only shortens it): the cluster-dynamics bytes per particle, the lattice built a
 * second time before the surface is cut (90 B), the coupling's fragment and transport buffers
 * (skip flags, forces: 25 B). */
static ptl_region_estimate region_estimate(const ptl_region_params *pp, double depth) {
  const cd_region_params *p = (const cd_region_params *)pp;
  const bool fcc = p->lattice == 1;
  const double a = p->k.r0, cell_x = fcc ? sqrt(2.0) * a : sqrt(3.0) * a,
               cell_y = fcc ? sqrt(2.0) * a : a;
  double n = (fcc ? 4.0 : 2.0) * fmax(2.0, depth / cell_x) * fmax(2.0, p->width / cell_y) *
             (fcc ? fmax(2.0, p->width_z / cell_y) : 1.0);
  ptl_region_estimate est = {
      n, cd_particle_bytes(fcc ? CD_LATTICE_FCC : CD_LATTICE_TRI2D, p->k.rc + 0.1) + 90 + 25,
      p->at_r0 ? p->at_r0 : p->at};
  return est;
}

/* ---------------------------------------------------------------------------------------- */
/* The free-surface profile                                                                  */

typedef struct surface_modes {
  int n;
  double ky[64], kz[64], amp[64], phase[64];
  double lo, hi; /* range of the raw sum, for scaling to the peak-to-valley depth */
} surface_modes;

/* Height below the nominal surface (0 at the peaks, depth at the valleys). */
static double surface_drop(const cd_region_params *p, const surface_modes *m, double y, double z) {
  if (p->surface == SURF_FLAT || !(p->surf_depth > 0)) return 0.0;
  if (p->surface == SURF_SINE) {
    double lam = p->width / fmax(1.0, nearbyint(p->width / p->surf_wavelength));
    return 0.5 * p->surf_depth * (1 - cos(2 * CD_PI * y / lam));
  }
  double s = 0;
  for (int k = 0; k < m->n; k++) s += m->amp[k] * cos(m->ky[k] * y + m->kz[k] * z + m->phase[k]);
  return p->surf_depth * (m->hi - s) / (m->hi - m->lo);
}

/* Random roughness: periodic modes with wavelengths from the box size down to the deck's
 * wavelength (the correlation length), random phases, amplitudes ∝ wavelength (a rough,
 * self-affine-like profile), scaled to the peak-to-valley depth Rz. */
static void surface_setup(const cd_region_params *p, surface_modes *m, bool three_d) {
  memset(m, 0, sizeof *m);
  if (p->surface != SURF_RANDOM) return;
  int my = (int)fmax(1.0, floor(p->width / p->surf_wavelength));
  int mz = three_d ? (int)fmax(1.0, floor(p->width_z / p->surf_wavelength)) : 0;
  uint64_t k = 0;
  for (int iy = 0; iy <= my && m->n < 64; iy++)
    for (int iz = 0; iz <= mz && m->n < 64; iz++) {
      if (!iy && !iz) continue;
      double ky = 2 * CD_PI * iy / p->width, kz = three_d ? 2 * CD_PI * iz / p->width_z : 0;
      double kk = sqrt(ky * ky + kz * kz);
      m->ky[m->n] = ky;
      m->kz[m->n] = kz;
      m->amp[m->n] = (0.5 + ptl_splitmix64_uniform((uint64_t)p->seed, k++)) / kk;
      m->phase[m->n] = 2 * CD_PI * ptl_splitmix64_uniform((uint64_t)p->seed, k++);
      m->n++;
    }
  /* range of the sum over a fine sample of the period */
  m->lo = INFINITY;
  m->hi = -INFINITY;
  int ny = 512, nz = three_d ? 128 : 1;
  for (int a = 0; a < ny; a++)
    for (int b = 0; b < nz; b++) {
      double y = p->width * a / ny, z = three_d ? p->width_z * b / nz : 0, s = 0;
      for (int j = 0; j < m->n; j++)
        s += m->amp[j] * cos(m->ky[j] * y + m->kz[j] * z + m->phase[j]);
      if (s < m->lo) m->lo = s;
      if (s > m->hi) m->hi = s;
    }
  if (!(m->hi > m->lo)) m->hi = m->lo + 1;
}

/* ---------------------------------------------------------------------------------------- */
/* Building the region                                                                        */

/* The lattice between x_drive and its nominal top, cut by the surface profile; piston rows and
 * the surface layer flagged. */
static ptl_state *region_lattice(const cd_region_params *p, double x_drive, const int n[3],
                                 double x_top, double mass) {
  const bool fcc = p->lattice == 1;
  const double a = p->k.r0;
  size_t ncap = (size_t)(fcc ? 4 : 2) * (size_t)n[0] * (size_t)n[1] * (size_t)n[2];
  ptl_state *tmp = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = ncap, .dim = fcc ? 3 : 2}, &tmp),
          "ptl_state_create");
  if (fcc) {
    double sh[3] = {0.25, 0.25, 0.25}, o[3] = {x_drive, 0, 0};
    cd_lattice_fcc(tmp, n[0], n[1], n[2], sh, o, a, mass, 0);
  } else {
    /* generated as cd_lattice_tri's (x', y') = (y, x): rows of constant x hold neighbours */
    double sh[2] = {0.25, 0.25}, o[2] = {0, x_drive};
    cd_lattice_tri(tmp, n[1], n[0], sh, o, a, mass, 0);
    for (size_t i = 0; i < tmp->n; i++) {
      double t = tmp->x[i];
      tmp->x[i] = tmp->y[i];
      tmp->y[i] = t;
    }
  }
  surface_modes modes;
  surface_setup(p, &modes, fcc);
  ptl_state *ps = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = tmp->n, .dim = fcc ? 3 : 2}, &ps),
          "ptl_state_create");
  const double row = fcc ? 0.5 * sqrt(2.0) * a : 0.5 * sqrt(3.0) * a; /* layer spacing in x */
  for (size_t i = 0; i < tmp->n; i++) {
    double drop = surface_drop(p, &modes, tmp->y[i], tmp->z[i]);
    double top = x_top - drop;
    if (tmp->x[i] > top) continue;
    size_t j = ptl_state_add(ps, tmp->x[i], tmp->y[i], tmp->z[i], mass, 0);
    if (tmp->x[i] < x_drive + p->piston_rows * row) ps->flags[j] |= PTL_DRIVEN;
    else if (tmp->x[i] > top - row) ps->flags[j] |= PTL_SURFACE;
  }
  ptl_state_destroy(&tmp);
  return ps;
}

static ms_status region_create(const ptl_region_params *pp, const ms_ctx *ctx, const eos_t *eos,
                               double x_drive, double depth, ptl_region **out) {
  const cd_region_params *p = (const cd_region_params *)pp;
  const double rho0 = eos_rho0(eos), c0 = eos_c0(eos), a = p->k.r0;
  const bool fcc = p->lattice == 1;
  const cd_lattice lat = fcc ? CD_LATTICE_FCC : CD_LATTICE_TRI2D;
  const double mass = rho0 * cd_cluster_volume(lat, a, p->k.thickness);
  int n[3];
  double cell[2];
  lattice_counts(p, depth, n, cell);
  const double width = n[1] * cell[1], width_z = fcc ? n[2] * cell[1] : 0.0;
  const double x_top = x_drive + n[0] * cell[0]; /* nominal free surface of the lattice */
  ptl_state *ps = region_lattice(p, x_drive, n, x_top, mass);
  ms_log(ctx, MS_LOG_INFO,
         "coupled: particles: %s lattice, a = %g cm, %zu particles (%d x %d x %d cells), "
         "region %g..%g cm (grid: %g..%g), width %g cm, surface %s (depth %g cm)",
         lattice_names[p->lattice], a, ps->n, n[0], n[1], n[2], x_drive, x_top, x_drive,
         x_drive + depth, width, surface_names[p->surface], p->surf_depth);

  cd_box box;
  memset(&box, 0, sizeof box);
  box.lo[0] = x_drive - 10 * a;
  box.hi[0] = x_top + 10 * a;
  box.bc[0] = CD_BC_FREE;
  box.hi[1] = width;
  box.bc[1] = CD_BC_PERIODIC;
  box.hi[2] = fcc ? width_z : 0.0; /* 2D: no extent (as cd_problem.c); a z extent made the MPI
                                     * partition grid ~2000 empty cells deep */
  box.bc[2] = fcc ? CD_BC_PERIODIC : CD_BC_FREE;
  cd_config cfg;
  memset(&cfg, 0, sizeof cfg);
  cfg.r0 = a;
  cfg.skin = p->k.skin * a;
  cfg.dt = p->k.dt > 0 ? p->k.dt : p->k.courant * a / c0;
  cfg.cutoff = p->k.mode;
  cfg.damping_gamma = p->k.damping_j > 0 ? c0 / (p->k.damping_j * a) : 0.0;
  cfg.lattice = lat;
  cfg.thickness = p->k.thickness;
  const size_t nglobal = ps->n;
  cd_sim *sim = NULL;
  ms_must(
      cd_sim_create(&(cd_sim_params){.particles = ps, .box = &box, .cfg = &cfg, .nmat = 1}, &sim),
      "cd_sim_create");
  cd_pair_table *tab = ms_calloc(1, sizeof *tab);
  ms_status st = cd_pair_table_build(tab, eos, eos, lat, a, p->k.thickness, p->k.rc * a,
                                     p->k.r_min * a, 1.0, p->k.table_intervals);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR,
           "coupled: cannot build the pair potential of the sample material "
           "(cold curve missing or not finite on [r_min a, R_c])");
    free(tab);
    cd_sim_destroy(&sim);
    return st;
  }
  cd_sim_set_pair(sim, 0, 0, tab);
  cd_region *r = ms_calloc(1, sizeof *r);
  r->sim = sim;
  r->geo = (ptl_region_geometry){.dim = fcc ? 3 : 2,
                                 .spacing = a,
                                 .rho0 = rho0,
                                 .c0 = c0,
                                 .x_drive = x_drive,
                                 .x_top = x_top,
                                 .surface_depth = p->surface != SURF_FLAT ? p->surf_depth : 0.0,
                                 .period = {0.0, width, width_z},
                                 .area = fcc ? width * width_z : width * p->k.thickness,
                                 .dt = cfg.dt,
                                 .particles = nglobal};
  *out = &r->base;
  return MS_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* The interface's calls                                                                      */

static cd_sim *sim_of(const ptl_region *r) { return ((const cd_region *)r)->sim; }

static void region_destroy(ptl_region *r) {
  cd_sim_destroy(&((cd_region *)r)->sim);
  free(r);
}
static ptl_region_geometry region_geometry(const ptl_region *r) {
  return ((const cd_region *)r)->geo;
}
static ptl_state *region_state(ptl_region *r) { return sim_of(r)->p; }
static double region_time(const ptl_region *r) { return sim_of(r)->t; }

static void region_set_piston(ptl_region *r, size_t n, const double *t, const double *u,
                              const double dir[3]) {
  cd_history h = {n, (double *)t, (double *)u};
  cd_sim_set_piston(sim_of(r), &h, dir);
}

static void region_hold_piston(ptl_region *r, double u, double span) {
  cd_sim *s = sim_of(r);
  if (s->piston.n < 2) { /* room for the two points of a constant velocity */
    double t2[2] = {0, 0}, u2[2] = {0, 0};
    region_set_piston(r, 2, t2, u2, s->piston_dir);
  }
  s->piston.n = 2;
  s->piston.t[0] = s->t;
  s->piston.t[1] = s->t + span;
  s->piston.u[0] = s->piston.u[1] = u;
}

static void region_set_dt(ptl_region *r, double dt) { sim_of(r)->cfg.dt = dt; }

/* MPI: every rank built the whole region; cd_sim_init keeps what each rank's coarse cells own
 * (the cluster_dynamics defaults: auto partition, rebalance above 1.2 checked every 10 list
 * builds). Serial: nothing to do. */
static void region_distribute(ptl_region *r, const ms_ctx *ctx) {
  if (ctx->size < 2) return;
  const cd_mpi_config mc = {.partition = CD_PART_AUTO,
                            .rebalance_threshold = 1.2,
                            .rebalance_interval = 10,
                            .replicated = true};
  cd_sim_set_mpi(sim_of(r), &mc);
}

static ms_status region_init(ptl_region *r) { return cd_sim_init(sim_of(r)); }
static ms_status region_step(ptl_region *r) { return cd_sim_step(sim_of(r)); }
static const char *region_error(const ptl_region *r) { return cd_sim_error(sim_of(r)); }

static double region_driven_force(const ptl_region *r) {
  const ptl_state *ps = sim_of(r)->p;
  double f = 0;
  for (size_t i = 0; i < ps->nlocal; i++)
    if (ps->flags[i] & PTL_DRIVEN) f += ps->fx[i];
  return f;
}

static double region_free_surface_velocity(const ptl_region *r) {
  return cd_free_surface_velocity(sim_of(r), 0);
}

_Static_assert(sizeof(ptl_region_energy) == sizeof(cd_energy),
               "ptl_region_energy mirrors cd_energy term by term");
static void region_energy(ptl_region *r, ptl_region_energy *out) {
  cd_energy en;
  cd_sim_energy(sim_of(r), &en);
  *out = (ptl_region_energy){en.kinetic,     en.potential,
                             en.dissipated,  en.broken,
                             en.piston_work, en.wall_work,
                             en.total,       {en.momentum[0], en.momentum[1], en.momentum[2]}};
}

static void region_refresh_ghosts(ptl_region *r) { cd_sim_refresh_ghosts(sim_of(r)); }
static void region_ghost_owners(const ptl_region *r, int32_t *owner) {
  cd_sim_ghost_owners(sim_of(r), owner);
}
static ms_status region_write_snapshot(ptl_region *r, const char *path, const char *material) {
  if (material) cd_sim_set_material_names(sim_of(r), material);
  return cd_write_snapshot(sim_of(r), path);
}
static ms_status region_refresh(ptl_region *r) { return cd_sim_refresh(sim_of(r)); }
static ms_status region_checkpoint_write(const ptl_region *r, ms_h5 *h, const ms_ctx *ctx) {
  return cd_checkpoint_write(h, ctx, sim_of(r));
}

static ms_status region_restore(ptl_region *r, ms_h5r *h, const ms_ctx *ctx, long *step,
                                dk_errors *e) {
  cd_sim *sim = sim_of(r);
  cd_restart *rs = cd_restart_read(h, ctx, sim->p->dim, sim->cfg.cutoff == CD_CUTOFF_BONDED, e);
  if (!rs) return MS_ERR_INPUT;
  ptl_state_destroy(&sim->p); /* the lattice region_create made: the checkpoint's replaces it */
  sim->p = cd_restart_take_particles(rs);
  ms_status st = cd_sim_init_restart(sim, rs, e);
  *step = cd_restart_step(rs);
  cd_restart_destroy(&rs);
  return st;
}

static const ptl_region_model cd_region_model = {
    .name = "cluster_dynamics",
    .read = region_read,
    .params_destroy = region_params_destroy,
    .notes = region_notes,
    .estimate = region_estimate,
    .create = region_create,
    .destroy = region_destroy,
    .geometry = region_geometry,
    .state = region_state,
    .time = region_time,
    .set_piston = region_set_piston,
    .hold_piston = region_hold_piston,
    .set_dt = region_set_dt,
    .distribute = region_distribute,
    .init = region_init,
    .step = region_step,
    .error = region_error,
    .driven_force = region_driven_force,
    .free_surface_velocity = region_free_surface_velocity,
    .energy = region_energy,
    .refresh_ghosts = region_refresh_ghosts,
    .ghost_owners = region_ghost_owners,
    .write_snapshot = region_write_snapshot,
    .refresh = region_refresh,
    .checkpoint_write = region_checkpoint_write,
    .restore = region_restore,
};

const ptl_region_model *cd_region_model_get(void) { return &cd_region_model; }
