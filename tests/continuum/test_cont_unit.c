/* SPDX-License-Identifier: MIT */
/* Unit checks of the continuum grid's pieces: time functions, grading, energy from pressure,
 * sampling and nearest node, rest and uniform-motion states in every geometry. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "cont.h"

static void test_time_functions(void **state) {
  cont_fn c = {.kind = CONT_FN_CONST, .value = 3.0};
  assert_true(cont_fn_eval(&c, 123.0) == 3.0);
  double t[3] = {0.0, 1.0, 3.0}, v[3] = {0.0, 2.0, -2.0};
  cont_fn tab = {.kind = CONT_FN_TABLE, .n = 3, .t = t, .v = v};
  /* piecewise linear inside, constant beyond the ends; exact in binary for these points */
  assert_true(cont_fn_eval(&tab, -1.0) == 0.0);
  assert_true(cont_fn_eval(&tab, 0.5) == 1.0);
  assert_true(cont_fn_eval(&tab, 2.0) == 0.0);
  assert_true(cont_fn_eval(&tab, 5.0) == -2.0);
  cont_fn tr = {
      .kind = CONT_FN_TRAPEZOID, .value = 4.0, .t0 = 1.0, .rise = 1.0, .hold = 2.0, .fall = 1.0};
  assert_true(cont_fn_eval(&tr, 0.5) == 0.0);
  assert_true(cont_fn_eval(&tr, 1.5) == 2.0);
  assert_true(cont_fn_eval(&tr, 3.0) == 4.0);
  assert_true(cont_fn_eval(&tr, 4.5) == 2.0);
  assert_true(cont_fn_eval(&tr, 6.0) == 0.0);
  cont_fn ex = {.kind = CONT_FN_EXP_DECAY, .value = 2.0, .t0 = 0.0, .rise = 0.0, .tau = 0.5};
  assert_true(fabs(cont_fn_eval(&ex, 1.0) - 2.0 * exp(-2.0)) < 1e-15);
  cont_fn copy;
  cont_fn_copy(&copy, &tab);
  assert_true(copy.t != tab.t && cont_fn_eval(&copy, 0.5) == 1.0);
  cont_fn_free(&copy);
}

static void test_grading_and_sampling(void **state) {
  eos_t *gas = eos_create_ideal_gas(1.4, 1.0);
  cont_layer_spec layers[2] = {{.name = "a",
                                .eos = gas,
                                .thickness = 1.0,
                                .rho = 1.0,
                                .e = 1.0,
                                .ncells = 20,
                                .grade_ratio = 1.1,
                                .grade_side = CONT_GRADE_RIGHT,
                                .material = 3},
                               {.name = "b",
                                .eos = gas,
                                .thickness = 1.0,
                                .rho = 1.0,
                                .e = 1.0,
                                .u = 1.0,
                                .ncells = 20,
                                .grade_ratio = 1.1,
                                .grade_side = CONT_GRADE_LEFT,
                                .material = 5}};
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
  cont_view v = cont_grid_view(g);
  /* layer ends where it should (round-off of 20 additions), smallest cells at the contact,
   * neighbour ratio 1.1 */
  assert_true(fabs(v.x[20] - 0.0) < 1e-14 && fabs(v.x[40] - 1.0) < 1e-14);
  double d19 = v.x[20] - v.x[19], d18 = v.x[19] - v.x[18], d20 = v.x[21] - v.x[20];
  assert_true(fabs(d18 / d19 - 1.1) < 1e-12 && fabs(d20 - d19) < 1e-15);
  assert_true(v.x[1] - v.x[0] > 5.0 * d19);
  /* contact node: mass-weighted mean of the two layers' velocities (equal masses: 0.5) */
  assert_true(fabs(v.u[20] - 0.5) < 1e-15);
  cont_sample smp;
  double xm = 0.5 * (v.x[19] + v.x[20]);
  assert_true(cont_grid_sample(g, xm, &smp));
  assert_int_equal(smp.cell, 19);
  assert_int_equal(smp.material, 3);
  assert_int_equal(smp.layer, 0);
  assert_true(fabs(smp.u - 0.25) < 1e-15 && fabs(smp.rho - 1.0) < 1e-15);
  assert_true(fabs(smp.p - 0.4) < 1e-15);
  assert_true(cont_grid_sample(g, 0.5, &smp) && smp.material == 5);
  assert_false(cont_grid_sample(g, -1.5, &smp));
  assert_int_equal(cont_grid_nearest_node(g, -0.0001), 20);
  assert_int_equal(cont_grid_nearest_node(g, 7.0), 40);
  cont_grid_destroy(&g);
  eos_destroy(&gas);
}

static void test_energy_from_pressure(void **state) {
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  eos_t *gas = eos_create_ideal_gas(5.0 / 3.0, 1.0);
  double e = 0;
  /* bisection to the last bit of e: p back within 1e-12 relative */
  assert_true(cont_energy_from_pressure(al, 3.0, 10.0, &e));
  assert_true(fabs(eos_pressure(al, 3.0, e) - 10.0) < 1e-11);
  assert_true(cont_energy_from_pressure(al, 2.5, 0.0, &e)); /* tension: e < 0 is fine here */
  assert_true(fabs(eos_pressure(al, 2.5, e)) < 1e-11);
  assert_true(cont_energy_from_pressure(gas, 2.0, 3.0, &e));
  assert_true(fabs(e - 3.0 / ((5.0 / 3.0 - 1.0) * 2.0)) < 1e-13);
  assert_false(cont_energy_from_pressure(gas, 2.0, -1.0, &e)); /* no e ≥ 0 gives p < 0 */
  eos_destroy(&al);
  eos_destroy(&gas);
}

/* A gas at rest at uniform pressure stays exactly at rest in every geometry (the face-area
 * force of a uniform pressure field cancels), and in planar geometry a uniformly moving slab
 * between equal outside pressures keeps its velocity and density. */
static void test_rest_and_uniform_motion(void **state) {
  eos_t *gas = eos_create_ideal_gas(1.4, 1.0);
  const double p_in = eos_pressure(gas, 1.0, 2.5); /* (γ−1)ρe, ~1 up to rounding of γ−1 */
  for (int geo = 0; geo < 3; ++geo) {
    cont_layer_spec layer = {.name = "g",
                             .eos = gas,
                             .thickness = 1.0,
                             .rho = 1.0,
                             .e = 2.5,
                             .ncells = 50,
                             .grade_ratio = 1.05,
                             .grade_side = CONT_GRADE_BOTH};
    cont_setup s;
    cont_setup_defaults(&s);
    s.geometry = (cont_geometry)geo;
    s.x_left = 0.5;
    s.layers = &layer;
    s.nlayers = 1;
    s.left.kind = CONT_BC_PRESSURE;
    s.left.fn = (cont_fn){.kind = CONT_FN_CONST, .value = p_in};
    s.right.kind = CONT_BC_PRESSURE;
    s.right.fn = (cont_fn){.kind = CONT_FN_CONST, .value = p_in};
    char msg[256];
    cont_grid *g = NULL;
    cont_grid_create(&s, &g, msg, sizeof msg);
    assert_non_null(g);
    for (int n = 0; n < 200; ++n) assert_int_equal(cont_grid_step(g, INFINITY), MS_OK);
    cont_view v = cont_grid_view(g);
    double umax = 0;
    for (size_t j = 0; j < v.nnodes; ++j) umax = fmax(umax, fabs(v.u[j]));
    /* the same pressure in and out: every force is exactly zero */
    assert_true(umax == 0.0);
    cont_grid_destroy(&g);
  }
  cont_layer_spec layer = {
      .name = "g", .eos = gas, .thickness = 1.0, .rho = 1.0, .e = 2.5, .u = 1.0, .ncells = 50};
  cont_setup s;
  cont_setup_defaults(&s);
  s.layers = &layer;
  s.nlayers = 1;
  s.left.kind = CONT_BC_PRESSURE;
  s.left.fn = (cont_fn){.kind = CONT_FN_CONST, .value = p_in};
  s.right.kind = CONT_BC_PRESSURE;
  s.right.fn = (cont_fn){.kind = CONT_FN_CONST, .value = p_in};
  char msg[256];
  cont_grid *g = NULL;
  cont_grid_create(&s, &g, msg, sizeof msg);
  assert_int_equal(cont_grid_run_to(g, 0.3), MS_OK);
  cont_view v = cont_grid_view(g);
  /* translation: every node moved by 0.3, ρ unchanged, up to round-off (positions rounded at
   * each step perturb volumes by ~1e-16, which feeds back as ~1e-16 pressure differences) */
  for (size_t j = 0; j < v.nnodes; ++j) {
    assert_true(fabs(v.u[j] - 1.0) < 1e-12);
    assert_true(fabs(v.x[j] - (0.3 + (double)j / 50.0)) < 1e-13);
  }
  for (size_t i = 0; i < v.ncells; ++i) assert_true(fabs(v.rho[i] - 1.0) < 1e-12);
  assert_true(cont_grid_time(g) == 0.3);
  cont_grid_destroy(&g);
  eos_destroy(&gas);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_time_functions), cmocka_unit_test(test_grading_and_sampling),
      cmocka_unit_test(test_energy_from_pressure), cmocka_unit_test(test_rest_and_uniform_motion)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
