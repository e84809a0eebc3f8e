/* SPDX-License-Identifier: MIT */
/* cd_relax.c — what a cluster-dynamics run measures of its sample (the energy balance, the
 * virial stress, the free-surface velocity) and the relaxation stage before the run, which
 * drives the sample to rest and its mean stress toward zero with those measurements. The time
 * step and the list builds it calls are cd_sim.c's (cd_impl.h, "cd_sim.c internals").
 */
#include "cd_impl.h"

#include <math.h>
#include <string.h>

/* ---- diagnostics ---- */
/* Diagnostics under MPI: ghosts at x^{n+1} (after an RKN step they hold the last stage's). */
static void diag_ghosts(cd_sim *s) {
  if (s->dd && s->rkn) cd_dd_refresh(s, CD_REFRESH_X);
}

void cd_sim_energy(cd_sim *s, cd_energy *out) {
  const ptl_state *p = s->p;
  memset(out, 0, sizeof *out);
  diag_ghosts(s);
  cd_compute_forces(s, s->sums, NULL, false);
  double ke = 0, mom[3] = {0, 0, 0};
  for (size_t i = 0; i < p->nlocal; i++) {
    if (p->flags[i] & (PTL_DRIVEN | PTL_REMOVED)) continue;
    ke += 0.5 * p->mass[i] * (p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i] + p->vz[i] * p->vz[i]);
    mom[0] += p->mass[i] * p->vx[i];
    mom[1] += p->mass[i] * p->vy[i];
    mom[2] += p->mass[i] * p->vz[i];
  }
  double pe = 0.0;
  long inside[CD_MAX_MATERIALS * CD_MAX_MATERIALS] = {0};
  for (int l = 0; l < s->nl->nlayer; l++) {
    pe += s->sums[l].epot;
    for (int k = 0; k < CD_MAX_MATERIALS * CD_MAX_MATERIALS; k++) inside[k] += s->sums[l].inside[k];
  }
  double broken = s->broken_bonded, dissipated = s->dissipated, piston_work = s->piston_work;
  if (s->dd) { /* every rank's share (pairs booked once: cd_force.c) */
    double v[8] = {ke, mom[0], mom[1], mom[2], pe, broken, dissipated, piston_work};
    par_sum_doubles(v, 8);
    ke = v[0], mom[0] = v[1], mom[1] = v[2], mom[2] = v[3], pe = v[4], broken = v[5];
    dissipated = v[6], piston_work = v[7];
    int64_t in64[CD_MAX_MATERIALS * CD_MAX_MATERIALS];
    for (int k = 0; k < CD_MAX_MATERIALS * CD_MAX_MATERIALS; k++) in64[k] = inside[k];
    par_sum_int64s(in64, CD_MAX_MATERIALS * CD_MAX_MATERIALS);
    for (int k = 0; k < CD_MAX_MATERIALS * CD_MAX_MATERIALS; k++) inside[k] = (long)in64[k];
  }
  if (cd_pairs_by_distance(s->cfg.cutoff)) /* shifted: e_rc = 0, nothing is booked */
    for (int a = 0; a < s->nmat; a++)
      for (int b = 0; b < s->nmat; b++)
        broken +=
            s->pair[a][b]->e_rc * (double)(s->n_inside0[a][b] - inside[a * CD_MAX_MATERIALS + b]);
  out->kinetic = ke;
  out->potential = pe;
  out->dissipated = dissipated;
  out->broken = broken;
  out->piston_work = piston_work;
  out->total = ke + pe + dissipated + broken - piston_work;
  for (int a = 0; a < 3; a++) out->momentum[a] = mom[a];
}

void cd_sim_virial(cd_sim *s, double volume, double stress[6]) {
  const ptl_state *p = s->p;
  diag_ghosts(s);
  cd_compute_forces(s, s->sums, NULL, false);
  double w[6] = {0, 0, 0, 0, 0, 0};
  for (int l = 0; l < s->nl->nlayer; l++)
    for (int c = 0; c < 6; c++) w[c] += s->sums[l].vir[c];
  for (size_t i = 0; i < p->nlocal; i++) {
    if (p->flags[i] & PTL_REMOVED) continue;
    double mi = p->mass[i], v[3] = {p->vx[i], p->vy[i], p->vz[i]};
    w[0] += mi * v[0] * v[0];
    w[1] += mi * v[1] * v[1];
    w[2] += mi * v[2] * v[2];
    w[3] += mi * v[0] * v[1];
    w[4] += mi * v[1] * v[2];
    w[5] += mi * v[2] * v[0];
  }
  if (s->dd) par_sum_doubles(w, 6);
  for (int c = 0; c < 6; c++) stress[c] = w[c] / volume;
}

void cd_sim_particle_virial(cd_sim *s, double *w) {
  diag_ghosts(s);
  cd_compute_forces(s, s->sums, w, false);
}

double cd_von_mises(const double t[6]) {
  double a = t[0] - t[1], b = t[1] - t[2], c = t[2] - t[0];
  return sqrt(0.5 * (a * a + b * b + c * c + 6.0 * (t[3] * t[3] + t[4] * t[4] + t[5] * t[5])));
}

double cd_free_surface_velocity(const cd_sim *s, int axis) {
  const ptl_state *p = s->p;
  const double *v = axis == 0 ? p->vx : (axis == 1 ? p->vy : p->vz);
  double sum[2] = {0.0, 0.0}; /* Σ v, count */
  for (size_t i = 0; i < p->nlocal; i++)
    if ((p->flags[i] & PTL_SURFACE) && !(p->flags[i] & PTL_REMOVED)) {
      sum[0] += v[i];
      sum[1] += 1.0;
    }
  if (s->dd) par_sum_doubles(sum, 2);
  return sum[1] > 0 ? sum[0] / sum[1] : NAN;
}

/* ---- relaxation before the run (particles-cd.md "Polycrystals and the relaxation stage") ---- */

/* Sample lengths for the mean stress and density: the period along a periodic axis, else the
 * particles' extent plus one site spacing (the surface layers count half a spacing each);
 * 2D: the plane-strain thickness along z. Collective. */
static void sample_lengths(cd_sim *s, double len[3]) {
  const ptl_state *p = s->p;
  const double vsite = cd_cluster_volume(s->cfg.lattice, s->cfg.r0, s->cfg.thickness);
  const double spacing = p->dim == 2 ? sqrt(vsite / s->cfg.thickness) : cbrt(vsite);
  const double *xs[3] = {p->x, p->y, p->z};
  for (int a = 0; a < 3; a++) {
    if (p->dim == 2 && a == 2) {
      len[a] = s->cfg.thickness;
      continue;
    }
    if (s->box.bc[a] == CD_BC_PERIODIC) {
      len[a] = s->box.hi[a] - s->box.lo[a];
      continue;
    }
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < p->nlocal; i++) {
      if (p->flags[i] & PTL_REMOVED) continue;
      lo = fmin(lo, xs[a][i]);
      hi = fmax(hi, xs[a][i]);
    }
    if (s->dd) {
      lo = par_min_double(lo);
      hi = par_max_double(hi);
    }
    len[a] = hi - lo + spacing;
  }
}

/* Mean stress over the sample volume (returned) and the volume. Collective. */
static double sample_stress(cd_sim *s, double stress[6]) {
  double len[3];
  sample_lengths(s, len);
  const double vol = len[0] * len[1] * len[2];
  cd_sim_virial(s, vol, stress);
  return vol;
}

ms_status cd_sim_relax(cd_sim *s, const cd_relax_config *rc, cd_relax_result *out) {
  ptl_state *p = s->p;
  memset(out, 0, sizeof *out);
  if (!(rc->time >= 0.0) || (rc->box && !(rc->modulus > 0.0 && rc->tau > 0.0))) return MS_ERR_INPUT;
  cd_energy e0;
  cd_sim_energy(s, &e0);
  out->volume0 = sample_stress(s, out->stress0);
  double mass = 0.0;
  for (size_t i = 0; i < p->nlocal; i++)
    if (!(p->flags[i] & PTL_REMOVED)) mass += p->mass[i];
  out->mass = s->dd ? par_sum_double(mass) : mass;
  /* the piston stands still (an empty history is u = 0); the relaxation's damping */
  const size_t piston_n = s->piston.n;
  const double gamma_run = s->cfg.damping_gamma;
  s->piston.n = 0;
  s->cfg.damping_gamma = rc->damping_gamma;
  if (rc->damping_gamma > 0.0 && !s->scratch)
    s->scratch = ms_aligned_alloc(3 * p->cap, sizeof(double));
  const double diss0 = s->dissipated;
  const long broken0 = s->n_broken_bonds;
  /* plain: every pair inside R_c interacts (grain boundaries attract and close); the partner
   * lists are set aside and the lists rebuilt without bond flags */
  int32_t *const partners = s->partners;
  const cd_cutoff_mode mode = s->cfg.cutoff;
  ms_status st = MS_OK;
  if (rc->plain && mode == CD_CUTOFF_BONDED) {
    s->partners = NULL;
    s->cfg.cutoff = CD_CUTOFF_PLAIN;
    st = cd_rebuild_lists(s, false);
    if (st == MS_OK) cd_step_forces(s);
  }
  if (st == MS_OK) st = cd_half_lists_unless_fit(s);
  const long nsteps = (long)ceil(rc->time / s->cfg.dt - 1e-9);
  const long every = rc->box_every > 0 ? rc->box_every : 10;
  const double max_strain = rc->max_strain > 0.0 ? rc->max_strain : 1e-3;
  for (int a = 0; a < 3; a++) out->lambda[a] = 1.0;
  double quenched = 0.0;
  for (long k = 1; k <= nsteps && st == MS_OK; k++) {
    st = cd_sim_step(s);
    if (st != MS_OK) break;
    if (rc->quench) { /* stop every particle moving against its force (its kinetic energy goes) */
      const long n = (long)p->nlocal;
#pragma omp parallel for schedule(static) reduction(+ : quenched) if (CD_PAR(n))
      for (long i = 0; i < n; i++) {
        if (p->vx[i] * p->fx[i] + p->vy[i] * p->fy[i] + p->vz[i] * p->fz[i] >= 0.0) continue;
        const double v2 = p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i] + p->vz[i] * p->vz[i];
        quenched += 0.5 * p->mass[i] * v2;
        p->vx[i] = p->vy[i] = p->vz[i] = 0.0;
      }
    }
    if (rc->box && k % every == 0) {
      /* Berendsen-like: strain each axis by (k Δt/τ)·P_aa/M toward P_aa = 0 (compression
       * positive: a compressed sample expands), at most max_strain per rescale */
      double sig[6], lam[3] = {1.0, 1.0, 1.0};
      sample_stress(s, sig);
      for (int a = 0; a < p->dim; a++) {
        if (s->box.bc[a] == CD_BC_WALL) continue;
        const double e = (double)every * s->cfg.dt / rc->tau * sig[a] / rc->modulus;
        lam[a] = 1.0 + fmax(-max_strain, fmin(max_strain, e));
        out->lambda[a] *= lam[a];
      }
      st = cd_sim_affine(s, lam);
    }
  }
  out->steps = s->step;
  out->quenched = s->dd ? par_sum_double(quenched) : quenched;
  const double damped = s->dissipated - diss0;
  out->dissipated = (s->dd ? par_sum_double(damped) : damped) + out->quenched;
  out->broken_bonds =
      s->dd ? par_sum_long(s->n_broken_bonds - broken0) : s->n_broken_bonds - broken0;
  s->piston.n = piston_n;
  s->cfg.damping_gamma = gamma_run;
  s->partners = partners;
  s->cfg.cutoff = mode;
  if (st != MS_OK) return st;
  /* at rest, the clock and the balance start here; bonded: the partners of the relaxed packing */
  for (size_t i = 0; i < p->n; i++) p->vx[i] = p->vy[i] = p->vz[i] = 0.0;
  if ((rc->rebond || rc->plain) && mode == CD_CUTOFF_BONDED) st = cd_form_partners(s);
  if (st != MS_OK) return st;
  s->t = 0.0;
  s->step = 0;
  s->dissipated = s->piston_work = s->broken_bonded = 0.0;
  s->n_broken_bonds = 0;
  cd_count_inside0(s);
  cd_step_forces(s);
  cd_energy e1;
  cd_sim_energy(s, &e1);
  out->energy = e0.kinetic + e0.potential - e1.potential;
  out->volume = sample_stress(s, out->stress);
  return MS_OK;
}
