/* SPDX-License-Identifier: MIT */
/* dm_checkpoint.c — checkpoint and restart of the discrete-model problem (docs/mpi.md): the
 * global state in particle order (the same file for every rank count) and the diagnostics
 * recorded so far, so that a restarted run continues bit for bit. */
#include "dm_problem_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

ms_status dmp_write_checkpoint(const ms_ctx *ctx, const dm_state *s, double dt, int ranks,
                               const dm_checkpoint_data *ck) {
  if (!ctx->outdir || !ctx->outdir[0]) return MS_OK;
  char *path = ms_out_path(ctx, "dm_checkpoint.h5");
  ms_h5 *h = ms_h5_create(path);
  ms_status st = h ? MS_OK : MS_ERR_IO;
  if (st == MS_OK) st = ms_h5_write_doubles(h, "/state/w", s->n, 3, s->w, "cm");
  if (st == MS_OK) st = ms_h5_write_doubles(h, "/state/u", s->n, 3, s->u, "km/s");
  if (st == MS_OK && ck->nrec > 0)
    st = ms_h5_write_doubles(h, "/history/probes", ck->nrec, ck->pcols, ck->hist, "10 us, cm");
  if (st == MS_OK && ck->nerec > 0)
    st = ms_h5_write_doubles(h, "/history/energy", ck->nerec, 5, ck->ehist, "10 us, kJ");
  const char *names[] = {"step", "dt", "particles", "E0", "dw_scale", "energy_err_max", "ranks"};
  double vals[] = {(double)ck->step,   dt,           (double)s->n, ck->E0, ck->dw_scale,
                   ck->energy_err_max, (double)ranks};
  for (int k = 0; k < 7 && st == MS_OK; ++k) st = ms_h5_attr_double(h, "/", names[k], vals[k]);
  if (st == MS_OK) st = ms_h5_attr_string(h, "/", "format", "mscale discrete_model checkpoint 1");
  if (h) {
    if (st == MS_OK) st = ms_h5_close(h);
    else ms_h5_abort(h);
  }
  if (st == MS_OK)
    ms_log(ctx, MS_LOG_INFO, "discrete model: checkpoint at step %ld written to %s", ck->step,
           path);
  else ms_log(ctx, MS_LOG_ERROR, "discrete model: cannot write the checkpoint %s", path);
  free(path);
  return st;
}

static ms_status read_rows(ms_h5r *h, const char *name, size_t ncol, size_t nmax, double *dst,
                           size_t *nrow, dk_errors *e) {
  *nrow = 0;
  if (!ms_h5_exists(h, name)) return MS_OK;
  double *v = NULL;
  size_t n0 = 0, n1 = 0;
  ms_status st = ms_h5_read_doubles(h, name, &v, &n0, &n1, e);
  if (st == MS_OK && (n1 != ncol || n0 > nmax)) {
    dk_error_at(e, "checkpoint", 0, 0, "'%s' has %zu x %zu values, expected at most %zu x %zu",
                name, n0, n1, nmax, ncol);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK) memcpy(dst, v, n0 * ncol * sizeof(double)), *nrow = n0;
  free(v);
  return st;
}

/* Every rank reads the checkpoint into the global state s; the deck must describe the same
 * particles and time step (the restart continues the same run). */
ms_status dmp_read_checkpoint(const ms_ctx *ctx, const char *path, dm_state *s, long nsteps,
                              double dt, dm_checkpoint_data *ck) {
  dk_errors e;
  dk_errors_init(&e);
  ms_status st = MS_ERR_INPUT;
  ms_h5r *h = ms_h5_open_read(path, &e);
  double step = 0, ck_dt = 0, np = 0, E0 = 0, dws = 0, emax = NAN;
  if (h) {
    st = MS_OK;
    if (ms_h5_read_attr_double(h, "/", "step", &step, &e) ||
        ms_h5_read_attr_double(h, "/", "dt", &ck_dt, &e) ||
        ms_h5_read_attr_double(h, "/", "particles", &np, &e) ||
        ms_h5_read_attr_double(h, "/", "E0", &E0, &e) ||
        ms_h5_read_attr_double(h, "/", "dw_scale", &dws, &e) ||
        ms_h5_read_attr_double(h, "/", "energy_err_max", &emax, &e))
      st = MS_ERR_INPUT;
    if (st == MS_OK && ((size_t)np != s->n || ck_dt != dt || step < 0 || step > nsteps)) {
      dk_error_at(&e, path, 0, 0,
                  "checkpoint of %zu particles, dt = %.17g at step %ld does not continue this "
                  "deck (%zu particles, dt = %.17g, %ld steps)",
                  (size_t)np, ck_dt, (long)step, s->n, dt, nsteps);
      st = MS_ERR_INPUT;
    }
    double *v = NULL;
    size_t n0 = 0, n1 = 0;
    for (int k = 0; k < 2 && st == MS_OK; ++k) {
      st = ms_h5_read_doubles(h, k ? "/state/u" : "/state/w", &v, &n0, &n1, &e);
      if (st == MS_OK && (n0 != s->n || n1 != 3)) st = MS_ERR_INPUT;
      if (st == MS_OK) memcpy(k ? s->u : s->w, v, 3 * s->n * sizeof(double));
      free(v);
      v = NULL;
    }
    if (st == MS_OK && ck->hist)
      st = read_rows(h, "/history/probes", ck->pcols, ck->nrec_max, ck->hist, &ck->nrec, &e);
    if (st == MS_OK)
      st = read_rows(h, "/history/energy", 5, ck->nerec_max, ck->ehist, &ck->nerec, &e);
    ms_h5_close_read(h);
  }
  if (st != MS_OK) {
    if (ctx->rank == 0) dk_errors_print(&e, stderr);
    ms_log(ctx, MS_LOG_ERROR, "discrete model: cannot restart from %s", path);
  }
  dk_errors_free(&e);
  ck->step = (long)step, ck->E0 = E0, ck->dw_scale = dws, ck->energy_err_max = emax;
  return st;
}
