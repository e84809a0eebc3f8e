/* SPDX-License-Identifier: MIT */
/* Sod shock tube along x on a 2D x–y mesh (γ = 1.4, t = 0.2): every row of zones stays equal to
 * the first (the flow is 1D), the L1 errors against the exact Riemann solution are of the size of
 * the 1D grid's at the same resolution, and total energy is conserved to 1e-12 (issue 24). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "c2d_test.h"
#include "riemann_exact.h"

static const double gam = 1.4, t_end = 0.2, x0 = 0.5;

/* L1 errors of ρ, u, p from zone row 0 of the 2D grid (or the 1D grid's cells). */
static void l1_errors(size_t n, const double *xn, const double *un, const double *rho,
                      const double *p, double err[3]) {
  riemann_state L = {1.0, 0.0, 1.0}, R = {0.125, 0.0, 0.1};
  double ps, us;
  riemann_star(&L, &R, gam, &ps, &us);
  err[0] = err[1] = err[2] = 0.0;
  for (size_t i = 0; i < n; ++i) {
    double dx = xn[i + 1] - xn[i], er = 0, ep = 0;
    for (int k = 0; k < 8; ++k) {
      double xs = xn[i] + (k + 0.5) / 8.0 * dx;
      riemann_state w = riemann_sample(&L, &R, gam, ps, us, (xs - x0) / t_end);
      er += w.rho / 8.0;
      ep += w.p / 8.0;
    }
    double xc = 0.5 * (xn[i] + xn[i + 1]);
    riemann_state wc = riemann_sample(&L, &R, gam, ps, us, (xc - x0) / t_end);
    err[0] += fabs(rho[i] - er) * dx;
    err[1] += fabs(0.5 * (un[i] + un[i + 1]) - wc.u) * dx;
    err[2] += fabs(p[i] - ep) * dx;
  }
}

static void run_1d(size_t n, const eos_t *gas, double err[3]) {
  cont_layer_spec layers[2] = {{.name = "l",
                                .eos = gas,
                                .thickness = 0.5,
                                .rho = 1.0,
                                .e_from_p = true,
                                .p = 1.0,
                                .ncells = (long)n / 2},
                               {.name = "r",
                                .eos = gas,
                                .thickness = 0.5,
                                .rho = 0.125,
                                .e_from_p = true,
                                .p = 0.1,
                                .ncells = (long)n / 2}};
  cont_setup s;
  cont_setup_defaults(&s);
  s.layers = layers;
  s.nlayers = 2;
  char msg[256];
  cont_grid *g = NULL;
  cont_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);
  assert_int_equal(cont_grid_run_to(g, t_end), MS_OK);
  cont_view v = cont_grid_view(g);
  l1_errors(v.ncells, v.x, v.u, v.rho, v.p, err);
  cont_grid_destroy(&g);
}

static void run_2d(size_t ni, size_t nj, const eos_t *gas, double err[3], double *row_diff,
                   double *drift) {
  c2d_fixture f;
  fixture_init(&f, ni, nj, gas);
  c2d_mesh_rect(ni, nj, 0.0, 1.0, 0.0, 0.1, f.x, f.y);
  for (size_t z = 0; z < ni * nj; ++z) {
    bool left = (z % ni) < ni / 2;
    f.rho[z] = left ? 1.0 : 0.125;
    f.e[z] = (left ? 1.0 : 0.1) / ((gam - 1.0) * f.rho[z]);
  }
  c2d_setup s;
  c2d_setup_defaults(&s);
  fixture_setup(&f, &s);
  s.q_gamma = gam;
  for (int k = 0; k < 4; ++k) s.bc[k].kind = C2D_BC_WALL; /* closed tube, as the 1D default */
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
  double *xr = malloc((ni + 1) * sizeof(double)), *ur = malloc((ni + 1) * sizeof(double));
  for (size_t i = 0; i <= ni; ++i) {
    xr[i] = v.x[i];
    ur[i] = v.u[i];
  }
  l1_errors(ni, xr, ur, v.rho, v.p, err);
  double d = 0.0;
  for (size_t j = 1; j < nj; ++j)
    for (size_t i = 0; i < ni; ++i) {
      double r = fabs(v.rho[i + ni * j] - v.rho[i]) / v.rho[i];
      d = r > d ? r : d;
    }
  for (size_t n = 0; n < v.nnodes; ++n) d = fabs(v.v[n]) > d ? fabs(v.v[n]) : d;
  *row_diff = d;
  *drift = energy_drift(g, e0, 0.0);
  printf("sod2d: %zu x %zu zones, %ld steps: L1(rho) %.4e L1(u) %.4e L1(p) %.4e, max row "
         "difference %.2e, energy drift %.2e\n",
         ni, nj, c2d_grid_steps(g), err[0], err[1], err[2], d, *drift);
  free(xr);
  free(ur);
  c2d_grid_destroy(&g);
  fixture_free(&f);
}

static void test_sod2d(void **state) {
  (void)state;
  eos_t *gas = eos_create_ideal_gas(gam, 1.0);
  const size_t ns[2] = {100, 200};
  for (int k = 0; k < 2; ++k) {
    double e2[3], e1[3], rd, drift;
    run_2d(ns[k], 4, gas, e2, &rd, &drift);
    run_1d(ns[k], gas, e1);
    printf("sod1d: %zu cells: L1(rho) %.4e L1(u) %.4e L1(p) %.4e\n", ns[k], e1[0], e1[1], e1[2]);
    /* Rows: the mesh, the data and the walls are symmetric in y, so the rows can differ only by
     * round-off (the y-velocity is exactly 0 at walls and ±round-off inside). */
    assert_true(rd < 1e-12);
    /* Compatible discretisation: internal + kinetic is constant to round-off (closed tube). */
    assert_true(drift < 1e-12);
    /* Accuracy: the 2D grid has a different (edge, limited) viscosity from the 1D grid's
     * linear + quadratic one, so its errors are not equal; both are first-order schemes at
     * discontinuities, and we require the 2D L1 errors to be within 10 % of the 1D grid's at the
     * same zone size (measured: within 2 %). */
    for (int q = 0; q < 3; ++q) assert_true(e2[q] < 1.1 * e1[q]);
  }
  eos_destroy(&gas);
}

/* r–z, flow along z on a mesh that touches the axis (4 × 200 zones, r ≤ 0.1): the columns stay
 * equal (the lumped-mass / control-volume pairing, docs/continuum2d.md §2) and the L1 errors
 * are those of the planar run. */
static void test_sod_rz_along_z(void **state) {
  (void)state;
  eos_t *gas = eos_create_ideal_gas(gam, 1.0);
  const size_t ni = 4, nj = 200;
  c2d_fixture f;
  fixture_init(&f, ni, nj, gas);
  c2d_mesh_rect(ni, nj, 0.0, 0.1, 0.0, 1.0, f.x, f.y);
  for (size_t z = 0; z < ni * nj; ++z) {
    bool lo = z / ni < nj / 2;
    f.rho[z] = lo ? 1.0 : 0.125;
    f.e[z] = (lo ? 1.0 : 0.1) / ((gam - 1.0) * f.rho[z]);
  }
  c2d_setup s;
  c2d_setup_defaults(&s);
  fixture_setup(&f, &s);
  s.geometry = C2D_RZ;
  s.q_gamma = gam;
  for (int k = 0; k < 4; ++k) s.bc[k].kind = C2D_BC_WALL;
  s.bc[C2D_ILO].normal[0] = 1.0; /* the axis */
  s.bc[C2D_IHI].normal[0] = 1.0;
  char msg[256];
  c2d_grid *g = NULL;
  c2d_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);
  double e0 = energy_total(g);
  assert_int_equal(c2d_grid_run_to(g, t_end), MS_OK);
  c2d_view v = c2d_grid_view(g);
  double d = 0, ur = 0;
  for (size_t j = 0; j < nj; ++j)
    for (size_t i = 1; i < ni; ++i)
      d = fmax(d, fabs(v.rho[i + ni * j] - v.rho[ni * j]) / v.rho[ni * j]);
  for (size_t n = 0; n < v.nnodes; ++n) ur = fmax(ur, fabs(v.u[n]));
  /* column 0 as a 1D profile along z */
  double *zn = malloc((nj + 1) * sizeof(double)), *wn = malloc((nj + 1) * sizeof(double)),
         *rc = malloc(nj * sizeof(double)), *pc = malloc(nj * sizeof(double)), err[3], e1[3];
  for (size_t j = 0; j <= nj; ++j) {
    zn[j] = v.y[(ni + 1) * j];
    wn[j] = v.v[(ni + 1) * j];
  }
  for (size_t j = 0; j < nj; ++j) {
    rc[j] = v.rho[ni * j];
    pc[j] = v.p[ni * j];
  }
  l1_errors(nj, zn, wn, rc, pc, err);
  run_1d(nj, gas, e1);
  double drift = energy_drift(g, e0, 0.0);
  printf("sod r-z along z: %zu x %zu zones: L1(rho) %.4e L1(u) %.4e L1(p) %.4e (1D planar %.4e "
         "%.4e %.4e), max column difference %.2e, max |u_r| %.2e, energy drift %.2e\n",
         ni, nj, err[0], err[1], err[2], e1[0], e1[1], e1[2], d, ur, drift);
  /* Round-off only: the r–z forces and the lumped masses give every node of a row the same
   * acceleration for a flow along z. */
  assert_true(d < 1e-12 && ur < 1e-12);
  for (int q = 0; q < 3; ++q) assert_true(err[q] < 1.1 * e1[q]); /* as the x–y case */
  assert_true(drift < 1e-12);
  free(zn);
  free(wn);
  free(rc);
  free(pc);
  c2d_grid_destroy(&g);
  fixture_free(&f);
  eos_destroy(&gas);
}

/* r–z, radial Sod (diaphragm at r = 0.5, 200 × 2 zones, walls at r = 1 and top/bottom) against
 * the 1D cylindrical grid at the same 200 cells. */
static void test_sod_rz_radial(void **state) {
  (void)state;
  eos_t *gas = eos_create_ideal_gas(gam, 1.0);
  const size_t ni = 200, nj = 2;
  c2d_fixture f;
  fixture_init(&f, ni, nj, gas);
  c2d_mesh_rect(ni, nj, 0.0, 1.0, 0.0, 0.01, f.x, f.y);
  for (size_t z = 0; z < ni * nj; ++z) {
    bool in = z % ni < ni / 2;
    f.rho[z] = in ? 1.0 : 0.125;
    f.e[z] = (in ? 1.0 : 0.1) / ((gam - 1.0) * f.rho[z]);
  }
  c2d_setup s;
  c2d_setup_defaults(&s);
  fixture_setup(&f, &s);
  s.geometry = C2D_RZ;
  s.q_gamma = gam;
  for (int k = 0; k < 4; ++k) s.bc[k].kind = C2D_BC_WALL;
  char msg[256];
  c2d_grid *g = NULL;
  c2d_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);
  double e0 = energy_total(g);
  assert_int_equal(c2d_grid_run_to(g, t_end), MS_OK);
  c2d_view v = c2d_grid_view(g);
  cont_layer_spec layers[2] = {{.name = "in",
                                .eos = gas,
                                .thickness = 0.5,
                                .rho = 1.0,
                                .e_from_p = true,
                                .p = 1.0,
                                .ncells = (long)ni / 2},
                               {.name = "out",
                                .eos = gas,
                                .thickness = 0.5,
                                .rho = 0.125,
                                .e_from_p = true,
                                .p = 0.1,
                                .ncells = (long)ni / 2}};
  cont_setup s1;
  cont_setup_defaults(&s1);
  s1.geometry = CONT_CYLINDRICAL;
  s1.layers = layers;
  s1.nlayers = 2;
  cont_grid *g1 = NULL;
  cont_grid_create(&s1, &g1, msg, sizeof msg);
  assert_non_null(g1);
  assert_int_equal(cont_grid_run_to(g1, t_end), MS_OK);
  /* L1 difference of the density profiles over r ∈ [0, 1], the 1D solution sampled at the 2D
   * zone centres (linear between its cell centres). */
  double diff = 0;
  for (size_t i = 0; i < ni; ++i) {
    double rc = 0.5 * (v.x[i] + v.x[i + 1]), dr = v.x[i + 1] - v.x[i];
    cont_sample smp;
    assert_true(cont_grid_sample(g1, rc, &smp));
    diff += fabs(v.rho[i] - smp.rho) * dr;
  }
  double drift = energy_drift(g, e0, 0.0);
  printf("sod r-z radial: %zu x %zu zones vs the 1D cylindrical grid (200 cells): L1(rho "
         "difference) %.4e, energy drift %.2e\n",
         ni, nj, diff, drift);
  /* Both are first-order at the discontinuities with planar L1 errors ≈ 2.6e-3 against the
   * exact solution at this resolution (test_sod2d); their viscosities differ, so their difference
   * is of that size: we require less than twice it. */
  assert_true(diff < 5e-3);
  assert_true(drift < 1e-12);
  cont_grid_destroy(&g1);
  c2d_grid_destroy(&g);
  fixture_free(&f);
  eos_destroy(&gas);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_sod2d),
                                     cmocka_unit_test(test_sod_rz_along_z),
                                     cmocka_unit_test(test_sod_rz_radial)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
