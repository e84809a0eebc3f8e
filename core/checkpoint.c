/* SPDX-License-Identifier: MIT */
/* Checkpoint files shared by the restartable problems (docs/mpi.md, "Checkpoint/restart").
 *
 * A checkpoint is an HDF5 file written collectively (every rank adds its own segment of the
 * distributed arrays) as "<name>.part" and renamed when complete, so a crash while writing
 * leaves the previous checkpoint untouched. Its root carries the format name, the hash of the
 * resolved deck (dk_hash) and the rank count; a restart checks the first two before reading
 * anything else. Output files that a run streams (CSV) are stored as their text so far and
 * written back into the restarted run's files, which then continue byte for byte. */
#include "core.h"

#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static void hash_text(uint64_t h, char buf[17]) { snprintf(buf, 17, "%016" PRIx64, h); }

ms_h5 *ms_ckpt_create(const ms_ctx *ctx, const char *name, const char *format, uint64_t deck_hash) {
  char *path = ms_out_path(ctx, name), hex[17];
  ms_h5 *h = ms_h5_create_collective(path);
  free(path);
  if (!h) return NULL;
  hash_text(deck_hash, hex);
  ms_status st = ms_h5_attr_string(h, "/", "format", format);
  if (st == MS_OK) st = ms_h5_attr_string(h, "/", "deck_hash", hex);
  if (st == MS_OK) st = ms_h5_attr_string(h, "/", "version", MSCALE_VERSION_STRING);
  if (st == MS_OK) st = ms_h5_attr_double(h, "/", "ranks", (double)ctx->size);
  if (st != MS_OK) {
    ms_h5_abort(h);
    return NULL;
  }
  return h;
}

ms_status ms_ckpt_commit(const ms_ctx *ctx, ms_h5 *h, ms_status st, const char *name, long step) {
  if (!h) return MS_ERR_IO;
  /* MSCALE_CHECKPOINT_DELAY (seconds): hold the complete .part file open before the rename, so
   * that tests can kill the run inside a checkpoint write (tests/restart_check.sh). */
  const char *delay = getenv("MSCALE_CHECKPOINT_DELAY");
  double d = delay ? atof(delay) : 0.0;
  st = par_agree_status(st);
  if (st == MS_OK && d > 0) {
    struct timespec ts = {(time_t)d, (long)((d - (double)(time_t)d) * 1e9)};
    nanosleep(&ts, NULL);
  }
  if (st == MS_OK) {
    st = ms_h5_close(h);
  } else {
    ms_h5_abort(h);
  }
  char *path = ms_out_path(ctx, name);
  if (st == MS_OK) ms_log(ctx, MS_LOG_INFO, "checkpoint at step %ld written to %s", step, path);
  else ms_log(ctx, MS_LOG_ERROR, "cannot write the checkpoint %s (the previous one is kept)", path);
  free(path);
  return st;
}

ms_h5r *ms_ckpt_open(const char *path, const char *format, uint64_t deck_hash, dk_errors *e) {
  ms_h5r *h = ms_h5_open_read(path, e);
  if (!h) return NULL;
  char *fmt = NULL, *hash = NULL, hex[17];
  hash_text(deck_hash, hex);
  bool ok = ms_h5_read_attr_string(h, "/", "format", &fmt, e) == MS_OK &&
            ms_h5_read_attr_string(h, "/", "deck_hash", &hash, e) == MS_OK;
  if (ok && strcmp(fmt, format) != 0) {
    dk_error_at(e, path, 0, 0, "not a checkpoint of this problem type: format '%s', expected '%s'",
                fmt, format);
    ok = false;
  } else if (ok && strcmp(hash, hex) != 0) {
    dk_error_at(e, path, 0, 0,
                "the checkpoint was written by a different deck (deck hash %s, "
                "this deck's is %s): a restart must use the deck that wrote the checkpoint",
                hash, hex);
    ok = false;
  }
  free(fmt);
  free(hash);
  if (!ok) {
    ms_h5_close_read(h);
    return NULL;
  }
  return h;
}

ms_status ms_ckpt_save_afile(const ms_ctx *ctx, ms_h5 *h, const char *name, ms_afile *af) {
  char *text = NULL;
  size_t len = 0;
  ms_status st = MS_OK;
  if (ctx->rank == 0 && af->f) { /* the file is written by rank 0: read its text so far back */
    long end = (fflush(af->f) == 0) ? ftell(af->f) : -1;
    FILE *f = end >= 0 ? fopen(af->tmp_path, "rb") : NULL;
    text = ms_calloc((size_t)(end > 0 ? end : 0) + 1, 1);
    if (!f || fread(text, 1, (size_t)end, f) != (size_t)end) st = MS_ERR_IO;
    else len = (size_t)end;
    if (f) fclose(f);
  }
  ms_status w = ms_h5_write_bytes_dist(h, name, len, text ? text : "");
  free(text);
  return st != MS_OK ? st : w;
}

ms_status ms_ckpt_restore_afile(const ms_ctx *ctx, ms_h5r *h, const char *name, ms_afile *af,
                                dk_errors *e) {
  char *text = NULL;
  size_t len = 0;
  ms_status st = ms_h5_read_bytes(h, name, &text, &len, e);
  if (st == MS_OK && ctx->rank == 0 && af->f && fwrite(text, 1, len, af->f) != len) st = MS_ERR_IO;
  if (st == MS_OK && ctx->rank == 0 && af->f) ms_csv_resume(af->f, text, len);
  free(text);
  return st;
}
