/* SPDX-License-Identifier: MIT */
/* The piston by columns of the particle-region interface (ptl_region_set_piston_columns,
 * particles/dm/dm_columns.c; issue 24's 2D drive), on the discrete model's region:
 *   - columns that all carry the single piston's history give a run bit for bit equal to
 *     ptl_region_set_piston's (same arithmetic: the step's mean velocity);
 *   - columns with a velocity varying across y and a lateral component: every driven particle
 *     moves by exactly the displacement interpolated between its two columns (to round-off);
 *   - bad arrays are refused (MS_ERR_INPUT), and so is the call on cluster dynamics, which has
 *     no piston by columns (its results are untouched). */
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

/* h = 10 µm, 20 columns, 30 layers of Al (yield none) */
static const char *const DM = "particles:\n"
                              "  r0: 1.0e-3\n"
                              "  width: 0.02\n"
                              "  response: eos\n"
                              "  yield: none\n";

typedef struct built {
  dk_doc *doc;
  ptl_region_params *pp;
  ptl_region *r;
} built;

static void build(built *b, const char *model, const char *text, const eos_t *eos, double depth) {
  dk_errors e;
  dk_errors_init(&e);
  b->doc = dk_load_string(text, "p.yaml", &e);
  assert_non_null(b->doc);
  const ptl_region_model *m = ptl_region_model_find(model);
  assert_non_null(m);
  b->pp = ptl_region_params_read(m, b->doc, dk_get(dk_root(b->doc), "particles"), &e);
  if (e.n) dk_errors_print(&e, stderr);
  assert_non_null(b->pp);
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  b->r = NULL;
  assert_int_equal(ptl_region_create(b->pp, &ctx, eos, 0.0, depth, &b->r), MS_OK);
  ms_ctx_close(&ctx);
  dk_errors_free(&e);
}

static void drop(built *b) {
  ptl_region_destroy(&b->r);
  ptl_region_params_destroy(&b->pp);
  dk_free(b->doc);
}

/* A ramp to 0.5 km/s and a hold: the single piston vs 20 identical columns at the particles' y. */
static void test_same_as_single(void **state) {
  (void)state;
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  built a, b;
  build(&a, "discrete_model", DM, al, 0.03);
  build(&b, "discrete_model", DM, al, 0.03);
  const double t[3] = {0, 0.002, 1}, u[3] = {0, 0.5, 0.5}, dir[3] = {1, 0, 0};
  ptl_region_set_piston(a.r, 3, t, u, dir);
  enum { NC = 20 };
  double y[NC], uc[3 * NC];
  for (int c = 0; c < NC; c++) {
    y[c] = (c + 0.5) * 1.0e-3; /* the particles' columns: weights 0 and 1 exactly */
    for (int k = 0; k < 3; k++) uc[k * NC + c] = u[k];
  }
  assert_int_equal(ptl_region_set_piston_columns(b.r, NC, y, 3, t, uc, NULL), MS_OK);
  assert_int_equal(ptl_region_init(a.r), MS_OK);
  assert_int_equal(ptl_region_init(b.r), MS_OK);
  for (int k = 0; k < 300; k++) {
    assert_int_equal(ptl_region_step(a.r), MS_OK);
    assert_int_equal(ptl_region_step(b.r), MS_OK);
  }
  const ptl_state *pa = ptl_region_state(a.r), *pb = ptl_region_state(b.r);
  size_t differ = 0;
  for (size_t i = 0; i < pa->n; i++)
    differ += pa->x[i] != pb->x[i] || pa->y[i] != pb->y[i] || pa->vx[i] != pb->vx[i] ||
              pa->vy[i] != pb->vy[i];
  printf("single piston vs identical columns: %zu of %zu particles differ after 300 steps; "
         "free surface %.6f km/s\n",
         differ, pa->n, ptl_region_free_surface_velocity(a.r));
  assert_int_equal(differ, 0);
  assert_true(ptl_region_free_surface_velocity(a.r) > 0.1); /* the shock reached the surface */
  drop(&a);
  drop(&b);
  eos_destroy(&al);
}

/* 5 columns at y = 0, 0.005, …, 0.02 with u_x = 0.2 + 10 y and u_y = 0.05 − 2.5 y ramping in
 * over 0.001: each driven particle's displacement after the run is the column displacements
 * interpolated linearly at its y (the piecewise-linear histories integrate exactly). */
static void test_interpolated_displacement(void **state) {
  (void)state;
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  built a;
  build(&a, "discrete_model", DM, al, 0.03);
  enum { NC = 5 };
  const double t[2] = {0, 0.001};
  double y[NC], ux[2 * NC], uy[2 * NC];
  for (int c = 0; c < NC; c++) {
    y[c] = 0.005 * c;
    ux[c] = uy[c] = 0.0;
    ux[NC + c] = 0.2 + 10 * y[c], uy[NC + c] = 0.05 - 2.5 * y[c];
  }
  ptl_state *ps = ptl_region_state(a.r);
  const size_t n = ps->n;
  double *x0 = malloc(n * sizeof *x0), *y0 = malloc(n * sizeof *y0);
  for (size_t i = 0; i < n; i++) x0[i] = ps->x[i], y0[i] = ps->y[i];
  assert_int_equal(ptl_region_set_piston_columns(a.r, NC, y, 2, t, ux, uy), MS_OK);
  assert_int_equal(ptl_region_init(a.r), MS_OK);
  for (int k = 0; k < 100; k++) assert_int_equal(ptl_region_step(a.r), MS_OK);
  const double T = ptl_region_time(a.r), hold = T - 0.5 * t[1]; /* ∫ of ramp then hold */
  double worst = 0;
  size_t nd = 0;
  ps = ptl_region_state(a.r);
  for (size_t i = 0; i < n; i++) {
    if (!(ps->flags[i] & PTL_DRIVEN)) continue;
    nd++;
    /* linear in y between columns, and so the interpolation is exact: the particle's own */
    const double yy = fmin(y0[i], y[NC - 1]);
    const double dx = (0.2 + 10 * yy) * hold, dy = (0.05 - 2.5 * yy) * hold;
    worst = fmax(worst, fmax(fabs(ps->x[i] - x0[i] - dx), fabs(ps->y[i] - y0[i] - dy)));
  }
  printf("columns: %zu driven particles, largest displacement error %.3g cm of %.3g cm\n", nd,
         worst, 0.4 * hold);
  assert_int_equal(nd, 40);
  /* 100 steps of summed means: 1e-12 of the displacement is ~1e4 roundings of 1e-16 */
  assert_true(worst < 1e-12 * 0.4 * hold);
  free(x0), free(y0);
  drop(&a);
  eos_destroy(&al);
}

static void test_refused(void **state) {
  (void)state;
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  built a;
  build(&a, "discrete_model", DM, al, 0.03);
  const double t[2] = {0, 1}, tbad[2] = {1, 0}, u[4] = {0, 0, 1, 1}, ybad[2] = {0.01, 0.0},
               y[2] = {0.0, 0.01}, unan[4] = {0, NAN, 1, 1};
  assert_int_equal(ptl_region_set_piston_columns(a.r, 2, ybad, 2, t, u, NULL), MS_ERR_INPUT);
  assert_int_equal(ptl_region_set_piston_columns(a.r, 2, y, 2, tbad, u, NULL), MS_ERR_INPUT);
  assert_int_equal(ptl_region_set_piston_columns(a.r, 2, y, 2, t, unan, NULL), MS_ERR_INPUT);
  assert_int_equal(ptl_region_set_piston_columns(a.r, 0, y, 2, t, u, NULL), MS_ERR_INPUT);
  drop(&a);
  /* cluster dynamics has none */
  built c;
  build(&c, "cluster_dynamics",
        "particles:\n  lattice: tri2d\n  width: 0.004\n  cutoff: 1.2\n  r0: 2.0e-4\n", al, 0.01);
  assert_int_equal(ptl_region_set_piston_columns(c.r, 2, y, 2, t, u, NULL), MS_ERR_INPUT);
  drop(&c);
  eos_destroy(&al);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_same_as_single),
                                     cmocka_unit_test(test_interpolated_displacement),
                                     cmocka_unit_test(test_refused)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
