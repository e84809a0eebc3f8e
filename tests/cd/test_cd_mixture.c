/* SPDX-License-Identifier: MIT */
/* Heterogeneous material ([Davydov] §1.2): B4C and h-BN grains (cold-curve Mie–Grüneisen
 * parameters of the paper), shocked by a piston; the measured D(u) is compared with the
 * Kuropatenko mixture rule 1/(D − u) = Σ α_i/(D_i − u_i) (eos_kuropatenko). Grains: Voronoi
 * cells of random seeds on one fcc lattice (no rotation), each grain B4C with probability equal to
 * the B4C volume fraction; unlike pairs use the mixing rule E_ab = ½(E_a + E_b).
 * Two mixtures as in the paper: 28 % (mass) B4C in h-BN (α = 0.262) and 75 % (mass) B4C
 * (α = 0.732), and the pure components against their own EOS Hugoniots. Numbers recorded in
 * docs/validation.md. CI (u = 2 km/s, 6x6x160 cells) asserts only the bracketing
 * D(h-BN) < D(mixture) < D(B4C): the measured mixture D is 13 % above the Kuropatenko rule fed
 * with the EOS Hugoniots, so agreement is not asserted (fed with the lattices' own component
 * Hugoniots, --lattice-rule, the rule is within 2–4 %: validation.md).
 *   build/tests/cd/test_cd_mixture --full    (u = 1, 2, 3, 4 km/s, 8x8x240 cells)
 *   build/tests/cd/test_cd_mixture --lattice-rule   (the rule fed with the lattice's own
 *     component Hugoniots: pure-component D measured at u = 1, 2, 3 km/s, interpolated;
 *     mixtures at u = 2 km/s, 6x6x160) */
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

static bool full_run = false, lattice_rule = false;

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

/* returns D; *alpha_out the realised B4C volume fraction (sites), *rho0_out the mean density */
static double mixture_shock(eos_t *const comp[2], double alpha, double up, int nx, int nz,
                            double *alpha_out) {
  const double a = sqrt(2.0) * R0, vs = cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = (size_t)4 * nx * nx * nz, .dim = 3}, &p),
          "ptl_state_create");
  double sh[3] = {0.25, 0.25, 0.0}, o[3] = {0, 0, 0};
  cd_lattice_fcc(p, nx, nx, nz, sh, o, R0, 1.0, 0);
  /* grains of ~6 r0 diameter */
  const double L[3] = {nx * a, nx * a, nz * a};
  const int ng = (int)(L[0] * L[1] * L[2] / (4.18879 * pow(3.0 * R0, 3)));
  double *seed = malloc(3 * (size_t)ng * sizeof *seed);
  int *gm = malloc((size_t)ng * sizeof *gm);
  for (int g = 0; g < ng; g++) {
    for (int c = 0; c < 3; c++)
      seed[3 * g + c] = L[c] * ptl_splitmix64_uniform(99, 3 * (uint64_t)g + c);
    gm[g] = ptl_splitmix64_uniform(77, (uint64_t)g) < alpha ? 0 : 1;
  }
  const size_t npist = (size_t)4 * nx * nx * 2;
  size_t n0 = 0;
  for (size_t i = 0; i < p->n; i++) {
    int best = 0;
    double bd = INFINITY;
    const double x[3] = {p->x[i], p->y[i], p->z[i]};
    for (int g = 0; g < ng; g++) { /* nearest seed, periodic in x and y */
      double d2 = 0;
      for (int c = 0; c < 3; c++) {
        double d = x[c] - seed[3 * g + c];
        if (c < 2) d -= L[c] * round(d / L[c]);
        d2 += d * d;
      }
      if (d2 < bd) {
        bd = d2;
        best = g;
      }
    }
    p->mat[i] = (uint8_t)gm[best];
    p->mass[i] = eos_rho0(comp[gm[best]]) * vs;
    if (i < npist) p->flags[i] = PTL_DRIVEN;
    else if (gm[best] == 0) n0++;
  }
  *alpha_out = (double)n0 / (double)(p->n - npist);
  free(seed);
  free(gm);
  cd_box box = {.hi = {L[0], L[1], L[2]}, .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, CD_BC_FREE}};
  const double cmax = fmax(eos_c0(comp[0]), eos_c0(comp[1]));
  cd_config cfg = {.r0 = R0,
                   .skin = 0.1 * R0,
                   .dt = 0.02 * R0 / cmax,
                   .cutoff = CD_CUTOFF_BONDED,
                   .sort_every = 8,
                   .lattice = CD_LATTICE_FCC};
  cd_sim *s = NULL;
  ms_must(cd_sim_create(&(cd_sim_params){.particles = p, .box = &box, .cfg = &cfg, .nmat = 2}, &s),
          "cd_sim_create");
  for (int x = 0; x < 2; x++)
    for (int y = x; y < 2; y++) {
      cd_pair_table *t = calloc(1, sizeof *t);
      assert_int_equal(cd_pair_table_build(t, comp[x], comp[y], CD_LATTICE_FCC, R0, 0, 1.2 * R0,
                                           0.5 * R0, 1.0, 0),
                       MS_OK);
      cd_sim_set_pair(s, x, y, t);
    }
  double th[1] = {0}, uh[1] = {up}, dir[3] = {0, 0, 1};
  cd_history h = {1, th, uh};
  cd_sim_set_piston(s, &h, dir);
  assert_int_equal(cd_sim_init(s), MS_OK);
  const double Dg = 1.3 * cmax + 1.5 * up;
  const long nsteps = (long)(0.7 * L[2] / Dg / cfg.dt), every = nsteps / 40 + 1;
  const int nbin = nz + 20;
  double *prof = calloc((size_t)nbin * CD_PROFILE_NCOL, sizeof *prof), tf[64], zf[64];
  int nf = 0;
  for (long k = 1; k <= nsteps; k++) {
    assert_int_equal(cd_sim_step(s), MS_OK);
    if (k % every == 0 && nf < 64) {
      cd_profile(s, 2, -0.25 * a, (nbin - 0.25) * a, nbin, L[0] * L[1], prof);
      tf[nf] = cd_sim_time(s);
      zf[nf++] = cd_front_position(prof, nbin, 2, up, 0.5);
    }
  }
  double D = fit_slope(tf, zf, nf, 0.25 * tf[nf - 1]);
  free(prof);
  cd_sim_destroy(&s);
  return D;
}

static void test_kuropatenko(void **state) {
  (void)state;
  eos_t *comp[2] = {eos_create_mg_cold(2.51, 9.06, 3.13, 1.0, true),   /* B4C */
                    eos_create_mg_cold(2.29, 3.19, 10.41, 1.0, true)}; /* h-BN */
  const double ups_full[4] = {1.0, 2.0, 3.0, 4.0}, ups_ci[1] = {2.0};
  const int nup = full_run ? 4 : 1, nx = full_run ? 8 : 6, nz = full_run ? 240 : 160;
  printf("| B4C volume fraction | u km/s | D (CD) km/s | D (Kuropatenko / EOS Hugoniot) km/s | "
         "difference |\n|---|---|---|---|---|\n");
  for (int k = 0; k < nup; k++) {
    const double up = full_run ? ups_full[k] : ups_ci[k];
    /* pure components first (alpha = 1: all B4C, 0: all h-BN), then the two mixtures */
    const double alphas[4] = {1.0, 0.0, 0.262, 0.732};
    double Dm[4];
    for (int m = 0; m < (full_run ? 4 : 3); m++) {
      double al, Dk = NAN, pk = NAN;
      Dm[m] = mixture_shock(comp, alphas[m], up, nx, nz, &al);
      double frac[2] = {al, 1.0 - al};
      const eos_t *cc[2] = {comp[0], comp[1]};
      assert_int_equal(eos_kuropatenko(2, cc, frac, up, &Dk, &pk), MS_OK);
      printf("| %.3f | %.1f | %.3f | %.3f | %+.1f %% |\n", al, up, Dm[m], Dk,
             100 * (Dm[m] - Dk) / Dk);
      fflush(stdout);
    }
    /* what must hold whatever the mixing rule: the mixture's shock is slower than pure B4C's
     * and faster than pure h-BN's (the Kuropatenko rule lies between them too) */
    if (!full_run) assert_true(Dm[1] < Dm[2] && Dm[2] < Dm[0]);
  }
  eos_destroy(&comp[0]);
  eos_destroy(&comp[1]);
}

/* The rule with the lattice's own component Hugoniots (validation.md): each pure lattice's D
 * measured at u = 1, 2, 3 km/s, D_i(u) piecewise linear through them (linear beyond). At a
 * pressure p each component sits at the u_i with ρ0_i D_i(u_i) u_i = p (bisection: the measured
 * p_i(u) increase), W = 1/Σ α_i/(D_i − u_i) = D − u, and p = ρ0 D u with ρ0 = Σ α_i ρ0_i gives
 * the mixture's u(p) = 2(p/ρ0)/(W + √(W² + 4p/ρ0)) (as eos_kuropatenko_at_pressure, P0 = 0);
 * bisection on p for u(p) = u. Returns D. */
enum { NRULE = 3 };
static const double rule_u[NRULE] = {1.0, 2.0, 3.0};

static double tab_d(const double *D, double u) {
  const int k = u < rule_u[1] ? 0 : 1; /* segment (linear beyond the ends) */
  return D[k] + (D[k + 1] - D[k]) * (u - rule_u[k]) / (rule_u[k + 1] - rule_u[k]);
}

static double rule_u_of_p(double rho0, const double *D, double p) {
  double lo = 0.0, hi = 10.0;
  for (int it = 0; it < 100; it++) {
    const double u = 0.5 * (lo + hi);
    if (rho0 * tab_d(D, u) * u < p) lo = u;
    else hi = u;
  }
  return 0.5 * (lo + hi);
}

static double rule_mixture_u(const double rho0i[2], double D[2][NRULE], const double alpha[2],
                             double p, double *W_out) {
  const double rho0 = alpha[0] * rho0i[0] + alpha[1] * rho0i[1];
  double sum = 0.0;
  for (int c = 0; c < 2; c++) {
    const double ui = rule_u_of_p(rho0i[c], D[c], p);
    sum += alpha[c] / (tab_d(D[c], ui) - ui);
  }
  const double W = 1.0 / sum, q = p / rho0;
  *W_out = W;
  return 2.0 * q / (W + sqrt(W * W + 4.0 * q));
}

static double rule_tabulated(const double rho0i[2], double D[2][NRULE], const double alpha[2],
                             double u) {
  double lo = 0.0, hi = 500.0, W = NAN; /* GPa */
  for (int it = 0; it < 100; it++) {
    const double p = 0.5 * (lo + hi);
    if (rule_mixture_u(rho0i, D, alpha, p, &W) < u) lo = p;
    else hi = p;
  }
  rule_mixture_u(rho0i, D, alpha, 0.5 * (lo + hi), &W);
  return u + W;
}

static void lattice_rule_run(eos_t *const comp[2]) {
  const double alphas[2] = {1.0, 0.0}, rho0i[2] = {eos_rho0(comp[0]), eos_rho0(comp[1])};
  const int nx = 6, nz = 160;
  double D[2][NRULE];
  for (int c = 0; c < 2; c++) {
    double al;
    for (int k = 0; k < NRULE; k++)
      D[c][k] = mixture_shock(comp, alphas[c], rule_u[k], nx, nz, &al);
    printf("%s lattice: D = %.3f, %.3f, %.3f km/s at u = 1, 2, 3 (EOS c0 %.3f)\n",
           c ? "h-BN" : "B4C", D[c][0], D[c][1], D[c][2], eos_c0(comp[c]));
  }
  printf("| B4C volume fraction (sites) | u km/s | D (CD) km/s | Kuropatenko, lattice Hugoniots | "
         "difference | Kuropatenko, EOS Hugoniots | difference |\n|---|---|---|---|---|---|---|\n");
  const double mix[2] = {0.262, 0.732}, up = 2.0;
  for (int m = 0; m < 2; m++) {
    double al, De = NAN, pk;
    const double Dm = mixture_shock(comp, mix[m], up, nx, nz, &al), frac[2] = {al, 1.0 - al};
    const double Dl = rule_tabulated(rho0i, D, frac, up);
    const eos_t *ce[2] = {comp[0], comp[1]};
    assert_int_equal(eos_kuropatenko(2, ce, frac, up, &De, &pk), MS_OK);
    printf("| %.3f | %.1f | %.3f | %.3f | %+.1f %% | %.3f | %+.1f %% |\n", al, up, Dm, Dl,
           100 * (Dm - Dl) / Dl, De, 100 * (Dm - De) / De);
    fflush(stdout);
  }
}

static void test_lattice_rule(void **state) {
  (void)state;
  eos_t *comp[2] = {eos_create_mg_cold(2.51, 9.06, 3.13, 1.0, true),   /* B4C */
                    eos_create_mg_cold(2.29, 3.19, 10.41, 1.0, true)}; /* h-BN */
  lattice_rule_run(comp);
  eos_destroy(&comp[0]);
  eos_destroy(&comp[1]);
}

int main(int argc, char **argv) {
  for (int k = 1; k < argc; k++) {
    if (!strcmp(argv[k], "--full")) full_run = true;
    if (!strcmp(argv[k], "--lattice-rule")) lattice_rule = true;
  }
  /* one thread: results do not depend on the thread count (test_cd_dynamics), and ctest -j
   * runs several of these at once, where OpenMP barriers of oversubscribed threads stall */
  omp_set_num_threads(1);
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_kuropatenko)};
  const struct CMUnitTest rule[] = {cmocka_unit_test(test_lattice_rule)};
  return lattice_rule ? cmocka_run_group_tests(rule, NULL, NULL)
                      : cmocka_run_group_tests(tests, NULL, NULL);
}
