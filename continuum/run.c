/* SPDX-License-Identifier: MIT */
/* run.c — running a continuum deck: the time loop with output events, the x–t diagram data,
 * the energy/momentum balance in the log and the instability guard. */
#include "cont_run.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* x–t diagram data: frames of (coarsened) node positions, density and pressure. Grids finer
 * than XT_MAX_COLUMNS cells are coarsened by merging `stride` cells (mass-weighted density,
 * volume-weighted pressure) so the file stays small. */
enum { XT_MAX_COLUMNS = 2000 };

typedef struct xt_data {
  size_t stride, ncol, nframes, cap;
  double *t, *x, *rho, *p;
} xt_data;

static void xt_init(xt_data *xt, const cont_grid *g, size_t frames) {
  memset(xt, 0, sizeof *xt);
  xt->stride = (g->ncells + XT_MAX_COLUMNS - 1) / XT_MAX_COLUMNS;
  if (xt->stride < 1) xt->stride = 1;
  xt->ncol = (g->ncells + xt->stride - 1) / xt->stride;
  xt->cap = frames + 2;
  xt->t = ms_calloc(xt->cap, sizeof(double));
  xt->x = ms_calloc(xt->cap * (xt->ncol + 1), sizeof(double));
  xt->rho = ms_calloc(xt->cap * xt->ncol, sizeof(double));
  xt->p = ms_calloc(xt->cap * xt->ncol, sizeof(double));
}

static void xt_add(xt_data *xt, const cont_grid *g) {
  if (xt->nframes >= xt->cap) return;
  size_t f = xt->nframes++, nc = xt->ncol;
  xt->t[f] = g->t;
  for (size_t k = 0; k < nc; ++k) {
    size_t a = k * xt->stride, b = a + xt->stride < g->ncells ? a + xt->stride : g->ncells;
    double m = 0, v = 0, pv = 0;
    for (size_t i = a; i < b; ++i) {
      double vi = cont_cell_volume(g, g->x[i], g->x[i + 1]);
      m += g->mass[i];
      v += vi;
      pv += g->p[i] * vi;
    }
    xt->x[f * (nc + 1) + k] = g->x[a];
    xt->rho[f * nc + k] = m / v;
    xt->p[f * nc + k] = pv / v;
  }
  xt->x[f * (nc + 1) + nc] = g->x[g->ncells];
}

static ms_status xt_write(const ms_ctx *ctx, const xt_data *xt, int quantity) {
  char *path = ms_out_path(ctx, "xt.h5");
  ms_h5 *h = ms_h5_create(path);
  free(path);
  if (!h) return MS_ERR_IO;
  size_t nf = xt->nframes, nc = xt->ncol;
  ms_status s = ms_h5_write_times(h, "t", nf, xt->t);
  if (!s) s = ms_h5_write_doubles(h, "x", nf, nc + 1, xt->x, ms_unit_label(MS_DIM_LENGTH));
  if (!s) s = ms_h5_write_doubles(h, "rho", nf, nc, xt->rho, ms_unit_label(MS_DIM_DENSITY));
  if (!s) s = ms_h5_write_doubles(h, "p", nf, nc, xt->p, ms_unit_label(MS_DIM_PRESSURE));
  if (!s) s = ms_h5_attr_string(h, "/", "quantity", quantity ? "p" : "rho");
  if (!s) s = ms_h5_attr_double(h, "/", "cell_stride", (double)xt->stride);
  if (!s) return ms_h5_close(h);
  ms_h5_abort(h);
  return s;
}

static void xt_free(xt_data *xt) {
  free(xt->t);
  free(xt->x);
  free(xt->rho);
  free(xt->p);
}

static void log_balance(const ms_ctx *ctx, const cont_grid *g, double e0, double mom0) {
  cont_balance b = cont_grid_balance(g);
  double total = b.internal + b.kinetic;
  /* scale: the largest energy in play (initial, current, or delivered by the boundaries) */
  double scale = fmax(fmax(fabs(e0), fabs(b.internal) + b.kinetic), fabs(b.work));
  if (!(scale > 0.0)) scale = 1.0;
  double drift = (total - b.work - e0) / scale;
  ms_log(ctx, MS_LOG_INFO,
         "continuum t = %.6g %s step %ld: energy [%s] internal %.9g + kinetic %.9g = %.9g, "
         "boundary work %.6g, relative drift %.2e",
         ms_out_time(g->t), ms_out_time_label(), g->step, cont_energy_unit(g->geometry), b.internal,
         b.kinetic, total, b.work, drift);
  if (g->geometry == CONT_PLANAR) {
    double mscale = fabs(mom0) > 0 ? fabs(mom0) : 1.0;
    ms_log(ctx, MS_LOG_INFO,
           "continuum t = %.6g %s: momentum [g*km/s/cm^2] %.9g, boundary impulse %.6g, drift "
           "%.2e (scale %.3g)",
           ms_out_time(g->t), ms_out_time_label(), b.momentum, b.impulse,
           (b.momentum - b.impulse - mom0) / mscale, mscale);
  }
}

static ms_status run_on_this_rank(ms_ctx *ctx, cont_problem *p, const cont_step_hooks *h);

/* Rank 0 writes the files. A hooked run goes on every rank (the coupled problem's replicated
 * grid, docs/mpi.md "The coupled problem on MPI ranks"): there every rank learns rank 0's write
 * status, so that all of them stop together. */
typedef struct file_writer {
  const ms_ctx *ctx;
  bool agree; /* hooked run on several ranks */
} file_writer;

static ms_status agreed(const file_writer *w, ms_status s) {
  return w->agree ? par_agree_status(s) : s;
}
static ms_status write_profile(const file_writer *w, const cont_grid *g, const char *stem) {
  return agreed(w, w->ctx->rank == 0 ? cont_write_profile(w->ctx, g, stem) : MS_OK);
}
static ms_status write_histories(const file_writer *w, const cont_grid *g, long stride) {
  return agreed(w, w->ctx->rank == 0 ? cont_write_histories(w->ctx, g, stride) : MS_OK);
}
static ms_status write_xt(const file_writer *w, const xt_data *xt, int quantity) {
  return agreed(w, w->ctx->rank == 0 ? xt_write(w->ctx, xt, quantity) : MS_OK);
}

/* The 1D grid is cheap and serial: under MPI rank 0 runs it and writes every file (two ranks
 * writing the same outputs would race); the other ranks wait and share its status. */
ms_status cont_problem_run(ms_ctx *ctx, cont_problem *p) {
  ms_status s = ctx->rank == 0 ? run_on_this_rank(ctx, p, NULL) : MS_OK;
  return par_agree_status(s);
}

/* Hooked runs belong to the caller's coupling loop: every rank that calls runs (the hooks keep
 * the copies equal; rank 0 writes the files). */
ms_status cont_problem_run_hooked(ms_ctx *ctx, cont_problem *p, const cont_step_hooks *hooks) {
  if (hooks && hooks->end > 0) p->t_end = hooks->end;
  return run_on_this_rank(ctx, p, hooks);
}

static ms_status run_on_this_rank(ms_ctx *ctx, cont_problem *p, const cont_step_hooks *h) {
  cont_grid *g = p->grid;
  ms_status s = MS_OK;
  const file_writer fw = {ctx, h != NULL && ctx->size > 1};
  cont_balance b0 = cont_grid_balance(g);
  double e0 = b0.internal + b0.kinetic, mom0 = b0.momentum;
  ms_log(ctx, MS_LOG_INFO, "continuum: %zu cells in %zu layers, %s geometry, t_end = %g %s",
         g->ncells, g->nregions,
         g->geometry == CONT_PLANAR        ? "planar"
         : g->geometry == CONT_CYLINDRICAL ? "cylindrical"
                                           : "spherical",
         ms_out_time(p->t_end), ms_out_time_label());

  xt_data xt;
  xt_init(&xt, g, p->xt_frames > 0 ? (size_t)p->xt_frames : 0);
  if (p->xt_frames > 0) xt_add(&xt, g);
  double frame_dt = p->xt_frames > 0 ? p->t_end / (double)p->xt_frames : INFINITY;
  long next_frame = 1;

  size_t next_out = 0;
  while (next_out < p->n_out && p->out_times[next_out] <= 0.0) {
    char stem[32];
    snprintf(stem, sizeof stem, "profile_%04zu", next_out);
    s = write_profile(&fw, g, stem);
    if (s) goto done;
    ++next_out;
  }

  ms_progress prog;
  ms_progress_start(&prog, ctx, "continuum", 0.0, p->t_end);
  while (g->t < p->t_end) {
    if (!h && ctx->size == 1 && ms_interrupt_requested()) { /* no checkpoints: stop at once */
      ms_log(ctx, MS_LOG_WARN, "continuum: interrupted at t = %g %s (step %ld)", ms_out_time(g->t),
             ms_out_time_label(), g->step);
      s = MS_INTERRUPTED;
      break;
    }
    double target = p->t_end;
    if (next_out < p->n_out && p->out_times[next_out] < target) target = p->out_times[next_out];
    double tf = (double)next_frame * frame_dt;
    if (tf < target) target = tf;
    double left = target - g->t;
    double lim = left;
    if (g->dt_next < left && g->dt_next > 0.5 * left) lim = 0.5 * left; /* no sliver steps */
    if (lim == left) g->land_time = target;
    if (h && h->before && (s = h->before(h->user, g)) != MS_OK) break;
    s = cont_grid_step(g, lim);
    if (s == MS_OK && h && h->after && (s = h->after(h->user, g)) != MS_OK) break;
    if (s != MS_OK) {
      ms_log(ctx, MS_LOG_ERROR, "continuum: %s", cont_grid_error(g));
      /* every rank that runs the grid failed alike: no agreement needed (fw.agree off) */
      const file_writer fail = {ctx, false};
      ms_status s2 = write_profile(&fail, g, "profile_unstable");
      if (s2 == MS_OK && ctx->rank == 0)
        ms_log(ctx, MS_LOG_ERROR, "continuum: final state written to profile_unstable.h5/.csv");
      write_histories(&fail, g, p->history_stride);
      break;
    }
    if (g->t >= target) {
      if (next_out < p->n_out && g->t >= p->out_times[next_out]) {
        char stem[32];
        snprintf(stem, sizeof stem, "profile_%04zu", next_out);
        s = write_profile(&fw, g, stem);
        if (s) break;
        log_balance(ctx, g, e0, mom0);
        ++next_out;
      }
      while ((double)next_frame * frame_dt <= g->t * (1 + 1e-12)) {
        xt_add(&xt, g);
        ++next_frame;
      }
    }
    ms_progress_update(&prog, g->t, g->step);
    if (p->max_steps > 0 && g->step >= p->max_steps) {
      ms_log(ctx, MS_LOG_WARN, "continuum: stopped after max_steps = %ld at t = %g %s",
             p->max_steps, ms_out_time(g->t), ms_out_time_label());
      break;
    }
  }
  ms_progress_finish(&prog, g->t, g->step);
  if (s == MS_OK) {
    log_balance(ctx, g, e0, mom0);
    s = write_profile(&fw, g, "profile_final");
    if (!s) s = write_histories(&fw, g, p->history_stride);
    if (!s && p->xt_frames > 0) s = write_xt(&fw, &xt, p->xt_quantity);
  } else if (s == MS_INTERRUPTED) { /* what the run has so far, under the usual names */
    write_profile(&fw, g, "profile_interrupted");
    write_histories(&fw, g, p->history_stride);
  } else if (s == MS_ERR_UNSTABLE && p->xt_frames > 0) {
    xt_add(&xt, g);
    const file_writer fail = {ctx, false};
    write_xt(&fail, &xt, p->xt_quantity);
  }
done:
  xt_free(&xt);
  return s;
}
