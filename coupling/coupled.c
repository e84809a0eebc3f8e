/* The `coupled` problem (docs/input-coupled.md, docs/coupling.md §6): the one-way drive of
 * docs/design.md §6. The Lagrangian grid computes the loading; the velocity history U(t) of a tagged
 * node inside the sample drives the piston of a cluster-dynamics region that represents the
 * sample between that node and its (flat, grooved or rough) free surface; fragments are found
 * during and after the particle phase, feel Schiller–Naumann drag from the grid's gas layer, and
 * the detached ones are transported to a detector plane with CVODE.
 *
 * Two grids are read from the same `grid:` section: one runs first through the continuum
 * problem's own loop (its outputs — profiles, histories, x–t diagram — land in the run
 * directory and its tag histories drive the particles); the other is advanced in lock-step with
 * the particles and the transport to supply the gas state at the current time. */
#include "cpl_checkpoint.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cont.h"
#include "cont_run.h"
#include "cd.h"

enum { SURF_FLAT = 0, SURF_GROOVES, SURF_RANDOM };
static const char *const surface_names[] = {"flat", "grooves", "random", NULL};
static const char *const lattice_names[] = {"tri2d", "fcc", NULL};
static const char *const cutoff_names[] = {"plain", "bonded", NULL};
static const char *const drive_mode_names[] = {"velocity", "transmitting", "two_way", NULL};
enum { DRIVE_VELOCITY = 0, DRIVE_TRANSMITTING, DRIVE_TWO_WAY };

struct cpl_problem {
  const eos_materials *mats;
  cont_problem *grid_out, *grid_live;
  cont_problem *gas_grid;   /* two-way: the gas beyond the particles' free surface (`gas:`) */
  size_t tag_drive, tag_fs; /* tag indices in both grids */
  int drive_mode;           /* 0 velocity history, 1 transmitting (characteristic) piston */
  double impedance;         /* Z for the transmitting piston (0: √1.5 ρ0 c0) */
  bool have_fs;
  int sample_mat, gas_mat, gas_layer;
  /* particles */
  int lattice;  /* 0 tri2d, 1 fcc */
  double depth; /* two-way: particle region length beyond the interface node */
  double spacing, thickness, width, width_z, cutoff, damping_j, dt_factor, dt;
  int cutoff_mode;
  long piston_rows;
  int surface;
  double surf_depth, surf_wavelength;
  long seed;
  /* time and outputs */
  double t_end;
  long n_out;
  double check_window;
  long checkpoint_every;  /* particle steps between checkpoints (0: none) */
  double checkpoint_time; /* or simulated time between them (rounded to whole steps) */
  uint64_t deck_hash;     /* of the resolved deck: a restart must use the same one */
  /* fragments, drag, transport */
  double bond, jet_margin;
  long frag_every;
  int drag_law;
  bool gas_return; /* drag.gas_return: the gas receives −(drag impulse) and the energy */
  double det_distance, transport_end;
  long transport_windows;
  cpl_run_summary sum; /* what the last run measured */
};

const cpl_run_summary *cpl_problem_summary(const cpl_problem *p) { return &p->sum; }

/* ---------------------------------------------------------------------------------------- */
/* Reading                                                                                   */

static size_t find_tag(const cont_grid *g, const char *name) {
  for (size_t i = 0; i < cont_grid_ntags(g); i++)
    if (!strcmp(cont_grid_history(g, i).name, name)) return i;
  return (size_t)-1;
}

static void read_particles(cpl_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *P = dk_get(sec, "particles");
  if (!P) {
    dk_error(e, doc, sec, "coupled: a 'particles:' section is required");
    return;
  }
  if (!dk_expect_map(e, doc, P, "particles")) return;
  dk_read_enum(e, doc, P, "lattice", false, 0, lattice_names, &p->lattice);
  dk_read_positive(e, doc, P, "spacing", MS_DIM_LENGTH, true, 0, &p->spacing);
  dk_read_double(e, doc, P, "thickness", MS_DIM_LENGTH, false, 0.0, 0.0, INFINITY, &p->thickness);
  dk_read_positive(e, doc, P, "width", MS_DIM_LENGTH, true, 0, &p->width);
  dk_read_double(e, doc, P, "width_z", MS_DIM_LENGTH, false, 0.0, 0.0, INFINITY, &p->width_z);
  /* two-way coupling: the particle region's extent beyond the grid's last node */
  dk_read_double(e, doc, P, "depth", MS_DIM_LENGTH, false, 0.0, 0.0, INFINITY, &p->depth);
  dk_read_double(e, doc, P, "cutoff", MS_DIM_NONE, false, 1.2, 1.0, 1.5, &p->cutoff);
  int mode = 1;
  dk_read_enum(e, doc, P, "cutoff_mode", false, 1, cutoff_names, &mode);
  p->cutoff_mode = mode;
  dk_read_double(e, doc, P, "damping_j", MS_DIM_NONE, false, 50.0, 0.0, 1e6, &p->damping_j);
  dk_read_int(e, doc, P, "piston_rows", false, 2, 1, 100, &p->piston_rows);
  dk_read_double(e, doc, P, "dt_factor", MS_DIM_NONE, false, 0.05, 1e-4, 0.5, &p->dt_factor);
  dk_read_double(e, doc, P, "dt", MS_DIM_TIME, false, 0.0, 0.0, INFINITY, &p->dt);
  const dk_node *S = dk_get(P, "surface");
  p->surface = SURF_FLAT;
  if (S && dk_expect_map(e, doc, S, "particles.surface")) {
    dk_read_enum(e, doc, S, "type", false, 0, surface_names, &p->surface);
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
}

/* Check-time memory estimate (docs/reliability.md §4), with build_region's lattice counts over
 * the sample's initial depth (compression only shortens it): the cluster-dynamics bytes per
 * particle, the lattice built a second time before the surface is cut (90 B), the fragment
 * and transport buffers (skip flags, forces: 25 B); plus the grid's cells (both copies, which
 * cont_problem_read has allocated already: counted so the total is right). */
static void memory_check(const cpl_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const cont_grid *g = cont_problem_grid(p->grid_out);
  cont_view v = cont_grid_view(g);
  double depth = p->drive_mode == DRIVE_TWO_WAY ? p->depth
                                                : v.x[cont_grid_history(g, p->tag_fs).node] -
                                                      v.x[cont_grid_history(g, p->tag_drive).node];
  const bool fcc = p->lattice == 1;
  const double a = p->spacing, cell_x = fcc ? sqrt(2.0) * a : sqrt(3.0) * a,
               cell_y = fcc ? sqrt(2.0) * a : a;
  double n = (fcc ? 4.0 : 2.0) * fmax(2.0, depth / cell_x) * fmax(2.0, p->width / cell_y) *
             (fcc ? fmax(2.0, p->width_z / cell_y) : 1.0);
  const dk_node *P = dk_get(sec, "particles");
  ms_mem_estimate m;
  ms_mem_init(&m);
  ms_mem_add(&m, dk_get(P, "spacing"), "coupled particles", n,
             cd_particle_bytes(fcc ? CD_LATTICE_FCC : CD_LATTICE_TRI2D, p->cutoff + 0.1) + 90 + 25);
  ms_mem_add(&m, dk_get(sec, "grid"), "coupled grid cells (2 copies)", 2.0 * (double)v.ncells,
             176.0 /* continuum/cont_impl.h: 10 node and 11 cell arrays of doubles, 2 of ints */);
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

cpl_problem *cpl_problem_read(dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                              dk_errors *e) {
  size_t nerr0 = e->n;
  cpl_problem *p = ms_calloc(1, sizeof *p);
  p->sum.check.rel_diff = NAN;
  p->mats = mats;
  /* the grid first: the continuum reader checks the error count it started with */
  const dk_node *G = dk_get(sec, "grid");
  if (!G) {
    dk_error(e, doc, sec,
             "coupled: a 'grid:' section (the keys of a continuum section) is "
             "required");
  } else {
    p->grid_out = cont_problem_read(doc, G, mats, e);
    if (p->grid_out) {
      dk_errors scratch; /* the second read repeats the first one's (already empty) findings */
      dk_errors_init(&scratch);
      p->grid_live = cont_problem_read(doc, G, mats, &scratch);
      dk_errors_free(&scratch);
    }
  }
  /* two-way only: the gas beyond the particles' free surface, a grid of its own */
  const dk_node *Gs = dk_get(sec, "gas");
  if (Gs) p->gas_grid = cont_problem_read(doc, Gs, mats, e);
  const dk_node *D = dk_get(sec, "drive");
  const char *drive_tag = NULL, *fs_tag = NULL;
  if (!D)
    dk_error(e, doc, sec,
             "coupled: a 'drive:' section is required (the tag whose U(t) drives "
             "the particles)");
  else if (dk_expect_map(e, doc, D, "drive")) {
    dk_read_string(e, doc, D, "tag", true, NULL, &drive_tag);
    dk_read_string(e, doc, D, "free_surface_tag", false, "", &fs_tag);
    p->drive_mode = 1;
    dk_read_enum(e, doc, D, "mode", false, 1, drive_mode_names, &p->drive_mode);
    dk_read_double(e, doc, D, "impedance", MS_DIM_NONE, false, 0.0, 0.0, INFINITY, &p->impedance);
    /* 0: depth/c0, shorter than the round trip of the release to the piston and back */
    dk_read_double(e, doc, D, "check_window", MS_DIM_TIME, false, 0.0, 0.0, INFINITY,
                   &p->check_window);
  }
  read_particles(p, doc, sec, e);

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

  /* consistency with the grid: tags, the sample between them, the gas beyond */
  if (p->grid_out && drive_tag) {
    const cont_grid *g = cont_problem_grid(p->grid_out);
    cont_view v = cont_grid_view(g);
    p->tag_drive = find_tag(g, drive_tag);
    const dk_node *at = dk_get(D, "tag");
    if (p->tag_drive == (size_t)-1) {
      dk_error(e, doc, at, "drive.tag: no tag named '%s' in grid.tags", drive_tag);
    } else {
      p->have_fs = fs_tag && fs_tag[0];
      size_t nd = cont_grid_history(g, p->tag_drive).node, nf = v.ncells;
      if (p->drive_mode == DRIVE_TWO_WAY) {
        /* the grid ends at the interface; the particles continue it */
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
        goto consistency_done;
      }
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
        if (!mats->m[p->sample_mat].eos)
          dk_error(e, doc, at, "the sample material has no equation of state");
      }
    }
  }
consistency_done:
  if (p->lattice == 0 && p->thickness == 0) p->thickness = p->spacing;
  if (p->lattice == 1 && !(p->width_z > 0)) p->width_z = 4 * sqrt(2.0) * p->spacing;
  if (p->surface != SURF_FLAT && p->surf_wavelength > 0 && p->width > 0 &&
      p->surf_wavelength > p->width * (1 + 1e-9))
    dk_error(e, doc, dk_get(dk_get(sec, "particles"), "width"),
             "particles.width (%g cm) must hold at least one surface wavelength (%g cm)", p->width,
             p->surf_wavelength);
  if (e->n == nerr0 && p->grid_out) /* before build_region allocates the lattice */
    memory_check(p, doc, sec, e);
  if (e->n != nerr0) {
    cpl_problem_free(p);
    return NULL;
  }
  p->deck_hash = dk_hash(doc, NULL);
  return p;
}

void cpl_problem_free(cpl_problem *p) {
  if (!p) return;
  cont_problem_free(p->grid_out);
  cont_problem_free(p->grid_live);
  cont_problem_free(p->gas_grid);
  free(p);
}

/* ---------------------------------------------------------------------------------------- */
/* Free-surface profile                                                                      */

typedef struct surface_modes {
  int n;
  double ky[64], kz[64], amp[64], phase[64];
  double lo, hi; /* range of the raw sum, for scaling to the peak-to-valley depth */
} surface_modes;

/* Height below the nominal surface (0 at the peaks, depth at the valleys). */
static double surface_drop(const cpl_problem *p, const surface_modes *m, double y, double z) {
  if (p->surface == SURF_FLAT || !(p->surf_depth > 0)) return 0.0;
  if (p->surface == SURF_GROOVES) {
    double lam = p->width / fmax(1.0, nearbyint(p->width / p->surf_wavelength));
    return 0.5 * p->surf_depth * (1 - cos(2 * CPL_PI * y / lam));
  }
  double s = 0;
  for (int k = 0; k < m->n; k++) s += m->amp[k] * cos(m->ky[k] * y + m->kz[k] * z + m->phase[k]);
  return p->surf_depth * (m->hi - s) / (m->hi - m->lo);
}

/* Random roughness: periodic modes with wavelengths from the box size down to the deck's
 * wavelength (the correlation length), random phases, amplitudes ∝ wavelength (a rough,
 * self-affine-like profile), scaled to the peak-to-valley depth Rz. */
static void surface_setup(const cpl_problem *p, surface_modes *m, bool three_d) {
  memset(m, 0, sizeof *m);
  if (p->surface != SURF_RANDOM) return;
  int my = (int)fmax(1.0, floor(p->width / p->surf_wavelength));
  int mz = three_d ? (int)fmax(1.0, floor(p->width_z / p->surf_wavelength)) : 0;
  uint64_t k = 0;
  for (int iy = 0; iy <= my && m->n < 64; iy++)
    for (int iz = 0; iz <= mz && m->n < 64; iz++) {
      if (!iy && !iz) continue;
      double ky = 2 * CPL_PI * iy / p->width, kz = three_d ? 2 * CPL_PI * iz / p->width_z : 0;
      double kk = sqrt(ky * ky + kz * kz);
      m->ky[m->n] = ky;
      m->kz[m->n] = kz;
      m->amp[m->n] = (0.5 + ptl_splitmix64_uniform((uint64_t)p->seed, k++)) / kk;
      m->phase[m->n] = 2 * CPL_PI * ptl_splitmix64_uniform((uint64_t)p->seed, k++);
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
/* Running                                                                                   */

/* Linear interpolation in a sampled history (constant beyond the ends). */
static double interp(size_t n, const double *t, const double *v, double x) {
  if (!n) return 0.0;
  if (x <= t[0]) return v[0];
  if (x >= t[n - 1]) return v[n - 1];
  size_t lo = 0, hi = n - 1;
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (t[mid] <= x) lo = mid;
    else hi = mid;
  }
  return v[lo] + (v[hi] - v[lo]) * (x - t[lo]) / (t[hi] - t[lo]);
}

/* Gas state from the live grid: only the gas layer beyond the sample counts. */
typedef struct gas_ctx {
  cont_grid *g;
  int gas_layer;
  double mu;
  double offset; /* particle frame − grid frame (two-way gas grid; 0 for the one-way grid) */
  /* momentum/energy return (drag.gas_return): the particle region's cross-section, which the
   * grid's per-cm² cells stand for, and the first failure */
  double area;
  ms_status st;
  double returned_p, returned_e; /* what the gas received (absolute, g·km/s and kJ) */
  cpl_gaslog *log;               /* sources recorded for checkpoints (NULL: none) */
  /* MPI, drag kicks: each rank's sources per grid cell (dp, de per cm²), summed over the ranks
   * before they enter the replicated grid (gas_return_sum); NULL otherwise */
  double *cell_src;
} gas_ctx;

/* The gas at x receives momentum −dp (along the grid axis: the 1D gas has no transverse
 * momentum, so dp[1], dp[2] are not represented) and energy −de (all of it, transverse motion
 * included: energy is conserved exactly), per cm² of the particle region's cross-section.
 * Outside the gas layer nothing is returned (nor was drag applied there). */
static void gas_deposit(void *user, const double x[3], double t0, double t1, const double dp[3],
                        double de) {
  (void)t0;
  (void)t1;
  gas_ctx *c = user;
  cont_sample s;
  if (c->st != MS_OK || !cont_grid_sample(c->g, x[0] - c->offset, &s) || s.layer != c->gas_layer)
    return;
  if (c->cell_src) {
    c->cell_src[2 * s.cell] -= dp[0] / c->area;
    c->cell_src[2 * s.cell + 1] -= de / c->area;
    return;
  }
  ms_status st = cont_grid_add_cell_source(c->g, s.cell, -dp[0] / c->area, -de / c->area);
  if (st != MS_OK) {
    c->st = st;
    return;
  }
  c->returned_p -= dp[0];
  c->returned_e -= de;
  if (c->log) cpl_gaslog_source(c->log, s.cell, -dp[0] / c->area, -de / c->area);
}

static bool grid_gas(void *user, const double x[3], double t, cpl_gas *out) {
  (void)t;
  const gas_ctx *c = user;
  cont_sample s;
  if (!cont_grid_sample(c->g, x[0] - c->offset, &s) || s.layer != c->gas_layer) return false;
  out->rho = s.rho;
  out->u[0] = s.u;
  out->u[1] = out->u[2] = 0;
  out->p = s.p;
  out->mu = c->mu;
  return true;
}

/* Rank 0 writes the CSV files (docs/mpi.md "The coupled problem on MPI ranks"); the other ranks
 * get NULL and write nothing. */
static FILE *open_csv(const ms_ctx *ctx, ms_afile *af, const char *name) {
  memset(af, 0, sizeof *af);
  if (ctx->rank != 0) return NULL;
  char *path = ms_out_path(ctx, name);
  ms_status s = ms_afile_open(af, path);
  free(path);
  return s == MS_OK ? af->f : NULL;
}

static ms_status commit_csv(ms_afile *af) { return af->f ? ms_afile_commit(af) : MS_OK; }

static ms_status write_table(const ms_ctx *ctx, const char *name, const cpl_fragments *fr, int kind,
                             const cpl_ejecta_sel *sel, const char *title) {
  if (ctx->rank != 0) return MS_OK;
  ms_afile af;
  FILE *f = open_csv(ctx, &af, name);
  if (!f) return MS_ERR_IO;
  switch (kind) {
  case 0:
    cpl_write_spectrum(f, fr, title);
    break;
  case 1:
    cpl_write_fragment_table(f, fr, title);
    break;
  case 2:
    cpl_write_cumulative(f, fr, title);
    break;
  case 3:
    cpl_write_histogram(f, fr, CPL_HIST_MASS, 30, title);
    break;
  case 4:
    cpl_write_histogram(f, fr, CPL_HIST_DIAMETER, 30, title);
    break;
  default:
    cpl_write_ejecta_velocity(f, fr, sel, title);
    break;
  }
  return commit_csv(&af);
}

/* View of the CD particles for the fragment search: piston and removed particles excluded. */
static cpl_particles particle_view(const ptl_state *ps, uint8_t *skip) {
  for (size_t i = 0; i < ps->n; i++) skip[i] = (ps->flags[i] & (PTL_DRIVEN | PTL_REMOVED)) != 0;
  cpl_particles v = {ps->n,
                     ps->x,
                     ps->y,
                     ps->dim == 3 ? ps->z : NULL,
                     ps->vx,
                     ps->vy,
                     ps->dim == 3 ? ps->vz : NULL,
                     ps->mass,
                     skip,
                     ps->gid}; /* fragments numbered by smallest gid: independent of the
                                * particle sorting and of the rank count */
  return v;
}

/* Fragments of the particle region (piston and removed particles excluded); on MPI ranks the
 * distributed search over owned particles + ghosts (docs/mpi.md "Fragments on MPI ranks"), after
 * which *view covers the owned particles only (each rank kicks and writes its own). */
static ms_status find_fragments(const ms_ctx *ctx, cd_sim *sim, cpl_fragments *fr,
                                const cpl_fragment_opts *fo, uint8_t *skip, int32_t *ghost_owner,
                                cpl_particles *view) {
  if (ctx->size < 2) {
    *view = particle_view(sim->p, skip);
    return cpl_fragments_find(fr, view, fo);
  }
  cd_sim_refresh_ghosts(sim);
  *view = particle_view(sim->p, skip);
  cd_sim_ghost_owners(sim, ghost_owner);
  ms_status st = cpl_fragments_find_dist(fr, view, sim->p->nlocal, ghost_owner, fo, ctx);
  view->n = sim->p->nlocal;
  return st;
}

/* MPI: the ranks' drag-kick sources, summed over the ranks in rank order (the same bits on every
 * rank), enter every rank's copy of the grid identically (cell order; serially they enter
 * particle by particle: the same sums to round-off, since a cell source is additive). */
static void gas_return_sum(gas_ctx *c) {
  const size_t ncell = cont_grid_ncells(c->g);
  double *src = c->cell_src;
  par_sum_doubles_ordered(src, 2 * ncell);
  c->cell_src = NULL;
  for (size_t k = 0; k < ncell && c->st == MS_OK; k++) {
    if (src[2 * k] == 0 && src[2 * k + 1] == 0) continue;
    c->st = cont_grid_add_cell_source(c->g, k, src[2 * k], src[2 * k + 1]);
    if (c->st == MS_OK) {
      c->returned_p += src[2 * k] * c->area;
      c->returned_e += src[2 * k + 1] * c->area;
      if (c->log) /* every rank logs the same sums: a restart replays them bit for bit */
        cpl_gaslog_source(c->log, k, src[2 * k], src[2 * k + 1]);
    }
  }
  memset(src, 0, 2 * ncell * sizeof *src);
  c->cell_src = src;
}

/* Drag on the detached fragments (their share of the fragment's force, cpl_drag_fragments) as a
 * velocity kick over `span`, and with drag.gas_return the opposite momentum and the energy into
 * the gas cell at each kicked particle. MS_ERR_UNSTABLE if the gas refused a return. */
static ms_status drag_kick(const cpl_problem *p, cpl_fragments *fr, const cpl_particles *view,
                           const cpl_ejecta_sel *sel, gas_ctx *gas, double t, double span,
                           ptl_state *ps, const uint8_t *skip, double *fx, double *fy, double *fz) {
  const size_t n = view->n;         /* owned particles: each rank kicks its own */
  double *cell_src = gas->cell_src; /* MPI: gas_deposit collects per cell */
  const bool three_d = ps->dim == 3;
  memset(fx, 0, n * sizeof *fx);
  memset(fy, 0, n * sizeof *fy);
  memset(fz, 0, n * sizeof *fz);
  cpl_drag_fragments(p->drag_law, fr, view, sel, grid_gas, gas, t, fx, fy, fz);
  for (size_t i = 0; i < n; i++) {
    if (skip[i] || (fx[i] == 0 && fy[i] == 0 && fz[i] == 0)) continue;
    double v0[3] = {ps->vx[i], ps->vy[i], three_d ? ps->vz[i] : 0.0};
    ps->vx[i] += fx[i] / ps->mass[i] * span;
    ps->vy[i] += fy[i] / ps->mass[i] * span;
    if (three_d) ps->vz[i] += fz[i] / ps->mass[i] * span;
    if (p->gas_return) {
      double v1[3] = {ps->vx[i], ps->vy[i], three_d ? ps->vz[i] : 0.0};
      double dp[3], de = 0, xi[3] = {ps->x[i], ps->y[i], three_d ? ps->z[i] : 0.0};
      for (int k = 0; k < 3; k++) {
        dp[k] = ps->mass[i] * (v1[k] - v0[k]);
        de += 0.5 * ps->mass[i] * (v1[k] * v1[k] - v0[k] * v0[k]);
      }
      gas_deposit(gas, xi, t, t, dp, de);
    }
  }
  if (cell_src) gas_return_sum(gas);
  return gas->st;
}

/* Transport of the detached fragments ahead of the free surface (sel) from t0 to the detector
 * plane det_x, the gas grid advancing in lock-step (transport.windows); arrivals and the
 * detector spectrum are written. */
static ms_status transport_phase(ms_ctx *ctx, cpl_problem *p, const cpl_fragments *fr,
                                 const cpl_ejecta_sel *sel, gas_ctx *gas, double t0, double det_x,
                                 double rho0) {
  ms_status st = MS_OK;
  cpl_transport_opts to;
  cpl_transport_opts_default(&to);
  to.law = (cpl_drag_law)p->drag_law;
  to.rho_p = rho0;
  to.det_x = det_x;
  cpl_transport *tr = cpl_transport_create(&to, grid_gas, gas);
  if (p->gas_return) cpl_transport_set_return(tr, gas_deposit, gas);
  /* keep each flight's fragment size g for the detector spectrum */
  int64_t *gcount = ms_calloc(fr->n + 1, sizeof *gcount);
  size_t nfl = 0, big = cpl_largest_fragment(fr);
  for (size_t k = 0; k < fr->n; k++) {
    if (!cpl_is_ejecta_with(fr, k, sel, big)) continue;
    double x[3] = {fr->cx[k], fr->cy[k], fr->cz[k]}, v[3] = {fr->vx[k], fr->vy[k], fr->vz[k]};
    cpl_transport_add(tr, fr->mass[k], x, v, t0);
    gcount[nfl++] = fr->count[k];
  }
  ms_log(ctx, MS_LOG_INFO,
         "coupled: 3/3 transport of %zu ejecta fragments to the detector at "
         "x = %g cm (%g cm beyond the free surface), until t = %g",
         nfl, to.det_x, p->det_distance, p->transport_end);
  ms_progress prog;
  ms_progress_start(&prog, ctx, "transport", t0, p->transport_end);
  for (long w = 1; w <= p->transport_windows && st == MS_OK; w++) {
    double tw = t0 + (p->transport_end - t0) * (double)w / (double)p->transport_windows;
    st = cont_grid_run_to(gas->g, tw);
    if (st != MS_OK) {
      ms_log(ctx, MS_LOG_ERROR, "coupled: gas grid: %s", cont_grid_error(gas->g));
      break;
    }
    ms_status s2 = cpl_transport_advance(tr, tw);
    if (s2 != MS_OK) /* a failed fragment is reported, the others fly on */
      ms_log(ctx, MS_LOG_WARN, "coupled: transport: %s", cpl_transport_error(tr));
    if (gas->st != MS_OK) {
      st = gas->st;
      ms_log(ctx, MS_LOG_ERROR, "coupled: gas return: %s", cont_grid_error(gas->g));
    }
    ms_progress_update(&prog, tw, w);
  }
  ms_progress_finish(&prog, p->transport_end, p->transport_windows);
  if (st == MS_OK) {
    ms_afile af;
    FILE *f = open_csv(ctx, &af, "arrivals.csv");
    if (!f && ctx->rank == 0) {
      st = MS_ERR_IO;
    } else if (f) {
      cpl_write_arrivals(f, tr, NULL);
      st = commit_csv(&af);
    }
    /* the spectrum at the detector: arrived fragments only */
    cpl_fragments det;
    memset(&det, 0, sizeof det);
    det.count = ms_calloc(nfl + 1, sizeof *det.count);
    det.mass = ms_calloc(nfl + 1, sizeof *det.mass);
    size_t narr = 0;
    double marr = 0;
    for (size_t i = 0; i < nfl; i++) {
      cpl_flight fl = cpl_transport_get(tr, i);
      if (fl.state != CPL_ARRIVED) continue;
      det.count[det.n] = gcount[i];
      det.mass[det.n] = fl.mass;
      det.n++;
      narr++;
      marr += fl.mass;
    }
    if (st == MS_OK) {
      f = open_csv(ctx, &af, "spectrum_detector.csv");
      if (!f && ctx->rank == 0) {
        st = MS_ERR_IO;
      } else if (f) {
        cpl_write_spectrum(f, &det, "fragment spectrum N(g) of the arrivals at the detector");
        st = commit_csv(&af);
      }
    }
    ms_log(ctx, MS_LOG_INFO, "coupled: %zu of %zu fragments (%.4g g) reached the detector", narr,
           nfl, marr);
    if (p->gas_return) {
      cont_balance gb = cont_grid_balance(gas->g);
      ms_log(ctx, MS_LOG_INFO,
             "coupled: the gas received momentum %.6g g*km/s and energy %.6g kJ from the "
             "fragments (grid sources per cm^2: %.6g, %.6g)",
             gas->returned_p, gas->returned_e, gb.source_momentum, gb.source_energy);
    }
    p->sum.gas_momentum = gas->returned_p;
    p->sum.gas_energy = gas->returned_e;
    p->sum.transported = nfl;
    p->sum.arrived = narr;
    free(det.count);
    free(det.mass);
  }
  free(gcount);
  cpl_transport_free(tr);
  return ctx->size > 1 ? par_agree_status(st) : st; /* rank 0's file errors */
}

/* MPI: the grids are replicated, every rank advancing its copy with the same operands (what
 * the ranks contribute enters through fixed-order sums or broadcasts). Guard: a digest of every
 * copy's node and cell arrays, compared over the ranks at the end of the run; a difference is an
 * internal error (MS_ERR_INTERNAL on every rank). Serial: nothing to compare. */
static ms_status check_replicated(const ms_ctx *ctx, const cont_grid *g1, const cont_grid *g2) {
  if (ctx->size < 2) return MS_OK;
  uint64_t h = 0xcbf29ce484222325ull; /* FNV-1a offset basis */
  const cont_grid *grids[2] = {g1, g2};
  for (int k = 0; k < 2; k++) {
    if (!grids[k]) continue;
    cont_view v = cont_grid_view(grids[k]);
    h = dk_hash_doubles(h, v.x, v.nnodes);
    h = dk_hash_doubles(h, v.u, v.nnodes);
    h = dk_hash_doubles(h, v.rho, v.ncells);
    h = dk_hash_doubles(h, v.e, v.ncells);
    h = dk_hash_doubles(h, v.p, v.ncells);
  }
  const int64_t mine = (int64_t)h, top = par_max_int64(mine);
  if (par_max_int(mine != top) == 0) {
    ms_log(ctx, MS_LOG_INFO, "coupled: the replicated grid is bitwise identical on all %d ranks",
           ctx->size);
    return MS_OK;
  }
  ms_log(ctx, MS_LOG_ERROR, "coupled: the replicated grid differs between the ranks (rank %d)",
         ctx->rank);
  return MS_ERR_INTERNAL;
}

/* The particle region between x_drive and x_drive + depth (lattice, surface profile, piston and
 * surface layers, pair table); the piston history is set by the caller. */
typedef struct region {
  cd_sim *sim;
  ptl_state *ps;
  cd_config cfg;
  const eos_t *eos;
  double rho0, c0, a, width, width_z, x_top, area;
  bool fcc;
} region;

static ms_status build_region(const ms_ctx *ctx, const cpl_problem *p, double x_drive, double depth,
                              region *r) {
  ms_status st;
  const eos_t *eos = p->mats->m[p->sample_mat].eos;
  const double rho0 = eos_rho0(eos), c0 = eos_c0(eos), a = p->spacing;
  const bool fcc = p->lattice == 1;
  const cd_lattice lat = fcc ? CD_LATTICE_FCC : CD_LATTICE_TRI2D;
  const double mass = rho0 * cd_cluster_volume(lat, a, p->thickness);
  /* lattice counts: tri2d with close-packed rows along y (row spacing √3/2 a in x);
   * fcc cubic cells √2 a */
  const double cell_x = fcc ? sqrt(2.0) * a : sqrt(3.0) * a, cell_y = fcc ? sqrt(2.0) * a : a;
  int nx = (int)fmax(2.0, nearbyint(depth / cell_x));
  int ny = (int)fmax(2.0, nearbyint(p->width / cell_y));
  int nz = fcc ? (int)fmax(2.0, nearbyint(p->width_z / cell_y)) : 1;
  const double width = ny * cell_y, width_z = fcc ? nz * cell_y : 0.0;
  const double x_top = x_drive + nx * cell_x; /* nominal free surface of the lattice */
  size_t ncap = (size_t)(fcc ? 4 : 2) * (size_t)nx * (size_t)ny * (size_t)nz;
  ptl_state *tmp = ptl_state_create(ncap, fcc ? 3 : 2);
  if (fcc) {
    double sh[3] = {0.25, 0.25, 0.25}, o[3] = {x_drive, 0, 0};
    cd_lattice_fcc(tmp, nx, ny, nz, sh, o, a, mass, 0);
  } else {
    /* generated as cd_lattice_tri's (x', y') = (y, x): rows of constant x hold neighbours */
    double sh[2] = {0.25, 0.25}, o[2] = {0, x_drive};
    cd_lattice_tri(tmp, ny, nx, sh, o, a, mass, 0);
    for (size_t i = 0; i < tmp->n; i++) {
      double t = tmp->x[i];
      tmp->x[i] = tmp->y[i];
      tmp->y[i] = t;
    }
  }
  surface_modes modes;
  surface_setup(p, &modes, fcc);
  ptl_state *ps = ptl_state_create(tmp->n, fcc ? 3 : 2);
  const double row = fcc ? 0.5 * sqrt(2.0) * a : 0.5 * sqrt(3.0) * a; /* layer spacing in x */
  for (size_t i = 0; i < tmp->n; i++) {
    double drop = surface_drop(p, &modes, tmp->y[i], tmp->z[i]);
    double top = x_top - drop;
    if (tmp->x[i] > top) continue;
    size_t j = ptl_state_add(ps, tmp->x[i], tmp->y[i], tmp->z[i], mass, 0);
    if (tmp->x[i] < x_drive + p->piston_rows * row) ps->flags[j] |= PTL_DRIVEN;
    else if (tmp->x[i] > top - row) ps->flags[j] |= PTL_SURFACE;
  }
  ptl_state_free(tmp);
  ms_log(ctx, MS_LOG_INFO,
         "coupled: particles: %s lattice, a = %g cm, %zu particles (%d x %d x %d cells), "
         "region %g..%g cm (grid: %g..%g), width %g cm, surface %s (depth %g cm)",
         lattice_names[p->lattice], a, ps->n, nx, ny, nz, x_drive, x_top, x_drive, x_drive + depth,
         width, surface_names[p->surface], p->surf_depth);

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
  cfg.skin = 0.1 * a;
  cfg.dt = p->dt > 0 ? p->dt : p->dt_factor * a / c0;
  cfg.cutoff = p->cutoff_mode == 1 ? CD_CUTOFF_BONDED : CD_CUTOFF_PLAIN;
  cfg.damping_gamma = p->damping_j > 0 ? c0 / (p->damping_j * a) : 0.0;
  cfg.lattice = lat;
  cfg.thickness = p->thickness;
  cd_sim *sim = cd_sim_create(ps, &box, &cfg, 1);
  cd_pair_table *tab = ms_calloc(1, sizeof *tab);
  st = cd_pair_table_build(tab, eos, eos, lat, a, p->thickness, p->cutoff * a, 0.5 * a, 1.0, 0);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR,
           "coupled: cannot build the pair potential of the sample material "
           "(cold curve missing or not finite on [0.5a, R_c])");
    free(tab);
    cd_sim_free(sim);
    return st;
  }
  cd_sim_set_pair(sim, 0, 0, tab);
  r->sim = sim;
  r->ps = ps;
  r->cfg = cfg;
  r->eos = eos;
  r->rho0 = rho0;
  r->c0 = c0;
  r->a = a;
  r->fcc = fcc;
  r->width = width;
  r->width_z = width_z;
  r->x_top = x_top;
  r->area = fcc ? width * width_z : width * p->thickness;
  return MS_OK;
}

/* MPI: every rank built the whole region; cd_sim_init keeps what each rank's coarse cells own
 * (the cluster_dynamics defaults: auto partition, rebalance above 1.2 checked every 10 list
 * builds). Serial: nothing to do. */
static void distribute_region(const ms_ctx *ctx, cd_sim *sim) {
  if (ctx->size < 2) return;
  const cd_mpi_config mc = {.partition = CD_PART_AUTO,
                            .rebalance_threshold = 1.2,
                            .rebalance_interval = 10,
                            .replicated = true};
  cd_sim_set_mpi(sim, &mc);
}

/* A particle step failed: the guard's finding (cd_sim_guard: step, time on the particles' clock,
 * particle, quantity) and the state it found, particles_unstable.h5 (docs/reliability.md §5). */
static void particles_unstable(const ms_ctx *ctx, cd_sim *sim, ms_status st, double t_start) {
  ms_log(ctx, MS_LOG_ERROR, "coupled: particles (clock started at t = %g): %s", t_start,
         st == MS_ERR_UNSTABLE ? cd_sim_error(sim) : ms_status_str(st));
  char *path = ms_out_path(ctx, "particles_unstable.h5");
  if (cd_write_snapshot(sim, path) == MS_OK)
    ms_log(ctx, MS_LOG_ERROR, "coupled: final state written to particles_unstable.h5");
  free(path);
}

/* Particle steps between checkpoints: time.checkpoint_every, or checkpoint_time rounded to whole
 * steps of dt (0: none). */
static long checkpoint_steps(const cpl_problem *p, double dt) {
  if (p->checkpoint_every > 0) return p->checkpoint_every;
  return p->checkpoint_time > 0 ? lround(fmax(1.0, p->checkpoint_time / dt)) : 0;
}

/* Σ fx over this rank's driven particles (the piston layer's force, this rank's share). */
static double driven_force_local(const ptl_state *ps) {
  double f = 0;
  for (size_t i = 0; i < ps->nlocal; i++)
    if (ps->flags[i] & PTL_DRIVEN) f += ps->fx[i];
  return f;
}

/* Two-way coupling (docs/coupling.md §6): the grid ends at the interface node and runs through
 * the continuum problem's own loop (profiles, histories, x–t data as in a grid-only run); per
 * grid step the node gets the impulse the particles received in the previous step as a
 * traction (before the step), then the particles sub-cycle with the piston moving at the node's
 * mean velocity over the step, so the piston follows the node's displacement exactly (after
 * it). With a `gas:` section a second grid carries the gas beyond the particles' free surface:
 * its first node moves with the particles' free-surface velocity, and detached fragments ahead
 * of it feel its drag and are transported through it as in the one-way run. */
typedef struct two_way {
  ms_ctx *ctx;
  cpl_problem *p;
  size_t node;
  region reg;
  FILE *f_if, *f_ej;
  cpl_fragments fr;
  cpl_fragment_opts fo;
  cpl_ejecta_sel sel;
  uint8_t *skip;
  int32_t *ghost_owner; /* MPI: owner rank of each ghost (fragment search) */
  double *fx, *fy, *fz;
  double ta, xa, traction; /* interface node before the current grid step; its load */
  cpl_two_way_acc acc;     /* impulse and work exchanged so far (acc.gsteps unused: gsteps) */
  double f_prev;           /* force on this rank's driven particles after the last particle step */
  long gsteps, psteps, next_out, last_search;
  gas_ctx gas; /* gas.g == NULL: no gas section */
  /* checkpoints (docs/coupling.md §7b): every ckpt_every particle steps, at the end of a grid
   * step; ls.gaslog records the tractions and what was done to the gas grid. A restart replays
   * the log through the grid's own loop until gsteps reaches replay_gsteps, then goes live. */
  long ckpt_every, next_ckpt, replay_gsteps;
  size_t replay_pos;
  cpl_loop_state ls;
  ms_afile *csv[2];
  int ncsv;
} two_way;

/* Restart: the next logged row, which must be of `kind` (else the log does not fit the deck). */
static const double *replay_row(two_way *w, int kind) {
  const cpl_gaslog *l = &w->ls.gaslog;
  if (w->replay_pos >= l->n || l->row[4 * w->replay_pos] != kind) return NULL;
  return l->row + 4 * w->replay_pos++;
}

static ms_status two_way_before(void *user, cont_grid *g) {
  two_way *w = user;
  if (w->gsteps < w->replay_gsteps) { /* restart: the logged traction */
    const double *r = replay_row(w, CPL_LOG_TRACTION);
    if (!r) {
      ms_log(w->ctx, MS_LOG_ERROR, "coupled: the checkpoint's grid log ends early");
      return MS_ERR_INPUT;
    }
    cont_grid_set_node_force(g, w->node, r[1]);
    return MS_OK;
  }
  /* the particles push the node towards −x: the traction hands the grid the impulse the
   * particles received and the grid has not yet (`owed`, normally the last step's), spread
   * over the expected step; what a different step size leaves over is carried on, so the
   * exchange conserves momentum exactly up to the impulse in flight */
  w->traction = w->acc.dtg_last > 0 ? -w->acc.owed / w->acc.dtg_last : 0.0;
  cont_grid_set_node_force(g, w->node, w->traction);
  if (w->ls.gaslog.on) cpl_gaslog_traction(&w->ls.gaslog, w->traction);
  w->ta = cont_grid_time(g);
  w->xa = cont_grid_view(g).x[w->node];
  return MS_OK;
}

/* Fragments, ejected mass and the drag kick since the last search (gas section only). */
static ms_status two_way_fragments(two_way *w, double t) {
  cpl_problem *p = w->p;
  ptl_state *ps = w->reg.ps;
  cpl_particles view;
  ms_status st = find_fragments(w->ctx, w->reg.sim, &w->fr, &w->fo, w->skip, w->ghost_owner, &view);
  if (st != MS_OK || !w->gas.g) return st;
  /* ejecta: detached fragments ahead of the gas grid's first node (the particles' free surface
   * as the gas sees it) */
  w->sel.plane = cont_grid_view(w->gas.g).x[0] + w->gas.offset;
  double row[3] = {t, cpl_ejected_mass(&w->fr, &w->sel), (double)w->fr.n};
  if (w->f_ej) ms_csv_row(w->f_ej, 3, row);
  if (p->drag_law != CPL_DRAG_NONE) {
    double span = (double)(w->psteps - w->last_search) * w->reg.sim->cfg.dt;
    st = drag_kick(p, &w->fr, &view, &w->sel, &w->gas, t, span, ps, w->skip, w->fx, w->fy, w->fz);
    if (st != MS_OK)
      ms_log(w->ctx, MS_LOG_ERROR, "coupled: gas return: %s", cont_grid_error(w->gas.g));
  }
  w->last_search = w->psteps;
  return st;
}

/* Restart: what the logged grid step did to the gas grid (velocity, advance, drag sources). */
static ms_status two_way_replay(two_way *w) {
  const cpl_gaslog *l = &w->ls.gaslog;
  ms_status st = MS_OK;
  while (st == MS_OK && w->replay_pos < l->n && l->row[4 * w->replay_pos] != CPL_LOG_TRACTION)
    st = w->gas.g ? cpl_gaslog_apply(l->row + 4 * w->replay_pos++, w->gas.g) : MS_ERR_INPUT;
  if (st == MS_OK && ++w->gsteps == w->replay_gsteps && w->replay_pos != l->n) st = MS_ERR_INPUT;
  if (st != MS_OK)
    ms_log(w->ctx, MS_LOG_ERROR,
           "coupled: replaying the checkpoint's grid log failed at entry "
           "%zu (grid step %ld)",
           w->replay_pos, w->gsteps);
  return st;
}

/* Checkpoint at the end of a grid step: the particles refreshed (cd_sim_refresh, as the restart
 * will), the accumulators, the log and the streamed CSV text (cpl_checkpoint_write). */
static ms_status two_way_checkpoint(two_way *w) {
  w->ls.step = w->psteps, w->ls.next_out = w->next_out, w->ls.last_search = w->last_search;
  w->ls.returned_p = w->gas.returned_p, w->ls.returned_e = w->gas.returned_e;
  w->ls.tw = w->acc;
  w->ls.tw.gsteps = (double)w->gsteps;
  ms_status st = cpl_checkpoint_write(w->ctx, w->p->deck_hash, w->reg.sim, &w->ls, w->csv, w->ncsv);
  w->f_prev = driven_force_local(w->reg.ps); /* the refresh recomputed the forces */
  return st;
}

static ms_status two_way_after(void *user, cont_grid *g) {
  two_way *w = user;
  if (w->gsteps < w->replay_gsteps) return two_way_replay(w);
  cpl_problem *p = w->p;
  cd_sim *sim = w->reg.sim;
  ptl_state *ps = w->reg.ps;
  const double area = w->reg.area;
  ms_status st = MS_OK;
  w->gsteps++;
  double tb = cont_grid_time(g), xb = cont_grid_view(g).x[w->node], dtg = tb - w->ta;
  double ubar = (xb - w->xa) / dtg;
  w->acc.Jg += w->traction * dtg;
  w->acc.Wg += w->traction * (xb - w->xa);
  w->acc.owed += w->traction * dtg;
  /* sub-cycle: whole number of particle steps over the grid step */
  long nsub = (long)ceil(dtg / w->reg.cfg.dt * (1 - 1e-12));
  if (nsub < 1) nsub = 1;
  sim->cfg.dt = dtg / (double)nsub;
  sim->piston.t[0] = sim->t;
  sim->piston.t[1] = sim->t + dtg;
  sim->piston.u[0] = sim->piston.u[1] = ubar;
  double imp = 0;
  for (long k = 0; k < nsub && st == MS_OK; k++) {
    st = cd_sim_step(sim); /* MPI: the status is the same on every rank */
    w->psteps++;
    const double f = driven_force_local(ps);
    /* impulse on the particles from the piston: velocity Verlet's ½(F_old + F_new) Δt */
    imp += -0.5 * (w->f_prev + f) * sim->cfg.dt;
    w->f_prev = f;
  }
  if (st != MS_OK) {
    particles_unstable(w->ctx, sim, st, 0.0);
    return st;
  }
  /* MPI: each rank holds the impulse on its own driven particles (linear in their forces, so the
   * shares add up to the whole even when driven particles migrate between the sub-steps); one
   * fixed-order sum per grid step gives every rank the same bits, so the replicated grids stay
   * bitwise equal (docs/mpi.md "The coupled problem on MPI ranks") */
  if (w->ctx->size > 1) par_sum_doubles_ordered(&imp, 1);
  /* the piston's work on the particles: velocity Verlet's ½(F_old + F_new)·Δs with Δs = ū Δt
   * over every sub-step, i.e. ū × impulse (cd_sim's piston_work to round-off; this sum is the
   * same on every rank and continues bit for bit after a restart) */
  w->acc.w_before = w->acc.Wp;
  w->acc.Wp += ubar * imp;
  w->acc.p_avg = imp / (dtg * area);
  w->acc.Jp += w->acc.p_avg * dtg;
  w->acc.owed += w->acc.p_avg * dtg;
  w->acc.dtg_last = dtg;
  double ufs = cd_free_surface_velocity(sim, 0);
  if (w->ctx->size > 1) /* an all-reduced mean: rank 0's bits drive every rank's gas grid */
    par_bcast_doubles(&ufs, 1, 0);
  if (w->gas.g) {
    /* the gas ahead is pushed by the particles' free surface */
    cont_grid_set_node_velocity(w->gas.g, 0, ufs);
    st = cont_grid_run_to(w->gas.g, tb);
    if (w->ls.gaslog.on) {
      cpl_gaslog_velocity(&w->ls.gaslog, ufs);
      cpl_gaslog_run_to(&w->ls.gaslog, tb);
    }
    if (st != MS_OK) {
      ms_log(w->ctx, MS_LOG_ERROR, "coupled: gas grid: %s", cont_grid_error(w->gas.g));
      return st;
    }
  }
  double row[8] = {tb, ubar, w->acc.p_avg, ufs, w->acc.Jg, w->acc.Jp, w->acc.Wg, w->acc.Wp / area};
  if (w->f_if) ms_csv_row(w->f_if, 8, row);
  bool out_now = tb >= p->t_end * (double)w->next_out / (double)p->n_out * (1 - 1e-12);
  if (out_now || (w->gas.g && w->psteps - w->last_search >= p->frag_every)) {
    st = two_way_fragments(w, tb);
    if (st != MS_OK) return st;
  }
  if (out_now) {
    char name[64];
    snprintf(name, sizeof name, "particles_%04ld.h5", w->next_out);
    char *path = ms_out_path(w->ctx, name);
    cpl_particles view = particle_view(ps, w->skip);
    view.n = ps->nlocal; /* MPI: written collectively, each rank its owned particles */
    cpl_snapshot_info info = {tb, w->reg.a, w->reg.rho0, w->fo.box};
    st = cpl_write_snapshot(path, &view, &w->fr, &info);
    free(path);
    ms_log(w->ctx, MS_LOG_INFO,
           "coupled: two-way t = %.5g: %ld grid steps, %ld particle steps; interface u = %.5g "
           "km/s, p = %.5g GPa; impulse grid %.6g vs particles %.6g, work grid %.6g vs "
           "particles %.6g (per cm^2); %zu fragments",
           tb, w->gsteps, w->psteps, ubar, w->acc.p_avg, w->acc.Jg, w->acc.Jp, w->acc.Wg,
           w->acc.Wp / area, w->fr.n);
    w->next_out++;
  }
  p->sum.u_interface = ubar;
  p->sum.u_free_surface = ufs;
  if (st == MS_OK && w->ckpt_every > 0 && w->psteps >= w->next_ckpt) {
    st = two_way_checkpoint(w);
    w->next_ckpt = (w->psteps / w->ckpt_every + 1) * w->ckpt_every;
  }
  return st;
}

static ms_status run_two_way(ms_ctx *ctx, cpl_problem *p) {
  two_way w;
  memset(&w, 0, sizeof w);
  w.ctx = ctx;
  w.p = p;
  w.next_out = 1;
  cont_grid *g = cont_problem_grid(p->grid_live);
  w.node = cont_grid_history(g, p->tag_drive).node;
  const double x_if0 = cont_grid_view(g).x[w.node];
  ms_status st = build_region(ctx, p, x_if0, p->depth, &w.reg);
  if (st != MS_OK) return st;
  cd_sim *sim = w.reg.sim;
  ptl_state *ps = w.reg.ps;
  double th[2] = {0, 1}, uh[2] = {0, 0}, dir[3] = {1, 0, 0};
  cd_history ph = {2, th, uh};
  cd_sim_set_piston(sim, &ph, dir);
  /* MPI: the particles distributed as in the one-way run; the grids replicated (every rank
   * advances them alike; docs/mpi.md "The coupled problem on MPI ranks") */
  const bool dist = ctx->size > 1;
  const size_t nglobal = ps->n; /* owned + ghosts never exceed it */
  distribute_region(ctx, sim);
  st = ctx->restart ? MS_OK : cd_sim_init(sim); /* a restart initialises from its checkpoint */
  if (st != MS_OK) {
    cd_sim_free(sim);
    return st;
  }
  w.ckpt_every = checkpoint_steps(p, w.reg.cfg.dt);
  w.next_ckpt = w.ckpt_every;
  w.ls.gaslog.on = w.ckpt_every > 0;
  ms_afile af_if, af_ej;
  w.f_if = open_csv(ctx, &af_if, "interface.csv");
  w.f_ej = p->gas_grid ? open_csv(ctx, &af_ej, "ejecta_mass.csv") : NULL;
  w.csv[0] = &af_if, w.csv[1] = &af_ej, w.ncsv = p->gas_grid ? 2 : 1;
  st = ctx->rank == 0 && (!w.f_if || (p->gas_grid && !w.f_ej)) ? MS_ERR_IO : MS_OK;
  if (dist) st = par_agree_status(st);
  if (st != MS_OK) {
    if (w.f_if) ms_afile_abort(&af_if);
    if (w.f_ej) ms_afile_abort(&af_ej);
    cd_sim_free(sim);
    return st;
  }
  static const char *const names[] = {"t",      "u_interface", "p_particles", "u_free_surface",
                                      "J_grid", "J_particles", "W_grid",      "W_particles"};
  static const char *const units[] = {"10us",     "km/s",     "GPa",     "km/s",
                                      "GPa*10us", "GPa*10us", "kJ/cm^2", "kJ/cm^2"};
  if (w.f_if && !ctx->restart) /* a restart writes back the text so far */
    ms_csv_header(w.f_if,
                  "two-way interface: node velocity, particle pressure, impulse and work "
                  "per unit area as the grid and the particles received them",
                  8, names, units);
  if (w.f_ej && !ctx->restart) {
    static const char *const ejn[] = {"t", "M_ej", "fragments"};
    static const char *const eju[] = {"10us", "g", "1"};
    ms_csv_header(w.f_ej,
                  "ejected mass (fragments but the largest, ahead of the particles' "
                  "free surface) vs time",
                  3, ejn, eju);
  }
  cpl_fragments_init(&w.fr);
  w.fo.bond = p->bond;
  w.fo.spacing = w.reg.a;
  w.fo.rho0 = w.reg.rho0;
  w.fo.box.period[1] = w.reg.width;
  if (w.reg.fcc) w.fo.box.period[2] = w.reg.width_z;
  cpl_ejecta_sel_default(&w.sel);
  w.skip = ms_calloc(nglobal + 1, 1);
  w.ghost_owner = dist ? ms_calloc(nglobal + 1, sizeof *w.ghost_owner) : NULL;
  w.fx = ms_calloc(nglobal + 1, sizeof(double));
  w.fy = ms_calloc(nglobal + 1, sizeof(double));
  w.fz = ms_calloc(nglobal + 1, sizeof(double));
  if (p->gas_grid) {
    cont_grid *gg = cont_problem_grid(p->gas_grid);
    /* the gas grid's first node sits on the particles' nominal free surface */
    w.gas = (gas_ctx){gg,
                      p->gas_layer,
                      p->mats->m[p->gas_mat].viscosity,
                      w.reg.x_top - cont_grid_view(gg).x[0],
                      w.reg.area,
                      MS_OK,
                      0,
                      0,
                      NULL,
                      NULL};
    if (dist && p->gas_return) /* per-cell sources summed over the ranks (gas_return_sum) */
      w.gas.cell_src = ms_calloc(2 * cont_grid_ncells(gg) + 1, sizeof *w.gas.cell_src);
    w.gas.log = w.ls.gaslog.on ? &w.ls.gaslog : NULL;
  }
  if (ctx->restart) {
    st = cpl_checkpoint_restore(ctx, p->deck_hash, sim, &w.ls, NULL, w.csv, w.ncsv);
    const size_t nckpt = dist ? (size_t)par_sum_long((long)sim->p->nlocal) : sim->p->n;
    if (st == MS_OK && nckpt != nglobal) {
      ms_log(ctx, MS_LOG_ERROR, "coupled: the checkpoint holds %zu particles, this deck %zu", nckpt,
             nglobal);
      st = MS_ERR_INPUT;
    }
    ps = w.reg.ps = sim->p;
    w.psteps = w.ls.step, w.next_out = w.ls.next_out, w.last_search = w.ls.last_search;
    w.acc = w.ls.tw;
    w.replay_gsteps = (long)w.ls.tw.gsteps;
    w.gas.returned_p = w.ls.returned_p, w.gas.returned_e = w.ls.returned_e;
    if (w.ckpt_every > 0) /* (a deck without checkpoints fails the deck-hash check above) */
      w.next_ckpt = (w.psteps / w.ckpt_every + 1) * w.ckpt_every;
  }
  w.f_prev = driven_force_local(ps);
  ms_log(ctx, MS_LOG_INFO,
         "coupled: two-way: grid node %zu at x = %g, particle region %g cm, particle dt %g%s",
         w.node, x_if0, p->depth, w.reg.cfg.dt,
         p->gas_grid ? ", gas grid beyond the free surface" : "");
  cont_step_hooks hooks = {two_way_before, two_way_after, &w, p->t_end};
  if (st == MS_OK) st = cont_problem_run_hooked(ctx, p->grid_live, &hooks);
  if (st == MS_OK && w.gsteps < w.replay_gsteps) {
    ms_log(ctx, MS_LOG_ERROR, "coupled: the checkpoint is beyond the end of this deck's run");
    st = MS_ERR_INPUT;
  }
  ms_status s2 = commit_csv(&af_if);
  if (st == MS_OK) st = s2;
  if (w.f_ej) {
    s2 = commit_csv(&af_ej);
    if (st == MS_OK) st = s2;
  }
  /* the transport runs replicated and deposits its returns directly (not checkpointed) */
  free(w.gas.cell_src);
  w.gas.cell_src = NULL;
  w.gas.log = NULL;
  cpl_gaslog_free(&w.ls.gaslog);
  if (st == MS_OK) st = write_table(ctx, "spectrum.csv", &w.fr, 0, NULL, NULL);
  if (dist) /* rank 0's file errors stop every rank */
    st = par_agree_status(st);
  if (p->gas_grid) /* at the end of the particle phase (the transport moves it on) */
    p->sum.gas_shift = cont_grid_view(w.gas.g).x[0] + w.gas.offset - w.reg.x_top;
  if (st == MS_OK && p->gas_grid) {
    const char *tables[] = {"fragments.csv", "cumulative.csv", "mass_hist.csv", "diameter_hist.csv",
                            "ejecta_velocity.csv"};
    for (int k = 0; k < 5 && st == MS_OK; k++)
      st = write_table(ctx, tables[k], &w.fr, k + 1, &w.sel, NULL);
    if (dist) st = par_agree_status(st);
    if (st == MS_OK && p->det_distance > 0 && p->transport_end > cont_grid_time(g))
      st = transport_phase(ctx, p, &w.fr, &w.sel, &w.gas, cont_grid_time(g),
                           w.reg.x_top + p->det_distance, w.reg.rho0);
  }
  p->sum.particles = nglobal;
  p->sum.steps = w.psteps;
  p->sum.fragments = w.fr.n;
  p->sum.ejected_mass = p->gas_grid ? cpl_ejected_mass(&w.fr, &w.sel) : 0.0;
  /* the particles' last grid step is in flight: the grid receives its counterpart in its next
   * step; compare what both sides have exchanged so far */
  p->sum.impulse_grid = w.acc.Jg;
  p->sum.impulse_particles = w.acc.Jp - w.acc.owed;
  p->sum.work_grid = w.acc.Wg;
  p->sum.work_particles = w.acc.w_before / w.reg.area;
  p->sum.piston_work = w.acc.Wp;
  if (st == MS_OK) st = check_replicated(ctx, g, w.gas.g);
  const double jsum = w.acc.Jg + p->sum.impulse_particles, wsum = w.acc.Wg + p->sum.work_particles;
  ms_log(ctx, MS_LOG_INFO,
         "coupled: two-way interface balance (per cm^2, the last grid step's exchange in "
         "flight excluded): impulse grid %.6g + particles %.6g = %.3g (%.2g of it); work grid "
         "%.6g + particles %.6g = %.3g (%.2g of it)",
         w.acc.Jg, p->sum.impulse_particles, jsum,
         jsum / fmax(fabs(p->sum.impulse_particles), 1e-300), w.acc.Wg, p->sum.work_particles, wsum,
         wsum / fmax(fabs(p->sum.work_particles), 1e-300));
  cpl_fragments_free(&w.fr);
  free(w.skip);
  free(w.ghost_owner);
  free(w.fx);
  free(w.fy);
  free(w.fz);
  cd_sim_free(sim);
  return st;
}

/* Under MPI rank 0 ran the grid (cont_problem_run); the tag history h (t, x, u, p_right) goes to
 * every rank, into *buf (the caller frees it). Serial: nothing to do. */
static void share_history(const ms_ctx *ctx, cont_history *h, double **buf) {
  *buf = NULL;
  if (ctx->size < 2) return;
  double nd = (double)h->n;
  par_bcast_doubles(&nd, 1, 0);
  const size_t n = (size_t)nd;
  double *b = ms_calloc(4 * n + 1, sizeof *b);
  if (ctx->rank == 0) {
    memcpy(b, h->t, n * sizeof *b);
    memcpy(b + n, h->x, n * sizeof *b);
    memcpy(b + 2 * n, h->u, n * sizeof *b);
    memcpy(b + 3 * n, h->p_right, n * sizeof *b);
  }
  par_bcast_doubles(b, 4 * n, 0);
  h->n = n, h->t = b, h->x = b + n, h->u = b + 2 * n, h->p_right = b + 3 * n;
  *buf = b;
}

/* The bulk (the fragment holding the deepest particle along x) over all ranks: a one-particle
 * view of the global deepest particle for cpl_ejecta_classify, so it classifies as serially. */
static void classify_dist(const cpl_fragments *fr, const cpl_particles *view, double u_ref,
                          double margin, cpl_ejecta_classes *out) {
  double deepest = INFINITY;
  for (size_t i = 0; i < view->n && i < fr->n_particles; i++)
    if (fr->id[i] >= 0 && view->x[i] < deepest) deepest = view->x[i];
  const double dmin = par_min_double(deepest);
  int64_t bulk = -1;
  for (size_t i = 0; i < view->n && i < fr->n_particles; i++)
    if (fr->id[i] >= 0 && view->x[i] == dmin) bulk = fr->id[i] > bulk ? fr->id[i] : bulk;
  bulk = par_max_int64(bulk);
  double zero = 0;
  cpl_particles one = {.n = bulk >= 0 ? 1 : 0, .x = &dmin, .y = &zero};
  cpl_fragments f1 = *fr; /* shallow: the table, and the bulk particle's id */
  f1.id = &bulk;
  f1.n_particles = 1;
  const double normal[3] = {1, 0, 0};
  cpl_ejecta_classify(&f1, &one, normal, u_ref, margin, out);
}

ms_status cpl_problem_run(ms_ctx *ctx, cpl_problem *p) {
  if (p->drive_mode == DRIVE_TWO_WAY) return run_two_way(ctx, p);
  ms_status st;
  /* 1. the grid alone, with its own outputs */
  ms_log(ctx, MS_LOG_INFO, "coupled: 1/3 grid run (U(t) of the drive node)");
  st = cont_problem_run(ctx, p->grid_out);
  if (st != MS_OK) return st;
  const cont_grid *gout = cont_problem_grid(p->grid_out);
  cont_history hd = cont_grid_history(gout, p->tag_drive);
  cont_history hf = cont_grid_history(gout, p->tag_fs);
  double *hd_buf, *hf_buf; /* MPI: rank 0's histories on every rank */
  share_history(ctx, &hd, &hd_buf);
  share_history(ctx, &hf, &hf_buf);
  cpl_piston drive, fsurf;
  if (cpl_piston_build(&drive, hd.n, hd.t, hd.x, hd.u) != MS_OK ||
      cpl_piston_build(&fsurf, hf.n, hf.t, hf.x, hf.u) != MS_OK) {
    free(hd_buf);
    free(hf_buf);
    ms_log(ctx, MS_LOG_ERROR,
           "coupled: the grid's tag histories are unusable (non-finite or "
           "not increasing in time)");
    return MS_ERR_INTERNAL;
  }
  ms_log(ctx, MS_LOG_INFO,
         "coupled: drive history '%s': %zu samples, max displacement correction %.3g km/s "
         "(0 for the conservative cross scheme)",
         hd.name, hd.n, drive.max_correction);

  /* particle phase starts a little before the drive node moves (saves steps) */
  double umax = 0;
  for (size_t k = 0; k < hd.n; k++) umax = fmax(umax, fabs(hd.u[k]));
  size_t k0 = 0;
  while (k0 + 1 < hd.n && fabs(hd.u[k0 + 1]) <= 1e-3 * umax) k0++;
  double t_start = hd.t[k0];
  if (!(p->t_end > t_start)) {
    ms_log(ctx, MS_LOG_ERROR, "coupled: time.end = %g is before the drive node moves (t = %g)",
           p->t_end, t_start);
    cpl_piston_free(&drive);
    cpl_piston_free(&fsurf);
    free(hd_buf);
    free(hf_buf);
    return MS_ERR_INPUT;
  }
  if (p->t_end > hd.t[hd.n - 1])
    ms_log(ctx, MS_LOG_WARN,
           "coupled: the particle phase (to %g) outlasts the grid run (%g): "
           "the piston keeps the last velocity",
           p->t_end, hd.t[hd.n - 1]);

  /* 2. the particle region */
  const double x_drive = hd.x[0], x_fs = hf.x[0], depth = x_fs - x_drive;
  region reg;
  st = build_region(ctx, p, x_drive, depth, &reg);
  if (st != MS_OK) {
    cpl_piston_free(&drive);
    cpl_piston_free(&fsurf);
    free(hd_buf);
    free(hf_buf);
    return st;
  }
  cd_sim *sim = reg.sim;
  ptl_state *ps = reg.ps;
  const cd_config cfg = reg.cfg;
  const double rho0 = reg.rho0, c0 = reg.c0, a = reg.a, width = reg.width, width_z = reg.width_z;
  const bool fcc = reg.fcc;
  /* piston: the drive history from the particle phase's start (relative time) */
  cd_history ph;
  ph.n = hd.n - k0;
  ph.t = ms_calloc(ph.n < 2 ? 2 : ph.n, sizeof(double));
  ph.u = ms_calloc(ph.n < 2 ? 2 : ph.n, sizeof(double));
  for (size_t k = 0; k < ph.n; k++) {
    ph.t[k] = hd.t[k0 + k] - t_start;
    ph.u[k] = hd.u[k0 + k];
  }
  double dir[3] = {1, 0, 0};
  if (p->drive_mode == 1) ph.n = 2; /* rewritten in place every step (transmitting piston) */
  cd_sim_set_piston(sim, &ph, dir);
  free(ph.t);
  free(ph.u);
  /* transmitting piston (docs/coupling.md §5): u = U_g + (p_g − p_particles)/Z passes waves
   * coming from the particle side out of the region instead of reflecting them; Z defaults to
   * ρ0 c_L with c_L = √1.5 c0, the longitudinal speed of a nearest-neighbour central-force
   * lattice (2D triangular and fcc [100] alike) */
  const double Z = p->impedance > 0 ? p->impedance : sqrt(1.5) * rho0 * c0;
  const double area = reg.area;
  double p_particles = 0.0; /* pressure of the particles on the piston layer, last step */
  const bool dist = ctx->size > 1;
  const size_t nglobal = ps->n;
  distribute_region(ctx, sim);
  st = ctx->restart ? MS_OK : cd_sim_init(sim); /* a restart initialises from its checkpoint */
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR, "coupled: particle set-up failed (%s)", ms_status_str(st));
    cd_sim_free(sim);
    cpl_piston_free(&drive);
    cpl_piston_free(&fsurf);
    free(hd_buf);
    free(hf_buf);
    return st;
  }

  /* 3. the particle phase, with the live grid supplying the gas */
  cont_grid *glive = cont_problem_grid(p->grid_live);
  gas_ctx gas = {glive, p->gas_layer, p->mats->m[p->gas_mat].viscosity, 0.0, reg.area, MS_OK, 0, 0,
                 NULL,  NULL};
  if (dist && p->gas_return) /* the transport phase runs replicated: it deposits directly */
    gas.cell_src = ms_calloc(2 * cont_grid_ncells(glive) + 1, sizeof *gas.cell_src);
  cpl_loop_state ls = {0}; /* checkpoints (set up below) */
  cpl_fragments fr;
  cpl_fragments_init(&fr);
  cpl_fragment_opts fo;
  memset(&fo, 0, sizeof fo);
  fo.bond = p->bond;
  fo.spacing = a;
  fo.rho0 = rho0;
  fo.box.period[1] = width;
  if (fcc) fo.box.period[2] = width_z;
  cpl_ejecta_sel sel;
  cpl_ejecta_sel_default(&sel);
  size_t n = nglobal; /* owned + ghosts never exceed the global count */
  uint8_t *skip = ms_calloc(n + 1, 1);
  int32_t *ghost_owner = dist ? ms_calloc(n + 1, sizeof *ghost_owner) : NULL;
  double *fx = ms_calloc(n + 1, sizeof(double)), *fy = ms_calloc(n + 1, sizeof(double)),
         *fz = ms_calloc(n + 1, sizeof(double));
  ms_afile af_ej, af_fs;
  FILE *f_ej = open_csv(ctx, &af_ej, "ejecta_mass.csv");
  FILE *f_fs = open_csv(ctx, &af_fs, "free_surface.csv");
  st = ctx->rank == 0 && (!f_ej || !f_fs) ? MS_ERR_IO : MS_OK;
  if (dist) st = par_agree_status(st);
  if (st != MS_OK) goto particle_done;
  if (!ctx->restart && f_ej) { /* a restart writes back the text so far */
    static const char *const ejn[] = {"t", "M_ej", "fragments"};
    static const char *const eju[] = {"10us", "g", "1"};
    ms_csv_header(f_ej,
                  "ejected mass (fragments but the largest, ahead of the grid's free surface) "
                  "vs time",
                  3, ejn, eju);
    static const char *const fsn[] = {"t", "u_grid", "u_particles"};
    static const char *const fsu[] = {"10us", "km/s", "km/s"};
    ms_csv_header(f_fs, "free-surface velocity: grid tag vs particle surface layer", 3, fsn, fsu);
  }
  const double t_rel_end = p->t_end - t_start;
  const long nsteps = (long)ceil(t_rel_end / cfg.dt);
  long next_out = 1, last_search = 0;
  /* free-surface samples for the drive check */
  size_t fs_cap = (size_t)(nsteps / p->frag_every) + (size_t)p->n_out + 4, fs_n = 0;
  double *fs_t = ms_calloc(fs_cap, sizeof(double)), *fs_ug = ms_calloc(fs_cap, sizeof(double)),
         *fs_up = ms_calloc(fs_cap, sizeof(double));
  /* checkpoints (docs/coupling.md): the loop state at the end of a step, with the gas grid's
   * history so that a restart can rebuild it */
  const long ckpt_every = checkpoint_steps(p, cfg.dt);
  ms_afile *const csv[2] = {&af_ej, &af_fs};
  ls.fs_cap = fs_cap, ls.fs_t = fs_t, ls.fs_ug = fs_ug, ls.fs_up = fs_up;
  ls.gaslog.on = ckpt_every > 0;
  gas.log = ls.gaslog.on ? &ls.gaslog : NULL;
  long step0 = 0;
  cd_energy e0;
  if (ctx->restart) {
    st = cpl_checkpoint_restore(ctx, p->deck_hash, sim, &ls, glive, csv, 2);
    const size_t nckpt = dist ? (size_t)par_sum_long((long)sim->p->nlocal) : sim->p->n;
    if (st == MS_OK && nckpt != n) {
      ms_log(ctx, MS_LOG_ERROR, "coupled: the checkpoint holds %zu particles, this deck %zu", nckpt,
             n);
      st = MS_ERR_INPUT;
    }
    ps = reg.ps = sim->p;
    step0 = ls.step, next_out = ls.next_out, last_search = ls.last_search;
    p_particles = ls.p_particles, fs_n = ls.fs_n, e0 = ls.e0;
    gas.returned_p = ls.returned_p, gas.returned_e = ls.returned_e;
  } else {
    cd_sim_energy(sim, &e0);
  }
  ms_log(ctx, MS_LOG_DEBUG, "coupled: initial energy: kinetic %g potential %g total %g", e0.kinetic,
         e0.potential, e0.total);
  ms_progress prog;
  ms_progress_start(&prog, ctx, "particles", t_start + sim->t, p->t_end);
  for (long step = step0 + 1; step <= nsteps && st == MS_OK; step++) {
    if (ckpt_every > 0 && step - 1 > step0 && (step - 1) % ckpt_every == 0) {
      ls.step = step - 1, ls.next_out = next_out, ls.last_search = last_search;
      ls.p_particles = p_particles, ls.e0 = e0, ls.fs_n = fs_n;
      ls.returned_p = gas.returned_p, ls.returned_e = gas.returned_e;
      st = cpl_checkpoint_write(ctx, p->deck_hash, sim, &ls, csv, 2);
      if (st != MS_OK) break;
    }
    if (p->drive_mode == 1) {
      /* grid state over the step: mean velocity (exact displacement) and sample-side
       * pressure at the mid-step */
      double ta = t_start + sim->t, tb = ta + cfg.dt;
      double ug =
          (cpl_piston_displacement(&drive, tb) - cpl_piston_displacement(&drive, ta)) / cfg.dt;
      double pg = interp(hd.n, hd.t, hd.p_right, 0.5 * (ta + tb));
      double u_cmd = ug + (pg - p_particles) / Z;
      sim->piston.t[0] = sim->t;
      sim->piston.t[1] = sim->t + cfg.dt;
      sim->piston.u[0] = sim->piston.u[1] = u_cmd;
    }
    st = cd_sim_step(sim);
    if (p->drive_mode == 1) {
      double fsum = 0;
      for (size_t i = 0; i < ps->nlocal; i++)
        if (ps->flags[i] & PTL_DRIVEN) fsum += ps->fx[i];
      if (dist) /* rank order: every rank's piston gets the same bits */
        par_sum_doubles_ordered(&fsum, 1);
      p_particles = -fsum / area; /* compression pushes the piston towards −x */
    }
    if (st != MS_OK) {
      particles_unstable(ctx, sim, st, t_start);
      break;
    }
    bool out_now = step * p->n_out >= next_out * nsteps;
    if (step % p->frag_every && !out_now && step != nsteps) continue;
    double t_abs = t_start + sim->t;
    /* fragments, ejected mass, drag kick over the interval since the last search */
    cpl_particles view;
    st = find_fragments(ctx, sim, &fr, &fo, skip, ghost_owner, &view);
    if (st != MS_OK) {
      ms_log(ctx, MS_LOG_ERROR,
             "coupled: fragment search failed at t = %g (non-finite "
             "particle positions?)",
             t_abs);
      break;
    }
    /* ejecta: detached fragments ahead of the grid's free surface at this time */
    sel.plane = hf.x[0] + cpl_piston_displacement(&fsurf, t_abs);
    double row_ej[3] = {t_abs, cpl_ejected_mass(&fr, &sel), (double)fr.n};
    if (f_ej) ms_csv_row(f_ej, 3, row_ej);
    if (p->drag_law != CPL_DRAG_NONE) {
      st = cont_grid_run_to(glive, t_abs);
      if (st != MS_OK) {
        ms_log(ctx, MS_LOG_ERROR, "coupled: gas grid: %s", cont_grid_error(glive));
        break;
      }
      cpl_gaslog_run_to(&ls.gaslog, t_abs);
      /* a velocity kick over the search interval (operator splitting; drag is slow on the
       * particle time step) */
      st = drag_kick(p, &fr, &view, &sel, &gas, t_abs, (double)(step - last_search) * cfg.dt, ps,
                     skip, fx, fy, fz);
      if (st != MS_OK) {
        ms_log(ctx, MS_LOG_ERROR, "coupled: gas return: %s", cont_grid_error(glive));
        break;
      }
    }
    last_search = step; /* after the kick: its interval is the time since the previous search */
    /* free-surface check */
    double ug = cpl_piston_velocity(&fsurf, t_abs), up = cd_free_surface_velocity(sim, 0);
    double row_fs[3] = {t_abs, ug, up};
    if (f_fs) ms_csv_row(f_fs, 3, row_fs);
    if (fs_n < fs_cap) {
      fs_t[fs_n] = t_abs;
      fs_ug[fs_n] = ug;
      fs_up[fs_n] = up;
      fs_n++;
    }
    if (out_now) {
      char name[64];
      snprintf(name, sizeof name, "particles_%04ld.h5", next_out);
      char *path = ms_out_path(ctx, name);
      cpl_snapshot_info info = {t_abs, a, rho0, fo.box};
      st = cpl_write_snapshot(path, &view, &fr, &info);
      free(path);
      if (st != MS_OK) break;
      snprintf(name, sizeof name, "spectrum_%04ld.csv", next_out);
      char title[160];
      snprintf(title, sizeof title, "fragment spectrum N(g) at t = %g (10us), b = %g", t_abs,
               p->bond);
      st = write_table(ctx, name, &fr, 0, &sel, title);
      if (dist) st = par_agree_status(st); /* rank 0's file error stops every rank */
      if (st != MS_OK) break;
      cd_energy en;
      cd_sim_energy(sim, &en);
      ms_log(ctx, MS_LOG_INFO,
             "coupled: t = %.5g: %zu fragments, ejected mass %.4g g, free surface %.4g km/s "
             "(grid %.4g); energy [kJ]: kinetic %.4g potential %.4g damped %.4g broken %.4g "
             "piston work %.4g, balance %.3g of the work",
             t_abs, fr.n, row_ej[1], up, ug, en.kinetic, en.potential - e0.potential, en.dissipated,
             en.broken, en.piston_work,
             en.piston_work != 0 ? (en.total - e0.total) / en.piston_work : 0.0);
      next_out++;
    }
    ms_progress_update(&prog, t_abs, step);
  }
  ms_progress_finish(&prog, t_start + sim->t, (long)(sim->t / cfg.dt));
  cpl_fs_check chk;
  const double window = p->check_window > 0 ? p->check_window : depth / c0;
  if (st == MS_OK && cpl_free_surface_check(fs_n, fs_t, fs_ug, fs_up, window, &chk))
    ms_log(ctx, MS_LOG_INFO,
           "coupled: drive check (free surface, %zu samples over [%g, %g]): plateau particles "
           "%.5g km/s vs grid %.5g km/s: %.2f %%; half-rise at t = %.5g (particles) vs %.5g "
           "(grid); smallest particle velocity in the next two windows %.4g km/s (%s piston)",
           chk.samples, chk.t_break + 0.5 * window, chk.t_break + window, chk.plateau_particles,
           chk.plateau_grid, 100 * chk.rel_diff, chk.t_half_particles, chk.t_half_grid,
           chk.min_after, drive_mode_names[p->drive_mode]);
  else if (st == MS_OK)
    ms_log(ctx, MS_LOG_WARN,
           "coupled: drive check: no free-surface breakout within the "
           "particle phase (or no samples in the check window)");
  p->sum.check = chk;
  free(fs_t);
  free(fs_ug);
  free(fs_up);

  if (st == MS_OK) {
    cd_energy en;
    cd_sim_energy(sim, &en);
    p->sum.particles = nglobal;
    p->sum.steps = (long)nsteps;
    p->sum.energy_balance = en.piston_work != 0 ? (en.total - e0.total) / en.piston_work : 0.0;
    p->sum.piston_work = en.piston_work;
    p->sum.fragments = fr.n;
    p->sum.ejected_mass = cpl_ejected_mass(&fr, &sel);
    /* jets vs spall (docs/coupling.md §9): measured against the flat free surface's (the
     * grid's) jump-off velocity, its first peak: from breakout (5 % of the maximum over the
     * phase, as in the drive check) until it first falls below 90 % of the running maximum
     * (later peaks are reverberations in the unbroken grid) */
    double u_all = 0, u_ref = 0;
    for (size_t k = 0; k < hf.n && hf.t[k] <= t_start + sim->t; k++) u_all = fmax(u_all, hf.u[k]);
    for (size_t k = 0; k < hf.n && hf.t[k] <= t_start + sim->t; k++) {
      if (hf.u[k] < 0.05 * u_all) continue;
      if (hf.u[k] < 0.9 * u_ref) break;
      u_ref = fmax(u_ref, hf.u[k]);
    }
    cpl_particles view = particle_view(ps, skip);
    const double normal[3] = {1, 0, 0};
    if (dist) {
      view.n = ps->nlocal;
      classify_dist(&fr, &view, u_ref, p->jet_margin, &p->sum.classes);
    } else {
      cpl_ejecta_classify(&fr, &view, normal, u_ref, p->jet_margin, &p->sum.classes);
    }
    p->sum.u_ref = u_ref;
    const cpl_ejecta_classes *ec = &p->sum.classes;
    ms_log(ctx, MS_LOG_INFO,
           "coupled: detached material at t = %.5g (bulk %.4g g): jets (faster than %.4g km/s = "
           "(1 + %g) x the grid's free-surface jump-off velocity %.4g) %.4g g in %zu fragments, "
           "slower (spall layers, debris) %.4g g in %zu fragments; fastest %.4g km/s",
           t_start + sim->t, ec->m_bulk, (1 + p->jet_margin) * u_ref, p->jet_margin, u_ref,
           ec->m_jet, ec->n_jet, ec->m_slow, ec->n_slow, ec->v_max);
  }
  /* final fragment tables */
  if (st == MS_OK) {
    char title[160];
    snprintf(title, sizeof title, "fragments at the end of the particle phase, t = %g (10us)",
             t_start + sim->t);
    const char *names[] = {"spectrum.csv",  "fragments.csv",     "cumulative.csv",
                           "mass_hist.csv", "diameter_hist.csv", "ejecta_velocity.csv"};
    for (int k = 0; k < 6 && st == MS_OK; k++)
      st = write_table(ctx, names[k], &fr, k, &sel, k == 0 ? title : NULL);
  }
  if (dist) st = par_agree_status(st);
particle_done:
  if (f_ej) {
    ms_status s2 = commit_csv(&af_ej);
    if (st == MS_OK) st = s2;
  }
  if (f_fs) {
    ms_status s2 = commit_csv(&af_fs);
    if (st == MS_OK) st = s2;
  }
  if (dist) st = par_agree_status(st);

  /* 4. transport of the ejecta to the detector (not checkpointed: no gas log) */
  gas.log = NULL;
  free(gas.cell_src);
  gas.cell_src = NULL;
  cpl_gaslog_free(&ls.gaslog);
  if (st == MS_OK && p->det_distance > 0 && p->transport_end > t_start + sim->t)
    st = transport_phase(ctx, p, &fr, &sel, &gas, t_start + sim->t, x_fs + p->det_distance, rho0);
  if (st == MS_OK) st = check_replicated(ctx, glive, NULL);
  cpl_fragments_free(&fr);
  free(skip);
  free(ghost_owner);
  free(fx);
  free(fy);
  free(fz);
  cd_sim_free(sim);
  cpl_piston_free(&drive);
  cpl_piston_free(&fsurf);
  free(hd_buf);
  free(hf_buf);
  return st;
}
