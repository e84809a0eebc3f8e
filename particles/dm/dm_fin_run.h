/* SPDX-License-Identifier: MIT */
/* dm_fin_run.h — the run of the discrete-model problem with response: eos, shared by its
 * sources (not part of the public API): dm_problem_finite.c sets it up and steps it,
 * dm_fin_output.c writes its particle snapshots and keeps the last good state,
 * dm_fin_restart.c writes and reads its checkpoints (docs/input-dm.md "Response eos"). On MPI
 * ranks the model is replicated: every rank steps every particle with the same arithmetic (so
 * the ranks agree bit for bit) and rank 0 writes the files. */
#ifndef MSCALE_DM_FIN_RUN_H
#define MSCALE_DM_FIN_RUN_H

#include "dm_problem_impl.h"

/* What a snapshot shows of one state: the live model's arrays, or the copy of the last good
 * state. J may be NULL: then it is computed from w (the copy does not keep it). */
typedef struct dmf_fields {
  const double *w, *u;                         /* [n][3] */
  const double *e, *ehg, *eps_p, *q, *sigma_u; /* [n] */
  const double *p, *J;                         /* [n]; J may be NULL */
} dmf_fields;

typedef struct dmf_run {
  ms_ctx *ctx;
  ms_ctx octx; /* the files: rank 0's outdir, an empty one on the other ranks */
  dm_problem *p;
  dm_state s;
  dm_model *m;
  dm_fin *f;
  dm_fin_material *mat;
  uint8_t *imat;
  size_t nreal;
  int flyer;  /* some layer has a velocity: the free-surface history */
  double *eh; /* [nemax][6]: t, kinetic, internal, bond_penalty, work, balance */
  size_t ne, nemax;
  char *prof_done, *snap_done; /* [nprofile_times], [nsnapshot_times] */
  dm_fs_history fs;
  probe_rec *pr; /* [nprobes] the probe particles */
  double *hist;  /* [nrec_max][pcols]: t, w_x at each probe, every probe_every·pstride steps */
  size_t pcols, nrec, nrec_max;
  long pstride;                   /* doubled (every other row dropped) whenever the table is full */
  double *bins, *sigma_u;         /* scratch: profile bins, σ_u of the live state */
  double E0, t, dEmax, wall, cpu; /* wall and CPU time (s) of the steps */
  double K, U, H;                 /* energies of the last good state (kJ) */
  long step0;                     /* the step the run started from (0, or the checkpoint's) */
  long steps; /* the steps completed */ /* the step the run started from (0, or the checkpoint's) */
  /* the state at the start of the step being taken: w, u, e, E_hg, ε_p, p, q, σ_u */
  dmp_backup bk;
} dmf_run;

/* ---- dm_fin_output.c ---- */
/* σ_u = √(3/2 s:s) of every particle's deviator into out[n]. */
void dmf_sigma_u(const dm_fin *f, double *out);
/* The fields of the live model (σ_u into r->sigma_u). */
dmf_fields dmf_live_fields(dmf_run *r);
/* OUTDIR/name: an HDF5 snapshot of the real particles (ptl_write_snapshot, with the run's
 * particles.xmf time series); nothing without an outdir. */
ms_status dmf_write_snapshot(const dmf_run *r, const dmf_fields *fl, double t, long step,
                             const char *name);
/* A step failed: the report (particle, step, quantity) and the last good state's snapshot
 * particles_unstable.h5. `what`, `value`, `particle` describe the finding. */
void dmf_report_unstable(dmf_run *r, size_t particle, const char *what, double value, double t);

/* ---- dm_fin_restart.c: OUTDIR/dm_checkpoint.h5 (every rank calls both) ---- */
ms_status dmf_checkpoint_write(dmf_run *r);
/* Reads ctx->restart into the run (after dm_fin_create); located messages, MS_ERR_INPUT. */
ms_status dmf_restart(dmf_run *r);

#endif
