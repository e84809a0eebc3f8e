/* SPDX-License-Identifier: MIT */
/* dm_impact.c — the run of the deck problem type `impact` (docs/input-impact.md,
 * docs/particles-dm.md "Impact onto a rigid wall"): bodies of the finite-deformation model
 * (dm_finite.c) onto a rigid frictionless wall, free surfaces everywhere else.
 *
 * Wall (a penalty on the particles crossing its contact plane): a particle's centre may come no
 * closer than half a spacing to the wall plane (the body's surface is half a spacing beyond its
 * last particles); beyond that contact plane it feels the normal force
 *   f = k_i d,  d = h/2 − side (x_a − x_wall) > 0,  k_i = c_w M_i h,
 * M = ρ0 c_L² the particle material's P-wave modulus, so that a layer pressed on the wall
 * compresses like a layer of the body (c_w = 1: penetration = the strain of the contact stress
 * times h). Frictionless: no tangential force. Energy: the wall's work on the free particles,
 * with the half kicks' time-centred velocities, is dm_fin's ext_work, so K + U + E_hg − W_wall
 * is constant to round-off; the stored penalty energy E_wall = Σ k d²/2 equals −W_wall up to
 * the time discretisation (reported). Time step: ω_w Δt ≤ 2·courant (ω_w = √(k/m)), and a
 * particle approaching the wall moves at most 0.1 h per step. */
#include "dm_impact_run.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double wall_force(void *user, const dm_fin *f, double *fext) {
  dmi_wall *w = user;
  const dm_state *s = f->m->s;
  const int a = w->axis;
  double E = 0, vmax = 0;
  long nc = 0;
  memset(fext, 0, 3 * f->n * sizeof(double));
  for (size_t i = 0; w->on && i < f->n; ++i) {
    const double x = s->X[3 * i + a] + s->w[3 * i + a];
    const double d = w->side * (w->contact - x); /* > 0: beyond the contact plane */
    if (d > 0) {
      fext[3 * i + a] = w->side * w->k[i] * d;
      E += 0.5 * dm_fin_fold(f, i) * w->k[i] * d * d; /* the full body's (symmetry planes) */
      nc += (long)dm_fin_fold(f, i);
    }
    vmax = fmax(vmax, -w->side * s->u[3 * i + a]); /* approach speed */
  }
  const double dt_c = dmi_contact_force(w->ct, f, fext);
  w->stored = E + w->ct->stored, w->in_contact = nc;
  const double dt_v = vmax > 0 ? 0.1 * w->h / vmax : INFINITY;
  return fmin(fmin(w->dt_k, dt_v), dt_c);
}

/* The particles of every body, lattice sites in body order; X0 keeps the first reference. */
static void build_state(dm_impact *p, dm_state *s, uint8_t **imat) {
  size_t n = 0;
  for (size_t b = 0; b < p->nbodies; ++b) {
    p->bodies[b].first = n;
    p->bodies[b].count = dmi_body_sites(&p->bodies[b], p->h, NULL);
    n += p->bodies[b].count;
  }
  dm_state_alloc(s, n, 3);
  *imat = ms_calloc(n, 1);
  const double vol = p->h * p->h * p->h;
  for (size_t b = 0; b < p->nbodies; ++b) {
    dmi_body *bd = &p->bodies[b];
    dmi_body_sites(bd, p->h, &s->X[3 * bd->first]);
    const double rho0 = eos_rho0(bd->mat.eos), c0 = eos_c0(bd->mat.eos);
    for (size_t i = bd->first; i < bd->first + bd->count; ++i) {
      for (int a = 0; a < 3; ++a) s->u[3 * i + a] = bd->velocity[a];
      s->mass[i] = rho0 * vol, s->vol[i] = vol;
      s->K[i] = rho0 * c0 * c0, s->G[i] = bd->mat.G;
      s->bc[i] = DM_FREE;
      (*imat)[i] = (uint8_t)b;
    }
  }
}

/* Body 0 as a Taylor rod: a cylinder whose axis is the wall normal. Length = the axial extent
 * of its particles + h (half a spacing at each end); footprint = D0 max r/r0 over its outer
 * particles (r0 within h/2 of the largest initial radius): the rod's surface taken to stretch
 * radially with the outer particles beside it, so that the footprint is D0 at t = 0 whatever the
 * lattice. NaN for other bodies. */
static void taylor_measures(const dm_impact *p, const dm_state *s, const double *X0, double *length,
                            double *footprint) {
  const dmi_body *b = &p->bodies[0];
  *length = *footprint = NAN;
  if (b->shape != DMI_CYLINDER || !p->has_wall || b->axis != p->wall_axis) return;
  const int a = b->axis, q1 = (a + 1) % 3, q2 = (a + 2) % 3;
  double zmin = INFINITY, zmax = -INFINITY, r0max = 0, D = 0;
  for (size_t i = b->first; i < b->first + b->count; ++i) {
    const double z = s->X[3 * i + a] + s->w[3 * i + a];
    zmin = fmin(zmin, z), zmax = fmax(zmax, z);
    r0max = fmax(r0max, hypot(X0[3 * i + q1] - b->center[q1], X0[3 * i + q2] - b->center[q2]));
  }
  for (size_t i = b->first; i < b->first + b->count; ++i) {
    const double r0 = hypot(X0[3 * i + q1] - b->center[q1], X0[3 * i + q2] - b->center[q2]);
    if (r0 < r0max - 0.5 * p->h) continue;
    const double x1 = s->X[3 * i + q1] + s->w[3 * i + q1] - b->center[q1];
    const double x2 = s->X[3 * i + q2] + s->w[3 * i + q2] - b->center[q2];
    D = fmax(D, 2.0 * b->radius * hypot(x1, x2) / r0);
  }
  *length = zmax - zmin + p->h, *footprint = D;
}

/* Body 0's profile (as taylor_measures): the surface radius R0 max r/r0 of its outer particles
 * in the slice of one spacing that contains the height f L_f above the impact face (the face at
 * half a spacing beyond the last layer), for f = DM_TAYLOR_PROFILE_F (tools/taylor_profile.py
 * plots the same slices). NaN where the slice holds no outer particle or body 0 is not a rod. */
static void taylor_profile(const dm_impact *p, const dm_state *s, const double *X0, double length,
                           double *radius) {
  static const double frac[DM_TAYLOR_PROFILE_N] = DM_TAYLOR_PROFILE_F;
  const dmi_body *b = &p->bodies[0];
  for (int k = 0; k < DM_TAYLOR_PROFILE_N; ++k) radius[k] = NAN;
  if (b->shape != DMI_CYLINDER || !p->has_wall || b->axis != p->wall_axis || !(length > 0)) return;
  const int a = b->axis, q1 = (a + 1) % 3, q2 = (a + 2) % 3, side = p->wall_side;
  double zface = INFINITY, r0max = 0; /* zface: the face layer's distance from the wall plane */
  for (size_t i = b->first; i < b->first + b->count; ++i) {
    zface = fmin(zface, side * (s->X[3 * i + a] + s->w[3 * i + a] - p->wall_pos));
    r0max = fmax(r0max, hypot(X0[3 * i + q1] - b->center[q1], X0[3 * i + q2] - b->center[q2]));
  }
  for (size_t i = b->first; i < b->first + b->count; ++i) {
    const double r0 = hypot(X0[3 * i + q1] - b->center[q1], X0[3 * i + q2] - b->center[q2]);
    if (r0 < r0max - 0.5 * p->h) continue;
    const double hgt = side * (s->X[3 * i + a] + s->w[3 * i + a] - p->wall_pos) - zface;
    const double x1 = s->X[3 * i + q1] + s->w[3 * i + q1] - b->center[q1];
    const double x2 = s->X[3 * i + q2] + s->w[3 * i + q2] - b->center[q2];
    for (int k = 0; k < DM_TAYLOR_PROFILE_N; ++k) { /* slice [j h, (j+1) h) from the face */
      const double at = frac[k] * length, j = floor(at / p->h);
      if (hgt + 0.5 * p->h >= j * p->h && hgt + 0.5 * p->h < (j + 1) * p->h) {
        const double r = b->radius * hypot(x1, x2) / r0;
        radius[k] = isnan(radius[k]) ? r : fmax(radius[k], r);
      }
    }
  }
}

/* The per-particle fields a snapshot shows: w, u ([n][3]), e, ρ, p, J, ε_p ([n]), of the live
 * model or of the copy taken at the start of a step (the last good state when it fails). */
enum { NFIELD = 7 };
static void live_fields(const dm_fin *f, double *fld[NFIELD]) {
  double *const live[NFIELD] = {f->m->s->w, f->m->s->u, f->e, f->rho, f->p, f->J, f->eps_p};
  memcpy(fld, live, sizeof live);
}

/* OUTDIR/NAME: an HDF5 snapshot of every particle in the layout of every particle problem
 * (docs/output.md, "Particle snapshots"; ptl_write_snapshot with the particles.xmf series):
 * current x = X + w, velocity u, mass, material (index into material_names: the bodies'
 * materials, each name once), then the model's fields: body, first reference X0, ρ, p, e,
 * ε_p, J (fld: live_fields' order), failed (0 intact, 1 failed: dm_fracture.c);
 * attributes time, step, r0 = h. */
static void write_particles(const ms_ctx *ctx, const dm_impact *p, const char *name,
                            const dm_fin *f, double *const fld[NFIELD], const double *X0,
                            const uint8_t *imat, double t, long step) {
  if (!ctx->outdir || !ctx->outdir[0]) return;
  const dm_state *s = f->m->s;
  const size_t n = f->n;
  double *xv = ms_calloc(6 * n + 1, sizeof(double));
  int64_t *ids = ms_calloc(3 * n + 1, sizeof(int64_t)), *body = ids, *mat = ids + n,
          *failed = ids + 2 * n;
  /* the table: every body's material once, in body order; bmat[b] its index */
  char names[4096] = "";
  int64_t *bmat = ms_calloc(p->nbodies + 1, sizeof *bmat);
  for (size_t b = 0, nm = 0; b < p->nbodies; ++b) {
    bmat[b] = (int64_t)nm;
    for (size_t c = 0; c < b; ++c)
      if (!strcmp(p->bodies[c].material, p->bodies[b].material)) bmat[b] = bmat[c];
    if (bmat[b] == (int64_t)nm) ptl_material_table_add(names, sizeof names, p->bodies[b].material);
    if (bmat[b] == (int64_t)nm) ++nm;
  }
  for (size_t i = 0; i < n; ++i)
    body[i] = imat[i], mat[i] = bmat[imat[i]], failed[i] = f->failed ? f->failed[i] : 0;
  const ptl_snapshot_data data[] = {{"particles/material", NULL, mat, 1, NULL},
                                    {"particles/body", NULL, body, 1, NULL},
                                    {"particles/X0", X0, NULL, 3, "cm"},
                                    {"particles/density", fld[3], NULL, 1, "g/cm^3"},
                                    {"particles/pressure", fld[4], NULL, 1, "GPa"},
                                    {"particles/energy", fld[2], NULL, 1, "kJ/g"},
                                    {"particles/eps_p", fld[6], NULL, 1, "1"},
                                    {"particles/J", fld[5], NULL, 1, "1"},
                                    {"particles/failed", NULL, failed, 1, NULL}};
  const ms_xdmf_attr xdmf[] = {{"velocity", "particles/v", 3, false},
                               {"mass", "particles/mass", 1, false},
                               {"density", "particles/density", 1, false},
                               {"pressure", "particles/pressure", 1, false},
                               {"energy", "particles/energy", 1, false},
                               {"eps_p", "particles/eps_p", 1, false},
                               {"J", "particles/J", 1, false}};
  ptl_snapshot snap = dmp_snapshot_of(n, s->X, fld[0], fld[1], s->mass, t, xv); /* w, u */
  ptl_snapshot_contents(&snap, sizeof data / sizeof data[0], data, sizeof xdmf / sizeof xdmf[0],
                        xdmf, names, step);
  ptl_snapshot_attr_add(&snap, "r0", p->h);
  for (int j = 0; j < p->sym.n; ++j) /* the + side of these planes only (dm_impact_sym.c) */
    ptl_snapshot_attr_add(
        &snap, (const char *[]){"symmetry_x", "symmetry_y", "symmetry_z"}[p->sym.axis[j]],
        p->sym.pos[j]);
  dmp_snapshot_write(ctx, name, &snap, "impact");
  free(xv), free(ids), free(bmat);
}

enum { NHIST = 17 }; /* columns of impact_history.csv */

/* Body 0's momentum along its initial velocity (g·km/s; 0 for a body at rest; the full
 * body's with symmetry planes: its velocity has no component through them). */
static double body0_momentum(const dm_impact *p, const dm_fin *f) {
  const dmi_body *b = &p->bodies[0];
  const dm_state *s = f->m->s;
  const double v = hypot(hypot(b->velocity[0], b->velocity[1]), b->velocity[2]);
  double P = 0;
  for (size_t i = b->first; v > 0 && i < b->first + b->count; ++i)
    for (int a = 0; a < 3; ++a)
      P += dm_fin_fold(f, i) * s->mass[i] * s->u[3 * i + a] * b->velocity[a] / v;
  return P;
}

static void record(dmi_run *r) {
  const dm_fin *f = r->f;
  const dm_state *s = f->m->s;
  double K, U, H, P[3] = {0, 0, 0}, L, D;
  dm_fin_energies(f, &K, &U, &H);
  dm_fin_momentum(f, P); /* the full body's (symmetry planes) */
  taylor_measures(r->p, s, r->X0, &L, &D);
  dm_impact_summary *sum = &r->p->sum;
  const double B = dm_fin_broken_energy(f);  /* booked out of E_hg at failures (dm_fracture.c) */
  const double C = dm_fin_contact_energy(f); /* failed particles' springs (dm_fracture.c) */
  const double bal = K + U + H + B + C - f->ext_work - r->E0;
  sum->stretch_max = fmax(sum->stretch_max, dm_fin_max_stretch(f, NULL));
  for (size_t i = 0; i < f->n; ++i)
    sum->J_min = fmin(sum->J_min, f->J[i]), sum->J_max = fmax(sum->J_max, f->J[i]);
  sum->energy_err = fmax(sum->energy_err, fabs(bal) / r->E0);
  if (r->Pabs0 > 0)
    sum->p_total =
        fmax(sum->p_total,
             hypot(hypot(P[0] - r->Pv0[0], P[1] - r->Pv0[1]), P[2] - r->Pv0[2]) / r->Pabs0);
  sum->wall_err = fmax(sum->wall_err, fabs(f->ext_work + r->wl->stored) / r->E0);
  if (r->p->has_wall && r->P0 > 0) {
    const int a = r->p->wall_axis;
    sum->p_transverse = fmax(
        sum->p_transverse,
        hypot(P[(a + 1) % 3] - r->Pv0[(a + 1) % 3], P[(a + 2) % 3] - r->Pv0[(a + 2) % 3]) / r->P0);
    sum->p_normal = r->p->wall_side * P[a] / r->P0;
  }
  if (r->nh == r->nhmax) r->nh = dm_rows_thin(r->hist, r->nh, NHIST), r->p->energy_every *= 2;
  const double row[NHIST] = {r->t,
                             K,
                             U,
                             H,
                             f->ext_work,
                             r->wl->stored,
                             bal,
                             P[0],
                             P[1],
                             P[2],
                             L,
                             D,
                             (double)r->wl->in_contact,
                             B,
                             (double)dm_fin_failed_count(f),
                             (double)r->wl->ct->in_contact,
                             C};
  memcpy(&r->hist[NHIST * r->nh++], row, sizeof row);
}

static void write_outputs(const ms_ctx *ctx, const dmi_run *r) {
  const char *nm[] = {
      "t",        "kinetic", "internal", "bond_penalty",  "wall_work",       "wall_energy",
      "balance",  "p_x",     "p_y",      "p_z",           "length",          "footprint",
      "contacts", "broken",  "failed",   "body_contacts", "fracture_contact"};
  const char *un[] = {"10 us",  "kJ", "kJ", "kJ", "kJ", "kJ", "kJ", "g*km/s", "g*km/s",
                      "g*km/s", "cm", "cm", "1",  "kJ", "1",  "1",  "kJ"};
  dmp_write_series(ctx, "impact_history.csv",
                   "impact history: balance = kinetic + internal + bond_penalty + broken + "
                   "fracture_contact - "
                   "wall_work - E0 (wall_work, wall_energy: the wall's and the contact's); "
                   "length, footprint of body 0 (a cylinder on the wall)",
                   NHIST, nm, un, r->hist, r->nh);
  const dm_impact_summary *s = &r->p->sum;
  const double row[] = {(double)s->particles,
                        (double)s->bonds,
                        (double)s->steps,
                        s->t_end,
                        s->wall_s,
                        s->E0,
                        s->energy_err,
                        s->wall_err,
                        s->hg_ratio,
                        (double)s->ref_updates,
                        s->released,
                        s->p_transverse,
                        s->p_normal,
                        s->J_min,
                        s->J_max,
                        s->stretch_max,
                        s->length0,
                        s->length,
                        s->footprint0,
                        s->footprint,
                        s->broken,
                        (double)s->failed};
  const char *sn[] = {"particles",   "bonds",        "steps",    "t_end",      "wall_time",
                      "E0",          "energy_err",   "wall_err", "hg_ratio",   "ref_updates",
                      "released",    "p_transverse", "p_normal", "J_min",      "J_max",
                      "stretch_max", "length0",      "length",   "footprint0", "footprint",
                      "broken",      "failed"};
  const char *su[] = {"1", "1", "1", "10 us", "s", "kJ", "1",  "1",  "1",  "1",  "kJ",
                      "1", "1", "1", "1",     "1", "cm", "cm", "cm", "cm", "kJ", "1"};
  dmp_write_series(ctx, "impact_summary.csv", "impact summary (docs/input-impact.md)", 22, sn, su,
                   row, 1);
}

/* A particle outside the domain stops the run (the box bounds the problem). */
static long outside_box(const dm_impact *p, const dm_state *s, size_t n) {
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      const double x = s->X[3 * i + a] + s->w[3 * i + a];
      if (!(x >= p->lo[a] && x <= p->hi[a])) return (long)i;
    }
  return -1;
}

/* The reference update when a bond stretch passes 1 + threshold (dm_refamily.c). */
static ms_status maybe_update(dmi_run *r, const ms_ctx *ctx) {
  dm_impact *p = r->p;
  if (!(p->ref_threshold > 0)) return MS_OK;
  size_t at = 0;
  dm_refamily_report rep;
  double lam = 0;
  ms_status st;
  if (p->ref_family) { /* each family against its own trigger */
    st = dm_fin_rebase_local(r->f, ctx, p->ref_threshold, p->ref_keep == 2, &rep);
    if (st == MS_OK && rep.families == 0) return MS_OK;
    lam = 1.0 + p->ref_threshold, at = rep.bad;
  } else {
    lam = dm_fin_max_stretch(r->f, &at);
    if (lam <= 1.0 + p->ref_threshold) return MS_OK;
    st = p->ref_keep ? dm_fin_rebase(r->f, ctx, p->ref_keep == 2, &rep)
                     : dm_fin_reference_update(r->f, ctx, &rep);
  }
  const dm_state *s = r->f->m->s;
  if (st != MS_OK && rep.uncovered && rep.bad < s->n) { /* dm_sym_family.c */
    const size_t b = rep.bad;
    ms_log(ctx, MS_LOG_ERROR,
           "impact: step %ld, t = %.9g: the reference update is refused: particle %zu at x = "
           "(%g, %g, %g) has come within the horizon of a symmetry plane where it has no mirror "
           "ghost (the kept families use the set-up's ghosts); the run stops (no output of this "
           "state): run the full body",
           r->f->step, r->t, b, s->X[3 * b] + s->w[3 * b], s->X[3 * b + 1] + s->w[3 * b + 1],
           s->X[3 * b + 2] + s->w[3 * b + 2]);
    return st;
  }
  if (st != MS_OK) {
    const size_t b = rep.bad < s->n ? rep.bad : at;
    ms_log(ctx, MS_LOG_ERROR,
           "impact: step %ld, t = %.9g: the reference update (bond stretch %.4g at particle %zu) "
           "is refused: particle %zu at x = (%g, %g, %g) would have a degenerate family; the run "
           "stops (no output of this state)",
           r->f->step, r->t, lam, at, b, s->X[3 * b] + s->w[3 * b],
           s->X[3 * b + 1] + s->w[3 * b + 1], s->X[3 * b + 2] + s->w[3 * b + 2]);
    return st;
  }
  p->sum.ref_updates++, p->sum.released += rep.released;
  if (p->ref_family) {
    p->family_updates += (long)rep.families;
    ms_log(ctx, MS_LOG_DEBUG,
           "impact: step %ld, t = %.6g: reference update %ld: %zu families past the bond stretch "
           "%.4g (%ld in all), %zu gained bonds; %zu bonds, J in [%.4g, %.4g], bond-penalty "
           "energy released %.4g kJ",
           r->f->step, r->t, p->sum.ref_updates, rep.families, lam, p->family_updates, rep.gained,
           rep.bonds, rep.jmin, rep.jmax, rep.released);
    return MS_OK;
  }
  ms_log(ctx, MS_LOG_INFO,
         "impact: step %ld, t = %.6g: reference update %ld (bond stretch %.4g at particle %zu): "
         "%zu bonds, J in [%.4g, %.4g], bond-penalty energy released %.4g kJ",
         r->f->step, r->t, p->sum.ref_updates, lam, at, rep.bonds, rep.jmin, rep.jmax,
         rep.released);
  return MS_OK;
}

/* The time loop. Before every step it copies the fields of the snapshots (dmp_backup: 11 doubles
 * = 88 B per particle), since a step that fails (dm_fin_step) changes them before it can fail:
 * the last good state is then particles_unstable.h5 (docs/reliability.md §6), as the
 * discrete_model problem does (dm_fin_output.c). */
static ms_status time_loop(dmi_run *r, const ms_ctx *ctx, const uint8_t *imat) {
  dm_impact *p = r->p;
  dm_fin *f = r->f;
  ms_status st = MS_OK;
  size_t next_out = r->next_out;
  double wall_time = 0;
  dmp_backup bk;
  dmp_backup_alloc(&bk, f->n, DMP_KEEP_RHO | DMP_KEEP_J);
  double *live[NFIELD], *const good[NFIELD] = {bk.w, bk.u, bk.e, bk.rho, bk.p, bk.J, bk.eps_p};
  for (long step = r->step0;; ++step) {
    live_fields(f, live);
    const int last = r->t >= p->t_end * (1 - 1e-12);
    /* a checkpoint of the cadence, or the interrupted run's last: the state at the top of this
     * step, before anything of it is recorded (dm_impact_checkpoint.c) */
    r->next_out = next_out;
    if (!last && (dmi_checkpoint_due(r) || r->stopping)) {
      st = dmi_checkpoint_write(r);
      if (st == MS_OK && r->stopping) {
        ms_log(ctx, MS_LOG_WARN, "impact: interrupted; checkpoint at step %ld written", f->step);
        st = MS_INTERRUPTED;
      }
      if (st != MS_OK) break;
    }
    if (step % p->energy_every == 0 || last) record(r);
    /* particles_NNNN.h5 at output.particle_times, and the final state always the last one */
    const size_t first_now = next_out;
    char name[64];
    while (next_out < p->nparticle_times &&
           (r->t >= p->particle_times[next_out] * (1 - 1e-12) || last)) {
      ptl_snapshot_name(name, sizeof name, (long)next_out);
      write_particles(ctx, p, name, f, live, r->X0, imat, r->t, f->step);
      ++next_out;
    }
    if (last && next_out == first_now) {
      ptl_snapshot_name(name, sizeof name, (long)next_out);
      write_particles(ctx, p, name, f, live, r->X0, imat, r->t, f->step);
    }
    if (last) break;
    if (r->t + f->dt_next > p->t_end) f->dt_next = p->t_end - r->t;
    dmp_backup_take(&bk, f, r->t);
    const double dt = f->dt_next, w0 = ms_wall_time();
    st = dm_fin_step(f);
    const bool step_failed = st != MS_OK;
    if (st == MS_OK) st = maybe_update(r, ctx);
    wall_time += ms_wall_time() - w0;
    r->t += dt;
    if (st != MS_OK) {
      if (step_failed && f->bad_what) {
        const double *X = &f->m->s->X[3 * f->bad];
        ms_log(ctx, MS_LOG_ERROR,
               "impact: step %ld, t = %.9g %s: particle %zu (X = %g %g %g): %s = %g; the run "
               "stops, the last good state (step %ld, t = %.9g %s) is in " PTL_SNAPSHOT_UNSTABLE,
               f->step, ms_out_time(r->t), ms_out_time_label(), f->bad, X[0], X[1], X[2],
               f->bad_what, f->bad_value, bk.step, ms_out_time(bk.t), ms_out_time_label());
        write_particles(ctx, p, PTL_SNAPSHOT_UNSTABLE, f, good, r->X0, imat, bk.t, bk.step);
      }
      break;
    }
    /* SIGINT/SIGTERM (docs/reliability.md): checkpoint at the top of the next step, stop */
    if (ms_interrupt_agreed(ctx)) r->stopping = true;
    const long out = outside_box(p, f->m->s, f->n); /* real particles (not mirror ghosts) */
    if (out >= 0) { /* a finite state: the one that left the domain */
      ms_log(ctx, MS_LOG_ERROR,
             "impact: step %ld, t = %.9g %s: particle %ld left the domain; its state is "
             "in " PTL_SNAPSHOT_UNSTABLE,
             f->step, ms_out_time(r->t), ms_out_time_label(), out);
      live_fields(f, live);
      write_particles(ctx, p, PTL_SNAPSHOT_UNSTABLE, f, live, r->X0, imat, r->t, f->step);
      st = MS_ERR_UNSTABLE;
      break;
    }
  }
  dmp_backup_free(&bk);
  p->sum.wall_s = wall_time;
  return st;
}

/* After the time loop: the summary of the state reached (also the last good one of a run that
 * stopped), the log line and the outputs. */
static void report(const ms_ctx *ctx, dmi_run *r) {
  dm_impact *p = r->p;
  const dm_fin *f = r->f;
  double K1, U1, H1;
  dm_fin_energies(f, &K1, &U1, &H1);
  p->sum.steps = f->step, p->sum.t_end = r->t, p->sum.hg_ratio = H1 / r->E0;
  p->sum.broken = dm_fin_broken_energy(f), p->sum.failed = dm_fin_failed_count(f);
  p->sum.p_body0 = body0_momentum(p, f);
  taylor_measures(p, f->m->s, r->X0, &p->sum.length, &p->sum.footprint);
  taylor_profile(p, f->m->s, r->X0, p->sum.length, p->sum.radius_at);
  if (p->ref_family)
    ms_log(ctx, MS_LOG_INFO,
           "impact: per-family reference updates at %ld steps, %ld family updates in all (of %zu "
           "families), %zu bonds now",
           p->sum.ref_updates, p->family_updates, f->n, f->m->nbonds);
  ms_log(ctx, MS_LOG_INFO,
         "impact: %ld steps to t = %.6g in %.3f s; energy balance max |K + U + E_hg (+ broken + "
         "contact) - W_wall - E0| / E0 = %.3g; wall |W_wall + E_wall| / E0 <= %.3g; E_hg / E0 = "
         "%.3g; transverse momentum / |P0| <= %.3g, normal at the end %.4g; J in [%.4g, %.4g], "
         "bond stretch <= %.4g; %ld reference updates; %zu failed particles (of the real ones: %ld "
         "by the criterion, %ld isolated, %ld degenerate), broken energy %.4g "
         "kJ; body 0: length %.5g cm (L/L0 %.4f), footprint %.5g cm (D/D0 %.4f)",
         f->step, r->t, p->sum.wall_s, p->sum.energy_err, p->sum.wall_err, p->sum.hg_ratio,
         p->sum.p_transverse, p->sum.p_normal, p->sum.J_min, p->sum.J_max, p->sum.stretch_max,
         p->sum.ref_updates, p->sum.failed, f->nfail_stress, f->nfail_isolated, f->nfail_degenerate,
         p->sum.broken, p->sum.length, p->sum.length / p->sum.length0, p->sum.footprint,
         p->sum.footprint / p->sum.footprint0);
  write_outputs(ctx, r);
}

ms_status dm_impact_problem_run(ms_ctx *ctx, dm_impact *p) {
  static char no_outdir[1] = "";
  ms_ctx octx = *ctx; /* the files: rank 0 writes them (replicated on ranks: dm_impact_run.h) */
  if (ctx->rank != 0) octx.outdir = no_outdir;
  memset(&p->sum, 0, sizeof p->sum);
  p->sum.J_min = INFINITY, p->sum.J_max = -INFINITY;
  const long energy_every = p->energy_every;
  dm_state s;
  uint8_t *imat = NULL;
  build_state(p, &s, &imat);
  if (p->sym.n) dmi_sym_reduce(p, &s, &imat); /* the + side and its mirror ghosts */
  double *X0 = ms_calloc(3 * s.n, sizeof(double));
  memcpy(X0, s.X, 3 * s.n * sizeof(double));
  dm_options opt = {
      .horizon = p->horizon * p->h, .cond_max = p->cond_max, .ghost_rows = p->sym.n > 0};
  dm_model *m = NULL;
  ms_status st = dm_model_create(&(dm_model_params){.state = &s, .opt = opt, .ctx = ctx}, &m);
  dm_fin_material *mat = ms_calloc(p->nbodies, sizeof *mat);
  for (size_t b = 0; b < p->nbodies; ++b) mat[b] = p->bodies[b].mat, mat[b].sg = &p->bodies[b].sg;
  dm_fin *f = NULL;
  dm_fin_params par = {.cq = p->cq,
                       .cl = p->cl,
                       .courant = p->courant,
                       .hourglass = p->hourglass,
                       .ell = p->h,
                       .contact = p->contact_distance};
  if (st == MS_OK)
    st = dm_fin_create(&(dm_fin_setup){.m = m, .mat = mat, .imat = imat, .par = par, .sym = p->sym},
                       &f);
  dmi_contact ct;
  dmi_wall wl = {.axis = p->wall_axis,
                 .side = p->wall_side,
                 .h = p->h,
                 .courant = p->courant,
                 .on = p->has_wall,
                 .ct = &ct};
  wl.contact = p->wall_pos + p->wall_side * 0.5 * p->h;
  wl.k = ms_calloc(s.n, sizeof(double));
  wl.dt_k = INFINITY;
  double *M = ms_calloc(s.n ? s.n : 1, sizeof(double)); /* P-wave modulus ρ0 c_L² */
  for (size_t i = 0; i < s.n; ++i) {
    double cL, c;
    dmi_body_speeds(&p->bodies[imat[i]], &cL, &c);
    M[i] = s.mass[i] / s.vol[i] * cL * cL;
    wl.k[i] = p->wall_stiffness * M[i] * p->h;
    if (p->has_wall) wl.dt_k = fmin(wl.dt_k, 2.0 * p->courant / sqrt(wl.k[i] / s.mass[i]));
  }
  dmi_contact_init(&ct, p, s.n, imat, M);
  /* the short-range contact (dm_contact.c) inside bodies; between them the bodies' own */
  if (f && f->sr) f->sr->within_material = ct.on;
  free(M);
  if (st == MS_OK && (p->has_wall || ct.on)) st = dm_fin_set_external(f, wall_force, &wl);
  dmi_run r = {.p = p,
               .f = f,
               .wl = &wl,
               .X0 = X0,
               .nhmax = 4096,
               .ncol = NHIST,
               .ctx = ctx,
               .ckpt_next = p->checkpoint_time};
  if (st == MS_OK) {
    double K, U, H, P[3] = {0, 0, 0};
    dm_fin_energies(f, &K, &U, &H);
    r.E0 = K + U + H;
    dm_fin_momentum(f, P);
    r.P0 = sqrt(P[0] * P[0] + P[1] * P[1] + P[2] * P[2]);
    for (size_t i = 0; i < f->n; ++i)
      r.Pabs0 +=
          dm_fin_fold(f, i) * s.mass[i] * hypot(hypot(s.u[3 * i], s.u[3 * i + 1]), s.u[3 * i + 2]);
    p->sum.p0_body0 = body0_momentum(p, f);
    for (int a = 0; a < 3; ++a) r.Pv0[a] = P[a];
    r.hist = ms_calloc(NHIST * r.nhmax, sizeof(double));
    p->sum.particles = f->n, p->sum.bonds = f->m->nbonds, p->sum.E0 = r.E0;
    taylor_measures(p, &s, X0, &p->sum.length0, &p->sum.footprint0);
    ms_log(ctx, MS_LOG_INFO,
           "impact: %zu particles (+ %zu mirror ghosts, %d symmetry planes) in %zu bodies, %zu "
           "bonds, h %g cm, first dt %.6g, E0 %.6g kJ (the full body's), wall %s, contact "
           "between bodies %s; body 0: length %.5g cm, footprint %.5g cm",
           f->n, f->nall - f->n, p->sym.n, p->nbodies, f->m->nbonds, p->h, f->dt_next, r.E0,
           p->has_wall ? "on" : "off", ct.on ? "on" : "off", p->sum.length0, p->sum.footprint0);
    if (ctx->size > 1)
      ms_log(ctx, MS_LOG_INFO,
             "impact on %d ranks: replicated (every rank steps all %zu particles; rank 0 writes)",
             ctx->size, f->nall);
    if (ctx->restart) st = dmi_restart(&r);
    if (st == MS_OK) {
      st = time_loop(&r, &octx, imat);
      report(&octx, &r);
    }
  } else ms_log(ctx, MS_LOG_ERROR, "impact: the initial state is not valid");
  p->energy_every = energy_every;
  if (f) m = f->m; /* a reference update replaces the model */
  free(r.hist), free(wl.k), free(mat), free(imat), free(X0);
  dmi_contact_free(&ct);
  dm_fin_destroy(&f);
  dm_model_destroy(&m);
  dm_state_free(&s);
  return st;
}
