/* SPDX-License-Identifier: MIT */
/* The `grid2d` deck problem (issue 24): a deck builds the grid; a tangled mesh (skew too large),
 * an inverted mesh (x range reversed) and r < 0 in r–z are located deck errors at the mesh entry
 * (FILE:LINE:COL), reported before anything runs. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "cont2d.h"
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

static bool read_deck(const char *geo, const char *mesh, dk_errors *e) {
  char text[2048];
  snprintf(text, sizeof text, deck_fmt, geo, mesh);
  dk_errors_init(e);
  dk_doc *doc = dk_load_string(text, "deck.yaml", e);
  assert_non_null(doc);
  eos_materials *mats = eos_materials_read(doc, e);
  assert_non_null(mats);
  c2d_problem *p = c2d_problem_read(doc, dk_get(dk_root(doc), "grid2d"), mats, e);
  for (size_t i = 0; i < e->n; ++i) printf("  %s\n", e->msg[i]);
  /* the grid keeps only EOS pointers; this test frees everything at once at the end */
  if (p) {
    c2d_grid *g = c2d_problem_grid(p);
    assert_int_equal(c2d_grid_step(g, 1e-3), MS_OK);
  }
  bool built = p != NULL;
  c2d_problem_destroy(&p);
  eos_materials_destroy(&mats);
  dk_free(doc);
  return built;
}

static void test_deck_ok(void **state) {
  (void)state;
  dk_errors e;
  assert_true(read_deck("xy", "{type: rect, ni: 10, nj: 4, x: [0, 1], y: [0, 0.4]}", &e));
  assert_int_equal(e.n, 0);
  dk_errors_free(&e);
  assert_true(read_deck("rz", "{type: polar, ni: 10, nj: 8, r: [0.1, 1], theta: [0, 90]}", &e));
  assert_int_equal(e.n, 0);
  dk_errors_free(&e);
}

static void test_deck_bad_mesh(void **state) {
  (void)state;
  dk_errors e;
  /* skew 30: x moves by up to 30 zone heights, so neighbouring columns cross */
  assert_false(
      read_deck("xy", "{type: rect, ni: 10, nj: 4, x: [0, 1], y: [0, 0.4], skew: 30}", &e));
  assert_true(has_error(&e, "deck.yaml:7:9: 2D grid: zone"));
  assert_true(has_error(&e, "is tangled or inverted"));
  dk_errors_free(&e);
  assert_false(read_deck("xy", "{type: rect, ni: 10, nj: 4, x: [1, 0], y: [0, 0.4]}", &e));
  assert_true(has_error(&e, "deck.yaml:7:9: 2D grid: zone 0 (i = 0, j = 0"));
  dk_errors_free(&e);
  assert_false(read_deck("rz", "{type: rect, ni: 10, nj: 4, x: [-0.5, 1], y: [0, 0.4]}", &e));
  assert_true(has_error(&e, "deck.yaml:7:9: r–z grid: node 0 (i = 0, j = 0) has r = -0.5 < 0"));
  dk_errors_free(&e);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_deck_ok),
                                     cmocka_unit_test(test_deck_bad_mesh)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
