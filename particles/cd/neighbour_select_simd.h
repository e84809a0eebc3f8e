/* SPDX-License-Identifier: MIT */
/* neighbour_select_simd.h — the list builder's candidate selection (neighbour_select.h) in
 * AVX-512 (sixteen candidates per instruction) and AVX2 (eight); included by
 * neighbour_select.h only, which documents the contract and holds the scalar reference. Both
 * append the same indices in the same order as the reference. */
#ifndef MSCALE_NEIGHBOUR_SELECT_SIMD_H
#define MSCALE_NEIGHBOUR_SELECT_SIMD_H

#include <immintrin.h>

/* A portable build compiles each kernel for its own instruction set (#pragma GCC target); the
 * caller runs it only on a CPU that has it (cd_simd_level_, cd_impl.h). */
#if CD_X86_DISPATCH || (defined(__AVX512F__) && defined(__AVX512VL__))
#define CD_SELECT_AVX512 1
#if CD_X86_DISPATCH
#pragma GCC push_options
#if !defined(__AVX512F__)
#pragma GCC target("arch=x86-64-v4")
#endif
#endif
static inline int cd_select_range_avx512(const cd_neigh *nl, int32_t q0, int32_t q1,
                                         const float *sv, float xi, float yi, float zi, float rl2,
                                         int32_t *restrict out) {
  const float *restrict xs = nl->xs, *restrict ys = nl->ys, *restrict zs = nl->zs;
  const int32_t *restrict sorted = nl->sorted;
  int nc = 0;
  const __m512 vxi = _mm512_set1_ps(xi), vyi = _mm512_set1_ps(yi), vzi = _mm512_set1_ps(zi),
               vrl2 = _mm512_set1_ps(rl2);
  const __m512 sx = _mm512_set1_ps(sv ? sv[0] : 0.0f), sy = _mm512_set1_ps(sv ? sv[1] : 0.0f),
               sz = _mm512_set1_ps(sv ? sv[2] : 0.0f);
  for (int32_t q = q0; q < q1; q += 16) {
    const __mmask16 live = q1 - q >= 16 ? 0xffff : (__mmask16)((1u << (q1 - q)) - 1u);
    __m512 xj = _mm512_maskz_loadu_ps(live, xs + q), yj = _mm512_maskz_loadu_ps(live, ys + q),
           zj = _mm512_maskz_loadu_ps(live, zs + q);
    if (sv) {
      xj = _mm512_add_ps(xj, sx);
      yj = _mm512_add_ps(yj, sy);
      zj = _mm512_add_ps(zj, sz);
    }
    const __m512 dx = _mm512_sub_ps(vxi, xj), dy = _mm512_sub_ps(vyi, yj),
                 dz = _mm512_sub_ps(vzi, zj);
    const __m512 d2 = _mm512_fmadd_ps(dx, dx, _mm512_fmadd_ps(dy, dy, _mm512_mul_ps(dz, dz)));
    const __mmask16 take = _mm512_mask_cmp_ps_mask(live, d2, vrl2, _CMP_LT_OQ);
    /* no branch on `take` (unpredictable); compress in a register and store the whole vector:
     * compress-to-memory is slow on Zen 4 */
    const __m512i j = _mm512_maskz_loadu_epi32(live, sorted + q);
    _mm512_storeu_si512((void *)(out + nc), _mm512_maskz_compress_epi32(take, j));
    nc += __builtin_popcount(take);
  }
  return nc;
}
#if CD_X86_DISPATCH
#pragma GCC pop_options
#endif
#endif

#if CD_X86_DISPATCH || (defined(__AVX2__) && defined(__FMA__))
#define CD_SELECT_AVX2 1
/* compress_lut[m]: the positions of the set bits of the 8-bit mask m, in order (the lanes an
 * AVX2 compress keeps, by a permute); filled once by cd_neigh_create */
static uint8_t compress_lut[256][8];
static void fill_compress_lut(void) {
  for (int m = 0; m < 256; m++) {
    int k = 0;
    for (int l = 0; l < 8; l++)
      if (m & (1 << l)) compress_lut[m][k++] = (uint8_t)l;
    while (k < 8) compress_lut[m][k++] = 0;
  }
}

#if CD_X86_DISPATCH
#pragma GCC push_options
#if !defined(__AVX2__)
#pragma GCC target("arch=x86-64-v3")
#endif
#endif
static inline int cd_select_range_avx2(const cd_neigh *nl, int32_t q0, int32_t q1, const float *sv,
                                       float xi, float yi, float zi, float rl2,
                                       int32_t *restrict out) {
  const float *restrict xs = nl->xs, *restrict ys = nl->ys, *restrict zs = nl->zs;
  const int32_t *restrict sorted = nl->sorted;
  int nc = 0;
  /* eight candidates per instruction; the taken indices are compressed by a permute from
   * compress_lut and stored as a whole vector (out has the spare entries) */
  const __m256 vxi = _mm256_set1_ps(xi), vyi = _mm256_set1_ps(yi), vzi = _mm256_set1_ps(zi),
               vrl2 = _mm256_set1_ps(rl2);
  const __m256 sx = _mm256_set1_ps(sv ? sv[0] : 0.0f), sy = _mm256_set1_ps(sv ? sv[1] : 0.0f),
               sz = _mm256_set1_ps(sv ? sv[2] : 0.0f);
  for (int32_t q = q0; q < q1; q += 8) { /* lanes past q1 are read (padding) and dropped */
    __m256 xj = _mm256_loadu_ps(xs + q), yj = _mm256_loadu_ps(ys + q), zj = _mm256_loadu_ps(zs + q);
    if (sv) {
      xj = _mm256_add_ps(xj, sx);
      yj = _mm256_add_ps(yj, sy);
      zj = _mm256_add_ps(zj, sz);
    }
    const __m256 dx = _mm256_sub_ps(vxi, xj), dy = _mm256_sub_ps(vyi, yj),
                 dz = _mm256_sub_ps(vzi, zj);
    const __m256 d2 = _mm256_fmadd_ps(dx, dx, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dz, dz)));
    int take = _mm256_movemask_ps(_mm256_cmp_ps(d2, vrl2, _CMP_LT_OQ));
    if (q1 - q < 8) take &= (1 << (q1 - q)) - 1;
    const __m256i perm =
        _mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)compress_lut[take]));
    const __m256i j = _mm256_loadu_si256((const __m256i *)(const void *)(sorted + q));
    _mm256_storeu_si256((__m256i *)(void *)(out + nc), _mm256_permutevar8x32_epi32(j, perm));
    nc += __builtin_popcount((unsigned)take);
  }
  return nc;
}
#if CD_X86_DISPATCH
#pragma GCC pop_options
#endif
#endif

#endif /* MSCALE_NEIGHBOUR_SELECT_SIMD_H */
