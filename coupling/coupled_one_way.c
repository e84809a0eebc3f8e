/* SPDX-License-Identifier: MIT */
/* coupled_one_way.c — the one-way drive of docs/design.md §6 (docs/coupling.md §6). The grid
 * runs first through the continuum problem's own loop (its outputs land in the run directory);
 * the velocity history U(t) of the drive tag then drives the piston of the particle region that
 * represents the sample between that node and its free surface, while a second copy of the grid
 * advances in lock-step to supply the gas; fragments are found during the particle phase, feel
 * the gas's drag, and the detached ones are transported to the detector plane. */
#include "coupled_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct one_way {
  ms_ctx *ctx;
  cpl_problem *p;
  /* phase 1: the grid's tag histories and the pistons built from them */
  cont_history hd, hf;
  double *hd_buf, *hf_buf; /* MPI: rank 0's histories on every rank */
  cpl_piston drive, fsurf;
  bool have_pistons;
  double t_start; /* the particle phase starts a little before the drive node moves */
  size_t k0;      /* its sample in hd */
  /* phase 2: the particles */
  cpl_particle_phase ph;
  bool have_phase;
  double Z;           /* transmitting piston's impedance */
  double p_particles; /* pressure of the particles on the piston layer, last step */
  gas_ctx gas;        /* from the live grid */
  cpl_loop_state ls;
  ms_afile af_ej, af_fs;
  FILE *f_ej, *f_fs;
  long nsteps, next_out, last_search, ckpt_every;
  size_t fs_n, fs_cap; /* free-surface samples for the drive check */
  double *fs_t, *fs_ug, *fs_up;
  ptl_region_energy e0;
  ms_progress prog;
  bool stopping; /* interrupted: stop at the next checkpoint */
} one_way;

/* 1. The grid alone, with its own outputs; the drive and free-surface histories as pistons. */
static ms_status grid_phase(one_way *w) {
  ms_ctx *ctx = w->ctx;
  cpl_problem *p = w->p;
  ms_log(ctx, MS_LOG_INFO, "coupled: 1/3 grid run (U(t) of the drive node)");
  ms_status st = cont_problem_run(ctx, p->grid_out);
  if (st != MS_OK) return st;
  const cont_grid *gout = cont_problem_grid(p->grid_out);
  w->hd = cont_grid_history(gout, p->tag_drive);
  w->hf = cont_grid_history(gout, p->tag_fs);
  cpl_share_history(ctx, &w->hd, &w->hd_buf);
  cpl_share_history(ctx, &w->hf, &w->hf_buf);
  const cont_history *hd = &w->hd, *hf = &w->hf;
  if (cpl_piston_build(&w->drive, hd->n, hd->t, hd->x, hd->u) != MS_OK ||
      cpl_piston_build(&w->fsurf, hf->n, hf->t, hf->x, hf->u) != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR,
           "coupled: the grid's tag histories are unusable (non-finite or "
           "not increasing in time)");
    return MS_ERR_INTERNAL;
  }
  w->have_pistons = true;
  ms_log(ctx, MS_LOG_INFO,
         "coupled: drive history '%s': %zu samples, max displacement correction %.3g km/s "
         "(0 for the conservative cross scheme)",
         hd->name, hd->n, w->drive.max_correction);
  double umax = 0;
  for (size_t k = 0; k < hd->n; k++) umax = fmax(umax, fabs(hd->u[k]));
  size_t k0 = 0;
  while (k0 + 1 < hd->n && fabs(hd->u[k0 + 1]) <= 1e-3 * umax) k0++;
  w->k0 = k0;
  w->t_start = hd->t[k0];
  if (!(p->t_end > w->t_start)) {
    ms_log(ctx, MS_LOG_ERROR, "coupled: time.end = %g is before the drive node moves (t = %g)",
           p->t_end, w->t_start);
    return MS_ERR_INPUT;
  }
  if (p->t_end > hd->t[hd->n - 1])
    ms_log(ctx, MS_LOG_WARN,
           "coupled: the particle phase (to %g) outlasts the grid run (%g): "
           "the piston keeps the last velocity",
           p->t_end, hd->t[hd->n - 1]);
  return MS_OK;
}

/* 2. The particle region between the drive node and the free surface, its piston the drive
 * history from the particle phase's start (relative time); the live grid as its gas; the
 * streamed CSV files; a restart's state. */
static ms_status particle_setup(one_way *w) {
  ms_ctx *ctx = w->ctx;
  cpl_problem *p = w->p;
  const cont_history *hd = &w->hd;
  const double x_drive = hd->x[0], depth = w->hf.x[0] - x_drive;
  size_t n = hd->n - w->k0;
  double *t = ms_calloc(n < 2 ? 2 : n, sizeof(double)),
         *u = ms_calloc(n < 2 ? 2 : n, sizeof(double));
  for (size_t k = 0; k < n; k++) {
    t[k] = hd->t[w->k0 + k] - w->t_start;
    u[k] = hd->u[w->k0 + k];
  }
  if (p->drive_mode == DRIVE_TRANSMITTING) n = 2; /* held anew every step */
  ms_status st = cpl_phase_open(ctx, p, x_drive, depth, n, t, u, &w->ph);
  free(t);
  free(u);
  if (st != MS_OK) return st;
  w->have_phase = true;
  const ptl_region_geometry *geo = &w->ph.geo;
  /* transmitting piston (docs/coupling.md §5): u = U_g + (p_g − p_particles)/Z passes waves
   * coming from the particle side out of the region instead of reflecting them; Z defaults to
   * ρ0 c_L with c_L = √1.5 c0, the longitudinal speed of a nearest-neighbour central-force
   * lattice (2D triangular and fcc [100] alike) */
  w->Z = p->impedance > 0 ? p->impedance : sqrt(1.5) * geo->rho0 * geo->c0;
  cont_grid *glive = cont_problem_grid(p->grid_live);
  w->gas = cpl_gas_of(p, glive, 0.0, geo->area);
  if (ctx->size > 1 && p->gas_return) /* the transport runs replicated: it deposits directly */
    w->gas.cell_src = ms_calloc(2 * cont_grid_ncells(glive) + 1, sizeof *w->gas.cell_src);
  w->f_ej = cpl_open_csv(ctx, &w->af_ej, "ejecta_mass.csv");
  w->f_fs = cpl_open_csv(ctx, &w->af_fs, "free_surface.csv");
  st = ctx->rank == 0 && (!w->f_ej || !w->f_fs) ? MS_ERR_IO : MS_OK;
  if (ctx->size > 1) st = par_agree_status(st);
  if (st != MS_OK) return st;
  if (!ctx->restart && w->f_ej) { /* a restart writes back the text so far */
    ms_csv_header(w->f_ej, CPL_EJECTA_TITLE, CPL_EJECTA_COLS, cpl_ejecta_names, cpl_ejecta_units);
    static const char *const fsn[] = {"t", "u_grid", "u_particles"};
    static const char *const fsu[] = {"10us", "km/s", "km/s"};
    ms_csv_header(w->f_fs, "free-surface velocity: grid tag vs particle surface layer", 3, fsn,
                  fsu);
  }
  w->nsteps = (long)ceil((p->t_end - w->t_start) / geo->dt);
  w->next_out = 1;
  w->fs_cap = (size_t)(w->nsteps / p->frag_every) + (size_t)p->n_out + 4;
  w->fs_t = ms_calloc(w->fs_cap, sizeof(double));
  w->fs_ug = ms_calloc(w->fs_cap, sizeof(double));
  w->fs_up = ms_calloc(w->fs_cap, sizeof(double));
  /* checkpoints (docs/coupling.md): the loop state at the end of a step, with the gas grid's
   * history so that a restart can rebuild it */
  w->ckpt_every = cpl_checkpoint_steps(p, geo->dt);
  w->ls.fs_cap = w->fs_cap, w->ls.fs_t = w->fs_t, w->ls.fs_ug = w->fs_ug, w->ls.fs_up = w->fs_up;
  w->ls.gaslog.on = w->ckpt_every > 0;
  w->gas.log = w->ls.gaslog.on ? &w->ls.gaslog : NULL;
  if (ctx->restart) {
    ms_afile *const csv[2] = {&w->af_ej, &w->af_fs};
    st = cpl_checkpoint_restore(ctx, p->deck_hash, w->ph.region, &w->ls, glive, csv, 2);
    if (st == MS_OK) st = cpl_check_restart_count(ctx, w->ph.region, geo->particles);
    w->next_out = w->ls.next_out, w->last_search = w->ls.last_search;
    w->p_particles = w->ls.p_particles, w->fs_n = w->ls.fs_n, w->e0 = w->ls.e0;
    w->gas.returned_p = w->ls.returned_p, w->gas.returned_e = w->ls.returned_e;
    w->gas.drag_work = w->ls.drag_work;
  } else {
    ptl_region_energy_get(w->ph.region, &w->e0);
  }
  ms_log(ctx, MS_LOG_DEBUG, "coupled: initial energy: kinetic %g potential %g total %g",
         w->e0.kinetic, w->e0.potential, w->e0.total);
  return st;
}

/* The kinetic energy the drag kicks took so far, summed over the ranks (collective). */
static double drag_work(const one_way *w) {
  return w->ctx->size > 1 ? par_sum_double(w->gas.drag_work) : w->gas.drag_work;
}

static ms_status checkpoint(one_way *w, long step) {
  cpl_loop_state *ls = &w->ls;
  ls->step = step, ls->next_out = w->next_out, ls->last_search = w->last_search;
  ls->p_particles = w->p_particles, ls->e0 = w->e0, ls->fs_n = w->fs_n;
  ls->returned_p = w->gas.returned_p, ls->returned_e = w->gas.returned_e;
  ls->drag_work = w->gas.drag_work;
  ms_afile *const csv[2] = {&w->af_ej, &w->af_fs};
  return cpl_checkpoint_write(w->ctx, w->p->deck_hash, w->ph.region, ls, csv, 2);
}

/* One particle step; the transmitting piston holds the grid's mean velocity over the step plus
 * the pressure mismatch at mid-step over Z, then learns the particles' pressure on it. */
static ms_status particle_step(one_way *w) {
  ptl_region *r = w->ph.region;
  const double dt = w->ph.geo.dt;
  const bool transmitting = w->p->drive_mode == DRIVE_TRANSMITTING;
  if (transmitting) {
    double ta = w->t_start + ptl_region_time(r), tb = ta + dt;
    double ug =
        (cpl_piston_displacement(&w->drive, tb) - cpl_piston_displacement(&w->drive, ta)) / dt;
    double pg = cpl_interp(w->hd.n, w->hd.t, w->hd.p_right, 0.5 * (ta + tb));
    ptl_region_hold_piston(r, ug + (pg - w->p_particles) / w->Z, dt);
  }
  ms_status st = ptl_region_step(r);
  if (transmitting) {
    double fsum = ptl_region_driven_force(r);
    if (w->ctx->size > 1) /* rank order: every rank's piston gets the same bits */
      par_sum_doubles_ordered(&fsum, 1);
    w->p_particles = -fsum / w->ph.geo.area; /* compression pushes the piston towards −x */
  }
  return st;
}

/* Fragments, ejected mass, drag kick over the interval since the last search, the drive-check
 * sample, and at output times the snapshot and spectrum. */
static ms_status search(one_way *w, long step, bool out_now) {
  ms_ctx *ctx = w->ctx;
  cpl_problem *p = w->p;
  ptl_region *r = w->ph.region;
  const double t_abs = w->t_start + ptl_region_time(r);
  cpl_particles view;
  ms_status st = cpl_find_fragments(ctx, &w->ph, &view);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR,
           "coupled: fragment search failed at t = %g (non-finite "
           "particle positions?)",
           t_abs);
    return st;
  }
  /* ejecta: detached fragments ahead of the grid's free surface at this time */
  w->ph.sel.plane = w->hf.x[0] + cpl_piston_displacement(&w->fsurf, t_abs);
  double row_ej[CPL_EJECTA_COLS];
  cpl_ejecta_row(ctx, &w->ph, &view, t_abs, row_ej);
  if (w->f_ej) ms_csv_row(w->f_ej, CPL_EJECTA_COLS, row_ej);
  if (p->drag_law != CPL_DRAG_NONE) {
    st = cont_grid_run_to(w->gas.g, t_abs);
    if (st != MS_OK) {
      ms_log(ctx, MS_LOG_ERROR, "coupled: gas grid: %s", cont_grid_error(w->gas.g));
      return st;
    }
    cpl_gaslog_run_to(&w->ls.gaslog, t_abs);
    /* a velocity kick over the search interval (operator splitting; drag is slow on the
     * particle time step) */
    st = cpl_drag_kick(p, &w->ph, &view, &w->gas, t_abs,
                       (double)(step - w->last_search) * w->ph.geo.dt);
    if (st != MS_OK) {
      ms_log(ctx, MS_LOG_ERROR, "coupled: gas return: %s", cont_grid_error(w->gas.g));
      return st;
    }
  }
  w->last_search = step; /* after the kick: its interval is the time since the previous search */
  double ug = cpl_piston_velocity(&w->fsurf, t_abs), up = ptl_region_free_surface_velocity(r);
  double row_fs[3] = {t_abs, ug, up};
  if (w->f_fs) ms_csv_row(w->f_fs, 3, row_fs);
  if (w->fs_n < w->fs_cap) {
    w->fs_t[w->fs_n] = t_abs;
    w->fs_ug[w->fs_n] = ug;
    w->fs_up[w->fs_n] = up;
    w->fs_n++;
  }
  if (!out_now) return MS_OK;
  st = cpl_write_particles(ctx, &w->ph, w->next_out, t_abs, &view);
  if (st != MS_OK) return st;
  char name[64], title[160];
  snprintf(name, sizeof name, "spectrum_%04ld.csv", w->next_out);
  snprintf(title, sizeof title, "fragment spectrum N(g) at t = %g %s, b = %g", ms_out_time(t_abs),
           ms_out_time_label(), p->bond);
  st = cpl_write_table(ctx, name, &w->ph.fr, 0, &w->ph.sel, title);
  if (ctx->size > 1) st = par_agree_status(st); /* rank 0's file error stops every rank */
  if (st != MS_OK) return st;
  ptl_region_energy en;
  ptl_region_energy_get(r, &en);
  const double drag = drag_work(w);
  long nfail[3];
  char failed[128] = "";
  if (ptl_region_failures(r, nfail))
    snprintf(failed, sizeof failed,
             "; failed particles %ld by the criterion, %ld isolated, %ld degenerate", nfail[0],
             nfail[1], nfail[2]);
  ms_log(ctx, MS_LOG_INFO,
         "coupled: t = %.5g %s: %zu fragments, ejected mass %.4g g, free surface %.4g km/s "
         "(grid %.4g); energy [kJ]: kinetic %.4g potential %.4g damped %.4g broken %.4g "
         "drag %.4g piston work %.4g, balance %.3g of the work%s",
         ms_out_time(t_abs), ms_out_time_label(), w->ph.fr.n, row_ej[1], up, ug, en.kinetic,
         en.potential - w->e0.potential, en.dissipated, en.broken, drag, en.piston_work,
         en.piston_work != 0 ? (en.total - w->e0.total - drag) / en.piston_work : 0.0, failed);
  w->next_out++;
  return MS_OK;
}

/* 3. The particle phase. */
static ms_status particle_loop(one_way *w) {
  ms_ctx *ctx = w->ctx;
  cpl_problem *p = w->p;
  ptl_region *r = w->ph.region;
  const long step0 = ctx->restart ? w->ls.step : 0;
  ms_status st = MS_OK;
  ms_progress_start(&w->prog, ctx, "particles", w->t_start + ptl_region_time(r), p->t_end);
  for (long step = step0 + 1; step <= w->nsteps && st == MS_OK; step++) {
    if (w->ckpt_every > 0 && step - 1 > step0 && (step - 1) % w->ckpt_every == 0) {
      st = checkpoint(w, step - 1);
      if (st != MS_OK) break;
      if (w->stopping) {
        ms_log(ctx, MS_LOG_WARN, "coupled: interrupted; checkpoint at particle step %ld written",
               step - 1);
        st = MS_INTERRUPTED;
        break;
      }
    }
    if (!w->stopping && cpl_should_stop(ctx, p)) { /* collective: every rank, every step */
      w->stopping = true;
      if (w->ckpt_every == 0) {
        ms_log(ctx, MS_LOG_WARN, "coupled: interrupted at particle step %ld (no checkpoints)",
               step - 1);
        st = MS_INTERRUPTED;
        break;
      }
      ms_log(ctx, MS_LOG_WARN,
             "coupled: interrupt or wall-time limit: stopping at the next checkpoint (step %ld)",
             ((step - 1) / w->ckpt_every + 1) * w->ckpt_every);
    }
    st = particle_step(w);
    if (st != MS_OK) {
      cpl_particles_unstable(ctx, r, st, w->t_start, w->ph.material);
      break;
    }
    bool out_now = step * p->n_out >= w->next_out * w->nsteps;
    if (step % p->frag_every && !out_now && step != w->nsteps) continue;
    st = search(w, step, out_now);
    if (st == MS_OK) ms_progress_update(&w->prog, w->t_start + ptl_region_time(r), step);
  }
  ms_progress_finish(&w->prog, w->t_start + ptl_region_time(r),
                     (long)(ptl_region_time(r) / w->ph.geo.dt));
  return st;
}

/* The drive check (free surface of the particles against the grid's tag). */
static void drive_check(one_way *w) {
  cpl_problem *p = w->p;
  cpl_fs_check chk;
  const double depth = w->hf.x[0] - w->hd.x[0];
  const double window = p->check_window > 0 ? p->check_window : depth / w->ph.geo.c0;
  const bool found = cpl_free_surface_check(w->fs_n, w->fs_t, w->fs_ug, w->fs_up, window, &chk);
  if (found)
    ms_log(w->ctx, MS_LOG_INFO,
           "coupled: drive check (free surface, %zu samples over [%g, %g] %s): plateau particles "
           "%.5g km/s vs grid %.5g km/s: %.2f %%; half-rise at t = %.5g %s (particles) vs %.5g "
           "(grid); smallest particle velocity in the next two windows %.4g km/s (%s piston)",
           chk.samples, ms_out_time(chk.t_break + 0.5 * window), ms_out_time(chk.t_break + window),
           ms_out_time_label(), chk.plateau_particles, chk.plateau_grid, 100 * chk.rel_diff,
           ms_out_time(chk.t_half_particles), ms_out_time_label(), ms_out_time(chk.t_half_grid),
           chk.min_after, cpl_drive_mode_names[p->drive_mode]);
  if (found && w->ph.geo.surface_depth > 0) /* docs/coupling.md, the default deck */
    ms_log(w->ctx, MS_LOG_INFO,
           "coupled: drive check: the free surface is profiled (depth %g um), so the particles' "
           "surface layer includes its jets (and, with fracture, its failed particles, which fly "
           "as ejecta): the figure above measures the ejecta, not the plane; the same deck with "
           "a flat surface (coupled.particles.surface.profile: flat) is the check",
           1e4 * w->ph.geo.surface_depth);
  if (!found)
    ms_log(w->ctx, MS_LOG_WARN,
           "coupled: drive check: no free-surface breakout within the "
           "particle phase (or no samples in the check window)");
  p->sum.check = chk;
}

/* The run's summary; jets, spall layers and debris (cpl_ejecta_classify, docs/coupling.md §9
 * "The split"), and the fast detached mass: faster than (1 + jet_margin) × the grid's
 * free-surface plateau (the drive check's window; its first peak, the breakout overshoot, if the
 * check found no breakout). u_ref, that first peak, is kept for the summary: from breakout (5 %
 * of the maximum over the phase, as in the drive check) until it first falls below 90 % of the
 * running maximum. The final fragment tables. */
static ms_status summarise(one_way *w) {
  ms_ctx *ctx = w->ctx;
  cpl_problem *p = w->p;
  ptl_region *r = w->ph.region;
  const double t_now = w->t_start + ptl_region_time(r);
  ptl_region_energy en;
  ptl_region_energy_get(r, &en);
  p->sum.particles = w->ph.geo.particles;
  p->sum.steps = w->nsteps;
  const double drag = drag_work(w);
  p->sum.energy_balance =
      en.piston_work != 0 ? (en.total - w->e0.total - drag) / en.piston_work : 0.0;
  ptl_region_failures(r, p->sum.failed);
  p->sum.piston_work = en.piston_work;
  p->sum.fragments = w->ph.fr.n;
  p->sum.ejected_mass = cpl_ejected_mass(&w->ph.fr, &w->ph.sel);
  const cont_history *hf = &w->hf;
  double u_all = 0, u_ref = 0;
  for (size_t k = 0; k < hf->n && hf->t[k] <= t_now; k++) u_all = fmax(u_all, hf->u[k]);
  for (size_t k = 0; k < hf->n && hf->t[k] <= t_now; k++) {
    if (hf->u[k] < 0.05 * u_all) continue;
    if (hf->u[k] < 0.9 * u_ref) break;
    u_ref = fmax(u_ref, hf->u[k]);
  }
  p->sum.u_ref = u_ref;
  p->sum.u_plateau = isfinite(p->sum.check.plateau_grid) ? p->sum.check.plateau_grid : u_ref;
  cpl_particles view = cpl_particle_view(r, w->ph.skip);
  if (ctx->size > 1) view.n = ptl_region_state(r)->nlocal;
  cpl_phase_classify(ctx, &w->ph, &view, (1 + p->jet_margin) * p->sum.u_plateau, &p->sum.classes);
  const cpl_ejecta_classes *ec = &p->sum.classes;
  /* no full-width fragment left (a layer broken sideways): say so rather than print NaN */
  char level[96];
  if (isfinite(ec->level)) snprintf(level, sizeof level, "x = %.5g cm", ec->level);
  else snprintf(level, sizeof level, "none, so no jets and every detached piece is debris");
  ms_log(ctx, MS_LOG_INFO,
         "coupled: detached material at t = %.5g %s (docs/coupling.md \"The split\"; bulk %.4g g "
         "in fragment %lld; level of the foremost full-width fragment %s): jets (ahead "
         "of the level) %.4g g, spall layers (full-width) %.4g g in %zu fragments, debris %.4g "
         "g; fragments ahead %zu, behind %zu; faster than %.4g km/s = (1 + %g) x the grid's "
         "free-surface plateau %.4g: %.4g g in %zu fragments; fastest %.4g km/s",
         ms_out_time(t_now), ms_out_time_label(), ec->m_bulk,
         ec->bulk == SIZE_MAX ? -1LL : (long long)ec->bulk, level, ec->m_jet, ec->m_layer,
         ec->n_layer, ec->m_debris, ec->n_jet, ec->n_debris, ec->v_fast, p->jet_margin,
         p->sum.u_plateau, ec->m_fast, ec->n_fast, ec->v_max);
  char title[160];
  snprintf(title, sizeof title, "fragments at the end of the particle phase, t = %g %s",
           ms_out_time(t_now), ms_out_time_label());
  const char *names[] = {"spectrum.csv",  "fragments.csv",     "cumulative.csv",
                         "mass_hist.csv", "diameter_hist.csv", "ejecta_velocity.csv"};
  ms_status st = MS_OK;
  for (int k = 0; k < 6 && st == MS_OK; k++)
    st = cpl_write_table(ctx, names[k], &w->ph.fr, k, &w->ph.sel, k == 0 ? title : NULL);
  return st;
}

/* Commit the streamed CSV files (each even after an error: what was written stays). */
static ms_status close_csv(one_way *w, ms_status st) {
  if (w->f_ej) {
    ms_status s2 = cpl_commit_csv(&w->af_ej);
    if (st == MS_OK) st = s2;
  }
  if (w->f_fs) {
    ms_status s2 = cpl_commit_csv(&w->af_fs);
    if (st == MS_OK) st = s2;
  }
  w->f_ej = w->f_fs = NULL;
  return w->ctx->size > 1 ? par_agree_status(st) : st;
}

ms_status cpl_run_one_way(ms_ctx *ctx, cpl_problem *p) {
  one_way w;
  memset(&w, 0, sizeof w);
  w.ctx = ctx;
  w.p = p;
  ms_status st = grid_phase(&w);
  if (st == MS_OK) st = particle_setup(&w);
  if (w.have_phase) {
    if (st == MS_OK) st = particle_loop(&w);
    if (st == MS_OK) drive_check(&w);
    if (st == MS_OK) st = summarise(&w);
    if (ctx->size > 1) st = par_agree_status(st);
    st = close_csv(&w, st);
    /* 4. transport of the ejecta to the detector (not checkpointed: no gas log) */
    w.gas.log = NULL;
    free(w.gas.cell_src);
    w.gas.cell_src = NULL;
    const double t_now = w.t_start + ptl_region_time(w.ph.region);
    if (st == MS_OK && p->det_distance > 0 && p->transport_end > t_now)
      st = cpl_transport_phase(ctx, p, &w.ph.fr, &w.ph.sel, &w.gas, t_now,
                               w.hf.x[0] + p->det_distance, w.ph.geo.rho0);
    if (st == MS_OK) st = cpl_check_replicated(ctx, w.gas.g, NULL);
  }
  cpl_gaslog_free(&w.ls.gaslog);
  free(w.gas.cell_src);
  free(w.fs_t);
  free(w.fs_ug);
  free(w.fs_up);
  cpl_phase_close(&w.ph);
  if (w.have_pistons) {
    cpl_piston_free(&w.drive);
    cpl_piston_free(&w.fsurf);
  }
  free(w.hd_buf);
  free(w.hf_buf);
  return st;
}
