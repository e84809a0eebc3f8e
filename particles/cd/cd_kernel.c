/* SPDX-License-Identifier: MIT */
/* cd_kernel.c — which SIMD kernels of cluster dynamics this CPU runs (cd_impl.h, "Runtime
 * dispatch"): AVX-512 (x86-64-v4: the fit kernel, sixteen-wide list selection), AVX2 with FMA
 * (x86-64-v3: eight-wide selection, hardware fma) or scalar. Detected once when the library is
 * loaded; MSCALE_CD_KERNEL=scalar|avx2|avx512 lowers it (tests, benchmarks), never raises it
 * above what the CPU has. */
#include "cd_impl.h"

#include <stdlib.h>
#include <string.h>

int cd_simd_level_ = CD_SIMD_SCALAR;

static int cpu_level(void) {
#if CD_X86_DISPATCH
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
      __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    return CD_SIMD_AVX512;
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return CD_SIMD_AVX2;
  return CD_SIMD_SCALAR;
#elif defined(__AVX512F__) && defined(__AVX512VL__)
  return CD_SIMD_AVX512;
#elif defined(__AVX2__) && defined(__FMA__)
  return CD_SIMD_AVX2;
#else
  return CD_SIMD_SCALAR;
#endif
}

static const char *const level_names[] = {"scalar", "avx2", "avx512"};

__attribute__((constructor)) static void detect(void) {
  int level = cpu_level();
  const char *want = getenv("MSCALE_CD_KERNEL");
  for (int k = 0; want && k < level; k++)
    if (!strcmp(want, level_names[k])) level = k;
  cd_simd_level_ = level;
}

const char *cd_kernel_name(void) { return level_names[cd_simd_level_]; }
