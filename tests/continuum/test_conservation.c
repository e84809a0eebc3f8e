/* SPDX-License-Identifier: MIT */
/* Conservation over 10⁴ steps (issue 3): total energy Σ(m e + ½ m u²) minus the work done by
 * the boundaries and by coupling forces, and (planar) momentum minus boundary impulse, stay
 * constant to round-off. Shocks, contacts, walls, free surfaces, pistons, pressure pulses and
 * the two-way coupling hooks are all exercised. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "cont.h"

enum { NSTEPS = 10000 };

typedef struct drift {
  double energy, momentum;
} drift;

/* Runs NSTEPS steps, returns the largest relative drifts seen. Energy is scaled by
 * |IE| + KE + |W| (the largest energy in play), momentum by Σ M|u| + |impulse|. */
static drift run_steps(cont_grid *g, void (*hook)(cont_grid *, long)) {
  cont_balance b0 = cont_grid_balance(g);
  double e0 = b0.internal + b0.kinetic, p0 = b0.momentum;
  drift d = {0, 0};
  for (long n = 0; n < NSTEPS; ++n) {
    if (hook) hook(g, n);
    ms_status st = cont_grid_step(g, INFINITY);
    if (st != MS_OK) printf("%s\n", cont_grid_error(g));
    assert_int_equal(st, MS_OK);
    cont_balance b = cont_grid_balance(g);
    double escale = fabs(b.internal) + b.kinetic + fabs(b.work) + fabs(e0);
    double de = fabs(b.internal + b.kinetic - b.work - e0) / escale;
    cont_view v = cont_grid_view(g);
    double pscale = fabs(b.impulse) + fabs(p0);
    for (size_t j = 0; j < v.nnodes; ++j)
      pscale += fabs(v.u[j]) * 0.5 * ((j > 0 ? v.mass[j - 1] : 0) + (j < v.ncells ? v.mass[j] : 0));
    double dp = fabs(b.momentum - b.impulse - p0) / pscale;
    if (de > d.energy) d.energy = de;
    if (dp > d.momentum) d.momentum = dp;
  }
  return d;
}

/* Round-off bound: each step adds O(10 ε) relative error per cell update, accumulating like a
 * random walk over 10⁴ steps, so ~1e-14; 1e-12 leaves a margin of 100 while a scheme that is
 * merely consistent (O(Δt²) energy error per step) fails it by orders of magnitude. */
static const double tol = 1e-12;

static void test_planar_impact_wall_free(void **state) {
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  eos_t *air = eos_create_ideal_gas(1.4, 1.2e-3);
  assert_non_null(al);
  assert_non_null(air);
  double e_air = 1.01325e-4 / (0.4 * 1.2e-3);
  cont_layer_spec layers[3] = {
      {.name = "target", .eos = al, .thickness = 0.2, .rho = 2.703, .ncells = 60},
      {.name = "flyer", .eos = al, .thickness = 0.1, .rho = 2.703, .u = -1.5, .ncells = 30},
      {.name = "air",
       .eos = air,
       .thickness = 0.3,
       .rho = 1.2e-3,
       .e = e_air,
       .ncells = 30,
       .grade_ratio = 1.05,
       .grade_side = CONT_GRADE_LEFT}};
  cont_setup s;
  cont_setup_defaults(&s);
  s.layers = layers;
  s.nlayers = 3;
  s.left.kind = CONT_BC_WALL;
  s.right.kind = CONT_BC_FREE;
  char msg[256];
  cont_grid *g = NULL;
  cont_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);
  drift d = run_steps(g, NULL);
  printf("planar impact, wall + free surface: %d steps to t = %.4g, max energy drift %.2e, "
         "momentum drift %.2e\n",
         NSTEPS, cont_grid_time(g), d.energy, d.momentum);
  assert_true(d.energy < tol);
  assert_true(d.momentum < tol);
  cont_grid_destroy(&g);
  eos_destroy(&al);
  eos_destroy(&air);
}

/* Piston with a velocity table on the left, trapezoidal pressure pulse on the right. */
static void test_spherical_piston_pressure(void **state) {
  eos_t *gas = eos_create_ideal_gas(5.0 / 3.0, 1.0);
  eos_t *pb = eos_create_mg_cold(11.34, 1.972, 3.0, 2.0, true);
  assert_non_null(gas);
  assert_non_null(pb);
  cont_layer_spec layers[2] = {
      {.name = "gas", .eos = gas, .thickness = 0.5, .rho = 1.0, .e = 1.0, .ncells = 50},
      {.name = "lead", .eos = pb, .thickness = 0.5, .rho = 11.34, .ncells = 50}};
  double tt[3] = {0.0, 0.05, 0.5}, vv[3] = {0.0, 0.5, 0.0}; /* out, then back to rest */
  cont_geometry geos[3] = {CONT_PLANAR, CONT_CYLINDRICAL, CONT_SPHERICAL};
  for (int k = 0; k < 3; ++k) {
    cont_setup s;
    cont_setup_defaults(&s);
    s.geometry = geos[k];
    s.x_left = 0.2;
    s.layers = layers;
    s.nlayers = 2;
    s.left.kind = CONT_BC_PISTON;
    s.left.fn = (cont_fn){.kind = CONT_FN_TABLE, .n = 3, .t = tt, .v = vv};
    s.right.kind = CONT_BC_PRESSURE;
    s.right.fn = (cont_fn){.kind = CONT_FN_TRAPEZOID,
                           .value = 5.0,
                           .t0 = 0.001,
                           .rise = 0.002,
                           .hold = 0.01,
                           .fall = 0.005};
    char msg[256];
    cont_grid *g = NULL;
    cont_grid_create(&s, &g, msg, sizeof msg);
    assert_non_null(g);
    drift d = run_steps(g, NULL);
    cont_balance b = cont_grid_balance(g);
    printf("geometry %d, piston + pressure pulse: t = %.4g, boundary work %.4g, max energy drift "
           "%.2e\n",
           k, cont_grid_time(g), b.work, d.energy);
    assert_true(fabs(b.work) > 1e-3 * (b.internal + b.kinetic)); /* the boundaries did work */
    assert_true(d.energy < tol);
    if (k == 0) assert_true(d.momentum < tol);
    cont_grid_destroy(&g);
  }
  eos_destroy(&gas);
  eos_destroy(&pb);
}

/* Two-way coupling hooks: an oscillating external traction on one interior node and a
 * prescribed velocity on another; their work and impulse enter the balance. */
static void coupling_hook(cont_grid *g, long n) {
  cont_grid_set_node_force(g, 30, 2.0 * sin(0.01 * (double)n));
  if (n == 0) cont_grid_set_node_velocity(g, 70, 0.3);
  if (n == NSTEPS / 2) cont_grid_set_node_velocity(g, 70, NAN);
}

static void test_coupling_hooks(void **state) {
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  cont_layer_spec layer = {.name = "al", .eos = al, .thickness = 1.0, .rho = 2.703, .ncells = 100};
  cont_setup s;
  cont_setup_defaults(&s);
  s.layers = &layer;
  s.nlayers = 1;
  s.left.kind = CONT_BC_FREE;
  s.right.kind = CONT_BC_FREE;
  char msg[256];
  cont_grid *g = NULL;
  cont_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);
  drift d = run_steps(g, coupling_hook);
  cont_balance b = cont_grid_balance(g);
  printf("coupling hooks: work %.4g, impulse %.4g, max drifts energy %.2e momentum %.2e\n", b.work,
         b.impulse, d.energy, d.momentum);
  assert_true(fabs(b.work) > 0.0 && fabs(b.impulse) > 0.0);
  assert_true(d.energy < tol);
  assert_true(d.momentum < tol);
  cont_grid_destroy(&g);
  eos_destroy(&al);
}

/* Several cache-blocking chunks (3000 cells > 2 × CONT_CHUNK): two Al slabs collide at ±1 km/s.
 * The flow is mirror-symmetric about the centre while the chunk boundaries are not, so a
 * mistake in the chunk/window hand-over would break the symmetry at O(1); round-off (positions
 * summed from the left end) allows ~1e-12. Energy and momentum are checked as above. */
static void test_chunk_boundaries(void **state) {
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  cont_layer_spec layers[2] = {
      {.name = "left", .eos = al, .thickness = 1.0, .rho = 2.703, .u = 1.0, .ncells = 1500},
      {.name = "right", .eos = al, .thickness = 1.0, .rho = 2.703, .u = -1.0, .ncells = 1500}};
  cont_setup s;
  cont_setup_defaults(&s);
  s.x_left = -1.0;
  s.layers = layers;
  s.nlayers = 2;
  s.left.kind = CONT_BC_FREE;
  s.right.kind = CONT_BC_FREE;
  char msg[256];
  cont_grid *g = NULL;
  cont_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);
  cont_balance b0 = cont_grid_balance(g);
  for (int n = 0; n < 2000; ++n) assert_int_equal(cont_grid_step(g, INFINITY), MS_OK);
  cont_balance b = cont_grid_balance(g);
  cont_view v = cont_grid_view(g);
  double asym_u = 0, asym_rho = 0;
  for (size_t j = 0; j < v.nnodes; ++j) asym_u = fmax(asym_u, fabs(v.u[j] + v.u[v.ncells - j]));
  for (size_t i = 0; i < v.ncells; ++i)
    asym_rho = fmax(asym_rho, fabs(v.rho[i] - v.rho[v.ncells - 1 - i]) / v.rho[i]);
  double de =
      fabs(b.internal + b.kinetic - b.work - b0.internal - b0.kinetic) / (b0.internal + b0.kinetic);
  printf("chunked grid (3000 cells): t = %.4g, mirror asymmetry u %.2e, rho %.2e, energy drift "
         "%.2e, momentum %.2e\n",
         cont_grid_time(g), asym_u, asym_rho, de, b.momentum);
  assert_true(asym_u < 1e-10 && asym_rho < 1e-10);
  assert_true(de < tol);
  assert_true(fabs(b.momentum) < 1e-12); /* ±1 km/s slabs of equal mass: zero total */
  cont_grid_destroy(&g);
  eos_destroy(&al);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_planar_impact_wall_free),
                                     cmocka_unit_test(test_spherical_piston_pressure),
                                     cmocka_unit_test(test_coupling_hooks),
                                     cmocka_unit_test(test_chunk_boundaries)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
