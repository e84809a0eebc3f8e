/* SPDX-License-Identifier: MIT */
/* dm_refamily.c — the reference-configuration update of the finite-deformation discrete model
 * (docs/particles-dm.md, "Reference update"; docs/design.md §9): the total-Lagrangian families
 * and shape matrices are rebuilt on the current configuration when a bond has stretched or
 * shortened by more than a threshold, as LAMMPS smd/tlsph does [Ganzenmuller2015]:
 *   X ← x = X + w,  w ← 0 (so F ← I),  V ← J V = m/ρ,  families and A⁻¹ from the new X,
 * with the Cauchy deviator s, the plastic strain, e and the velocities kept. ρ = m/V is then
 * unchanged, so p(ρ, e) and σ are continuous across the update; the next forces differ only by
 * the new families' quadrature and by the bond penalty, whose stored energy Σ κ|z|²/2 becomes
 * unrecoverable (reported as released; the accumulated E_hg of the energy balance is the
 * penalty's work and stays). Rule for a degenerate new family (fewer or coplanar neighbours,
 * λ_max/λ_min of A above cond_max): the update is refused, the old state restored and the run
 * stops with the particle, its position, its neighbour count and the condition number
 * (MS_ERR_UNSTABLE) — never a silent NaN. J ≤ 0 already stops dm_fin_step. */
#include "dm_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

double dm_fin_max_stretch(const dm_fin *f, size_t *where) {
  const dm_model *m = f->m;
  const double *w = m->s->w;
  const long n = (long)f->n;
  double lmax = 1.0;
  long at = 0;
#pragma omp parallel
  {
    double lm = 1.0;
    long am = 0;
#pragma omp for schedule(static) nowait
    for (long i = 0; i < n; ++i)
      for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
        const size_t k = m->nbr[b];
        double xi[3], r0 = 0, r1 = 0;
        dm_bond_vector(m, (size_t)i, b, xi);
        for (int a = 0; a < 3; ++a) {
          const double d = xi[a] + w[3 * k + a] - w[3 * i + a];
          r0 += xi[a] * xi[a], r1 += d * d;
        }
        /* stretch of the bond or of its inverse: max(|x_k − x_i|/|ξ|, |ξ|/|x_k − x_i|) */
        const double l = r1 > r0 ? sqrt(r1 / r0) : (r1 > 0 ? sqrt(r0 / r1) : INFINITY);
        if (l > lm || (l == lm && i < am)) lm = l, am = i;
      }
#pragma omp critical
    if (lm > lmax || (lm == lmax && am < at)) lmax = lm, at = am;
  }
  if (where) *where = (size_t)at;
  return lmax;
}

/* Σ_i κ_i/2 Σ_k |z_ik|², z_ik = (x_k − x_i) − F_i ξ_ik, with F of the last force evaluation. */
static double penalty_stored(const dm_fin *f) {
  const dm_model *m = f->m;
  const double *w = m->s->w;
  double E = 0;
  for (size_t i = 0; i < f->n; ++i) {
    const double *F = &f->F[9 * i];
    double zz = 0;
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
      const size_t k = m->nbr[b];
      double xi[3];
      dm_bond_vector(m, i, b, xi);
      for (int a = 0; a < 3; ++a) {
        const double z = xi[a] + w[3 * k + a] - w[3 * i + a] -
                         (F[3 * a] * xi[0] + F[3 * a + 1] * xi[1] + F[3 * a + 2] * xi[2]);
        zz += z * z;
      }
    }
    E += dm_fin_fold(f, i) * 0.5 * m->kappa[i] * zz;
  }
  return E;
}

ms_status dm_fin_reference_update(dm_fin *f, const ms_ctx *ctx, dm_refamily_report *rep) {
  dm_model *old = f->m;
  dm_state *s = old->s;
  const size_t n = f->n;
  memset(rep, 0, sizeof *rep);
  /* fracture's per-bond contact state (dm_fracture.c: rest lengths, dashpot) is indexed by the
   * old families' bonds: not carried over to new families (yet), so no update with fracture */
  if (f->failed) return MS_ERR_INTERNAL;
  const ms_status fl = dm_fin_flush(f); /* at the families it is about to replace */
  if (fl != MS_OK) return fl;
  rep->released = penalty_stored(f);
  double *keep = ms_calloc(7 * (n ? n : 1), sizeof(double)); /* X, w, V to restore on refusal */
  double jmin = INFINITY, jmax = 0;
  for (size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      keep[6 * i + a] = s->X[3 * i + a], keep[6 * i + 3 + a] = s->w[3 * i + a];
      s->X[3 * i + a] += s->w[3 * i + a];
      s->w[3 * i + a] = 0.0;
    }
    keep[6 * n + i] = s->vol[i];
    s->vol[i] *= f->J[i]; /* V ← J V: ρ = m/V is the current density */
    jmin = fmin(jmin, f->J[i]), jmax = fmax(jmax, f->J[i]);
  }
  rep->jmin = jmin, rep->jmax = jmax;
  /* symmetry planes: the ghosts of the new reference (which particles lie within a horizon of
   * a plane has changed); the state's arrays are reallocated */
  if (f->sym.n) dm_sym_ghosts(s, n, &f->sym, old->opt.horizon, f->par.ell);
  dm_model *m = NULL;
  size_t bad = (size_t)-1;
  ms_status st = dm_model_create(
      &(dm_model_params){.state = s, .opt = old->opt, .ctx = ctx, .first_bad = &bad}, &m);
  if (st != MS_OK) { /* refused: the old reference stays, the caller stops the run */
    for (size_t i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a)
        s->X[3 * i + a] = keep[6 * i + a], s->w[3 * i + a] = keep[6 * i + 3 + a];
      s->vol[i] = keep[6 * n + i];
    }
    if (f->sym.n) dm_sym_ghosts(s, n, &f->sym, old->opt.horizon, f->par.ell); /* the old set */
    dm_sym_sync(f);
    free(keep);
    rep->bad = bad;
    return MS_ERR_UNSTABLE;
  }
  free(keep);
  m->prescribe = old->prescribe, m->prescribe_user = old->prescribe_user;
  f->m = m;
  dm_model_destroy(&old);
  if (f->sym.n) dm_sym_resize(f, f->imat_all); /* v̄, v_close, materials of the new ghosts */
  dm_fin_bond_penalty(f);
  if (f->sr) dm_pair_stiffness(f, f->sr->kc, f->par.ell); /* the short-range κc: V changed */
  rep->bonds = m->nbonds;
  for (size_t i = 0; i < n; ++i) f->J[i] = 1.0; /* J is now relative to the new reference */
  return dm_fin_refresh(f);
}
