/* SPDX-License-Identifier: MIT */
/* Noh implosion on a polar mesh (γ = 5/3, ρ0 = 1, u0 = −r̂, p0 ≈ 0), t = 0.6 [Noh]: cylindrical
 * in x–y, post-shock density ((γ+1)/(γ−1))² = 16, spherical in r–z, 64; shock radius t/3 = 0.2
 * (issue 24). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "c2d_test.h"

static const double gam = 5.0 / 3.0, t_end = 0.6;

static void run_noh(size_t ni, size_t nj, c2d_geometry geo, double tol) {
  const double rho_ex = geo == C2D_RZ ? 64.0 : 16.0;
  eos_t *gas = eos_create_ideal_gas(gam, 1.0);
  c2d_fixture f;
  fixture_init(&f, ni, nj, gas);
  c2d_mesh_polar(ni, nj, 0.0, 1.0, 0.0, 0.5 * 3.14159265358979323846, f.x, f.y);
  for (size_t n = 0; n < (ni + 1) * (nj + 1); ++n) {
    double r = hypot(f.x[n], f.y[n]);
    if (r > 0) {
      f.u[n] = -f.x[n] / r;
      f.v[n] = -f.y[n] / r;
    }
  }
  /* e0 = 1e-9 (p0 ~ 7e-10 against the post-shock p = 16/3 · ... ≫ 1): the ideal gas needs e > 0
   * (as the 1D Noh test, tests/continuum/test_noh.c). */
  for (size_t z = 0; z < ni * nj; ++z) {
    f.rho[z] = 1.0;
    f.e[z] = 1e-9;
  }
  c2d_setup s;
  c2d_setup_defaults(&s);
  fixture_setup(&f, &s);
  s.q_gamma = gam;
  s.geometry = geo;
  s.bc[C2D_ILO].kind = C2D_BC_FIXED; /* the degenerate centre */
  s.bc[C2D_IHI].kind = C2D_BC_PISTON;
  s.bc[C2D_IHI].radial = true;
  s.bc[C2D_IHI].fn.kind = CONT_FN_CONST;
  s.bc[C2D_IHI].fn.value = -1.0; /* the inflow keeps coming at u = −r̂ */
  s.bc[C2D_JLO].kind = C2D_BC_WALL;
  s.bc[C2D_JLO].normal[1] = 1.0; /* y = 0 */
  s.bc[C2D_JHI].kind = C2D_BC_WALL;
  s.bc[C2D_JHI].normal[0] = 1.0; /* x = 0 */
  char msg[256];
  c2d_grid *g = NULL;
  c2d_grid_create(&s, &g, msg, sizeof msg);
  if (!g) printf("%s\n", msg);
  assert_non_null(g);
  double e0 = energy_total(g);
  ms_status st = c2d_grid_run_to(g, t_end);
  if (st != MS_OK) printf("%s\n", c2d_grid_error(g));
  assert_int_equal(st, MS_OK);
  c2d_view v = c2d_grid_view(g);
  /* Shock radius along each ray: the outermost zone above half of the plateau + the pre-shock
   * density just ahead ((1 + t/r)^d = 4 or 16 at r = 0.2), i.e. 10 or 40. */
  const double thr = 0.5 * (rho_ex + (geo == C2D_RZ ? 16.0 : 4.0));
  double rs_mean = 0, rs_min = INFINITY, rs_max = 0;
  for (size_t j = 0; j < nj; ++j) {
    double rs = 0;
    for (size_t i = 0; i < ni; ++i) {
      size_t z = i + ni * j, n = i + 1 + (ni + 1) * j;
      if (v.rho[z] > thr) rs = hypot(v.x[n], v.y[n]);
    }
    rs_mean += rs / (double)nj;
    rs_min = rs < rs_min ? rs : rs_min;
    rs_max = rs > rs_max ? rs : rs_max;
  }
  /* Plateau: mass / volume of the zones with centre radius in (0.5, 0.9) r_s — away from the
   * wall-heating dip at the centre and the smeared front (as the 1D test). */
  double m = 0, vol = 0;
  for (size_t z = 0; z < v.nzones; ++z) {
    size_t i = z % ni, j = z / ni, w = ni + 1, a = i + w * j;
    double xc = 0.25 * (v.x[a] + v.x[a + 1] + v.x[a + w] + v.x[a + w + 1]);
    double yc = 0.25 * (v.y[a] + v.y[a + 1] + v.y[a + w] + v.y[a + w + 1]);
    double rc = hypot(xc, yc);
    if (rc > 0.5 * rs_mean && rc < 0.9 * rs_mean) {
      m += v.mass[z];
      vol += v.vol[z];
    }
  }
  double rho_pl = m / vol, drift = energy_drift(g, e0, 0.0);
  printf("noh2d %s polar %zu x %zu: %ld steps, plateau density %.4f (exact %.0f, error %.2f %%), "
         "shock radius mean %.4f min %.4f max %.4f (exact 0.2), energy drift %.2e\n",
         geo == C2D_RZ ? "r-z (spherical)" : "x-y (cylindrical)", ni, nj, c2d_grid_steps(g), rho_pl,
         rho_ex, 100 * (rho_pl / rho_ex - 1), rs_mean, rs_min, rs_max, drift);
  /* Issue 24: plateau within 5 % (cylindrical) / 8 % (spherical): the wall-heating error
   * converges slowly (the 1D grid: 15.54 and 58.8 at 200 cells, tests/continuum/test_noh.c). */
  assert_true(fabs(rho_pl - rho_ex) < tol * rho_ex);
  /* Shock radius within 2 zones (initial zone size 1/ni) + 1 % of 0.2 on every ray. */
  assert_true(fabs(rs_min - 0.2) < 2.0 / (double)ni + 0.002);
  assert_true(fabs(rs_max - 0.2) < 2.0 / (double)ni + 0.002);
  /* Compatible discretisation: internal + kinetic − piston work constant to round-off, relative
   * to the initial kinetic energy. */
  assert_true(drift < 1e-12);
  c2d_grid_destroy(&g);
  fixture_free(&f);
  eos_destroy(&gas);
}

static void test_noh_xy(void **state) {
  (void)state;
  run_noh(100, 30, C2D_XY, 0.05);
}

/* Spherical Noh: the same polar mesh in r–z (x = r, y = z; the centre fixed, z = 0 and the axis
 * are symmetry walls). */
static void test_noh_rz(void **state) {
  (void)state;
  run_noh(100, 30, C2D_RZ, 0.08);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_noh_xy), cmocka_unit_test(test_noh_rz)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
