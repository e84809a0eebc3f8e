/* SPDX-License-Identifier: MIT */
/* Cluster dynamics behind the particle-region interface (ptl_region.h, particles/cd/cd_region.c):
 *   - the coupled problem's `particles:` section with the cluster_dynamics key names builds the
 *     same region (particles, time step, geometry) as with the old names, which are accepted as
 *     deprecated aliases with a located note; both names at once is a located error;
 *   - `surface: {type: grooves}` (old) and `{profile: sine}` (new) cut the same profile;
 *   - the region advances through the interface: a piston at constant velocity does work on it,
 *     and kinetic + potential energy grow by that work (what the coupled run's balance uses).
 * Needs no grid: the region is built between x = 0 and a given depth. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "ptl_region.h"

#define SECTION(keys)                                                                              \
  "particles:\n"                                                                                   \
  "  lattice: tri2d\n"                                                                             \
  "  width: 0.004\n"                                                                               \
  "  cutoff: 1.2\n" keys

static ptl_region_params *read(const char *text, dk_errors *e, dk_doc **doc) {
  *doc = dk_load_string(text, "region.yaml", e);
  assert_non_null(*doc);
  const ptl_region_model *m = ptl_region_model_find("cluster_dynamics");
  assert_non_null(m);
  return ptl_region_params_read(m, *doc, dk_get(dk_root(*doc), "particles"), e);
}

/* Al, the default deck's sample (docs/input-coupled.md): mg_cold 2.71, 5.35, 4, Γ0 2. */
static ptl_region *build(const ptl_region_params *pp, eos_t *eos) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ptl_region *r = NULL;
  assert_int_equal(ptl_region_create(pp, &ctx, eos, 0.0, 0.01, &r), MS_OK);
  ms_ctx_close(&ctx);
  return r;
}

static void assert_same_region(ptl_region *a, ptl_region *b) {
  ptl_region_geometry ga = ptl_region_get_geometry(a), gb = ptl_region_get_geometry(b);
  assert_true(ga.particles == gb.particles && ga.particles > 100);
  assert_true(ga.dt == gb.dt && ga.spacing == gb.spacing && ga.x_top == gb.x_top);
  assert_true(ga.area == gb.area && ga.period[1] == gb.period[1]);
  const ptl_state *sa = ptl_region_state(a), *sb = ptl_region_state(b);
  assert_int_equal(sa->n, sb->n);
  for (size_t i = 0; i < sa->n; i++) {
    assert_true(sa->x[i] == sb->x[i] && sa->y[i] == sb->y[i]);
    assert_int_equal(sa->flags[i], sb->flags[i]);
  }
}

static void test_old_names_are_aliases(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *d_new, *d_old;
  ptl_region_params *pn = read(SECTION("  r0: 2.0e-4\n  courant: 0.05\n  damping: 50\n"
                                       "  surface: {profile: sine, depth: 4.0e-4, "
                                       "wavelength: 2.0e-3}\n"),
                               &e, &d_new);
  ptl_region_params *po = read(SECTION("  spacing: 2.0e-4\n  dt_factor: 0.05\n  damping_j: 50\n"
                                       "  surface: {type: grooves, depth: 4.0e-4, "
                                       "wavelength: 2.0e-3}\n"),
                               &e, &d_old);
  if (e.n) dk_errors_print(&e, stderr);
  assert_int_equal(e.n, 0);
  assert_non_null(pn);
  assert_non_null(po);
  assert_string_equal(ptl_region_params_notes(pn), "");
  const char *notes = ptl_region_params_notes(po);
  /* one note per old name, located at its value: spacing (line 5), dt_factor (6), damping_j (7),
   * type (8) */
  assert_non_null(strstr(notes, "region.yaml:5:12: particles.spacing is the deprecated name of "
                                "particles.r0"));
  assert_non_null(strstr(notes, "region.yaml:6:14: particles.dt_factor"));
  assert_non_null(strstr(notes, "region.yaml:7:14: particles.damping_j"));
  assert_non_null(strstr(notes, "particles.surface.type is the deprecated name of"));
  eos_t *eos = eos_create_mg_cold(2.71, 5.35, 4.0, 2.0, true);
  ptl_region *rn = build(pn, eos), *ro = build(po, eos);
  assert_same_region(rn, ro);
  /* the grooves cut the lattice: fewer particles than the flat slab's */
  dk_doc *d_flat;
  ptl_region_params *pf = read(SECTION("  r0: 2.0e-4\n"), &e, &d_flat);
  ptl_region *rf = build(pf, eos);
  assert_true(ptl_region_get_geometry(rf).particles > ptl_region_get_geometry(rn).particles);
  ptl_region_destroy(&rn);
  ptl_region_destroy(&ro);
  ptl_region_destroy(&rf);
  assert_null(rn);
  ptl_region_params_destroy(&pn);
  ptl_region_params_destroy(&po);
  ptl_region_params_destroy(&pf);
  eos_destroy(&eos);
  dk_free(d_new);
  dk_free(d_old);
  dk_free(d_flat);
  dk_errors_free(&e);
}

static void test_both_names_is_an_error(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc;
  ptl_region_params *pp = read(SECTION("  r0: 2.0e-4\n  spacing: 2.0e-4\n"), &e, &doc);
  assert_null(pp);
  assert_true(e.n >= 1);
  assert_non_null(strstr(e.msg[0], "region.yaml:6:12"));
  assert_non_null(strstr(e.msg[0], "give 'r0' (its old name 'spacing' is deprecated), not both"));
  dk_free(doc);
  dk_errors_free(&e);
}

/* A piston at 0.5 km/s for 200 steps: the driven layer's force opposes the motion, and
 * kinetic + potential energy (no damping) equal the piston work to the velocity-Verlet energy
 * error, O(Δt²): 1e-3 of the work is 50x what such a run shows and far below a missing term. */
static void test_region_advances(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc;
  ptl_region_params *pp = read(SECTION("  r0: 2.0e-4\n  damping: 0\n"), &e, &doc);
  assert_non_null(pp);
  eos_t *eos = eos_create_mg_cold(2.71, 5.35, 4.0, 2.0, true);
  ptl_region *r = build(pp, eos);
  const double t[2] = {0, 1}, u[2] = {0.5, 0.5}, dir[3] = {1, 0, 0};
  ptl_region_set_piston(r, 2, t, u, dir);
  assert_int_equal(ptl_region_init(r), MS_OK);
  ptl_region_energy e0, e1;
  ptl_region_energy_get(r, &e0);
  for (int k = 0; k < 200; k++) assert_int_equal(ptl_region_step(r), MS_OK);
  ptl_region_energy_get(r, &e1);
  const double dt = ptl_region_get_geometry(r).dt;
  assert_true(fabs(ptl_region_time(r) - 200 * dt) < 1e-12 * 200 * dt);
  assert_true(ptl_region_driven_force(r) < 0); /* the compressed lattice pushes back */
  assert_true(e1.piston_work > 0);
  const double gained = (e1.kinetic + e1.potential) - (e0.kinetic + e0.potential);
  assert_true(fabs(gained - e1.piston_work) < 1e-3 * e1.piston_work);
  ptl_region_destroy(&r);
  ptl_region_params_destroy(&pp);
  eos_destroy(&eos);
  dk_free(doc);
  dk_errors_free(&e);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_old_names_are_aliases),
      cmocka_unit_test(test_both_names_is_an_error),
      cmocka_unit_test(test_region_advances),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
