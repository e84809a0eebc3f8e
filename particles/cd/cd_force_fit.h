/* SPDX-License-Identifier: MIT */
/* cd_force_fit.h — private to the fit kernel of cd_force.c (full lists, F/r from the fit of
 * cd_potential.c, forces only; the benchmark's model, bench/cd_lammps).
 *
 * Each pair is computed under both of its particles with the same arithmetic (s is the same
 * bitwise from d and −d), so the two forces are exact opposites and Newton's third law holds
 * up to the rounding of the sums (momentum is conserved to round-off: test_cd_dynamics). No
 * particle writes another's force: no colouring phases, no read-modify-write of f_j, every
 * layer in parallel, results independent of the thread count.
 *
 * Two implementations of one layer, with the same operations per particle in the same order,
 * so their forces are bitwise equal:
 *   cd_force_fit.c         the scalar kernel, the readable reference (and the build without
 *                          AVX-512);
 *   cd_force_fit_avx512.c  the AVX-512 kernel: the particles of a group of CD_GROUP positions
 *                          are the lanes, the plain entries taken eight at a time (loads of
 *                          x_j; segment coefficients by register permutes), the image entries
 *                          (particles at a periodic boundary) entry by entry across the lanes.
 * cd_layer_forces_fit picks the one the CPU runs (cd_simd_level_). The helpers below are shared by both
 * (and by cd_force.c's other kernels). */
#ifndef MSCALE_CD_FORCE_FIT_H
#define MSCALE_CD_FORCE_FIT_H

#include "cd_impl.h"

#include <math.h>

/* F/r at s (same arithmetic as pair_fast) and optionally the energy (cd_potential.c). */
static inline double cd_tab_force(const cd_pair_table *t, double s, double *e) {
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

/* F/r of one pair inside R_c: the fit, or below its range (r < R_c/2, a rare compression) the
 * table's value. */
static inline double cd_fit_force(const cd_pair_table *t, double s) {
  return s >= t->fit_slo ? cd_fit_eval(t, s) : cd_tab_force(t, s, NULL);
}

/* The force on i is final once its list is done (no other particle writes it), so the
 * velocity-Verlet closing kick v += (Δt/2) f/m can follow at once (hdt > 0; the same arithmetic
 * as vv_step's kick loop), saving a pass over v, f and m. */
static inline void cd_add_force(ptl_state *p, int32_t i, double fxi, double fyi, double fzi,
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

/* One layer of the fit kernel: the forces of the layer's particles added to p->f (and, if
 * hdt > 0, the closing kick). */
void cd_layer_forces_fit_scalar(const cd_neigh *nl, ptl_state *p, const cd_pair_table *t, int layer,
                                double hdt);
#if CD_X86_DISPATCH || defined(__AVX512F__)
#define CD_FIT_AVX512 1
void cd_layer_forces_fit_avx512(const cd_neigh *nl, ptl_state *p, const cd_pair_table *t, int layer,
                                double hdt);
#endif

static inline void cd_layer_forces_fit(const cd_neigh *nl, ptl_state *p, const cd_pair_table *t,
                                       int layer, double hdt) {
#if defined(CD_FIT_AVX512)
  if (cd_simd_level_ == CD_SIMD_AVX512) {
    cd_layer_forces_fit_avx512(nl, p, t, layer, hdt);
    return;
  }
#endif
  cd_layer_forces_fit_scalar(nl, p, t, layer, hdt);
}

#endif /* MSCALE_CD_FORCE_FIT_H */
