/* SPDX-License-Identifier: MIT */
/* Sod shock tube (ideal gas γ = 1.4) against the exact Riemann solution: L1 errors of ρ, u, p
 * at 100, 200, 400, 800 cells and the measured convergence order (issue 3). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "cont.h"
#include "riemann_exact.h"

static const double gam = 1.4, t_end = 0.2, x0 = 0.5;

/* L1 errors ∫|f − f_exact| dx of ρ, u, p over [0, 1] at t_end with n cells (n/2 per side). */
static void sod_errors(long n, const eos_t *gas, double err[3]) {
  cont_layer_spec layers[2] = {{.name = "left",
                                .eos = gas,
                                .thickness = 0.5,
                                .rho = 1.0,
                                .e_from_p = true,
                                .p = 1.0,
                                .ncells = n / 2},
                               {.name = "right",
                                .eos = gas,
                                .thickness = 0.5,
                                .rho = 0.125,
                                .e_from_p = true,
                                .p = 0.1,
                                .ncells = n / 2}};
  cont_setup s;
  cont_setup_defaults(&s);
  s.layers = layers;
  s.nlayers = 2;
  char msg[256];
  cont_grid *g = NULL;
  cont_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);
  assert_int_equal(cont_grid_run_to(g, t_end), MS_OK);
  assert_true(fabs(cont_grid_time(g) - t_end) < 1e-14);

  riemann_state L = {1.0, 0.0, 1.0}, R = {0.125, 0.0, 0.1};
  double ps, us;
  riemann_star(&L, &R, gam, &ps, &us);
  /* Toro's table 4.2: p* = 0.30313, u* = 0.92745 for Sod */
  assert_true(fabs(ps - 0.30313) < 1e-4 && fabs(us - 0.92745) < 1e-4);

  cont_view v = cont_grid_view(g);
  err[0] = err[1] = err[2] = 0.0;
  for (size_t i = 0; i < v.ncells; ++i) {
    double dx = v.x[i + 1] - v.x[i];
    /* exact solution averaged over the cell with 8-point midpoint sampling (the cell may
     * straddle a discontinuity) */
    double er = 0, eu = 0, ep = 0;
    for (int k = 0; k < 8; ++k) {
      double xs = v.x[i] + (k + 0.5) / 8.0 * dx;
      riemann_state w = riemann_sample(&L, &R, gam, ps, us, (xs - x0) / t_end);
      er += w.rho / 8.0;
      ep += w.p / 8.0;
    }
    double xc = 0.5 * (v.x[i] + v.x[i + 1]);
    riemann_state wc = riemann_sample(&L, &R, gam, ps, us, (xc - x0) / t_end);
    eu = wc.u;
    double uc = 0.5 * (v.u[i] + v.u[i + 1]);
    err[0] += fabs(v.rho[i] - er) * dx;
    err[1] += fabs(uc - eu) * dx;
    err[2] += fabs(v.p[i] - ep) * dx;
  }
  cont_grid_destroy(&g);
}

static void test_sod_convergence(void **state) {
  (void)state;
  eos_t *gas = eos_create_ideal_gas(gam, 1.0);
  assert_non_null(gas);
  const long cells[4] = {100, 200, 400, 800};
  double err[4][3];
  for (int k = 0; k < 4; ++k) {
    sod_errors(cells[k], gas, err[k]);
    printf("sod: %4ld cells  L1(rho) = %.4e  L1(u) = %.4e  L1(p) = %.4e\n", cells[k], err[k][0],
           err[k][1], err[k][2]);
  }
  /* Order from a least-squares fit of log E against log N over the four resolutions. */
  const char *names[3] = {"rho", "u", "p"};
  for (int q = 0; q < 3; ++q) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int k = 0; k < 4; ++k) {
      double lx = log((double)cells[k]), ly = log(err[k][q]);
      sx += lx;
      sy += ly;
      sxx += lx * lx;
      sxy += lx * ly;
    }
    double order = -(4 * sxy - sx * sy) / (4 * sxx - sx * sx);
    printf("sod: measured L1 order of %s = %.3f\n", names[q], order);
    /* First-order for a flow with discontinuities (issue 3: assert >= 0.8). */
    assert_true(order >= 0.8);
  }
  /* Absolute accuracy guard: at 800 cells a working scheme is well below 1 % of the jump
   * (ρ jump 0.875, u* 0.93, p jump 0.9) in L1 over the unit tube. */
  assert_true(err[3][0] < 5e-3 && err[3][1] < 5e-3 && err[3][2] < 5e-3);
  eos_destroy(&gas);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_sod_convergence)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
