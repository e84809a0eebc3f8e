/* Hugoniot validation of cluster dynamics (paper 002 §1.1, DESIGN.md §5.1): a piston driven at
 * up into an fcc aluminium slab (shock along [001] unless --orient; periodic cross-section, free
 * far end). Cold curves: Table 1 of paper 002 (OSA, eos/data/al_osa_cold.txt) and the
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
 * ordered lattice is too stiff (paper 002 §2; validation.md), asserted as over-stiff by less
 * than 6 % (momentum and mass D).
 * Full table (docs/validation.md "Cluster dynamics"):
 *   build/tests/particles/test_cd_hugoniot --full      (6 up x 2 curves x {bonded, plain})
 * Exploration: --up LIST --size NX,NZ --curve table|mg --cutoff bonded|plain --orient 001|110|111
 *   --integrator NAME --dump FILE (binned profiles at every sample, CSV). */
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

#include "ptl.h"

#define R0 5.0e-4

static bool full_run = false;
static FILE *dump = NULL; /* --dump FILE: profiles along z at every sample (exploration) */

typedef struct shock_result {
  double D, D_ahead, D_mom, rho_ratio, pzz, pxx, sigma_u, up_behind;
} shock_result;

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
      sx += t[k]; sy += z[k]; sxx += t[k] * t[k]; sxy += t[k] * z[k]; m++;
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
    cell[0] = 1.0; cell[1] = s2; cell[2] = 1.0;
    *nb = 2;
    memcpy(basis, b, sizeof b);
  } else {
    cell[0] = 1.0; cell[1] = s3; cell[2] = s6;
    *nb = 6;
    for (int k = 0; k < 3; k++) /* plane k shifted by k·(½, 1/6) of the in-plane cell */
      for (int q = 0; q < 2; q++) {
        basis[2 * k + q][0] = fmod(0.5 * q + 0.5 * k, 1.0);
        basis[2 * k + q][1] = fmod(0.5 * q + k / 6.0 + 1.0, 1.0);
        basis[2 * k + q][2] = k / 3.0;
      }
  }
}

static shock_result piston_shock(const eos_t *eos, cd_cutoff_mode mode, double up, int nx, int nz,
                                 orientation orient, cd_integrator integ) {
  const double a = sqrt(2.0) * R0, m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  /* the cross-section and length of nx × nx × nz cubic cells, in whole cells of `orient` */
  double cell[3], basis[6][3];
  int nb, nc[3];
  orient_cell(orient, cell, &nb, basis);
  for (int c = 0; c < 3; c++) {
    cell[c] *= R0;
    nc[c] = (int)lround((c < 2 ? nx : nz) * a / cell[c]);
  }
  ptl_state *p = ptl_state_create((size_t)nb * nc[0] * nc[1] * nc[2], 3);
  for (int iz = 0; iz < nc[2]; iz++)
    for (int iy = 0; iy < nc[1]; iy++)
      for (int ix = 0; ix < nc[0]; ix++)
        for (int b = 0; b < nb; b++)
          ptl_state_add(p, (ix + basis[b][0] + 0.25) * cell[0], (iy + basis[b][1] + 0.25) * cell[1],
                        (iz + basis[b][2]) * cell[2], m, 0);
  /* piston: the sites below 2a (two [001] cells, thicker than R_c + skin) */
  const double zpist = 2.0 * a - 1e-3 * R0;
  double mean[3] = {0, 0, 0}, *v[3] = {p->vx, p->vy, p->vz};
  size_t nfree = 0;
  for (size_t i = 0; i < p->n; i++) nfree += p->z[i] >= zpist;
  for (size_t i = 0; i < p->n; i++) {
    if (p->z[i] < zpist) { p->flags[i] = PTL_DRIVEN; continue; }
    for (int c = 0; c < 3; c++) {
      v[c][i] = 0.01 * (2.0 * ptl_splitmix64_uniform(12345, 3 * i + c) - 1.0);
      mean[c] += v[c][i] / (double)nfree;
    }
  }
  for (size_t i = 0; i < p->n; i++)
    if (p->z[i] >= zpist)
      for (int c = 0; c < 3; c++) v[c][i] -= mean[c];
  cd_box box = {.hi = {nc[0] * cell[0], nc[1] * cell[1], nc[2] * cell[2]},
                .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, CD_BC_FREE}};
  const double c0 = 5.35;
  cd_config cfg = {.r0 = R0, .skin = 0.1 * R0, .dt = 0.02 * R0 / c0, .cutoff = mode,
                   .sort_every = 8, .lattice = CD_LATTICE_FCC, .integrator = integ};
  cd_sim *s = cd_sim_create(p, &box, &cfg, 1);
  cd_pair_table *t = calloc(1, sizeof *t);
  assert_int_equal(cd_pair_table_build(t, eos, eos, CD_LATTICE_FCC, R0, 0, 1.2 * R0, 0.5 * R0, 1.0, 0), MS_OK);
  cd_sim_set_pair(s, 0, 0, t);
  double th[1] = {0}, uh[1] = {up}, dir[3] = {0, 0, 1};
  cd_history h = {1, th, uh};
  cd_sim_set_piston(s, &h, dir);
  assert_int_equal(cd_sim_init(s), MS_OK);
  /* run until the front has crossed ~70 % of the slab, at a guessed D = Us(exp) (+20 %) */
  const double L = box.hi[2], Dg = 5.35 + 1.34 * up;
  const long nsteps = (long)(0.7 * L / (1.2 * Dg) / cfg.dt), every = nsteps / 40 + 1;
  /* bins of whole lattice planes (2, 3, 2 planes of [001], [110], [111]: about a wide),
   * centred between planes */
  const double dz = cell[2] / (orient == ORIENT_111 ? 3 : 2), bw = lround(a / dz) * dz;
  const double blo = -0.5 * dz;
  const int nbin = (int)(L / bw) + 20;
  double *prof = calloc((size_t)nbin * CD_PROFILE_NCOL, sizeof *prof);
  double tf[64], zf[64], zb[64], pm[64];
  int nf = 0;
  for (long k = 1; k <= nsteps; k++) {
    assert_int_equal(cd_sim_step(s), MS_OK);
    if (k % every == 0 && nf < 64) {
      cd_profile(s, 2, blo, blo + nbin * bw, nbin, box.hi[0] * box.hi[1], prof);
      tf[nf] = s->t;
      cd_energy en;
      cd_sim_energy(s, &en);
      pm[nf] = en.momentum[2];
      zf[nf] = cd_front_position(prof, nbin, 2, up, 0.5);
      zb[nf++] = front_from_ahead(prof, nbin, up, 0.5);
      if (dump)
        for (int b = 0; b < nbin; b++) {
          const double *row = prof + (size_t)b * CD_PROFILE_NCOL;
          if (row[1] > 0)
            fprintf(dump, "%g,%g,%g,%g,%g,%g,%g,%g\n", up, s->t, row[0], row[2], row[5], row[6], row[8], row[12]);
        }
    }
  }
  shock_result r = {0};
  r.D = fit_slope(tf, zf, nf, 0.25 * tf[nf - 1]);
  r.D_ahead = fit_slope(tf, zb, nf, 0.25 * tf[nf - 1]);
  /* momentum of the sample grows at the piston force: dΠ/dt = ρ0 A D up for a steady shock */
  r.D_mom = fit_slope(tf, pm, nf, 0.25 * tf[nf - 1]) / (eos_rho0(eos) * box.hi[0] * box.hi[1] * up);
  /* shocked state: bins between the piston + 5a and the front − 5a at the last frame */
  cd_profile(s, 2, blo, blo + nbin * bw, nbin, box.hi[0] * box.hi[1], prof);
  double zp = 2 * a + up * s->t, zfront = cd_front_position(prof, nbin, 2, up, 0.5);
  double rho = 0, pzz = 0, vz = 0, pxx = 0, su = 0;
  int cnt = 0;
  for (int b = 0; b < nbin; b++) {
    const double *row = prof + (size_t)b * CD_PROFILE_NCOL;
    if (row[0] > zp + 5 * a && row[0] < zfront - 5 * a && row[1] > 0) {
      rho += row[2]; pzz += row[8]; vz += row[5]; pxx += 0.5 * (row[6] + row[7]); su += row[12];
      cnt++;
    }
  }
  r.pxx = cnt ? pxx / cnt : NAN;
  r.sigma_u = cnt ? su / cnt : NAN;
  r.rho_ratio = cnt ? rho / cnt / eos_rho0(eos) : NAN;
  r.pzz = cnt ? pzz / cnt : NAN;
  r.up_behind = cnt ? vz / cnt : NAN;
  free(prof);
  cd_sim_free(s);
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
    if (hp.rho < rho) lo = mid; else hi = mid;
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

static void test_hugoniot(void **state) {
  (void)state;
  eos_t *curves[2] = {table1(), eos_create_mg_cold(2.71, 5.35, 4.0, 2.0, true)};
  const char *cname[2] = {"Table-1 OSA", "MG cold n=4"};
  const double ups_full[] = {1.0, 1.5, 2.0, 3.0, 4.0, 5.0};
  const double ups_ci[2][3] = {{1.5, 2.0, 3.0}, {2.0, 4.0}};
  const int nup_ci[2] = {3, 2};
  const bool ci = !full_run && opt_nup == 0 && opt_mode < 0 && opt_curve < 0;
  printf("| cold curve | cutoff | shock along | up km/s | D km/s | D (front seen from ahead) | D (momentum) | D (mass) | Us exp km/s | (D-Us)/Us | EOS Hugoniot Us | rho/rho0 (bins) | P_zz bins GPa | P exp at rho | P EOS at rho | P_xx,yy GPa | sigma_u GPa |\n");
  printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (int c = 0; c < 2; c++) {
    if (opt_curve >= 0 && c != opt_curve) continue;
    for (int mode = CD_CUTOFF_BONDED; mode >= CD_CUTOFF_PLAIN; mode--) {
      if (opt_mode >= 0 ? mode != opt_mode : (!full_run && mode == CD_CUTOFF_PLAIN)) continue;
      int nup = opt_nup ? opt_nup : (full_run ? 6 : nup_ci[c]);
      for (int k = 0; k < nup; k++) {
        double up = opt_nup ? opt_ups[k] : (full_run ? ups_full[k] : ups_ci[c][k]);
        shock_result r = piston_shock(curves[c], (cd_cutoff_mode)mode, up, opt_nx, opt_nz,
                                      opt_orient, opt_integ);
        double us = 5.35 + 1.34 * up;
        eos_hugoniot_point hp;
        double upl[1] = {up};
        double eos_us = eos_hugoniot(curves[c], eos_rho0(curves[c]), 0.0, 1, upl, &hp) == MS_OK ? hp.us : NAN;
        const double d_mass = up * r.rho_ratio / (r.rho_ratio - 1.0);
        const double rho = r.rho_ratio * eos_rho0(curves[c]);
        printf("| %s | %s | %s | %.1f | %.3f | %.3f | %.3f | %.3f | %.3f | %+.1f %% | %.3f | %.3f | "
               "%.1f | %.1f | %.1f | %.1f | %.2f |\n",
               cname[c], mode == CD_CUTOFF_BONDED ? "bonded" : "plain", orient_name[opt_orient], up,
               r.D, r.D_ahead, r.D_mom, d_mass, us, 100 * (r.D - us) / us, eos_us, r.rho_ratio,
               r.pzz, p_exp_at(eos_rho0(curves[c]), rho), p_eos_at(curves[c], rho), r.pxx, r.sigma_u);
        fflush(stdout);
        /* Paper 002 §2: the close-packed cluster medium needs no plasticity model for
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
  eos_destroy(curves[0]);
  eos_destroy(curves[1]);
}

/* --full | --up 1,2,3 | --size NX,NZ | --curve table|mg | --cutoff bonded|plain */
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
      opt_orient = !strcmp(argv[k], "110") ? ORIENT_110 : (!strcmp(argv[k], "111") ? ORIENT_111 : ORIENT_001);
    } else if (!strcmp(argv[k], "--integrator") && k + 1 < argc) {
      k++;
      for (int q = 0; cd_integrator_names[q]; q++)
        if (!strcmp(argv[k], cd_integrator_names[q])) opt_integ = (cd_integrator)q;
    } else if (!strcmp(argv[k], "--curve") && k + 1 < argc) {
      opt_curve = !strcmp(argv[++k], "mg");
    } else if (!strcmp(argv[k], "--cutoff") && k + 1 < argc) {
      opt_mode = !strcmp(argv[++k], "bonded") ? CD_CUTOFF_BONDED : CD_CUTOFF_PLAIN;
    }
  }
  /* one thread: results do not depend on the thread count (test_cd_dynamics), and ctest -j
   * runs several of these at once, where OpenMP barriers of oversubscribed threads stall */
  omp_set_num_threads(1);
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_hugoniot)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
