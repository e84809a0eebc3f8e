/* SPDX-License-Identifier: MIT */
/* cd_force_fit_avx512.c — the fit kernel in AVX-512 (cd_force_fit.h): per lane the operations
 * of the scalar reference cd_force_fit.c, in the same order. */
#include "cd_force_fit.h"

#if CD_X86_DISPATCH || defined(__AVX512F__)
#if !defined(__AVX512F__) /* a portable build: this file's code for AVX-512 CPUs only */
#pragma GCC target("arch=x86-64-v4")
#endif
#include <immintrin.h>

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
      if (below & (1u << l)) fv[l] = cd_tab_force(t, sv[l], NULL);
    acc = _mm512_loadu_pd(fv);
  }
  return _mm512_maskz_mov_pd(in, acc);
}

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

void cd_layer_forces_fit_avx512(const cd_neigh *nl, ptl_state *p, const cd_pair_table *t, int layer,
                                double hdt) {
  const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  const int32_t ls = nl->layer_start[layer], le = nl->layer_start[layer + 1];
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
    for (int l = 0; l < nlane; l++)
      cd_add_force(p, nl->sorted[g0 + l], fxl[l], fyl[l], fzl[l], hdt);
  }
}
#endif /* CD_X86_DISPATCH || __AVX512F__ */
