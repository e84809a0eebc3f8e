/* SPDX-License-Identifier: MIT */
/* cd_force_fit.c — the fit kernel, scalar: the readable reference of cd_force_fit_avx512.c
 * (cd_force_fit.h), and the kernel of builds without AVX-512. */
#include "cd_force_fit.h"

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
      const double fr = cd_fit_force(t, s);
      *fxi = fma(fr, dx, *fxi);
      *fyi = fma(fr, dy, *fyi);
      *fzi = fma(fr, dz, *fzi);
    }
  }
}

void cd_layer_forces_fit_scalar(const cd_neigh *nl, ptl_state *p, const cd_pair_table *t, int layer,
                                double hdt) {
  const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  const int32_t ls = nl->layer_start[layer], le = nl->layer_start[layer + 1];
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
        const double fr = cd_fit_force(t, s);
        fxi = fma(fr, dx, fxi);
        fyi = fma(fr, dy, fyi);
        fzi = fma(fr, dz, fzi);
      }
    }
    image_forces(nl, p, t, layer, pos, &fxi, &fyi, &fzi);
    cd_add_force(p, i, fxi, fyi, fzi, hdt);
  }
}
