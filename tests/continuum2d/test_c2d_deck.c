/* SPDX-License-Identifier: MIT */
/* The `grid2d` deck problem (issue 24): a deck builds the grid; a tangled mesh (skew too large),
 * an inverted mesh (x range reversed) and r < 0 in r–z are located deck errors at the mesh entry
 * (FILE:LINE:COL), reported before anything runs. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "c2d_deck_test.h"
#include "test_util.h"

static const char *deck_fmt = "problem: grid2d\n"
                              "materials:\n"
                              "  - name: gas\n"
                              "    eos: {type: ideal_gas, gamma: 1.4, rho0: 1.0, p0: 1.0}\n"
                              "grid2d:\n"
                              "  geometry: %s\n"
                              "  mesh: %s\n"
                              "  material: gas\n"
                              "  density: 1.0\n"
                              "  pressure: 1.0\n"
                              "  boundaries: {ilo: {type: wall}, jlo: {type: wall}}\n"
                              "  time: {end: 0.1}\n";

/* The deck of geometry geo and mesh, read into l, steps once where it reads; true if it does. */
static bool read_deck(c2d_deck *l, const char *geo, const char *mesh) {
  char text[2048];
  snprintf(text, sizeof text, deck_fmt, geo, mesh);
  c2d_deck_load(l, text);
  if (l->p) assert_int_equal(c2d_grid_step(c2d_problem_grid(l->p), 1e-3), MS_OK);
  return l->p != NULL;
}

static void test_deck_ok(void **state) {
  (void)state;
  c2d_deck l;
  assert_true(read_deck(&l, "xy", "{type: rect, ni: 10, nj: 4, x: [0, 1], y: [0, 0.4]}"));
  assert_int_equal(l.e.n, 0);
  c2d_deck_close(&l);
  assert_true(read_deck(&l, "rz", "{type: polar, ni: 10, nj: 8, r: [0.1, 1], theta: [0, 90]}"));
  assert_int_equal(l.e.n, 0);
  c2d_deck_close(&l);
}

static void test_deck_bad_mesh(void **state) {
  (void)state;
  c2d_deck l;
  /* skew 30: x moves by up to 30 zone heights, so neighbouring columns cross */
  assert_false(
      read_deck(&l, "xy", "{type: rect, ni: 10, nj: 4, x: [0, 1], y: [0, 0.4], skew: 30}"));
  assert_true(has_error(&l.e, "deck.yaml:7:9: 2D grid: zone"));
  assert_true(has_error(&l.e, "is tangled or inverted"));
  c2d_deck_close(&l);
  assert_false(read_deck(&l, "xy", "{type: rect, ni: 10, nj: 4, x: [1, 0], y: [0, 0.4]}"));
  assert_true(has_error(&l.e, "deck.yaml:7:9: 2D grid: zone 0 (i = 0, j = 0"));
  c2d_deck_close(&l);
  assert_false(read_deck(&l, "rz", "{type: rect, ni: 10, nj: 4, x: [-0.5, 1], y: [0, 0.4]}"));
  assert_true(has_error(&l.e, "deck.yaml:7:9: r–z grid: node 0 (i = 0, j = 0) has r = -0.5 < 0"));
  c2d_deck_close(&l);
}

static const char *sedov_fmt = "problem: grid2d\n"
                               "materials:\n"
                               "  - name: gas\n"
                               "    eos: {type: ideal_gas, gamma: 1.4, rho0: 1.0, p0: 1.0e-6}\n"
                               "grid2d:\n"
                               "  geometry: %s\n"
                               "  mesh: {type: polar, ni: 20, nj: 6, r: [0, 1], theta: [0, 90]}\n"
                               "  material: gas\n"
                               "  density: 2.0\n"
                               "  energy: 1.0e-6\n"
                               "  regions:\n"
                               "    - {radius: [%g, %g], energy_total: 0.25}\n"
                               "  boundaries: {ilo: {type: fixed}}\n"
                               "  time: {end: 0.1}\n";

/* energy_total: the grid's internal energy holds the deposit E exactly (to round-off: e = E/M
 * summed back over the same masses) on top of the ambient e0 of the other zones, in x–y and r–z
 * (per radian there); a region that holds no zone centre is a located error. */
static void test_energy_total(void **state) {
  (void)state;
  for (int geo = 0; geo < 2; ++geo) {
    char text[2048];
    snprintf(text, sizeof text, sedov_fmt, geo ? "rz" : "xy", 0.0, 0.05);
    c2d_deck l;
    c2d_deck_load(&l, text);
    assert_non_null(l.p);
    c2d_view v = c2d_grid_view(c2d_problem_grid(l.p));
    double m_in = 0, m_all = 0;
    for (size_t z = 0; z < v.nzones; ++z) {
      m_all += v.mass[z];
      if (z % v.ni == 0) m_in += v.mass[z]; /* the innermost ring: centres at r = 0.025 */
    }
    const double want = 0.25 + 1e-6 * (m_all - m_in),
                 got = c2d_grid_balance(c2d_problem_grid(l.p)).internal;
    printf("energy_total (%s): internal %.15g, expected %.15g\n", geo ? "rz" : "xy", got, want);
    assert_true(fabs(got - want) < 1e-13 * want);
    c2d_deck_close(&l);
  }
  char text[2048];
  snprintf(text, sizeof text, sedov_fmt, "rz", 0.3, 0.31); /* between ring centres 0.275, 0.325 */
  c2d_deck l;
  c2d_deck_load(&l, text);
  assert_null(l.p);
  assert_true(has_error(&l.e, "deck.yaml:12:7: region 0: energy_total: no zone centre lies in it"));
  c2d_deck_close(&l);
}

static const char *piston_fmt = "problem: grid2d\n"
                                "materials:\n"
                                "  - name: gas\n"
                                "    eos: {type: ideal_gas, gamma: 1.4, rho0: 1.0, p0: 1.0}\n"
                                "grid2d:\n"
                                "  mesh: {type: rect, ni: 20, nj: 2, x: [0, 1], y: [0, 0.1]}\n"
                                "  material: gas\n"
                                "  density: 1.0\n"
                                "  pressure: 1.0\n"
                                "  boundaries:\n"
                                "    ilo: {type: piston, velocity: %s}\n"
                                "    jlo: {type: wall, normal: [0, 1]}\n"
                                "    jhi: {type: wall, normal: [0, 1]}\n"
                                "  time: {end: 0.1}\n";

/* A piston history from the deck (the 1D deck's value | table | pulse forms): after each step
 * the piston nodes move at the table's velocity at the step's end time, to round-off (measured
 * in units of one step's change of it, |du/dt| dt = 2 dt; a grid that lagged by a step would
 * show 1). Bad histories are located errors. */
static void test_piston_history(void **state) {
  (void)state;
  char text[2048];
  snprintf(text, sizeof text, piston_fmt, "{table: [[0, 0], [0.5, 1.0]]}");
  c2d_deck l;
  c2d_deck_load(&l, text);
  assert_non_null(l.p);
  c2d_grid *g = c2d_problem_grid(l.p);
  double worst = 0;
  for (int k = 0; k < 50; ++k) {
    const double t0 = c2d_grid_time(g);
    assert_int_equal(c2d_grid_step(g, 1e-3), MS_OK);
    const double t1 = c2d_grid_time(g), want = 2.0 * t1;
    c2d_view v = c2d_grid_view(g);
    const double dev = fabs(v.u[0] - want) / (2.0 * (t1 - t0));
    worst = dev > worst ? dev : worst;
  }
  printf("piston table: worst |u - u_table(t)| = %.3f of one step's change\n", worst);
  assert_true(worst < 1e-9);
  assert_true(c2d_grid_time(g) > 0.01); /* the ramp was really followed, not u = 0 */
  c2d_deck_close(&l);
  snprintf(text, sizeof text, piston_fmt, "{table: [[0, 0], [0, 1.0]]}");
  c2d_deck_load(&l, text);
  assert_null(l.p);
  assert_true(has_error(&l.e, "deck.yaml:11:52: table row 1: time 0 does not increase"));
  c2d_deck_close(&l);
  snprintf(text, sizeof text, piston_fmt, "{value: 1, pulse: {amplitude: 1, hold: 1}}");
  c2d_deck_load(&l, text);
  assert_null(l.p);
  assert_true(has_error(&l.e, "ilo.velocity: give exactly one of value, table, file, pulse"));
  c2d_deck_close(&l);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_deck_ok), cmocka_unit_test(test_deck_bad_mesh),
      cmocka_unit_test(test_energy_total), cmocka_unit_test(test_piston_history)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
