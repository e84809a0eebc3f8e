/* SPDX-License-Identifier: MIT */
/* The cluster-dynamics instability guard (cd_sim_guard, docs/reliability.md section 5), one test
 * per finding it can make, each on a small fcc block: a non-finite position or velocity, a
 * particle faster than half a lattice spacing per step, a particle beyond a wall. The message
 * must name the step, the time, the particle and the quantity. (Deck-level cases with exit code
 * and snapshot: tests/reliability/unstable/.) */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "cd.h"

#define R0 5.0e-4
#define C0 5.35
enum { NCELL = 3 };

/* a resting fcc block of NCELL³ cells, walls on z, periodic on x and y, run for 10 steps */
static cd_sim *block(eos_t *eos) {
  const double a = sqrt(2.0) * R0, m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  ptl_state *p = NULL;
  ms_must(
      ptl_state_create(&(ptl_state_params){.cap = (size_t)4 * NCELL * NCELL * NCELL, .dim = 3}, &p),
      "ptl_state_create");
  double sh[3] = {0.25, 0.25, 0.25}, o[3] = {0, 0, 0};
  cd_lattice_fcc(p, NCELL, NCELL, NCELL, sh, o, R0, m, 0);
  cd_box box = {.lo = {0, 0, 0},
                .hi = {NCELL * a, NCELL * a, NCELL * a},
                .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, CD_BC_WALL}};
  cd_config cfg = {.r0 = R0,
                   .skin = 0.1 * R0,
                   .dt = 0.02 * R0 / C0,
                   .cutoff = CD_CUTOFF_BONDED,
                   .lattice = CD_LATTICE_FCC};
  cd_sim *s = NULL;
  ms_must(cd_sim_create(&(cd_sim_params){.particles = p, .box = &box, .cfg = &cfg, .nmat = 1}, &s),
          "cd_sim_create");
  cd_pair_table *t = calloc(1, sizeof *t);
  assert_int_equal(
      cd_pair_table_build(t, eos, eos, CD_LATTICE_FCC, R0, 0, 1.2 * R0, 0.5 * R0, 1.0, 0), MS_OK);
  cd_sim_set_pair(s, 0, 0, t);
  assert_int_equal(cd_sim_init(s), MS_OK);
  for (int k = 0; k < CD_GUARD_EVERY; k++) assert_int_equal(cd_sim_step(s), MS_OK);
  assert_int_equal(cd_sim_guard(s), MS_OK); /* a lattice at rest passes */
  return s;
}

static void expect_message(const cd_sim *s, const char *quantity) {
  const char *m = cd_sim_error(s);
  printf("guard: %s\n", m);
  assert_non_null(strstr(m, "unstable at step 10, t = "));
  assert_non_null(strstr(m, "particle 17 ("));
  assert_non_null(strstr(m, quantity));
}

static void test_non_finite(void **state) {
  (void)state;
  eos_t *eos = eos_create_mg_cold(2.71, C0, 4.0, 2.0, true);
  cd_sim *s = block(eos);
  cd_sim_particles(s)->vy[17] = NAN;
  assert_int_equal(cd_sim_guard(s), MS_ERR_UNSTABLE);
  expect_message(s, "non-finite vy = nan");
  cd_sim_particles(s)->vy[17] = 0.0;
  cd_sim_particles(s)->x[17] = INFINITY;
  assert_int_equal(cd_sim_guard(s), MS_ERR_UNSTABLE);
  expect_message(s, "non-finite x = inf");
  /* ... and cd_sim_step reports it at the next guard step (the NaN spreads through the forces) */
  cd_sim_particles(s)->x[17] = NAN;
  ms_status st = MS_OK;
  for (int k = 0; k < CD_GUARD_EVERY && st == MS_OK; k++) st = cd_sim_step(s);
  assert_int_equal(st, MS_ERR_UNSTABLE);
  assert_non_null(strstr(cd_sim_error(s), "unstable at step 20"));
  cd_sim_destroy(&s);
  eos_destroy(&eos);
}

static void test_too_fast(void **state) {
  (void)state;
  eos_t *eos = eos_create_mg_cold(2.71, C0, 4.0, 2.0, true);
  cd_sim *s = block(eos);
  /* 0.5 r0 per step is |v| = 0.5 r0 / dt = 25 c0: just below passes, just above does not */
  cd_sim_particles(s)->vx[17] = 0.99 * 25.0 * C0;
  assert_int_equal(cd_sim_guard(s), MS_OK);
  cd_sim_particles(s)->vx[17] = 1.01 * 25.0 * C0;
  assert_int_equal(cd_sim_guard(s), MS_ERR_UNSTABLE);
  expect_message(s, "moves it 0.505 r0 per step");
  cd_sim_destroy(&s);
  eos_destroy(&eos);
}

static void test_left_through_wall(void **state) {
  (void)state;
  eos_t *eos = eos_create_mg_cold(2.71, C0, 4.0, 2.0, true);
  cd_sim *s = block(eos);
  cd_sim_particles(s)->x[17] = -0.1 * R0; /* periodic axis: no finding */
  assert_int_equal(cd_sim_guard(s), MS_OK);
  cd_sim_particles(s)->z[17] = cd_sim_box(s)->hi[2] + 0.1 * R0;
  assert_int_equal(cd_sim_guard(s), MS_ERR_UNSTABLE);
  expect_message(s, "left the box through the wall: z = ");
  cd_sim_destroy(&s);
  eos_destroy(&eos);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_non_finite),
      cmocka_unit_test(test_too_fast),
      cmocka_unit_test(test_left_through_wall),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
