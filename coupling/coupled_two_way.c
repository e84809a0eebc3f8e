/* SPDX-License-Identifier: MIT */
/* coupled_two_way.c — two-way coupling (docs/coupling.md §6): the grid ends at the interface
 * node and runs through the continuum problem's own loop with hooks before and after each of
 * its steps; the particle region beyond the node sub-cycles over each grid step and hands the
 * grid back the impulse it received. */
#include "coupled_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Two-way coupling (docs/coupling.md §6): the grid ends at the interface node and runs through
 * the continuum problem's own loop (profiles, histories, x–t data as in a grid-only run); per
 * grid step the node gets the impulse the particles received in the previous step as a
 * traction (before the step), then the particles sub-cycle with the piston moving at the node's
 * mean velocity over the step, so the piston follows the node's displacement exactly (after
 * it). With a `gas:` section a second grid carries the gas beyond the particles' free surface:
 * its first node moves with the particles' free-surface velocity, and detached fragments ahead
 * of it feel its drag and are transported through it as in the one-way run. */
typedef struct two_way {
  ms_ctx *ctx;
  cpl_problem *p;
  size_t node;
  cpl_particle_phase ph;
  bool have_phase;
  FILE *f_if, *f_ej;
  ms_afile af_if, af_ej;
  double ta, xa, traction; /* interface node before the current grid step; its load */
  cpl_two_way_acc acc;     /* impulse and work exchanged so far (acc.gsteps unused: gsteps) */
  double f_prev;           /* force on this rank's driven particles after the last particle step */
  double dt_sub;           /* the particle step of the current grid step's sub-cycle */
  long gsteps, psteps, next_out, last_search;
  gas_ctx gas; /* gas.g == NULL: no gas section */
  /* checkpoints (docs/coupling.md §7b): every ckpt_every particle steps, at the end of a grid
   * step; ls.gaslog records the tractions and what was done to the gas grid. A restart replays
   * the log through the grid's own loop until gsteps reaches replay_gsteps, then goes live. */
  long ckpt_every, next_ckpt, replay_gsteps;
  bool stopping; /* interrupted: stop at the next checkpoint */
  size_t replay_pos;
  cpl_loop_state ls;
  ms_afile *csv[2];
  int ncsv;
} two_way;

/* Restart: the next logged row, which must be of `kind` (else the log does not fit the deck). */
static const double *replay_row(two_way *w, int kind) {
  const cpl_gaslog *l = &w->ls.gaslog;
  if (w->replay_pos >= l->n || l->row[4 * w->replay_pos] != kind) return NULL;
  return l->row + 4 * w->replay_pos++;
}

static ms_status two_way_before(void *user, cont_grid *g) {
  two_way *w = user;
  if (w->gsteps < w->replay_gsteps) { /* restart: the logged traction */
    const double *r = replay_row(w, CPL_LOG_TRACTION);
    if (!r) {
      ms_log(w->ctx, MS_LOG_ERROR, "coupled: the checkpoint's grid log ends early");
      return MS_ERR_INPUT;
    }
    cont_grid_set_node_force(g, w->node, r[1]);
    return MS_OK;
  }
  /* the particles push the node towards −x: the traction hands the grid the impulse the
   * particles received and the grid has not yet (`owed`, normally the last step's), spread
   * over the expected step; what a different step size leaves over is carried on, so the
   * exchange conserves momentum exactly up to the impulse in flight */
  w->traction = w->acc.dtg_last > 0 ? -w->acc.owed / w->acc.dtg_last : 0.0;
  cont_grid_set_node_force(g, w->node, w->traction);
  if (w->ls.gaslog.on) cpl_gaslog_traction(&w->ls.gaslog, w->traction);
  w->ta = cont_grid_time(g);
  w->xa = cont_grid_view(g).x[w->node];
  return MS_OK;
}

/* Fragments, ejected mass and the drag kick since the last search (gas section only). */
static ms_status two_way_fragments(two_way *w, double t) {
  cpl_problem *p = w->p;
  cpl_particles view;
  ms_status st = cpl_find_fragments(w->ctx, &w->ph, &view);
  if (st != MS_OK || !w->gas.g) return st;
  /* ejecta: detached fragments ahead of the gas grid's first node (the particles' free surface
   * as the gas sees it) */
  w->ph.sel.plane = cont_grid_view(w->gas.g).x[0] + w->gas.offset;
  double row[CPL_EJECTA_COLS];
  cpl_ejecta_row(w->ctx, &w->ph, &view, t, row);
  if (w->f_ej) ms_csv_row(w->f_ej, CPL_EJECTA_COLS, row);
  if (p->drag_law != CPL_DRAG_NONE) {
    double span = (double)(w->psteps - w->last_search) * w->dt_sub;
    st = cpl_drag_kick(p, &w->ph, &view, &w->gas, t, span);
    if (st != MS_OK)
      ms_log(w->ctx, MS_LOG_ERROR, "coupled: gas return: %s", cont_grid_error(w->gas.g));
  }
  w->last_search = w->psteps;
  return st;
}

/* Restart: what the logged grid step did to the gas grid (velocity, advance, drag sources). */
static ms_status two_way_replay(two_way *w) {
  const cpl_gaslog *l = &w->ls.gaslog;
  ms_status st = MS_OK;
  while (st == MS_OK && w->replay_pos < l->n && l->row[4 * w->replay_pos] != CPL_LOG_TRACTION)
    st = w->gas.g ? cpl_gaslog_apply(l->row + 4 * w->replay_pos++, w->gas.g) : MS_ERR_INPUT;
  if (st == MS_OK && ++w->gsteps == w->replay_gsteps && w->replay_pos != l->n) st = MS_ERR_INPUT;
  if (st != MS_OK)
    ms_log(w->ctx, MS_LOG_ERROR,
           "coupled: replaying the checkpoint's grid log failed at entry "
           "%zu (grid step %ld)",
           w->replay_pos, w->gsteps);
  return st;
}

/* Checkpoint at the end of a grid step: the particles refreshed (ptl_region_refresh, as the
 * restart will), the accumulators, the log and the streamed CSV text (cpl_checkpoint_write). */
static ms_status two_way_checkpoint(two_way *w) {
  w->ls.step = w->psteps, w->ls.next_out = w->next_out, w->ls.last_search = w->last_search;
  w->ls.returned_p = w->gas.returned_p, w->ls.returned_e = w->gas.returned_e;
  w->ls.drag_work = w->gas.drag_work;
  w->ls.tw = w->acc;
  w->ls.tw.gsteps = (double)w->gsteps;
  ms_status st =
      cpl_checkpoint_write(w->ctx, w->p->deck_hash, w->ph.region, &w->ls, w->csv, w->ncsv);
  w->f_prev = ptl_region_driven_force(w->ph.region); /* the refresh recomputed the forces */
  return st;
}

/* The particles sub-cycle over the grid step that just ended, the piston at the node's mean
 * velocity; the impulse and work they received. */
static ms_status sub_cycle(two_way *w, double dtg, double ubar) {
  ptl_region *r = w->ph.region;
  /* sub-cycle: whole number of particle steps over the grid step */
  long nsub = (long)ceil(dtg / w->ph.geo.dt * (1 - 1e-12));
  if (nsub < 1) nsub = 1;
  w->dt_sub = dtg / (double)nsub;
  ptl_region_set_dt(r, w->dt_sub);
  ptl_region_hold_piston(r, ubar, dtg);
  ms_status st = MS_OK;
  double imp = 0;
  for (long k = 0; k < nsub && st == MS_OK; k++) {
    st = ptl_region_step(r); /* MPI: the status is the same on every rank */
    w->psteps++;
    const double f = ptl_region_driven_force(r);
    /* impulse on the particles from the piston: velocity Verlet's ½(F_old + F_new) Δt */
    imp += -0.5 * (w->f_prev + f) * w->dt_sub;
    w->f_prev = f;
  }
  if (st != MS_OK) {
    cpl_particles_unstable(w->ctx, r, st, 0.0, w->ph.material);
    return st;
  }
  /* MPI: each rank holds the impulse on its own driven particles (linear in their forces, so the
   * shares add up to the whole even when driven particles migrate between the sub-steps); one
   * fixed-order sum per grid step gives every rank the same bits, so the replicated grids stay
   * bitwise equal (docs/mpi.md "The coupled problem on MPI ranks") */
  if (w->ctx->size > 1) par_sum_doubles_ordered(&imp, 1);
  /* the piston's work on the particles: velocity Verlet's ½(F_old + F_new)·Δs with Δs = ū Δt
   * over every sub-step, i.e. ū × impulse (the model's piston work to round-off; this sum is
   * the same on every rank and continues bit for bit after a restart) */
  w->acc.w_before = w->acc.Wp;
  w->acc.Wp += ubar * imp;
  w->acc.p_avg = imp / (dtg * w->ph.geo.area);
  w->acc.Jp += w->acc.p_avg * dtg;
  w->acc.owed += w->acc.p_avg * dtg;
  w->acc.dtg_last = dtg;
  return MS_OK;
}

/* The gas ahead is pushed by the particles' free surface (ufs). */
static ms_status push_gas(two_way *w, double ufs, double tb) {
  cont_grid_set_node_velocity(w->gas.g, 0, ufs);
  ms_status st = cont_grid_run_to(w->gas.g, tb);
  if (w->ls.gaslog.on) {
    cpl_gaslog_velocity(&w->ls.gaslog, ufs);
    cpl_gaslog_run_to(&w->ls.gaslog, tb);
  }
  if (st != MS_OK) ms_log(w->ctx, MS_LOG_ERROR, "coupled: gas grid: %s", cont_grid_error(w->gas.g));
  return st;
}

static ms_status two_way_output(two_way *w, double tb, double ubar) {
  cpl_particles view = cpl_particle_view(w->ph.region, w->ph.skip);
  view.n = ptl_region_state(w->ph.region)->nlocal; /* MPI: each rank its owned particles */
  ms_status st = cpl_write_particles(w->ctx, &w->ph, w->next_out, tb, &view);
  ms_log(w->ctx, MS_LOG_INFO,
         "coupled: two-way t = %.5g %s: %ld grid steps, %ld particle steps; interface u = "
         "%.5g km/s, p = %.5g GPa; impulse [GPa*us] grid %.6g vs particles %.6g, work [kJ/cm^2] "
         "grid %.6g vs particles %.6g; %zu fragments",
         ms_out_time(tb), ms_out_time_label(), w->gsteps, w->psteps, ubar, w->acc.p_avg,
         ms_out_time(w->acc.Jg), ms_out_time(w->acc.Jp), w->acc.Wg, w->acc.Wp / w->ph.geo.area,
         w->ph.fr.n);
  w->next_out++;
  return st;
}

static ms_status two_way_after(void *user, cont_grid *g) {
  two_way *w = user;
  if (w->gsteps < w->replay_gsteps) return two_way_replay(w);
  cpl_problem *p = w->p;
  const double area = w->ph.geo.area;
  w->gsteps++;
  double tb = cont_grid_time(g), xb = cont_grid_view(g).x[w->node], dtg = tb - w->ta;
  double ubar = (xb - w->xa) / dtg;
  w->acc.Jg += w->traction * dtg;
  w->acc.Wg += w->traction * (xb - w->xa);
  w->acc.owed += w->traction * dtg;
  ms_status st = sub_cycle(w, dtg, ubar);
  if (st != MS_OK) return st;
  double ufs = ptl_region_free_surface_velocity(w->ph.region);
  if (w->ctx->size > 1) /* an all-reduced mean: rank 0's bits drive every rank's gas grid */
    par_bcast_doubles(&ufs, 1, 0);
  if (w->gas.g && (st = push_gas(w, ufs, tb)) != MS_OK) return st;
  double row[8] = {tb, ubar, w->acc.p_avg, ufs, w->acc.Jg, w->acc.Jp, w->acc.Wg, w->acc.Wp / area};
  if (w->f_if) ms_csv_row(w->f_if, 8, row);
  bool out_now = tb >= p->t_end * (double)w->next_out / (double)p->n_out * (1 - 1e-12);
  if (out_now || (w->gas.g && w->psteps - w->last_search >= p->frag_every)) {
    st = two_way_fragments(w, tb);
    if (st != MS_OK) return st;
  }
  if (out_now) st = two_way_output(w, tb, ubar);
  p->sum.u_interface = ubar;
  p->sum.u_free_surface = ufs;
  if (st == MS_OK && w->ckpt_every > 0 && w->psteps >= w->next_ckpt) {
    st = two_way_checkpoint(w);
    w->next_ckpt = (w->psteps / w->ckpt_every + 1) * w->ckpt_every;
    if (st == MS_OK && w->stopping) {
      ms_log(w->ctx, MS_LOG_WARN, "coupled: interrupted; checkpoint at particle step %ld written",
             w->psteps);
      return MS_INTERRUPTED;
    }
  }
  if (st == MS_OK && !w->stopping && cpl_should_stop(w->ctx, p)) { /* collective */
    w->stopping = true;
    if (w->ckpt_every == 0) {
      ms_log(w->ctx, MS_LOG_WARN, "coupled: interrupted at particle step %ld (no checkpoints)",
             w->psteps);
      return MS_INTERRUPTED;
    }
    ms_log(w->ctx, MS_LOG_WARN, "coupled: interrupt: stopping at the next checkpoint");
  }
  return st;
}

/* The streamed CSV files (interface; ejected mass with a gas grid), headers unless restarting. */
static ms_status open_files(two_way *w) {
  ms_ctx *ctx = w->ctx;
  const bool gas = w->p->gas_grid != NULL;
  w->f_if = cpl_open_csv(ctx, &w->af_if, "interface.csv");
  w->f_ej = gas ? cpl_open_csv(ctx, &w->af_ej, "ejecta_mass.csv") : NULL;
  w->csv[0] = &w->af_if, w->csv[1] = &w->af_ej, w->ncsv = gas ? 2 : 1;
  ms_status st = ctx->rank == 0 && (!w->f_if || (gas && !w->f_ej)) ? MS_ERR_IO : MS_OK;
  if (ctx->size > 1) st = par_agree_status(st);
  if (st != MS_OK) {
    if (w->f_if) ms_afile_abort(&w->af_if);
    if (w->f_ej) ms_afile_abort(&w->af_ej);
    w->f_if = w->f_ej = NULL;
    return st;
  }
  static const char *const names[] = {"t",      "u_interface", "p_particles", "u_free_surface",
                                      "J_grid", "J_particles", "W_grid",      "W_particles"};
  static const char *const units[] = {"10us",     "km/s",     "GPa",     "km/s",
                                      "GPa*10us", "GPa*10us", "kJ/cm^2", "kJ/cm^2"};
  if (w->f_if && !ctx->restart) /* a restart writes back the text so far */
    ms_csv_header(w->f_if,
                  "two-way interface: node velocity, particle pressure, impulse and work "
                  "per unit area as the grid and the particles received them",
                  8, names, units);
  if (w->f_ej && !ctx->restart)
    ms_csv_header(w->f_ej, CPL_EJECTA_TITLE, CPL_EJECTA_COLS, cpl_ejecta_names, cpl_ejecta_units);
  return MS_OK;
}

/* The particle region beyond the interface node (piston at rest until the first grid step),
 * the gas grid beyond its free surface, the files, and a restart's state. */
static ms_status setup(two_way *w) {
  ms_ctx *ctx = w->ctx;
  cpl_problem *p = w->p;
  cont_grid *g = cont_problem_grid(p->grid_live);
  w->node = cont_grid_history(g, p->tag_drive).node;
  const double x_if0 = cont_grid_view(g).x[w->node];
  const double th[2] = {0, 1}, uh[2] = {0, 0};
  ms_status st = cpl_phase_open(ctx, p, x_if0, p->depth, 2, th, uh, &w->ph);
  if (st != MS_OK) return st;
  w->have_phase = true;
  const ptl_region_geometry *geo = &w->ph.geo;
  w->dt_sub = geo->dt;
  w->ckpt_every = cpl_checkpoint_steps(p, geo->dt);
  w->next_ckpt = w->ckpt_every;
  w->ls.gaslog.on = w->ckpt_every > 0;
  st = open_files(w);
  if (st != MS_OK) return st;
  if (p->gas_grid) {
    cont_grid *gg = cont_problem_grid(p->gas_grid);
    /* the gas grid's first node sits on the particles' nominal free surface */
    w->gas = cpl_gas_of(p, gg, geo->x_top - cont_grid_view(gg).x[0], geo->area);
    if (ctx->size > 1 && p->gas_return) /* per-cell sources summed over the ranks */
      w->gas.cell_src = ms_calloc(2 * cont_grid_ncells(gg) + 1, sizeof *w->gas.cell_src);
    w->gas.log = w->ls.gaslog.on ? &w->ls.gaslog : NULL;
  }
  if (ctx->restart) {
    st = cpl_checkpoint_restore(ctx, p->deck_hash, w->ph.region, &w->ls, NULL, w->csv, w->ncsv);
    if (st == MS_OK) st = cpl_check_restart_count(ctx, w->ph.region, geo->particles);
    w->psteps = w->ls.step, w->next_out = w->ls.next_out, w->last_search = w->ls.last_search;
    w->acc = w->ls.tw;
    w->replay_gsteps = (long)w->ls.tw.gsteps;
    w->gas.returned_p = w->ls.returned_p, w->gas.returned_e = w->ls.returned_e;
    w->gas.drag_work = w->ls.drag_work;
    if (w->ckpt_every > 0) /* (a deck without checkpoints fails the deck-hash check above) */
      w->next_ckpt = (w->psteps / w->ckpt_every + 1) * w->ckpt_every;
  }
  w->f_prev = ptl_region_driven_force(w->ph.region);
  ms_log(ctx, MS_LOG_INFO,
         "coupled: two-way: grid node %zu at x = %g, particle region %g cm, particle dt %g%s",
         w->node, x_if0, p->depth, geo->dt,
         p->gas_grid ? ", gas grid beyond the free surface" : "");
  return st;
}

/* After the grid's loop: the fragment tables, the transport (gas section), the summary. */
static ms_status finish(two_way *w, ms_status st) {
  ms_ctx *ctx = w->ctx;
  cpl_problem *p = w->p;
  const bool dist = ctx->size > 1;
  const cont_grid *g = cont_problem_grid(p->grid_live);
  const ptl_region_geometry *geo = &w->ph.geo;
  if (st == MS_OK) st = cpl_write_table(ctx, "spectrum.csv", &w->ph.fr, 0, NULL, NULL);
  if (dist) /* rank 0's file errors stop every rank */
    st = par_agree_status(st);
  if (p->gas_grid) /* at the end of the particle phase (the transport moves it on) */
    p->sum.gas_shift = cont_grid_view(w->gas.g).x[0] + w->gas.offset - geo->x_top;
  if (st == MS_OK && p->gas_grid) {
    const char *tables[] = {"fragments.csv", "cumulative.csv", "mass_hist.csv", "diameter_hist.csv",
                            "ejecta_velocity.csv"};
    for (int k = 0; k < 5 && st == MS_OK; k++)
      st = cpl_write_table(ctx, tables[k], &w->ph.fr, k + 1, &w->ph.sel, NULL);
    if (dist) st = par_agree_status(st);
    if (st == MS_OK && p->det_distance > 0 && p->transport_end > cont_grid_time(g))
      st = cpl_transport_phase(ctx, p, &w->ph.fr, &w->ph.sel, &w->gas, cont_grid_time(g),
                               geo->x_top + p->det_distance, geo->rho0);
  }
  p->sum.particles = geo->particles;
  p->sum.steps = w->psteps;
  p->sum.fragments = w->ph.fr.n;
  p->sum.ejected_mass = p->gas_grid ? cpl_ejected_mass(&w->ph.fr, &w->ph.sel) : 0.0;
  /* the particles' last grid step is in flight: the grid receives its counterpart in its next
   * step; compare what both sides have exchanged so far */
  p->sum.impulse_grid = w->acc.Jg;
  p->sum.impulse_particles = w->acc.Jp - w->acc.owed;
  p->sum.work_grid = w->acc.Wg;
  p->sum.work_particles = w->acc.w_before / geo->area;
  p->sum.piston_work = w->acc.Wp;
  if (st == MS_OK) st = cpl_check_replicated(ctx, g, w->gas.g);
  const double jsum = w->acc.Jg + p->sum.impulse_particles,
               wsum = w->acc.Wg + p->sum.work_particles;
  ms_log(ctx, MS_LOG_INFO,
         "coupled: two-way interface balance (per cm^2, the last grid step's exchange in "
         "flight excluded): impulse grid %.6g + particles %.6g = %.3g (%.2g of it); work grid "
         "%.6g + particles %.6g = %.3g (%.2g of it)",
         w->acc.Jg, p->sum.impulse_particles, jsum,
         jsum / fmax(fabs(p->sum.impulse_particles), 1e-300), w->acc.Wg, p->sum.work_particles,
         wsum, wsum / fmax(fabs(p->sum.work_particles), 1e-300));
  return st;
}

ms_status cpl_run_two_way(ms_ctx *ctx, cpl_problem *p) {
  two_way w;
  memset(&w, 0, sizeof w);
  w.ctx = ctx;
  w.p = p;
  w.next_out = 1;
  ms_status st = setup(&w);
  if (st == MS_OK) {
    cont_step_hooks hooks = {two_way_before, two_way_after, &w, p->t_end};
    st = cont_problem_run_hooked(ctx, p->grid_live, &hooks);
    if (st == MS_OK && w.gsteps < w.replay_gsteps) {
      ms_log(ctx, MS_LOG_ERROR, "coupled: the checkpoint is beyond the end of this deck's run");
      st = MS_ERR_INPUT;
    }
  }
  if (w.have_phase) {
    if (w.f_if) {
      ms_status s2 = cpl_commit_csv(&w.af_if);
      if (st == MS_OK) st = s2;
    }
    if (w.f_ej) {
      ms_status s2 = cpl_commit_csv(&w.af_ej);
      if (st == MS_OK) st = s2;
    }
    /* the transport runs replicated and deposits its returns directly (not checkpointed) */
    free(w.gas.cell_src);
    w.gas.cell_src = NULL;
    w.gas.log = NULL;
    st = finish(&w, st);
  }
  free(w.gas.cell_src);
  cpl_gaslog_free(&w.ls.gaslog);
  cpl_phase_close(&w.ph);
  return st;
}
