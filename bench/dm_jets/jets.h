/* SPDX-License-Identifier: MIT */
/* jets.h — Richtmyer–Meshkov jets from a sinusoidal groove on the free surface of the
 * finite-deformation discrete model (the coupled problem's particle region `discrete_model`,
 * driven through particles/ptl_region.h without a grid). One case = a grooved slab (one groove
 * wavelength wide, periodic across) and a flat strip of the same depth and drive (5 columns),
 * both hit by a piston (held at u_p, or decaying); the spike, bubble and free surface are
 * measured from the particles' positions, the jet's tip also by leading mass and by cluster
 * (jets_tip.h). docs/validation.md "Microjets". */
#ifndef MSCALE_BENCH_JETS_H
#define MSCALE_BENCH_JETS_H

#include <stdio.h>

#include "jets_tip.h"
#include "ptl_region.h"

typedef struct jets_case {
  const eos_t *eos;         /* the sample's EOS */
  double up;                /* piston velocity, km/s */
  double h;                 /* lattice spacing, cm */
  long ncol;                /* spacings per groove wavelength (λ = ncol h, the slab's width) */
  double kh0;               /* k h0 of the groove: depth 2 h0 (peak to valley), k = 2π/λ */
  double depth_wl;          /* slab depth (drive face to the groove peaks) in wavelengths */
  double obs_wl;            /* run time after breakout, in λ/U_s */
  double fit_from;          /* the fit window starts this many λ/U_s after breakout */
  double fit_to;            /* and ends this many (or at the run's end) */
  double Y, G;              /* Y > 0: yield elastic_plastic with these (GPa); Y = 0: yield none */
  const char *strength_set; /* if not NULL (and Y = 0): yield steinberg_guinan with this
                             * built-in set (particles/dm/dm_strength.c, [Steinberg1996]) */
  double dt_margin;         /* the region's dt_margin */
  /* diagnostics (0: the region's default): the viscosity's linear coefficient C_l, the bond
   * penalty c_s (`hourglass`), and a decaying drive u_p exp(−t/τ) with τ = decay λ/U_s on the
   * region's clock (0: the piston held at u_p) */
  double visc_linear, hourglass, decay;
  double spall_strength; /* > 0: fracture {model: mean_stress} with this σ_s (GPa); 0: none */
  double ref_threshold;  /* > 0: reference_update {threshold} (per-family, kept; dm_region.c) */
  const char *snapshot;  /* if not NULL: the region's HDF5 snapshot at the end (pressure, ρ) */
} jets_case;

typedef struct jets_result {
  int status;          /* 0 ran to the end; 1 the region stopped (err) */
  char err[600];       /* the region's finding when it stopped */
  double us;           /* Hugoniot shock speed at up, km/s */
  double lambda;       /* groove wavelength, cm */
  double k;            /* 2π/λ, 1/cm */
  double h0;           /* nominal amplitude (half depth), cm */
  double a0;           /* the cut lattice's amplitude: −(fundamental cosine coefficient) of the
                     * surface particles' positions at t = 0 (the staircase's sine), cm */
  double dt;           /* the fixed step, 10 µs */
  double t_break;      /* breakout of the flat strip (half-rise of its surface to u_p), 10 µs */
  double t_end;        /* the run's end (or where it stopped), 10 µs */
  double du;           /* Δu: the flat strip's free-surface velocity, mean over the fit window */
  double eta_b;        /* η at the flat strip's breakout (jets.c: −a0⁺ before the inversion) */
  double v_lin;        /* Richtmyer's impulsive k a0 (1 − u_p/U_s) Δu */
  double v_spike;      /* slope of x_valley − x_fs(flat) over the fit window, km/s (jets.c) */
  double v_spike_max;  /* the same for x_spike (the foremost particle of the valley half) */
  double v_spike_peak; /* the largest such slope over a sliding λ/U_s after breakout */
  double v_spike_late; /* the slope over the run's last λ/U_s */
  double v_tip;        /* the leading particle's velocity − u_fs(flat), mean over the window */
  double v_eta;        /* slope of η over the fit window (the amplitude growth rate) */
  /* the weakly nonlinear (second-order) impulsive theory for |A| = 1 (jets.c): spike and bubble
   * at ±η + (k/2)(η² − η_b²) about the bulk surface, from the measured η */
  double v_bubble;    /* slope of x_peak − x_fs over the fit window (negative: it lags) */
  double v_spike_nl;  /* slope of η + (k/2) η² over the fit window: the predicted spike */
  double v_bubble_nl; /* slope of −η + (k/2) η²: the predicted bubble */
  double keta_fit0;   /* k η at the fit window's start and end */
  double keta_fit1;
  double deta_end;  /* η − η_b at the fit window's end, cm */
  double deta_max;  /* max η − η_b over the run, cm */
  double t_eta_max; /* when, after breakout, 10 µs */
  int arrested;     /* η reached its maximum before the last 10 % of the run */
  double spike_len; /* x_spike − x_bubble at the end, cm */
  /* the tip measures of jets_tip.h, absolute (not relative to x_fs), over the fit window:
   * slopes of x_spike (the foremost particle), of the leading-mass fronts x_m[j] and of the
   * jet cluster's front x_main; means of the leading masses' velocities v_m[j]; and, at the
   * window's end, the jet's mass / (ρ0 h0 λ), its particles, clusters, the particles ahead of
   * the jet cluster and the size of the foremost particle's cluster */
  double u_fs_b; /* the flat strip's surface velocity at t_b + fit_from λ/U_s */
  double v_tip_slope, v_front[JETS_TIP_NFRAC], v_lead[JETS_TIP_NFRAC], v_main;
  double m_jet_end;
  long n_jet_end, n_clusters_end, n_ahead_end, tip_cluster_end;
  long steps, particles;
  /* the grooved run's energy balance: |ΔE_total| / W over the run (K + U + E_hg − W at
   * round-off, reference updates included: their released penalty energy is booked as heat) */
  double energy_err;
} jets_result;

/* Run the case (the flat strip, then the grooved slab). trace: if not NULL, a CSV of the
 * histories (t, x_spike, x_bubble, x_fs_flat, η, the tip's velocity, u_fs_flat, x_valley and
 * the jets_tip_sample's fields) every `every` steps. Returns MS_OK if both ran (result->status tells whether the grooved run stopped
 * early), an error if the set-up failed. */
ms_status jets_run(const jets_case *c, jets_result *r, FILE *trace, long every);

/* Least-squares slope of y(t) over n samples. */
double jets_slope(const double *t, const double *y, long n);

#endif
