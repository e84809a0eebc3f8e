/* SPDX-License-Identifier: MIT */
/* cpl_checkpoint.c — checkpoint/restart of the `coupled` run (docs/coupling.md §7b).
 *
 * OUTDIR/coupled_checkpoint.h5 (core/checkpoint.c: atomic, deck hash, rank count) holds
 *   /cd/...            the particle region (ptl_region_checkpoint_write; cluster dynamics:
 *                      particles/cd/cd_checkpoint.c);
 *   /loop              attributes step, next_out, last_search, p_particles, returned_p,
 *                      returned_e, drag_work and the two-way accumulators (gsteps, J_grid, J_particles,
 *                      W_grid, W_particles, owed, dtg_last, p_avg, w_before; 0 in one-way runs);
 *                      datasets e0 (the initial energy terms), fs [n][3] (drive-check samples t,
 *                      u_grid, u_particles), gaslog [n][4] (what was done to the grids,
 *                      replayed on restart);
 *   /outputs/csvK      the text so far of the streamed CSV files.
 * The grid run that makes the drive history (phase 1) is deterministic and repeated by the
 * restart; the transport phase is not checkpointed (it starts after the particle phase and is
 * repeated from the last checkpoint). Two-way runs replay the whole log through the grid's
 * own loop (coupled.c), which rebuilds the grid's outputs too. */
#include "cpl_checkpoint.h"

#include <stdlib.h>
#include <string.h>

#define CPL_CHECKPOINT_FORMAT "mscale coupled checkpoint 3" /* 3: drag_work */

static void gaslog_add(cpl_gaslog *l, double kind, double a, double b, double c) {
  if (!l->on) return;
  if (l->n == l->cap) { /* amortised doubling: a few reallocations over a run */
    l->cap = l->cap ? 2 * l->cap : 256;
    l->row = ms_realloc(l->row, 4 * l->cap, sizeof *l->row);
  }
  double *r = l->row + 4 * l->n++;
  r[0] = kind, r[1] = a, r[2] = b, r[3] = c;
}
void cpl_gaslog_run_to(cpl_gaslog *l, double t) { gaslog_add(l, CPL_LOG_RUN_TO, t, 0, 0); }
void cpl_gaslog_source(cpl_gaslog *l, size_t cell, double dp, double de) {
  gaslog_add(l, CPL_LOG_SOURCE, (double)cell, dp, de);
}
void cpl_gaslog_velocity(cpl_gaslog *l, double u) { gaslog_add(l, CPL_LOG_VELOCITY, u, 0, 0); }
void cpl_gaslog_traction(cpl_gaslog *l, double f) { gaslog_add(l, CPL_LOG_TRACTION, f, 0, 0); }

ms_status cpl_gaslog_apply(const double *r, cont_grid *gas) {
  if (r[0] == CPL_LOG_RUN_TO) return cont_grid_run_to(gas, r[1]);
  if (r[0] == CPL_LOG_SOURCE && r[1] >= 0 && r[1] < (double)cont_grid_ncells(gas))
    return cont_grid_add_cell_source(gas, (size_t)r[1], r[2], r[3]);
  if (r[0] == CPL_LOG_VELOCITY) {
    cont_grid_set_node_velocity(gas, 0, r[1]);
    return MS_OK;
  }
  return MS_ERR_INPUT;
}
void cpl_gaslog_free(cpl_gaslog *l) {
  free(l->row);
  memset(l, 0, sizeof *l);
}

static const char *const loop_attrs[] = {"step",       "next_out",    "last_search", "p_particles",
                                         "returned_p", "returned_e",  "drag_work",   "gsteps",
                                         "J_grid",     "J_particles", "W_grid",      "W_particles",
                                         "owed",       "dtg_last",    "p_avg",       "w_before"};
enum { N_TW = sizeof(cpl_two_way_acc) / sizeof(double) };
enum {
  N_LOOP = sizeof loop_attrs / sizeof *loop_attrs,
  N_E0 = sizeof(ptl_region_energy) / sizeof(double)
};
_Static_assert(N_LOOP == 7 + N_TW, "loop_attrs: 7 loop values, then cpl_two_way_acc in order");

ms_status cpl_checkpoint_write(const ms_ctx *ctx, uint64_t deck_hash, ptl_region *region,
                               const cpl_loop_state *ls, ms_afile *const *csv, int ncsv) {
  ms_status st = ptl_region_refresh(region); /* what the restart repeats (ptl_region_restore) */
  if (st != MS_OK) return st;
  ms_h5 *h = ms_ckpt_create(ctx, CPL_CHECKPOINT_NAME, CPL_CHECKPOINT_FORMAT, deck_hash);
  if (!h) return MS_ERR_IO;
  const bool root = ctx->rank == 0; /* replicated data: rank 0 writes it */
  st = ptl_region_checkpoint_write(region, h, ctx);
  /* the drag's work as one total (each rank kicks its own particles); a restart gives it to
   * rank 0, so the ranks' sum stays the run's */
  const double drag = ctx->size > 1 ? par_sum_double(ls->drag_work) : ls->drag_work;
  double vals[N_LOOP] = {(double)ls->step,
                         (double)ls->next_out,
                         (double)ls->last_search,
                         ls->p_particles,
                         ls->returned_p,
                         ls->returned_e,
                         drag};
  memcpy(vals + N_LOOP - N_TW, &ls->tw, sizeof ls->tw);
  for (int k = 0; k < N_LOOP && st == MS_OK; k++)
    st = ms_h5_attr_double(h, "/loop", loop_attrs[k], vals[k]);
  double e0[N_E0];
  memcpy(e0, &ls->e0, sizeof e0);
  if (st == MS_OK) st = ms_h5_write_doubles_dist(h, "/loop/e0", root ? N_E0 : 0, 1, e0, "kJ");
  double *fs = ms_calloc(3 * ls->fs_n + 1, sizeof *fs);
  for (size_t k = 0; k < ls->fs_n; k++)
    fs[3 * k] = ls->fs_t[k], fs[3 * k + 1] = ls->fs_ug[k], fs[3 * k + 2] = ls->fs_up[k];
  if (st == MS_OK)
    st = ms_h5_write_doubles_dist(h, "/loop/fs", root ? ls->fs_n : 0, 3, fs, "10us, km/s, km/s");
  free(fs);
  if (st == MS_OK)
    st = ms_h5_write_doubles_dist(h, "/loop/gaslog", root ? ls->gaslog.n : 0, 4, ls->gaslog.row,
                                  NULL);
  for (int k = 0; k < ncsv && st == MS_OK; k++) {
    char name[32];
    snprintf(name, sizeof name, "/outputs/csv%d", k);
    st = ms_ckpt_save_afile(ctx, h, name, csv[k]);
  }
  return ms_ckpt_commit(ctx, h, st, CPL_CHECKPOINT_NAME, ls->step);
}

static ms_status read_table(ms_h5r *h, const char *name, size_t ncol, size_t nmax, double **v,
                            size_t *n, dk_errors *e) {
  size_t nc = 0;
  ms_status st = ms_h5_read_doubles_rows(h, name, 0, SIZE_MAX, v, n, &nc, e);
  if (st == MS_OK && (nc != ncol || *n > nmax)) {
    dk_error_at(e, "checkpoint", 0, 0,
                "'%s' has %zu rows of %zu values, expected at most %zu of "
                "%zu",
                name, *n, nc, nmax, ncol);
    st = MS_ERR_INPUT;
  }
  return st;
}

/* Every rank reads (the run is replicated apart from the particles). */
static ms_status restore(const ms_ctx *ctx, ms_h5r *h, ptl_region *region, cpl_loop_state *ls,
                         cont_grid *gas, ms_afile *const *csv, int ncsv, dk_errors *e) {
  long region_step = 0;
  ms_status st = ptl_region_restore(region, h, ctx, &region_step, e);
  if (st != MS_OK) return st;
  double vals[N_LOOP];
  for (int k = 0; k < N_LOOP && st == MS_OK; k++)
    st = ms_h5_read_attr_double(h, "/loop", loop_attrs[k], &vals[k], e);
  double *e0 = NULL, *fs = NULL, *log = NULL;
  size_t n = 0, nfs = 0, nlog = 0;
  if (st == MS_OK) st = read_table(h, "/loop/e0", 1, N_E0, &e0, &n, e);
  if (st == MS_OK && n != N_E0) {
    dk_error_at(e, "checkpoint", 0, 0, "'/loop/e0' needs %d values", (int)N_E0);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK) st = read_table(h, "/loop/fs", 3, ls->fs_cap, &fs, &nfs, e);
  if (st == MS_OK) st = read_table(h, "/loop/gaslog", 4, SIZE_MAX, &log, &nlog, e);
  if (st == MS_OK) {
    ls->step = (long)vals[0], ls->next_out = (long)vals[1], ls->last_search = (long)vals[2];
    ls->p_particles = vals[3], ls->returned_p = vals[4], ls->returned_e = vals[5];
    ls->drag_work = ctx->rank == 0 ? vals[6] : 0.0;
    memcpy(&ls->tw, vals + N_LOOP - N_TW, sizeof ls->tw);
    memcpy(&ls->e0, e0, sizeof ls->e0);
    ls->fs_n = nfs;
    for (size_t k = 0; k < nfs; k++)
      ls->fs_t[k] = fs[3 * k], ls->fs_ug[k] = fs[3 * k + 1], ls->fs_up[k] = fs[3 * k + 2];
    /* the gas grid: the same operations in the same order (and logged again, for the next
     * checkpoint); two-way runs replay them themselves */
    for (size_t k = 0; k < nlog && st == MS_OK; k++) {
      const double *r = log + 4 * k;
      if (gas && (st = cpl_gaslog_apply(r, gas)) != MS_OK)
        dk_error_at(e, "checkpoint", 0, 0, "replaying the gas grid failed at entry %zu: %s", k,
                    cont_grid_error(gas));
      gaslog_add(&ls->gaslog, r[0], r[1], r[2], r[3]);
    }
  }
  for (int k = 0; k < ncsv && st == MS_OK; k++) {
    char name[32];
    snprintf(name, sizeof name, "/outputs/csv%d", k);
    st = ms_ckpt_restore_afile(ctx, h, name, csv[k], e);
  }
  if (st == MS_OK && region_step != ls->step) {
    dk_error_at(e, "checkpoint", 0, 0, "particle step %ld and loop step %ld disagree", region_step,
                ls->step);
    st = MS_ERR_INPUT;
  }
  free(e0), free(fs), free(log);
  return st;
}

ms_status cpl_checkpoint_restore(const ms_ctx *ctx, uint64_t deck_hash, ptl_region *region,
                                 cpl_loop_state *ls, cont_grid *gas, ms_afile *const *csv,
                                 int ncsv) {
  dk_errors e;
  dk_errors_init(&e);
  ms_h5r *h = ms_ckpt_open(ctx->restart, CPL_CHECKPOINT_FORMAT, deck_hash, &e);
  ms_status st = h ? restore(ctx, h, region, ls, gas, csv, ncsv, &e) : MS_ERR_INPUT;
  ms_h5_close_read(h);
  st = par_agree_status(st);
  if (st != MS_OK) {
    if (ctx->rank == 0) dk_errors_print(&e, stderr);
    ms_log(ctx, MS_LOG_ERROR, "coupled: cannot restart from %s", ctx->restart);
  } else {
    ms_log(ctx, MS_LOG_INFO, "coupled: restarted from %s at particle step %ld", ctx->restart,
           ls->step);
  }
  dk_errors_free(&e);
  return st;
}
