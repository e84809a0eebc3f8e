/* SPDX-License-Identifier: MIT */
/* The energy-shifted cutoff (cutoff_mode shifted, docs/particles-cd.md "The cutoff"): the shifted
 * potential E(r) − E(R_c) of [AllenTildesley1987] (p. 145) on the tabulated [Davydov] potential.
 * The table's energy is continuous at R_c and its forces (table and fit) are the plain table's
 * bit for bit; two clusters passing through each other's cutoff conserve K + V to the bound of
 * the force jump's work, where the plain cutoff's K + V jumps by E(R_c); the two modes' runs
 * are the same trajectory and book the same total energy. */
#include <math.h>
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
#define C0 5.35
#define RC (1.2 * R0)

/* the benchmark's aluminium cold curve (cd_lammps.md): rho0 2.71, c0 5.35, n 4 */
static eos_t *al_mg(void) { return eos_create_mg_cold(2.71, C0, 4.0, 2.0, true); }

static void build(cd_pair_table *t, const eos_t *eos) {
  assert_int_equal(cd_pair_table_build(t, eos, eos, CD_LATTICE_FCC, R0, 0.0, RC, 0.5 * R0, 1.0, 0),
                   MS_OK);
}

/* E continuous at R_c; E(r) = E_plain(r) − E(R_c) on [0.4 r0, R_c) (below r_min too); forces and
 * the fit untouched (bitwise); a second shift does nothing. */
static void test_table(void **state) {
  (void)state;
  eos_t *eos = al_mg();
  cd_pair_table plain, sh;
  build(&plain, eos);
  build(&sh, eos);
  cd_pair_table_shift_energy(&sh);
  const double erc = plain.e_rc, frc = cd_pair_table_force(&plain, nextafter(RC, 0.0));
  assert_true(erc > 0.0); /* the well's depth seen from outside (E(r0) = 0 is its bottom) */
  assert_true(sh.e_shift == erc && sh.e_rc == 0.0);
  /* just inside R_c the shifted energy is E'(R_c)·(R_c − r) plus the cubic's rounding at its
   * end node (a few ulps of the e coefficients, which are <= E(r_min) ~ 1e3 E(R_c) at 0.5 r0
   * for this curve: allow 1e-12 E(R_c)); the plain energy is E(R_c) there */
  const double rin = RC * (1.0 - 1e-12);
  const double e_sh = cd_pair_table_energy(&sh, rin), e_pl = cd_pair_table_energy(&plain, rin);
  printf("E(R_c) = %.6g, f(R_c) = %.6g; just inside R_c: shifted E = %.3g, plain E = %.6g\n", erc,
         frc, e_sh, e_pl);
  assert_true(fabs(e_sh) <= fabs(frc) * RC * 1e-12 + 1e-12 * erc);
  assert_true(fabs(e_pl - erc) <= 1e-9 * erc);
  assert_true(cd_pair_table_energy(&sh, RC) == 0.0); /* beyond: 0 as before */
  double worst = 0.0;
  for (int k = 0; k <= 4000; k++) {
    const double r = 0.4 * R0 + (RC - 0.4 * R0) * k / 4001.0;
    const double d = cd_pair_table_energy(&sh, r) - (cd_pair_table_energy(&plain, r) - erc);
    worst = fmax(worst, fabs(d));
    assert_true(cd_pair_table_force(&sh, r) == cd_pair_table_force(&plain, r)); /* bitwise */
  }
  printf("max |E_shifted − (E_plain − E(R_c))| on [0.4 r0, R_c): %.3g E(R_c)\n", worst / erc);
  /* two roundings of numbers up to E(0.4 r0) (~1e4 E(R_c)): below 1e-10 E(R_c) */
  assert_true(worst <= 1e-10 * erc);
  assert_memory_equal(sh.fcoef, plain.fcoef, (size_t)(plain.nint + 1) * 4 * sizeof(double));
  assert_memory_equal(sh.fit_coef, plain.fit_coef, sizeof plain.fit_coef);
  assert_true(sh.fit_ok == plain.fit_ok && sh.fit_slo == plain.fit_slo);
  const double e_mid = cd_pair_table_energy(&sh, 1.1 * R0);
  cd_pair_table_shift_energy(&sh);
  assert_true(cd_pair_table_energy(&sh, 1.1 * R0) == e_mid);
  cd_pair_table_free(&plain);
  cd_pair_table_free(&sh);
  eos_destroy(&eos);
}

/* The perfect lattice at rest (periodic fcc block of 3³ cells, 108 clusters, 6 pairs each at
 * r0, the second shell at √2 r0 beyond R_c): plain V = 0 (E(r0) = 0 is a node of the table;
 * the sites' rounding leaves ~1e-28 of the scale below); shifted V = −6 N E(R_c), the cohesive energy of the pair model (what dispersing the
 * lattice into free clusters costs), to the rounding of 648 terms. */
/* One material's simulation of p in box with the Al table, forces at t = 0. */
static cd_sim *start(ptl_state *p, const cd_box *box, const cd_config *cfg, const eos_t *eos) {
  cd_sim *s = NULL;
  ms_must(cd_sim_create(&(cd_sim_params){.particles = p, .box = box, .cfg = cfg, .nmat = 1}, &s),
          "cd_sim_create");
  cd_pair_table *t = calloc(1, sizeof *t);
  build(t, eos);
  cd_sim_set_pair(s, 0, 0, t);
  assert_int_equal(cd_sim_init(s), MS_OK);
  return s;
}

static double lattice_potential(const eos_t *eos, cd_cutoff_mode mode, size_t *n) {
  const int nc = 3;
  const double a = sqrt(2.0) * R0, m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = (size_t)4 * nc * nc * nc, .dim = 3}, &p),
          "ptl_state_create");
  const double sh[3] = {0.25, 0.25, 0.25}, o[3] = {0, 0, 0};
  cd_lattice_fcc(p, nc, nc, nc, sh, o, R0, m, 0);
  *n = p->n;
  cd_box box = {.lo = {0, 0, 0},
                .hi = {nc * a, nc * a, nc * a},
                .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, CD_BC_PERIODIC}};
  cd_config cfg = {
      .r0 = R0, .skin = 0.1 * R0, .dt = 0.02 * R0 / C0, .cutoff = mode, .lattice = CD_LATTICE_FCC};
  cd_sim *s = start(p, &box, &cfg, eos);
  cd_energy e;
  cd_sim_energy(s, &e);
  cd_sim_destroy(&s);
  return e.potential;
}

static void test_cohesive(void **state) {
  (void)state;
  eos_t *eos = al_mg();
  cd_pair_table t;
  build(&t, eos);
  const double erc = t.e_rc;
  cd_pair_table_free(&t);
  size_t n;
  const double vp = lattice_potential(eos, CD_CUTOFF_PLAIN, &n);
  const double vs = lattice_potential(eos, CD_CUTOFF_SHIFTED, &n);
  printf("lattice at rest, %zu clusters: V plain %.3g, shifted %.10g = %.12f x (-6 N E(R_c))\n", n,
         vp, vs, vs / (-6.0 * (double)n * erc));
  assert_true(fabs(vp) <= 1e-12 * 6.0 * (double)n * erc);
  assert_true(fabs(vs + 6.0 * (double)n * erc) <= 1e-12 * 6.0 * (double)n * erc);
  eos_destroy(&eos);
}

/* Two clusters approaching head-on along x from 1.3 r0 apart with relative speed v: they enter
 * R_c, fall through the well, bounce off the core and leave R_c again (v is chosen so that
 * ¼ m v² = 4 E(R_c), well above the ¼ m v² > E(R_c) needed to escape). */
typedef struct crossing {
  double dev_hk;   /* max |(K + V) − (K + V)(0)| over the run */
  double total[2]; /* the booked total (K + V + broken) at the start and the end */
  double broken;   /* booked broken energy at the end */
  double x[2], vx[2];
  long inside_steps; /* steps with the pair inside R_c */
} crossing;

static crossing cross(const eos_t *eos, cd_cutoff_mode mode, double dt, double v, long nsteps) {
  const double m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = 2, .dim = 3}, &p), "ptl_state_create");
  for (int i = 0; i < 2; i++) {
    const size_t k = ptl_state_add(p, (i ? 0.65 : -0.65) * R0, 0.0, 0.0, m, 0);
    p->vx[k] = (i ? -0.5 : 0.5) * v;
  }
  cd_box box = {.lo = {-1, -1, -1}, .hi = {1, 1, 1}, .bc = {CD_BC_FREE, CD_BC_FREE, CD_BC_FREE}};
  cd_config cfg = {.r0 = R0, .skin = 0.1 * R0, .dt = dt, .cutoff = mode, .lattice = CD_LATTICE_FCC};
  cd_sim *s = start(p, &box, &cfg, eos);
  crossing c = {0};
  cd_energy e;
  cd_sim_energy(s, &e);
  const double h0 = e.kinetic + e.potential;
  c.total[0] = e.total;
  for (long k = 0; k < nsteps; k++) {
    assert_int_equal(cd_sim_step(s), MS_OK);
    cd_sim_energy(s, &e);
    c.dev_hk = fmax(c.dev_hk, fabs(e.kinetic + e.potential - h0));
    const ptl_state *q = cd_sim_particles(s);
    if (fabs(q->x[1] - q->x[0]) < RC) c.inside_steps++;
  }
  c.total[1] = e.total;
  c.broken = e.broken;
  const ptl_state *q = cd_sim_particles(s);
  for (int i = 0; i < 2; i++) {
    c.x[i] = q->x[i];
    c.vx[i] = q->vx[i];
  }
  const ptl_state *end = cd_sim_particles(s);
  assert_true(fabs(end->x[1] - end->x[0]) > RC); /* they have left each other */
  cd_sim_destroy(&s);
  return c;
}

static void test_crossing(void **state) {
  (void)state;
  eos_t *eos = al_mg();
  cd_pair_table t;
  build(&t, eos);
  const double erc = t.e_rc, frc = fabs(cd_pair_table_force(&t, nextafter(RC, 0.0)));
  cd_pair_table_free(&t);
  const double m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  const double v = sqrt(16.0 * erc / m); /* ¼ m v² = 4 E(R_c) */
  /* a quarter of the benchmark's step, so that the bound below is a tenth of E(R_c) or less */
  const double dt = 0.005 * R0 / C0;
  /* through 1.3 r0 of approach, the well and out again: the pair moves at least v, so 3 r0/v
   * suffices */
  const long nsteps = (long)ceil(3.0 * R0 / v / dt);
  crossing pl = cross(eos, CD_CUTOFF_PLAIN, dt, v, nsteps);
  crossing sh = cross(eos, CD_CUTOFF_SHIFTED, dt, v, nsteps);
  /* The bound: velocity Verlet samples the force at the steps; across R_c the force jumps by
   * f(R_c), so the step that crosses does work wrong by at most |f(R_c)| times the distance
   * moved inside that step, <= |f(R_c)| u Δt with u the relative speed there (u <= v: the
   * well speeds the pair up only inside R_c, u at R_c is v); two crossings. The smooth part's
   * Verlet error, O((Δt/T_well)²) of the well's energy, is far below that at this Δt (one
   * pass). Plain adds E(R_c) to K + V while inside. So shifted <= B = 2 |f(R_c)| v Δt and
   * plain >= E(R_c) − B: a factor E(R_c)/B − 1 at least. */
  const double bound = 2.0 * frc * v * dt;
  printf("v = %.4g km/s, %ld steps (%ld inside R_c): max |Δ(K + V)| plain %.4g, shifted %.4g "
         "E(R_c); bound B = %.4g E(R_c); factor %.1f (guaranteed >= %.1f)\n",
         v, nsteps, sh.inside_steps, pl.dev_hk / erc, sh.dev_hk / erc, bound / erc,
         pl.dev_hk / sh.dev_hk, erc / bound - 1.0);
  assert_true(sh.inside_steps > 10 && sh.inside_steps == pl.inside_steps);
  assert_true(sh.dev_hk <= bound);
  assert_true(pl.dev_hk >= erc - bound);
  assert_true(erc / bound > 10.0); /* the set-up discriminates by more than an order */
  /* the same trajectory, bit for bit: the forces are the plain table's */
  for (int i = 0; i < 2; i++) {
    assert_true(sh.x[i] == pl.x[i]);
    assert_true(sh.vx[i] == pl.vx[i]);
  }
  /* the booking: shifted books nothing as broken; plain books −E(R_c)·(pairs entered − left) = 0
   * at the end, and its total (K + V + broken) equals the shifted K + V (the constant between
   * them is E(R_c) × the pairs inside at the start: none) to the rounding of E(R_c)-sized sums */
  assert_true(sh.broken == 0.0);
  for (int k = 0; k < 2; k++) assert_true(fabs(sh.total[k] - pl.total[k]) <= 1e-12 * erc);
  eos_destroy(&eos);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_table),
      cmocka_unit_test(test_cohesive),
      cmocka_unit_test(test_crossing),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
