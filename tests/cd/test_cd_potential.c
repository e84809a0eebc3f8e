/* SPDX-License-Identifier: MIT */
/* Cluster-dynamics pair potentials (docs/design.md §5.1, [Davydov] eqs. 1–2, Table 1):
 * tabulated force vs the analytic formula, force = −dE/dr of the tabulated energy, Table 1's
 * E and f columns from its ε_x and P_x columns, the 2D potential, the mixing rule. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "cd.h"

#define R0 5.0e-4

/* the benchmark's aluminium cold curve (cd_lammps.md): rho0 2.71, c0 5.35, n 4 */
static eos_t *al_mg(void) { return eos_create_mg_cold(2.71, 5.35, 4.0, 2.0, true); }

/* max relative error of table vs exact force on [0.7 r0, rc), relative to max(|f|, 1e-3 max|f|)
 * (at r0 the force vanishes, so a pure relative error is meaningless there) */
static double force_error(const cd_pair_table *t, const eos_t *eos, cd_lattice lat, double h,
                          double rlo, double *e_err) {
  const int n = 20001;
  double fscale = 0.0, escale = 0.0;
  for (int k = 0; k < n; k++) {
    double r = rlo + (t->rc - rlo) * k / n;
    fscale = fmax(fscale, fabs(cd_pair_force_exact(eos, lat, R0, h, r)));
    escale = fmax(escale, fabs(cd_pair_energy_exact(eos, lat, R0, h, r)));
  }
  double worst = 0.0, eworst = 0.0;
  for (int k = 0; k < n; k++) {
    double r = rlo + (t->rc - rlo) * k / n;
    double fe = cd_pair_force_exact(eos, lat, R0, h, r), ft = cd_pair_table_force(t, r);
    double ee = cd_pair_energy_exact(eos, lat, R0, h, r), et = cd_pair_table_energy(t, r);
    double rel = fabs(ft - fe) / fmax(fabs(fe), 1e-3 * fscale);
    double erel = fabs(et - ee) / fmax(fabs(ee), 1e-3 * escale);
    if (rel > worst) worst = rel;
    if (erel > eworst) eworst = erel;
  }
  *e_err = eworst;
  return worst;
}

static void test_table_vs_formula_fcc(void **state) {
  (void)state;
  eos_t *eos = al_mg();
  cd_pair_table t;
  assert_int_equal(
      cd_pair_table_build(&t, eos, eos, CD_LATTICE_FCC, R0, 0.0, 1.2 * R0, 0.5 * R0, 1.0, 0),
      MS_OK);
  double eerr, ferr = force_error(&t, eos, CD_LATTICE_FCC, 0.0, 0.6 * R0, &eerr);
  printf("fcc: max force error %.3g, energy error %.3g (relative, floor 1e-3 max)\n", ferr, eerr);
  /* the benchmark requires 1e-6 relative agreement with the formulas */
  assert_true(ferr < 1e-6);
  assert_true(eerr < 1e-6);
  /* the cutoff: nothing beyond rc, E(rc) recorded for the broken-pair balance */
  assert_true(cd_pair_table_force(&t, 1.2000001 * R0) == 0.0);
  assert_true(fabs(t.e_rc - cd_pair_energy_exact(eos, CD_LATTICE_FCC, R0, 0, 1.2 * R0)) <
              1e-9 * fabs(t.e_rc));
  /* at rest: E = f = 0 exactly (r0² is a node) */
  assert_true(cd_pair_table_force(&t, R0) == 0.0);
  assert_true(cd_pair_table_energy(&t, R0) == 0.0);
  cd_pair_table_free(&t);
  eos_destroy(&eos);
}

/* The fast path's fit of F/r (cd_potential.c): within 1e-12 of max|F/r| of the formula on its
 * range (set-up criterion; measured 4e-13 at degree 9) and reaching down to R_c/2 (16 segments
 * of 1/8 octave); within the table's own accuracy of the table (set-up criterion: 1e-9 of
 * max|F/r| over the table, i.e. at 0.5 r0; measured 9e-10 of the max over the fit range, 1e-10
 * of the table's, the table's own error). A coarse table (64 intervals, errors ~1e-5) fails the comparison: no fit. */
static void test_fit(void **state) {
  (void)state;
  eos_t *eos = al_mg();
  cd_pair_table t;
  assert_int_equal(
      cd_pair_table_build(&t, eos, eos, CD_LATTICE_FCC, R0, 0.0, 1.2 * R0, 0.5 * R0, 1.0, 0),
      MS_OK);
  assert_true(t.fit_ok);
  assert_true(t.fit_deg <= CD_FIT_MAXDEG);
  assert_true(t.fit_slo <= 0.6 * 0.6 * 1.2 * 1.2 * R0 * R0); /* (R_c/2)² up to a segment */
  double frmax = 0.0, err = 0.0, err_tab = 0.0;
  const int n = 200001;
  for (int k = 0; k < n; k++) {
    const double s = t.fit_slo + (t.rc2 - t.fit_slo) * k / n, r = sqrt(s);
    const double ex = cd_pair_force_exact(eos, CD_LATTICE_FCC, R0, 0, r) / r;
    frmax = fmax(frmax, fabs(ex));
    const double fit = cd_pair_fit_eval(&t, s);
    err = fmax(err, fabs(fit - ex));
    if (r * r < t.rc2) err_tab = fmax(err_tab, fabs(fit - cd_pair_table_force(&t, r) / r));
  }
  printf("fit: degree %d from r = %.3f r0, error %.3g (formula), %.3g (table) of max|F/r|\n",
         t.fit_deg, sqrt(t.fit_slo) / R0, err / frmax, err_tab / frmax);
  /* the formula evaluated here (cd_pair_force_exact / r) rounds differently from the one fitted
   * (−2 dE/ds): a few ulp of |F/r|, far below 1e-12 of its maximum */
  assert_true(err < 1e-12 * frmax);
  /* set-up criterion: 1e-9 of max|F/r| over the table, which is at its inner end s_lo */
  const double rlo = sqrt(t.s_lo), ftab = fabs(cd_pair_table_force(&t, rlo) / rlo);
  assert_true(err_tab < 1e-9 * ftab);
  cd_pair_table_free(&t);
  assert_int_equal(
      cd_pair_table_build(&t, eos, eos, CD_LATTICE_FCC, R0, 0.0, 1.2 * R0, 0.5 * R0, 1.0, 64),
      MS_OK);
  assert_false(t.fit_ok);
  cd_pair_table_free(&t);
  eos_destroy(&eos);
}

/* f = −dE/dr of the tabulated energy (central differences, step 1e-6 r0: truncation error of
 * the cubic ~1e-12 relative, round-off ~1e-10 relative to max|f|) */
static void test_force_is_energy_derivative(void **state) {
  (void)state;
  eos_t *eos = al_mg();
  cd_pair_table t;
  assert_int_equal(
      cd_pair_table_build(&t, eos, eos, CD_LATTICE_FCC, R0, 0.0, 1.2 * R0, 0.5 * R0, 1.0, 256),
      MS_OK);
  double fscale = fabs(cd_pair_table_force(&t, 0.7 * R0)), worst = 0.0;
  for (int k = 0; k < 4999; k++) {
    double r = (0.55 + 0.64 * (k + 0.5) / 5000.0) * R0, h = 1e-6 * R0;
    double fd = -(cd_pair_table_energy(&t, r + h) - cd_pair_table_energy(&t, r - h)) / (2 * h);
    double rel = fabs(fd - cd_pair_table_force(&t, r)) / fscale;
    if (rel > worst) worst = rel;
  }
  printf("f vs -dE/dr (256 intervals): %.3g of max|f|\n", worst);
  assert_true(worst < 1e-7);
  cd_pair_table_free(&t);
  eos_destroy(&eos);
}

/* Table 1 of [Davydov]: E(r) [J] and f(r) [N] columns follow from eps_x and P_x by eqs. 1–2.
 * Internal units: energy g·(km/s)² = 1e3 J, force g·cm/(10 µs)² = 1e5 N. The printed columns
 * have 4 significant digits: tolerance 0.3 %. */
static void test_paper_table1(void **state) {
  (void)state;
  const char *src = getenv("MSCALE_SOURCE_DIR");
  char path[4096];
  snprintf(path, sizeof path, "%s/eos/data/al_osa_cold.txt", src ? src : "../..");
  dk_errors e;
  dk_errors_init(&e);
  eos_t *eos = eos_create_table_cold(path, 2.0, true, &e);
  dk_errors_print(&e, stderr);
  assert_non_null(eos);
  static const double row[][3] = {
      /* r/r0, E [J], f [N] */
      {0.75, 8.304e-07, 1.936e+00},  {0.8, 4.332e-07, 1.253e+00},   {0.85, 1.969e-07, 6.796e-01},
      {0.9, 7.249e-08, 3.437e-01},   {0.95, 1.513e-08, 1.317e-01},  {1.05, 1.053e-08, -7.678e-02},
      {1.1, 3.583e-08, -1.222e-01},  {1.15, 7.042e-08, -1.529e-01}, {1.2, 1.117e-07, -1.766e-01},
      {1.25, 1.585e-07, -1.971e-01}, {1.3, 2.102e-07, -2.163e-01}};
  for (size_t k = 0; k < sizeof row / sizeof *row; k++) {
    double r = row[k][0] * R0;
    /* the table rows list delta with 3 decimals; evaluate at the printed delta's r */
    double E = cd_pair_energy_exact(eos, CD_LATTICE_FCC, R0, 0, r) * 1e3;
    double f = cd_pair_force_exact(eos, CD_LATTICE_FCC, R0, 0, r) * 1e5;
    printf("r/r0 %.2f: E %.4e J (paper %.4e), f %.4e N (paper %.4e)\n", row[k][0], E, row[k][1], f,
           row[k][2]);
    assert_true(fabs(E - row[k][1]) < 3e-3 * fabs(row[k][1]));
    assert_true(fabs(f - row[k][2]) < 3e-3 * fabs(row[k][2]));
  }
  /* and the table built from it reproduces the formula inside the cold curve's range */
  cd_pair_table t;
  assert_int_equal(
      cd_pair_table_build(&t, eos, eos, CD_LATTICE_FCC, R0, 0, 1.2 * R0, 0.5 * R0, 1.0, 0), MS_OK);
  assert_true(t.s_lo >= pow(0.75 * R0, 2) * (1 - 1e-9)); /* clamped to the table's delta range */
  double eerr, ferr = force_error(&t, eos, CD_LATTICE_FCC, 0.0, 0.76 * R0, &eerr);
  printf("Table-1 EOS: max force error %.3g, energy %.3g\n", ferr, eerr);
  /* The tabulated cold curve is a piecewise cubic in delta whose P_x' jumps at its 12 nodes;
   * a smooth interpolant in s = r² resolves a kink only to O(h): 6.7e-6 with 4096 intervals.
   * (Analytic cold curves reach ~1e-9, test above.) */
  assert_true(ferr < 1e-5);
  cd_pair_table_free(&t);
  eos_destroy(&eos);
  dk_errors_free(&e);
}

/* 2D triangular lattice: f = r h P_x((r0/r)²)/√3 must be −dE/dr of E = (m/3) ε_x((r0/r)²) */
static void test_2d_potential(void **state) {
  (void)state;
  eos_t *eos = al_mg();
  const double h = R0;
  for (int k = 1; k < 100; k++) {
    double r = (0.7 + 0.6 * k / 100.0) * R0, dr = 1e-6 * R0;
    double fd = -(cd_pair_energy_exact(eos, CD_LATTICE_TRI2D, R0, h, r + dr) -
                  cd_pair_energy_exact(eos, CD_LATTICE_TRI2D, R0, h, r - dr)) /
                (2 * dr);
    double f = cd_pair_force_exact(eos, CD_LATTICE_TRI2D, R0, h, r);
    double scale = fabs(cd_pair_force_exact(eos, CD_LATTICE_TRI2D, R0, h, 0.7 * R0));
    assert_true(fabs(fd - f) < 1e-7 * scale);
  }
  cd_pair_table t;
  assert_int_equal(
      cd_pair_table_build(&t, eos, eos, CD_LATTICE_TRI2D, R0, h, 1.35 * R0, 0.5 * R0, 1.0, 0),
      MS_OK);
  double eerr, ferr = force_error(&t, eos, CD_LATTICE_TRI2D, h, 0.6 * R0, &eerr);
  printf("2D: max force error %.3g, energy %.3g\n", ferr, eerr);
  assert_true(ferr < 1e-6);
  cd_pair_table_free(&t);
  eos_destroy(&eos);
}

/* mixing rule: E_ab = ½(E_a + E_b) in compression, scaled by `attraction` beyond r0 */
static void test_mixing_rule(void **state) {
  (void)state;
  eos_t *a = eos_create_mg_cold(2.51, 9.06, 3.13, 1.0, true);  /* B4C */
  eos_t *b = eos_create_mg_cold(2.29, 3.19, 10.41, 1.0, true); /* h-BN */
  cd_pair_table t;
  assert_int_equal(cd_pair_table_build(&t, a, b, CD_LATTICE_FCC, R0, 0, 1.2 * R0, 0.5 * R0, 0.5, 0),
                   MS_OK);
  for (int k = 0; k < 10; k++) {
    double r = (0.8 + 0.04 * k) * R0;
    double ea = cd_pair_energy_exact(a, CD_LATTICE_FCC, R0, 0, r),
           eb = cd_pair_energy_exact(b, CD_LATTICE_FCC, R0, 0, r);
    double want = 0.5 * (ea + eb) * (r > R0 ? 0.5 : 1.0);
    assert_true(fabs(cd_pair_table_energy(&t, r) - want) < 1e-7 * fabs(want) + 1e-20);
  }
  cd_pair_table_free(&t);
  eos_destroy(&a);
  eos_destroy(&b);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_table_vs_formula_fcc),
                                     cmocka_unit_test(test_force_is_energy_derivative),
                                     cmocka_unit_test(test_paper_table1),
                                     cmocka_unit_test(test_2d_potential),
                                     cmocka_unit_test(test_mixing_rule),
                                     cmocka_unit_test(test_fit)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
