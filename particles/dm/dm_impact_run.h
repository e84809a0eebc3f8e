/* SPDX-License-Identifier: MIT */
/* dm_impact_run.h — the run of the deck problem type `impact`, shared by dm_impact.c (set-up,
 * time loop, outputs) and dm_impact_checkpoint.c (its checkpoints and restart; docs/input-impact.md
 * "Checkpoints, restart and MPI ranks"). On MPI ranks the run is replicated: every rank builds
 * and steps every particle with the same arithmetic (as the discrete_model problem with
 * response: eos, dm_fin_run.h), so every rank holds the serial run's state bit for bit, and
 * rank 0 writes the files. */
#ifndef MSCALE_DM_IMPACT_RUN_H
#define MSCALE_DM_IMPACT_RUN_H

#include "dm_impact_impl.h"

/* The rigid wall (dm_impact.c, wall_force) and, through it, the contact between bodies. */
typedef struct dmi_wall {
  int axis, side;
  double contact; /* plane of the particle centres: x_wall + side·h/2 */
  double h;
  double *k;       /* [n] penalty stiffness */
  double dt_k;     /* courant·2/max ω_w */
  double courant;  /* for the approach limit */
  double stored;   /* Σ k d²/2 at the last evaluation (kJ): wall and contact */
  long in_contact; /* particles beyond the contact plane */
  int on;          /* a wall in the deck */
  dmi_contact *ct; /* contact between bodies (dm_impact_contact.c) */
} dmi_wall;

typedef struct dmi_run {
  dm_impact *p;
  dm_fin *f;
  dmi_wall *wl;
  const double *X0;
  double E0, P0, Pv0[3], t; /* initial energy, |momentum|, momentum vector */
  double Pabs0;             /* Σ m |u(0)| */
  double *hist;             /* [nhmax][ncol] the rows of impact_history.csv */
  size_t nh, nhmax, ncol;
  /* checkpoints (dm_impact_checkpoint.c) */
  const ms_ctx *ctx; /* the run's context (collective checkpoint files) */
  size_t next_out;   /* particle snapshots written (index of the next one) */
  double ckpt_next;  /* output.checkpoint_time: time of the next checkpoint */
  long step0;        /* the step the run started from (0, or the checkpoint's) */
  bool stopping;     /* interrupted: write a checkpoint at the top of the next step, stop */
} dmi_run;

/* ---- dm_impact_checkpoint.c: OUTDIR/impact_checkpoint.h5 (every rank calls each) ---- */
#define DMI_CHECKPOINT_NAME "impact_checkpoint.h5"
/* Whether the state at the top of the loop (step f->step, time r->t, not the last) gets a
 * checkpoint of the cadence (output.checkpoint_every / checkpoint_time; advances ckpt_next). */
bool dmi_checkpoint_due(dmi_run *r);
/* The state at the top of a step, before anything of it is recorded. */
ms_status dmi_checkpoint_write(dmi_run *r);
/* Reads ctx->restart into the run, after the set-up of a fresh run (the model is rebuilt on the
 * checkpoint's reference configuration when reference updates had moved it); located messages,
 * MS_ERR_INPUT. */
ms_status dmi_restart(dmi_run *r);

#endif
