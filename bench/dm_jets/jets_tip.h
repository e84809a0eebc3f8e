/* SPDX-License-Identifier: MIT */
/* jets_tip.h — what a jet's tip is made of, and tip measures that average over mass (the jet
 * cases of jets.c; docs/validation.md "Microjets", the [20] paragraph). The jet = the particles
 * that started in the groove's valley half and are ahead of the bulk free surface x_fs (the
 * flat strip's). Measured per step:
 *   the leading-mass fronts: x_m[j], the position where the mass of the valley half counted
 *            from the jet's front reaches M_j = jets_tip_frac[j] · ρ0 h0 λ (the groove's missing mass per wavelength,
 *            an absolute mass: with the mass ahead fixed the front is a material point of a
 *            stretching jet, so the slope of x_m is a material velocity), and v_m[j], the mean
 *            velocity along x of that leading mass;
 *   clusters: the jet's particles linked at distances ≤ jets_tip_link · h (the horizon 1.5 h:
 *            in 2D that is material above ≈ 0.44 ρ0); the largest (by particles) is the jet,
 *            the others are debris; x_main = the jet's foremost particle, n_ahead = particles
 *            ahead of it, tip_cluster = the size of the foremost particle's cluster. */
#ifndef MSCALE_BENCH_JETS_TIP_H
#define MSCALE_BENCH_JETS_TIP_H

#include <stdint.h>

#include "ptl_region.h"

enum { JETS_TIP_NFRAC = 3 };
extern const double jets_tip_frac[JETS_TIP_NFRAC]; /* 0.01, 0.1, 0.5 */
extern const double jets_tip_link;                 /* 1.5 (spacings) */

typedef struct jets_tip_sample {
  double m_jet;                                    /* jet mass / (ρ0 h0 λ) */
  double x_m[JETS_TIP_NFRAC], v_m[JETS_TIP_NFRAC]; /* cm, km/s; NAN if the jet is lighter */
  double x_main, v_main;                           /* the jet cluster's foremost particle */
  long n_jet, n_clusters, n_ahead, tip_cluster;
} jets_tip_sample;

typedef struct jets_tip jets_tip; /* work space (allocated once, before the time steps) */

/* For the particles of ps with (role[i] & 1) (the valley half); m_groove = ρ0 h0 λ in the
 * particles' mass unit, h the spacing. NULL on allocation failure. */
jets_tip *jets_tip_create(const ptl_state *ps, const uint8_t *role, double m_groove, double h);
void jets_tip_destroy(jets_tip **t);
/* One sample: the jet ahead of x_fs (the leading masses may reach behind it, down to
 * x_fs − λ/4: they are defined before the jet holds them). */
void jets_tip_measure(jets_tip *t, const ptl_state *ps, const uint8_t *role, double x_fs,
                      double lambda, jets_tip_sample *out);

#endif
