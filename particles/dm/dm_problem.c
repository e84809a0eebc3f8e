/* SPDX-License-Identifier: MIT */
/* dm_problem.c — the deck problem type `discrete_model` (docs/input-dm.md): builds a lattice of
 * particles in a box with per-face boundaries, material layers, initial data of [Sofronov] §5
 * or random velocities (benchmark), an optional spherical displacement source, integrates with
 * a symplectic RKN scheme and compares with the exact solutions where one exists. The deck is
 * read by dm_deck.c; the files are written by dm_output.c, the comparisons made by
 * dm_analysis.c (dm_problem_impl.h).
 */
#include "dm_problem_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

const dm_run_summary *dm_problem_summary(const dm_problem *p) { return &p->sum; }

size_t dm_problem_final_state(const dm_problem *p, const double **w, const double **u) {
  if (w) *w = p->final_w;
  if (u) *u = p->final_u;
  return p->final_n;
}

static void dm_problem_free(dm_problem *p) {
  if (!p) return;
  free(p->layers);
  free(p->probes);
  free(p->profile_times);
  free(p->snapshot_times);
  free(p->final_w);
  free(p->final_u);
  free(p);
}

void dm_problem_destroy(dm_problem **p) {
  if (!p) return;
  dm_problem_free(*p);
  *p = NULL;
}

/* ------------------------------------------------------------------------------------------ */
/* Set-up                                                                                      */

const dm_layer *dmp_layer_at(const dm_problem *p, double x) {
  for (size_t i = 0; i + 1 < p->nlayers; ++i)
    if (x < p->layers[i].x_max) return &p->layers[i];
  return &p->layers[p->nlayers - 1];
}

/* Thickness (cells) of the particle layer added outside a face. */
static long face_layers(const dm_problem *p, int f) {
  long hz = (long)ceil(p->horizon - 1e-9);
  switch (p->face[f]) {
  case FACE_WALL:
  case FACE_SYMMETRY:
    return 2 * hz; /* ghosts next to the wall need complete families */
  case FACE_FIXED:
    return hz;
  default:
    return 0;
  }
}

/* Builds the particles: real ones first in lattice order (x fastest), then fixed layers and
 * mirror ghosts. */
void dmp_build_particles(dm_problem *p, dm_state *s) {
  long ext_lo[3] = {0, 0, 0}, ext_hi[3] = {0, 0, 0};
  size_t nreal = 1, ntot = 1;
  for (int a = 0; a < 3; ++a) {
    if (a < p->dim) ext_lo[a] = face_layers(p, 2 * a), ext_hi[a] = face_layers(p, 2 * a + 1);
    nreal *= (size_t)p->ncell[a];
    ntot *= (size_t)(p->ncell[a] + ext_lo[a] + ext_hi[a]);
  }
  /* Arrays sized for the whole extended lattice; outside particles are kept only when no
   * face they lie beyond is free. */
  dm_state_alloc(s, ntot, p->dim);
  size_t next = nreal;
  for (long k = -ext_lo[2]; k < p->ncell[2] + ext_hi[2]; ++k)
    for (long j = -ext_lo[1]; j < p->ncell[1] + ext_hi[1]; ++j)
      for (long i = -ext_lo[0]; i < p->ncell[0] + ext_hi[0]; ++i) {
        long idx[3] = {i, j, k}, mir[3] = {i, j, k};
        int outside = 0, skip = 0, fixed = 0;
        int8_t sign[3] = {1, 1, 1};
        for (int a = 0; a < p->dim; ++a) {
          int f = -1;
          if (idx[a] < 0) f = 2 * a, mir[a] = -1 - idx[a];
          if (idx[a] >= p->ncell[a]) f = 2 * a + 1, mir[a] = 2 * p->ncell[a] - 1 - idx[a];
          if (f < 0) continue;
          outside = 1;
          if (p->face[f] == FACE_FIXED) fixed = 1;
          else if (p->face[f] == FACE_WALL)
            for (int c = 0; c < 3; ++c) sign[c] = (int8_t)-sign[c];
          else if (p->face[f] == FACE_SYMMETRY) sign[a] = (int8_t)-sign[a];
          else skip = 1;
        }
        if (skip) continue;
        size_t id;
        if (!outside) {
          id = (size_t)i + (size_t)p->ncell[0] * ((size_t)j + (size_t)p->ncell[1] * (size_t)k);
        } else {
          id = next++;
          if (fixed) {
            s->bc[id] = DM_FIXED;
          } else {
            s->bc[id] = DM_MIRROR;
            s->partner[id] = (uint32_t)((size_t)mir[0] + (size_t)p->ncell[0] *
                                                             ((size_t)mir[1] + (size_t)p->ncell[1] *
                                                                                   (size_t)mir[2]));
            for (int c = 0; c < 3; ++c) s->msign[3 * id + c] = c < p->dim ? sign[c] : 1;
          }
        }
        for (int a = 0; a < p->dim; ++a) s->X[3 * id + a] = p->lo[a] + (idx[a] + 0.5) * p->h;
        /* material: by x of the particle (of its mirror partner for ghosts) */
        double xm = p->lo[0] + (mir[0] + 0.5) * p->h;
        const dm_layer *ly = dmp_layer_at(p, outside && !fixed ? xm : s->X[3 * id]);
        s->vol[id] = pow(p->h, p->dim);
        s->mass[id] = ly->rho * s->vol[id];
        s->K[id] = ly->K;
        s->G[id] = ly->G;
      }
  s->n = next; /* arrays are longer than needed when faces are free: harmless */
}

double dmp_wave_speed(const dm_problem *p) {
  const dm_layer *l = &p->layers[0];
  return sqrt((l->K + 4.0 * l->G / 3.0) / l->rho);
}

void dmp_set_initial(dm_problem *p, dm_state *s, size_t nreal) {
  const double L = p->length, eps = p->amplitude;
  uint64_t rng_k = 0; /* the next output of the generator started from p->seed */
  for (size_t i = 0; i < nreal; ++i) {
    double x = s->X[3 * i];
    switch (p->profile) {
    case PROF_ROD_TRIANGLE:
      s->w[3 * i] = dm_exact_rod_triangle(x, 0.0, L, eps, 1.0, 0);
      break;
    case PROF_ROD_SINE:
      s->w[3 * i] = eps * L * sin(p->mode * M_PI * x / (2.0 * L));
      break;
    case PROF_CONTACT:
      s->w[3 * i] = x < L ? eps * sin(8.0 * M_PI * x / L) : 0.0;
      break;
    case PROF_RANDOM_VELOCITY: /* as bench/lammps/gen_inputs.py: u = A(2ξ − 1), ξ the (3i+c)-th */
      for (int c = 0; c < 3; ++c)
        s->u[3 * i + c] =
            p->amplitude * (2.0 * ptl_splitmix64_uniform((uint64_t)p->seed, rng_k++) - 1.0);
      break;
    default:
      break;
    }
  }
  if (p->profile == PROF_RANDOM_VELOCITY) {
    double mean[3] = {0, 0, 0};
    for (size_t i = 0; i < nreal; ++i)
      for (int c = 0; c < 3; ++c) mean[c] += s->u[3 * i + c] / (double)nreal;
    for (size_t i = 0; i < nreal; ++i)
      for (int c = 0; c < 3; ++c) s->u[3 * i + c] = c < p->dim ? s->u[3 * i + c] - mean[c] : 0.0;
  }
}

static void sphere_prescribe(void *user, size_t i, const double X[3], double t, double w[3]) {
  (void)i;
  const dm_problem *p = user;
  const double cl = dmp_wave_speed(p);
  double r = sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]), wr, ur;
  dm_exact_sphere(r, t, p->src_r0, p->src_w0, p->src_period, cl, &wr, &ur);
  for (int a = 0; a < 3; ++a) w[a] = X[a] / r * wr;
}

/* Largest eigenvalue of the symmetric tridiagonal matrix (α, β) by Sturm-sequence bisection. */
static double tridiag_max_eig(const double *al, const double *be, int k) {
  double lo = INFINITY, hi = -INFINITY;
  for (int j = 0; j < k; ++j) { /* Gershgorin interval */
    double r = (j > 0 ? fabs(be[j - 1]) : 0) + (j + 1 < k ? fabs(be[j]) : 0);
    lo = fmin(lo, al[j] - r);
    hi = fmax(hi, al[j] + r);
  }
  for (int it = 0; it < 200 && hi - lo > 1e-14 * fabs(hi); ++it) {
    double x = 0.5 * (lo + hi), d = 1.0;
    int above = 0; /* eigenvalues > x = sign changes... count of negative pivots of T − xI */
    for (int j = 0; j < k; ++j) {
      d = al[j] - x - (j > 0 ? be[j - 1] * be[j - 1] / d : 0.0);
      if (d == 0.0) d = 1e-300;
      if (d < 0) ++above;
    }
    if (above == k) /* every eigenvalue below x */
      hi = x;
    else lo = x;
  }
  return hi;
}

/* ω_max of the free particles: Lanczos on M⁻¹K (self-adjoint in the mass inner product) with
 * ghosts following their partners and fixed/prescribed particles held at 0. 40 iterations give
 * the top of the spectrum to well under 1 % on the lattices used here (it converges from
 * below; the run refuses ω_max Δt > 0.99 × the scheme's stability limit).
 * Runs on the distributed model (dot products in global particle order: the same bits on any
 * rank count). */
static double omega_max(dm_dist *d, const dm_state *gs) {
  const int kmax = 40;
  dm_state *s = dm_dist_state(d);
  dm_model *lm = dm_dist_model(d);
  const size_t n = s->n ? s->n : 1; /* local particles (owned + ghosts) */
  double *q = calloc(3 * n, sizeof(double)), *qp = calloc(3 * n, sizeof(double));
  double *z = calloc(3 * n, sizeof(double)), *work = calloc(3 * n, sizeof(double));
  double al[64], be[64];
  { /* the start vector in global particle order, the same for every rank count */
    double *g = calloc(3 * gs->n, sizeof(double));
    uint64_t rng_k = 0; /* the generator started from seed 7 */
    for (size_t i = 0; i < gs->n; ++i)
      for (int c = 0; c < 3; ++c)
        g[3 * i + c] = (gs->bc[i] == DM_FREE && c < gs->dim)
                           ? 2.0 * ptl_splitmix64_uniform(7, rng_k++) - 1.0
                           : 0.0;
    dm_dist_scatter(d, g, 3, q);
    free(g);
  }
  double nrm = sqrt(dm_dist_mass_dot(d, q, q));
  for (size_t i = 0; i < 3 * n; ++i) q[i] /= nrm;
  dm_prescribe_fn saved = lm->prescribe;
  lm->prescribe = NULL;
  int k = 0;
  double beta_prev = 0.0;
  for (; k < kmax && nrm > 0; ++k) {
    memcpy(work, q, 3 * n * sizeof(double));
    dm_dist_constrain(d, 0.0, work, NULL); /* ghosts mirror their partners; ghost values */
    dm_dist_accel(d, 0.0, work, z);        /* z = −M⁻¹K q on free particles, 0 elsewhere */
    for (size_t i = 0; i < 3 * n; ++i) z[i] = -z[i];
    double a = dm_dist_mass_dot(d, q, z);
    al[k] = a;
    for (size_t i = 0; i < 3 * n; ++i) z[i] -= a * q[i] + beta_prev * qp[i];
    double b = sqrt(dm_dist_mass_dot(d, z, z));
    be[k] = b;
    if (!(b > 1e-12 * fabs(a))) {
      ++k;
      break;
    }
    for (size_t i = 0; i < 3 * n; ++i) qp[i] = q[i], q[i] = z[i] / b;
    beta_prev = b;
  }
  lm->prescribe = saved;
  double lam = k > 0 ? tridiag_max_eig(al, be, k) : 0.0;
  free(q);
  free(qp);
  free(z);
  free(work);
  return sqrt(fmax(lam, 0.0));
}

double dmp_cpu_time(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void dmp_summary_reset(dm_run_summary *sum, int finite) {
  *sum = (dm_run_summary){0};
  sum->amp_err = sum->phase_err = sum->rms_err = sum->peak_err = NAN;
  sum->err_l1 = sum->err_l2 = sum->err_max = sum->err_u_l2 = NAN;
  sum->hourglass_first = sum->hourglass_max = NAN;
  if (!finite) sum->energy_err_max = sum->hourglass_last = NAN;
}

/* ------------------------------------------------------------------------------------------ */
/* Run (linear elastic): set-up, the model on the ranks, the time loop, analyses, files        */

typedef struct dm_run {
  ms_ctx *ctx;
  ms_ctx octx; /* the files: rank 0 writes them (every rank holds the gathered global state
                * when it matters); an empty outdir on the others */
  dm_problem *p;
  int par;      /* more than one rank */
  dm_state s;   /* the global particles (every rank) */
  dm_model *m;  /* the global model (its families are released once the local one exists) */
  dm_dist *d;   /* this rank's part */
  dm_state *ls; /* this rank's particles: owned, then ghosts */
  rkn_integrator *ig;
  size_t nreal; /* the lattice inside the domain (the first nreal particles) */
  double dt;
  long nsteps, step0, last_step; /* last_step: the last step begun */
  probe_rec *pr;                 /* the nearest real particle to each probe x */
  double *probe_val;
  double *hist;  /* [nrec][pcols]: t, w_x at every probe (NULL without probes) */
  double *ehist; /* [nerec][5]: t, kinetic, potential, total, hourglass */
  size_t pcols, nrec, nrec_max, nerec, nerec_max;
  long *prof_step, *snap_step; /* the steps of the profile and snapshot times */
  double E0, wall, cpu, dw_scale;
  dm_checkpoint_data ck;
} dm_run;

void dmp_find_probes(const dm_problem *p, const dm_state *s, size_t nreal, probe_rec *pr) {
  for (size_t q = 0; q < p->nprobes; ++q) {
    double best = INFINITY;
    for (size_t i = 0; i < nreal; ++i) {
      const double *X = &s->X[3 * i];
      double dd = fabs(X[0] - p->probes[q]);
      for (int a = 1; a < p->dim; ++a) dd += fabs(X[a] - (p->lo[a] + 0.5 * p->h));
      if (dd < best) best = dd, pr[q].particle = i, pr[q].x = X[0];
    }
  }
}

static double sound_speed_max(const dm_state *s, size_t nreal) {
  double cmax = 0;
  for (size_t i = 0; i < nreal; ++i)
    cmax = fmax(cmax, sqrt((s->K[i] + 4.0 * s->G[i] / 3.0) * s->vol[i] / s->mass[i]));
  return cmax;
}

/* The particles, the global model and the time step. */
static ms_status run_model(dm_run *r) {
  dm_problem *p = r->p;
  dm_state *s = &r->s;
  dmp_build_particles(p, s);
  const size_t nreal = r->nreal = (size_t)(p->ncell[0] * p->ncell[1] * p->ncell[2]);
  if (p->has_source)
    for (size_t i = 0; i < nreal; ++i) {
      const double *X = &s->X[3 * i];
      if (fmax(fabs(X[0]), fmax(fabs(X[1]), fabs(X[2]))) < p->src_r0) s->bc[i] = DM_PRESCRIBED;
    }
  for (size_t i = nreal; i < s->n; ++i) /* ghosts of source particles follow the source */
    if (s->bc[i] == DM_MIRROR && s->bc[s->partner[i]] == DM_PRESCRIBED) s->bc[i] = DM_PRESCRIBED;
  dmp_set_initial(p, s, nreal);

  dm_options opt = {
      .horizon = p->horizon * p->h, .cond_max = p->cond_max, .hourglass = p->hourglass};
  for (int a = 0; a < p->dim; ++a)
    if (p->face[2 * a] == FACE_PERIODIC) opt.box[a] = p->hi[a] - p->lo[a];
  ms_status st = dm_model_create(&(dm_model_params){.state = s, .opt = opt, .ctx = r->ctx}, &r->m);
  if (st != MS_OK) return st;
  if (p->has_source) {
    r->m->prescribe = sphere_prescribe;
    r->m->prescribe_user = p;
  }
  p->sum.particles = s->n;
  p->sum.real_particles = nreal;
  p->sum.bonds = r->m->nbonds;
  dm_constrain(r->m, 0.0, s->w, s->u);

  /* Time step: given, or courant · h / c_max; checked against the scheme's stability limit. */
  double dt = p->dt > 0 ? p->dt : p->courant * p->h / sound_speed_max(s, nreal);
  long nsteps = p->steps;
  if (nsteps <= 0) {
    nsteps = (long)ceil(p->t_end / dt - 1e-9);
    dt = p->t_end / nsteps;
  }
  r->dt = dt, r->nsteps = nsteps;
  return MS_OK;
}

/* MPI: partition the bond graph and build this rank's local model (docs/mpi.md); then the
 * stability check of the time step. */
static ms_status run_distribute(dm_run *r) {
  ms_ctx *ctx = r->ctx;
  dm_problem *p = r->p;
  dm_run_summary *sum = &p->sum;
  ms_status st = dm_dist_create(&(dm_dist_params){.global = r->m, .ctx = ctx}, &r->d);
  if (st != MS_OK) return st;
  r->par = ctx->size > 1;
  const dm_dist_stats *ds = dm_dist_get_stats(r->d);
  sum->ranks = ctx->size;
  sum->edge_cut = ds->edge_cut, sum->edge_cut_slab = ds->edge_cut_slab;
  sum->imbalance = ds->imbalance, sum->imbalance_slab = ds->imbalance_slab;
  if (r->par)
    ms_log(ctx, MS_LOG_INFO,
           "discrete model on %d ranks: METIS edge cut %ld of %zu bonds (%.2f %%), imbalance "
           "%.4f; plain x slabs: edge cut %ld, imbalance %.4f; owned max %zu, ghosts max %zu "
           "(total %zu); partitioning %.3f s",
           ctx->size, ds->edge_cut, ds->bonds, 100.0 * ds->edge_cut / fmax(1.0, ds->bonds),
           ds->imbalance, ds->edge_cut_slab, ds->imbalance_slab, ds->max_owned, ds->max_ghosts,
           ds->total_ghosts, ds->partition_s);
  const double dt = r->dt;
  double wmax = omega_max(r->d, &r->s), limit = rkn_stability_limit(p->integrator);
  dm_dist_release_global(r->d); /* the local model has all it needs: halve the memory */
  sum->dt = dt;
  sum->steps = r->nsteps;
  sum->t_end = r->nsteps * dt;
  sum->omega_dt = wmax * dt;
  ms_log(ctx, MS_LOG_INFO,
         "discrete model: %zu particles (%zu real), %zu bonds (%.1f per particle), dim %d, "
         "horizon %.3g h; %s, dt = %.6g %s (omega_max dt = %.4g, stability limit %.4g), %ld steps",
         r->s.n, r->nreal, r->m->nbonds, (double)r->m->nbonds / r->s.n, p->dim, p->horizon,
         rkn_scheme_names[p->integrator], ms_out_time(dt), ms_out_time_label(), wmax * dt, limit,
         r->nsteps);
  if (wmax * dt > 0.99 * limit) {
    ms_log(ctx, MS_LOG_ERROR,
           "discrete model: time step %.6g too large: omega_max dt = %.4g exceeds 0.99 x the "
           "stability limit %.4g of %s (lower dt or courant)",
           dt, wmax * dt, limit, rkn_scheme_names[p->integrator]);
    return MS_ERR_INPUT;
  }
  r->ls = dm_dist_state(r->d);
  return MS_OK;
}

/* The recording arrays (sized once, before the time loop), the integrator and E0. */
static void run_records(dm_run *r) {
  static char no_outdir[1] = "";
  const dm_problem *p = r->p;
  r->octx = *r->ctx;
  if (r->ctx->rank != 0) r->octx.outdir = no_outdir;
  r->pr = ms_calloc(p->nprobes ? p->nprobes : 1, sizeof *r->pr);
  dmp_find_probes(p, &r->s, r->nreal, r->pr);
  r->probe_val = ms_calloc(p->nprobes ? p->nprobes : 1, sizeof(double));
  r->nrec_max = (size_t)(r->nsteps / p->probe_every) + 2;
  r->pcols = 1 + p->nprobes;
  r->hist = p->nprobes ? ms_calloc(r->nrec_max * r->pcols, sizeof(double)) : NULL;
  r->nerec_max = (size_t)(r->nsteps / p->energy_every) + 2;
  r->ehist = ms_calloc(r->nerec_max * 5, sizeof(double));
  r->prof_step = ms_calloc(p->nprofile_times ? p->nprofile_times : 1, sizeof(long));
  for (size_t q = 0; q < p->nprofile_times; ++q)
    r->prof_step[q] = lround(p->profile_times[q] / r->dt);
  r->snap_step = ms_calloc(p->nsnapshot_times ? p->nsnapshot_times : 1, sizeof(long));
  for (size_t q = 0; q < p->nsnapshot_times; ++q)
    r->snap_step[q] = lround(p->snapshot_times[q] / r->dt);

  ms_must(rkn_create(&(rkn_params){.kind = p->integrator, .ndof = 3 * (r->ls->n ? r->ls->n : 1)},
                     &r->ig),
          "rkn_create");
  dm_dist_diag dg;
  dm_dist_diagnostics(r->d, &dg);
  r->E0 = dg.kinetic + dg.potential;
  r->ck = (dm_checkpoint_data){.hist = r->hist, .ehist = r->ehist, .pcols = r->pcols};
}

/* `mscale run --restart FILE`: the state and the records so far from a checkpoint. */
static ms_status run_restart(dm_run *r) {
  const ms_ctx *ctx = r->ctx;
  if (!ctx->restart) return MS_OK;
  dm_checkpoint_data *ck = &r->ck;
  ck->nrec_max = r->nrec_max, ck->nerec_max = r->nerec_max;
  ms_status st = dmp_read_checkpoint(ctx, ctx->restart, &r->s, r->nsteps, r->dt, ck);
  if (r->par) st = par_agree_status(st);
  if (st == MS_OK) {
    dm_dist_scatter(r->d, r->s.w, 3, r->ls->w);
    dm_dist_scatter(r->d, r->s.u, 3, r->ls->u);
    r->step0 = ck->step, r->E0 = ck->E0, r->dw_scale = ck->dw_scale;
    r->nrec = ck->nrec, r->nerec = ck->nerec;
    r->p->sum.energy_err_max = ck->energy_err_max;
    r->p->sum.restart_step = r->step0;
    ms_log(ctx, MS_LOG_INFO, "discrete model: restarted from %s at step %ld (t = %.9g %s)",
           ctx->restart, r->step0, ms_out_time(r->step0 * r->dt), ms_out_time_label());
  }
  return st;
}

/* The global w and u (every rank) from the ranks' owned particles. */
static void gather_state(dm_run *r) {
  dm_dist_gather(r->d, r->ls->w, 3, r->s.w);
  dm_dist_gather(r->d, r->ls->u, 3, r->s.u);
}

/* The checkpoint of the state at the top of step `step`, before anything of it is recorded. */
static ms_status run_checkpoint(dm_run *r, long step) {
  gather_state(r);
  dm_checkpoint_data *ck = &r->ck;
  ck->step = step, ck->E0 = r->E0, ck->dw_scale = r->dw_scale;
  ck->nrec = r->nrec, ck->nerec = r->nerec;
  ck->energy_err_max = r->p->sum.energy_err_max;
  ms_status cs =
      r->ctx->rank == 0 ? dmp_write_checkpoint(&r->octx, &r->s, r->dt, r->ctx->size, ck) : MS_OK;
  return r->par ? par_agree_status(cs) : cs;
}

/* Probe displacements (every probe_every steps) and energies (every energy_every steps). */
static void run_record(dm_run *r, long step, double t) {
  const dm_problem *p = r->p;
  dm_run_summary *sum = &r->p->sum;
  if (r->hist && step % p->probe_every == 0 && r->nrec < r->nrec_max) {
    for (size_t q = 0; q < p->nprobes; ++q) {
      long l = dm_dist_local_index(r->d, r->pr[q].particle);
      r->probe_val[q] = l >= 0 ? r->ls->w[3 * l] : 0.0;
    }
    if (r->par) par_sum_doubles(r->probe_val, p->nprobes); /* one owner per probe: exact */
    double *row = &r->hist[r->nrec * r->pcols];
    row[0] = t;
    for (size_t q = 0; q < p->nprobes; ++q) row[1 + q] = r->probe_val[q];
    ++r->nrec;
  }
  if ((step % p->energy_every == 0 || step == r->nsteps) && r->nerec < r->nerec_max) {
    dm_dist_diag dg;
    dm_dist_diagnostics(r->d, &dg);
    double K = dg.kinetic, U = dg.potential;
    r->dw_scale = fmax(r->dw_scale, dg.dw_norm);
    double *row = &r->ehist[5 * r->nerec++];
    row[0] = t, row[1] = K, row[2] = U, row[3] = K + U, row[4] = dg.hourglass;
    if (r->E0 > 0 && !p->has_source) { /* a source does work: no conservation to check */
      double err = fabs(K + U - r->E0) / r->E0;
      sum->energy_err_max = isnan(sum->energy_err_max) ? err : fmax(sum->energy_err_max, err);
    }
    if (step == r->nsteps) sum->kinetic_end = K, sum->potential_end = U;
  }
}

/* The profiles and snapshots due at step `step` (of the gathered global state). */
static void run_write_fields(dm_run *r, long step, double t) {
  const dm_problem *p = r->p;
  int gathered = 0;
  for (int kind = 0; kind < 2; ++kind) {
    const long *due = kind == 0 ? r->prof_step : r->snap_step;
    const size_t ntimes = kind == 0 ? p->nprofile_times : p->nsnapshot_times;
    for (size_t q = 0; q < ntimes; ++q) {
      if (due[q] != step) continue;
      if (!gathered) {
        gather_state(r);
        dm_dist_global_stress(r->d); /* stresses of the current state */
        gathered = 1;
      }
      if (kind == 0) {
        dmp_write_profile(&r->octx, p, r->m, r->nreal, t, (int)q);
      } else {
        char name[64];
        ptl_snapshot_name(name, sizeof name, (long)q);
        dmp_write_snapshot(&r->octx, p, r->m, r->nreal, t, step, name);
      }
    }
  }
}

/* The time loop from step0 to nsteps (nothing when st is already an error). */
static ms_status run_steps(dm_run *r, ms_status st) {
  const dm_problem *p = r->p;
  const double dt = r->dt;
  ms_progress prog;
  ms_progress_start(&prog, r->ctx, "discrete model", r->step0 * dt, p->sum.t_end);
  r->last_step = r->step0;
  bool stopping = false; /* interrupted: stop at the next checkpoint */
  for (long step = r->step0; step <= r->nsteps && st == MS_OK; ++step) {
    double t = step * dt;
    if (p->checkpoint_every > 0 && step > r->step0 && step % p->checkpoint_every == 0 &&
        step < r->nsteps) {
      st = run_checkpoint(r, step);
      if (st != MS_OK) break;
      if (stopping) { /* SIGINT/SIGTERM: `mscale run --continue` goes on from here */
        ms_log(r->ctx, MS_LOG_WARN, "discrete model: interrupted; checkpoint at step %ld written",
               step);
        st = MS_INTERRUPTED;
        break;
      }
    }
    if (!stopping && step < r->nsteps && ms_interrupt_agreed(r->ctx)) { /* collective */
      stopping = true;
      if (p->checkpoint_every <= 0) {
        ms_log(r->ctx, MS_LOG_WARN, "discrete model: interrupted at step %ld (no checkpoints)",
               step);
        st = MS_INTERRUPTED;
        break;
      }
      ms_log(r->ctx, MS_LOG_WARN,
             "discrete model: interrupt: stopping at the next checkpoint (step %ld)",
             (step / p->checkpoint_every + 1) * p->checkpoint_every);
    }
    run_record(r, step, t);
    run_write_fields(r, step, t);
    if (step == r->nsteps) break;
    r->last_step = step;
    double w0 = ms_wall_time(), c0 = dmp_cpu_time();
    st = rkn_step(r->ig, t, dt, r->ls->w, r->ls->u, dm_dist_accel, dm_dist_constrain, r->d);
    r->wall += ms_wall_time() - w0;
    r->cpu += dmp_cpu_time() - c0;
    ms_progress_update(&prog, t + dt, step + 1);
  }
  ms_progress_finish(&prog, p->sum.t_end, r->nsteps);
  return st;
}

/* After the loop: the final state (every rank), the zero-energy-mode indicator relative to the
 * largest |Δw| of the run, the timings; the report of an unstable step. */
static void run_finish(dm_run *r, ms_status st) {
  dm_problem *p = r->p;
  dm_run_summary *sum = &p->sum;
  gather_state(r);
  const dm_state *s = &r->s;
  free(p->final_w);
  free(p->final_u);
  p->final_n = s->n;
  p->final_w = ms_calloc(3 * s->n, sizeof(double));
  p->final_u = ms_calloc(3 * s->n, sizeof(double));
  memcpy(p->final_w, s->w, 3 * s->n * sizeof(double));
  memcpy(p->final_u, s->u, 3 * s->n * sizeof(double));
  for (size_t k = 0; k < r->nerec; ++k) {
    double hg = r->dw_scale > 0 ? r->ehist[5 * k + 4] / r->dw_scale : 0.0;
    r->ehist[5 * k + 4] = hg;
    if (k == 0) sum->hourglass_first = sum->hourglass_max = hg;
    sum->hourglass_max = fmax(sum->hourglass_max, hg);
    sum->hourglass_last = hg;
  }
  if (r->par) { /* the slowest rank sets the pace; CPU time of all ranks */
    const dm_dist_stats *ds = dm_dist_get_stats(r->d);
    double ex_max = par_max_double(ds->exchange_s), ex_min = par_min_double(ds->exchange_s);
    double vol = par_sum_double(ds->exchanged_doubles);
    ms_log(r->ctx, MS_LOG_INFO,
           "discrete model: ghost exchanges took %.3f-%.3f s per rank (of the step loop's %.3f s "
           "on the slowest rank); %.4g doubles received in all (%.3g per particle-step)",
           ex_min, ex_max, par_max_double(r->wall), vol,
           vol / fmax(1.0, (double)r->nreal * (double)(r->nsteps - r->step0)));
    r->wall = par_max_double(r->wall);
    r->cpu = par_sum_double(r->cpu);
  }
  sum->wall_s = r->wall;
  sum->cpu_s = r->cpu;
  sum->particle_steps_per_s = r->wall > 0 ? (double)r->nreal * (r->nsteps - r->step0) / r->wall : 0;
  if (st == MS_ERR_UNSTABLE)
    dmp_report_unstable(r->ctx, &r->octx, r->p, r->m, r->d, r->ls, r->nreal, r->last_step,
                        r->last_step * r->dt);
}

/* Analyses against the exact solutions (after a run that completed). */
static void run_analyses(dm_run *r) {
  dm_problem *p = r->p;
  const dm_run_summary *sum = &p->sum;
  const ms_ctx *ctx = r->ctx;
  if ((p->profile == PROF_ROD_TRIANGLE || p->profile == PROF_ROD_SINE) && p->nprobes) {
    double *h1 = ms_calloc(2 * r->nrec, sizeof(double));
    for (size_t k = 0; k < r->nrec; ++k)
      h1[2 * k] = r->hist[k * r->pcols], h1[2 * k + 1] = r->hist[k * r->pcols + 1];
    dmp_rod_analysis(p, h1, r->nrec, r->pr[0].x);
    free(h1);
    ms_log(ctx, MS_LOG_INFO,
           "rod: probe x = %.6g, last 10 L/c: amplitude error %+.3f %% (least-squares fit), "
           "lag %+.5f L/c, peak error %+.3f %%, rms error %.3f %% of the amplitude",
           r->pr[0].x, 100 * sum->amp_err, sum->phase_err, 100 * sum->peak_err, 100 * sum->rms_err);
  }
  if (p->profile == PROF_CONTACT) {
    dmp_contact_analysis(p, r->m, r->nreal, sum->t_end);
    ms_log(ctx, MS_LOG_INFO,
           "contact: sigma_xx at t = %.6g vs exact: L1 %.4f, L2 %.4f, max %.4f (of max|sigma|)",
           sum->t_end, sum->err_l1, sum->err_l2, sum->err_max);
  }
  if (p->has_source) {
    dmp_sphere_analysis(p, &r->s, r->nreal, sum->t_end);
    dmp_write_sphere_radial(&r->octx, p, &r->s, r->nreal, sum->t_end);
    ms_log(ctx, MS_LOG_INFO,
           "sphere: radial w at t = %.6g vs exact: L1 %.4f, L2 %.4f, max %.4f (of max|w|); "
           "u: L2 %.4f of w0*omega",
           sum->t_end, sum->err_l1, sum->err_l2, sum->err_max, sum->err_u_l2);
  }
}

/* The run's log line and files: probe history, energy history, summary. */
static void run_report(dm_run *r) {
  const dm_run_summary *sum = &r->p->sum;
  ms_log(r->ctx, MS_LOG_INFO,
         "discrete model: %ld steps in %.3f s (CPU %.3f s): %.4g particle-steps/s; "
         "max |dH|/H0 = %.3g; "
         "hourglass indicator first %.3g max %.3g last %.3g",
         r->nsteps - r->step0, r->wall, r->cpu, sum->particle_steps_per_s, sum->energy_err_max,
         sum->hourglass_first, sum->hourglass_max, sum->hourglass_last);
  if (r->hist) dmp_write_probes(&r->octx, r->p, r->pr, r->hist, r->nrec);
  dmp_write_energy(&r->octx, r->ehist, r->nerec);
  dmp_write_summary(&r->octx, sum);
}

static void run_free(dm_run *r) {
  free(r->hist);
  free(r->ehist);
  free(r->prof_step);
  free(r->snap_step);
  free(r->pr);
  free(r->probe_val);
  rkn_destroy(&r->ig);
  dm_dist_destroy(&r->d);
  dm_model_destroy(&r->m);
  dm_state_free(&r->s);
}

ms_status dm_problem_run(ms_ctx *ctx, dm_problem *p) {
  dmp_summary_reset(&p->sum, p->finite);
  if (p->finite) return dmp_run_finite(ctx, p);
  dm_run r = {.ctx = ctx, .p = p};
  ms_status st = run_model(&r);
  if (st == MS_OK) st = run_distribute(&r);
  if (st == MS_OK) {
    run_records(&r);
    st = run_restart(&r);
    st = run_steps(&r, st);
    run_finish(&r, st);
    dm_dist_global_stress(r.d); /* C, σ of the final state for the analyses */
    if (st == MS_OK) run_analyses(&r);
    run_report(&r);
  }
  run_free(&r);
  return st;
}
