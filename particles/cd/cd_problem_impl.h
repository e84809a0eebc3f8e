/* SPDX-License-Identifier: MIT */
/* cd_problem_impl.h — private to the `cluster_dynamics` deck problem: the problem read from the
 * deck (cd_deck.c), set up and run (cd_problem.c), and its output files (cd_output.c). */
#ifndef MSCALE_CD_PROBLEM_IMPL_H
#define MSCALE_CD_PROBLEM_IMPL_H

#include "cd_impl.h"

enum { CD_MAX_REGIONS = 32 };
typedef enum { SHAPE_BOX = 0, SHAPE_SPHERE, SHAPE_CYLINDER, SHAPE_HALFSPACE } region_shape;

/* Largest lattice a deck may ask for: particle indices are int32_t. */
#define CD_MAX_LATTICE_SITES 2.0e9
typedef enum { SURF_FLAT = 0, SURF_SINE, SURF_RANDOM } surface_kind;
extern const char *const cd_partition_names[]; /* cd_partition_method */
extern const char *const cd_mode_names[];      /* cd_cutoff_mode */

typedef struct cd_deck_region {
  int mat; /* index into the problem's material list */
  region_shape shape;
  double lo[3], hi[3];      /* box */
  double center[3], radius; /* sphere, cylinder (axis `axis`) */
  int axis;                 /* cylinder axis; halfspace normal axis */
  double plane;             /* halfspace: x_axis < plane */
  double velocity[3];
  bool piston;
  bool matrix; /* fills only the sites no other region takes (no overlap check) */
  int ngrains; /* polycrystal / grain structure (box, sphere, cylinder; 0 = single crystal) */
  uint64_t grain_seed;
  bool rotate; /* random lattice orientation per grain */
  double dmin; /* overlap removal distance / r0 */
  int ngmat;   /* grain materials (0: the region's material) */
  int gmat[CD_MAX_MATERIALS];
  double gfrac[CD_MAX_MATERIALS];
  surface_kind surface; /* box: profile of the hi face along `surface_axis` */
  int surface_axis, surface_along;
  double amplitude, wavelength;
  uint64_t seed;
  const dk_node *node;
} cd_deck_region;

struct cd_problem {
  int dim;
  cd_lattice lattice;
  double r0, thickness, rc, skin, courant, dt, t_end, r_min, damping_j, attraction_default;
  int table_intervals;
  cd_cutoff_mode mode;
  cd_integrator integrator;
  cd_box box;
  double origin[3];
  int nmat;
  const eos_material *mat[CD_MAX_MATERIALS];
  double rc_pair[CD_MAX_MATERIALS][CD_MAX_MATERIALS],
      attraction[CD_MAX_MATERIALS][CD_MAX_MATERIALS];
  int nreg;
  cd_deck_region reg[CD_MAX_REGIONS];
  cd_history piston;
  double piston_dir[3];
  double thermal_amp;
  uint64_t thermal_seed;
  int out_every, profile_axis, profile_bins, snapshots;
  cd_mpi_config mpi;      /* decomposition on MPI ranks (docs/input-cd.md "mpi") */
  double front_u;         /* reference velocity for front tracking (piston velocity by default) */
  long checkpoint_every;  /* steps between checkpoints (0: none) */
  double checkpoint_time; /* or simulated time between them (rounded to whole steps) */
  uint64_t deck_hash;     /* resolved deck (t_end left out) and piston history */
  bool relax_on;          /* `relax:` given: cd_sim_relax before the piston starts */
  cd_relax_config relax;  /* times in 10 us; Γ, tau, modulus set at run time from c0 */
  double relax_j, relax_tau; /* damping J (0: none); box tau in r0/c0 */
};

/* ---- region geometry (cd_deck.c) ---- */
/* lattice period along each axis: fcc cubic constant a = √2 r0; triangular r0 × √3 r0 */
void cd_deck_lattice_period(const cd_problem *p, double per[3]);
bool cd_deck_region_contains(const cd_deck_region *r, const double x[3], int dim);
/* the region's bounding box (clipped to the problem's box if `clip`) */
void cd_deck_region_bounds(const cd_problem *p, const cd_deck_region *r, bool clip, double lo[3],
                           double hi[3]);

/* ---- output files (cd_output.c) ---- */
#define CD_CHECKPOINT_FORMAT "mscale cluster_dynamics checkpoint 1"
enum { CD_NSTREAMS = 3, CD_MAX_FRONT = 4096 };

/* The CSV files (rank 0 writes them, every rank runs the collective diagnostics), the profile
 * bins and the front samples of a run. */
typedef struct cd_outputs {
  ms_afile fe, fp, ff;            /* cd_energy.csv, cd_profiles.csv, cd_front.csv */
  int axis;                       /* profile axis */
  double lo, hi, area;            /* profile range along it; cross-section */
  double *prof;                   /* profile_bins × CD_PROFILE_NCOL */
  double front[2 * CD_MAX_FRONT]; /* (t, z) of the front fit */
  int nf;
  bool with_vfs; /* cd_energy.csv has the v_free_surface column (a piston run) */
} cd_outputs;

/* Opens the three CSV files on rank 0 (a restart fills them from the checkpoint, else they get
 * their headers); agreed over the ranks. */
ms_status cd_outputs_open(ms_ctx *ctx, cd_outputs *o, bool restart);
/* The profile range and cross-section along p->profile_axis (from the box of s) and the bins. */
void cd_outputs_setup(const cd_problem *p, const cd_sim *s, cd_outputs *o);
/* One output row of step k: energy, profiles, front. */
void cd_outputs_write(ms_ctx *ctx, const cd_problem *p, cd_sim *s, cd_outputs *o);
/* The shock speed of the front samples (log). */
void cd_outputs_front_fit(ms_ctx *ctx, const cd_outputs *o);
/* Commits the files (st MS_OK or MS_ERR_UNSTABLE: the series so far) or removes them. */
ms_status cd_outputs_close(ms_ctx *ctx, const cd_sim *s, cd_outputs *o, ms_status st);
/* Aborts what is still open, frees the bins (null-safe, idempotent). */
void cd_outputs_free(cd_outputs *o);

/* The state at the end of a step, before that step's outputs: the particles (after
 * cd_sim_refresh, which the restart repeats), the CSV text so far and the front samples. */
ms_status cd_outputs_checkpoint(ms_ctx *ctx, const cd_problem *p, cd_sim *s, cd_outputs *o);
ms_status cd_outputs_restore(const ms_ctx *ctx, ms_h5r *h, cd_outputs *o);

#endif
