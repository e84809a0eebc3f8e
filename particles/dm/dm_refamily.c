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
  if (f->m->xref) return dm_fin_local_max_stretch(f, where);
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

/* κ_i/2 Σ_k |z_ik|², z_ik = (x_k − x_i) − F_i ξ_ik, with F of the last force evaluation. */
static double penalty_stored_one(const dm_fin *f, size_t i) {
  const dm_model *m = f->m;
  const double *w = m->s->w;
  {
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
    return 0.5 * m->kappa[i] * zz;
  }
}

/* Σ_i κ_i/2 Σ_k |z_ik|², of the full body with symmetry planes (dm_fin_fold) */
static double penalty_stored(const dm_fin *f) {
  double E = 0;
  for (size_t i = 0; i < f->n; ++i) E += dm_fin_fold(f, i) * penalty_stored_one(f, i);
  return E;
}

/* The reference moves to the current configuration: X ← X + w, w ← 0, V ← J V (ρ = m/V stays
 * the current density); the old X, w (6n) and V (n) saved in keep for a refusal; J's range in
 * rep. */
static void move_reference(dm_fin *f, double *keep, dm_refamily_report *rep) {
  dm_state *s = f->m->s;
  const size_t n = f->n;
  double jmin = INFINITY, jmax = 0;
  for (size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      keep[6 * i + a] = s->X[3 * i + a], keep[6 * i + 3 + a] = s->w[3 * i + a];
      s->X[3 * i + a] += s->w[3 * i + a];
      s->w[3 * i + a] = 0.0;
    }
    keep[6 * n + i] = s->vol[i];
    s->vol[i] *= f->J[i];
    jmin = fmin(jmin, f->J[i]), jmax = fmax(jmax, f->J[i]);
  }
  rep->jmin = jmin, rep->jmax = jmax;
}

/* A refused update: the old X, w and V back from keep. */
static void restore_reference(dm_state *s, size_t n, const double *keep) {
  for (size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a)
      s->X[3 * i + a] = keep[6 * i + a], s->w[3 * i + a] = keep[6 * i + 3 + a];
    s->vol[i] = keep[6 * n + i];
  }
}

ms_status dm_fin_reference_update(dm_fin *f, const ms_ctx *ctx, dm_refamily_report *rep) {
  dm_model *old = f->m;
  dm_state *s = old->s;
  const size_t n = f->n;
  memset(rep, 0, sizeof *rep);
  /* fracture's per-bond contact state (dm_fracture.c: rest lengths, dashpot) is indexed by the
   * old families' bonds: not carried over to new families (yet), so no update with fracture */
  if (f->failed || old->xref) return MS_ERR_INTERNAL; /* xref: dm_fin_rebase_local's */
  const ms_status fl = dm_fin_flush(f);               /* at the families it is about to replace */
  if (fl != MS_OK) return fl;
  rep->released = penalty_stored(f);
  double *keep = ms_calloc(7 * (n ? n : 1), sizeof(double)); /* X, w, V to restore on refusal */
  move_reference(f, keep, rep);
  /* symmetry planes: the ghosts of the new reference (which particles lie within a horizon of
   * a plane has changed); the state's arrays are reallocated */
  if (f->sym.n) dm_sym_ghosts(s, n, &f->sym, old->opt.horizon, f->par.ell);
  dm_model *m = NULL;
  size_t bad = (size_t)-1;
  ms_status st = dm_model_create(
      &(dm_model_params){.state = s, .opt = old->opt, .ctx = ctx, .first_bad = &bad}, &m);
  if (st != MS_OK) { /* refused: the old reference stays, the caller stops the run */
    restore_reference(s, n, keep);
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

/* The bond lists of a model (CSR), kept to restore a refused update. */
typedef struct bond_lists {
  size_t *start, nbonds;
  uint32_t *nbr;
  uint8_t *img;
} bond_lists;

/* Adds to each family the particles now within the horizon of the current configuration (X
 * already moved to x): the union of two symmetric neighbour relations is symmetric, and the
 * old members keep the family as well conditioned as F A Fᵀ. Both lists are sorted by
 * (neighbour, image), so a merge keeps dm_family.c's fixed summation order. The old lists go
 * to *old (the caller frees or restores them). */
static ms_status merge_families(dm_model *m, const ms_ctx *ctx, bond_lists *old) {
  dm_model t = {.s = m->s, .opt = m->opt};
  const ms_status st = dm_build_families(&t, ctx);
  if (st != MS_OK) {
    free(t.start), free(t.nbr), free(t.img);
    return st;
  }
  const size_t n = m->s->n;
  size_t *start = ms_calloc(n + 1, sizeof(size_t));
  uint32_t *nbr = ms_calloc(m->nbonds + t.nbonds + 1, sizeof(uint32_t));
  uint8_t *img = ms_calloc(m->nbonds + t.nbonds + 1, sizeof(uint8_t));
  size_t c = 0;
  for (size_t i = 0; i < n; ++i) {
    size_t a = m->start[i], b = t.start[i];
    const size_t ae = m->start[i + 1], be = t.start[i + 1];
    while (a < ae || b < be) {
      const uint64_t ka = a < ae ? ((uint64_t)m->nbr[a] << 8 | m->img[a]) : UINT64_MAX;
      const uint64_t kb = b < be ? ((uint64_t)t.nbr[b] << 8 | t.img[b]) : UINT64_MAX;
      const uint64_t k = ka < kb ? ka : kb;
      nbr[c] = (uint32_t)(k >> 8), img[c] = (uint8_t)(k & 0xff), ++c;
      if (ka == k) ++a;
      if (kb == k) ++b;
    }
    start[i + 1] = c;
  }
  free(t.start), free(t.nbr), free(t.img);
  *old = (bond_lists){.start = m->start, .nbonds = m->nbonds, .nbr = m->nbr, .img = m->img};
  m->start = start, m->nbr = nbr, m->img = img, m->nbonds = c;
  return MS_OK;
}

ms_status dm_fin_rebase(dm_fin *f, const ms_ctx *ctx, bool merge, dm_refamily_report *rep) {
  dm_model *m = f->m;
  dm_state *s = m->s;
  const size_t n = f->n;
  memset(rep, 0, sizeof *rep);
  if (f->failed || m->xref) return MS_ERR_INTERNAL; /* as dm_fin_reference_update */
  const ms_status fl = dm_fin_flush(f);
  if (fl != MS_OK) return fl;
  /* keep: X, w (6n), V (n) to restore on refusal, and each family's stored penalty energy (n),
   * measured at the old reference */
  double *keep = ms_calloc(8 * (n ? n : 1), sizeof(double)), *Ehg = keep + 7 * n;
  for (size_t i = 0; i < n; ++i) Ehg[i] = penalty_stored_one(f, i);
  move_reference(f, keep, rep);
  size_t bad = (size_t)-1;
  bond_lists old = {0};
  ms_status st = MS_OK;
  if (f->sym.n) { /* the ghosts follow their partners on the set-up's ghost set, which the kept
                   * lists index; a merge needs every image within the horizon among them */
    dm_sym_reference(s, n, &f->sym);
    dm_sym_sync(f);
    dm_sym_map mp;
    dm_sym_map_build(f, &mp);
    bad = merge ? dm_sym_uncovered(f, &mp, m->opt.horizon) : SIZE_MAX;
    dm_sym_map_free(&mp);
    if (bad != SIZE_MAX) rep->uncovered = true, st = MS_ERR_UNSTABLE;
  }
  if (st == MS_OK && merge) st = merge_families(m, ctx, &old);
  rep->bonds = m->nbonds;
  if (st == MS_OK && dm_build_shape(m, ctx, &bad) != MS_OK) st = MS_ERR_UNSTABLE;
  if (st != MS_OK) { /* refused (cond F A Fᵀ > cond_max): the old reference and families */
    restore_reference(s, n, keep);
    if (f->sym.n) dm_sym_reference(s, n, &f->sym), dm_sym_sync(f);
    if (old.start) {
      free(m->start), free(m->nbr), free(m->img);
      m->start = old.start, m->nbr = old.nbr, m->img = old.img, m->nbonds = old.nbonds;
    }
    free(keep);
    dm_build_shape(m, ctx, NULL);
    dm_fin_bond_penalty(f);
    rep->bad = bad;
    return st;
  }
  free(old.start), free(old.nbr), free(old.img);
  /* the penalty's stored energy of each family becomes the particle's heat: K + U + E_hg is
   * unchanged, E_hg drops by what it releases */
  for (size_t i = 0; i < n; ++i)
    f->e[i] += Ehg[i] / s->mass[i], f->ehg[i] -= Ehg[i],
        rep->released += dm_fin_fold(f, i) * Ehg[i]; /* full body */
  free(keep);
  dm_fin_bond_penalty(f);
  if (f->sr) dm_pair_stiffness(f, f->sr->kc, f->par.ell); /* the short-range κc: V changed */
  for (size_t i = 0; i < n; ++i) f->J[i] = 1.0;
  return dm_fin_refresh(f);
}
