/* SPDX-License-Identifier: MIT */
/* 2D grid unit tests (issue 24): a uniform state at rest stays at rest to round-off in x–y and
 * r–z (corner forces of a uniform pressure cancel at every interior node); a random-velocity
 * state conserves internal + kinetic energy to 1e-12 (closed box); bad meshes are refused with
 * the zone named (tangled/inverted, r < 0 in r–z). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "c2d_test.h"

static void make_box(c2d_fixture *f, c2d_setup *s, size_t n, c2d_geometry geo, const eos_t *gas) {
  fixture_init(f, n, n, gas);
  c2d_mesh_rect(n, n, 0.0, 1.0, 0.0, 1.0, f->x, f->y);
  for (size_t z = 0; z < n * n; ++z) {
    f->rho[z] = 1.0;
    f->e[z] = 2.5;
  }
  c2d_setup_defaults(s);
  fixture_setup(f, s);
  s->geometry = geo;
  for (int k = 0; k < 4; ++k) s->bc[k].kind = C2D_BC_WALL;
}

static void test_uniform_rest(void **state) {
  (void)state;
  eos_t *gas = eos_create_ideal_gas(1.4, 1.0);
  for (int geo = 0; geo < 2; ++geo) {
    c2d_fixture f;
    c2d_setup s;
    make_box(&f, &s, 8, (c2d_geometry)geo, gas);
    /* skew the interior nodes: equilibrium must not depend on a regular mesh */
    for (size_t j = 1; j < 8; ++j)
      for (size_t i = 1; i < 8; ++i) f.x[i + 9 * j] += 0.02 * sin(1.0 * (double)(i * j));
    char msg[256];
    c2d_grid *g = NULL;
    c2d_grid_create(&s, &g, msg, sizeof msg);
    assert_non_null(g);
    assert_int_equal(c2d_grid_run_to(g, 1.0), MS_OK);
    c2d_view v = c2d_grid_view(g);
    double umax = 0;
    for (size_t n = 0; n < v.nnodes; ++n) umax = fmax(umax, hypot(v.u[n], v.v[n]));
    printf("uniform %s: %ld steps, max |u| = %.2e\n", geo ? "r-z" : "x-y", c2d_grid_steps(g), umax);
    /* c = 1.18, so t = 1 is ~10 sound crossings of a zone (0.125): an O(1) imbalance of the
     * corner forces would give |u| ~ 0.1; round-off gives ~1e-15. */
    assert_true(umax < 1e-12);
    c2d_grid_destroy(&g);
    fixture_free(&f);
  }
  eos_destroy(&gas);
}

static void test_energy_random(void **state) {
  (void)state;
  eos_t *gas = eos_create_ideal_gas(1.4, 1.0);
  for (int geo = 0; geo < 2; ++geo)
    for (int hg = 0; hg < 2; ++hg) {
      c2d_fixture f;
      c2d_setup s;
      make_box(&f, &s, 16, (c2d_geometry)geo, gas);
      s.hg_coef = hg;
      srand(7);
      for (size_t j = 1; j < 16; ++j)
        for (size_t i = 1; i < 16; ++i) {
          f.u[i + 17 * j] = 0.5 * ((double)rand() / RAND_MAX - 0.5);
          f.v[i + 17 * j] = 0.5 * ((double)rand() / RAND_MAX - 0.5);
        }
      char msg[256];
      c2d_grid *g = NULL;
      c2d_grid_create(&s, &g, msg, sizeof msg);
      assert_non_null(g);
      double e0 = energy_total(g);
      assert_int_equal(c2d_grid_run_to(g, 0.5), MS_OK);
      double d = energy_drift(g, e0, 0.0);
      printf("random velocities %s hg %d: %ld steps, energy drift %.2e\n", geo ? "r-z" : "x-y", hg,
             c2d_grid_steps(g), d);
      assert_true(d < 1e-12); /* issue 24: total energy to 1e-12 relative */
      c2d_grid_destroy(&g);
      fixture_free(&f);
    }
  eos_destroy(&gas);
}

static void test_bad_mesh(void **state) {
  (void)state;
  eos_t *gas = eos_create_ideal_gas(1.4, 1.0);
  c2d_fixture f;
  c2d_setup s;
  char msg[256];
  make_box(&f, &s, 4, C2D_XY, gas);
  f.x[2 + 5 * 2] = 0.9; /* node (2,2) pushed past its neighbours: zones around it tangle */
  c2d_grid *bad = NULL;
  assert_int_equal(c2d_grid_create(&s, &bad, msg, sizeof msg), MS_ERR_INPUT);
  assert_null(bad);
  printf("%s\n", msg);
  assert_non_null(strstr(msg, "tangled or inverted"));
  assert_non_null(strstr(msg, "i = 2, j = 1")); /* the first zone (in index order) touching it */
  fixture_free(&f);
  make_box(&f, &s, 4, C2D_RZ, gas);
  for (size_t n = 0; n < 25; ++n) f.x[n] -= 0.5; /* r from −0.5 */
  assert_int_equal(c2d_grid_create(&s, &bad, msg, sizeof msg), MS_ERR_INPUT);
  assert_null(bad);
  printf("%s\n", msg);
  assert_non_null(strstr(msg, "r = -0.5 < 0"));
  fixture_free(&f);
  eos_destroy(&gas);
}

/* Outside pressure equal to the gas pressure on two sides (walls on the others, skewed interior):
 * exact equilibrium in x–y and r–z; a higher outside pressure compresses the box with the
 * pressure's work booked, so the energy balance holds to 1e-12. */
static void test_pressure_bc(void **state) {
  (void)state;
  eos_t *gas = eos_create_ideal_gas(1.4, 1.0);
  for (int geo = 0; geo < 2; ++geo)
    for (int squeeze = 0; squeeze < 2; ++squeeze) {
      c2d_fixture f;
      c2d_setup s;
      make_box(&f, &s, 8, (c2d_geometry)geo, gas);
      for (size_t j = 1; j < 8; ++j)
        for (size_t i = 1; i < 8; ++i) f.x[i + 9 * j] += 0.02 * sin(1.0 * (double)(i * j));
      double p_gas = 0.4 * 1.0 * 2.5; /* (γ − 1) ρ e */
      for (int k = 1; k < 4; k += 2) {
        s.bc[k].kind = C2D_BC_PRESSURE; /* IHI, JHI */
        s.bc[k].fn.kind = CONT_FN_CONST;
        s.bc[k].fn.value = squeeze ? 2.0 * p_gas : p_gas;
      }
      char msg[256];
      c2d_grid *g = NULL;
      c2d_grid_create(&s, &g, msg, sizeof msg);
      assert_non_null(g);
      double e0 = energy_total(g);
      assert_int_equal(c2d_grid_run_to(g, 1.0), MS_OK);
      c2d_view v = c2d_grid_view(g);
      double umax = 0;
      for (size_t n = 0; n < v.nnodes; ++n) umax = fmax(umax, hypot(v.u[n], v.v[n]));
      c2d_balance b = c2d_grid_balance(g);
      double d = energy_drift(g, e0, 0.0);
      printf("pressure boundary %s %s: %ld steps, max |u| %.2e, work %.4e, energy drift %.2e\n",
             geo ? "r-z" : "x-y", squeeze ? "2 p_gas" : "p_gas", c2d_grid_steps(g), umax, b.work,
             d);
      if (!squeeze) assert_true(umax < 1e-12); /* round-off, as test_uniform_rest */
      if (squeeze) assert_true(b.work > 0.01); /* the box is compressed: work was done */
      assert_true(d < 1e-12);
      c2d_grid_destroy(&g);
      fixture_free(&f);
    }
  eos_destroy(&gas);
}

/* A run that tangles (Saltzman mesh, no viscosity at all, a 5 km/s piston into cold gas) stops
 * with MS_ERR_UNSTABLE and a message naming the step, the time and the zone (i, j). */
static void test_runtime_inversion(void **state) {
  (void)state;
  eos_t *gas = eos_create_ideal_gas(5.0 / 3.0, 1.0);
  c2d_fixture f;
  fixture_init(&f, 40, 8, gas);
  c2d_mesh_saltzman(40, 8, f.x, f.y);
  for (size_t z = 0; z < 320; ++z) {
    f.rho[z] = 1.0;
    f.e[z] = 1e-9;
  }
  c2d_setup s;
  c2d_setup_defaults(&s);
  fixture_setup(&f, &s);
  s.q1 = s.q2 = 0.0;
  s.bc[C2D_ILO].kind = C2D_BC_PISTON;
  s.bc[C2D_ILO].dir[0] = 1.0;
  s.bc[C2D_ILO].fn.kind = CONT_FN_CONST;
  s.bc[C2D_ILO].fn.value = 5.0;
  s.bc[C2D_IHI].kind = s.bc[C2D_JLO].kind = s.bc[C2D_JHI].kind = C2D_BC_WALL;
  char msg[256];
  c2d_grid *g = NULL;
  c2d_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);
  ms_status st = c2d_grid_run_to(g, 0.15);
  printf("no viscosity: %s\n", st == MS_OK ? "ran (no inversion)" : c2d_grid_error(g));
  assert_int_equal(st, MS_ERR_UNSTABLE);
  const char *m = c2d_grid_error(g);
  assert_non_null(strstr(m, "step "));
  assert_non_null(strstr(m, "inverted"));
  assert_non_null(strstr(m, "(i = "));
  c2d_grid_destroy(&g);
  fixture_free(&f);
  eos_destroy(&gas);
}

/* OpenMP: the same Saltzman-like run with 1 and 2 threads gives bitwise equal states (zones
 * write only their own corners, nodes gather in a fixed order, sums are serial). */
/* Results do not depend on the thread count: a Saltzman piston run on 1, 2 and 3 threads (8 zone
 * rows: bands of 4/4 and 3/3/2, so band boundaries inside the mesh), with the sub-zonal pressure
 * (the scalar zone kernel) and without it (the vectorized x–y row), compared bit for bit. */
static void test_threads(void **state) {
  (void)state;
  eos_t *gas = eos_create_ideal_gas(5.0 / 3.0, 1.0);
  for (int h = 0; h < 2; ++h) {
    double *st[3];
    const size_t nz = 320, nn = 41 * 9;
    for (int t = 0; t < 3; ++t) {
      c2d_fixture f;
      fixture_init(&f, 40, 8, gas);
      c2d_mesh_saltzman(40, 8, f.x, f.y);
      for (size_t z = 0; z < nz; ++z) {
        f.rho[z] = 1.0;
        f.e[z] = 1e-9;
      }
      c2d_setup s;
      c2d_setup_defaults(&s);
      fixture_setup(&f, &s);
      s.hg_coef = h == 0 ? 1.0 : 0.0;
      s.bc[C2D_ILO].kind = C2D_BC_PISTON;
      s.bc[C2D_ILO].dir[0] = 1.0;
      s.bc[C2D_ILO].fn.kind = CONT_FN_CONST;
      s.bc[C2D_ILO].fn.value = 1.0;
      s.bc[C2D_IHI].kind = s.bc[C2D_JLO].kind = s.bc[C2D_JHI].kind = C2D_BC_WALL;
      char msg[256];
      c2d_grid *g = NULL;
      c2d_grid_create(&s, &g, msg, sizeof msg);
      assert_non_null(g);
      c2d_grid_set_threads(g, t + 1);
      assert_int_equal(c2d_grid_run_to(g, 0.3), MS_OK);
      c2d_view v = c2d_grid_view(g);
      st[t] = malloc((3 * nz + 4 * nn + 1) * sizeof(double));
      memcpy(st[t], v.rho, nz * sizeof(double));
      memcpy(st[t] + nz, v.e, nz * sizeof(double));
      memcpy(st[t] + 2 * nz, v.p, nz * sizeof(double));
      memcpy(st[t] + 3 * nz, v.x, nn * sizeof(double));
      memcpy(st[t] + 3 * nz + nn, v.y, nn * sizeof(double));
      memcpy(st[t] + 3 * nz + 2 * nn, v.u, nn * sizeof(double));
      memcpy(st[t] + 3 * nz + 3 * nn, v.v, nn * sizeof(double));
      st[t][3 * nz + 4 * nn] = c2d_grid_balance(g).work;
      c2d_grid_destroy(&g);
      fixture_free(&f);
    }
    for (int t = 1; t < 3; ++t)
      assert_memory_equal(st[0], st[t], (3 * nz + 4 * nn + 1) * sizeof(double));
    for (int t = 0; t < 3; ++t) free(st[t]);
  }
  eos_destroy(&gas);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_uniform_rest), cmocka_unit_test(test_energy_random),
      cmocka_unit_test(test_bad_mesh),     cmocka_unit_test(test_threads),
      cmocka_unit_test(test_pressure_bc),  cmocka_unit_test(test_runtime_inversion)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
