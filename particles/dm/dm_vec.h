/* SPDX-License-Identifier: MIT */
/* dm_vec.h — the 4-lane helpers of the finite-deformation model's bond loops (dm_finite.c and
 * the per-family reference kernels of dm_fin_local.c; both compiled with the options of
 * particles/CMakeLists.txt). */
#ifndef MSCALE_DM_VEC_H
#define MSCALE_DM_VEC_H

#include "dm_impl.h"

#include <string.h>

/* 4-lane vectors (GCC/Clang vector extension, lowered to what the target has). ld4 loads a
 * particle's 3-vector and the next double (lane 3, unused): the arrays it reads (X, w, u of
 * dm_state_alloc, v̄, Q, the backup's w) carry one double of padding at their end. */
typedef double v4d __attribute__((vector_size(32)));
MS_KERNEL_INLINE static inline v4d ld4(const double *p) {
  v4d v;
  memcpy(&v, p, sizeof v);
  return v;
}
MS_KERNEL_INLINE static inline v4d bc4(double x) { return (v4d){x, x, x, x}; }

/* Bond moments of one particle: Bw, Bu (stress), Bv, sv (a half kick's v̄), Bc, sc (the pending
 * closing half kick's v̄). */
typedef struct moments {
  double Bw[9], Bu[9], Bv[9], Bc[9], sv, sc;
} moments;


/* Per-family references (m->xref, dm_fin_local.c): the bond moments and the force of particle
 * i as dm_finite.c's bond_moments and gather_one compute them, with each family's own bond
 * vectors. */
void dm_fin_local_moments(const dm_model *m, size_t i, const double *w, const double *u,
                          const double *vb, const double *vc, double dt, bool stress, bool kick,
                          bool close, moments *M);
void dm_fin_local_gather(const dm_model *m, const double *w, size_t i, double *F);

#endif
