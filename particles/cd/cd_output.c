/* SPDX-License-Identifier: MIT */
/* cd_output.c — the output files of the `cluster_dynamics` problem (docs/input-cd.md): energy
 * balance, binned profiles and front positions (CSV, rank 0), the shock-speed fit of the front,
 * and their part of the checkpoint (docs/mpi.md): OUTDIR/cd_checkpoint.h5. */
#include "cd_problem_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The energy row; v_free_surface only in a run with a free-surface layer (a piston run: the
 * layer is tagged opposite the piston), so that no row holds NaN. */
static void write_energy_row(FILE *f, const cd_sim *s, const cd_energy *e, double vfs, bool with) {
  double row[11] = {s->t,           e->kinetic,     e->potential, e->dissipated,
                    e->broken,      e->piston_work, e->total,     e->momentum[0],
                    e->momentum[1], e->momentum[2], vfs};
  ms_csv_row(f, with ? 11 : 10, row);
}

static void write_headers(FILE *fe, FILE *fp, FILE *ff, bool with_vfs) {
  static const char *const ecol[] = {"t",      "kinetic",     "potential",     "dissipated",
                                     "broken", "piston_work", "total",         "px",
                                     "py",     "pz",          "v_free_surface"};
  static const char *const eunit[] = {"10us",      "g(km/s)^2", "g(km/s)^2", "g(km/s)^2",
                                      "g(km/s)^2", "g(km/s)^2", "g(km/s)^2", "g km/s",
                                      "g km/s",    "g km/s",    "km/s"};
  ms_csv_header(fe,
                "cluster dynamics energy balance (total = kinetic + potential + dissipated "
                "+ broken - piston_work)",
                with_vfs ? 11 : 10, ecol, eunit);
  const char *pcol[CD_PROFILE_NCOL + 1] = {"t"};
  const char *punit[CD_PROFILE_NCOL + 1] = {"10us", "cm",  "-",   "g/cm^3", "km/s", "km/s", "km/s",
                                            "GPa",  "GPa", "GPa", "GPa",    "GPa",  "GPa",  "GPa"};
  for (int c = 0; c < CD_PROFILE_NCOL; c++) pcol[c + 1] = cd_profile_columns[c];
  ms_csv_header(fp, "cluster dynamics binned profiles (stress compression-positive)",
                CD_PROFILE_NCOL + 1, pcol, punit);
  static const char *const fcol[] = {"t", "front"}, *const funit[] = {"10us", "cm"};
  ms_csv_header(ff,
                "shock front: where the bin-mean velocity along the profile axis falls "
                "below half the front_velocity",
                2, fcol, funit);
}

static const char *const stream_names[CD_NSTREAMS] = {
    "/outputs/cd_energy.csv", "/outputs/cd_profiles.csv", "/outputs/cd_front.csv"};

ms_status cd_outputs_checkpoint(ms_ctx *ctx, const cd_problem *p, cd_sim *s, cd_outputs *o) {
  ms_afile *const streams[CD_NSTREAMS] = {&o->fe, &o->fp, &o->ff};
  ms_status st = cd_sim_refresh(s);
  if (st != MS_OK) return st;
  ms_h5 *h = ms_ckpt_create(ctx, "cd_checkpoint.h5", CD_CHECKPOINT_FORMAT, p->deck_hash);
  if (!h) return MS_ERR_IO;
  st = cd_checkpoint_write(h, ctx, s);
  for (int k = 0; k < CD_NSTREAMS && st == MS_OK; k++)
    st = ms_ckpt_save_afile(ctx, h, stream_names[k], streams[k]);
  if (st == MS_OK)
    st = ms_h5_write_doubles_dist(h, "/outputs/front", ctx->rank == 0 ? (size_t)o->nf : 0, 2,
                                  o->front, "10us, cm");
  return ms_ckpt_commit(ctx, h, st, "cd_checkpoint.h5", s->step);
}

ms_status cd_outputs_restore(const ms_ctx *ctx, ms_h5r *h, cd_outputs *o) {
  ms_afile *const streams[CD_NSTREAMS] = {&o->fe, &o->fp, &o->ff};
  dk_errors e;
  dk_errors_init(&e);
  ms_status st = MS_OK;
  for (int k = 0; k < CD_NSTREAMS && st == MS_OK; k++)
    st = ms_ckpt_restore_afile(ctx, h, stream_names[k], streams[k], &e);
  double *v = NULL;
  size_t n = 0, ncol = 0;
  if (st == MS_OK)
    st = ms_h5_read_doubles_rows(h, "/outputs/front", 0, SIZE_MAX, &v, &n, &ncol, &e);
  if (st == MS_OK && (ncol != 2 || n > CD_MAX_FRONT)) {
    dk_error_at(&e, ctx->restart, 0, 0, "'/outputs/front' is not a table of at most %d (t, z) rows",
                CD_MAX_FRONT);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK) {
    memcpy(o->front, v, 2 * n * sizeof *v);
    o->nf = (int)n;
  }
  free(v);
  st = par_agree_status(st);
  if (st != MS_OK && ctx->rank == 0) dk_errors_print(&e, stderr);
  dk_errors_free(&e);
  return st;
}

ms_status cd_outputs_open(ms_ctx *ctx, cd_outputs *o, bool restart) {
  const bool root = ctx->rank == 0;
  ms_status st = MS_OK;
  if (root) {
    char *path = ms_out_path(ctx, "cd_energy.csv");
    st = ms_afile_open(&o->fe, path);
    free(path);
    if (st == MS_OK) {
      path = ms_out_path(ctx, "cd_profiles.csv");
      st = ms_afile_open(&o->fp, path);
      free(path);
    }
    if (st == MS_OK) {
      path = ms_out_path(ctx, "cd_front.csv");
      st = ms_afile_open(&o->ff, path);
      free(path);
    }
  }
  if (ctx->size > 1) st = par_agree_status(st);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: cannot open output files");
    return st;
  }
  /* a restart writes back the text so far */
  if (!restart && root) write_headers(o->fe.f, o->fp.f, o->ff.f, o->with_vfs);
  return MS_OK;
}

void cd_outputs_setup(const cd_problem *p, const cd_sim *s, cd_outputs *o) {
  const int axis = p->profile_axis;
  o->axis = axis;
  double lo = p->box.lo[axis], hi = p->box.hi[axis];
  if (p->box.bc[axis] != CD_BC_PERIODIC) { /* free axis: the extent may grow; pad by 50 % */
    double L = hi - lo;
    hi += 0.5 * L;
  }
  double area = 1.0; /* of the box at the start (a relaxation may have rescaled it) */
  for (int a = 0; a < p->dim; a++)
    if (a != axis) area *= s->box.hi[a] - s->box.lo[a];
  if (p->dim == 2) area *= p->thickness;
  o->lo = lo, o->hi = hi, o->area = area;
  o->prof = ms_calloc((size_t)p->profile_bins * CD_PROFILE_NCOL, sizeof *o->prof);
}

void cd_outputs_write(ms_ctx *ctx, const cd_problem *p, cd_sim *s, cd_outputs *o) {
  const bool root = ctx->rank == 0;
  const int axis = o->axis;
  cd_energy en;
  cd_sim_energy(s, &en);
  const double vfs = cd_free_surface_velocity(s, axis);
  if (root) write_energy_row(o->fe.f, s, &en, vfs, o->with_vfs);
  cd_profile(s, axis, o->lo, o->hi, p->profile_bins, o->area, o->prof);
  for (int b = 0; b < p->profile_bins; b++) {
    double row[CD_PROFILE_NCOL + 1];
    row[0] = s->t;
    memcpy(row + 1, o->prof + (size_t)b * CD_PROFILE_NCOL, CD_PROFILE_NCOL * sizeof(double));
    if (row[2] > 0 && root) ms_csv_row(o->fp.f, CD_PROFILE_NCOL + 1, row);
  }
  if (p->front_u > 0) {
    double z = cd_front_position(o->prof, p->profile_bins, axis, p->front_u, 0.5);
    double row[2] = {s->t, z};
    if (root && isfinite(z)) ms_csv_row(o->ff.f, 2, row); /* no row (never NaN) before a front */
    if (isfinite(z) && o->nf < CD_MAX_FRONT) {
      o->front[2 * o->nf] = s->t;
      o->front[2 * o->nf++ + 1] = z;
    }
  }
}

void cd_outputs_front_fit(ms_ctx *ctx, const cd_outputs *o) {
  const int nf = o->nf;
  const double *front = o->front;
  if (nf > 3) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int m = 0;
    for (int k = 0; k < nf; k++) {
      const double tk = front[2 * k], zk = front[2 * k + 1];
      if (tk >= 0.25 * front[2 * (nf - 1)]) {
        sx += tk;
        sy += zk;
        sxx += tk * tk;
        sxy += tk * zk;
        m++;
      }
    }
    if (m > 2)
      ms_log(ctx, MS_LOG_INFO,
             "cluster_dynamics: shock speed D = %.4f km/s (front fit over t >= T/4)",
             (m * sxy - sx * sy) / (m * sxx - sx * sx));
  }
}

ms_status cd_outputs_close(ms_ctx *ctx, const cd_sim *s, cd_outputs *o, ms_status st) {
  const bool root = ctx->rank == 0;
  if ((st == MS_OK || st == MS_ERR_UNSTABLE) && root) { /* unstable: keep the series so far */
    ms_status sc = ms_afile_commit(&o->fe);
    if (sc == MS_OK) sc = ms_afile_commit(&o->fp);
    else ms_afile_abort(&o->fp);
    if (sc == MS_OK) sc = ms_afile_commit(&o->ff);
    else ms_afile_abort(&o->ff);
    if (sc != MS_OK) ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: cannot write the CSV files");
    if (st == MS_OK) st = sc;
  } else if (st != MS_OK && st != MS_ERR_UNSTABLE) {
    ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: stopped at t = %g %s (%s)", ms_out_time(s->t),
           ms_out_time_label(), ms_status_str(st));
    cd_outputs_free(o);
  }
  return st;
}

void cd_outputs_free(cd_outputs *o) {
  ms_afile_abort(&o->fe);
  ms_afile_abort(&o->fp);
  ms_afile_abort(&o->ff);
  free(o->prof);
  o->prof = NULL;
}
