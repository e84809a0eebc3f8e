/* SPDX-License-Identifier: MIT */
/* Noh implosion (γ = 5/3, ρ0 = 1, u0 = −1, p0 = 0) in planar, cylindrical and spherical
 * geometry: post-shock density (γ+1)/(γ−1))^d = 4, 16, 64 and shock speed 1/3 (issue 3). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "cont.h"

static const double t_end = 0.6; /* shock at r = t/3 = 0.2 */

static void run_noh(cont_geometry geo, long NCELLS, double rho_exact, double rho_tol,
                    double *rho_mean, double *r_shock) {
  eos_t *gas = eos_create_ideal_gas(5.0 / 3.0, 1.0);
  assert_non_null(gas);
  cont_layer_spec layer = {.name = "gas",
                           .eos = gas,
                           .thickness = 1.0,
                           .rho = 1.0,
                           .u = -1.0,
                           .e = 1e-9,
                           .ncells = NCELLS};
  /* e0 = 1e-9 instead of 0 (p0 ~ 7e-10, negligible against the post-shock p = 4/3 or more):
   * the ideal-gas EOS is undefined for e < 0, and round-off in a perfectly cold gas could
   * produce e = −1e-40. */
  cont_setup s;
  cont_setup_defaults(&s);
  s.geometry = geo;
  s.layers = &layer;
  s.nlayers = 1;
  s.left.kind = CONT_BC_WALL;
  s.right.kind = CONT_BC_PISTON; /* the inflow keeps coming at u = −1 */
  s.right.fn.kind = CONT_FN_CONST;
  s.right.fn.value = -1.0;
  char msg[256];
  cont_grid *g = NULL;
  cont_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);
  ms_status st = cont_grid_run_to(g, t_end);
  if (st != MS_OK) printf("%s\n", cont_grid_error(g));
  assert_int_equal(st, MS_OK);
  cont_view v = cont_grid_view(g);
  /* Shock position: the outermost cell whose density exceeds half of the post-shock value
   * (pre-shock density just ahead is (1 + t/r)^d ≤ 4 for d = 2 at r = 0.2, far below half of
   * 16 or 64; for planar it is 1 < 2). */
  double rs = 0.0;
  for (size_t i = 0; i < v.ncells; ++i)
    if (v.rho[i] > 0.5 * (rho_exact + pow(1.0 + t_end / 0.2, (double)geo))) rs = v.x[i + 1];
  /* Mean density of the shocked region between 0.5 r_s and 0.9 r_s: away from the wall-heating
   * dip at the centre and from the smeared shock front. */
  double m = 0, vol = 0;
  for (size_t i = 0; i < v.ncells; ++i) {
    double xc = 0.5 * (v.x[i] + v.x[i + 1]);
    if (xc > 0.5 * rs && xc < 0.9 * rs) {
      double dv = pow(v.x[i + 1], geo + 1.0) - pow(v.x[i], geo + 1.0);
      m += v.rho[i] * dv;
      vol += dv;
    }
  }
  *rho_mean = m / vol;
  *r_shock = rs;
  printf("noh %s: %d cells, post-shock density %.4f (exact %.0f), shock radius %.4f (exact 0.2), "
         "steps %ld\n",
         geo == CONT_PLANAR        ? "planar"
         : geo == CONT_CYLINDRICAL ? "cylindrical"
                                   : "spherical",
         (int)NCELLS, *rho_mean, rho_exact, rs, cont_grid_steps(g));
  assert_true(fabs(*rho_mean - rho_exact) < rho_tol * rho_exact);
  /* Shock speed 1/3: the front is resolved to ~2 post-shock cells; the initial cell size is
   * 1/NCELLS and shocked cells are (ρ0/ρ)^(1/(d+1))-ish smaller, so 2/NCELLS is generous. */
  assert_true(fabs(rs - t_end / 3.0) < 2.0 / NCELLS + 0.01);
  cont_grid_destroy(&g);
  eos_destroy(&gas);
}

/* Tolerances on the plateau density: planar 1 % at 200 cells (the plateau is flat to 1e-4);
 * in convergent geometry the wall-heating error spreads from the centre and converges slowly
 * (spherical: 58.8, 61.2, 62.6 at 200, 400, 800 cells; cylindrical 15.54, 15.74, 15.88), so
 * cylindrical runs 400 cells with 3 % and spherical 800 cells with 4 % (docs/validation.md). */
static void test_noh_planar(void **state) {
  double rho, rs;
  run_noh(CONT_PLANAR, 200, 4.0, 0.01, &rho, &rs);
}
static void test_noh_cylindrical(void **state) {
  double rho, rs;
  run_noh(CONT_CYLINDRICAL, 400, 16.0, 0.03, &rho, &rs);
}
static void test_noh_spherical(void **state) {
  double rho, rs;
  run_noh(CONT_SPHERICAL, 800, 64.0, 0.04, &rho, &rs);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_noh_planar),
                                     cmocka_unit_test(test_noh_cylindrical),
                                     cmocka_unit_test(test_noh_spherical)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
