/* SPDX-License-Identifier: MIT */
/* dm_problem_finite.c — the run of the discrete-model problem with response: eos: the
 * finite-deformation model (dm_finite.c), on one rank. */
#include "dm_problem_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The layers' initial velocities (returns 1 if some layer has one: the flyer problem, with its
 * free-surface history), the piston's driven layers, ghosts at rest. */
static int set_velocities(const dm_problem *p, dm_state *s, size_t nreal) {
  int flyer = 0;
  for (size_t i = 0; i < nreal; ++i) {
    const dm_layer *ly = dmp_layer_at(p, s->X[3 * i]);
    if (ly->has_u0) s->u[3 * i] = ly->u0, flyer = 1;
  }
  if (p->has_piston)
    for (size_t i = 0; i < nreal; ++i)
      if ((long)(i % (size_t)p->ncell[0]) < p->piston_layers) {
        s->bc[i] = DM_PRESCRIBED;
        s->u[3 * i] = p->piston_u, s->u[3 * i + 1] = s->u[3 * i + 2] = 0.0;
      }
  for (size_t i = nreal; i < s->n; ++i) s->u[3 * i] = s->u[3 * i + 1] = s->u[3 * i + 2] = 0.0;
  return flyer;
}

ms_status dmp_run_finite(ms_ctx *ctx, dm_problem *p) {
  dm_run_summary *sum = &p->sum;
  if (ctx->size > 1) {
    ms_log(ctx, MS_LOG_ERROR, "discrete model: response: eos runs on one rank (not distributed)");
    return MS_ERR_INPUT;
  }
  if (ctx->restart) {
    ms_log(ctx, MS_LOG_ERROR, "discrete model: response: eos has no restart yet");
    return MS_ERR_INPUT;
  }
  dm_state s;
  dmp_build_particles(p, &s);
  const size_t nreal = (size_t)(p->ncell[0] * p->ncell[1] * p->ncell[2]);
  dmp_set_initial(p, &s, nreal);
  const int flyer = set_velocities(p, &s, nreal);
  dm_options opt = {.horizon = p->horizon * p->h, .cond_max = p->cond_max, .hourglass = 0.0};
  for (int a = 0; a < p->dim; ++a)
    if (p->face[2 * a] == FACE_PERIODIC) opt.box[a] = p->hi[a] - p->lo[a];
  dm_model *m = NULL;
  ms_status st = dm_model_create(&(dm_model_params){.state = &s, .opt = opt, .ctx = ctx}, &m);
  if (st != MS_OK) {
    dm_state_free(&s);
    return st;
  }
  dm_fin_material *mat = ms_calloc(p->nlayers, sizeof *mat);
  for (size_t l = 0; l < p->nlayers; ++l)
    mat[l] = (dm_fin_material){.eos = p->layers[l].eos,
                               .yield = p->layers[l].yield,
                               .G = p->layers[l].G,
                               .Y0 = p->layers[l].Y0,
                               .sg = &p->layers[l].sg,
                               .frac = p->layers[l].frac};
  uint8_t *imat = ms_calloc(s.n, 1);
  for (size_t i = 0; i < s.n; ++i) imat[i] = (uint8_t)(dmp_layer_at(p, s.X[3 * i]) - p->layers);
  dm_fin_params par = {
      .cq = p->cq, .cl = p->cl, .courant = p->courant, .hourglass = p->hourglass, .ell = p->h};
  dm_fin *f = NULL;
  st = dm_fin_create(&(dm_fin_setup){.m = m, .mat = mat, .imat = imat, .par = par}, &f);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR, "discrete model (response eos): the initial state is not valid");
    free(mat), free(imat), dm_model_destroy(&m), dm_state_free(&s);
    return st;
  }
  sum->particles = s.n, sum->real_particles = nreal, sum->bonds = m->nbonds, sum->ranks = 1;
  ms_log(ctx, MS_LOG_INFO,
         "discrete model (response eos): %zu particles (%zu real), %zu bonds, dim %d, viscosity "
         "C_q %.3g C_l %.3g, bond penalty c_s %.3g, courant %.3g, first dt %.6g%s",
         s.n, nreal, m->nbonds, p->dim, p->cq, p->cl, p->hourglass, p->courant, f->dt_next,
         p->has_piston ? ", piston" : "");
  const long nx = p->ncell[0];
  double *bins = ms_calloc((size_t)nx * 11, sizeof(double));
  const size_t nemax = 4096;
  double *eh = ms_calloc(nemax * 7, sizeof(double));
  size_t ne = 0;
  char *done = ms_calloc(p->nprofile_times + 1, 1);
  /* free-surface history of the flyer problem (dm_fs_history: thinned when full) */
  dm_fs_history fs = {0};
  if (flyer) dm_fs_history_init(&fs, 8192);
  double K, U, H;
  dm_fin_energies(f, &K, &U, &H);
  const double E0 = K + U + H;
  double t = 0.0, dEmax = 0.0, wall = 0.0;
  const double t_end = p->steps > 0 ? INFINITY : p->t_end;
  long every = p->energy_every;
  for (long step = 0;; ++step) {
    dm_fin_energies(f, &K, &U, &H);
    const double bal =
        K + U + H + dm_fin_broken_energy(f) - f->work - E0; /* broken: 0 without fracture */
    dEmax = fmax(dEmax, fabs(bal));
    const int last = (p->steps > 0 && step >= p->steps) || t >= t_end * (1 - 1e-12);
    if ((step % every == 0 || last) && ne < nemax) {
      double row[7] = {t, K, U, H, f->work, bal, 0};
      memcpy(&eh[7 * ne++], row, sizeof row);
    }
    for (size_t q = 0; q < p->nprofile_times; ++q)
      if (!done[q] && (t >= p->profile_times[q] * (1 - 1e-12) || last)) {
        dmp_write_fin_profile(ctx, p, f, nreal, t, (int)q, bins);
        done[q] = 1;
      }
    if (flyer) dm_fs_history_record(&fs, step, t, &s, nx, p->ncell[1] * p->ncell[2]);
    if (last) break;
    if (t + f->dt_next > t_end) f->dt_next = t_end - t;
    const double dt = f->dt_next, w0 = ms_wall_time();
    st = dm_fin_step(f);
    wall += ms_wall_time() - w0;
    t += dt;
    if (st != MS_OK) {
      const double *X = &s.X[3 * f->bad];
      ms_log(ctx, MS_LOG_ERROR,
             "discrete model (response eos): step %ld, t = %.9g: particle %zu (X = %g %g %g): %s "
             "= %g; the run stops (no output of this state)",
             f->step + 1, t, f->bad, X[0], X[1], X[2], f->bad_what, f->bad_value);
      break;
    }
  }
  if (f->failed)
    ms_log(ctx, MS_LOG_INFO,
           "discrete model (response eos): fracture: %zu particles failed, broken energy %.6g kJ "
           "(in the balance: K + U + E_hg + broken - W - E0)",
           dm_fin_failed_count(f), dm_fin_broken_energy(f));
  sum->steps = f->step, sum->t_end = t, sum->wall_s = wall;
  sum->particle_steps_per_s = wall > 0 ? (double)nreal * f->step / wall : 0;
  sum->energy_err_max = f->work != 0 ? dEmax / fabs(f->work) : dEmax / fmax(fabs(E0), 1e-300);
  /* no driven particles (a flyer): both relative to the initial energy E0 (kinetic) instead */
  sum->hourglass_last = f->work != 0 ? H / fabs(f->work) : H / fmax(fabs(E0), 1e-300);
  sum->kinetic_end = K, sum->potential_end = U;
  ms_log(ctx, MS_LOG_INFO,
         "discrete model (response eos): %ld steps to t = %.6g in %.3f s (%.4g particle-steps/s); "
         "energy balance max |K + U + E_hg - W - E0| = %.3g of %s %.6g kJ; "
         "bond-penalty energy / that = %.3g",
         f->step, t, wall, sum->particle_steps_per_s, sum->energy_err_max,
         f->work != 0 ? "the piston work" : "the initial energy E0", f->work != 0 ? f->work : E0,
         sum->hourglass_last);
  {
    const char *nm[] = {"t",           "kinetic", "internal", "bond_penalty",
                        "piston_work", "balance", "unused"};
    const char *un[] = {"10 us", "kJ", "kJ", "kJ", "kJ", "kJ", "1"};
    /* rows of 7 written as 6 columns: compact them first */
    for (size_t r = 0; r < ne; ++r) memmove(&eh[6 * r], &eh[7 * r], 6 * sizeof(double));
    dmp_write_series(ctx, "dm_fin_energy.csv",
                     f->failed ? "energy history: balance = kinetic + internal + bond_penalty + "
                                 "broken - piston_work - E0 (broken: fracture, in run.log)"
                               : "energy history: balance = kinetic + internal + bond_penalty - "
                                 "piston_work - E0",
                     6, nm, un, eh, ne);
  }
  if (flyer) {
    const char *nm[] = {"t", "u_free_surface"}, *un[] = {"10 us", "km/s"};
    dmp_write_series(ctx, "dm_fin_free_surface.csv",
                     "free-surface velocity: mean x velocity of the last x layer of particles", 2,
                     nm, un, fs.rows, fs.n);
  }
  free(fs.rows), free(bins), free(eh), free(done), free(mat), free(imat);
  dm_fin_destroy(&f);
  dm_model_destroy(&m);
  dm_state_free(&s);
  return st;
}
