/* SPDX-License-Identifier: MIT */
/* cpl_checkpoint.h — private to coupling/: checkpoint/restart of the `coupled` run, one-way and
 * two-way (coupling/cpl_checkpoint.c, docs/coupling.md "Checkpoint/restart"). */
#ifndef MSCALE_CPL_CHECKPOINT_H
#define MSCALE_CPL_CHECKPOINT_H

#include "cont.h"
#include "cpl_impl.h"
#include "ptl_region.h"

/* What the particle phase did to the grids, in order: advance the gas grid to time t, a cell
 * source (drag.gas_return), and in two-way runs the gas grid's first-node velocity and the
 * traction on the main grid's interface node for its next step. A restart replays it on fresh
 * grids, which then hold the same bits as the interrupted run's (the 1D grids are cheap next to
 * the particles; their state never has to be serialised). Rows [kind, a, b, c]. */
typedef struct cpl_gaslog {
  bool on; /* record (checkpoints enabled) */
  size_t n, cap;
  double *row;
} cpl_gaslog;
enum { CPL_LOG_RUN_TO = 0, CPL_LOG_SOURCE = 1, CPL_LOG_VELOCITY = 2, CPL_LOG_TRACTION = 3 };
void cpl_gaslog_run_to(cpl_gaslog *l, double t);
void cpl_gaslog_source(cpl_gaslog *l, size_t cell, double dp, double de);
void cpl_gaslog_velocity(cpl_gaslog *l, double u);
void cpl_gaslog_traction(cpl_gaslog *l, double f);
/* Apply row r (kind run_to, source or velocity) to the gas grid. */
ms_status cpl_gaslog_apply(const double *r, cont_grid *gas);
void cpl_gaslog_free(cpl_gaslog *l);

/* The two-way loop's accumulators (coupled.c, struct two_way), as the checkpoint stores them. */
typedef struct cpl_two_way_acc {
  double gsteps;                /* grid steps done */
  double Jg, Jp, Wg, Wp;        /* impulse and work per cm² as grid and particles received them */
  double owed, dtg_last, p_avg; /* impulse in flight, last grid step, particle pressure */
  double w_before;              /* Wp before the last grid step */
} cpl_two_way_acc;

/* The particle-phase loop's own state at the end of a step. */
typedef struct cpl_loop_state {
  long step, next_out, last_search;
  double p_particles;            /* transmitting piston: the particles' pressure, last step */
  ptl_region_energy e0;          /* at the start of the particle phase */
  double returned_p, returned_e; /* gas return so far */
  double drag_work;              /* this rank's drag work so far (gas_ctx.drag_work) */
  size_t fs_n, fs_cap;           /* drive-check samples (arrays owned by the run) */
  double *fs_t, *fs_ug, *fs_up;
  cpl_gaslog gaslog;
  cpl_two_way_acc tw; /* two-way runs (zero in one-way ones) */
} cpl_loop_state;

#define CPL_CHECKPOINT_NAME "coupled_checkpoint.h5"

/* Refresh the particles (ptl_region_refresh) and write OUTDIR/coupled_checkpoint.h5: particles,
 * loop state, the gas log and the text so far of the streamed CSV files. Every rank. */
ms_status cpl_checkpoint_write(const ms_ctx *ctx, uint64_t deck_hash, ptl_region *region,
                               const cpl_loop_state *ls, ms_afile *const *csv, int ncsv);
/* Restart: replaces the region's particles by the checkpoint's and initialises it from them
 * (ptl_region_restore), restores the loop state (ls->fs_* arrays must have room: fs_cap),
 * replays the gas log on `gas` (NULL: the caller replays ls->gaslog itself, as two-way runs do
 * step by step) and writes the CSV text back. Every rank; MS_ERR_INPUT with a message for
 * another deck or a damaged file. */
ms_status cpl_checkpoint_restore(const ms_ctx *ctx, uint64_t deck_hash, ptl_region *region,
                                 cpl_loop_state *ls, cont_grid *gas, ms_afile *const *csv,
                                 int ncsv);

#endif
