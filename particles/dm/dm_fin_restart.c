/* SPDX-License-Identifier: MIT */
/* dm_fin_restart.c — checkpoint and restart of the discrete-model problem with response: eos
 * (docs/mpi.md "Checkpoint/restart"): OUTDIR/dm_checkpoint.h5 (core/checkpoint.c: written as
 * .part and renamed, stamped with the deck's hash) holds the model's state through
 * dm_fin_checkpoint.c (the coupled region's code: every array a step reads) and what the run
 * has recorded so far (time, energy rows, profile and snapshot times done, the free-surface
 * history), so that a restarted run writes the same files bit for bit, on any rank count
 * (the model is replicated: rank 0's rows are the whole state). */
#include "dm_fin_run.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DMF_CHECKPOINT_NAME   "dm_checkpoint.h5"
#define DMF_CHECKPOINT_FORMAT "mscale discrete_model response eos checkpoint 1"

/* The done flags of the profile and snapshot times as one column (plus a last 0 row, so that
 * the dataset is never empty). */
static size_t done_rows(const dmf_run *r) {
  return r->p->nprofile_times + r->p->nsnapshot_times + 1;
}

ms_status dmf_checkpoint_write(dmf_run *r) {
  const ms_ctx *ctx = r->ctx;
  const bool owner = ctx->rank == 0;
  ms_h5 *h = ms_ckpt_create(ctx, DMF_CHECKPOINT_NAME, DMF_CHECKPOINT_FORMAT, r->p->deck_hash);
  if (!h) return par_agree_status(MS_ERR_IO);
  ms_status st = dm_fin_checkpoint_write(r->f, &r->s, h, "/dm_fin", owner);
  const size_t nd = done_rows(r);
  double *done = ms_calloc(nd, sizeof *done);
  for (size_t q = 0; q < r->p->nprofile_times; ++q) done[q] = r->prof_done[q];
  for (size_t q = 0; q < r->p->nsnapshot_times; ++q)
    done[r->p->nprofile_times + q] = r->snap_done[q];
  if (st == MS_OK) st = ms_h5_write_doubles_dist(h, "/run/done", owner ? nd : 0, 1, done, "1");
  free(done);
  if (st == MS_OK)
    st = ms_h5_write_doubles_dist(h, "/run/energy", owner ? r->ne : 0, 6, r->eh, "10 us, kJ");
  if (st == MS_OK && r->flyer)
    st = ms_h5_write_doubles_dist(h, "/run/free_surface", owner ? r->fs.n : 0, 2, r->fs.rows,
                                  "10 us, km/s");
  if (st == MS_OK && r->p->nprobes)
    st = ms_h5_write_doubles_dist(h, "/run/probes", owner ? r->nrec : 0, r->pcols, r->hist,
                                  "10 us, cm");
  const char *names[] = {"t", "E0", "dEmax", "fs_stride", "particles", "probe_stride"};
  const double vals[] = {
      r->t, r->E0, r->dEmax, (double)r->fs.stride, (double)r->s.n, (double)r->pstride};
  for (int k = 0; k < 6 && st == MS_OK; ++k)
    st = ms_h5_attr_double(h, "/run/done", names[k], vals[k]);
  return ms_ckpt_commit(ctx, h, st, DMF_CHECKPOINT_NAME, r->f->step);
}

/* Rows of a [≤ nmax][ncol] dataset into dst. */
static ms_status read_rows(ms_h5r *h, const char *name, size_t ncol, size_t nmax, double *dst,
                           size_t *nrow, dk_errors *e) {
  double *v = NULL;
  size_t nr = 0, nc = 0;
  ms_status st = ms_h5_read_doubles_rows(h, name, 0, SIZE_MAX, &v, &nr, &nc, e);
  if (st == MS_OK && (nc != ncol || nr > nmax)) {
    dk_error_at(e, "checkpoint", 0, 0,
                "'%s' has %zu rows of %zu values; expected at most %zu of %zu", name, nr, nc, nmax,
                ncol);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK) memcpy(dst, v, nr * ncol * sizeof *dst), *nrow = nr;
  free(v);
  return st;
}

static ms_status read_run(dmf_run *r, ms_h5r *h, dk_errors *e) {
  const size_t nd = done_rows(r);
  double *done = ms_calloc(nd, sizeof *done);
  size_t n = 0;
  ms_status st = read_rows(h, "/run/done", 1, nd, done, &n, e);
  if (st == MS_OK && n != nd) {
    dk_error_at(e, "checkpoint", 0, 0, "'/run/done' has %zu rows, this deck's output times %zu", n,
                nd);
    st = MS_ERR_INPUT;
  }
  for (size_t q = 0; st == MS_OK && q < r->p->nprofile_times; ++q) r->prof_done[q] = done[q] != 0;
  for (size_t q = 0; st == MS_OK && q < r->p->nsnapshot_times; ++q)
    r->snap_done[q] = done[r->p->nprofile_times + q] != 0;
  free(done);
  if (st == MS_OK) st = read_rows(h, "/run/energy", 6, r->nemax, r->eh, &r->ne, e);
  if (st == MS_OK && r->flyer)
    st = read_rows(h, "/run/free_surface", 2, r->fs.cap, r->fs.rows, &r->fs.n, e);
  if (st == MS_OK && r->p->nprobes)
    st = read_rows(h, "/run/probes", r->pcols, r->nrec_max, r->hist, &r->nrec, e);
  double stride = 1, pstride = 1;
  if (st == MS_OK) st = ms_h5_read_attr_double(h, "/run/done", "t", &r->t, e);
  if (st == MS_OK) st = ms_h5_read_attr_double(h, "/run/done", "E0", &r->E0, e);
  if (st == MS_OK) st = ms_h5_read_attr_double(h, "/run/done", "dEmax", &r->dEmax, e);
  if (st == MS_OK) st = ms_h5_read_attr_double(h, "/run/done", "fs_stride", &stride, e);
  if (st == MS_OK) st = ms_h5_read_attr_double(h, "/run/done", "probe_stride", &pstride, e);
  r->fs.stride = (long)stride, r->pstride = (long)pstride;
  return st;
}

ms_status dmf_restart(dmf_run *r) {
  const ms_ctx *ctx = r->ctx;
  dk_errors e;
  dk_errors_init(&e);
  ms_status st = MS_ERR_INPUT;
  ms_h5r *h = ms_ckpt_open(ctx->restart, DMF_CHECKPOINT_FORMAT, r->p->deck_hash, &e);
  if (h) {
    st = dm_fin_checkpoint_read(r->f, &r->s, h, "/dm_fin", &e);
    if (st == MS_OK) st = read_run(r, h, &e);
    ms_h5_close_read(h);
  }
  st = par_agree_status(st);
  if (st != MS_OK) {
    if (ctx->rank == 0) dk_errors_print(&e, stderr);
    ms_log(ctx, MS_LOG_ERROR, "discrete model: cannot restart from %s", ctx->restart);
    st = MS_ERR_INPUT;
  } else {
    r->step0 = r->f->step;
    ms_log(ctx, MS_LOG_INFO,
           "discrete model (response eos): restarted from %s at step %ld (t = %.9g)", ctx->restart,
           r->step0, r->t);
  }
  dk_errors_free(&e);
  return st;
}
