/* SPDX-License-Identifier: MIT */
/* dm_problem_finite.c — the run of the discrete-model problem with response: eos: the
 * finite-deformation model (dm_finite.c) with its profiles, snapshots, energy and free-surface
 * histories, checkpoints (dm_fin_restart.c) and the report of a failed step with the last good
 * state (dm_fin_output.c).
 *
 * MPI ranks: the model is replicated (dm_fin_run.h): every rank builds and steps every particle
 * with the same arithmetic, so every rank holds the serial run's state bit for bit, and rank 0
 * writes the files. It costs the serial run's time and memory on every rank (no speed-up; the
 * run can sit inside an MPI job, e.g. beside ranks' other work, and restart on any rank count;
 * docs/mpi.md). */
#include "dm_fin_run.h"

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

/* An initial displacement (the paper's rod and contact profiles) as an elastic state reached
 * from rest: the deviator s = 2G dev ε and the strain energy (½K (tr ε)² + G ε′:ε′)V added to
 * m e, with ε = sym(F − I) the small strain of the fitted F and K = ρ0c0², G of the material
 * (G = 0 without strength). The hypoelastic deviator starts at 0 otherwise, and E0 would miss
 * the strain energy. Second order in ε off the finite-strain state (docs/particles-dm.md). */
static ms_status initial_strain(dmf_run *r) {
  dm_fin *f = r->f;
  const dm_state *s = &r->s;
  for (size_t i = 0; i < s->n; ++i) {
    const dm_fin_material *mt = &r->mat[r->imat[i]];
    const double *F = &f->F[9 * i];
    double eps[9];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) eps[3 * a + b] = 0.5 * (F[3 * a + b] + F[3 * b + a]);
    eps[0] -= 1.0, eps[4] -= 1.0, eps[8] -= 1.0;
    const double tr = eps[0] + eps[4] + eps[8];
    const double rho0 = eos_rho0(mt->eos), c0 = eos_sound_speed(mt->eos, rho0, eos_e0(mt->eos));
    const double G = mt->yield != DM_YIELD_NONE ? mt->G : 0.0;
    double dd = 0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const double d = eps[3 * a + b] - (a == b ? tr / 3.0 : 0.0);
        f->s[9 * i + 3 * a + b] = 2.0 * G * d;
        dd += d * d;
      }
    f->e[i] += (0.5 * rho0 * c0 * c0 * tr * tr + G * dd) * s->vol[i] / s->mass[i];
  }
  return dm_fin_refresh(f);
}

/* The particles, the model and the run's records (sized once, before the time loop). */
static ms_status setup(dmf_run *r) {
  static char no_outdir[1] = "";
  ms_ctx *ctx = r->ctx;
  dm_problem *p = r->p;
  r->octx = *ctx;
  if (ctx->rank != 0) r->octx.outdir = no_outdir;
  dm_state *s = &r->s;
  dmp_build_particles(p, s);
  r->nreal = (size_t)(p->ncell[0] * p->ncell[1] * p->ncell[2]);
  dmp_set_initial(p, s, r->nreal);
  r->flyer = set_velocities(p, s, r->nreal);
  dm_options opt = {.horizon = p->horizon * p->h, .cond_max = p->cond_max, .hourglass = 0.0};
  for (int a = 0; a < p->dim; ++a)
    if (p->face[2 * a] == FACE_PERIODIC) opt.box[a] = p->hi[a] - p->lo[a];
  ms_status st = dm_model_create(&(dm_model_params){.state = s, .opt = opt, .ctx = ctx}, &r->m);
  if (st != MS_OK) return st;
  r->mat = ms_calloc(p->nlayers, sizeof *r->mat);
  for (size_t l = 0; l < p->nlayers; ++l)
    r->mat[l] = (dm_fin_material){.eos = p->layers[l].eos,
                                  .yield = p->layers[l].yield,
                                  .G = p->layers[l].G,
                                  .Y0 = p->layers[l].Y0,
                                  .sg = &p->layers[l].sg,
                                  .frac = p->layers[l].frac};
  r->imat = ms_calloc(s->n, 1);
  for (size_t i = 0; i < s->n; ++i)
    r->imat[i] = (uint8_t)(dmp_layer_at(p, s->X[3 * i]) - p->layers);
  dm_fin_params par = {.cq = p->cq,
                       .cl = p->cl,
                       .courant = p->courant,
                       .hourglass = p->hourglass,
                       .ell = p->h,
                       .contact = p->contact};
  st = dm_fin_create(&(dm_fin_setup){.m = r->m, .mat = r->mat, .imat = r->imat, .par = par}, &r->f);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR, "discrete model (response eos): the initial state is not valid");
    return st;
  }
  r->bins = ms_calloc((size_t)p->ncell[0] * 11, sizeof(double));
  r->sigma_u = ms_calloc(s->n ? s->n : 1, sizeof(double));
  r->nemax = 4096;
  r->eh = ms_calloc(r->nemax * 6, sizeof(double));
  r->prof_done = ms_calloc(p->nprofile_times + 1, 1);
  r->snap_done = ms_calloc(p->nsnapshot_times + 1, 1);
  /* free-surface history of the flyer problem (dm_fs_history: thinned when full) */
  if (r->flyer) dm_fs_history_init(&r->fs, 8192);
  r->pr = ms_calloc(p->nprobes + 1, sizeof *r->pr);
  dmp_find_probes(p, s, r->nreal, r->pr);
  r->pcols = 1 + p->nprobes, r->nrec_max = 8192, r->pstride = 1;
  r->hist = ms_calloc(r->nrec_max * r->pcols, sizeof(double));
  dmp_backup_alloc(&r->bk, s->n, DMP_KEEP_EHG | DMP_KEEP_Q | DMP_KEEP_SIGMA_U);
  if (p->profile == PROF_ROD_TRIANGLE || p->profile == PROF_ROD_SINE ||
      p->profile == PROF_CONTACT) {
    st = initial_strain(r);
    if (st != MS_OK) {
      ms_log(ctx, MS_LOG_ERROR, "discrete model (response eos): the initial strain is not valid");
      return st;
    }
  }
  double K, U, H;
  dm_fin_energies(r->f, &K, &U, &H);
  r->E0 = K + U + H;
  return MS_OK;
}

/* The profiles and snapshots due at time t (all that remain at the last step). */
static void write_fields(dmf_run *r, double t, int last) {
  const dm_problem *p = r->p;
  for (size_t q = 0; q < p->nprofile_times; ++q)
    if (!r->prof_done[q] && (t >= p->profile_times[q] * (1 - 1e-12) || last)) {
      dmp_write_fin_profile(&r->octx, p, r->f, r->nreal, t, (int)q, r->bins);
      r->prof_done[q] = 1;
    }
  for (size_t q = 0; q < p->nsnapshot_times; ++q)
    if (!r->snap_done[q] && (t >= p->snapshot_times[q] * (1 - 1e-12) || last)) {
      char name[64];
      ptl_snapshot_name(name, sizeof name, (long)q);
      const dmf_fields fl = dmf_live_fields(r);
      dmf_write_snapshot(r, &fl, t, r->f->step, name);
      r->snap_done[q] = 1;
    }
}

/* The probes' w_x every probe_every steps; when the table is full every other row is dropped
 * and the interval doubled, so any run length fits (the rows stay evenly spaced in steps). */
static void record_probes(dmf_run *r, long step) {
  const dm_problem *p = r->p;
  if (!p->nprobes || step % p->probe_every != 0) return;
  const long k = step / p->probe_every;
  if (k % r->pstride != 0) return;
  if (r->nrec == r->nrec_max) {
    r->nrec = dm_rows_thin(r->hist, r->nrec, r->pcols), r->pstride *= 2;
    if (k % r->pstride != 0) return;
  }
  double *row = &r->hist[r->nrec++ * r->pcols];
  row[0] = r->t;
  for (size_t q = 0; q < p->nprobes; ++q) row[1 + q] = r->s.w[3 * r->pr[q].particle];
}

/* The first particle whose velocity, energy or bond-penalty energy is not finite (a total
 * energy that is not finite has one). */
static size_t first_nonfinite(const dmf_run *r, const char **what, double *val) {
  const dm_fin *f = r->f;
  for (size_t i = 0; i < r->s.n; ++i) {
    const double *u = &r->s.u[3 * i];
    const double v[5] = {u[0], u[1], u[2], f->e[i], f->ehg[i]};
    static const char *const names[5] = {"velocity u_x", "velocity u_y", "velocity u_z",
                                         "specific internal energy e", "bond-penalty energy"};
    for (int k = 0; k < 5; ++k)
      if (!isfinite(v[k])) {
        *what = names[k], *val = v[k];
        return i;
      }
  }
  *what = "piston work", *val = f->work;
  return 0;
}

/* Whether write_fields has a profile or a snapshot to write at time t. */
static int fields_due(const dmf_run *r, double t, int last) {
  const dm_problem *p = r->p;
  for (size_t q = 0; q < p->nprofile_times; ++q)
    if (!r->prof_done[q] && (t >= p->profile_times[q] * (1 - 1e-12) || last)) return 1;
  for (size_t q = 0; q < p->nsnapshot_times; ++q)
    if (!r->snap_done[q] && (t >= p->snapshot_times[q] * (1 - 1e-12) || last)) return 1;
  return 0;
}

/* The pending half kick's energies (dm_fin_flush), timed with the steps. */
static ms_status flush(dmf_run *r) {
  const double w0 = ms_wall_time(), c0 = dmp_cpu_time();
  const ms_status st = dm_fin_flush(r->f);
  r->wall += ms_wall_time() - w0, r->cpu += dmp_cpu_time() - c0;
  return st;
}

/* A step (or the flush of its energies) failed: the report and the last good state's snapshot
 * (dm_fin_run.h's backup: the start of the failed step). */
static ms_status failed(dmf_run *r, ms_status st) {
  /* the backup's e and e_hg were completed by the failed step's stress pass (keep_e): a
   * non-finite one there (the last step's closing kick) leaves no good state to write */
  for (size_t i = 0; i < r->s.n && r->bk.valid; ++i)
    if (!isfinite(r->bk.e[i]) || !isfinite(r->bk.ehg[i])) {
      r->bk.valid = false;
      ms_log(r->ctx, MS_LOG_WARN,
             "discrete model (response eos): particle %zu: the energy of the last step's closing "
             "half kick is not finite: no snapshot of the last good state",
             i);
    }
  dmf_report_unstable(r, r->f->bad, r->f->bad_what, r->f->bad_value, r->t);
  r->t = r->bk.t;
  return st;
}

/* The time loop from the run's state to the end; MS_ERR_UNSTABLE with the report and the last
 * good state's snapshot when a step fails. The steps leave their closing half kick's energies
 * pending (dm_fin_advance: the next step's stress pass adds them, saving a pass over the bonds);
 * they are added (dm_fin_flush) at the states that are recorded — every energy_every steps, the
 * last, and those a checkpoint, a profile, a snapshot or a stop writes — and only there are the
 * energies summed, the balance taken and checked finite. The last good state's e and e_hg are
 * completed by the next stress pass (dm_fin keep_e, keep_ehg). */
static ms_status run_steps(dmf_run *r) {
  const dm_problem *p = r->p;
  dm_fin *f = r->f;
  const double t_end = p->steps > 0 ? INFINITY : p->t_end;
  const long every = p->energy_every, nyz = p->ncell[1] * p->ncell[2];
  ms_status st = MS_OK;
  bool stopping = false; /* SIGINT/SIGTERM: stop at the next checkpoint (docs/reliability.md) */
  f->keep_e = r->bk.e, f->keep_ehg = r->bk.ehg;
  for (long step = r->step0;; ++step) {
    r->steps = f->step;
    const int last = (p->steps > 0 && step >= p->steps) || r->t >= t_end * (1 - 1e-12);
    const int ckpt =
        p->checkpoint_every > 0 && step > r->step0 && step % p->checkpoint_every == 0 && !last;
    const int sample = step % every == 0 || last || ckpt || stopping || fields_due(r, r->t, last);
    double K = 0, U = 0, H = 0;
    if (sample) {
      st = flush(r);
      if (st != MS_OK) return failed(r, st);
      dm_fin_energies(f, &K, &U, &H);
      if (!isfinite(K + U + H - f->work)) {
        const char *what;
        double val;
        const size_t i = first_nonfinite(r, &what, &val);
        dmf_report_unstable(r, i, what, val, r->t);
        r->t = r->bk.t;
        return MS_ERR_UNSTABLE;
      }
      r->K = K, r->U = U, r->H = H;
    }
    /* the checkpoint of the state at the top of this step, before anything of it is recorded */
    if (ckpt) {
      st = dmf_checkpoint_write(r);
      if (st != MS_OK) return st;
      if (stopping) { /* `mscale run --continue` goes on from here */
        ms_log(r->ctx, MS_LOG_WARN,
               "discrete model (response eos): interrupted; checkpoint at step %ld written", step);
        return MS_INTERRUPTED;
      }
    }
    if (!stopping && !last && ms_interrupt_agreed(r->ctx)) { /* collective on ranks */
      stopping = true;
      if (p->checkpoint_every <= 0) {
        ms_log(r->ctx, MS_LOG_WARN,
               "discrete model (response eos): interrupted at step %ld (no checkpoints)", step);
        return flush(r) != MS_OK ? failed(r, MS_ERR_UNSTABLE) : MS_INTERRUPTED;
      }
      ms_log(r->ctx, MS_LOG_WARN,
             "discrete model (response eos): interrupt: stopping at the next checkpoint (step %ld)",
             (step / p->checkpoint_every + 1) * p->checkpoint_every);
    }
    if (sample) {
      const double bal = K + U + H + dm_fin_broken_energy(f) + dm_fin_contact_energy(f) - f->work -
                         r->E0; /* broken, contact: 0 without fracture */
      r->dEmax = fmax(r->dEmax, fabs(bal));
      if ((step % every == 0 || last) && r->ne < r->nemax) {
        const double row[6] = {r->t, K, U, H, f->work, bal};
        memcpy(&r->eh[6 * r->ne++], row, sizeof row);
      }
    }
    write_fields(r, r->t, last);
    if (r->flyer) dm_fs_history_record(&r->fs, step, r->t, &r->s, p->ncell[0], nyz);
    record_probes(r, step);
    if (last) break;
    dmp_backup_take(&r->bk, f, r->t);
    if (r->t + f->dt_next > t_end) f->dt_next = t_end - r->t;
    const double dt = f->dt_next, w0 = ms_wall_time(), c0 = dmp_cpu_time();
    st = dm_fin_advance(f);
    r->wall += ms_wall_time() - w0, r->cpu += dmp_cpu_time() - c0;
    r->t += dt;
    if (st != MS_OK) return failed(r, st);
  }
  return MS_OK;
}

/* After a run that completed: the comparisons with the exact solutions of the paper's
 * problems (dm_analysis.c), as the linear model's run makes them. */
static void analyses(dmf_run *r) {
  dm_problem *p = r->p;
  const dm_run_summary *sum = &p->sum;
  if ((p->profile == PROF_ROD_TRIANGLE || p->profile == PROF_ROD_SINE) && p->nprobes) {
    double *h1 = ms_calloc(2 * r->nrec + 1, sizeof(double));
    for (size_t k = 0; k < r->nrec; ++k)
      h1[2 * k] = r->hist[k * r->pcols], h1[2 * k + 1] = r->hist[k * r->pcols + 1];
    dmp_rod_analysis(p, h1, r->nrec, r->pr[0].x);
    free(h1);
    ms_log(r->ctx, MS_LOG_INFO,
           "rod: probe x = %.6g, last 10 L/c: amplitude error %+.3f %% (least-squares fit), "
           "lag %+.5f L/c, peak error %+.3f %%, rms error %.3f %% of the amplitude",
           r->pr[0].x, 100 * sum->amp_err, sum->phase_err, 100 * sum->peak_err, 100 * sum->rms_err);
  }
  if (p->profile == PROF_CONTACT && p->nlayers >= 2) {
    dmp_contact_analysis_sigma(p, r->s.X, r->f->sig, r->nreal, sum->t_end);
    ms_log(r->ctx, MS_LOG_INFO,
           "contact: sigma_xx at t = %.6g vs exact: L1 %.4f, L2 %.4f, max %.4f (of max|sigma|)",
           sum->t_end, sum->err_l1, sum->err_l2, sum->err_max);
  }
}

/* The summary, the log line and the histories (of the good states only). */
static void report(dmf_run *r) {
  dm_run_summary *sum = &r->p->sum;
  const dm_fin *f = r->f;
  const double K = r->K, U = r->U, H = r->H; /* of the last good state */
  const long steps = r->steps;
  if (f->failed)
    ms_log(r->ctx, MS_LOG_INFO,
           "discrete model (response eos): fracture: %zu particles failed, broken energy %.6g kJ, "
           "contact energy %.6g kJ (potential %.6g) (in the balance: K + U + E_hg + broken + "
           "contact - W - E0)",
           dm_fin_failed_count(f), dm_fin_broken_energy(f), dm_fin_contact_energy(f),
           dm_fin_contact_potential(f));
  sum->steps = steps, sum->t_end = r->t, sum->wall_s = r->wall, sum->cpu_s = r->cpu;
  sum->particle_steps_per_s =
      r->wall > 0 ? (double)r->nreal * (double)(steps - r->step0) / r->wall : 0;
  sum->energy_err_max =
      f->work != 0 ? r->dEmax / fabs(f->work) : r->dEmax / fmax(fabs(r->E0), 1e-300);
  /* no driven particles (a flyer): both relative to the initial energy E0 (kinetic) instead */
  sum->hourglass_last = f->work != 0 ? H / fabs(f->work) : H / fmax(fabs(r->E0), 1e-300);
  sum->kinetic_end = K, sum->potential_end = U;
  sum->restart_step = r->step0;
  ms_log(r->ctx, MS_LOG_INFO,
         "discrete model (response eos): %ld steps to t = %.6g in %.3f s (%.4g particle-steps/s); "
         "energy balance max |K + U + E_hg (+ broken + contact) - W - E0| = %.3g of %s %.6g kJ; "
         "bond-penalty energy / that = %.3g",
         steps, r->t, r->wall, sum->particle_steps_per_s, sum->energy_err_max,
         f->work != 0 ? "the piston work" : "the initial energy E0", f->work != 0 ? f->work : r->E0,
         sum->hourglass_last);
  const char *nm[] = {"t", "kinetic", "internal", "bond_penalty", "piston_work", "balance"};
  const char *un[] = {"10 us", "kJ", "kJ", "kJ", "kJ", "kJ"};
  dmp_write_series(&r->octx, "dm_fin_energy.csv",
                   f->failed ? "energy history: balance = kinetic + internal + bond_penalty + "
                               "broken + contact - piston_work - E0 (broken, contact: fracture, "
                               "in run.log)"
                             : "energy history: balance = kinetic + internal + bond_penalty - "
                               "piston_work - E0",
                   6, nm, un, r->eh, r->ne);
  if (r->p->nprobes) dmp_write_probes(&r->octx, r->p, r->pr, r->hist, r->nrec);
  if (r->flyer) {
    const char *fnm[] = {"t", "u_free_surface"}, *fun[] = {"10 us", "km/s"};
    dmp_write_series(&r->octx, "dm_fin_free_surface.csv",
                     "free-surface velocity: mean x velocity of the last x layer of particles", 2,
                     fnm, fun, r->fs.rows, r->fs.n);
  }
}

static void run_free(dmf_run *r) {
  dmp_backup_free(&r->bk);
  free(r->fs.rows), free(r->bins), free(r->sigma_u), free(r->eh), free(r->pr), free(r->hist);
  free(r->prof_done), free(r->snap_done), free(r->mat), free(r->imat);
  dm_fin_destroy(&r->f);
  dm_model_destroy(&r->m);
  dm_state_free(&r->s);
}

ms_status dmp_run_finite(ms_ctx *ctx, dm_problem *p) {
  dmf_run r = {.ctx = ctx, .p = p};
  ms_status st = setup(&r);
  if (st == MS_OK && ctx->restart) st = dmf_restart(&r);
  if (st == MS_OK) {
    dm_run_summary *sum = &p->sum;
    const size_t lim = r.f->dt_particle;
    sum->particles = r.s.n, sum->real_particles = r.nreal, sum->bonds = r.m->nbonds;
    sum->ranks = ctx->size;
    ms_log(ctx, MS_LOG_INFO,
           "discrete model (response eos): %zu particles (%zu real), %zu bonds, dim %d, "
           "viscosity C_q %.3g C_l %.3g, bond penalty c_s %.3g, courant %.3g, first dt %.6g "
           "(limited by particle %zu at X = %g)%s",
           r.s.n, r.nreal, r.m->nbonds, p->dim, p->cq, p->cl, p->hourglass, p->courant,
           r.f->dt_next, lim, r.s.X[3 * lim], p->has_piston ? ", piston" : "");
    if (ctx->size > 1)
      ms_log(ctx, MS_LOG_INFO,
             "discrete model (response eos) on %d ranks: replicated (every rank steps all %zu "
             "particles; rank 0 writes)",
             ctx->size, r.s.n);
    st = run_steps(&r);
    report(&r);
    if (st == MS_OK) analyses(&r);
  }
  run_free(&r);
  return st;
}
