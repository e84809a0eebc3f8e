/* Hugoniot validation of cluster dynamics (paper 002 §1.1, DESIGN.md §5.1): a piston driven at
 * up into an fcc aluminium slab ([001], periodic cross-section, free far end); D is measured by
 * tracking the front (bin-mean velocity = up/2) and fitting z_f(t) over t >= T/4. Cold curves:
 * Table 1 of paper 002 (OSA, eos/data/al_osa_cold.txt) and the cold-curve Mie–Grüneisen form
 * (rho0 2.71, c0 5.35, n 4). Reference: experimental Al Hugoniot Us = 5.35 + 1.34 up.
 *
 * CI (default): bonded cutoff (the remedy of the known trap), 6x6x180 cells, up = 2, 3 km/s
 * with the Table-1 curve and up = 2, 4 with the MG curve; asserts |D − Us|/Us < 3 %.
 * (On 4x4x100 cells D is still 5 % high: the front's start-up transient; validation.md.)
 * Full table (docs/validation.md "Cluster dynamics"):
 *   build/tests/particles/test_cd_hugoniot --full      (6 up x 2 curves x {bonded, plain}) */
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

typedef struct shock_result {
  double D, rho_ratio, pzz, sigma_rh, up_behind;
} shock_result;

static double fit_slope(const double *t, const double *z, int n, double tmin) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int m = 0;
  for (int k = 0; k < n; k++)
    if (t[k] >= tmin && isfinite(z[k])) {
      sx += t[k]; sy += z[k]; sxx += t[k] * t[k]; sxy += t[k] * z[k]; m++;
    }
  return m > 2 ? (m * sxy - sx * sy) / (m * sxx - sx * sx) : NAN;
}

static shock_result piston_shock(const eos_t *eos, cd_cutoff_mode mode, double up, int nx, int nz) {
  const double a = sqrt(2.0) * R0, m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  ptl_state *p = ptl_state_create((size_t)4 * nx * nx * nz, 3);
  double sh[3] = {0.25, 0.25, 0.0}, o[3] = {0, 0, 0};
  cd_lattice_fcc(p, nx, nx, nz, sh, o, R0, m, 0);
  const size_t npist = (size_t)4 * nx * nx * 2;
  double mean[3] = {0, 0, 0}, *v[3] = {p->vx, p->vy, p->vz};
  for (size_t i = 0; i < p->n; i++) {
    if (i < npist) { p->flags[i] = PTL_DRIVEN; continue; }
    for (int c = 0; c < 3; c++) {
      v[c][i] = 0.01 * (2.0 * ptl_splitmix64_uniform(12345, 3 * i + c) - 1.0);
      mean[c] += v[c][i] / (double)(p->n - npist);
    }
  }
  for (size_t i = npist; i < p->n; i++)
    for (int c = 0; c < 3; c++) v[c][i] -= mean[c];
  cd_box box = {.hi = {nx * a, nx * a, nz * a}, .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, CD_BC_FREE}};
  const double c0 = 5.35;
  cd_config cfg = {.r0 = R0, .skin = 0.1 * R0, .dt = 0.02 * R0 / c0, .cutoff = mode,
                   .sort_every = 8, .lattice = CD_LATTICE_FCC};
  cd_sim *s = cd_sim_create(p, &box, &cfg, 1);
  cd_pair_table *t = calloc(1, sizeof *t);
  assert_int_equal(cd_pair_table_build(t, eos, eos, CD_LATTICE_FCC, R0, 0, 1.2 * R0, 0.5 * R0, 1.0, 0), MS_OK);
  cd_sim_set_pair(s, 0, 0, t);
  double th[1] = {0}, uh[1] = {up}, dir[3] = {0, 0, 1};
  cd_history h = {1, th, uh};
  cd_sim_set_piston(s, &h, dir);
  assert_int_equal(cd_sim_init(s), MS_OK);
  /* run until the front has crossed ~70 % of the slab, at a guessed D = Us(exp) (+20 %) */
  const double L = nz * a, Dg = 5.35 + 1.34 * up;
  const long nsteps = (long)(0.7 * L / (1.2 * Dg) / cfg.dt), every = nsteps / 40 + 1;
  const int nbin = nz + 20;
  double *prof = calloc((size_t)nbin * CD_PROFILE_NCOL, sizeof *prof);
  double tf[64], zf[64];
  int nf = 0;
  for (long k = 1; k <= nsteps; k++) {
    assert_int_equal(cd_sim_step(s), MS_OK);
    if (k % every == 0 && nf < 64) {
      cd_profile(s, 2, -0.25 * a, (nbin - 0.25) * a, nbin, nx * a * nx * a, prof);
      tf[nf] = s->t;
      zf[nf++] = cd_front_position(prof, nbin, 2, up, 0.5);
    }
  }
  shock_result r = {0};
  r.D = fit_slope(tf, zf, nf, 0.25 * tf[nf - 1]);
  /* shocked state: bins between the piston + 5a and the front − 5a at the last frame */
  cd_profile(s, 2, -0.25 * a, (nbin - 0.25) * a, nbin, nx * a * nx * a, prof);
  double zp = 2 * a + up * s->t, zfront = cd_front_position(prof, nbin, 2, up, 0.5);
  double rho = 0, pzz = 0, vz = 0;
  int cnt = 0;
  for (int b = 0; b < nbin; b++) {
    const double *row = prof + (size_t)b * CD_PROFILE_NCOL;
    if (row[0] > zp + 5 * a && row[0] < zfront - 5 * a && row[1] > 0) {
      rho += row[2]; pzz += row[8]; vz += row[5]; cnt++;
    }
  }
  r.rho_ratio = cnt ? rho / cnt / eos_rho0(eos) : NAN;
  r.pzz = cnt ? pzz / cnt : NAN;
  r.up_behind = cnt ? vz / cnt : NAN;
  r.sigma_rh = eos_rho0(eos) * r.D * up;
  free(prof);
  cd_sim_free(s);
  return r;
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

static void test_hugoniot(void **state) {
  (void)state;
  eos_t *curves[2] = {table1(), eos_create_mg_cold(2.71, 5.35, 4.0, 2.0, true)};
  const char *cname[2] = {"Table-1 OSA", "MG cold n=4"};
  const double ups_full[] = {1.0, 1.5, 2.0, 3.0, 4.0, 5.0};
  const double ups_ci[2][2] = {{2.0, 3.0}, {2.0, 4.0}};
  const bool ci = !full_run && opt_nup == 0 && opt_mode < 0 && opt_curve < 0;
  printf("| cold curve | cutoff | up km/s | D km/s | Us exp km/s | (D-Us)/Us | EOS Hugoniot Us | rho/rho0 (D/(D-u)) | rho/rho0 (bins) | P_zz bins GPa | rho0 D up GPa |\n");
  printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (int c = 0; c < 2; c++) {
    if (opt_curve >= 0 && c != opt_curve) continue;
    for (int mode = CD_CUTOFF_BONDED; mode >= CD_CUTOFF_PLAIN; mode--) {
      if (opt_mode >= 0 ? mode != opt_mode : (!full_run && mode == CD_CUTOFF_PLAIN)) continue;
      int nup = opt_nup ? opt_nup : (full_run ? 6 : 2);
      for (int k = 0; k < nup; k++) {
        double up = opt_nup ? opt_ups[k] : (full_run ? ups_full[k] : ups_ci[c][k]);
        shock_result r = piston_shock(curves[c], (cd_cutoff_mode)mode, up, opt_nx, opt_nz);
        double us = 5.35 + 1.34 * up;
        eos_hugoniot_point hp;
        double upl[1] = {up};
        double eos_us = eos_hugoniot(curves[c], eos_rho0(curves[c]), 0.0, 1, upl, &hp) == MS_OK ? hp.us : NAN;
        printf("| %s | %s | %.1f | %.3f | %.3f | %+.1f %% | %.3f | %.3f | %.3f | %.1f | %.1f |\n", cname[c],
               mode == CD_CUTOFF_BONDED ? "bonded" : "plain", up, r.D, us, 100 * (r.D - us) / us, eos_us,
               r.D / (r.D - up), r.rho_ratio, r.pzz, r.sigma_rh);
        fflush(stdout);
        /* paper 002 §2: the close-packed cluster medium needs no plasticity model for
         * up > 1.5–2 km/s; measured here: +7 % at 1.5 (too stiff), within 1 % from 2 to 4 km/s
         * (validation.md). 3 % on the CI size for the CI points (2–4 km/s). */
        if (ci) assert_true(fabs(r.D - us) / us < 0.03);
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
