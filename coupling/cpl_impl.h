/* SPDX-License-Identifier: MIT */
/* cpl_impl.h — internal helpers shared by the coupling sources (not part of the API). */
#ifndef MSCALE_CPL_IMPL_H
#define MSCALE_CPL_IMPL_H

#include "cpl.h"

/* Strict C11 + POSIX does not define M_PI. */
#define CPL_PI 3.14159265358979323846

/* Scratch doubles per fragment in cpl_fragments.work (the statistics' accumulators: CPL_ACC1
 * + 9; drag uses the first 3 of a row). */
#define CPL_WORK_COLS 24

/* Statistics passes (fragments.c), shared by the serial and the distributed finder. Fragment
 * ids id[i] < 0 are skipped; accumulators are indexed by fragment.
 * Pass 1 record (CPL_ACC1 doubles): count, mass, Σ m v, Σ cos θ and Σ sin θ per periodic axis,
 * the smallest key (gid, or index) and that particle's position (the reference on open axes). */
enum {
  CPL_ACC1_COUNT = 0,
  CPL_ACC1_MASS = 1,
  CPL_ACC1_MV = 2,
  CPL_ACC1_COS = 5,
  CPL_ACC1_SIN = 8,
  CPL_ACC1_KEY = 11, /* the columns before it are sums, the ones from it on go with the key */
  CPL_ACC1_REF = 12,
  CPL_ACC1 = 15
};
void cpl_acc1_clear(double *acc, size_t nf);
void cpl_acc1_add(double *acc, const int64_t *id, size_t n, const cpl_particles *p,
                  const cpl_box *box);
void cpl_acc1_merge(double *dst, const double *src); /* one record into another */
/* Reference point of a fragment from its pass-1 record. */
void cpl_ref_point(const double *acc1, const cpl_box *box, double ref[3]);
/* Pass 2: Σ m (r − ref) (minimum image), [nf][3]. */
void cpl_acc2_add(double *acc2, const int64_t *id, size_t n, const cpl_particles *p,
                  const cpl_box *box, const double *ref);
/* Offset of the centre from the reference and the centre wrapped into the box. */
void cpl_centre(double mass, const double ref[3], const double acc2[3], const cpl_box *box,
                double off[3], double c[3]);
/* Pass 3: Σ m |r − ref − off|², [nf]. */
void cpl_acc3_add(double *acc3, const int64_t *id, size_t n, const cpl_particles *p,
                  const cpl_box *box, const double *ref, const double *off);
/* Row k of the table from the pass results. */
void cpl_fragment_set(cpl_fragments *f, size_t k, const double *acc1, const double c[3],
                      double acc3, double rho0);
/* Per-fragment arrays for nf fragments (kept if large enough). */
void cpl_fragments_reserve(cpl_fragments *f, size_t nf);
/* Input checks, then union–find over every bonded pair of p (cell-list search); f->uf holds
 * the components. Masses are checked for particles [0, n_mass) only. */
ms_status cpl_fragments_bond_search(cpl_fragments *f, const cpl_particles *p,
                                    const cpl_fragment_opts *o, size_t n_mass);

/* The largest fragment by mass (lowest id on ties); (size_t)-1 if there is none. */
size_t cpl_largest_fragment(const cpl_fragments *f);
/* cpl_is_ejecta with the largest fragment already known. */
bool cpl_is_ejecta_with(const cpl_fragments *f, size_t k, const cpl_ejecta_sel *s, size_t largest);

#endif
