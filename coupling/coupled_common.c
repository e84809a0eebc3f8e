/* SPDX-License-Identifier: MIT */
/* coupled_common.c — what the one-way and the two-way drive share: the streamed CSV files
 * (rank 0 writes), the particle region with its fragment search and drag buffers, the drag kick,
 * the transport of the ejecta to the detector, snapshots, and the handling of an unstable step. */
#include "coupled_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Rank 0 writes the CSV files (docs/mpi.md "The coupled problem on MPI ranks"); the other ranks
 * get NULL and write nothing. */
FILE *cpl_open_csv(const ms_ctx *ctx, ms_afile *af, const char *name) {
  memset(af, 0, sizeof *af);
  if (ctx->rank != 0) return NULL;
  char *path = ms_out_path(ctx, name);
  ms_status s = ms_afile_open(af, path);
  free(path);
  return s == MS_OK ? af->f : NULL;
}

ms_status cpl_commit_csv(ms_afile *af) { return af->f ? ms_afile_commit(af) : MS_OK; }

ms_status cpl_write_table(const ms_ctx *ctx, const char *name, const cpl_fragments *fr, int kind,
                          const cpl_ejecta_sel *sel, const char *title) {
  if (ctx->rank != 0) return MS_OK;
  ms_afile af;
  FILE *f = cpl_open_csv(ctx, &af, name);
  if (!f) return MS_ERR_IO;
  switch (kind) {
  case 0:
    cpl_write_spectrum(f, fr, title);
    break;
  case 1:
    cpl_write_fragment_table(f, fr, title);
    break;
  case 2:
    cpl_write_cumulative(f, fr, title);
    break;
  case 3:
    cpl_write_histogram(f, fr, CPL_HIST_MASS, 30, title);
    break;
  case 4:
    cpl_write_histogram(f, fr, CPL_HIST_DIAMETER, 30, title);
    break;
  default:
    cpl_write_ejecta_velocity(f, fr, sel, title);
    break;
  }
  return cpl_commit_csv(&af);
}

/* View of the region's particles for the fragment search: piston and removed particles
 * excluded. */
cpl_particles cpl_particle_view(ptl_region *r, uint8_t *skip) {
  const ptl_state *ps = ptl_region_state(r);
  for (size_t i = 0; i < ps->n; i++) skip[i] = (ps->flags[i] & (PTL_DRIVEN | PTL_REMOVED)) != 0;
  cpl_particles v = {ps->n,
                     ps->x,
                     ps->y,
                     ps->dim == 3 ? ps->z : NULL,
                     ps->vx,
                     ps->vy,
                     ps->dim == 3 ? ps->vz : NULL,
                     ps->mass,
                     skip,
                     ps->gid}; /* fragments numbered by smallest gid: independent of the
                                * particle sorting and of the rank count */
  return v;
}

void cpl_phase_classify(const ms_ctx *ctx, const cpl_particle_phase *ph, const cpl_particles *view,
                        double v_fast, cpl_ejecta_classes *out) {
  cpl_split_opts o;
  cpl_split_opts_default(&o, &ph->fo, v_fast);
  cpl_ejecta_classify(&ph->fr, view, &o, ctx, out);
}

const char *const CPL_EJECTA_TITLE =
    "ejected mass vs time: M_ej every fragment but the largest with its centre ahead of the free "
    "surface (one-way: the grid's; two-way: the gas grid's first node); the split of "
    "docs/coupling.md \"The split\": M_jet ahead of the foremost "
    "full-width fragment, M_layer spall layers, M_debris other detached pieces, M_bulk what stays "
    "on the piston";
const char *const cpl_ejecta_names[CPL_EJECTA_COLS] = {"t",       "M_ej",     "fragments", "M_jet",
                                                       "M_layer", "M_debris", "M_bulk"};
const char *const cpl_ejecta_units[CPL_EJECTA_COLS] = {"10us", "g", "1", "g", "g", "g", "g"};

void cpl_ejecta_row(const ms_ctx *ctx, const cpl_particle_phase *ph, const cpl_particles *view,
                    double t, double row[CPL_EJECTA_COLS]) {
  cpl_ejecta_classes c;
  cpl_phase_classify(ctx, ph, view, INFINITY, &c);
  const double r[CPL_EJECTA_COLS] = {t,
                                     cpl_ejected_mass(&ph->fr, &ph->sel),
                                     (double)ph->fr.n,
                                     c.m_jet,
                                     c.m_layer,
                                     c.m_debris,
                                     c.m_bulk};
  memcpy(row, r, sizeof r);
}

ms_status cpl_phase_open(const ms_ctx *ctx, const cpl_problem *p, double x_drive, double depth,
                         size_t npiston, const double *t_piston, const double *u_piston,
                         cpl_particle_phase *ph) {
  memset(ph, 0, sizeof *ph);
  ms_status st =
      ptl_region_create(p->region, ctx, p->mats->m[p->sample_mat].eos, x_drive, depth, &ph->region);
  if (st != MS_OK) return st;
  ph->geo = ptl_region_get_geometry(ph->region);
  ph->material = p->mats->m[p->sample_mat].name;
  const double dir[3] = {1, 0, 0};
  ptl_region_set_piston(ph->region, npiston, t_piston, u_piston, dir);
  /* MPI: every rank built the whole region and keeps its share; the grids are replicated
   * (docs/mpi.md "The coupled problem on MPI ranks") */
  ptl_region_distribute(ph->region, ctx);
  st = ctx->restart ? MS_OK : ptl_region_init(ph->region); /* a restart: from its checkpoint */
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR, "coupled: particle set-up failed (%s)", ms_status_str(st));
    ptl_region_destroy(&ph->region);
    return st;
  }
  cpl_fragments_init(&ph->fr);
  ph->fo.bond = p->bond;
  ph->fo.spacing = ph->geo.spacing;
  ph->fo.rho0 = ph->geo.rho0;
  ph->fo.box.period[1] = ph->geo.period[1];
  ph->fo.box.period[2] = ph->geo.period[2];
  cpl_ejecta_sel_default(&ph->sel);
  const size_t n = ph->geo.particles; /* owned + ghosts never exceed the global count */
  ph->skip = ms_calloc(n + 1, 1);
  ph->ghost_owner = ctx->size > 1 ? ms_calloc(n + 1, sizeof *ph->ghost_owner) : NULL;
  ph->fx = ms_calloc(n + 1, sizeof(double));
  ph->fy = ms_calloc(n + 1, sizeof(double));
  ph->fz = ms_calloc(n + 1, sizeof(double));
  return MS_OK;
}

void cpl_phase_close(cpl_particle_phase *ph) {
  cpl_fragments_free(&ph->fr);
  free(ph->skip);
  free(ph->ghost_owner);
  free(ph->fx);
  free(ph->fy);
  free(ph->fz);
  ptl_region_destroy(&ph->region);
}

/* Fragments of the particle region (piston and removed particles excluded); on MPI ranks the
 * distributed search over owned particles + ghosts (docs/mpi.md "Fragments on MPI ranks"), after
 * which *view covers the owned particles only (each rank kicks and writes its own). */
ms_status cpl_find_fragments(const ms_ctx *ctx, cpl_particle_phase *ph, cpl_particles *view) {
  /* the model's own connectivity if it has one (the discrete model's unbroken bonds; NULL for
   * cluster dynamics: the distance criterion) */
  ptl_region_links(ph->region, &ph->fo.link_start, &ph->fo.link_nbr);
  if (ctx->size < 2) {
    *view = cpl_particle_view(ph->region, ph->skip);
    return cpl_fragments_find(&ph->fr, view, &ph->fo);
  }
  ptl_region_refresh_ghosts(ph->region);
  *view = cpl_particle_view(ph->region, ph->skip);
  ptl_region_ghost_owners(ph->region, ph->ghost_owner);
  const size_t nlocal = ptl_region_state(ph->region)->nlocal;
  ms_status st = cpl_fragments_find_dist(&ph->fr, view, nlocal, ph->ghost_owner, &ph->fo, ctx);
  view->n = nlocal;
  return st;
}

/* Drag on the detached fragments (their share of the fragment's force, cpl_drag_fragments) as a
 * velocity kick over `span`, and with drag.gas_return the opposite momentum and the energy into
 * the gas cell at each kicked particle. MS_ERR_UNSTABLE if the gas refused a return. */
ms_status cpl_drag_kick(const cpl_problem *p, cpl_particle_phase *ph, const cpl_particles *view,
                        gas_ctx *gas, double t, double span) {
  ptl_state *ps = ptl_region_state(ph->region);
  const uint8_t *skip = ph->skip;
  double *fx = ph->fx, *fy = ph->fy, *fz = ph->fz;
  const size_t n = view->n;         /* owned particles: each rank kicks its own */
  double *cell_src = gas->cell_src; /* MPI: cpl_gas_deposit collects per cell */
  const bool three_d = ps->dim == 3;
  memset(fx, 0, n * sizeof *fx);
  memset(fy, 0, n * sizeof *fy);
  memset(fz, 0, n * sizeof *fz);
  cpl_drag_fragments(p->drag_law, &ph->fr, view, &ph->sel, cpl_grid_gas, gas, t, fx, fy, fz);
  for (size_t i = 0; i < n; i++) {
    if (skip[i] || (fx[i] == 0 && fy[i] == 0 && fz[i] == 0)) continue;
    double v0[3] = {ps->vx[i], ps->vy[i], three_d ? ps->vz[i] : 0.0};
    ps->vx[i] += fx[i] / ps->mass[i] * span;
    ps->vy[i] += fy[i] / ps->mass[i] * span;
    if (three_d) ps->vz[i] += fz[i] / ps->mass[i] * span;
    double v1[3] = {ps->vx[i], ps->vy[i], three_d ? ps->vz[i] : 0.0};
    double dp[3], de = 0, xi[3] = {ps->x[i], ps->y[i], three_d ? ps->z[i] : 0.0};
    for (int k = 0; k < 3; k++) {
      dp[k] = ps->mass[i] * (v1[k] - v0[k]);
      de += 0.5 * ps->mass[i] * (v1[k] * v1[k] - v0[k] * v0[k]);
    }
    gas->drag_work += de; /* the kinetic energy the drag took: booked in the particle balance */
    if (p->gas_return) cpl_gas_deposit(gas, xi, t, t, dp, de);
  }
  if (cell_src) cpl_gas_return_sum(gas);
  return gas->st;
}

/* particles_NNNN.h5 with the fragment ids (MPI: written collectively, each rank its owned
 * particles, which `view` covers). */
ms_status cpl_write_particles(const ms_ctx *ctx, cpl_particle_phase *ph, long index, double t,
                              const cpl_particles *view) {
  char name[64];
  ptl_snapshot_name(name, sizeof name, index);
  char *path = ms_out_path(ctx, name);
  cpl_snapshot_info info = {t, ph->geo.spacing, ph->geo.rho0, ph->fo.box, ph->material};
  ms_status st = cpl_write_snapshot(path, view, &ph->fr, &info);
  free(path);
  return st;
}

/* A particle step failed: the guard's finding (step, time on the particles' clock, particle,
 * quantity) and the state it found, particles_unstable.h5 (docs/reliability.md §5). */
void cpl_particles_unstable(const ms_ctx *ctx, ptl_region *r, ms_status st, double t_start,
                            const char *material) {
  ms_log(ctx, MS_LOG_ERROR, "coupled: particles (clock started at t = %g %s): %s",
         ms_out_time(t_start), ms_out_time_label(),
         st == MS_ERR_UNSTABLE ? ptl_region_error(r) : ms_status_str(st));
  char *path = ms_out_path(ctx, PTL_SNAPSHOT_UNSTABLE);
  if (ptl_region_write_snapshot(r, path, material) == MS_OK)
    ms_log(ctx, MS_LOG_ERROR, "coupled: final state written to " PTL_SNAPSHOT_UNSTABLE);
  free(path);
}

/* Particle steps between checkpoints: time.checkpoint_every, or checkpoint_time rounded to whole
 * steps of dt (0: none). */
long cpl_checkpoint_steps(const cpl_problem *p, double dt) {
  if (p->checkpoint_every > 0) return p->checkpoint_every;
  return p->checkpoint_time > 0 ? lround(fmax(1.0, p->checkpoint_time / dt)) : 0;
}

bool cpl_should_stop(const ms_ctx *ctx, const cpl_problem *p) {
  int stop = ms_interrupt_requested();
  if (p->wall_limit > 0 && ctx->rank == 0 && ms_wall_time() - ctx->wall_start > p->wall_limit)
    stop = 1;
  return ctx->size > 1 ? par_max_int(stop) != 0 : stop;
}

ms_status cpl_check_restart_count(const ms_ctx *ctx, ptl_region *r, size_t nglobal) {
  const ptl_state *ps = ptl_region_state(r);
  const size_t nckpt = ctx->size > 1 ? (size_t)par_sum_long((long)ps->nlocal) : ps->n;
  if (nckpt == nglobal) return MS_OK;
  ms_log(ctx, MS_LOG_ERROR, "coupled: the checkpoint holds %zu particles, this deck %zu", nckpt,
         nglobal);
  return MS_ERR_INPUT;
}

/* Transport of the detached fragments ahead of the free surface (sel) from t0 to the detector
 * plane det_x, the gas grid advancing in lock-step (transport.windows); arrivals and the
 * detector spectrum are written. */
ms_status cpl_transport_phase(ms_ctx *ctx, cpl_problem *p, const cpl_fragments *fr,
                              const cpl_ejecta_sel *sel, gas_ctx *gas, double t0, double det_x,
                              double rho0) {
  ms_status st = MS_OK;
  cpl_transport_opts to;
  cpl_transport_opts_default(&to);
  to.law = (cpl_drag_law)p->drag_law;
  to.rho_p = rho0;
  to.det_x = det_x;
  cpl_transport *tr = NULL;
  const cpl_transport_params tp = {.opts = &to, .gas = cpl_grid_gas, .gas_user = gas};
  st = cpl_transport_create(&tp, &tr);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR, "coupled: the transport's ODE solver could not be set up");
    return ctx->size > 1 ? par_agree_status(st) : st;
  }
  if (p->gas_return) cpl_transport_set_return(tr, cpl_gas_deposit, gas);
  /* keep each flight's fragment size g for the detector spectrum */
  int64_t *gcount = ms_calloc(fr->n + 1, sizeof *gcount);
  size_t nfl = 0, big = cpl_largest_fragment(fr);
  for (size_t k = 0; k < fr->n; k++) {
    if (!cpl_is_ejecta_with(fr, k, sel, big)) continue;
    double x[3] = {fr->cx[k], fr->cy[k], fr->cz[k]}, v[3] = {fr->vx[k], fr->vy[k], fr->vz[k]};
    cpl_transport_add(tr, fr->mass[k], x, v, t0);
    gcount[nfl++] = fr->count[k];
  }
  ms_log(ctx, MS_LOG_INFO,
         "coupled: 3/3 transport of %zu ejecta fragments to the detector at "
         "x = %g cm (%g cm beyond the free surface), until t = %g %s",
         nfl, to.det_x, p->det_distance, ms_out_time(p->transport_end), ms_out_time_label());
  ms_progress prog;
  ms_progress_start(&prog, ctx, "transport", t0, p->transport_end);
  for (long w = 1; w <= p->transport_windows && st == MS_OK; w++) {
    double tw = t0 + (p->transport_end - t0) * (double)w / (double)p->transport_windows;
    st = cont_grid_run_to(gas->g, tw);
    if (st != MS_OK) {
      ms_log(ctx, MS_LOG_ERROR, "coupled: gas grid: %s", cont_grid_error(gas->g));
      break;
    }
    ms_status s2 = cpl_transport_advance(tr, tw);
    if (s2 != MS_OK) /* a failed fragment is reported, the others fly on */
      ms_log(ctx, MS_LOG_WARN, "coupled: transport: %s", cpl_transport_error(tr));
    if (gas->st != MS_OK) {
      st = gas->st;
      ms_log(ctx, MS_LOG_ERROR, "coupled: gas return: %s", cont_grid_error(gas->g));
    }
    ms_progress_update(&prog, tw, w);
  }
  ms_progress_finish(&prog, p->transport_end, p->transport_windows);
  if (st == MS_OK) {
    ms_afile af;
    FILE *f = cpl_open_csv(ctx, &af, "arrivals.csv");
    if (!f && ctx->rank == 0) {
      st = MS_ERR_IO;
    } else if (f) {
      cpl_write_arrivals(f, tr, NULL);
      st = cpl_commit_csv(&af);
    }
    /* the spectrum at the detector: arrived fragments only */
    cpl_fragments det;
    memset(&det, 0, sizeof det);
    det.count = ms_calloc(nfl + 1, sizeof *det.count);
    det.mass = ms_calloc(nfl + 1, sizeof *det.mass);
    size_t narr = 0;
    double marr = 0;
    for (size_t i = 0; i < nfl; i++) {
      cpl_flight fl = cpl_transport_get(tr, i);
      if (fl.state != CPL_ARRIVED) continue;
      det.count[det.n] = gcount[i];
      det.mass[det.n] = fl.mass;
      det.n++;
      narr++;
      marr += fl.mass;
    }
    if (st == MS_OK) {
      f = cpl_open_csv(ctx, &af, "spectrum_detector.csv");
      if (!f && ctx->rank == 0) {
        st = MS_ERR_IO;
      } else if (f) {
        cpl_write_spectrum(f, &det, "fragment spectrum N(g) of the arrivals at the detector");
        st = cpl_commit_csv(&af);
      }
    }
    ms_log(ctx, MS_LOG_INFO, "coupled: %zu of %zu fragments (%.4g g) reached the detector", narr,
           nfl, marr);
    if (p->gas_return) {
      cont_balance gb = cont_grid_balance(gas->g);
      ms_log(ctx, MS_LOG_INFO,
             "coupled: the gas received momentum %.6g g*km/s and energy %.6g kJ from the "
             "fragments (grid sources per cm^2: %.6g, %.6g)",
             gas->returned_p, gas->returned_e, gb.source_momentum, gb.source_energy);
    }
    p->sum.gas_momentum = gas->returned_p;
    p->sum.gas_energy = gas->returned_e;
    p->sum.transported = nfl;
    p->sum.arrived = narr;
    free(det.count);
    free(det.mass);
  }
  free(gcount);
  cpl_transport_destroy(&tr);
  return ctx->size > 1 ? par_agree_status(st) : st; /* rank 0's file errors */
}
