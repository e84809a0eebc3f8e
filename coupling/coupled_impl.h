/* SPDX-License-Identifier: MIT */
/* coupled_impl.h — private to the `coupled` problem's files (docs/input-coupled.md,
 * docs/coupling.md §6):
 *   coupled_deck.c     the deck section and its consistency with the grid;
 *   coupled_grid.c     the adapter over the grid (cont.h): gas state, gas return, replicated
 *                      grids on MPI ranks;
 *   coupled_common.c   what both drives share: CSV files, fragments, drag kicks, transport;
 *   coupled_one_way.c  the one-way drive (grid first, then the particles);
 *   coupled_two_way.c  two-way coupling (grid and particles in lock-step);
 *   coupled.c          cpl_problem_run.
 * The grid is reached only through cont.h and the particles only through ptl_region.h. */
#ifndef MSCALE_COUPLED_IMPL_H
#define MSCALE_COUPLED_IMPL_H

#include "cpl_checkpoint.h"

enum { DRIVE_VELOCITY = 0, DRIVE_TRANSMITTING, DRIVE_TWO_WAY };
extern const char *const cpl_drive_mode_names[];

struct cpl_problem {
  const eos_materials *mats;
  cont_problem *grid_out, *grid_live;
  cont_problem *gas_grid;   /* two-way: the gas beyond the particles' free surface (`gas:`) */
  size_t tag_drive, tag_fs; /* tag indices in both grids */
  int drive_mode;           /* DRIVE_* */
  double impedance;         /* Z for the transmitting piston (0: √1.5 ρ0 c0) */
  bool have_fs;
  int sample_mat, gas_mat, gas_layer;
  /* the particle region: its model and that model's deck section */
  const ptl_region_model *model;
  ptl_region_params *region;
  double depth; /* two-way: particle region length beyond the interface node */
  /* time and outputs */
  double t_end;
  long n_out;
  double check_window;
  long checkpoint_every;  /* particle steps between checkpoints (0: none) */
  double checkpoint_time; /* or simulated time between them (rounded to whole steps) */
  uint64_t deck_hash;     /* of the resolved deck: a restart must use the same one */
  double wall_limit;      /* time.wall_limit: stop at the next checkpoint after this many s */
  /* fragments, drag, transport */
  double bond, jet_margin;
  long frag_every;
  int drag_law;
  bool gas_return; /* drag.gas_return: the gas receives −(drag impulse) and the energy */
  double det_distance, transport_end;
  long transport_windows;
  cpl_run_summary sum; /* what the last run measured */
};

/* ---- the grid adapter (coupled_grid.c) ---- */

/* Gas state from a grid: only the gas layer beyond the sample counts. */
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
  double drag_work; /* Σ ΔK of this rank's drag kicks (kJ, ≤ 0): the balance's term */
  cpl_gaslog *log;  /* sources recorded for checkpoints (NULL: none) */
  /* MPI, drag kicks: each rank's sources per grid cell (dp, de per cm²), summed over the ranks
   * before they enter the replicated grid (cpl_gas_return_sum); NULL otherwise */
  double *cell_src;
} gas_ctx;
/* The gas of problem p's gas layer in grid g (offset: particle frame − grid frame). */
gas_ctx cpl_gas_of(const cpl_problem *p, cont_grid *g, double offset, double area);
void cpl_gas_deposit(void *user, const double x[3], double t0, double t1, const double dp[3],
                     double de);
bool cpl_grid_gas(void *user, const double x[3], double t, cpl_gas *out);
void cpl_gas_return_sum(gas_ctx *c);
ms_status cpl_check_replicated(const ms_ctx *ctx, const cont_grid *g1, const cont_grid *g2);
void cpl_share_history(const ms_ctx *ctx, cont_history *h, double **buf);
double cpl_interp(size_t n, const double *t, const double *v, double x);

/* ---- shared by both drives (coupled_common.c) ---- */

FILE *cpl_open_csv(const ms_ctx *ctx, ms_afile *af, const char *name);
ms_status cpl_commit_csv(ms_afile *af);
/* kind: 0 spectrum, 1 fragment table, 2 cumulative, 3 mass and 4 diameter histograms, 5 ejecta
 * velocity */
ms_status cpl_write_table(const ms_ctx *ctx, const char *name, const cpl_fragments *fr, int kind,
                          const cpl_ejecta_sel *sel, const char *title);

/* What a run of either drive holds for the particle region: the region, its geometry, the
 * fragment search and the drag buffers (sized for the whole region). */
typedef struct cpl_particle_phase {
  ptl_region *region;
  ptl_region_geometry geo;
  cpl_fragments fr;
  cpl_fragment_opts fo;
  cpl_ejecta_sel sel;
  uint8_t *skip;
  int32_t *ghost_owner; /* MPI: owner rank of each ghost (fragment search) */
  double *fx, *fy, *fz;
  const char *material; /* the sample's material name, for the snapshots (not owned) */
} cpl_particle_phase;
/* Build the region between x_drive and x_drive + depth with its piston history (t, u on the
 * region's clock, along +x), distribute it, and (unless restarting) initialise it; the
 * buffers sized for it. */
ms_status cpl_phase_open(const ms_ctx *ctx, const cpl_problem *p, double x_drive, double depth,
                         size_t npiston, const double *t_piston, const double *u_piston,
                         cpl_particle_phase *ph);
void cpl_phase_close(cpl_particle_phase *ph);
cpl_particles cpl_particle_view(ptl_region *r, uint8_t *skip);
/* Jets, spall layers and debris of the phase's last fragment search (cpl_ejecta_classify with the
 * search's spacing and box; view as cpl_find_fragments left it). Collective on MPI ranks. */
void cpl_phase_classify(const ms_ctx *ctx, const cpl_particle_phase *ph, const cpl_particles *view,
                        double v_fast, cpl_ejecta_classes *out);
/* The ejected-mass history (ejecta_mass.csv) of both drives: its title, columns and one row
 * (collective on MPI ranks). */
enum { CPL_EJECTA_COLS = 7 };
extern const char *const cpl_ejecta_names[CPL_EJECTA_COLS],
    *const cpl_ejecta_units[CPL_EJECTA_COLS];
extern const char *const CPL_EJECTA_TITLE;
void cpl_ejecta_row(const ms_ctx *ctx, const cpl_particle_phase *ph, const cpl_particles *view,
                    double t, double row[CPL_EJECTA_COLS]);
ms_status cpl_find_fragments(const ms_ctx *ctx, cpl_particle_phase *ph, cpl_particles *view);
ms_status cpl_drag_kick(const cpl_problem *p, cpl_particle_phase *ph, const cpl_particles *view,
                        gas_ctx *gas, double t, double span);
ms_status cpl_transport_phase(ms_ctx *ctx, cpl_problem *p, const cpl_fragments *fr,
                              const cpl_ejecta_sel *sel, gas_ctx *gas, double t0, double det_x,
                              double rho0);
ms_status cpl_write_particles(const ms_ctx *ctx, cpl_particle_phase *ph, long index, double t,
                              const cpl_particles *view);
void cpl_particles_unstable(const ms_ctx *ctx, ptl_region *r, ms_status st, double t_start,
                            const char *material);
long cpl_checkpoint_steps(const cpl_problem *p, double dt);
/* SIGINT/SIGTERM on any rank, or the wall-time limit passed on rank 0 (docs/reliability.md
 * §5b). Collective: every rank calls it at the same point of the loop. */
bool cpl_should_stop(const ms_ctx *ctx, const cpl_problem *p);
/* A restart's particle count against the deck's (MS_ERR_INPUT with a message). */
ms_status cpl_check_restart_count(const ms_ctx *ctx, ptl_region *r, size_t nglobal);

/* ---- the drives ---- */
ms_status cpl_run_one_way(ms_ctx *ctx, cpl_problem *p);
ms_status cpl_run_two_way(ms_ctx *ctx, cpl_problem *p);

#endif
