/* SPDX-License-Identifier: MIT */
/* Hugoniot validation of cluster dynamics ([Davydov] §1.1, docs/design.md §5.1): a piston driven at
 * up into an fcc aluminium slab (shock along [001] unless --orient; periodic cross-section, free
 * far end). Cold curves: Table 1 of [Davydov] (OSA, eos/data/al_osa_cold.txt) and the
 * cold-curve Mie–Grüneisen form (rho0 2.71, c0 5.35, n 4). Reference: experimental Al Hugoniot
 * Us = 5.35 + 1.34 up, and the cold curve's own EOS Hugoniot (`mscale hugoniot`, Γ0 = 2).
 * Shock speed, four ways (they agree for a steady shock; their spread is the measurement's
 * uncertainty, validation.md):
 *   D          front = first bin, scanning from the piston, where the bin-mean vz < up/2;
 *              least-squares slope of z_f(t) over t >= T/4;
 *   D ahead    the same front found scanning from the undisturbed side (a dip of the noisy
 *              front zone below up/2 does not stop it);
 *   D momentum slope of the sample's momentum / (ρ0 A up): the piston force, P = ρ0 D up;
 *   D mass     up ρ/(ρ − ρ0) with ρ the mean bin density behind the front.
 *
 * CI (default): bonded cutoff (the remedy of the known trap), 6x6x180 cells. Asserted: D within
 * 3 % of Us at up = 2, 3 km/s (Table-1 curve) and 2, 4 (MG curve); at up = 1.5 (Table 1) the
 * ordered lattice is too stiff ([Davydov] §2; validation.md), asserted as over-stiff by less
 * than 6 % (momentum and mass D). --poly-ci (ctest test_cd_hugoniot_poly): a relaxed Voronoi
 * polycrystal with the plain cutoff, momentum D against the porous Hugoniot at its measured
 * density (run_poly).
 * Full table (docs/validation.md "Cluster dynamics"):
 *   build/tests/cd/test_cd_hugoniot --full      (6 up x 2 curves x {bonded, plain})
 * Exploration: --up LIST --size NX,NZ --curve table|mg --cutoff bonded|plain --orient 001|110|111
 *   --integrator NAME --rc RC/r0 --dump FILE (binned profiles at every sample, CSV);
 *   --vacancies FRAC: that fraction of the crystal's sample sites left empty at random (the
 *   density ρ00 < ρ0 enters the momentum and mass D; the porous Hugoniot at ρ00 is printed);
 *   --poly NGRAINS[,DMIN[,SEED]] --relax TIME[,J[,QUENCH[,PLAIN]]]: a relaxed Voronoi
 *   polycrystal instead of the crystal (validation.md "Hugoniot of the relaxed polycrystal");
 *   --poly-ci: the polycrystal's CI case (ctest test_cd_hugoniot_poly, validation). */
#include <math.h>
#include <omp.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "cd.h"

#define R0 5.0e-4

static bool full_run = false;
static double opt_vacancies = 0.0; /* --vacancies: fraction of sample sites left empty */
static FILE *dump = NULL;          /* --dump FILE: profiles along z at every sample (exploration) */

typedef struct shock_result {
  double D, D_ahead, D_mom, rho_ratio, pzz, pxx, sigma_u, up_behind;
  double rho00; /* initial density the momentum and mass estimates use */
} shock_result;

/* A relaxed polycrystalline sample (--poly): particles at rest, the relaxed box. */
typedef struct poly_sample {
  ptl_state *p;
  cd_box box;
  double porosity; /* of the generated packing, 1 − N V_site/V_box */
  double rho00;    /* mean bin density of the relaxed sample's interior */
  cd_relax_result rr;
} poly_sample;

/* Front seen from the undisturbed side: scanning down from the far end, the first place where
 * the bin-mean velocity reaches frac·up (a dip behind a noisy front does not stop it). */
static double front_from_ahead(const double *prof, int nbin, double up, double frac) {
  const double thr = frac * up;
  double zn = NAN, vn = NAN;
  for (int k = nbin - 1; k >= 0; k--) {
    const double *row = prof + (size_t)k * CD_PROFILE_NCOL;
    if (row[1] <= 0) continue;
    if (isfinite(vn) && row[5] >= thr && vn < thr)
      return row[0] + (thr - row[5]) * (zn - row[0]) / (vn - row[5]);
    zn = row[0];
    vn = row[5];
  }
  return NAN;
}

static double fit_slope(const double *t, const double *z, int n, double tmin) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int m = 0;
  for (int k = 0; k < n; k++)
    if (t[k] >= tmin && isfinite(z[k])) {
      sx += t[k];
      sy += z[k];
      sxx += t[k] * t[k];
      sxy += t[k] * z[k];
      m++;
    }
  return m > 2 ? (m * sxy - sx * sy) / (m * sxx - sx * sx) : NAN;
}

/* Shock direction z along a lattice direction: orthorhombic cells (units of r0) and bases.
 * [001]: cubic cell a = √2 r0, 4 sites; [110]: r0 × a × r0, 2 sites; [111]: close-packed
 * planes (r0 × √3 r0 in plane, 2 sites) stacked ABC with spacing r0 √(2/3), 6 sites. */
typedef enum { ORIENT_001 = 0, ORIENT_110, ORIENT_111 } orientation;
static const char *const orient_name[] = {"[001]", "[110]", "[111]"};

static void orient_cell(orientation o, double cell[3], int *nb, double basis[6][3]) {
  const double s2 = sqrt(2.0), s3 = sqrt(3.0), s6 = sqrt(6.0);
  if (o == ORIENT_001) {
    static const double b[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
    cell[0] = cell[1] = cell[2] = s2;
    *nb = 4;
    memcpy(basis, b, sizeof b);
  } else if (o == ORIENT_110) {
    static const double b[2][3] = {{0, 0, 0}, {0.5, 0.5, 0.5}};
    cell[0] = 1.0;
    cell[1] = s2;
    cell[2] = 1.0;
    *nb = 2;
    memcpy(basis, b, sizeof b);
  } else {
    cell[0] = 1.0;
    cell[1] = s3;
    cell[2] = s6;
    *nb = 6;
    for (int k = 0; k < 3; k++) /* plane k shifted by k·(½, 1/6) of the in-plane cell */
      for (int q = 0; q < 2; q++) {
        basis[2 * k + q][0] = fmod(0.5 * q + 0.5 * k, 1.0);
        basis[2 * k + q][1] = fmod(0.5 * q + k / 6.0 + 1.0, 1.0);
        basis[2 * k + q][2] = k / 3.0;
      }
  }
}

/* The single-crystal slab of nx × nx × nz [001] cubic cells in whole cells of `orient`, the
 * piston flagged (the sites below 2a, two [001] cells: thicker than R_c + skin). *fill: the
 * fraction of the sample's sites (above the piston) that hold a particle (--vacancies). */
static ptl_state *crystal_slab(double m, int nx, int nz, orientation orient, cd_box *box,
                               double *fill) {
  const double a = sqrt(2.0) * R0;
  double cell[3], basis[6][3];
  int nb, nc[3];
  orient_cell(orient, cell, &nb, basis);
  for (int c = 0; c < 3; c++) {
    cell[c] *= R0;
    nc[c] = (int)lround((c < 2 ? nx : nz) * a / cell[c]);
  }
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = (size_t)nb * nc[0] * nc[1] * nc[2], .dim = 3},
                           &p),
          "ptl_state_create");
  const double piston_top = 2.0 * a - 1e-3 * R0;
  size_t sample_sites = 0, sample_kept = 0;
  for (int iz = 0; iz < nc[2]; iz++)
    for (int iy = 0; iy < nc[1]; iy++)
      for (int ix = 0; ix < nc[0]; ix++)
        for (int b = 0; b < nb; b++) {
          const double zs = (iz + basis[b][2]) * cell[2];
          const uint64_t site = (((uint64_t)iz * nc[1] + iy) * nc[0] + ix) * nb + b;
          const bool in_sample = zs >= piston_top;
          sample_sites += in_sample;
          /* --vacancies: random empty sites above the piston (splitmix64, seed 777) */
          if (in_sample && opt_vacancies > 0 && ptl_splitmix64_uniform(777, site) < opt_vacancies)
            continue;
          sample_kept += in_sample;
          const size_t k = ptl_state_add(p, (ix + basis[b][0] + 0.25) * cell[0],
                                         (iy + basis[b][1] + 0.25) * cell[1], zs, m, 0);
          if (!in_sample) p->flags[k] = PTL_DRIVEN;
        }
  *fill = (double)sample_kept / (double)sample_sites;
  *box = (cd_box){.hi = {nc[0] * cell[0], nc[1] * cell[1], nc[2] * cell[2]},
                  .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, CD_BC_FREE}};
  return p;
}

static cd_config run_config(cd_cutoff_mode mode, cd_integrator integ) {
  return (cd_config){.r0 = R0,
                     .skin = 0.1 * R0,
                     .dt = 0.02 * R0 / 5.35,
                     .cutoff = mode,
                     .sort_every = 8,
                     .lattice = CD_LATTICE_FCC,
                     .integrator = integ};
}

static double opt_rc = 1.2;        /* --rc: R_c / r0 (exploration) */
static double opt_thermal = 0.01;  /* --thermal: initial velocity amplitude, km/s (exploration) */
static double opt_damping_j = 0.0; /* --damping J: relative-velocity damping Γ = c0/(J r0) in the
                                    * shock run ([Davydov] eq. 6; exploration), 0: off */

static cd_sim *make_sim(const eos_t *eos, ptl_state *p, const cd_box *box, const cd_config *cfg) {
  cd_sim *s = NULL;
  ms_must(cd_sim_create(&(cd_sim_params){.particles = p, .box = box, .cfg = cfg, .nmat = 1}, &s),
          "cd_sim_create");
  cd_pair_table *t = calloc(1, sizeof *t);
  assert_int_equal(
      cd_pair_table_build(t, eos, eos, CD_LATTICE_FCC, R0, 0, opt_rc * R0, 0.5 * R0, 1.0, 0),
      MS_OK);
  cd_sim_set_pair(s, 0, 0, t);
  return s;
}

/* Mean density of the bins between z0 and z1 of a profile. */
static double mean_bin_density(const double *prof, int nbin, double z0, double z1) {
  double rho = 0;
  int cnt = 0;
  for (int b = 0; b < nbin; b++) {
    const double *row = prof + (size_t)b * CD_PROFILE_NCOL;
    if (row[0] > z0 && row[0] < z1) {
      rho += row[2];
      cnt++;
    }
  }
  return cnt ? rho / cnt : NAN;
}

static shock_result piston_shock(const eos_t *eos, cd_cutoff_mode mode, double up, int nx, int nz,
                                 orientation orient, cd_integrator integ, const poly_sample *poly) {
  const double a = sqrt(2.0) * R0, m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  cd_box box;
  ptl_state *p;
  double fill = 1.0;
  if (poly) { /* a copy of the relaxed sample */
    box = poly->box;
    ms_must(ptl_state_create(&(ptl_state_params){.cap = poly->p->n, .dim = 3}, &p),
            "ptl_state_create");
    for (size_t i = 0; i < poly->p->n; i++) {
      size_t k = ptl_state_add(p, poly->p->x[i], poly->p->y[i], poly->p->z[i], m, 0);
      p->flags[k] = poly->p->flags[i];
    }
  } else {
    p = crystal_slab(m, nx, nz, orient, &box, &fill);
  }
  /* the piston's top: its highest site (single crystal: 2a, as the CI numbers were taken) */
  double zpist = poly ? -INFINITY : 2.0 * a;
  if (poly)
    for (size_t i = 0; i < p->n; i++)
      if (p->flags[i] & PTL_DRIVEN) zpist = fmax(zpist, p->z[i]);
  double mean[3] = {0, 0, 0}, *v[3] = {p->vx, p->vy, p->vz};
  size_t nfree = 0;
  for (size_t i = 0; i < p->n; i++) nfree += !(p->flags[i] & PTL_DRIVEN);
  for (size_t i = 0; i < p->n; i++) {
    if (p->flags[i] & PTL_DRIVEN) continue;
    for (int c = 0; c < 3; c++) {
      v[c][i] = opt_thermal * (2.0 * ptl_splitmix64_uniform(12345, 3 * i + c) - 1.0);
      mean[c] += v[c][i] / (double)nfree;
    }
  }
  for (size_t i = 0; i < p->n; i++)
    if (!(p->flags[i] & PTL_DRIVEN))
      for (int c = 0; c < 3; c++) v[c][i] -= mean[c];
  cd_config cfg = run_config(mode, integ);
  if (opt_damping_j > 0) cfg.damping_gamma = 5.35 / (opt_damping_j * R0);
  cd_sim *s = make_sim(eos, p, &box, &cfg);
  double th[1] = {0}, uh[1] = {up}, dir[3] = {0, 0, 1};
  cd_history h = {1, th, uh};
  cd_sim_set_piston(s, &h, dir);
  assert_int_equal(cd_sim_init(s), MS_OK);
  /* run until the front has crossed ~70 % of the slab, at a guessed D = Us(exp) (+20 %) */
  const double L = box.hi[2] - box.lo[2], Dg = 5.35 + 1.34 * up,
               area = (box.hi[0] - box.lo[0]) * (box.hi[1] - box.lo[1]);
  const long nsteps = (long)(0.7 * L / (1.2 * Dg) / cfg.dt), every = nsteps / 40 + 1;
  /* bins of whole lattice planes (2, 3, 2 planes of [001], [110], [111]: about a wide),
   * centred between planes (a polycrystal: a wide) */
  double cell[3], basis[6][3];
  int nb;
  orient_cell(orient, cell, &nb, basis);
  const double dz = poly ? 0.5 * a : cell[2] * R0 / (orient == ORIENT_111 ? 3 : 2),
               bw = lround(a / dz) * dz;
  const double blo = -0.5 * dz;
  const int nbin = (int)(L / bw) + 20;
  double *prof = calloc((size_t)nbin * CD_PROFILE_NCOL, sizeof *prof);
  double tf[64], zf[64], zb[64], pm[64];
  int nf = 0;
  shock_result r = {.rho00 = fill * eos_rho0(eos)};
  if (poly) r.rho00 = poly->rho00;
  for (long k = 1; k <= nsteps; k++) {
    assert_int_equal(cd_sim_step(s), MS_OK);
    if (k % every == 0 && nf < 64) {
      cd_profile(s, 2, blo, blo + nbin * bw, nbin, area, prof);
      tf[nf] = cd_sim_time(s);
      cd_energy en;
      cd_sim_energy(s, &en);
      pm[nf] = en.momentum[2];
      zf[nf] = cd_front_position(prof, nbin, 2, up, 0.5);
      zb[nf++] = front_from_ahead(prof, nbin, up, 0.5);
      if (dump)
        for (int b = 0; b < nbin; b++) {
          const double *row = prof + (size_t)b * CD_PROFILE_NCOL;
          if (row[1] > 0)
            fprintf(dump, "%g,%g,%g,%g,%g,%g,%g,%g\n", up, cd_sim_time(s), row[0], row[2], row[5],
                    row[6], row[8], row[12]);
        }
    }
  }
  r.D = fit_slope(tf, zf, nf, 0.25 * tf[nf - 1]);
  r.D_ahead = fit_slope(tf, zb, nf, 0.25 * tf[nf - 1]);
  /* momentum of the sample grows at the piston force: dΠ/dt = ρ0 A D up for a steady shock */
  r.D_mom = fit_slope(tf, pm, nf, 0.25 * tf[nf - 1]) / (r.rho00 * area * up);
  /* shocked state: bins between the piston + 5a and the front − 5a at the last frame */
  cd_profile(s, 2, blo, blo + nbin * bw, nbin, area, prof);
  double zp = zpist + up * cd_sim_time(s), zfront = cd_front_position(prof, nbin, 2, up, 0.5);
  double rho = 0, pzz = 0, vz = 0, pxx = 0, su = 0;
  int cnt = 0;
  for (int b = 0; b < nbin; b++) {
    const double *row = prof + (size_t)b * CD_PROFILE_NCOL;
    if (row[0] > zp + 5 * a && row[0] < zfront - 5 * a && row[1] > 0) {
      rho += row[2];
      pzz += row[8];
      vz += row[5];
      pxx += 0.5 * (row[6] + row[7]);
      su += row[12];
      cnt++;
    }
  }
  r.pxx = cnt ? pxx / cnt : NAN;
  r.sigma_u = cnt ? su / cnt : NAN;
  r.rho_ratio = cnt ? rho / cnt / eos_rho0(eos) : NAN;
  r.pzz = cnt ? pzz / cnt : NAN;
  r.up_behind = cnt ? vz / cnt : NAN;
  free(prof);
  cd_sim_destroy(&s);
  return r;
}

/* P(ρ) references at the measured density: the experimental fit Us = c0 + s up gives
 * P = ρ0 c0² η/(1 − s η)², η = 1 − ρ0/ρ; the EOS Hugoniot is solved for the up whose density is ρ
 * (bisection: ρ_H(up) increases with up). */
static double p_exp_at(double rho0, double rho) {
  const double c0 = 5.35, sl = 1.34, eta = 1.0 - rho0 / rho;
  return rho0 * c0 * c0 * eta / ((1.0 - sl * eta) * (1.0 - sl * eta));
}

static double p_eos_at(const eos_t *eos, double rho) {
  double lo = 0.0, hi = 10.0;
  eos_hugoniot_point hp = {0};
  for (int it = 0; it < 50; it++) {
    double mid = 0.5 * (lo + hi), up[1] = {mid};
    if (eos_hugoniot(eos, eos_rho0(eos), 0.0, 1, up, &hp) != MS_OK) return NAN;
    if (hp.rho < rho) lo = mid;
    else hi = mid;
  }
  return hp.p;
}

static eos_t *table1(void) {
  const char *src = getenv("MSCALE_SOURCE_DIR");
  char path[4096];
  snprintf(path, sizeof path, "%s/eos/data/al_osa_cold.txt", src ? src : "../..");
  dk_errors e;
  dk_errors_init(&e);
  eos_t *eos = eos_create_table_cold(path, 2.0, true, &e);
  dk_errors_print(&e, stderr);
  dk_errors_free(&e);
  assert_non_null(eos);
  return eos;
}

/* command-line selection (defaults: the CI set) */
static double opt_ups[16];
static int opt_nup = 0, opt_nx = 6, opt_nz = 180, opt_curve = -1, opt_mode = -1;
static orientation opt_orient = ORIENT_001;
static cd_integrator opt_integ = CD_INT_VELOCITY_VERLET;
/* --poly NGRAINS[,DMIN[,SEED]] and --relax TIME[,J[,QUENCH[,PLAIN]]] (TIME in r0/c0, J: damping
 * Γ = c0/(J r0), 0 = none; QUENCH, PLAIN 1/0: cd_relax_config) */
static int opt_ngrains = 0;
static double opt_dmin = 0.8, opt_relax_time = 60.0, opt_relax_j = 5.0;
static int opt_seed = 7, opt_quench = 1, opt_plain = 1;
static bool poly_ci = false; /* --poly-ci: the CI polycrystal case (test_cd_hugoniot_poly) */

/* Hugoniot of a porous sample ([Davydov]'s porous targets; docs/eos.md): initial density
 * rho00 < ρ0 at P = 0, e = 0 (the pores close without resistance), final state on the
 * full-density EOS. With t = 1 − rho00/ρ: P = rho00 up²/t (Rayleigh line), e = up²/2 (energy
 * jump with P0 = 0); solve P_eos(rho00/(1 − t), up²/2) = rho00 up²/t by bisection on t up to
 * ρ = 2 ρ0 (P_eos − P_R < 0 at small t, > 0 at large t). Returns D = up/t. */
static double porous_us(const eos_t *eos, double rho00, double up) {
  double lo = 1e-6, hi = 1.0 - rho00 / (2.0 * eos_rho0(eos));
  for (int it = 0; it < 100; it++) {
    const double t = 0.5 * (lo + hi);
    const double g = eos_pressure(eos, rho00 / (1.0 - t), 0.5 * up * up) - rho00 * up * up / t;
    if (g < 0) lo = t;
    else hi = t;
  }
  return up / (0.5 * (lo + hi));
}

/* Voronoi polycrystal slab (nx × nx × nz [001] cells of the single crystal's size, periodic
 * cross-section, grains wrapping across it), relaxed once by cd_sim_relax: damped/quenched
 * dynamics with the piston at rest and the box rescaled toward zero mean normal stress. */
static poly_sample relax_poly(const eos_t *eos, int nx, int nz) {
  const double a = sqrt(2.0) * R0, m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  const double lo[3] = {0, 0, 0}, hi[3] = {nx * a, nx * a, nz * a};
  const bool per[3] = {true, true, false};
  poly_sample ps = {0};
  double *xyz = NULL;
  int32_t *grain = NULL;
  size_t n = cd_polycrystal(3, R0, 0, lo, hi, per, opt_ngrains, (uint64_t)opt_seed, opt_dmin, NULL,
                            NULL, &xyz, &grain, &ps.porosity);
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = n, .dim = 3}, &p), "ptl_state_create");
  for (size_t i = 0; i < n; i++) {
    size_t k = ptl_state_add(p, xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], m, 0);
    if (p->z[k] < 2.0 * a) p->flags[k] = PTL_DRIVEN; /* the piston: the bottom 2a */
  }
  free(xyz);
  free(grain);
  ps.box =
      (cd_box){.hi = {hi[0], hi[1], hi[2]}, .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, CD_BC_FREE}};
  const cd_config cfg = run_config(opt_mode >= 0 ? (cd_cutoff_mode)opt_mode : CD_CUTOFF_BONDED,
                                   CD_INT_VELOCITY_VERLET);
  cd_sim *s = make_sim(eos, p, &ps.box, &cfg);
  assert_int_equal(cd_sim_init(s), MS_OK);
  const double c0 = eos_c0(eos);
  const cd_relax_config rc = {.time = opt_relax_time * R0 / c0,
                              .damping_gamma = opt_relax_j > 0 ? c0 / (opt_relax_j * R0) : 0.0,
                              .quench = opt_quench != 0,
                              .box = true,
                              .box_every = 10,
                              .tau = 10.0 * R0 / c0,
                              .modulus = eos_rho0(eos) * c0 * c0,
                              .rebond = true,
                              .plain = opt_plain != 0};
  assert_int_equal(cd_sim_relax(s, &rc, &ps.rr), MS_OK);
  ps.box = (*cd_sim_box(s));
  /* interior density: bins 5a away from both ends */
  double zmax = -INFINITY, zmin = INFINITY;
  for (size_t i = 0; i < cd_sim_particles(s)->n; i++)
    zmax = fmax(zmax, cd_sim_particles(s)->z[i]), zmin = fmin(zmin, cd_sim_particles(s)->z[i]);
  const int nbin = (int)fmin(1e5, (zmax - zmin) / a) + 1;
  double *prof = calloc((size_t)(unsigned)nbin * CD_PROFILE_NCOL, sizeof *prof);
  const double area = (ps.box.hi[0] - ps.box.lo[0]) * (ps.box.hi[1] - ps.box.lo[1]);
  cd_profile(s, 2, zmin - 0.5 * a, zmin - 0.5 * a + nbin * a, nbin, area, prof);
  ps.rho00 = mean_bin_density(prof, nbin, zmin + 5 * a, zmax - 5 * a);
  free(prof);
  ms_must(ptl_state_create(&(ptl_state_params){.cap = cd_sim_particles(s)->n, .dim = 3}, &ps.p),
          "ptl_state_create");
  for (size_t i = 0; i < cd_sim_particles(s)->n; i++) {
    size_t k = ptl_state_add(ps.p, cd_sim_particles(s)->x[i], cd_sim_particles(s)->y[i],
                             cd_sim_particles(s)->z[i], m, 0);
    ps.p->flags[k] = cd_sim_particles(s)->flags[i];
  }
  const cd_relax_result *r = &ps.rr;
  printf("polycrystal: %d grains, min_distance %.2f r0, seed %d, %zu sites, generated porosity "
         "%.2f %%\n",
         opt_ngrains, opt_dmin, opt_seed, n, 100 * ps.porosity);
  printf("relaxation: %ld steps (%.0f r0/c0, J %.1f, quench %d, plain %d): mean stress xx yy zz "
         "%.3f %.3f "
         "%.3f -> %.4f %.4f %.4f GPa; stretch %.5f %.5f %.5f; density (mass/volume) %.4f -> %.4f, "
         "interior bins %.4f g/cm3 (rho/rho0 %.4f); energy released %.4g kJ/g (dissipated "
         "%.4g); %ld bonds broken\n",
         r->steps, opt_relax_time, opt_relax_j, opt_quench, opt_plain, r->stress0[0], r->stress0[1],
         r->stress0[2], r->stress[0], r->stress[1], r->stress[2], r->lambda[0], r->lambda[1],
         r->lambda[2], r->mass / r->volume0, r->mass / r->volume, ps.rho00,
         ps.rho00 / eos_rho0(eos), r->energy / r->mass, r->dissipated / r->mass, r->broken_bonds);
  fflush(stdout);
  cd_sim_destroy(&s);
  return ps;
}

/* Hugoniot of the relaxed polycrystal (issue #4): the four D estimates against the porous
 * Hugoniots at the measured initial density of the experimental fit (as a Mie–Grüneisen EOS,
 * Us = 5.35 + 1.34 up, Γ0 = 2) and of the cold curve's own EOS. */
static void run_poly(const eos_t *eos, const char *cname, const double *ups, int nup, bool ci) {
  poly_sample ps = relax_poly(eos, opt_nx, opt_nz);
  /* CI (--poly-ci): the relaxation reached zero mean stress (30 r0/c0: |P_aa| <= 0.024 GPa
   * measured, 0.1 allowed as in test_cd_lattice) and left the grain boundaries' porosity
   * (ρ00 = 0.9487 ρ0 measured: between 0.9 and 1 whatever the seed, validation.md) */
  if (ci) {
    for (int a = 0; a < 3; a++) assert_true(fabs(ps.rr.stress[a]) < 0.1);
    assert_true(ps.rho00 > 0.9 * eos_rho0(eos) && ps.rho00 < eos_rho0(eos));
  }
  eos_t *fit = eos_create_mg_linear(eos_rho0(eos), 5.35, 1.34, 2.0);
  printf("| cold curve | up km/s | rho00/rho0 | D front | D ahead | D momentum | D mass | Us solid "
         "| Us porous (fit) | Us porous (cold-curve EOS) | (D-Us porous fit)/Us: front / ahead / "
         "momentum / mass | rho/rho0 | P_zz GPa | P_xx,yy GPa | sigma_u GPa |\n");
  printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (int k = 0; k < nup; k++) {
    const double up = ups[k];
    shock_result r = piston_shock(eos, opt_mode >= 0 ? (cd_cutoff_mode)opt_mode : CD_CUTOFF_BONDED,
                                  up, opt_nx, opt_nz, ORIENT_001, opt_integ, &ps);
    const double rho = r.rho_ratio * eos_rho0(eos), d_mass = up * rho / (rho - r.rho00);
    const double us = 5.35 + 1.34 * up, usp = porous_us(fit, r.rho00, up),
                 usc = porous_us(eos, r.rho00, up);
    printf("| %s | %.1f | %.4f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %+.1f / %+.1f / "
           "%+.1f / %+.1f %% | %.3f | %.1f | %.1f | %.2f |\n",
           cname, up, r.rho00 / eos_rho0(eos), r.D, r.D_ahead, r.D_mom, d_mass, us, usp, usc,
           100 * (r.D - usp) / usp, 100 * (r.D_ahead - usp) / usp, 100 * (r.D_mom - usp) / usp,
           100 * (d_mass - usp) / usp, r.rho_ratio, r.pzz, r.pxx, r.sigma_u);
    fflush(stdout);
    /* CI: the momentum estimate — the piston force, P = ρ00 D up: the P–up Hugoniot — of the
     * plain-cutoff polycrystal against the porous Hugoniot at its measured density. Measured
     * (validation.md): −3.0, −2.8, −2.1 % at 1.5, 2, 3 km/s (seed 7, asserted here), −3.8,
     * −2.0, −2.1 % with seed 11, −1.6 % at 1.5 km/s on a 12×12×240 sample; bound 4.5 %: the
     * seed-to-seed spread (~1 %) above the worst value. The front estimates are not asserted:
     * an elastic precursor through the stiffest grains makes them scatter by ±9 % between seeds
     * at this size. */
    if (ci) assert_true(fabs(r.D_mom - usp) / usp < 0.045);
  }
  eos_destroy(&fit);
  ptl_state_destroy(&ps.p);
}

static void test_hugoniot(void **state) {
  (void)state;
  eos_t *curves[2] = {table1(), eos_create_mg_cold(2.71, 5.35, 4.0, 2.0, true)};
  const char *cname[2] = {"Table-1 OSA", "MG cold n=4"};
  const double ups_full[] = {1.0, 1.5, 2.0, 3.0, 4.0, 5.0};
  const double ups_ci[2][3] = {{1.5, 2.0, 3.0}, {2.0, 4.0}};
  const int nup_ci[2] = {3, 2};
  const bool ci = !full_run && opt_nup == 0 && opt_mode < 0 && opt_curve < 0;
  if (opt_ngrains > 0) {
    const double ups_poly[] = {1.5, 2.0, 3.0};
    const int c = opt_curve > 0 ? 1 : 0;
    run_poly(curves[c], cname[c], opt_nup ? opt_ups : ups_poly, opt_nup ? opt_nup : 3, poly_ci);
    eos_destroy(&curves[0]);
    eos_destroy(&curves[1]);
    return;
  }
  printf("| cold curve | cutoff | shock along | up km/s | D km/s | D (front seen from ahead) | D "
         "(momentum) | D (mass) | Us exp km/s | (D-Us)/Us | EOS Hugoniot Us | rho/rho0 (bins) | "
         "P_zz bins GPa | P exp at rho | P EOS at rho | P_xx,yy GPa | sigma_u GPa |\n");
  printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  static const char *const mode_name[] = {"plain", "bonded", "shifted"}; /* cd_cutoff_mode */
  eos_t *fit = eos_create_mg_linear(eos_rho0(curves[0]), 5.35, 1.34, 2.0);
  for (int c = 0; c < 2; c++) {
    if (opt_curve >= 0 && c != opt_curve) continue;
    for (int mode = CD_CUTOFF_SHIFTED; mode >= CD_CUTOFF_PLAIN; mode--) {
      /* shifted (the plain cutoff's forces) only on request: --cutoff shifted */
      if (opt_mode >= 0 ? mode != opt_mode
                        : (mode == CD_CUTOFF_SHIFTED || (!full_run && mode == CD_CUTOFF_PLAIN)))
        continue;
      int nup = opt_nup ? opt_nup : (full_run ? 6 : nup_ci[c]);
      for (int k = 0; k < nup; k++) {
        double up = opt_nup ? opt_ups[k] : (full_run ? ups_full[k] : ups_ci[c][k]);
        shock_result r = piston_shock(curves[c], (cd_cutoff_mode)mode, up, opt_nx, opt_nz,
                                      opt_orient, opt_integ, NULL);
        double us = 5.35 + 1.34 * up;
        eos_hugoniot_point hp;
        double upl[1] = {up};
        double eos_us =
            eos_hugoniot(curves[c], eos_rho0(curves[c]), 0.0, 1, upl, &hp) == MS_OK ? hp.us : NAN;
        const double compression = r.rho_ratio * eos_rho0(curves[c]) / r.rho00; /* ρ/ρ00 */
        const double d_mass = up * compression / (compression - 1.0);
        if (opt_vacancies > 0)
          printf("vacancies: rho00/rho0 %.5f, porous Us (fit) %.3f km/s\n",
                 r.rho00 / eos_rho0(curves[c]), porous_us(fit, r.rho00, up));
        const double rho = r.rho_ratio * eos_rho0(curves[c]);
        printf(
            "| %s | %s | %s | %.1f | %.3f | %.3f | %.3f | %.3f | %.3f | %+.1f %% | %.3f | %.3f | "
            "%.1f | %.1f | %.1f | %.1f | %.2f |\n",
            cname[c], mode_name[mode], orient_name[opt_orient], up, r.D, r.D_ahead, r.D_mom, d_mass,
            us, 100 * (r.D - us) / us, eos_us, r.rho_ratio, r.pzz,
            p_exp_at(eos_rho0(curves[c]), rho), p_eos_at(curves[c], rho), r.pxx, r.sigma_u);
        fflush(stdout);
        /* [Davydov] §2: the close-packed cluster medium needs no plasticity model for
         * up > 1.5–2 km/s and is too stiff below. Measured here (validation.md): at the CI
         * points (2–4 km/s) the four D estimates lie within −3.4 … +3.1 % of Us (their spread,
         * up to 2.5 %, is the CI size's measurement uncertainty), the front D within 2.6 %. At
         * 1.5 km/s the lattice stays ordered behind the front and carries a shear stress
         * (σ_u ≈ 7 GPa): the transient-free estimates (momentum, mass) give +3.7, +4.0 %,
         * and a run twice as long +3.6 … +4.7 % with all four — the model's own
         * over-stiffness, bounded here at 6 %, not a 3 % agreement. */
        if (ci && up >= 2.0) assert_true(fabs(r.D - us) / us < 0.03);
        if (ci && up < 2.0)
          for (int q = 0; q < 2; q++) {
            const double d = q ? d_mass : r.D_mom;
            assert_true(d > us && d < 1.06 * us);
          }
      }
    }
  }
  eos_destroy(&fit);
  eos_destroy(&curves[0]);
  eos_destroy(&curves[1]);
}

/* --full | --up 1,2,3 | --size NX,NZ | --curve table|mg | --cutoff bonded|plain|shifted |
 * --thermal V |
 * --damping J
 * (and the exploration options below) */
int main(int argc, char **argv) {
  for (int k = 1; k < argc; k++) {
    if (!strcmp(argv[k], "--full")) {
      full_run = true;
      opt_nx = 6;
      opt_nz = 240;
    } else if (!strcmp(argv[k], "--up") && k + 1 < argc) {
      for (char *tok = strtok(argv[++k], ","); tok && opt_nup < 16; tok = strtok(NULL, ","))
        opt_ups[opt_nup++] = atof(tok);
    } else if (!strcmp(argv[k], "--size") && k + 1 < argc) {
      sscanf(argv[++k], "%d,%d", &opt_nx, &opt_nz);
    } else if (!strcmp(argv[k], "--dump") && k + 1 < argc) {
      dump = fopen(argv[++k], "w");
      if (dump) fprintf(dump, "up,t,z,rho,vz,Pxx,Pzz,sigma_u\n");
    } else if (!strcmp(argv[k], "--orient") && k + 1 < argc) {
      k++;
      opt_orient = !strcmp(argv[k], "110") ? ORIENT_110
                                           : (!strcmp(argv[k], "111") ? ORIENT_111 : ORIENT_001);
    } else if (!strcmp(argv[k], "--integrator") && k + 1 < argc) {
      k++;
      for (int q = 0; cd_integrator_names[q]; q++)
        if (!strcmp(argv[k], cd_integrator_names[q])) opt_integ = (cd_integrator)q;
    } else if (!strcmp(argv[k], "--poly-ci")) {
      /* 24 grains (~13 r0) in 8×8×150 cells, min_distance 0.6, seed 7, relaxed 30 r0/c0
       * (quench, J = 5, plain), plain-cutoff run at up = 1.5, 2, 3 km/s */
      poly_ci = true;
      opt_ngrains = 24, opt_dmin = 0.6, opt_seed = 7, opt_nx = 8, opt_nz = 150;
      opt_relax_time = 30, opt_relax_j = 5, opt_quench = 1, opt_plain = 1;
      opt_mode = CD_CUTOFF_PLAIN;
    } else if (!strcmp(argv[k], "--poly") && k + 1 < argc) {
      sscanf(argv[++k], "%d,%lf,%d", &opt_ngrains, &opt_dmin, &opt_seed);
    } else if (!strcmp(argv[k], "--vacancies") && k + 1 < argc) {
      opt_vacancies = atof(argv[++k]);
    } else if (!strcmp(argv[k], "--damping") && k + 1 < argc) {
      opt_damping_j = atof(argv[++k]);
    } else if (!strcmp(argv[k], "--thermal") && k + 1 < argc) {
      opt_thermal = atof(argv[++k]);
    } else if (!strcmp(argv[k], "--rc") && k + 1 < argc) {
      opt_rc = atof(argv[++k]);
    } else if (!strcmp(argv[k], "--relax") && k + 1 < argc) {
      sscanf(argv[++k], "%lf,%lf,%d,%d", &opt_relax_time, &opt_relax_j, &opt_quench, &opt_plain);
    } else if (!strcmp(argv[k], "--curve") && k + 1 < argc) {
      opt_curve = !strcmp(argv[++k], "mg");
    } else if (!strcmp(argv[k], "--cutoff") && k + 1 < argc) {
      k++;
      opt_mode = !strcmp(argv[k], "bonded")
                     ? CD_CUTOFF_BONDED
                     : (!strcmp(argv[k], "shifted") ? CD_CUTOFF_SHIFTED : CD_CUTOFF_PLAIN);
    }
  }
  /* one thread: results do not depend on the thread count (test_cd_dynamics), and ctest -j
   * runs several of these at once, where OpenMP barriers of oversubscribed threads stall */
  omp_set_num_threads(1);
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_hugoniot)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
