/* SPDX-License-Identifier: MIT */
/* cd_problem.c — the `cluster_dynamics` deck problem (docs/input-cd.md): fill the regions that
 * cd_deck.c read with a lattice, set up the simulation, run it and write the outputs
 * (cd_output.c) and HDF5/XDMF snapshots into the output directory. cd_problem_run is the list
 * of these phases, with one cleanup path. */
#include "cd_problem_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* seeds and materials of a region's grains (the seeds are those of cd_polycrystal): uniform in
 * a box region, in the bounding box of a sphere or cylinder (clipped to the problem's box) */
static void grain_seed(const cd_problem *p, const cd_deck_region *r, int g, double x[3]) {
  double lo[3], hi[3];
  if (r->shape == SHAPE_BOX) memcpy(lo, r->lo, sizeof lo), memcpy(hi, r->hi, sizeof hi);
  else cd_deck_region_bounds(p, r, true, lo, hi);
  for (int a = 0; a < 3; a++)
    x[a] = a < p->dim ? lo[a] + (hi[a] - lo[a]) *
                                    ptl_splitmix64_uniform(r->grain_seed, 3 * (uint64_t)g + a)
                      : 0.0;
}
static int grain_material(const cd_deck_region *r, int g) {
  if (r->ngmat == 0) return r->mat;
  double u = ptl_splitmix64_uniform(r->grain_seed ^ 0x5bd1e995u, (uint64_t)g), acc = 0;
  for (int k = 0; k < r->ngmat; k++) {
    acc += r->gfrac[k];
    if (u < acc) return r->gmat[k];
  }
  return r->gmat[r->ngmat - 1];
}
static int nearest_grain(const cd_problem *p, const cd_deck_region *r, const double x[3]) {
  int best = 0;
  double bd = INFINITY;
  for (int g = 0; g < r->ngrains; g++) {
    double s[3], d2 = 0;
    grain_seed(p, r, g, s);
    for (int a = 0; a < p->dim; a++) d2 += (x[a] - s[a]) * (x[a] - s[a]);
    if (d2 < bd) {
      bd = d2;
      best = g;
    }
  }
  return best;
}

/* Fill the regions: a site belongs to the first ordinary region containing it (overlaps of the
 * same material are fine), else to the first `matrix` region containing it. Polycrystal regions
 * with rotated grains claim their sites in the global lattice and are then filled by
 * cd_polycrystal (their residual porosity goes to the log). */
typedef struct site_list {
  size_t n, cap;
  double *x;
  int *reg, *mat;
} site_list;

static void site_add(site_list *l, const double x[3], int reg, int mat) {
  if (l->n == l->cap) {
    l->cap = l->cap ? 2 * l->cap : 4096;
    l->x = ms_realloc(l->x, 3 * l->cap, sizeof *l->x);
    l->reg = ms_realloc(l->reg, l->cap, sizeof *l->reg);
    l->mat = ms_realloc(l->mat, l->cap, sizeof *l->mat);
  }
  memcpy(l->x + 3 * l->n, x, 3 * sizeof *x);
  l->reg[l->n] = reg;
  l->mat[l->n++] = mat;
}

static int owner_region(const cd_problem *p, const double x[3]) {
  for (int kk = 0; kk < 2 * p->nreg; kk++) { /* ordinary regions, then matrices */
    const int k = kk % p->nreg;
    const cd_deck_region *r = &p->reg[k];
    if (r->matrix == (kk >= p->nreg) && cd_deck_region_contains(r, x, p->dim)) return k;
  }
  return -1;
}

typedef struct owner_filter {
  const cd_problem *p;
  int reg;
} owner_filter;
static bool owned_by(void *user, const double x[3]) {
  const owner_filter *f = user;
  return owner_region(f->p, x) == f->reg;
}

/* The particles of the regions; *region_of: each particle's region (index = its gid). */
static ptl_state *build_particles(const cd_problem *p, ms_ctx *ctx, int **region_of) {
  size_t lattice_sites[CD_MAX_REGIONS] = {0}; /* sites a rotated polycrystal region replaces */
  double per[3];
  cd_deck_lattice_period(p, per);
  long ncell[3] = {1, 1, 1};
  for (int a = 0; a < p->dim; a++)
    ncell[a] = (long)ceil((p->box.hi[a] - p->origin[a]) / per[a]) + 1;
  const int nb = p->dim == 3 ? 4 : 2;
  const double fcc[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  const double tri[2][3] = {{0, 0, 0}, {0.5, 0.5, 0}};
  const double vol = cd_cluster_volume(p->lattice, p->r0, p->thickness);
  site_list l = {0};
  for (long iz = 0; iz < ncell[2]; iz++)
    for (long iy = 0; iy < ncell[1]; iy++)
      for (long ix = 0; ix < ncell[0]; ix++)
        for (int b = 0; b < nb; b++) {
          const double *bs = p->dim == 3 ? fcc[b] : tri[b];
          double x[3] = {p->origin[0] + (ix + bs[0]) * per[0], p->origin[1] + (iy + bs[1]) * per[1],
                         p->dim == 3 ? p->origin[2] + (iz + bs[2]) * per[2] : 0.0};
          bool inside = true;
          for (int a = 0; a < p->dim; a++)
            if (x[a] < p->box.lo[a] || x[a] >= p->box.hi[a]) inside = false;
          if (!inside) continue;
          int k = owner_region(p, x);
          if (k < 0) continue;
          const cd_deck_region *r = &p->reg[k];
          if (r->ngrains > 0 && r->rotate) { /* filled below */
            lattice_sites[k]++;
            continue;
          }
          int mat = r->ngrains > 0 ? grain_material(r, nearest_grain(p, r, x)) : r->mat;
          site_add(&l, x, k, mat);
        }
  for (int k = 0; k < p->nreg; k++) {
    const cd_deck_region *r = &p->reg[k];
    if (r->ngrains == 0 || !r->rotate) continue;
    double lo[3], hi[3], ulo[3], uhi[3], *xyz = NULL, por = 0;
    int32_t *grain = NULL;
    /* a profiled face reaches up to `amplitude` beyond hi: grains fill that box and the owner
     * filter cuts the profile; the sine and random profiles average zero over the periodic
     * extent, so the region's volume is that of the flat box (the porosity's reference) */
    double vbox = 1.0;
    cd_deck_region_bounds(p, r, true, lo, hi);
    cd_deck_region_bounds(p, r, false, ulo, uhi);
    for (int a = 0; a < p->dim; a++) {
      vbox *= hi[a] - lo[a];
      if (r->surface != SURF_FLAT && a == r->surface_axis)
        hi[a] = fmin(r->hi[a] + r->amplitude, p->box.hi[a]);
    }
    /* grains wrap along a periodic axis that the region spans */
    bool per[3] = {false, false, false};
    for (int a = 0; a < p->dim; a++)
      per[a] = p->box.bc[a] == CD_BC_PERIODIC && ulo[a] <= p->box.lo[a] && uhi[a] >= p->box.hi[a];
    owner_filter f = {p, k};
    size_t n = cd_polycrystal(p->dim, p->r0, p->thickness, lo, hi, per, r->ngrains, r->grain_seed,
                              r->dmin, owned_by, &f, &xyz, &grain, &por);
    if (r->surface != SURF_FLAT)
      por = 1.0 - (double)n * vol / (p->dim == 2 ? vbox * p->thickness : vbox);
    /* a sphere or cylinder fills part of its bounding box: its porosity is relative to the
     * sites of the single-crystal lattice it replaces (the same shape's volume) */
    if (r->shape != SHAPE_BOX)
      por = lattice_sites[k] ? 1.0 - (double)n / (double)lattice_sites[k] : 0.0;
    for (size_t i = 0; i < n; i++) site_add(&l, xyz + 3 * i, k, grain_material(r, grain[i]));
    ms_log(ctx, MS_LOG_INFO,
           "cluster_dynamics: region %d: polycrystal of %d grains, %zu particles, "
           "residual porosity %.2f %%",
           k + 1, r->ngrains, n, 100.0 * por);
    free(xyz);
    free(grain);
  }
  ptl_state *s = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = l.n, .dim = p->dim}, &s), "ptl_state_create");
  *region_of = l.reg; /* gid q is site q */
  for (size_t q = 0; q < l.n; q++) {
    const cd_deck_region *r = &p->reg[l.reg[q]];
    const double *x = l.x + 3 * q;
    size_t i = ptl_state_add(s, x[0], x[1], x[2], eos_rho0(p->mat[l.mat[q]]->eos) * vol, l.mat[q]);
    s->vx[i] = r->velocity[0];
    s->vy[i] = r->velocity[1];
    s->vz[i] = r->velocity[2];
    if (r->piston) s->flags[i] |= PTL_DRIVEN;
  }
  free(l.x);
  free(l.mat);
  return s;
}

/* Thermal velocities: amplitude·(2u − 1) per component, u the splitmix64 output of the
 * particle's gid (the same on any rank count), mean removed over the integrated particles
 * (`dist`: over every rank's share). */
static void add_thermal(const cd_problem *p, ptl_state *ps, bool dist) {
  double mean[4] = {0, 0, 0, 0}, *v[3] = {ps->vx, ps->vy, ps->vz}; /* Σ dv per axis, count */
  for (size_t i = 0; i < ps->nlocal; i++) {
    if (ps->flags[i] & PTL_DRIVEN) continue;
    for (int c = 0; c < p->dim; c++) {
      double dv =
          p->thermal_amp *
          (2.0 * ptl_splitmix64_uniform(p->thermal_seed, 3 * (uint64_t)ps->gid[i] + c) - 1.0);
      v[c][i] += dv;
      mean[c] += dv;
    }
    mean[3] += 1.0;
  }
  if (dist) par_sum_doubles(mean, 4);
  for (size_t i = 0; i < ps->nlocal; i++)
    if (!(ps->flags[i] & PTL_DRIVEN))
      for (int c = 0; c < p->dim; c++) v[c][i] -= mean[c] / (mean[3] > 0 ? mean[3] : 1.0);
}

/* Each particle's velocity: that of its region (region_of: by gid). */
static void set_region_velocities(const cd_problem *p, ptl_state *ps, const int *region_of) {
  for (size_t i = 0; i < ps->nlocal; i++) {
    const double *v = p->reg[region_of[ps->gid[i]]].velocity;
    ps->vx[i] = v[0], ps->vy[i] = v[1], ps->vz[i] = v[2];
  }
}

/* The relaxation stage (`relax:`): damped dynamics with the box rescaled toward zero mean
 * normal stress, then at rest with the bonds of the relaxed packing; logged. The regions'
 * velocities are set aside for it (bodies relax at rest, where they were built) and given
 * back after it. */
static ms_status relax_sample(ms_ctx *ctx, const cd_problem *p, cd_sim *s, double c0max,
                              size_t nglobal, const int *region_of) {
  cd_relax_config rc = p->relax;
  double rho0 = 0.0; /* stiffness scale of the box rescale: largest ρ0 times largest c0² */
  for (int k = 0; k < p->nmat; k++) rho0 = fmax(rho0, eos_rho0(p->mat[k]->eos));
  rc.damping_gamma = p->relax_j > 0 ? c0max / (p->relax_j * p->r0) : 0.0;
  rc.tau = p->relax_tau * p->r0 / c0max;
  rc.modulus = rho0 * c0max * c0max;
  cd_relax_result r;
  ptl_state *ps = s->p;
  for (size_t i = 0; i < ps->nlocal; i++) ps->vx[i] = ps->vy[i] = ps->vz[i] = 0.0;
  ms_status st = cd_sim_relax(s, &rc, &r);
  if (st != MS_OK) return st;
  set_region_velocities(p, ps, region_of);
  const double vsolid = (double)nglobal * cd_cluster_volume(p->lattice, p->r0, p->thickness);
  ms_log(ctx, MS_LOG_INFO,
         "cluster_dynamics: relaxation: %ld steps; mean stress xx yy zz %.4g "
         "%.4g %.4g -> %.4g %.4g %.4g GPa; box stretch %.5f %.5f %.5f; density %.5g -> %.5g g/cm3, "
         "porosity (1 - N V_site/V) %.3f -> %.3f %%; energy released %.4g kJ/g (damping and quench "
         "%.4g); %ld bonds broken",
         r.steps, r.stress0[0], r.stress0[1], r.stress0[2], r.stress[0], r.stress[1], r.stress[2],
         r.lambda[0], r.lambda[1], r.lambda[2], r.mass / r.volume0, r.mass / r.volume,
         100.0 * (1.0 - vsolid / r.volume0), 100.0 * (1.0 - vsolid / r.volume), r.energy / r.mass,
         r.dissipated / r.mass, r.broken_bonds);
  if (p->thermal_amp > 0) add_thermal(p, s->p, s->dd != NULL);
  return MS_OK;
}

/* A run of the problem: what its phases hand on, and what the one cleanup path frees. */
typedef struct cd_run {
  ms_ctx *ctx;
  const cd_problem *p;
  cd_restart *rs; /* a restart: the checkpoint read (until its outputs are restored) */
  ms_h5r *rh;
  ptl_state *ps;  /* owned until cd_sim_create takes it */
  int *region_of; /* each particle's region, by gid (a built lattice, not a restart) */
  cd_sim *s;
  cd_config cfg;
  double c0max, dir[3];
  size_t nglobal;
  long nsteps;
  cd_outputs out;
} cd_run;

/* The particles: read from the checkpoint or built from the regions; thermal velocities; the
 * free-surface layer. */
static ms_status run_particles(cd_run *r) {
  ms_ctx *ctx = r->ctx;
  const cd_problem *p = r->p;
  if (ctx->restart) {
    dk_errors e;
    dk_errors_init(&e);
    r->rh = ms_ckpt_open(ctx->restart, CD_CHECKPOINT_FORMAT, p->deck_hash, &e);
    if (r->rh) r->rs = cd_restart_read(r->rh, ctx, p->dim, p->mode == CD_CUTOFF_BONDED, &e);
    if (r->rs) r->ps = cd_restart_take_particles(r->rs);
    ms_status st = par_agree_status(r->rs ? MS_OK : MS_ERR_INPUT);
    if (st != MS_OK) {
      if (ctx->rank == 0) dk_errors_print(&e, stderr);
      ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: cannot restart from %s", ctx->restart);
    }
    dk_errors_free(&e);
    if (st != MS_OK) return st;
  } else {
    r->ps = build_particles(p, ctx, &r->region_of);
  }
  ptl_state *ps = r->ps;
  if (!ps || ps->n == 0) {
    ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: the regions contain no lattice site");
    return MS_ERR_INPUT;
  }
  /* thermal velocities; with a relaxation they are given after it (it ends at rest) */
  if (p->thermal_amp > 0 && !r->rs && !p->relax_on) add_thermal(p, ps, false);
  /* free-surface layer: particles within r0 of the farthest one along the piston direction */
  const double *dir = r->dir;
  for (int a = 0; a < 3; a++) r->dir[a] = p->piston_dir[a];
  if (p->piston.n && !r->rs) {
    double smax = -INFINITY;
    for (size_t i = 0; i < ps->n; i++) {
      double sx = ps->x[i] * dir[0] + ps->y[i] * dir[1] + ps->z[i] * dir[2];
      if (sx > smax) smax = sx;
    }
    for (size_t i = 0; i < ps->n; i++) {
      double sx = ps->x[i] * dir[0] + ps->y[i] * dir[1] + ps->z[i] * dir[2];
      if (sx > smax - p->r0 && !(ps->flags[i] & PTL_DRIVEN)) ps->flags[i] |= PTL_SURFACE;
    }
  }
  r->nglobal = ps->n;
  return MS_OK;
}

/* The simulation: its configuration, the pair tables of every material pair, the piston. */
static ms_status sim_create(cd_run *r) {
  ms_ctx *ctx = r->ctx;
  const cd_problem *p = r->p;
  double c0max = 0;
  for (int k = 0; k < p->nmat; k++) c0max = fmax(c0max, eos_c0(p->mat[k]->eos));
  r->c0max = c0max;
  r->cfg = (cd_config){.r0 = p->r0,
                       .skin = p->skin * p->r0,
                       .dt = p->dt > 0 ? p->dt : p->courant * p->r0 / c0max,
                       .cutoff = p->mode,
                       .damping_gamma = p->damping_j > 0 ? c0max / (p->damping_j * p->r0) : 0.0,
                       .sort_every = 8,
                       .lattice = p->lattice,
                       .thickness = p->thickness,
                       .integrator = p->integrator};
  char names[CD_MAX_MATERIALS * 64] = ""; /* the snapshots' material table, "al,pb" */
  for (int k = 0; k < p->nmat; k++) ptl_material_table_add(names, sizeof names, p->mat[k]->name);
  ms_must(cd_sim_create(&(cd_sim_params){.particles = r->ps,
                                         .box = &p->box,
                                         .cfg = &r->cfg,
                                         .nmat = p->nmat,
                                         .material_names = names},
                        &r->s),
          "cd_sim_create");
  cd_sim *s = r->s;
  /* every rank built (or read) the whole set: cd_sim_init keeps what each rank's cells own */
  if (ctx->size > 1) cd_sim_set_mpi(s, &p->mpi);
  for (int a = 0; a < p->nmat; a++)
    for (int b = a; b < p->nmat; b++) {
      cd_pair_table *t = ms_calloc(1, sizeof *t);
      if (cd_pair_table_build(t, p->mat[a]->eos, p->mat[b]->eos, p->lattice, p->r0, p->thickness,
                              p->rc_pair[a][b] * p->r0, p->r_min * p->r0, p->attraction[a][b],
                              p->table_intervals) != MS_OK) {
        ms_log(ctx, MS_LOG_ERROR,
               "cluster_dynamics: cannot tabulate the pair potential of '%s'-'%s' "
               "on [r_min, R_c] (cold curve undefined there?)",
               p->mat[a]->name, p->mat[b]->name);
        free(t);
        return MS_ERR_INPUT;
      }
      cd_sim_set_pair(s, a, b, t);
    }
  if (p->piston.n) cd_sim_set_piston(s, &p->piston, r->dir);
  return MS_OK;
}

/* The initial state: the checkpoint's, or the lattice's (relaxed if `relax:`). */
static ms_status sim_init(cd_run *r) {
  ms_ctx *ctx = r->ctx;
  const cd_problem *p = r->p;
  r->nsteps = (long)ceil(p->t_end / r->cfg.dt - 1e-9);
  const long nsteps = r->nsteps;
  ms_status st;
  if (r->rs) {
    dk_errors e;
    dk_errors_init(&e);
    st = cd_restart_step(r->rs) > nsteps ? MS_ERR_INPUT : cd_sim_init_restart(r->s, r->rs, &e);
    if (cd_restart_step(r->rs) > nsteps)
      dk_error_at(&e, ctx->restart, 0, 0,
                  "the checkpoint is at step %ld, beyond this deck's "
                  "end (step %ld)",
                  cd_restart_step(r->rs), nsteps);
    if (st != MS_OK && ctx->rank == 0) dk_errors_print(&e, stderr);
    dk_errors_free(&e);
  } else {
    st = cd_sim_init(r->s);
    if (st == MS_OK && p->relax_on)
      st = relax_sample(ctx, p, r->s, r->c0max, r->nglobal, r->region_of);
  }
  if (st != MS_OK && cd_sim_error(r->s)[0]) /* the guard's or the list build's finding */
    ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: %s", cd_sim_error(r->s));
  if (st != MS_OK)
    ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: set-up failed (%s)", ms_status_str(st));
  return st;
}

static void log_setup(const cd_run *r) {
  ms_ctx *ctx = r->ctx;
  const cd_problem *p = r->p;
  ms_log(ctx, MS_LOG_INFO,
         "cluster_dynamics: %zu particles, %d material(s), dt = %g %s, R_c = %g r0, "
         "%s cutoff, damping Gamma = %g 1/%s, integrator %s, %zu bytes/particle",
         r->nglobal, p->nmat, ms_out_time(r->cfg.dt), ms_out_time_label(), p->rc,
         cd_mode_names[p->mode], r->cfg.damping_gamma / ms_out_time(1.0), ms_out_time_label(),
         cd_integrator_names[p->integrator],
         cd_sim_bytes(r->s) / (r->ps->nlocal ? r->ps->nlocal : 1));
  const cd_mpi_stats *ms = cd_sim_mpi_stats(r->s);
  if (ms) {
    const cd_partition_stats *pst = &ms->partition;
    char alt[80] = ""; /* auto: the map it did not take */
    if (!isnan(pst->rejected_load))
      snprintf(alt, sizeof alt, " (auto; %s: load %.3f)",
               cd_partition_names[pst->method == CD_PART_SLAB ? CD_PART_METIS : CD_PART_SLAB],
               pst->rejected_load);
    ms_log(ctx, MS_LOG_INFO,
           "cluster_dynamics on %d ranks: %dx%dx%d coarse cells, %s partition%s: "
           "edge cut %ld, imbalance %.3f, load %.3f; owned max %zu, ghosts %zu in all; "
           "rebalance above %g (checked every %d list builds)",
           ms->ranks, ms->ncell[0], ms->ncell[1], ms->ncell[2], cd_partition_names[pst->method],
           alt, pst->edge_cut, ms->imbalance, pst->load, ms->max_owned, ms->total_ghosts,
           p->mpi.rebalance_threshold, p->mpi.rebalance_interval);
  }
}

/* The time steps from the start (or the checkpoint's step) to t_end, with the outputs,
 * checkpoints and snapshots; the state an instability left behind. */
static ms_status run_steps(cd_run *r) {
  ms_ctx *ctx = r->ctx;
  const cd_problem *p = r->p;
  cd_sim *s = r->s;
  const long nsteps = r->nsteps;
  const cd_mpi_stats *ms = cd_sim_mpi_stats(s);
  long rebalances_logged = 0;
  cd_outputs_setup(p, s, &r->out);
  const long snap_every = p->snapshots > 0 ? (nsteps + p->snapshots - 1) / p->snapshots : 0;
  const long ckpt_every =
      p->checkpoint_every > 0
          ? p->checkpoint_every
          : (p->checkpoint_time > 0 ? lround(fmax(1.0, p->checkpoint_time / r->cfg.dt)) : 0);
  long step0 = 0;
  ms_status st = MS_OK;
  if (r->rs) {
    step0 = cd_restart_step(r->rs);
    st = cd_outputs_restore(ctx, r->rh, &r->out);
    cd_restart_destroy(&r->rs);
    ms_h5_close_read(r->rh);
    r->rh = NULL;
    if (st == MS_OK)
      ms_log(ctx, MS_LOG_INFO, "cluster_dynamics: restarted from %s at step %ld (t = %.9g %s)",
             ctx->restart, step0, ms_out_time(s->t), ms_out_time_label());
  }
  ms_progress prog;
  bool stopping = false; /* interrupted: stop at the next checkpoint */
  ms_progress_start(&prog, ctx, "cluster_dynamics", s->t, nsteps * r->cfg.dt);
  for (long k = step0; k <= nsteps && st == MS_OK; k++) {
    if (k > step0) st = cd_sim_step(s);
    if (st != MS_OK) break;
    if (ms && ms->rebalances > rebalances_logged) {
      rebalances_logged = ms->rebalances;
      ms_log(ctx, MS_LOG_INFO,
             "cluster_dynamics: rebalance at step %ld: imbalance %.3f -> %.3f, "
             "edge cut %ld, %s map",
             ms->rebalance_step, ms->rebalance_before, ms->rebalance_after, ms->partition.edge_cut,
             cd_partition_names[ms->partition.method]);
    }
    if (k > step0 && ckpt_every > 0 && k % ckpt_every == 0) {
      st = cd_outputs_checkpoint(ctx, p, s, &r->out);
      if (st != MS_OK) break;
      if (stopping) { /* SIGINT/SIGTERM: `mscale run --continue` goes on from here */
        ms_log(ctx, MS_LOG_WARN, "cluster_dynamics: interrupted; checkpoint at step %ld written",
               k);
        st = MS_INTERRUPTED;
        break;
      }
    }
    if (!stopping && k < nsteps && ms_interrupt_agreed(ctx)) { /* collective, every step */
      stopping = true;
      if (ckpt_every == 0) {
        ms_log(ctx, MS_LOG_WARN, "cluster_dynamics: interrupted at step %ld (no checkpoints)", k);
        cd_outputs_write(ctx, p, s, &r->out);
        st = MS_INTERRUPTED;
        break;
      }
      ms_log(ctx, MS_LOG_WARN,
             "cluster_dynamics: interrupt: stopping at the next checkpoint "
             "(step %ld)",
             (k / ckpt_every + 1) * ckpt_every);
    }
    if (k % p->out_every == 0 || k == nsteps) {
      cd_outputs_write(ctx, p, s, &r->out);
      ms_progress_update(&prog, s->t, k);
      if (ms && k % (10L * p->out_every) == 0)
        ms_log(ctx, MS_LOG_INFO,
               "cluster_dynamics: step %ld: owned max %zu (imbalance %.3f), "
               "ghosts %zu in all",
               k, ms->max_owned, ms->imbalance, ms->total_ghosts);
    }
    if (snap_every && (k % snap_every == 0 || k == nsteps)) {
      char name[64];
      ptl_snapshot_name(name, sizeof name, (k + snap_every - 1) / snap_every); /* ⌈k/every⌉ */
      char *sp = ms_out_path(ctx, name);
      if (cd_write_snapshot(s, sp) != MS_OK) st = MS_ERR_IO;
      free(sp);
    }
  }
  ms_progress_finish(&prog, s->t, s->step);
  if (st == MS_ERR_UNSTABLE) { /* the guard's finding, the state it found, the series so far */
    if (cd_sim_error(s)[0])    /* on the rank that found it */
      ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: %s", cd_sim_error(s));
    char *sp = ms_out_path(ctx, PTL_SNAPSHOT_UNSTABLE);
    if (cd_write_snapshot(s, sp) == MS_OK)
      ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: final state written to " PTL_SNAPSHOT_UNSTABLE);
    free(sp);
  }
  return st;
}

/* The log's summary of the run (collective: every rank calls it). */
static void log_summary(const cd_run *r) {
  ms_ctx *ctx = r->ctx;
  const cd_sim *s = r->s;
  const bool dist = ctx->size > 1;
  cd_outputs_front_fit(ctx, &r->out);
  ms_log(ctx, MS_LOG_INFO,
         "cluster_dynamics: %ld steps, %ld list builds, %ld broken bonds, wall "
         "force %.2f s, lists %.2f s",
         s->step, cd_sim_rebuilds(s), dist ? par_sum_long(s->n_broken_bonds) : s->n_broken_bonds,
         s->wall_time_force, s->wall_time_neigh);
  const cd_mpi_stats *ms = cd_sim_mpi_stats(s);
  if (ms) {
    const double xmax = par_max_double(ms->exchange_s), xmin = par_min_double(ms->exchange_s);
    const double recv = par_sum_double(ms->exchanged_doubles);
    ms_log(ctx, MS_LOG_INFO,
           "cluster_dynamics on %d ranks: %ld partitions (%ld rebalances), "
           "imbalance %.3f at the end; migration and ghost exchange %.3f-%.3f s per rank; %.4g "
           "doubles received in all; %ld bonds lost at migrations",
           ms->ranks, ms->partitions, ms->rebalances, ms->imbalance, xmin, xmax, recv,
           par_sum_long(ms->lost_bonds));
  }
}

static void run_cleanup(cd_run *r) {
  cd_outputs_free(&r->out);
  free(r->region_of);
  if (!r->s) ptl_state_destroy(&r->ps); /* else the simulation owns them */
  cd_sim_destroy(&r->s);
  cd_restart_destroy(&r->rs);
  ms_h5_close_read(r->rh);
  r->rh = NULL;
}

ms_status cd_problem_run(ms_ctx *ctx, cd_problem *p) {
  cd_run r = {.ctx = ctx, .p = p};
  ms_status st = run_particles(&r);
  if (st == MS_OK) st = sim_create(&r);
  if (st == MS_OK) st = sim_init(&r);
  if (st == MS_OK) {
    log_setup(&r);
    r.out.with_vfs = p->piston.n > 0; /* the free-surface layer is tagged in piston runs only */
    st = cd_outputs_open(ctx, &r.out, r.rs != NULL);
  }
  if (st == MS_OK) {
    st = run_steps(&r);
    log_summary(&r);
    st = cd_outputs_close(ctx, r.s, &r.out, st);
  }
  run_cleanup(&r);
  return st;
}
