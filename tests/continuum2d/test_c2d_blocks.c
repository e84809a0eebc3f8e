/* SPDX-License-Identifier: MIT */
/* Mesh blocks of the grid2d deck (`mesh: {blocks: [...]}`, docs/continuum2d.md §8, issue 24):
 * blocks tile the logical rectangle and share their edge nodes; grading; a sphere in gas from
 * two polar blocks in r–z; logical overlap, a logical gap, blocks that do not meet, a tangled
 * or inverted block, r < 0 and blocks overlapping in space are located errors at the block; the
 * finite flyer of test_flyer.c built from three blocks steps bit for bit as the same problem set
 * up zone by zone (the regions route: material and velocity by zone centre and node height). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "c2d_deck_test.h"
#include "c2d_test.h"
#include "test_util.h"

static const char *head =
    "problem: grid2d\n"
    "materials:\n"
    "  - name: gas\n"
    "    eos: {type: ideal_gas, gamma: 1.4, rho0: 0.01, p0: 1.01325e-4}\n"
    "  - name: al\n"
    "    eos: {type: mg_linear, rho0: 2.703, c0: 5.35, s: 1.34, gamma0: 2.0}\n"
    "grid2d:\n"
    "  geometry: %s\n"
    "  time: {end: 0.1}\n"
    "  boundaries: {ilo: {type: %s}}\n"
    "  mesh:\n"
    "    blocks:\n"; /* line 12 */

/* Loads the deck head + `blocks` (lines from 13 on, one block per line). */
static void load(c2d_deck *l, const char *geo, const char *ilo, const char *blocks) {
  char text[4096];
  int n = snprintf(text, sizeof text, head, geo, ilo);
  snprintf(text + n, sizeof text - (size_t)n, "%s", blocks);
  c2d_deck_load(l, text);
}

/* Four blocks 2 × 2 (different materials and densities) tile an 8 × 6 mesh: the shared nodes are
 * the same (one node each, positions continuous), each block's zones have its state, grading
 * makes successive zone widths grow by the ratio, and the grid steps. */
static void test_tiling(void **state) {
  (void)state;
  c2d_deck l;
  load(&l, "xy", "wall",
       "      - {i: [0, 5], j: [0, 4], x: [0, 1], y: [0, 1], material: al, density: 2.703}\n"
       "      - {i: [5, 8], j: [0, 4], x: [1, 2], y: [0, 1], grade: [1.2, 1], material: gas, "
       "density: 0.01, pressure: 1.01325e-4}\n"
       "      - {i: [0, 5], j: [4, 6], x: [0, 1], y: [1, 1.5], material: al, density: 3.0}\n"
       "      - {i: [5, 8], j: [4, 6], x: [1, 2], y: [1, 1.5], grade: [1.2, 1], material: gas, "
       "density: 0.01, energy: 0.025}\n");
  assert_non_null(l.p);
  assert_int_equal(l.e.n, 0);
  c2d_grid *g = c2d_problem_grid(l.p);
  c2d_view v = c2d_grid_view(g);
  assert_int_equal(v.ni, 8);
  assert_int_equal(v.nj, 6);
  for (size_t j = 0; j <= 6; ++j) {
    const double *x = &v.x[9 * j];
    assert_true(x[5] == 1.0 && x[8] == 2.0); /* the shared edge node, exactly */
    /* graded: widths grow by 1.2 (to round-off) */
    assert_true(fabs((x[7] - x[6]) / (x[6] - x[5]) - 1.2) < 1e-12);
    assert_true(fabs((x[8] - x[7]) / (x[7] - x[6]) - 1.2) < 1e-12);
    assert_true(fabs(x[1] - 0.2) < 1e-15);
  }
  for (size_t z = 0; z < v.nzones; ++z) {
    const size_t i = z % 8, j = z / 8;
    const double want = i < 5 ? (j < 4 ? 2.703 : 3.0) : 0.01;
    assert_true(fabs(v.rho[z] - want) < 1e-14);
    assert_int_equal(v.material[z], i < 5 ? 1 : 0);
    /* the gas: p from the block's pressure (through the EOS, to its solver's round-off) or
     * from its energy, 0.4 · 0.01 · 0.025 = 1e-4 */
    if (i >= 5) assert_true(fabs(v.p[z] / (j < 4 ? 1.01325e-4 : 1e-4) - 1) < 1e-12);
  }
  assert_int_equal(c2d_grid_step(g, 1e-3), MS_OK);
  c2d_deck_close(&l);
}

/* A sphere of Al (r < 0.5) in gas (0.5 < r < 1) in r–z: two polar blocks, the inner one with the
 * degenerate centre (ilo fixed). The shared circle r = 0.5 is one set of nodes. */
static void test_sphere_rz(void **state) {
  (void)state;
  c2d_deck l;
  load(&l, "rz", "fixed",
       "      - {type: polar, i: [0, 10], j: [0, 8], r: [0, 0.5], theta: [0, 90], material: al, "
       "density: 2.703, velocity: [0, -1]}\n"
       "      - {type: polar, i: [10, 20], j: [0, 8], r: [0.5, 1], theta: [0, 90], grade: [1.1, "
       "1], material: gas, density: 0.01, pressure: 1.01325e-4}\n");
  assert_non_null(l.p);
  c2d_grid *g = c2d_problem_grid(l.p);
  c2d_view v = c2d_grid_view(g);
  for (size_t j = 0; j <= 8; ++j) {
    const size_t n = 10 + 21 * j;
    assert_true(fabs(hypot(v.x[n], v.y[n]) - 0.5) < 1e-15);
    assert_true(v.v[n] == -1.0); /* the first block (in deck order) holding it */
    assert_true(v.v[n + 1] == 0.0);
  }
  for (int k = 0; k < 5; ++k) assert_int_equal(c2d_grid_step(g, 1e-3), MS_OK);
  c2d_deck_close(&l);
}

/* Regions on a blocks mesh with no section material: a region names its material and density
 * (its zones take them); one that does not is an error. */
static void test_regions_on_blocks(void **state) {
  (void)state;
  const char *blk =
      "      - {i: [0, 4], j: [0, 2], x: [0, 1], y: [0, 0.5], material: al, density: 2.703}\n"
      "  regions:\n"
      "    - {x: [0, 0.5], material: gas, density: 0.01, energy: 0.025}\n";
  c2d_deck l;
  load(&l, "xy", "wall", blk);
  assert_non_null(l.p);
  c2d_view v = c2d_grid_view(c2d_problem_grid(l.p));
  for (size_t z = 0; z < v.nzones; ++z) assert_int_equal(v.material[z], z % 4 < 2 ? 0 : 1);
  c2d_deck_close(&l);
  load(&l, "xy", "wall",
       "      - {i: [0, 4], j: [0, 2], x: [0, 1], y: [0, 0.5], material: al, density: 2.703}\n"
       "  regions:\n"
       "    - {x: [0, 0.5], energy: 0.025}\n");
  assert_null(l.p);
  assert_true(
      has_error(&l.e, "deck.yaml:15:7: grid2d.regions[0]: missing required key 'material'"));
  c2d_deck_close(&l);
}

typedef struct bad_case {
  const char *geo, *blocks, *msg;
} bad_case;

/* Each broken deck is refused with the error at the block (line 13 + its index, column 9). */
static void test_block_errors(void **state) {
  (void)state;
  const char *A =
      "      - {i: [0, 4], j: [0, 4], x: [0, 1], y: [0, 1], material: al, density: 2.7}\n";
  const bad_case cases[] = {
      {"xy",
       "      - {i: [3, 8], j: [0, 4], x: [0.75, 2], y: [0, 1], material: al, density: 2.7}\n",
       "deck.yaml:14:9: block 1 overlaps block 0 at zone (i = 3, j = 0)"},
      {"xy", "      - {i: [5, 8], j: [0, 4], x: [1, 2], y: [0, 1], material: al, density: 2.7}\n",
       "deck.yaml:13:7: blocks: zone (i = 4, j = 0) is in no block (a gap"},
      {"xy", "      - {i: [4, 8], j: [0, 4], x: [1.1, 2], y: [0, 1], material: al, density: 2.7}\n",
       "deck.yaml:14:9: blocks 0 and 1 do not meet at node (i = 4, j = 0): (1, 0) vs (1.1, 0)"},
      {"xy",
       "      - {i: [4, 8], j: [0, 4], x: [1, 2], y: [0, 1], skew: 20, material: al, density: "
       "2.7}\n",
       "deck.yaml:14:9: block 1: zone (i = 6, j = 0) is tangled or inverted"},
      {"xy", "      - {i: [4, 8], j: [0, 4], x: [2, 1], y: [0, 1], material: al, density: 2.7}\n",
       "deck.yaml:14:9: blocks 0 and 1 do not meet at node (i = 4, j = 0)"},
      {"rz", "      - {i: [4, 8], j: [0, 4], x: [1, -1], y: [0, 1], material: al, density: 2.7}\n",
       "deck.yaml:14:9: block 1: zone (i = 4, j = 0) is tangled or inverted"},
      {"xy", "      - {i: [4, 8], j: [0, 4], x: [1, 2], y: [0, 1], density: 2.7}\n",
       "deck.yaml:14:9: block 1: material: required (in the block or in grid2d)"},
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    char blocks[1024];
    snprintf(blocks, sizeof blocks, "%s%s", A, cases[c].blocks);
    c2d_deck l;
    load(&l, cases[c].geo, "wall", blocks);
    assert_null(l.p);
    if (!has_error(&l.e, cases[c].msg)) printf("case %zu: expected \"%s\"\n", c, cases[c].msg);
    assert_true(has_error(&l.e, cases[c].msg));
    c2d_deck_close(&l);
  }
  /* a block alone: inverted (x reversed), r < 0 in r–z */
  const bad_case single[] = {
      {"xy", "      - {i: [0, 4], j: [0, 4], x: [1, 0], y: [0, 1], material: al, density: 2.7}\n",
       "deck.yaml:13:9: block 0: zone (i = 0, j = 0) is tangled or inverted"},
      {"rz", "      - {i: [0, 4], j: [0, 4], x: [-1, 1], y: [0, 1], material: al, density: 2.7}\n",
       "deck.yaml:13:9: block 0: node (i = 0, j = 0) has r = -1 < 0 (r–z)"},
      /* two polar sectors that meet at 200° and wind on to 400°: every zone is fine and the
       * shared nodes agree, but the second block lies over the first */
      {"xy",
       "      - {type: polar, i: [0, 4], j: [0, 10], r: [1, 2], theta: [0, 200], material: al, "
       "density: 2.7}\n"
       "      - {type: polar, i: [0, 4], j: [10, 20], r: [1, 2], theta: [200, 400], material: "
       "al, density: 2.7}\n",
       "deck.yaml:14:9: block 1 overlaps block 0 in space: the mesh's outer boundary crosses "
       "itself"},
  };
  for (size_t c = 0; c < sizeof single / sizeof single[0]; ++c) {
    c2d_deck l;
    load(&l, single[c].geo, "wall", single[c].blocks);
    assert_null(l.p);
    if (!has_error(&l.e, single[c].msg)) printf("single %zu: expected \"%s\"\n", c, single[c].msg);
    assert_true(has_error(&l.e, single[c].msg));
    c2d_deck_close(&l);
  }
}

/* The finite flyer (test_flyer.c) in dyadic sizes (h = 1/16, flyer 1 × 0.375, target 1.5 × 1)
 * so that every node coordinate is exact in both routes: as three blocks (target at rest listed
 * first, so the contact nodes start at rest; flyer and gas beside it at 2 km/s) and as the
 * zone-by-zone set-up. Both are stepped to t = 0.1; every field must be bit for bit equal. */
static void test_flyer_blocks(void **state) {
  (void)state;
  c2d_deck l;
  load(&l, "rz", "wall",
       "      - {i: [0, 24], j: [0, 16], x: [0, 1.5], y: [-1, 0], material: al, density: 2.703, "
       "energy: 0}\n"
       "      - {i: [0, 16], j: [16, 22], x: [0, 1], y: [0, 0.375], material: al, density: "
       "2.703, energy: 0, velocity: [0, -2]}\n"
       "      - {i: [16, 24], j: [16, 22], x: [1, 1.5], y: [0, 0.375], material: gas, density: "
       "0.01, energy: 0.02533125, velocity: [0, -2]}\n"
       "  hourglass: 1\n");
  assert_non_null(l.p);
  c2d_grid *gb = c2d_problem_grid(l.p);
  const size_t ni = 24, nj = 22;
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  eos_t *gas = eos_create_ideal_gas(1.4, 0.01);
  c2d_fixture f;
  fixture_init(&f, ni, nj, al);
  c2d_mesh_rect(ni, nj, 0.0, 1.5, -1.0, 0.375, f.x, f.y);
  for (size_t n = 0; n < (ni + 1) * (nj + 1); ++n)
    if (f.y[n] > 1e-12) f.v[n] = -2.0;
  int *mid = calloc(ni * nj, sizeof *mid);
  for (size_t z = 0; z < ni * nj; ++z) {
    const double rc = ((double)(z % ni) + 0.5) / 16, zc = -1.0 + ((double)(z / ni) + 0.5) / 16;
    f.rho[z] = 2.703, f.e[z] = 0.0, mid[z] = 1;
    if (zc > 0 && rc > 1.0) f.eos[z] = gas, f.rho[z] = 0.01, f.e[z] = 0.02533125, mid[z] = 0;
  }
  c2d_setup s;
  c2d_setup_defaults(&s);
  fixture_setup(&f, &s);
  s.material = mid;
  s.geometry = C2D_RZ;
  s.hg_coef = 1.0;
  s.bc[C2D_ILO].kind = C2D_BC_WALL;
  char msg[256];
  c2d_grid *gr = NULL;
  assert_int_equal(c2d_grid_create(&s, &gr, msg, sizeof msg), MS_OK);
  assert_int_equal(c2d_grid_run_to(gb, 0.1), MS_OK);
  assert_int_equal(c2d_grid_run_to(gr, 0.1), MS_OK);
  c2d_view a = c2d_grid_view(gb), b = c2d_grid_view(gr);
  assert_int_equal(c2d_grid_steps(gb), c2d_grid_steps(gr));
  size_t differ = 0;
  for (size_t n = 0; n < a.nnodes; ++n)
    differ += a.x[n] != b.x[n] || a.y[n] != b.y[n] || a.u[n] != b.u[n] || a.v[n] != b.v[n];
  for (size_t z = 0; z < a.nzones; ++z)
    differ += a.rho[z] != b.rho[z] || a.e[z] != b.e[z] || a.p[z] != b.p[z] ||
              a.material[z] != b.material[z];
  printf("flyer as blocks vs zone by zone: %ld steps, %zu values differ; axis p at depth 0.25: "
         "%.6f GPa\n",
         c2d_grid_steps(gb), differ, a.p[ni * 12]);
  assert_int_equal(differ, 0);
  c2d_grid_destroy(&gr);
  fixture_free(&f);
  free(mid);
  eos_destroy(&al);
  eos_destroy(&gas);
  c2d_deck_close(&l);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_tiling), cmocka_unit_test(test_sphere_rz),
      cmocka_unit_test(test_block_errors), cmocka_unit_test(test_regions_on_blocks),
      cmocka_unit_test(test_flyer_blocks)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
