/* SPDX-License-Identifier: MIT */
/* dm_flyer.c — the flyer-plate problem of the finite-deformation discrete model
 * (docs/particles-dm.md, "Flyer onto a target"): two bodies along x with their own materials
 * and velocities, free x ends, periodic sides; records the target's free-surface velocity. */
#include "dm_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- the x slab of the piston (dm_finite.c) and the flyer problems ---- */

void dm_slab_place(dm_state *s, int dim, long nx, long ny, long nz, double h,
                   const dm_fin_material *mat, const uint8_t *imat) {
  const double vol = pow(h, dim);
  for (long iz = 0; iz < nz; ++iz)
    for (long iy = 0; iy < ny; ++iy)
      for (long ix = 0; ix < nx; ++ix) {
        const size_t i = (size_t)((iz * ny + iy) * nx + ix);
        const dm_fin_material *mt = &mat[imat[i]];
        const double rho0 = eos_rho0(mt->eos);
        s->X[3 * i] = (ix + 0.5) * h;
        s->X[3 * i + 1] = dim > 1 ? (iy + 0.5) * h : 0.0;
        s->X[3 * i + 2] = dim > 2 ? (iz + 0.5) * h : 0.0;
        for (int a = 0; a < 3; ++a) s->w[3 * i + a] = s->u[3 * i + a] = 0.0;
        s->mass[i] = rho0 * vol, s->vol[i] = vol;
        s->K[i] = rho0 * pow(eos_c0(mt->eos), 2), s->G[i] = mt->G;
        s->bc[i] = DM_FREE;
      }
}

ms_status dm_slab_create(dm_state *s, long ny, long nz, double h, double horizon,
                         const dm_fin_material *mat, uint8_t *imat, const dm_fin_params *par,
                         const ms_ctx *ctx, dm_model **m, dm_fin **f) {
  dm_options opt = {.horizon = horizon * h, .cond_max = 1e8, .hourglass = 0.0};
  if (s->dim > 1) opt.box[1] = ny * h;
  if (s->dim > 2) opt.box[2] = nz * h;
  *m = NULL, *f = NULL;
  ms_status st = dm_model_create(&(dm_model_params){.state = s, .opt = opt, .ctx = ctx}, m);
  if (st == MS_OK)
    st = dm_fin_create(&(dm_fin_setup){.m = *m, .mat = mat, .imat = imat, .par = *par}, f);
  if (st != MS_OK) free(imat), dm_model_destroy(m), dm_state_free(s);
  return st;
}

void dm_slab_layers(const dm_fin *f, const dm_state *s, long nx, long nyz, double *lay) {
  for (long ix = 0; ix < nx; ++ix) {
    double *r = &lay[8 * ix];
    for (long j = 0; j < nyz; ++j) {
      const size_t i = (size_t)(j * nx + ix);
      r[0] += s->X[3 * i], r[1] += s->X[3 * i] + s->w[3 * i], r[2] += s->u[3 * i];
      r[3] += f->rho[i], r[4] += f->p[i], r[5] += f->q[i], r[6] += -f->sig[9 * i];
      r[7] += f->e[i];
    }
    for (int c = 0; c < 8; ++c) r[c] /= (double)nyz;
  }
}

/* ---- the flyer problem ---- */

ms_status dm_flyer_run(const dm_flyer_spec *sp, const ms_ctx *ctx, dm_flyer_result *res) {
  memset(res, 0, sizeof *res);
  const int dim = sp->dim;
  const long nx = sp->nflyer + sp->ntarget, ny = dim > 1 ? sp->ny : 1, nz = dim > 2 ? sp->nz : 1;
  if (sp->nflyer < 1 || sp->ntarget < 1 || ny < 1 || nz < 1 || sp->nhist < 2 || !(sp->h > 0))
    return res->status = MS_ERR_INPUT;
  const size_t n = (size_t)(nx * ny * nz);
  const double h = sp->h;
  dm_state s;
  dm_state_alloc(&s, n, dim);
  uint8_t *imat = ms_calloc(n, 1);
  for (size_t i = 0; i < n; ++i) imat[i] = (uint8_t)((long)(i % (size_t)nx) >= sp->nflyer);
  dm_slab_place(&s, dim, nx, ny, nz, h, sp->mat, imat);
  for (size_t i = 0; i < n; ++i) s.u[3 * i] = sp->u[imat[i]]; /* 0 flyer, 1 target */
  dm_model *m;
  dm_fin *f;
  ms_status st = dm_slab_create(&s, ny, nz, h, sp->horizon, sp->mat, imat, &sp->par, ctx, &m, &f);
  if (st != MS_OK) return res->status = st;
  double K, U, H;
  dm_fin_energies(f, &K, &U, &H);
  const double E0 = K + U + H;
  res->K0 = K;
  dm_fs_history fs;
  dm_fs_history_init(&fs, sp->nhist);
  double t = 0.0, dEmax = 0.0;
  res->t_fail = res->X_fail = NAN;
  for (long step = 0;; ++step) {
    dm_fs_history_record(&fs, step, t, &s, nx, ny * nz);
    if (t >= sp->t_end * (1 - 1e-12) || st != MS_OK) break;
    if (t + f->dt_next > sp->t_end) f->dt_next = sp->t_end - t;
    t += f->dt_next;
    st = dm_fin_step(f);
    dm_fin_energies(f, &K, &U, &H);
    dEmax = fmax(dEmax, fabs(K + U + H + dm_fin_broken_energy(f) + dm_fin_contact_energy(f) - E0));
    if (f->failed && isnan(res->t_fail) && dm_fin_failed_count(f) > 0) {
      double sx = 0, c = 0;
      for (size_t i = 0; i < n; ++i)
        if (f->failed[i]) sx += s.X[3 * i], c += 1;
      res->t_fail = t, res->X_fail = sx / c;
    }
  }
  res->broken = dm_fin_broken_energy(f), res->nfailed = dm_fin_failed_count(f);
  if (f->failed) {
    res->failed_layer = ms_calloc((size_t)nx, sizeof(double));
    for (size_t i = 0; i < n; ++i)
      res->failed_layer[i % (size_t)nx] += (f->failed[i] != 0) / (double)(ny * nz);
  }
  res->steps = f->step;
  res->hist = fs.rows, res->nhist = fs.n;
  res->energy_err = res->K0 > 0 ? dEmax / res->K0 : dEmax;
  res->hg_ratio = res->K0 > 0 ? H / res->K0 : H;
  double *lay = ms_calloc((size_t)nx * 8, sizeof(double));
  dm_slab_layers(f, &s, nx, ny * nz, lay);
  res->profile = lay;
  if (st != MS_OK)
    ms_log(ctx, MS_LOG_ERROR, "discrete model (flyer): step %ld: particle %zu: %s = %g", f->step,
           f->bad, f->bad_what, f->bad_value);
  free(imat);
  dm_fin_destroy(&f);
  dm_model_destroy(&m);
  dm_state_free(&s);
  return res->status = st;
}
