/* cd_force.c — pair forces, energies, virials and the relative-velocity damping.
 *
 * Pair term ([Davydov] eqs. 1–2, tabulated in cd_potential.c): for a pair at d = x_i − x_j,
 * s = |d|², the force on i is (F/r)(s)·d and on j its opposite (F > 0 repulsive).
 * Virial: ½ Σ_{i≠j} f r_a r_b / r = Σ_{pairs} (F/r) d_a d_b.
 *
 * Loops run over the layers of the neighbour structure (cd_impl.h): the layers of one phase in
 * parallel (each writes only itself and the next layer), the phases one after the other, so
 * every sum has an order independent of the number of threads. The fast path on full lists
 * (layer_forces_fit) needs no phases: no particle writes another's force.
 */
#include "cd_impl.h"

#include <math.h>
#include <string.h>
#if defined(_OPENMP)
#include <omp.h>
#endif
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

/* Hot path: one table, plain cutoff, forces only (the benchmark's model). The table has one
 * spare interval at the top for s rounding onto rc²; fma() makes the Horner steps single
 * roundings. */
static inline void pair_fast(double s, double dx, double dy, double dz, double slo, double ih,
                             const double *restrict fc, double *fxi, double *fyi, double *fzi,
                             double *fxj, double *fyj, double *fzj) {
  double fr;
  if (s >= slo) {
    const double u = (s - slo) * ih;
    const int m = (int)u;
    const double w = u - m;
    const double *c = fc + 4 * m;
    fr = fma(w, fma(w, c[2], c[1]), c[0]);
  } else { /* below r_min: linear continuation of F/r in s (cd_potential.c) */
    fr = fma((s - slo) * ih, fc[1], fc[0]);
  }
  *fxi = fma(fr, dx, *fxi);
  *fyi = fma(fr, dy, *fyi);
  *fzi = fma(fr, dz, *fzi);
  *fxj = fma(-fr, dx, *fxj);
  *fyj = fma(-fr, dy, *fyj);
  *fzj = fma(-fr, dz, *fzj);
}

/* The rest of the particle at position pos (index i, at xi, yi, zi): its plain entries from k0
 * on and its image entries, one at a time, into its partners' forces and into the force it has
 * so far (fxi, ...), which is then added to f_i. */
static inline void finish_particle(const cd_neigh *nl, const int32_t *restrict lst, int k0,
                                   int32_t pos, int32_t i, double xi, double yi, double zi,
                                   const double *restrict x, const double *restrict y,
                                   const double *restrict z, double *restrict fx,
                                   double *restrict fy, double *restrict fz, double slo, double ih,
                                   double rc2, const double *restrict fc, double fxi, double fyi,
                                   double fzi) {
  const int np = nl->nplain[pos], ni = nl->nimg[pos];
  for (int k = k0; k < np; k++) {
    const int32_t j = lst[k];
    const double dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
    const double s = fma(dx, dx, fma(dy, dy, dz * dz));
    if (s < rc2) pair_fast(s, dx, dy, dz, slo, ih, fc, &fxi, &fyi, &fzi, fx + j, fy + j, fz + j);
  }
  lst += np;
  for (int k = 0; k < ni; k++) {
    const int32_t j = lst[2 * k];
    const double *sh = nl->shift[lst[2 * k + 1]];
    const double dx = xi - (x[j] + sh[0]), dy = yi - (y[j] + sh[1]), dz = zi - (z[j] + sh[2]);
    const double s = fma(dx, dx, fma(dy, dy, dz * dz));
    if (s < rc2) pair_fast(s, dx, dy, dz, slo, ih, fc, &fxi, &fyi, &fzi, fx + j, fy + j, fz + j);
  }
  fx[i] += fxi;
  fy[i] += fyi;
  fz[i] += fzi;
}

/* Two consecutive particles at a time, their plain entries interleaved (entry k of each, then
 * entry k + 1), so that two independent chains s → table → F/r → f_j are in flight: one
 * particle's chain is latency-bound (docs/benchmarks.md, round 10: problem B's force loop
 * ~12 % faster on one core; three or four lanes were no better). Each particle's remaining
 * entries follow one at a time. The order of the f_j updates is fixed by the layout alone, so
 * results stay independent of the thread count. */
static void layer_forces_fast(const cd_neigh *nl, ptl_state *p, const cd_pair_table *t, int layer) {
  const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  double *restrict fx = p->fx, *restrict fy = p->fy, *restrict fz = p->fz;
  const double slo = t->s_lo, ih = t->inv_h, rc2 = t->rc2;
  const double *restrict fc = t->fcoef;
  const int32_t *restrict buf = nl->buf[layer];
  const int32_t end = nl->layer_start[layer + 1];
  int32_t pos = nl->layer_start[layer];
  for (; pos + 1 < end; pos += 2) {
    const int32_t pa = nl->sorted[pos], pb = nl->sorted[pos + 1];
    const double xa = x[pa], ya = y[pa], za = z[pa], xb = x[pb], yb = y[pb], zb = z[pb];
    double fxa = 0.0, fya = 0.0, fza = 0.0, fxb = 0.0, fyb = 0.0, fzb = 0.0;
    const int32_t *restrict la = buf + nl->first[pos], *restrict lb = buf + nl->first[pos + 1];
    const int na = nl->nplain[pos], nb = nl->nplain[pos + 1];
    const int nboth = na < nb ? na : nb;
    for (int k = 0; k < nboth; k++) {
      const int32_t ja = la[k], jb = lb[k];
      const double dxa = xa - x[ja], dya = ya - y[ja], dza = za - z[ja];
      const double dxb = xb - x[jb], dyb = yb - y[jb], dzb = zb - z[jb];
      const double sa = fma(dxa, dxa, fma(dya, dya, dza * dza));
      const double sb = fma(dxb, dxb, fma(dyb, dyb, dzb * dzb));
      if (sa < rc2)
        pair_fast(sa, dxa, dya, dza, slo, ih, fc, &fxa, &fya, &fza, fx + ja, fy + ja, fz + ja);
      if (sb < rc2)
        pair_fast(sb, dxb, dyb, dzb, slo, ih, fc, &fxb, &fyb, &fzb, fx + jb, fy + jb, fz + jb);
    }
    finish_particle(nl, la, nboth, pos, pa, xa, ya, za, x, y, z, fx, fy, fz, slo, ih, rc2, fc, fxa,
                    fya, fza);
    finish_particle(nl, lb, nboth, pos + 1, pb, xb, yb, zb, x, y, z, fx, fy, fz, slo, ih, rc2, fc,
                    fxb, fyb, fzb);
  }
  if (pos < end) { /* an odd particle at the layer's end */
    const int32_t pi = nl->sorted[pos];
    finish_particle(nl, buf + nl->first[pos], 0, pos, pi, x[pi], y[pi], z[pi], x, y, z, fx, fy, fz,
                    slo, ih, rc2, fc, 0.0, 0.0, 0.0);
  }
}

/* F/r at s (same arithmetic as pair_fast) and optionally the energy (cd_potential.c). */
static inline double tab_force(const cd_pair_table *t, double s, double *e) {
  double w, fr;
  int m = 0;
  if (s >= t->s_lo) {
    const double u = (s - t->s_lo) * t->inv_h;
    m = (int)u;
    w = u - m;
    const double *c = t->fcoef + 4 * m;
    fr = fma(w, fma(w, c[2], c[1]), c[0]);
  } else { /* below r_min: linear F/r, quadratic E (cd_potential.c) */
    w = (s - t->s_lo) * t->inv_h;
    fr = fma(w, t->fcoef[1], t->fcoef[0]);
  }
  if (e) {
    const double *ec = t->ecoef + 4 * m;
    *e = s >= t->s_lo ? fma(w, fma(w, fma(w, ec[3], ec[2]), ec[1]), ec[0])
                      : fma(w, fma(w, ec[2], ec[1]), ec[0]);
  }
  return fr;
}

/* ---- the fit kernel: full lists, F/r from the fit (cd_potential.c), forces only ----
 *
 * Each pair is computed under both of its particles with the same arithmetic (s is the same
 * bitwise from d and −d), so the two forces are exact opposites and Newton's third law holds
 * up to the rounding of the sums (momentum is conserved to round-off: test_cd_dynamics). No
 * particle writes another's force: no colouring phases, no read-modify-write of f_j, every
 * layer in parallel, results independent of the thread count. With AVX-512 the plain
 * entries are taken eight at a time (gathers of x_j; segment coefficients by register
 * permutes); entries with an image shift (particles at a periodic boundary) one at a time. */

/* F/r of one pair inside R_c: the fit, or below its range (r < R_c/2, a rare compression) the
 * table's value. */
static inline double fit_force(const cd_pair_table *t, double s) {
  return s >= t->fit_slo ? cd_fit_eval(t, s) : tab_force(t, s, NULL);
}

#if defined(__AVX512F__)
/* F/r at eight s (lanes of `in` inside R_c; others are 0): cd_pair_fit_eval lane by lane. */
static inline __m512d fit_force8(const cd_pair_table *t, const __m512d (*cf)[2], __m512d s,
                                 __mmask8 in) {
  const __m512i bs = _mm512_castpd_si512(s);
  const __m512i k = _mm512_srli_epi64(bs, CD_FIT_SHIFT);
  /* centre of the segment: (bits & ~low) | half, one ternary-logic op (A & B) | C */
  const __m512d c = _mm512_castsi512_pd(_mm512_ternarylogic_epi64(
      bs, _mm512_set1_epi64((long long)~((UINT64_C(1) << CD_FIT_SHIFT) - 1)),
      _mm512_set1_epi64((long long)(UINT64_C(1) << (CD_FIT_SHIFT - 1))), 0xEA));
  const __m512d tt = _mm512_sub_pd(s, c);
#define CF(q) _mm512_permutex2var_pd(cf[q][0], k, cf[q][1])
  /* Estrin's scheme (a short dependency chain), the same as cd_pair_fit_eval */
  const __m512d t2 = _mm512_mul_pd(tt, tt), t4 = _mm512_mul_pd(t2, t2), t8 = _mm512_mul_pd(t4, t4);
  const __m512d p01 = _mm512_fmadd_pd(CF(1), tt, CF(0)), p23 = _mm512_fmadd_pd(CF(3), tt, CF(2)),
                p45 = _mm512_fmadd_pd(CF(5), tt, CF(4)), p67 = _mm512_fmadd_pd(CF(7), tt, CF(6)),
                p89 = _mm512_fmadd_pd(CF(9), tt, CF(8));
#undef CF
  const __m512d q03 = _mm512_fmadd_pd(p23, t2, p01), q47 = _mm512_fmadd_pd(p67, t2, p45);
  __m512d acc = _mm512_fmadd_pd(p89, t8, _mm512_fmadd_pd(q47, t4, q03));
  const __mmask8 below = _mm512_mask_cmp_pd_mask(in, s, _mm512_set1_pd(t->fit_slo), _CMP_LT_OQ);
  if (below) { /* rare: lanes under the fit's range take the table */
    double sv[8], fv[8];
    _mm512_storeu_pd(sv, s);
    _mm512_storeu_pd(fv, acc);
    for (int l = 0; l < 8; l++)
      if (below & (1u << l)) fv[l] = tab_force(t, sv[l], NULL);
    acc = _mm512_loadu_pd(fv);
  }
  return _mm512_maskz_mov_pd(in, acc);
}
#endif

/* Adds to f_i the forces of the image entries of position pos (one at a time). */
static inline void image_forces(const cd_neigh *nl, const ptl_state *p, const cd_pair_table *t,
                                int layer, int32_t pos, double *fxi, double *fyi, double *fzi) {
  const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  const int32_t i = nl->sorted[pos];
  const int32_t *img = cd_image_list(nl, layer, pos);
  for (int k = 0; k < nl->nimg[pos]; k++) {
    const int32_t j = img[2 * k];
    const double *sh = nl->shift[img[2 * k + 1]];
    const double dx = x[i] - (x[j] + sh[0]), dy = y[i] - (y[j] + sh[1]), dz = z[i] - (z[j] + sh[2]);
    const double s = fma(dx, dx, fma(dy, dy, dz * dz));
    if (s < t->rc2) {
      const double fr = fit_force(t, s);
      *fxi = fma(fr, dx, *fxi);
      *fyi = fma(fr, dy, *fyi);
      *fzi = fma(fr, dz, *fzi);
    }
  }
}

#if defined(__AVX512F__)
/* a[j[0..7]] as a vector by scalar loads: faster than vgatherdpd on Zen 4 (docs/benchmarks.md);
 * padding entries are 0, a valid index */
static inline __m512d load8(const double *restrict a, const int32_t *restrict j) {
  const __m128d v01 = _mm_loadh_pd(_mm_load_sd(a + j[0]), a + j[1]);
  const __m128d v23 = _mm_loadh_pd(_mm_load_sd(a + j[2]), a + j[3]);
  const __m128d v45 = _mm_loadh_pd(_mm_load_sd(a + j[4]), a + j[5]);
  const __m128d v67 = _mm_loadh_pd(_mm_load_sd(a + j[6]), a + j[7]);
  const __m256d lo = _mm256_insertf128_pd(_mm256_castpd128_pd256(v01), v23, 1);
  const __m256d hi = _mm256_insertf128_pd(_mm256_castpd128_pd256(v45), v67, 1);
  return _mm512_insertf64x4(_mm512_castpd256_pd512(lo), hi, 1);
}
#endif

#if defined(__AVX512F__)
/* counts[0 .. 7] of the lanes in `lanes` as int32 lanes, 0 elsewhere (nothing read there). */
static inline __m256i load_counts8(const uint16_t *counts, __mmask8 lanes) {
#if defined(__AVX512BW__) && defined(__AVX512VL__)
  return _mm256_cvtepu16_epi32(_mm_maskz_loadu_epi16(lanes, counts));
#else
  int32_t c[8] = {0};
  for (int l = 0; l < 8; l++)
    if (lanes & (1u << l)) c[l] = counts[l];
  return _mm256_loadu_si256((const __m256i *)(const void *)c);
#endif
}

/* The largest of eight int32 lanes. */
static inline int hmax8(__m256i v) {
  v = _mm256_max_epi32(v, _mm256_permute2x128_si256(v, v, 1));
  v = _mm256_max_epi32(v, _mm256_shuffle_epi32(v, 0x4E));
  v = _mm256_max_epi32(v, _mm256_shuffle_epi32(v, 0xB1));
  return _mm256_cvtsi256_si32(v);
}

/* Eight pairs at separations d (lanes of `live`): the lanes inside R_c add F/r·d to a. */
static inline void add_pairs8(const cd_pair_table *t, const __m512d (*cf)[2], __m512d vrc2,
                              __m512d dx, __m512d dy, __m512d dz, __mmask8 live, __m512d *ax,
                              __m512d *ay, __m512d *az) {
  const __m512d s = _mm512_fmadd_pd(dx, dx, _mm512_fmadd_pd(dy, dy, _mm512_mul_pd(dz, dz)));
  const __mmask8 in = _mm512_mask_cmp_pd_mask(live, s, vrc2, _CMP_LT_OQ);
  const __m512d fr = fit_force8(t, cf, s, in);
  *ax = _mm512_fmadd_pd(fr, dx, *ax);
  *ay = _mm512_fmadd_pd(fr, dy, *ay);
  *az = _mm512_fmadd_pd(fr, dz, *az);
}
#endif

/* The force on i is final once its list is done (no other particle writes it), so the
 * velocity-Verlet closing kick v += (Δt/2) f/m can follow at once (hdt > 0; the same arithmetic
 * as vv_step's kick loop), saving a pass over v, f and m. */
static inline void add_force(ptl_state *p, int32_t i, double fxi, double fyi, double fzi,
                             double hdt) {
  p->fx[i] += fxi;
  p->fy[i] += fyi;
  p->fz[i] += fzi;
  if (hdt > 0.0) {
    const double c = hdt / p->mass[i];
    p->vx[i] += c * p->fx[i];
    p->vy[i] += c * p->fy[i];
    p->vz[i] += c * p->fz[i];
  }
}

static void layer_forces_fit(const cd_neigh *nl, ptl_state *p, const cd_pair_table *t, int layer,
                             double hdt) {
  const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  const int32_t ls = nl->layer_start[layer], le = nl->layer_start[layer + 1];
#if defined(__AVX512F__)
  /* the particles of a group of CD_GROUP positions are the lanes; entry k of every lane's
   * list is one contiguous load (cd_impl.h) */
  __m512d cf[CD_FIT_MAXDEG + 1][2];
  for (int q = 0; q <= CD_FIT_MAXDEG; q++) {
    cf[q][0] = _mm512_loadu_pd(t->fit_coef[q]);
    cf[q][1] = _mm512_loadu_pd(t->fit_coef[q] + 8);
  }
  const __m512d(*ccf)[2] = (const __m512d(*)[2])cf;
  const __m512d vrc2 = _mm512_set1_pd(t->rc2), zero = _mm512_setzero_pd();
  const __m256i lane_no = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (int32_t g0 = ls; g0 < le; g0 += CD_GROUP) {
    const int nlane = le - g0 < CD_GROUP ? le - g0 : CD_GROUP;
    const __mmask8 lanes = (__mmask8)((1u << nlane) - 1u);
    /* lanes past the layer's end: particle 0, never used */
    const __m256i ivv = _mm256_maskz_loadu_epi32(lanes, nl->sorted + g0);
    int32_t iv[CD_GROUP];
    _mm256_storeu_si256((__m256i *)(void *)iv, ivv);
    const int32_t i0 = iv[0];
    /* a whole group of consecutive particles (the usual case after a renumbering build):
     * vector loads and, below, the closing in vector form */
    const bool run =
        nlane == CD_GROUP &&
        _mm256_cmpeq_epi32_mask(ivv, _mm256_add_epi32(_mm256_set1_epi32(i0), lane_no)) == 0xff;
    const __m512d xi = run ? _mm512_loadu_pd(x + i0) : load8(x, iv),
                  yi = run ? _mm512_loadu_pd(y + i0) : load8(y, iv),
                  zi = run ? _mm512_loadu_pd(z + i0) : load8(z, iv);
    const __m256i vcnt = load_counts8(nl->nplain + g0, lanes);
    const int kmax = hmax8(vcnt);
    const int32_t *blk = nl->buf[layer] + nl->first[g0] - (size_t)CD_GROUP * kmax;
    __m512d ax = zero, ay = zero, az = zero;
    for (int k = 0; k < kmax; k++) {
      const __mmask8 live = _mm256_cmpgt_epi32_mask(vcnt, _mm256_set1_epi32(k));
      const int32_t *jk = blk + CD_GROUP * k;
      add_pairs8(t, ccf, vrc2, _mm512_sub_pd(xi, load8(x, jk)), _mm512_sub_pd(yi, load8(y, jk)),
                 _mm512_sub_pd(zi, load8(z, jk)), live, &ax, &ay, &az);
    }
    /* the image entries (particles near a periodic face), entry m of every lane's image list
     * as one vector: per lane the same operations, in the same order, as image_forces */
    const __m256i vnimg = load_counts8(nl->nimg + g0, lanes);
    const int mmax = hmax8(vnimg);
    const int32_t *imgrow[CD_GROUP];
    int32_t nimg[CD_GROUP];
    if (mmax > 0) {
      _mm256_storeu_si256((__m256i *)(void *)nimg, vnimg);
      for (int l = 0; l < nlane; l++) imgrow[l] = cd_image_list(nl, layer, g0 + l);
    }
    for (int m = 0; m < mmax; m++) {
      int32_t jl[CD_GROUP] = {0};
      double sxl[CD_GROUP] = {0}, syl[CD_GROUP] = {0}, szl[CD_GROUP] = {0};
      __mmask8 live = 0;
      for (int l = 0; l < nlane; l++) {
        if (m >= nimg[l]) continue;
        const int32_t *img = imgrow[l] + 2 * m;
        const double *sh = nl->shift[img[1]];
        jl[l] = img[0];
        sxl[l] = sh[0];
        syl[l] = sh[1];
        szl[l] = sh[2];
        live |= (__mmask8)(1u << l);
      }
      const __m512d xj = _mm512_add_pd(load8(x, jl), _mm512_loadu_pd(sxl)),
                    yj = _mm512_add_pd(load8(y, jl), _mm512_loadu_pd(syl)),
                    zj = _mm512_add_pd(load8(z, jl), _mm512_loadu_pd(szl));
      add_pairs8(t, ccf, vrc2, _mm512_sub_pd(xi, xj), _mm512_sub_pd(yi, yj), _mm512_sub_pd(zi, zj),
                 live, &ax, &ay, &az);
    }
    if (run) { /* the closing in vector form, the same arithmetic as add_force */
      const __m512d fxv = _mm512_add_pd(_mm512_loadu_pd(p->fx + i0), ax),
                    fyv = _mm512_add_pd(_mm512_loadu_pd(p->fy + i0), ay),
                    fzv = _mm512_add_pd(_mm512_loadu_pd(p->fz + i0), az);
      _mm512_storeu_pd(p->fx + i0, fxv);
      _mm512_storeu_pd(p->fy + i0, fyv);
      _mm512_storeu_pd(p->fz + i0, fzv);
      if (hdt > 0.0) {
        const __m512d c = _mm512_div_pd(_mm512_set1_pd(hdt), _mm512_loadu_pd(p->mass + i0));
        double *v[3] = {p->vx + i0, p->vy + i0, p->vz + i0};
        const __m512d fv[3] = {fxv, fyv, fzv};
        for (int a = 0; a < 3; a++)
          _mm512_storeu_pd(v[a], _mm512_add_pd(_mm512_loadu_pd(v[a]), _mm512_mul_pd(c, fv[a])));
      }
      continue;
    }
    double fxl[CD_GROUP], fyl[CD_GROUP], fzl[CD_GROUP];
    _mm512_storeu_pd(fxl, ax);
    _mm512_storeu_pd(fyl, ay);
    _mm512_storeu_pd(fzl, az);
    for (int l = 0; l < nlane; l++) add_force(p, nl->sorted[g0 + l], fxl[l], fyl[l], fzl[l], hdt);
  }
#else
  for (int32_t pos = ls; pos < le; pos++) {
    const int32_t i = nl->sorted[pos];
    const double xi = x[i], yi = y[i], zi = z[i];
    double fxi = 0.0, fyi = 0.0, fzi = 0.0;
    int stride;
    const int32_t *lst = cd_plain_list(nl, layer, pos, &stride);
    for (int k = 0; k < nl->nplain[pos]; k++) {
      const int32_t j = lst[stride * k];
      const double dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
      const double s = fma(dx, dx, fma(dy, dy, dz * dz));
      if (s < t->rc2) {
        const double fr = fit_force(t, s);
        fxi = fma(fr, dx, fxi);
        fyi = fma(fr, dy, fyi);
        fzi = fma(fr, dz, fzi);
      }
    }
    image_forces(nl, p, t, layer, pos, &fxi, &fyi, &fzi);
    add_force(p, i, fxi, fyi, fzi, hdt);
  }
#endif
}

/* Bonded mode: drop bond (i, j) from both partner rows. */
static void break_bond(int32_t *partners, int32_t i, int32_t j) {
  int32_t *pi = partners + (size_t)i * CD_MAX_PARTNERS,
          *pj = partners + (size_t)j * CD_MAX_PARTNERS;
  for (int k = 0; k < CD_MAX_PARTNERS; k++) {
    if (pi[k] == j) pi[k] = -1;
    if (pj[k] == i) pj[k] = -1;
  }
}

/* Under MPI a pair of an owned particle and a ghost is computed on both ranks (each keeps the
 * force on its own particle); its energy, virial and counts are booked by the rank owning the
 * particle with the smaller gid, so global sums count every pair once (docs/mpi.md). */
static inline bool books_pair(const ptl_state *p, int32_t i, int32_t j) {
  const int32_t nloc = (int32_t)p->nlocal;
  if (i < nloc && j < nloc) return true;
  return (p->gid[i] < p->gid[j] ? i : j) < nloc;
}

/* General path: several materials, bonded mode, energies and virials. */
static void layer_forces_full(cd_sim *s, int layer, cd_layer_sums *sum, double *pw, bool wf) {
  const cd_neigh *nl = s->nl;
  ptl_state *p = s->p;
  const double *x = p->x, *y = p->y, *z = p->z;
  double *fx = p->fx, *fy = p->fy, *fz = p->fz;
  const bool bonded = s->cfg.cutoff == CD_CUTOFF_BONDED;
  const double r02 = s->cfg.r0 * s->cfg.r0;
  const int32_t nloc = (int32_t)p->nlocal;
  for (int32_t pos = nl->layer_start[layer]; pos < nl->layer_start[layer + 1]; pos++) {
    const int32_t i = nl->sorted[pos];
    const double xi = x[i], yi = y[i], zi = z[i];
    const int mi = p->mat[i];
    double fxi = 0.0, fyi = 0.0, fzi = 0.0;
    int stride;
    int32_t *lst = cd_plain_list(nl, layer, pos, &stride), *img = cd_image_list(nl, layer, pos);
    const int np = nl->nplain[pos], ni = nl->nimg[pos];
    for (int k = 0; k < np + ni; k++) {
      int32_t *entry = k < np ? lst + stride * k : img + 2 * (k - np);
      const int32_t j = *entry & CD_NB_INDEX;
      /* each pair once (cd_impl.h); under MPI a ghost's full row is empty, so an owned–ghost
       * pair is seen only from the owned side */
      if (nl->full && j < nloc && !cd_half_pair(nl, i, j)) continue;
      const double *sh = k < np ? nl->shift[13] : nl->shift[entry[1]];
      const double dx = xi - (x[j] + sh[0]), dy = yi - (y[j] + sh[1]), dz = zi - (z[j] + sh[2]);
      const double r2 = fma(dx, dx, fma(dy, dy, dz * dz));
      const int mj = p->mat[j];
      const cd_pair_table *t = s->pair[mi][mj];
      double fr, e = 0.0;
      if (!bonded) {
        if (r2 >= t->rc2) continue;
        fr = tab_force(t, r2, sum ? &e : NULL);
        if (sum && books_pair(p, i, j)) sum->inside[mi * CD_MAX_MATERIALS + mj]++;
      } else if (*entry & CD_NB_BONDED) {
        if (r2 >= t->rc2) {
          if (!wf) continue; /* diagnostics never change the state */
          /* the bond breaks: its energy leaves the potential and is booked as broken. With the
           * hard truncation the force does work only up to R_c, so the energy lost is E(R_c):
           * evaluate there (r2 itself may lie far beyond the end of the table). */
          double eb;
          tab_force(t, t->rc2, &eb);
          *entry &= ~CD_NB_BONDED;
          break_bond(s->partners, i, j);
          if (sum && books_pair(p, i, j)) {
            sum->broken += eb;
            sum->nbroken++;
          }
          continue;
        }
        fr = tab_force(t, r2, sum ? &e : NULL);
      } else {
        if (r2 >= r02) continue; /* non-bonded: compressive branch only */
        fr = tab_force(t, r2, sum ? &e : NULL);
      }
      if (wf) {
        fxi = fma(fr, dx, fxi);
        fyi = fma(fr, dy, fyi);
        fzi = fma(fr, dz, fzi);
        fx[j] = fma(-fr, dx, fx[j]);
        fy[j] = fma(-fr, dy, fy[j]);
        fz[j] = fma(-fr, dz, fz[j]);
      }
      if (sum) {
        double v[6] = {fr * dx * dx, fr * dy * dy, fr * dz * dz,
                       fr * dx * dy, fr * dy * dz, fr * dz * dx};
        if (books_pair(p, i, j)) {
          sum->epot += e;
          for (int c = 0; c < 6; c++) sum->vir[c] += v[c];
        }
        if (pw)
          for (int c = 0; c < 6; c++) {
            pw[6 * (size_t)i + c] += 0.5 * v[c];
            pw[6 * (size_t)j + c] += 0.5 * v[c];
          }
      }
    }
    if (wf) {
      fx[i] += fxi;
      fy[i] += fyi;
      fz[i] += fzi;
    }
  }
}

/* Inside a parallel region: the calling thread's share [*ka, *kb) of the layers layer(a) ..
 * layer(b − 1) (layer(k) = list[k], or k without a list), contiguous runs holding ~1/T of
 * their particles each. With the particles in cell order a thread then works on about the
 * particles that the static schedules of the step's other loops give it, so its data stays in
 * its core's caches (with dynamic scheduling problem A's step was 20 % slower on 2 threads:
 * docs/benchmarks.md). */
static void thread_layers(const cd_neigh *nl, const int *list, int a, int b, int *ka, int *kb) {
  int nth = 1, tid = 0;
#if defined(_OPENMP)
  nth = omp_get_num_threads();
  tid = omp_get_thread_num();
#endif
  int64_t total = 0;
  for (int k = a; k < b; k++) {
    const int l = list ? list[k] : k;
    total += nl->layer_start[l + 1] - nl->layer_start[l];
  }
  const int64_t lo = total * tid / nth, hi = total * (tid + 1) / nth;
  int64_t before = 0; /* particles in the layers before k */
  *ka = *kb = b;
  for (int k = a; k < b; k++) {
    if (before >= lo && *ka == b) *ka = k;
    if (before >= hi && *kb == b) *kb = k;
    const int l = list ? list[k] : k;
    before += nl->layer_start[l + 1] - nl->layer_start[l];
  }
  if (tid == nth - 1) *kb = b;
}

void cd_compute_forces(cd_sim *s, cd_layer_sums *sums, double *pw, bool wf) {
  ptl_state *p = s->p;
  const cd_neigh *nl = s->nl;
  const long n = (long)p->n;
  double *fx = p->fx, *fy = p->fy, *fz = p->fz;
  if (wf && !s->forces_zeroed) {
#pragma omp parallel for schedule(static) if (CD_PAR(n))
    for (long i = 0; i < n; i++) fx[i] = fy[i] = fz[i] = 0.0;
  }
  if (pw) memset(pw, 0, 6 * (size_t)n * sizeof *pw);
  if (sums) memset(sums, 0, (size_t)nl->nlayer * sizeof *sums);
  s->forces_zeroed = false;
  const bool fast = wf && !sums && !pw && s->nmat == 1 && s->cfg.cutoff == CD_CUTOFF_PLAIN;
  if (fast && nl->full) { /* no writes into other particles: every layer at once */
#pragma omp parallel if (CD_PAR(p->n))
    {
      int ka, kb;
      thread_layers(nl, NULL, 0, nl->nlayer, &ka, &kb);
      for (int l = ka; l < kb; l++) layer_forces_fit(nl, p, s->pair[0][0], l, s->kick_hdt);
    }
    return;
  }
  for (int ph = 0; ph < nl->nphase; ph++) {
    const int a = nl->phase_start[ph], b = nl->phase_start[ph + 1];
#pragma omp parallel if (nl->colour && CD_PAR(p->n)) /* without colouring: one thread, a..b */
    {
      int ka, kb;
      thread_layers(nl, nl->phase_layer, a, b, &ka, &kb);
      for (int k = ka; k < kb; k++) {
        const int l = nl->phase_layer[k];
        if (fast) layer_forces_fast(nl, p, s->pair[0][0], l);
        else layer_forces_full(s, l, sums ? sums + l : NULL, pw, wf);
      }
    }
  }
}

/* ---- damping ([Davydov] eq. 6) ---- */

static void layer_damping(cd_sim *s, int layer, double *dv) {
  const cd_neigh *nl = s->nl;
  const ptl_state *p = s->p;
  const double *x = p->x, *y = p->y, *z = p->z;
  const double *vx = p->vx, *vy = p->vy, *vz = p->vz;
  const double g = s->cfg.damping_gamma * s->cfg.dt;
  const bool bonded = s->cfg.cutoff == CD_CUTOFF_BONDED;
  const int32_t *buf = nl->buf[layer];
  for (int32_t pos = nl->layer_start[layer]; pos < nl->layer_start[layer + 1]; pos++) {
    const int32_t i = nl->sorted[pos];
    const int32_t *lst = buf + nl->first[pos];
    const int np = nl->nplain[pos], ni = nl->nimg[pos];
    for (int k = 0; k < np + ni; k++) {
      const double *sh;
      const int32_t *entry = cd_nb_entry(nl, lst, np, k, &sh);
      const int32_t j = *entry & CD_NB_INDEX;
      const double dx = x[i] - (x[j] + sh[0]), dy = y[i] - (y[j] + sh[1]),
                   dz = z[i] - (z[j] + sh[2]);
      const double r2 = dx * dx + dy * dy + dz * dz;
      const cd_pair_table *t = s->pair[p->mat[i]][p->mat[j]];
      /* neighbours "within the range of the potential": inside R_c (bonds, in bonded mode) */
      if (bonded ? !(*entry & CD_NB_BONDED) && r2 >= t->r0 * t->r0 : r2 >= t->rc2) continue;
      double mi = p->mass[i], mj = p->mass[j];
      double mu = 2.0 * mi * mj / (mi + mj);
      double ux = vx[i] - vx[j], uy = vy[i] - vy[j], uz = vz[i] - vz[j];
      double ci = g * mu / mi, cj = g * mu / mj;
      dv[3 * (size_t)i] -= ci * ux;
      dv[3 * (size_t)i + 1] -= ci * uy;
      dv[3 * (size_t)i + 2] -= ci * uz;
      dv[3 * (size_t)j] += cj * ux;
      dv[3 * (size_t)j + 1] += cj * uy;
      dv[3 * (size_t)j + 2] += cj * uz;
    }
  }
}

double cd_damping_step(cd_sim *s) {
  ptl_state *p = s->p;
  const cd_neigh *nl = s->nl;
  const long n = (long)p->nlocal; /* ghosts' increments are their owners' business */
  double *dv = s->scratch;
  memset(dv, 0, 3 * p->n * sizeof *dv);
  for (int ph = 0; ph < nl->nphase; ph++) {
    const int a = nl->phase_start[ph], b = nl->phase_start[ph + 1];
#pragma omp parallel for schedule(dynamic, 1) if (nl->colour && CD_PAR(p->n))
    for (int k = a; k < b; k++) layer_damping(s, nl->phase_layer[k], dv);
  }
  /* Apply to integrated particles; the exact kinetic-energy change is the dissipation
   * (driven particles keep their prescribed velocity). Summed in index order per static
   * chunk, then over chunks: deterministic for a fixed thread count. */
  double removed = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : removed) if (CD_PAR(n))
  for (long i = 0; i < n; i++) {
    if (p->flags[i] & (PTL_DRIVEN | PTL_REMOVED)) continue;
    double ax = dv[3 * i], ay = dv[3 * i + 1], az = dv[3 * i + 2];
    double de = p->mass[i] * (p->vx[i] * ax + p->vy[i] * ay + p->vz[i] * az +
                              0.5 * (ax * ax + ay * ay + az * az));
    p->vx[i] += ax;
    p->vy[i] += ay;
    p->vz[i] += az;
    removed -= de;
  }
  return removed;
}
