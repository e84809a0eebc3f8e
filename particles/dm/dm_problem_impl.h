/* SPDX-License-Identifier: MIT */
/* dm_problem_impl.h — internals of the deck problem type `discrete_model` (docs/input-dm.md),
 * shared by its sources: dm_deck.c reads the deck, dm_problem.c sets up and runs the linear
 * model, dm_problem_finite.c runs the finite-deformation one (response: eos), dm_output.c
 * writes the files, dm_analysis.c compares with the exact solutions, dm_checkpoint.c writes
 * and reads checkpoints. Not part of the public API (dm.h). */
#ifndef MSCALE_DM_PROBLEM_IMPL_H
#define MSCALE_DM_PROBLEM_IMPL_H

#include "dm_impl.h"

enum face_bc { FACE_FREE = 0, FACE_WALL, FACE_SYMMETRY, FACE_FIXED, FACE_PERIODIC };

enum profile {
  PROF_NONE = 0,
  PROF_ROD_TRIANGLE,
  PROF_ROD_SINE,
  PROF_CONTACT,
  PROF_RANDOM_VELOCITY
};

enum response { RESP_LINEAR = 0, RESP_EOS };

typedef struct dm_layer {
  double x_max; /* particles with x < x_max (the last layer takes the rest) */
  double rho, K, G;
  const char *name;
  int response, yield; /* enum response, dm_yield */
  double Y0;           /* yield stress (GPa), elastic_plastic */
  dm_sg sg;            /* steinberg_guinan (dm_strength.c) */
  dm_fracture frac;    /* fracture: {...} (dm_fracture.c), response eos */
  const eos_t *eos;    /* the material's EOS (response eos) */
  int has_u0;          /* 'velocity' given (response eos: a flyer or target body) */
  double u0;           /* its initial x velocity (km/s) */
} dm_layer;

struct dm_problem {
  int dim;
  double h, lo[3], hi[3];
  long ncell[3];
  double horizon; /* in spacings */
  int face[6];
  size_t nlayers;
  dm_layer *layers;
  int profile;
  double amplitude, length;
  long mode; /* rod_sine: w = εL sin(mode·πx/2L) */
  long seed;
  int has_source;
  double src_r0, src_w0, src_period;
  int integrator;
  double dt, courant, t_end;
  long steps;
  double hourglass, cond_max, contact; /* contact: d_c / h (response: eos) */
  double *probes;
  size_t nprobes;
  long probe_every, energy_every;
  double *profile_times;
  size_t nprofile_times;
  double *snapshot_times;
  size_t nsnapshot_times;
  long checkpoint_every; /* steps between checkpoints (0: none) */
  uint64_t deck_hash;    /* of the resolved deck but t_end, steps (response eos checkpoints) */
  int finite;            /* every layer has response: eos (dm_finite.c) */
  double cq, cl;         /* viscosity coefficients */
  int has_piston;
  double piston_u;    /* km/s along +x */
  long piston_layers; /* x layers of real particles driven */
  dm_run_summary sum;
  double *final_w, *final_u; /* global state at the end of the last run ([n][3]) */
  size_t final_n;
};

/* ---- set-up (dm_problem.c) ---- */
const dm_layer *dmp_layer_at(const dm_problem *p, double x);
/* The particles: real ones first in lattice order (x fastest), then fixed layers and mirror
 * ghosts; s is allocated here. */
void dmp_build_particles(dm_problem *p, dm_state *s);
void dmp_set_initial(dm_problem *p, dm_state *s, size_t nreal);
/* Longitudinal wave speed sqrt((K + 4G/3)/ρ) of the first layer. */
double dmp_wave_speed(const dm_problem *p);
/* The run's summary with every field that a run may leave unset as NaN. */
void dmp_summary_reset(dm_run_summary *sum, int finite);
/* CPU time of this process (s): the loop figures of the run summaries. */
double dmp_cpu_time(void);
/* response: eos (dm_problem_finite.c) */
ms_status dmp_run_finite(ms_ctx *ctx, dm_problem *p);

/* ---- outputs (dm_output.c); every writer does nothing without ctx->outdir ---- */
typedef struct probe_rec {
  size_t particle;
  double x;
} probe_rec;

ms_status dmp_write_series(const ms_ctx *ctx, const char *file, const char *title, size_t ncol,
                           const char *const *names, const char *const *units, const double *data,
                           size_t nrow);
void dmp_write_profile(const ms_ctx *ctx, const dm_problem *p, dm_model *m, size_t nreal, double t,
                       int index);
void dmp_material_table(const dm_problem *p, char *names, size_t size);
/* The snapshot set-up of the model's writers: particles [0, n) at the current positions X + w
 * and velocities u ([n][3] each, as columns into xv[6 n], which must live until it is written),
 * masses `mass`, at time t; serial. */
ptl_snapshot dmp_snapshot_of(size_t n, const double *X, const double *w, const double *u,
                             const double *mass, double t, double *xv);
/* Writes snap to OUTDIR/name; a failure is logged as a warning ("WHO: could not write PATH"). */
ms_status dmp_snapshot_write(const ms_ctx *ctx, const char *name, const ptl_snapshot *snap,
                             const char *who);
void dmp_write_snapshot(const ms_ctx *ctx, const dm_problem *p, dm_model *m, size_t nreal, double t,
                        long step, const char *name);
/* The last good state of a run of the finite model (dm_fin), which a failed step leaves to show
 * (docs/reliability.md §6): a step changes the arrays before it can fail, so the
 * discrete_model problem with response eos and the impact problem copy the ones their
 * snapshots show at the top of every step (dm_fin_output.c). w, u, e, ε_p and p are always
 * kept; the others (DMP_KEEP_*) when asked for, NULL otherwise. */
typedef struct dmp_backup {
  double *w, *u;                       /* [n][3] */
  double *e, *eps_p, *p;               /* [n] */
  double *ehg, *q, *sigma_u, *rho, *J; /* [n] or NULL; σ_u = √(3/2 s:s) of the deviator */
  size_t n;
  double t;
  long step; /* dm_fin's step count of that state */
  bool valid;
} dmp_backup;
enum {
  DMP_KEEP_EHG = 1u,
  DMP_KEEP_Q = 2u,
  DMP_KEEP_SIGMA_U = 4u,
  DMP_KEEP_RHO = 8u,
  DMP_KEEP_J = 16u
};
/* Room for the state of particles [0, n) (w one longer: the 4-lane loads of dm_finite.c). */
void dmp_backup_alloc(dmp_backup *b, size_t n, unsigned keep);
void dmp_backup_free(dmp_backup *b);
/* Copies f's state (particles [0, b->n)) at time t as the last good one. */
void dmp_backup_take(dmp_backup *b, const dm_fin *f, double t);
void dmp_write_sphere_radial(const ms_ctx *ctx, const dm_problem *p, const dm_state *s,
                             size_t nreal, double t);
void dmp_write_fin_profile(const ms_ctx *ctx, const dm_problem *p, const dm_fin *f, size_t nreal,
                           double t, int index, double *bins);
void dmp_write_probes(const ms_ctx *ctx, const dm_problem *p, const probe_rec *pr,
                      const double *hist, size_t nrec);
void dmp_write_energy(const ms_ctx *ctx, const double *ehist, size_t nerec);
void dmp_write_summary(const ms_ctx *ctx, const dm_run_summary *sum);
void dmp_report_unstable(const ms_ctx *ctx, const ms_ctx *octx, const dm_problem *p, dm_model *m,
                         dm_dist *d, const dm_state *ls, size_t nreal, long step, double t);

/* ---- analyses against the exact solutions (dm_analysis.c): fill p->sum ---- */
void dmp_rod_analysis(dm_problem *p, const double *hist, size_t nrec, double xprobe);
void dmp_contact_analysis(dm_problem *p, const dm_model *m, size_t nreal, double t);
/* The same on any stress: σ_xx = sigma[9 i] at reference positions X[3 i] (response eos). */
void dmp_contact_analysis_sigma(dm_problem *p, const double *X, const double *sigma, size_t nreal,
                                double t);
/* The nearest real particle to each probe x (and the y, z of the first lattice row). */
void dmp_find_probes(const dm_problem *p, const dm_state *s, size_t nreal, probe_rec *pr);
void dmp_sphere_analysis(dm_problem *p, const dm_state *s, size_t nreal, double t);

/* ---- checkpoint / restart (dm_checkpoint.c, docs/mpi.md) ---- */
/* What a run needs to continue bit for bit: the global state in particle order (the same file
 * for every rank count) and the diagnostics recorded so far. */
typedef struct dm_checkpoint_data {
  long step;
  double E0, dw_scale, energy_err_max;
  double *hist, *ehist; /* the run's arrays (not owned) */
  size_t pcols, nrec, nerec, nrec_max, nerec_max;
} dm_checkpoint_data;
/* OUTDIR/dm_checkpoint.h5, written as dm_checkpoint.h5.part and renamed when complete
 * (ms_h5_close): a crash while writing leaves the previous checkpoint intact. Rank 0 only. */
ms_status dmp_write_checkpoint(const ms_ctx *ctx, const dm_state *s, double dt, int ranks,
                               const dm_checkpoint_data *ck);
/* Every rank reads the checkpoint into the global state s; the deck must describe the same
 * particles and time step (the restart continues the same run). */
ms_status dmp_read_checkpoint(const ms_ctx *ctx, const char *path, dm_state *s, long nsteps,
                              double dt, dm_checkpoint_data *ck);

#endif
