/* SPDX-License-Identifier: MIT */
/* Cluster-dynamics time stepping (docs/particles-cd.md): NVE energy conservation, the energy
 * balance with relative-velocity damping (eq. 6 of [Davydov]), momentum conservation, forces
 * from the Verlet lists vs brute force after many rebuilds, results independent of the number
 * of OpenMP threads, and the piston's work balance; then every integrator (cfg.integrator):
 * measured convergence order, NVE drift, and the same piston shock speed. */
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

#include "cd_force_fit.h"     /* the fit kernel: scalar reference and AVX-512 */
#include "cd_impl.h"          /* cd_compute_forces, the list layout */
#include "neighbour_select.h" /* the list builder's candidate selection: scalar and SIMD */

#define R0 5.0e-4
#define C0 5.35

static eos_t *al(void) { return eos_create_mg_cold(2.71, C0, 4.0, 2.0, true); }

/* periodic fcc block of n³ cells with random velocities of amplitude vamp (mean removed) */
static cd_sim *hot_block_with(const eos_t *eos, int n, double vamp, double gamma, double dt_frac,
                              cd_cutoff_mode mode, cd_integrator integ) {
  const double a = sqrt(2.0) * R0, m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = (size_t)4 * n * n * n, .dim = 3}, &p),
          "ptl_state_create");
  double sh[3] = {0.25, 0.25, 0.25}, o[3] = {0, 0, 0};
  cd_lattice_fcc(p, n, n, n, sh, o, R0, m, 0);
  double mean[3] = {0, 0, 0}, *v[3] = {p->vx, p->vy, p->vz};
  for (size_t i = 0; i < p->n; i++)
    for (int c = 0; c < 3; c++) {
      v[c][i] = vamp * (2.0 * ptl_splitmix64_uniform(7, 3 * i + c) - 1.0);
      mean[c] += v[c][i] / p->n;
    }
  for (size_t i = 0; i < p->n; i++)
    for (int c = 0; c < 3; c++) v[c][i] -= mean[c];
  cd_box box = {.lo = {0, 0, 0},
                .hi = {n * a, n * a, n * a},
                .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, CD_BC_PERIODIC}};
  cd_config cfg = {.r0 = R0,
                   .skin = 0.1 * R0,
                   .dt = dt_frac * R0 / C0,
                   .cutoff = mode,
                   .damping_gamma = gamma,
                   .lattice = CD_LATTICE_FCC,
                   .integrator = integ};
  cd_sim *s = NULL;
  ms_must(cd_sim_create(&(cd_sim_params){.particles = p, .box = &box, .cfg = &cfg, .nmat = 1}, &s),
          "cd_sim_create");
  cd_pair_table *t = calloc(1, sizeof *t);
  assert_int_equal(
      cd_pair_table_build(t, eos, eos, CD_LATTICE_FCC, R0, 0, 1.2 * R0, 0.5 * R0, 1.0, 0), MS_OK);
  cd_sim_set_pair(s, 0, 0, t);
  assert_int_equal(cd_sim_init(s), MS_OK);
  return s;
}

static cd_sim *hot_block(const eos_t *eos, int n, double vamp, double gamma, double dt_frac,
                         cd_cutoff_mode mode) {
  return hot_block_with(eos, n, vamp, gamma, dt_frac, mode, CD_INT_VELOCITY_VERLET);
}

/* Runs nsteps, samples the balance every `every` steps; returns the drift (least-squares
 * slope × run time) and the largest deviation from the first sample, both relative to |E0|. */
static void balance(cd_sim *s, long nsteps, int every, double *drift, double *dev, double *e0out) {
  cd_energy e;
  cd_sim_energy(s, &e);
  const double e0 = e.total, scale = fabs(e.kinetic) + fabs(e.potential);
  double st = 0, se = 0, stt = 0, ste = 0, worst = 0;
  long m = 0;
  for (long k = 1; k <= nsteps; k++) {
    assert_int_equal(cd_sim_step(s), MS_OK);
    if (k % every) continue;
    cd_sim_energy(s, &e);
    double d = (e.total - e0) / scale;
    worst = fmax(worst, fabs(d));
    st += k;
    se += d;
    stt += (double)k * k;
    ste += k * d;
    m++;
  }
  double slope = (m * ste - st * se) / (m * stt - st * st);
  *drift = fabs(slope * nsteps);
  *dev = worst;
  if (e0out) *e0out = e0;
}

/* NVE, no damping, no bond breaking (amplitude 0.2 km/s keeps every pair far from R_c):
 * 10⁴ steps. With the benchmark's Δt = 0.02 r0/c0 Verlet's bounded energy oscillation is
 * ~5e-4 of the energy; its secular drift must stay below 1e-6. With Δt/40 the oscillation
 * itself (∝ Δt², so ~3e-7) stays below 1e-6 too. */
static void test_nve(void **state) {
  (void)state;
  eos_t *eos = al();
  double drift, dev;
  cd_sim *s = hot_block(eos, 3, 0.2, 0.0, 0.02, CD_CUTOFF_PLAIN);
  balance(s, 10000, 10, &drift, &dev, NULL);
  printf("NVE dt = 0.02 r0/c0: drift %.3g, max deviation %.3g (relative), rebuilds %ld\n", drift,
         dev, cd_sim_rebuilds(s));
  assert_true(drift < 1e-6);
  cd_energy e;
  cd_sim_energy(s, &e);
  assert_true(e.broken == 0.0); /* no pair crossed R_c */
  cd_sim_destroy(&s);
  s = hot_block(eos, 3, 0.2, 0.0, 0.0005, CD_CUTOFF_PLAIN);
  balance(s, 10000, 10, &drift, &dev, NULL);
  printf("NVE dt = 0.0005 r0/c0: drift %.3g, max deviation %.3g\n", drift, dev);
  assert_true(dev < 1e-6 && drift < 1e-6);
  cd_sim_destroy(&s);
  eos_destroy(&eos);
}

/* With damping Γ = c0/(50 a): kinetic + potential + dissipated is conserved like the NVE
 * energy, the damping really dissipates (more than 10 % of the initial kinetic energy over the
 * run), and momentum is conserved to round-off. While the damping cools the lattice, Verlet's
 * O((ωΔt)²) energy offset shrinks with it, which reads as a drift ~(ωΔt)² E0: 3.5e-5 at the
 * benchmark's Δt, so the 1e-6 balance is checked at Δt = 0.0005 r0/c0 (offset 1600× smaller),
 * 10⁴ steps (Γ t = 0.1). */
static void test_damping_balance(void **state) {
  (void)state;
  eos_t *eos = al();
  double drift, dev;
  cd_sim *s = hot_block(eos, 3, 0.2, C0 / (50 * R0), 0.0005, CD_CUTOFF_PLAIN);
  cd_energy e0, e1;
  cd_sim_energy(s, &e0);
  balance(s, 10000, 10, &drift, &dev, NULL);
  cd_sim_energy(s, &e1);
  printf("damped: drift %.3g, max deviation %.3g, dissipated %.4g of KE0 %.4g\n", drift, dev,
         e1.dissipated, e0.kinetic);
  assert_true(drift < 1e-6 && dev < 1e-6);
  assert_true(e1.dissipated > 0.1 * e0.kinetic);
  double pscale = 0;
  for (size_t i = 0; i < s->p->n; i++) pscale += s->p->mass[i] * fabs(s->p->vx[i]);
  for (int c = 0; c < 3; c++)
    assert_true(fabs(e1.momentum[c] - e0.momentum[c]) < 1e-12 * fmax(pscale, 1e-30) + 1e-25);
  cd_sim_destroy(&s);
  eos_destroy(&eos);
}

/* The largest difference between the forces in s (from its lists) and a brute-force sum over
 * all pairs (minimum image), relative to a typical pair force. */
static double forces_vs_brute_force(const cd_sim *s) {
  const ptl_state *p = s->p;
  const double L = s->box.hi[0];
  const cd_pair_table *t = s->pair[0][0];
  double worst = 0, fscale = fabs(cd_pair_table_force(t, 0.9 * R0));
  for (size_t i = 0; i < p->n; i++) {
    double f[3] = {0, 0, 0};
    for (size_t j = 0; j < p->n; j++) {
      if (j == i) continue;
      double d[3] = {p->x[i] - p->x[j], p->y[i] - p->y[j], p->z[i] - p->z[j]};
      for (int c = 0; c < 3; c++) d[c] -= L * round(d[c] / L);
      double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = sqrt(r2);
      /* the pair function the kernel uses: the fit on the fast path (cd_impl.h) */
      double fr = s->nl->full && r2 >= t->fit_slo && r2 < t->rc2 ? cd_pair_fit_eval(t, r2)
                                                                 : cd_pair_table_force(t, r) / r;
      for (int c = 0; c < 3; c++) f[c] += fr * d[c];
    }
    worst = fmax(worst, fabs(f[0] - p->fx[i]) + fabs(f[1] - p->fy[i]) + fabs(f[2] - p->fz[i]));
  }
  return worst / fscale;
}

/* Forces from the Verlet lists after many rebuilds equal a brute-force sum over all pairs
 * (minimum image) to round-off. Hot lattice (1.5 km/s) so that the lists are rebuilt often. */
static void test_lists_vs_brute_force(void **state) {
  (void)state;
  eos_t *eos = al();
  cd_sim *s = hot_block(eos, 4, 1.5, 0.0, 0.02, CD_CUTOFF_PLAIN);
  for (int k = 0; k < 1500; k++) assert_int_equal(cd_sim_step(s), MS_OK);
  assert_true(cd_sim_rebuilds(s) > 3);
  const double worst = forces_vs_brute_force(s);
  printf("lists vs brute force after %ld rebuilds: %.3g of a typical pair force\n",
         cd_sim_rebuilds(s), worst);
  assert_true(worst < 1e-9); /* only summation order differs */
  cd_sim_destroy(&s);
  eos_destroy(&eos);
}

/* The rebuild test ignores a common translation (neighbour.c): the same hot block, once at
 * rest and once drifting at (4, 3, 2) km/s — 30 r0 in 1500 steps, 600 times skin/2, which the
 * plain "every |Δ| < skin/2" test would answer with ~600 rebuilds. The two runs are the same
 * relative motion up to round-off; the drifting one measures displacements from the centre of
 * their bounding box instead of from zero, which may cost a few more rebuilds (allowed: 10 %
 * + 2), and its lists still give the brute-force forces. Then the test on constructed
 * displacements: a common part costs nothing, a spread beyond the skin fails. */
static void test_lists_moving_block(void **state) {
  (void)state;
  eos_t *eos = al();
  long rebuilds[2];
  for (int drift = 0; drift < 2; drift++) {
    cd_sim *s = hot_block(eos, 4, 1.5, 0.0, 0.02, CD_CUTOFF_PLAIN);
    for (size_t i = 0; drift && i < s->p->n; i++) {
      s->p->vx[i] += 4.0;
      s->p->vy[i] += 3.0;
      s->p->vz[i] += 2.0;
    }
    for (int k = 0; k < 1500; k++) assert_int_equal(cd_sim_step(s), MS_OK);
    rebuilds[drift] = cd_sim_rebuilds(s);
    if (drift) {
      const double worst = forces_vs_brute_force(s);
      printf("drifting block: %ld rebuilds (at rest %ld), lists vs brute force %.3g\n", rebuilds[1],
             rebuilds[0], worst);
      assert_true(worst < 1e-9);
    }
    cd_sim_destroy(&s);
  }
  assert_true(rebuilds[0] > 3 && rebuilds[1] <= rebuilds[0] + rebuilds[0] / 10 + 2);
  eos_destroy(&eos);

  /* four particles displaced from build positions at 0 (skin 0.1: skin/2 = 0.05; xb_err 0) */
  cd_neigh *nl = NULL;
  ms_must(cd_neigh_create(&(cd_neigh_params){.cap = 4, .rlist = 1.1, .skin = 0.1}, &nl),
          "cd_neigh_create");
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = 4, .dim = 3}, &p), "ptl_state_create");
  p->n = 4;
  const double dx[4] = {9.97, 10.03, 10.0, 10.0}; /* |Δ| ≈ 10, all within 0.03 of (10, 0, 0) */
  for (int i = 0; i < 4; i++) p->x[i] = dx[i];
  assert_true(cd_neigh_holds(nl, p, 4, INFINITY, 0.0, false, NULL));
  assert_false(cd_neigh_holds(nl, p, 4, INFINITY, 0.03, false, NULL)); /* 0.03 + 0.03 > 0.05 */
  p->y[2] = 0.035;
  p->y[3] = -0.035; /* box half-diagonal 0.046 */
  assert_true(cd_neigh_holds(nl, p, 4, INFINITY, 0.0, false, NULL));
  const double sq[4][2] = {{9.96, 0}, {10.04, 0}, {10, 0.04}, {10, -0.04}};
  for (int i = 0; i < 4; i++) p->x[i] = sq[i][0], p->y[i] = sq[i][1];
  /* half-diagonal 0.057, but each particle 0.04 from the centre: the second pass */
  assert_true(cd_neigh_holds(nl, p, 4, INFINITY, 0.0, false, NULL));
  p->x[2] = 10.03;
  p->y[2] = 0.045; /* now 0.052 from the box's centre (10, 0.0025) */
  assert_false(cd_neigh_holds(nl, p, 4, INFINITY, 0.0, false, NULL));
  for (int i = 0; i < 4; i++) p->x[i] = p->y[i] = 0.04; /* |Δ| = 0.057 but no spread */
  assert_true(cd_neigh_holds(nl, p, 4, INFINITY, 0.0, false, NULL));
  /* extents the caller took (vv_step's loop) stand for the positions: a spread of 0.2 along x */
  const double wide[7] = {0.01, 0.1, 0.0, 0.0, 0.1, 0.0, 0.0};
  assert_false(cd_neigh_holds(nl, p, 4, INFINITY, 0.0, false, wide));
  p->x[0] = -0.02; /* particles 0 and 1 end up 0.117 apart: no vector is within 0.05 of both */
  p->z[1] = 0.1;
  assert_false(cd_neigh_holds(nl, p, 4, INFINITY, 0.0, false, NULL));
  assert_true(cd_neigh_holds(nl, p, 4, 0.049, 0.0, false, NULL)); /* a bound < 0.05 is trusted */
  p->x[0] = NAN;
  assert_false(cd_neigh_holds(nl, p, 4, INFINITY, 0.0, false, NULL));
  ptl_state_destroy(&p);
  cd_neigh_destroy(&nl);
}

/* The fast path (the fit of F/r on full lists, AVX-512 builds) against the table path (the
 * half-list kernel of diagnostics, forces written) on a hot periodic lattice with image
 * entries, after 300 steps (several list builds) of the fast path. Bound: the set-up check puts the fit within 1e-9
 * of max|F/r| of the table at every s, so a particle's force differs by at most
 * 12 pairs × 1e-9 max|F/r| × R_c (a pair missed or counted twice would differ by a whole pair
 * force, ~1e-2 of that scale). Each pair's two forces are exact opposites, so Σ f vanishes
 * up to the rounding of the per-particle sums, and momentum stays at round-off. */
static void test_fit_path_vs_table(void **state) {
  (void)state;
  eos_t *eos = al();
  /* 0.5 km/s: lists live ~25 steps, so they stay full (cd_sim.c, CD_FULL_MIN_STEPS) */
  cd_sim *s = hot_block(eos, 5, 0.5, 0.0, 0.02, CD_CUTOFF_PLAIN);
  double p0[3] = {0, 0, 0}, pabs = 0.0;
  cd_energy e;
  cd_sim_energy(s, &e);
  memcpy(p0, e.momentum, sizeof p0);
  for (size_t i = 0; i < s->p->n; i++) pabs += s->p->mass[i] * fabs(s->p->vx[i]);
  for (int k = 0; k < 300; k++) assert_int_equal(cd_sim_step(s), MS_OK);
  cd_sim_energy(s, &e);
  double dp = 0.0;
  for (int c = 0; c < 3; c++) dp = fmax(dp, fabs(e.momentum[c] - p0[c]));
  printf("fit path: momentum change over 300 steps %.3g of sum m|vx|\n", dp / pabs);
  assert_true(dp < 1e-12 * pabs);
  const size_t n = s->p->n;
  const cd_neigh *nl = s->nl;
  long nimg = 0;
  for (int32_t q = 0; q < nl->layer_start[nl->nlayer]; q++) nimg += nl->nimg[q];
  assert_true(nimg > 0); /* periodic images are exercised */
  assert_true(cd_sim_rebuilds(s) > 3);
  if (cd_simd_level_ == CD_SIMD_AVX512) assert_true(nl->full); /* the fast path is on */
  ptl_state *p = s->p;
  double *ff = malloc(3 * n * sizeof *ff);
  cd_compute_forces(s, NULL, NULL, true); /* fast path */
  double sum[3] = {0, 0, 0}, fabs_sum = 0.0;
  for (size_t i = 0; i < n; i++) {
    ff[3 * i] = p->fx[i], ff[3 * i + 1] = p->fy[i], ff[3 * i + 2] = p->fz[i];
    sum[0] += p->fx[i], sum[1] += p->fy[i], sum[2] += p->fz[i];
    fabs_sum += fabs(p->fx[i]) + fabs(p->fy[i]) + fabs(p->fz[i]);
  }
  cd_compute_forces(s, s->sums, NULL, true); /* table path */
  const cd_pair_table *t = s->pair[0][0];
  double frmax = 0.0, worst = 0.0;
  for (int k = 0; k <= 1000; k++)
    frmax = fmax(frmax, fabs(cd_pair_table_force(t, t->rc * (0.5 + 0.5 * k / 1000.0)) /
                             (t->rc * (0.5 + 0.5 * k / 1000.0))));
  for (size_t i = 0; i < n; i++)
    worst = fmax(worst, fmax(fabs(ff[3 * i] - p->fx[i]),
                             fmax(fabs(ff[3 * i + 1] - p->fy[i]), fabs(ff[3 * i + 2] - p->fz[i]))));
  printf("fit path vs table: max force difference %.3g of max|F/r| R_c, |sum f| %.3g of sum|f|\n",
         worst / (frmax * t->rc), fmax(fabs(sum[0]), fmax(fabs(sum[1]), fabs(sum[2]))) / fabs_sum);
  assert_true(worst <= 12 * 1e-9 * frmax * t->rc);
  for (int c = 0; c < 3; c++) assert_true(fabs(sum[c]) < 1e-13 * fabs_sum);
  free(ff);
  cd_sim_destroy(&s);
  eos_destroy(&eos);
}

/* The layer colouring makes every force sum's order independent of the thread count:
 * bitwise identical trajectories with 1 and 2 threads (damping on: its loops too; damping off:
 * the fast path, where each particle's force is summed by one thread). */
static void test_threads_bitwise(void **state) {
  (void)state;
  eos_t *eos = al();
  double *pos[2];
  for (int run = 0; run < 4; run++) {
    omp_set_num_threads(run % 2 + 1);
    /* 13³ cells = 8788 particles: above the size where loops go parallel */
    cd_sim *s = hot_block(eos, 13, 1.0, run < 2 ? C0 / (50 * R0) : 0.0, 0.02, CD_CUTOFF_PLAIN);
    for (int k = 0; k < 100; k++) assert_int_equal(cd_sim_step(s), MS_OK);
    size_t n = s->p->n;
    if (run == 2) free(pos[0]), free(pos[1]);
    pos[run % 2] = malloc(3 * n * sizeof(double));
    /* particles may be renumbered: index by gid */
    for (size_t i = 0; i < n; i++) {
      size_t g = (size_t)s->p->gid[i];
      pos[run % 2][3 * g] = s->p->x[i];
      pos[run % 2][3 * g + 1] = s->p->y[i];
      pos[run % 2][3 * g + 2] = s->p->z[i];
    }
    if (run % 2 == 1) assert_memory_equal(pos[0], pos[1], 3 * n * sizeof(double));
    cd_sim_destroy(&s);
  }
  free(pos[0]);
  free(pos[1]);
  eos_destroy(&eos);
}

/* Piston (1 km/s) into a free slab: kinetic + potential + broken − piston work stays
 * constant. Bonded mode (partners fixed at set-up): smooth forces, the shock front's Verlet
 * error stays below 1e-5 of the work. Plain cutoff: pairs of the second shell flicker across
 * R_c at the front (the known trap), each crossing books E(R_c) exactly but integrates a force
 * jump f(R_c) with an O(f Δt v) error: balance to 1e-3 of the work. */
static double piston_run(const eos_t *eos, cd_cutoff_mode mode, cd_integrator integ, cd_energy *e1,
                         double *D) {
  const int nx = 3, nz = 40;
  const double a = sqrt(2.0) * R0, m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = (size_t)4 * nx * nx * nz, .dim = 3}, &p),
          "ptl_state_create");
  double sh[3] = {0.25, 0.25, 0.0}, o[3] = {0, 0, 0};
  cd_lattice_fcc(p, nx, nx, nz, sh, o, R0, m, 0);
  for (size_t i = 0; i < (size_t)4 * nx * nx * 2; i++) p->flags[i] = PTL_DRIVEN;
  cd_box box = {.hi = {nx * a, nx * a, nz * a}, .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, CD_BC_FREE}};
  cd_config cfg = {.r0 = R0,
                   .skin = 0.1 * R0,
                   .dt = 0.02 * R0 / C0,
                   .cutoff = mode,
                   .lattice = CD_LATTICE_FCC,
                   .integrator = integ};
  cd_sim *s = NULL;
  ms_must(cd_sim_create(&(cd_sim_params){.particles = p, .box = &box, .cfg = &cfg, .nmat = 1}, &s),
          "cd_sim_create");
  cd_pair_table *t = calloc(1, sizeof *t);
  assert_int_equal(
      cd_pair_table_build(t, eos, eos, CD_LATTICE_FCC, R0, 0, 1.2 * R0, 0.5 * R0, 1.0, 0), MS_OK);
  cd_sim_set_pair(s, 0, 0, t);
  double th[2] = {0, 1}, uh[2] = {1.0, 1.0}, dir[3] = {0, 0, 1};
  cd_history h = {2, th, uh};
  cd_sim_set_piston(s, &h, dir);
  assert_int_equal(cd_sim_init(s), MS_OK);
  cd_energy e0;
  cd_sim_energy(s, &e0);
  /* shock speed: front (bin-mean vz = ½ u) every 100 steps while it crosses the middle of the
   * slab (it reaches the free end near step 2000), least squares */
  const int nbin = nz + 10;
  double prof[(40 + 10) * CD_PROFILE_NCOL], st = 0, sz = 0, stt = 0, stz = 0;
  int nfit = 0;
  for (int k = 1; k <= 3000; k++) {
    assert_int_equal(cd_sim_step(s), MS_OK);
    if (k % 100 || k < 400 || k > 1800) continue;
    cd_profile(s, 2, -0.25 * a, (nbin - 0.25) * a, nbin, nx * a * nx * a, prof);
    double zf = cd_front_position(prof, nbin, 2, 1.0, 0.5);
    st += s->t;
    sz += zf;
    stt += s->t * s->t;
    stz += s->t * zf;
    nfit++;
  }
  *D = (nfit * stz - st * sz) / (nfit * stt - st * st);
  cd_sim_energy(s, e1);
  double err = (e1->total - e0.total) / e1->piston_work;
  printf("piston (%s, %s): work %.6g, KE %.6g PE %.6g broken %.3g, balance error %.3g of the work, "
         "D = %.5f km/s\n",
         mode == CD_CUTOFF_PLAIN ? "plain" : "bonded", cd_integrator_names[integ], e1->piston_work,
         e1->kinetic, e1->potential, e1->broken, err, *D);
  cd_sim_destroy(&s);
  return err;
}

static void test_piston_balance(void **state) {
  (void)state;
  eos_t *eos = al();
  cd_energy e;
  double D;
  double err = piston_run(eos, CD_CUTOFF_BONDED, CD_INT_VELOCITY_VERLET, &e, &D);
  assert_true(e.piston_work > 0);
  assert_true(fabs(err) < 1e-5);
  err = piston_run(eos, CD_CUTOFF_PLAIN, CD_INT_VELOCITY_VERLET, &e, &D);
  assert_true(fabs(err) < 1e-3);
  eos_destroy(&eos);
}

/* ---- the integrators (cfg.integrator): velocity Verlet and the RKN family ---- */

/* Positions after `steps` steps of dt·c0/r0 = dt_frac, indexed by gid ([N][3]). */
static double *positions_after(const eos_t *eos, cd_integrator integ, double dt_frac, long steps,
                               long *rebuilds) {
  cd_sim *s = hot_block_with(eos, 3, 0.2, 0.0, dt_frac, CD_CUTOFF_PLAIN, integ);
  for (long k = 0; k < steps; k++) assert_int_equal(cd_sim_step(s), MS_OK);
  const ptl_state *p = s->p;
  double *x = malloc(3 * p->n * sizeof *x);
  for (size_t i = 0; i < p->n; i++) {
    size_t g = (size_t)p->gid[i];
    x[3 * g] = p->x[i];
    x[3 * g + 1] = p->y[i];
    x[3 * g + 2] = p->z[i];
  }
  *rebuilds = cd_sim_rebuilds(s);
  cd_sim_destroy(&s);
  return x;
}

/* max |x − y| over particles, minimum image in the periodic 3-cell block */
static double max_distance(const double *x, const double *y, size_t n) {
  const double L = 3 * sqrt(2.0) * R0;
  double worst = 0.0;
  for (size_t k = 0; k < 3 * n; k++) {
    double d = x[k] - y[k];
    d -= L * round(d / L);
    worst = fmax(worst, fabs(d));
  }
  return worst;
}

/* Convergence order on smooth dynamics: the 108-particle periodic block with 0.2 km/s random
 * velocities (anharmonic lattice vibrations, no pair crosses R_c), t = 2 r0/c0, errors of Δt
 * and Δt/2 against the same scheme at Δt/16. Δt = 0.05 r0/c0 keeps ω_max Δt ≈ 0.2, where the
 * next term of the error expansion moves the measured order by < 0.05 (1 and 3 force
 * evaluations per step: order 2 for the Verlets, 4 for SIA4, RKN4 and its conjugate);
 * asserted within ±0.15. */
static void test_integrator_order(void **state) {
  (void)state;
  eos_t *eos = al();
  const int expected[CD_INT_COUNT] = {2, 2, 4, 4, 4};
  const double dt0 = 0.05, t_end = 2.0;
  for (int k = 0; k < CD_INT_COUNT; k++) {
    long nb[3];
    const long n0 = (long)lround(t_end / dt0);
    double *x1 = positions_after(eos, (cd_integrator)k, dt0, n0, nb);
    double *x2 = positions_after(eos, (cd_integrator)k, dt0 / 2, 2 * n0, nb + 1);
    double *xr = positions_after(eos, (cd_integrator)k, dt0 / 16, 16 * n0, nb + 2);
    double e1 = max_distance(x1, xr, 108), e2 = max_distance(x2, xr, 108);
    double order = log2(e1 / e2);
    printf(
        "%-16s error %.3e (dt) %.3e (dt/2) of r0: order %.3f (expected %d), rebuilds %ld %ld %ld\n",
        cd_integrator_names[k], e1 / R0, e2 / R0, order, expected[k], nb[0], nb[1], nb[2]);
    assert_true(fabs(order - expected[k]) < 0.15);
    free(x1);
    free(x2);
    free(xr);
  }
  eos_destroy(&eos);
}

/* NVE with every scheme, 10⁴ steps: secular drift of kinetic + potential below 1e-6 relative.
 * The schemes are symplectic, so their energy error is a bounded oscillation ~(ω Δt)^order; at
 * the benchmark's Δt = 0.02 r0/c0 the Verlets' oscillation is 5e-4 and the least-squares
 * slope of it over 10⁴ steps scatters up to ~3e-6 with no secular trend (measured: 6.7e-8
 * velocity Verlet, 2.8e-6 position Verlet; 8e-7 and 3e-7 at Δt/2, 7e-9 and 1.1e-7 at Δt/4).
 * So every scheme is asserted at Δt = 0.005 r0/c0 (oscillation 3.3e-5), and the fourth-order
 * ones also at 0.02 (oscillation ≤ 5e-7). */
static void test_integrator_nve(void **state) {
  (void)state;
  eos_t *eos = al();
  const double dts[2] = {0.02, 0.005};
  for (int q = 0; q < 2; q++)
    for (int k = 0; k < CD_INT_COUNT; k++) {
      if (q == 0 && k <= CD_INT_POSITION_VERLET) continue;
      double drift, dev;
      cd_sim *s = hot_block_with(eos, 3, 0.2, 0.0, dts[q], CD_CUTOFF_PLAIN, (cd_integrator)k);
      balance(s, 10000, 10, &drift, &dev, NULL);
      printf("NVE %-16s dt %.3g r0/c0: drift %.3g, max deviation %.3g (relative)\n",
             cd_integrator_names[k], dts[q], drift, dev);
      assert_true(drift < 1e-6);
      cd_sim_destroy(&s);
    }
  eos_destroy(&eos);
}

/* The SIMD kernels against their scalar references (cd_force_fit.h, neighbour_select.h), which
 * do the same operations per particle in the same order: forces and kicked velocities of every
 * layer, and the candidates of ranges of sorted positions, must be equal (==: exact; the one
 * freedom, the sign of a zero, does not count). Compared after some steps of a hot periodic
 * block, so that images and unordered groups are exercised. */
static void test_kernels_vs_scalar(void **state) {
  (void)state;
  eos_t *eos = al();
  cd_sim *s = hot_block(eos, 5, 0.5, 0.0, 0.02, CD_CUTOFF_PLAIN);
  for (int k = 0; k < 10; k++) assert_int_equal(cd_sim_step(s), MS_OK);
  ptl_state *p = s->p;
  const cd_neigh *nl = s->nl;
  const size_t n = p->n;
#if defined(CD_FIT_AVX512) /* the kernel is in the build: compared where the CPU runs it */
  if (cd_simd_level_ == CD_SIMD_AVX512) {
    assert_true(nl->full); /* lists live ~25 steps (test_fit_path_vs_table): still the first */
    const cd_pair_table *t = s->pair[0][0];
    double *f0 = malloc(6 * n * sizeof *f0), *v0 = malloc(3 * n * sizeof *v0);
    double *arr[6] = {p->fx, p->fy, p->fz, p->vx, p->vy, p->vz};
    for (size_t i = 0; i < n; i++)
      for (int c = 0; c < 3; c++) v0[3 * i + c] = arr[3 + c][i];
    long compared = 0;
    for (int pass = 0; pass < 2; pass++) { /* hdt = 0: forces only; hdt > 0: the closing kick */
      const double hdt = pass ? 0.5 * s->cfg.dt : 0.0;
      for (int kernel = 0; kernel < 2; kernel++) {
        for (size_t i = 0; i < n; i++)
          for (int c = 0; c < 3; c++) {
            arr[c][i] = 0.0;
            arr[3 + c][i] = v0[3 * i + c];
          }
        for (int l = 0; l < nl->nlayer; l++) {
          if (kernel == 0) cd_layer_forces_fit_scalar(nl, p, t, l, hdt);
          else cd_layer_forces_fit_avx512(nl, p, t, l, hdt);
        }
        for (size_t i = 0; i < n; i++)
          for (int c = 0; c < 6; c++) {
            if (kernel == 0) f0[6 * i + c] = arr[c][i];
            else assert_true(arr[c][i] == f0[6 * i + c]);
          }
      }
      compared += (long)n;
    }
    double fmax_ = 0.0;
    for (size_t i = 0; i < 3 * n; i++) fmax_ = fmax(fmax_, fabs(f0[i]));
    assert_true(fmax_ > 0.0); /* a hot block: the forces are not all zero */
    printf("fit kernels: AVX-512 == scalar on %ld particle evaluations\n", compared);
    free(f0);
    free(v0);
  }
#endif
#if defined(CD_SELECT_AVX2)
  fill_compress_lut(); /* this file's copy of the table (neighbour_select_simd.h) */
#endif
  /* candidate selection: random ranges of sorted positions (cells are contiguous in them),
   * queried from a particle in the range, with and without an image shift, against the scalar
   * reference */
  const int32_t npos = nl->layer_start[nl->nlayer];
  int32_t *a = malloc((size_t)(npos + 16) * sizeof *a),
          *b = malloc((size_t)(npos + 16) * sizeof *b);
  const float rl2 = (float)(nl->rlist * nl->rlist), shift[3] = {(float)(5 * sqrt(2.0) * R0), 0, 0};
  long taken = 0;
  const int detected = cd_simd_level_;
  for (int k = 0; k < 500 * (detected + 1); k++) { /* every kernel this CPU runs */
    cd_simd_level_ = k / 500;
    const int32_t q = (int32_t)(ptl_splitmix64_uniform(19, 3 * (uint64_t)(k % 500)) * npos);
    const int32_t len = 1 + (int32_t)(ptl_splitmix64_uniform(19, 3 * (uint64_t)(k % 500) + 1) * 60);
    const int32_t q0 = q, q1 = q + len < npos ? q + len : npos;
    const int32_t i = nl->sorted[q0 + (q1 - q0) / 2]; /* a query among the candidates */
    const float *sv = k % 2 ? shift : NULL;
    const float xi = (float)p->x[i], yi = (float)p->y[i], zi = (float)p->z[i];
    const int na = cd_select_range_scalar(nl, q0, q1, sv, xi, yi, zi, rl2, a);
    const int nb = select_range(nl, q0, q1, sv, xi, yi, zi, rl2, b);
    assert_int_equal(na, nb);
    for (int m = 0; m < na; m++) assert_int_equal(a[m], b[m]);
    taken += na;
  }
  cd_simd_level_ = detected;
  assert_true(taken > 0);
  printf("candidate selection: the %s, ... kernels == scalar on 500 ranges each (%ld taken)\n",
         cd_kernel_name(), taken);
  free(a);
  free(b);
  cd_sim_destroy(&s);
  eos_destroy(&eos);
}

/* Piston (1 km/s, bonded cutoff) with every scheme: the same shock speed as velocity Verlet and
 * a closed balance (work quadrature of each scheme: trapezoid for velocity Verlet, the stage
 * weights γ_l for RKN). The run starts from a perfect lattice at rest, so the schemes differ
 * only by truncation errors (measured: D within 3e-5 of velocity Verlet's); asserted to 1e-3,
 * far below the 3 % of the Hugoniot comparison and far above the measured scatter. */
static void test_integrator_piston(void **state) {
  (void)state;
  eos_t *eos = al();
  cd_energy e;
  double D0 = 0.0;
  for (int k = 0; k < CD_INT_COUNT; k++) {
    double D, err = piston_run(eos, CD_CUTOFF_BONDED, (cd_integrator)k, &e, &D);
    if (k == 0) D0 = D;
    assert_true(fabs(D - D0) < 1e-3 * D0);
    assert_true(fabs(err) < 1e-5);
  }
  eos_destroy(&eos);
}

/* Two ctest entries share this file: the default group is `unit` (also run under the sanitizers);
 * `integrators` (the per-scheme order, drift and piston runs: ~1 min of CPU in Release, far more
 * under ASan) is registered as test_cd_integrators with the `validation` label. */
int main(int argc, char **argv) {
  const struct CMUnitTest core[] = {cmocka_unit_test(test_nve),
                                    cmocka_unit_test(test_damping_balance),
                                    cmocka_unit_test(test_lists_vs_brute_force),
                                    cmocka_unit_test(test_lists_moving_block),
                                    cmocka_unit_test(test_fit_path_vs_table),
                                    cmocka_unit_test(test_kernels_vs_scalar),
                                    cmocka_unit_test(test_threads_bitwise),
                                    cmocka_unit_test(test_piston_balance)};
  const struct CMUnitTest integrators[] = {cmocka_unit_test(test_integrator_order),
                                           cmocka_unit_test(test_integrator_nve),
                                           cmocka_unit_test(test_integrator_piston)};
  if (argc > 1 && !strcmp(argv[1], "integrators"))
    return cmocka_run_group_tests(integrators, NULL, NULL);
  return cmocka_run_group_tests(core, NULL, NULL);
}
