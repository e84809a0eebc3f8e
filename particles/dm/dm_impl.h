/* dm_impl.h — internals shared by the discrete-model sources (not part of the public API). */
#ifndef MSCALE_DM_IMPL_H
#define MSCALE_DM_IMPL_H

#include "dm.h"

ms_status dm_build_families(dm_model *m, const ms_ctx *ctx);
ms_status dm_build_shape(dm_model *m, const ms_ctx *ctx, size_t *first_bad);
double dm_sym_inverse(int dim, const double *A, double *inv);
/* dm_forces' passes restricted to particles [0, n): C, σ, Q, energy; then F. */
void dm_stress_pass(dm_model *m, const double *w, size_t n);
void dm_gather_pass(dm_model *m, const double *w, double *F, size_t n);

/* ξ_ik = X_k + image shift − X_i of bond b of particle i. */
static inline void dm_bond_vector(const dm_model *m, size_t i, size_t b, double xi[3]) {
  const double *X = m->s->X;
  size_t k = m->nbr[b];
  const double *sh = m->shift[m->img[b]];
  for (int a = 0; a < 3; ++a) xi[a] = X[3 * k + a] + sh[a] - X[3 * i + a];
}

#endif
