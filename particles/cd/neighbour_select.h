/* SPDX-License-Identifier: MIT */
/* neighbour_select.h — private to neighbour.c: the candidate selection of the list builder.
 *
 * select_range: the candidates at sorted positions q0 .. q1 − 1 inside r_list of (xi, yi, zi),
 * with the image shift sv (NULL: none) added to their positions: their indices sorted[q] are
 * appended to out in order; returns how many. out needs 16 spare entries (whole vectors are
 * stored). Positions come from the sorted-order float copies xs/ys/zs, so the loads are
 * contiguous and sixteen candidates go in one instruction; rl2 is widened by the float rounding
 * (build_layer), so every pair inside r_list is taken (and a few just beyond it, which every
 * kernel skips as beyond R_c).
 *
 * cd_select_range_scalar below is the readable reference and the kernel of builds without
 * AVX2; neighbour_select_simd.h holds the AVX-512 and AVX2 kernels, which take the same
 * candidates in the same order; select_range picks the one the CPU runs (cd_simd_level_). */
#ifndef MSCALE_NEIGHBOUR_SELECT_H
#define MSCALE_NEIGHBOUR_SELECT_H

#include "cd_impl.h"

#if CD_X86_DISPATCH || (defined(__AVX512F__) && defined(__AVX512VL__)) ||                          \
    (defined(__AVX2__) && defined(__FMA__))
#include "neighbour_select_simd.h"
#endif

static inline int cd_select_range_scalar(const cd_neigh *nl, int32_t q0, int32_t q1,
                                         const float *sv, float xi, float yi, float zi, float rl2,
                                         int32_t *restrict out) {
  const float *restrict xs = nl->xs, *restrict ys = nl->ys, *restrict zs = nl->zs;
  const int32_t *restrict sorted = nl->sorted;
  int nc = 0;
  for (int32_t q = q0; q < q1; q++) { /* branchless: store every candidate, advance on a take */
    const float dx = xi - (sv ? xs[q] + sv[0] : xs[q]), dy = yi - (sv ? ys[q] + sv[1] : ys[q]),
                dz = zi - (sv ? zs[q] + sv[2] : zs[q]);
    out[nc] = sorted[q];
    nc += dx * dx + dy * dy + dz * dz < rl2;
  }
  return nc;
}

static inline int select_range(const cd_neigh *nl, int32_t q0, int32_t q1, const float *sv,
                               float xi, float yi, float zi, float rl2, int32_t *restrict out) {
#if defined(CD_SELECT_AVX512)
  if (cd_simd_level_ == CD_SIMD_AVX512)
    return cd_select_range_avx512(nl, q0, q1, sv, xi, yi, zi, rl2, out);
#endif
#if defined(CD_SELECT_AVX2)
  if (cd_simd_level_ >= CD_SIMD_AVX2)
    return cd_select_range_avx2(nl, q0, q1, sv, xi, yi, zi, rl2, out);
#endif
  return cd_select_range_scalar(nl, q0, q1, sv, xi, yi, zi, rl2, out);
}

#endif /* MSCALE_NEIGHBOUR_SELECT_H */
