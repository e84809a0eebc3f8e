/* SPDX-License-Identifier: MIT */
/* dm_fin_local.c — the per-family reference update of the finite-deformation discrete model
 * (docs/particles-dm.md "Reference update", per family; docs/design.md §9). The global update
 * of dm_refamily.c moves one reference X for every particle, so the bond that stretches
 * fastest anywhere sets the interval of every family. Here each family has its own reference:
 * bond b = i → k keeps its own vector ξ_b (m->xref), set when family i was last updated, and
 * only the families whose own bonds have stretched past 1 + threshold are updated.
 *
 * The model with per-family references. Family i's deformation gradient is the least-squares
 * fit over its own bonds, F_i = (Σ_b Δx_b ⊗ ξ_b) A_i⁻¹, A_i = Σ_b ξ_b ⊗ ξ_b, and its mismatch
 * z_b = Δx_b − F_i ξ_b = Δw_b − C_i ξ_b with Δw_b = Δx_b − ξ_b (C = F − I); its work
 * conjugate, the bond force t_b = Q_i ξ_b + κ_i Δw_b (Q_i = V_i P_i A_i⁻¹ − κ_i C_i), acts on i
 * and −t_b on k. So
 *   f_i = Σ_{b ∈ N_i} (t_b − t_rev(b)),   rev(b) = the bond k → i of family k,
 * which with one shared reference (ξ_rev = −ξ_b) is dm_finite.c's gather, and
 *   Σ_i f_i·ū_i = −Σ_i [V_i P_i : Ḟ_i(ū) + κ_i Σ_b z_b·Δū_b]   for any ū,
 * the energy identity of dm_finite.c term by term: the kicks' energy increments (Bv, sv over
 * each family's own ξ and Δw) keep K + U + E_hg − W at round-off, and the pair t_b, −t_b keeps
 * Σ m u exact. Families stay symmetric as sets (k ∈ N_i ⇔ i ∈ N_k), each bond direction with
 * its own vector.
 *
 * The update of the families U = {i : max_b max(|Δx_b|/|ξ_b|, |ξ_b|/|Δx_b|) > 1 + threshold}:
 * for i ∈ U, ξ_b ← Δx_b (so F_i ← I, z ← 0), V_i ← J_i V_i (ρ, p and the Cauchy deviator
 * continuous, as the global update), A_i⁻¹ and κ_i from the new vectors; the stored penalty
 * energy κ_i Σ|z|²/2 becomes the particle's heat (e += E/m, E_hg −= E: the balance unchanged).
 * merge: family i ∈ U also bonds the particles within the horizon of x_i, and each of them
 * (k ∉ U) gets the bond back with the vector F_k⁻¹ Δx (zero mismatch: its F_k, J_k, stress and
 * stored energy do not change; its κ_k = c_s M V_k / tr A_k drops with the larger family and
 * what that releases of its stored energy, E_k (1 − κ_new/κ_old), becomes its heat). The other
 * families are untouched. Refused (MS_ERR_UNSTABLE, nothing changed, rep->bad) when a changed
 * family's cond A exceeds cond_max. Not with fracture or the short-range contact
 * (MS_ERR_INTERNAL, nothing changed: their per-bond state belongs to one shared reference).
 * Periodic boxes (dm_family.c's images): bond b keeps its image s_b, so Δx_b = X_k + s_b − X_i +
 * w_k − w_i is the minimum-image bond for as long as the families are kept (the box is at least
 * 3 horizons, the bond shorter than a horizon, so its image is the nearest one while |Δx| stays
 * under half the box: what a stretch past 1 + threshold triggers long before), ξ_b ← Δx_b at an
 * update includes it, and the reverse bond of b is the one with the opposite image (build_rev).
 * merge with a box is refused (MS_ERR_INTERNAL): new_pairs would need the images of the new
 * pairs. Symmetry planes: the ghosts' rows hold the reverse bonds, the merged pairs are closed
 * under the reflections (dm_sym_family.c). */
#include "dm_vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Bond b of family i: its vector ξ in the family's reference and Δw = Δx − ξ. */
void dm_fin_local_bond(const dm_model *m, const double *w, size_t i, size_t b, double xi[3],
                       double dw[3]) {
  const double *X = m->s->X, *R = &m->xref[3 * b], *sh = m->shift[m->img[b]];
  const size_t k = m->nbr[b];
  for (int a = 0; a < 3; ++a) {
    xi[a] = R[a];
    dw[a] = (X[3 * k + a] + sh[a] - X[3 * i + a] - R[a]) + (w[3 * k + a] - w[3 * i + a]);
  }
}

/* dm_finite.c's bond_moments with each family's own ξ_b: Δw_b = (ΔX_b − ξ_b) + (w_k − w_i),
 * the first term the family's offset from the lattice (0 until its first update). */
MS_KERNEL_INLINE static inline void moments_ref(const dm_model *restrict m, size_t i,
                                                const double *restrict w, const double *restrict u,
                                                const double *restrict vb,
                                                const double *restrict vc, double dt, bool stress,
                                                bool kick, bool close, moments *restrict M) {
  const double *restrict X = m->s->X, *restrict R = m->xref;
  const v4d zero = {0}, x0 = ld4(&X[3 * i]), wi = ld4(&w[3 * i]);
  const v4d ui = stress ? ld4(&u[3 * i]) : zero;
  const v4d vi = kick ? ld4(&vb[3 * i]) : zero, ci = close ? ld4(&vc[3 * i]) : zero;
  const v4d wn = wi + dt * ui;
  v4d aw0 = zero, aw1 = zero, aw2 = zero, au0 = zero, au1 = zero, au2 = zero;
  v4d av0 = zero, av1 = zero, av2 = zero, s4 = zero;
  v4d ac0 = zero, ac1 = zero, ac2 = zero, c4 = zero;
  const size_t e = m->start[i + 1];
  for (size_t b = m->start[i]; b < e; ++b) {
    const size_t k = m->nbr[b];
    const v4d xi = ld4(&R[3 * b]);
    const v4d d = ld4(&X[3 * k]) + ld4(m->shift4[m->img[b]]) - x0 - xi;
    const v4d x = bc4(xi[0]), y = bc4(xi[1]), z = bc4(xi[2]);
    const v4d wk = ld4(&w[3 * k]);
    if (stress) {
      const v4d uk = ld4(&u[3 * k]), dw = d + (wk + dt * uk - wn), du = uk - ui;
      aw0 += dw * x, aw1 += dw * y, aw2 += dw * z;
      au0 += du * x, au1 += du * y, au2 += du * z;
    }
    if (kick) {
      const v4d dv = ld4(&vb[3 * k]) - vi;
      av0 += dv * x, av1 += dv * y, av2 += dv * z;
      s4 += dv * (d + (wk - wi));
    }
    if (close) {
      const v4d dc = ld4(&vc[3 * k]) - ci;
      ac0 += dc * x, ac1 += dc * y, ac2 += dc * z;
      c4 += dc * (d + (wk - wi));
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (stress) {
      M->Bw[3 * a] = aw0[a], M->Bw[3 * a + 1] = aw1[a], M->Bw[3 * a + 2] = aw2[a];
      M->Bu[3 * a] = au0[a], M->Bu[3 * a + 1] = au1[a], M->Bu[3 * a + 2] = au2[a];
    }
    if (kick) M->Bv[3 * a] = av0[a], M->Bv[3 * a + 1] = av1[a], M->Bv[3 * a + 2] = av2[a];
    if (close) M->Bc[3 * a] = ac0[a], M->Bc[3 * a + 1] = ac1[a], M->Bc[3 * a + 2] = ac2[a];
  }
  if (kick) M->sv = s4[0] + s4[1] + s4[2];
  if (close) M->sc = c4[0] + c4[1] + c4[2];
}

/* One loop per combination of the flags dm_finite.c uses (constants there). */
MS_KERNEL_CLONES void dm_fin_local_moments(const dm_model *m, size_t i, const double *w,
                                           const double *u, const double *vb, const double *vc,
                                           double dt, bool stress, bool kick, bool close,
                                           moments *M) {
  if (stress && kick && close) moments_ref(m, i, w, u, vb, vc, dt, true, true, true, M);
  else if (stress && kick) moments_ref(m, i, w, u, vb, NULL, dt, true, true, false, M);
  else if (stress) moments_ref(m, i, w, u, NULL, NULL, dt, true, false, false, M);
  else moments_ref(m, i, w, NULL, NULL, vc, dt, false, false, true, M);
}

/* f_i = Σ_b [Q_i ξ_b + κ_i Δw_b − Q_k ξ_rev − κ_k Δw_rev] (the head of this file), with
 * Δw_b = d_b + (w_k − w_i), d_b = ΔX_b − ξ_b, and Δw_rev = d_rev − (w_k − w_i),
 * d_rev = ΔX_rev − ξ_rev, ΔX_b = X_k + s_b − X_i with the bond's periodic shift s_b (0 without
 * a periodic box) and ΔX_rev = X_i + s_rev − X_k = −ΔX_b: the reverse bond's image is the
 * opposite one, s_rev = −s_b (build_rev).
 * m->Q holds each Q transposed (dm_finite.c). */
MS_KERNEL_CLONES void dm_fin_local_gather(const dm_model *m, const double *w, size_t i, double *F) {
  const double *restrict X = m->s->X, *restrict QT = m->Q, *restrict kap = m->kappa;
  const double *restrict R = m->xref;
  const double ki = kap[i];
  const v4d zero = {0}, wi = ld4(&w[3 * i]), x0 = ld4(&X[3 * i]);
  v4d r0 = zero, r1 = zero, r2 = zero, fw = zero, sxi = zero;
  const size_t e = m->start[i + 1];
  for (size_t b = m->start[i]; b < e; ++b) {
    const size_t k = m->nbr[b];
    const size_t r = m->rev[b];
    const v4d xi = ld4(&R[3 * b]), xr = ld4(&R[3 * r]);
    const v4d dX = ld4(&X[3 * k]) + ld4(m->shift4[m->img[b]]) - x0, dw = ld4(&w[3 * k]) - wi;
    /* the reverse bond's ΔX as family k computes it: with an image, X_i + s_rev − X_k is not
     * bit for bit −ΔX_b, and the pair's forces cancel exactly only with the same bits (without
     * one it is: a − b = −(b − a)) */
    const v4d dXr = x0 + ld4(m->shift4[m->img[r]]) - ld4(&X[3 * k]);
    const double *q = &QT[9 * k];
    r0 -= bc4(xr[0]) * ld4(q), r1 -= bc4(xr[1]) * ld4(q + 3), r2 -= bc4(xr[2]) * ld4(q + 6);
    const double kk = kap[k];
    fw += bc4(ki + kk) * dw + bc4(ki) * (dX - xi) + bc4(kk) * (xr - dXr);
    sxi += xi;
  }
  const double *qi = &QT[9 * i];
  for (int a = 0; a < 3; ++a)
    F[3 * i + a] =
        r0[a] + r1[a] + r2[a] + fw[a] + qi[a] * sxi[0] + qi[3 + a] * sxi[1] + qi[6 + a] * sxi[2];
}

/* The largest stretch max(|Δx|/|ξ|, |ξ|/|Δx|) of family i's bonds (before the first update:
 * against the shared reference). */
static double family_stretch(const dm_model *m, size_t i) {
  const double *w = m->s->w;
  double lm = 1.0;
  for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
    double xi[3], dw[3], r0 = 0, r1 = 0;
    if (m->xref) dm_fin_local_bond(m, w, i, b, xi, dw);
    else {
      dm_bond_vector(m, i, b, xi);
      for (int a = 0; a < 3; ++a) dw[a] = w[3 * m->nbr[b] + a] - w[3 * i + a];
    }
    for (int a = 0; a < 3; ++a) {
      const double d = xi[a] + dw[a];
      r0 += xi[a] * xi[a], r1 += d * d;
    }
    const double l = r1 > r0 ? sqrt(r1 / r0) : (r1 > 0 ? sqrt(r0 / r1) : INFINITY);
    lm = fmax(lm, l);
  }
  return lm;
}

double dm_fin_local_max_stretch(const dm_fin *f, size_t *where) {
  double lmax = 1.0;
  long at = 0;
#pragma omp parallel
  {
    double lm = 1.0;
    long am = 0;
#pragma omp for schedule(static) nowait
    for (long i = 0; i < (long)f->n; ++i) {
      const double l = family_stretch(f->m, (size_t)i);
      if (l > lm) lm = l, am = i;
    }
#pragma omp critical
    if (lm > lmax || (lm == lmax && am < at)) lmax = lm, at = am;
  }
  if (where) *where = (size_t)at;
  return lmax;
}

/* κ_i/2 Σ_b |z_b|², z_b = Δw_b − (F_i − I) ξ_b with F of the last force evaluation. */
static double stored_one(const dm_fin *f, size_t i) {
  const dm_model *m = f->m;
  const double *F = &f->F[9 * i];
  double zz = 0;
  for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
    double xi[3], dw[3];
    dm_fin_local_bond(m, m->s->w, i, b, xi, dw);
    for (int a = 0; a < 3; ++a) {
      const double z =
          xi[a] + dw[a] - (F[3 * a] * xi[0] + F[3 * a + 1] * xi[1] + F[3 * a + 2] * xi[2]);
      zz += z * z;
    }
  }
  return 0.5 * m->kappa[i] * zz;
}

/* The first per-family update: every family's vectors from the shared reference (ξ_b = ΔX_b,
 * the same bits as dm_bond_vector, so that nothing but round-off order changes) and rev. */
static void init_xref(dm_model *m) {
  m->xref = ms_calloc(3 * m->nbonds + 1, sizeof(double));
  for (size_t i = 0; i < m->s->n; ++i)
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) dm_bond_vector(m, i, b, &m->xref[3 * b]);
}

/* rev[b] for every bond b = i → k (image c): the position of (i, 26 − c) in k's list, sorted by
 * (neighbour, image) (dm_family.c; families symmetric). Image c = (s_x+1) + 3(s_y+1) + 9(s_z+1)
 * for the shift s ∈ {−1, 0, 1}³ boxes, so 26 − c is the opposite shift: across a periodic
 * boundary the reverse bond is the one to the other image (with a box of at least 3 horizons a
 * pair has one bond, but matching the image keeps rev right without relying on that). img NULL:
 * every bond's image is 13 (no box). */
static ms_status build_rev(const dm_model *m, const size_t *start, const uint32_t *nbr,
                           const uint8_t *img, size_t *rev) {
  const long n = (long)m->s->n;
  long bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad)
  for (long i = 0; i < n; ++i)
    for (size_t b = start[i]; b < start[i + 1]; ++b) {
      size_t lo = start[nbr[b]], hi = start[nbr[b] + 1];
      while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (nbr[mid] < (uint32_t)i) lo = mid + 1;
        else hi = mid;
      }
      const uint8_t want = img ? (uint8_t)(26 - img[b]) : 13;
      while (img && lo < start[nbr[b] + 1] && nbr[lo] == (uint32_t)i && img[lo] != want) ++lo;
      if (lo < start[nbr[b] + 1] && nbr[lo] == (uint32_t)i) rev[b] = lo;
      else ++bad;
    }
  return bad ? MS_ERR_INTERNAL : MS_OK;
}

ms_status dm_fin_local_rev(dm_model *m) {
  free(m->rev);
  m->rev = ms_calloc(m->nbonds + 1, sizeof(size_t));
  const ms_status st = build_rev(m, m->start, m->nbr, m->img, m->rev);
  if (st != MS_OK) free(m->rev), m->rev = NULL;
  return st;
}

ms_status dm_fin_local_init(dm_fin *f) {
  dm_model *m = f->m;
  if (m->xref) return MS_OK;
  ms_status st = MS_OK;
  if (f->sym.n) { /* the ghosts' rows: the reverse bonds of the real ones (dm_sym_family.c) */
    size_t *from = NULL;
    dm_sym_ghost_rows(m->s->n, f->n, &m->start, &m->nbr, &from, &m->nbonds);
    uint8_t *img = ms_calloc(m->nbonds + 1, 1);
    for (size_t c = 0; c < m->nbonds; ++c) img[c] = from[c] != SIZE_MAX ? m->img[from[c]] : 13;
    free(m->img), free(from);
    m->img = img;
  }
  init_xref(m);
  if (f->sym.n) {
    dm_sym_map mp;
    dm_sym_map_build(f, &mp);
    st = dm_sym_ghost_xref(f, &mp, m->start, m->nbr, m->xref);
    dm_sym_map_free(&mp);
  }
  m->rev = ms_calloc(m->nbonds + 1, sizeof(size_t));
  if (st == MS_OK) st = build_rev(m, m->start, m->nbr, m->img, m->rev);
  if (st != MS_OK) free(m->xref), free(m->rev), m->xref = NULL, m->rev = NULL;
  return st;
}

/* Is k in family i (sorted by neighbour)? */
static bool in_family(const dm_model *m, size_t i, uint32_t k) {
  size_t lo = m->start[i], hi = m->start[i + 1];
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (m->nbr[mid] < k) lo = mid + 1;
    else hi = mid;
  }
  return lo < m->start[i + 1] && m->nbr[lo] == k;
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* merge: the particles within the horizon of the current x_i (|x_k − x_i| < δ, as
 * dm_family.c's test on the reference) of each updated family i that are not in it yet, as
 * sorted unique pairs (row << 32 | column), both directions. Returns their number. */
static size_t new_pairs(const dm_fin *f, const size_t *list, size_t nl, uint64_t **out) {
  const dm_model *m = f->m;
  const dm_state *s = m->s;
  const double *X = s->X, *w = s->w, h2 = m->opt.horizon * m->opt.horizon;
  dm_cells cl;
  *out = NULL;
  /* the mirror ghosts too (symmetry planes): a family near a plane bonds across it */
  if (dm_cells_init(&cl, s->n, f->dim, m->opt.horizon, NULL, m->opt.box) != MS_OK) return 0;
  dm_cells_build(&cl, X, w);
  size_t np = 0, cap = 64;
  uint64_t *pr = ms_calloc(cap, sizeof *pr);
  for (size_t q = 0; q < nl; ++q) {
    const size_t i = list[q];
    const long *ci = &cl.cidx[3 * i];
    for (long dz = -cl.reach[2]; dz <= cl.reach[2]; ++dz)
      for (long dy = -cl.reach[1]; dy <= cl.reach[1]; ++dy)
        for (long dx = -cl.reach[0]; dx <= cl.reach[0]; ++dx) {
          long cn[3] = {ci[0] + dx, ci[1] + dy, ci[2] + dz};
          for (long j = cl.head[dm_cells_bucket(&cl, cn)]; j >= 0; j = cl.next[j]) {
            const long *cj = &cl.cidx[3 * j]; /* the cell's own particles only */
            if ((size_t)j == i || cj[0] != cn[0] || cj[1] != cn[1] || cj[2] != cn[2]) continue;
            double r2 = 0;
            for (int a = 0; a < 3; ++a) {
              const double y = (X[3 * j + a] + w[3 * j + a]) - (X[3 * i + a] + w[3 * i + a]);
              r2 += y * y;
            }
            if (!(r2 < h2) || in_family(m, i, (uint32_t)j)) continue;
            if (np + 2 > cap) pr = ms_realloc(pr, cap *= 2, sizeof *pr);
            pr[np++] = (uint64_t)i << 32 | (uint64_t)j, pr[np++] = (uint64_t)j << 32 | i;
          }
        }
  }
  dm_cells_free(&cl);
  qsort(pr, np, sizeof *pr, cmp_u64);
  size_t u = 0;
  for (size_t q = 0; q < np; ++q)
    if (u == 0 || pr[q] != pr[u - 1]) pr[u++] = pr[q];
  *out = pr;
  return u;
}

/* dm_sym_close_pairs without the pairs already bonded (a mirror image of a new pair is new in
 * the full body, whose families are mirror symmetric; a kept duplicate would bond twice). */
static size_t close_pairs(const dm_fin *f, const dm_sym_map *mp, uint64_t **pr, size_t np,
                          size_t *missing) {
  np = dm_sym_close_pairs(f, mp, pr, np, missing);
  size_t u = 0;
  for (size_t q = 0; q < np; ++q) {
    const uint64_t p = (*pr)[q];
    if (!in_family(f->m, (size_t)(p >> 32), (uint32_t)(p & 0xffffffffu))) (*pr)[u++] = p;
  }
  return u;
}

/* The new families: family j keeps its bonds and gains the pairs (j, k) of new_pairs; both
 * sorted by neighbour, so the merge keeps dm_family.c's order. from[c]: the old bond, or
 * SIZE_MAX. */
typedef struct new_families {
  size_t *start, nbonds, *from;
  uint32_t *nbr;
  double *xref, *Ainv, *cond, *kappa;
  size_t *rev;
} new_families;

static void merge_lists(const dm_model *m, const uint64_t *pr, size_t np, new_families *nf) {
  const size_t n = m->s->n, cap = m->nbonds + np + 1;
  nf->start = ms_calloc(n + 1, sizeof(size_t));
  nf->nbr = ms_calloc(cap, sizeof(uint32_t));
  nf->from = ms_calloc(cap, sizeof(size_t));
  size_t c = 0, p = 0;
  for (size_t j = 0; j < n; ++j) {
    size_t a = m->start[j];
    const size_t ae = m->start[j + 1];
    while (a < ae || (p < np && pr[p] >> 32 == j)) {
      const uint64_t ka = a < ae ? m->nbr[a] : UINT64_MAX;
      const uint64_t kb = p < np && pr[p] >> 32 == j ? (pr[p] & 0xffffffffu) : UINT64_MAX;
      if (ka < kb) nf->nbr[c] = (uint32_t)ka, nf->from[c] = a++;
      else nf->nbr[c] = (uint32_t)kb, nf->from[c] = SIZE_MAX, ++p;
      ++c;
    }
    nf->start[j + 1] = c;
  }
  nf->nbonds = c;
}

static void free_new(new_families *nf) {
  free(nf->start), free(nf->nbr), free(nf->from), free(nf->xref), free(nf->Ainv), free(nf->cond);
  free(nf->kappa), free(nf->rev);
}

/* ξ of every new bond (the head of this file), A⁻¹ and cond of the changed families; the first
 * degenerate one into *bad (SIZE_MAX: none). */
static void new_shapes(const dm_fin *f, const uint8_t *upd, new_families *nf, size_t *bad) {
  const dm_model *m = f->m;
  const dm_state *s = m->s;
  const long n = (long)f->n;
  const double cmax = m->opt.cond_max > 0 ? m->opt.cond_max : 1e8;
  nf->xref = ms_calloc(3 * nf->nbonds + 1, sizeof(double));
  nf->Ainv = ms_calloc(9 * s->n + 1, sizeof(double)); /* the ghosts' rows: unused, kept */
  nf->cond = ms_calloc(s->n + 1, sizeof(double));
  memcpy(&nf->Ainv[9 * n], &m->Ainv[9 * n], 9 * (s->n - (size_t)n) * sizeof(double));
  memcpy(&nf->cond[n], &m->cond[n], (s->n - (size_t)n) * sizeof(double));
  long first = n;
#pragma omp parallel for schedule(static) reduction(min : first)
  for (long j = 0; j < n; ++j) {
    bool changed = upd[j] != 0;
    double Fi[9];
    const double *F = &f->F[9 * j], J = dm_det3(F);
    Fi[0] = (F[4] * F[8] - F[5] * F[7]) / J, Fi[1] = (F[2] * F[7] - F[1] * F[8]) / J;
    Fi[2] = (F[1] * F[5] - F[2] * F[4]) / J, Fi[3] = (F[5] * F[6] - F[3] * F[8]) / J;
    Fi[4] = (F[0] * F[8] - F[2] * F[6]) / J, Fi[5] = (F[2] * F[3] - F[0] * F[5]) / J;
    Fi[6] = (F[3] * F[7] - F[4] * F[6]) / J, Fi[7] = (F[1] * F[6] - F[0] * F[7]) / J;
    Fi[8] = (F[0] * F[4] - F[1] * F[3]) / J;
    for (size_t c = nf->start[j]; c < nf->start[j + 1]; ++c) {
      const size_t k = nf->nbr[c];
      double *xi = &nf->xref[3 * c], dx[3];
      for (int a = 0; a < 3; ++a)
        dx[a] = (s->X[3 * k + a] - s->X[3 * j + a]) + (s->w[3 * k + a] - s->w[3 * j + a]);
      if (upd[j]) /* the family's new reference: the current bond */
        for (int a = 0; a < 3; ++a) xi[a] = dx[a];
      else if (nf->from[c] != SIZE_MAX) /* kept */
        for (int a = 0; a < 3; ++a) xi[a] = m->xref[3 * nf->from[c] + a];
      else { /* gained: pulled back through F_j, zero mismatch */
        for (int a = 0; a < 3; ++a)
          xi[a] = Fi[3 * a] * dx[0] + Fi[3 * a + 1] * dx[1] + Fi[3 * a + 2] * dx[2];
        changed = true;
      }
    }
    if (!changed) {
      memcpy(&nf->Ainv[9 * j], &m->Ainv[9 * j], 9 * sizeof(double));
      nf->cond[j] = m->cond[j];
      continue;
    }
    double A[9] = {0};
    for (size_t c = nf->start[j]; c < nf->start[j + 1]; ++c)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) A[3 * a + b] += nf->xref[3 * c + a] * nf->xref[3 * c + b];
    nf->cond[j] = dm_sym_inverse(s->dim, A, &nf->Ainv[9 * j]);
    if (!(nf->cond[j] <= cmax) && j < first) first = j;
  }
  *bad = first < n ? (size_t)first : SIZE_MAX;
}

/* Family j's new reference: its vectors ξ (from new_shapes), V ← J V, κ; the stored energy
 * into e (R, released). gained (not updated): κ only, releasing E (1 − κ_new/κ_old). */
static double commit_family(dm_fin *f, size_t j, bool updated, const double *xi, size_t nb) {
  dm_state *s = f->m->s;
  const double E = stored_one(f, j), kold = f->m->kappa[j]; /* at the old family */
  double trA = 0;
  for (size_t c = 0; c < 3 * nb; ++c) trA += xi[c] * xi[c];
  if (updated) s->vol[j] *= f->J[j], f->J[j] = 1.0;
  const double knew = dm_fin_kappa(f, j, trA);
  const double R = updated ? E : (kold > 0 ? E * (1.0 - knew / kold) : 0.0);
  f->e[j] += R / s->mass[j], f->ehg[j] -= R;
  return R;
}

/* No new bonds: the updated families' rows in place (the lists and rev unchanged). */
static ms_status update_in_place(dm_fin *f, const dm_sym_map *mp, const size_t *list, size_t nl,
                                 dm_refamily_report *rep) {
  dm_model *m = f->m;
  const dm_state *s = m->s;
  const double cmax = m->opt.cond_max > 0 ? m->opt.cond_max : 1e8;
  double *Ai = ms_calloc(10 * nl + 1, sizeof(double)), *cond = Ai + 9 * nl;
  size_t *off = ms_calloc(nl + 1, sizeof(size_t));
  for (size_t q = 0; q < nl; ++q) off[q + 1] = off[q] + m->start[list[q] + 1] - m->start[list[q]];
  double *xn = ms_calloc(3 * off[nl] + 1, sizeof(double));
  long first = (long)s->n;
#pragma omp parallel for schedule(static) reduction(min : first) if (nl > 256)
  for (long q = 0; q < (long)nl; ++q) {
    const size_t i = list[q];
    double A[9] = {0};
    for (size_t b = m->start[i], c = off[q]; b < m->start[i + 1]; ++b, ++c) {
      double xi[3], dw[3], *x = &xn[3 * c];
      dm_fin_local_bond(m, s->w, i, b, xi, dw);
      for (int a = 0; a < 3; ++a) x[a] = xi[a] + dw[a]; /* the current bond */
      for (int a = 0; a < 3; ++a)
        for (int d = 0; d < 3; ++d) A[3 * a + d] += x[a] * x[d];
    }
    cond[q] = dm_sym_inverse(s->dim, A, &Ai[9 * q]);
    if (!(cond[q] <= cmax) && (long)i < first) first = (long)i;
  }
  if (first < (long)s->n) {
    rep->bad = (size_t)first;
    free(Ai), free(off), free(xn);
    return MS_ERR_UNSTABLE;
  }
  for (size_t q = 0; q < nl; ++q) {
    const size_t i = list[q], nb = off[q + 1] - off[q];
    rep->jmin = fmin(rep->jmin, f->J[i]), rep->jmax = fmax(rep->jmax, f->J[i]);
    rep->released += dm_fin_fold(f, i) * commit_family(f, i, true, &xn[3 * off[q]], nb);
    memcpy(&m->xref[3 * m->start[i]], &xn[3 * off[q]], 3 * nb * sizeof(double));
    memcpy(&m->Ainv[9 * i], &Ai[9 * q], 9 * sizeof(double));
    m->cond[i] = cond[q];
    double trA = 0;
    for (size_t c = 0; c < 3 * nb; ++c) trA += xn[3 * off[q] + c] * xn[3 * off[q] + c];
    m->kappa[i] = dm_fin_kappa(f, i, trA);
  }
  free(Ai), free(off), free(xn);
  return mp ? dm_sym_ghost_xref(f, mp, m->start, m->nbr, m->xref) : MS_OK;
}

/* New bonds (merge): new lists, vectors, A⁻¹ and rev for all; the changed families committed. */
static ms_status update_merged(dm_fin *f, const dm_sym_map *mp, const uint8_t *upd,
                               const uint64_t *pr, size_t np, dm_refamily_report *rep) {
  dm_model *m = f->m;
  const size_t n = f->n, nall = m->s->n;
  new_families nf = {0};
  merge_lists(m, pr, np, &nf);
  if (mp) dm_sym_ghost_rows(nall, n, &nf.start, &nf.nbr, &nf.from, &nf.nbonds);
  new_shapes(f, upd, &nf, &rep->bad);
  ms_status st = rep->bad != SIZE_MAX ? MS_ERR_UNSTABLE : MS_OK;
  if (st == MS_OK && mp) st = dm_sym_ghost_xref(f, mp, nf.start, nf.nbr, nf.xref);
  nf.rev = ms_calloc(nf.nbonds + 1, sizeof(size_t));
  if (st == MS_OK) st = build_rev(m, nf.start, nf.nbr, NULL, nf.rev); /* no box: refused */
  if (st != MS_OK) {                                                  /* nothing changed */
    free_new(&nf);
    return st;
  }
  nf.kappa = ms_calloc(nall + 1, sizeof(double));
  memcpy(&nf.kappa[n], &m->kappa[n], (nall - n) * sizeof(double)); /* the ghosts': synced */
  for (size_t j = 0; j < n; ++j) {
    const size_t nb = nf.start[j + 1] - nf.start[j];
    const bool gained = nb != m->start[j + 1] - m->start[j];
    if (upd[j] || gained) {
      if (upd[j]) rep->jmin = fmin(rep->jmin, f->J[j]), rep->jmax = fmax(rep->jmax, f->J[j]);
      else rep->gained++;
      rep->released +=
          dm_fin_fold(f, j) * commit_family(f, j, upd[j], &nf.xref[3 * nf.start[j]], nb);
      double trA = 0;
      for (size_t c = 3 * nf.start[j]; c < 3 * nf.start[j + 1]; ++c) trA += nf.xref[c] * nf.xref[c];
      nf.kappa[j] = dm_fin_kappa(f, j, trA);
    } else nf.kappa[j] = m->kappa[j];
  }
  free(m->start), free(m->nbr), free(m->img), free(m->xref), free(m->rev);
  free(m->Ainv), free(m->cond), free(m->kappa), free(nf.from);
  m->start = nf.start, m->nbr = nf.nbr, m->nbonds = nf.nbonds, m->xref = nf.xref;
  m->rev = nf.rev, m->Ainv = nf.Ainv, m->cond = nf.cond, m->kappa = nf.kappa;
  m->img = ms_calloc(nf.nbonds + 1, 1);
  memset(m->img, 13, nf.nbonds); /* no periodic images */
  return MS_OK;
}

ms_status dm_fin_rebase_local(dm_fin *f, const ms_ctx *ctx, double threshold, bool merge,
                              dm_refamily_report *rep) {
  (void)ctx;
  dm_model *m = f->m;
  const dm_state *s = m->s;
  const size_t n = f->n;
  memset(rep, 0, sizeof *rep);
  rep->bad = SIZE_MAX, rep->jmin = INFINITY;
  const bool box = m->opt.box[0] > 0 || m->opt.box[1] > 0 || m->opt.box[2] > 0;
  if (f->failed || f->sr || (!f->sym.n && s->n != n) || (box && merge))
    return MS_ERR_INTERNAL; /* the head of this file */
  const ms_status fl = dm_fin_flush(f);
  if (fl != MS_OK) return fl;
  if (f->sym.n) dm_sym_sync(f); /* the ghosts' w for the neighbour search (a no-op if current) */
  uint8_t *upd = ms_calloc(n + 1, 1);
#pragma omp parallel for schedule(static) if (n > 4096)
  for (long i = 0; i < (long)n; ++i) upd[i] = family_stretch(m, (size_t)i) > 1.0 + threshold;
  size_t nl = 0;
  for (size_t i = 0; i < n; ++i) nl += upd[i];
  if (!nl) {
    free(upd);
    return MS_OK;
  }
  /* the first update: until now the shared reference's kernels ran (the same bits as a run
   * without the option, so a restart before it continues bit for bit) */
  if (!m->xref && dm_fin_local_init(f) != MS_OK) {
    free(upd);
    return MS_ERR_INTERNAL; /* asymmetric families */
  }
  size_t *list = ms_calloc(nl, sizeof(size_t));
  for (size_t i = 0, q = 0; i < n; ++i)
    if (upd[i]) list[q++] = i;
  dm_sym_map map = {0}, *mp = f->sym.n ? &map : NULL;
  if (mp) dm_sym_map_build(f, mp);
  /* symmetry planes: the ghost set is the set-up's; a merge needs every image within the
   * horizon of a real particle among the ghosts (dm_sym_family.c) */
  const size_t miss = mp && merge ? dm_sym_uncovered(f, mp, m->opt.horizon) : SIZE_MAX;
  uint64_t *pr = NULL;
  size_t np = merge && miss == SIZE_MAX ? new_pairs(f, list, nl, &pr) : 0;
  if (mp && np) np = close_pairs(f, mp, &pr, np, &rep->bad);
  ms_status st = MS_OK;
  if (miss != SIZE_MAX || rep->bad != SIZE_MAX) {
    rep->bad = miss != SIZE_MAX ? miss : rep->bad, rep->uncovered = true, st = MS_ERR_UNSTABLE;
  } else st = np ? update_merged(f, mp, upd, pr, np, rep) : update_in_place(f, mp, list, nl, rep);
  if (mp) dm_sym_map_free(mp);
  free(pr), free(list), free(upd);
  if (st != MS_OK) return st;
  rep->bonds = m->nbonds, rep->families = nl;
  return dm_fin_refresh(f);
}
