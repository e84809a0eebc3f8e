/* SPDX-License-Identifier: MIT */
/* The jet-tip measures of bench/dm_jets/jets_tip.c on a hand-made particle set whose answers are
 * known exactly (docs/validation.md "Microjets", the [20] paragraph): a column of particles of
 * unit mass along the valley's axis (spacing h, x = 0 … 19 h, vx = x/h km/s), one particle
 * flung 5 h ahead of it, and particles of the peak half (not part of the jet) further ahead.
 *   - the jet: the valley half ahead of x_fs; the debris particle is its own cluster, the
 *     column the jet cluster (links ≤ 1.5 h), so 2 clusters and 1 particle ahead of the jet's
 *     front, and the foremost particle's cluster holds 1;
 *   - the leading-mass fronts: with ρ0 h0 λ = 20 particle masses the leading 0.1 (2 masses) ends
 *     at the column's first particle, the leading 0.5 (10) at its 9th, and their mean
 *     velocities are those particles' mean vx;
 *   - the peak half's particles ahead of everything count for nothing. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "jets_tip.h"

static void test_fronts_and_clusters(void **state) {
  (void)state;
  const double h = 1e-4, lambda = 64 * h;
  ptl_state *ps = NULL;
  assert_int_equal(ptl_state_create(&(ptl_state_params){.cap = 64, .dim = 2}, &ps), MS_OK);
  for (int k = 0; k < 20; k++) { /* the column, x = 0 … 19 h on the valley's axis y = λ/2 */
    const size_t i = ptl_state_add(ps, k * h, 0.5 * lambda, 0, 1.0, 0);
    ps->vx[i] = k;
  }
  const size_t debris = ptl_state_add(ps, 24 * h, 0.5 * lambda + 0.3 * h, 0, 1.0, 0);
  ps->vx[debris] = 40;
  for (int k = 0; k < 3; k++) /* the peak half (y near 0): not the jet */
    ps->vx[ptl_state_add(ps, (30 + k) * h, 0.1 * h, 0, 1.0, 0)] = 99;
  uint8_t role[64] = {0};
  for (size_t i = 0; i < ps->n; i++) role[i] = fabs(ps->y[i] - 0.5 * lambda) < 0.25 * lambda;
  /* the surface at x_fs = 0.5 h: the column's particles from x = h on are the jet */
  jets_tip *t = jets_tip_create(ps, role, 20.0, h);
  assert_non_null(t);
  jets_tip_sample s;
  jets_tip_measure(t, ps, role, 0.5 * h, lambda, &s);
  printf("jet %ld particles (%.3f rho0 h0 lambda), %ld clusters, %ld ahead, tip cluster %ld; "
         "fronts %g %g %g h, v %g %g %g; jet front %g h\n",
         s.n_jet, s.m_jet, s.n_clusters, s.n_ahead, s.tip_cluster, s.x_m[0] / h, s.x_m[1] / h,
         s.x_m[2] / h, s.v_m[0], s.v_m[1], s.v_m[2], s.x_main / h);
  assert_int_equal(s.n_jet, 20); /* 19 of the column + the debris */
  assert_float_equal(s.m_jet, 1.0, 1e-12);
  assert_int_equal(s.n_clusters, 2);
  assert_int_equal(s.n_ahead, 1);
  assert_int_equal(s.tip_cluster, 1);
  assert_float_equal(s.x_main, 19 * h, 1e-15);
  assert_float_equal(s.v_main, 19, 1e-12);
  /* 0.01 × 20 = 0.2 masses: the debris alone; 0.1 × 20 = 2: debris + x = 19 h; 0.5 × 20 = 10:
   * debris + x = 19 … 11 h */
  assert_float_equal(s.x_m[0], 24 * h, 1e-15);
  assert_float_equal(s.v_m[0], 40, 1e-12);
  assert_float_equal(s.x_m[1], 19 * h, 1e-15);
  assert_float_equal(s.v_m[1], (40 + 19) / 2.0, 1e-12);
  assert_float_equal(s.x_m[2], 11 * h, 1e-15);
  assert_float_equal(s.v_m[2], (40 + 19 + 18 + 17 + 16 + 15 + 14 + 13 + 12 + 11) / 10.0, 1e-12);
  /* the debris joins the jet when it comes within the link (1.5 h) of the column's front */
  ps->x[debris] = 20.2 * h;
  jets_tip_measure(t, ps, role, 0.5 * h, lambda, &s);
  assert_int_equal(s.n_clusters, 1);
  assert_int_equal(s.n_ahead, 0);
  assert_int_equal(s.tip_cluster, 20);
  jets_tip_destroy(&t);
  ptl_state_destroy(&ps);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_fronts_and_clusters)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
