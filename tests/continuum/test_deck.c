/* SPDX-License-Identifier: MIT */
/* The `continuum:` deck section: bad input gives located deck errors (zero cells, overlapping
 * layers, non-monotone history file, CFL >= 1, unknown material), a good deck runs and writes
 * its outputs, and a run that breaks the time-step floor stops with MS_ERR_UNSTABLE, a message
 * naming step and time, and a final snapshot. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cmocka.h>

#include "cont.h"

static const char *materials =
    "materials:\n"
    "  - name: al\n"
    "    eos: {type: mg_linear, rho0: 2.703, c0: 5.35, s: 1.34, gamma0: 2.0}\n"
    "  - name: air\n"
    "    eos: {type: ideal_gas, gamma: 1.4}\n";

typedef struct parsed {
  dk_errors e;
  dk_doc *doc;
  eos_materials *mats;
  cont_problem *p;
} parsed;

static void parse(parsed *r, const char *section) {
  char text[4096];
  snprintf(text, sizeof text, "problem: continuum\n%s%s", materials, section);
  dk_errors_init(&r->e);
  r->doc = dk_load_string(text, "deck.yaml", &r->e);
  assert_non_null(r->doc);
  r->mats = eos_materials_read(r->doc, &r->e);
  assert_non_null(r->mats);
  r->p = cont_problem_read(r->doc, dk_get(dk_root(r->doc), "continuum"), r->mats, &r->e);
}

static void release(parsed *r) {
  cont_problem_destroy(&r->p);
  eos_materials_destroy(&r->mats);
  dk_free(r->doc);
  dk_errors_free(&r->e);
}

/* The error list holds a message containing `needle` located at deck.yaml:line. */
static bool has_error(const parsed *r, const char *needle, int line) {
  char loc[32];
  snprintf(loc, sizeof loc, "deck.yaml:%d:", line);
  for (size_t i = 0; i < r->e.n; ++i)
    if (strstr(r->e.msg[i], needle) && (line <= 0 || strstr(r->e.msg[i], loc))) return true;
  dk_errors_print(&r->e, stdout);
  return false;
}

/* Lines: 1 problem, 2-6 materials, so the section starts at line 7. */
static void test_zero_cells(void **state) {
  parsed r;
  parse(&r, "continuum:\n"                                     /* 7 */
            "  layers:\n"                                      /* 8 */
            "    - {material: al, thickness: 1.0, cells: 0}\n" /* 9 */
            "  time: {end: 1.0}\n");
  assert_null(r.p);
  assert_true(has_error(&r, "cells", 9));
  release(&r);
}

static void test_overlapping_layers(void **state) {
  parsed r;
  parse(&r, "continuum:\n"
            "  layers:\n"
            "    - {material: al, from: 0.0, to: 1.0, cells: 10}\n"
            "    - {material: al, from: 0.5, to: 2.0, cells: 10}\n" /* 10 */
            "  time: {end: 1.0}\n");
  assert_null(r.p);
  assert_true(has_error(&r, "overlaps", 10));
  release(&r);
}

static void test_cfl_not_below_one(void **state) {
  parsed r;
  parse(&r, "continuum:\n"
            "  layers:\n"
            "    - {material: al, thickness: 1.0, cells: 10}\n"
            "  time: {end: 1.0, cfl: 1.0}\n"); /* 10 */
  assert_null(r.p);
  assert_true(has_error(&r, "cfl", 10));
  release(&r);
}

static void test_unknown_material(void **state) {
  parsed r;
  parse(&r, "continuum:\n"
            "  layers:\n"
            "    - {material: copper, thickness: 1.0, cells: 10}\n" /* 9 */
            "  time: {end: 1.0}\n");
  assert_null(r.p);
  assert_true(has_error(&r, "copper", 9));
  release(&r);
}

static void test_history_not_monotone(void **state) {
  char path[] = "/tmp/cont_test_hist_XXXXXX";
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  const char *csv = "t,u\n0.0,0.0\n0.1,1.0\n0.05,1.0\n";
  assert_true(write(fd, csv, strlen(csv)) == (ssize_t)strlen(csv));
  close(fd);
  char section[1024];
  snprintf(section, sizeof section,
           "continuum:\n"
           "  layers:\n"
           "    - {material: al, thickness: 1.0, cells: 10}\n"
           "  left: {type: piston, file: %s}\n" /* 10 */
           "  time: {end: 1.0}\n",
           path);
  parsed r;
  parse(&r, section);
  assert_null(r.p);
  assert_true(has_error(&r, "not monotone", 10));
  release(&r);
  /* the same check for an inline table */
  parse(&r, "continuum:\n"
            "  layers:\n"
            "    - {material: al, thickness: 1.0, cells: 10}\n"
            "  right: {type: pressure, table: [[0, 1], [0.2, 2], [0.2, 3]]}\n"
            "  time: {end: 1.0}\n");
  assert_null(r.p);
  assert_true(has_error(&r, "does not increase", 10));
  release(&r);
  unlink(path);
}

/* All errors are collected, not just the first. */
static void test_errors_collected(void **state) {
  parsed r;
  parse(&r, "continuum:\n"
            "  layers:\n"
            "    - {material: al, thickness: 1.0, cells: 0}\n"
            "    - {material: tin, thickness: 1.0, cells: 10}\n"
            "  time: {end: 1.0, cfl: 1.5}\n");
  assert_null(r.p);
  assert_true(has_error(&r, "cells", 9));
  assert_true(has_error(&r, "tin", 10));
  assert_true(has_error(&r, "cfl", 11));
  release(&r);
}

static char *make_outdir(ms_ctx *ctx) {
  char *dir = ms_strdup("/tmp/cont_test_out_XXXXXX");
  assert_non_null(mkdtemp(dir));
  ms_ctx_init_serial(ctx);
  ctx->quiet = true;
  ctx->verbosity = MS_LOG_WARN;
  free(ctx->outdir);
  ctx->outdir = ms_strdup(dir);
  return dir;
}

static bool out_exists(const char *dir, const char *name) {
  char p[512];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  struct stat st;
  return stat(p, &st) == 0 && st.st_size > 0;
}

static void remove_dir(const char *dir) {
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  assert_int_equal(system(cmd), 0);
}

static void test_good_deck_runs(void **state) {
  parsed r;
  parse(&r, "continuum:\n"
            "  geometry: planar\n"
            "  layers:\n"
            "    - {name: flyer, material: al, thickness: 0.1, cells: 20, velocity: 1.0}\n"
            "    - {name: target, material: al, thickness: 0.2, cell_size: 0.005,\n"
            "       grading: {ratio: 1.05, toward: right}}\n"
            "    - {name: gas, material: air, thickness: 0.5, cells: 20, pressure: 1.0e-4,\n"
            "       density: 1.2e-3}\n"
            "  left: {type: free}\n"
            "  right: {type: pressure, pulse: {shape: trapezoid, amplitude: 1e-4, hold: 1.0}}\n"
            "  viscosity: {quadratic: 1.0, linear: 0.2}\n"
            "  time: {end: 0.02, cfl: 0.5}\n"
            "  output: {times: [0.0, 0.01], xt_frames: 10}\n"
            "  tags:\n"
            "    - {name: surface, layer: target, side: right}\n"
            "    - {name: mid, x: 0.2}\n");
  if (!r.p) dk_errors_print(&r.e, stdout);
  assert_non_null(r.p);
  cont_grid *g = cont_problem_grid(r.p);
  assert_int_equal(cont_grid_ncells(g), 20 + 40 + 20);
  assert_int_equal(cont_grid_ntags(g), 2);
  assert_int_equal(cont_grid_history(g, 0).node, 60);
  cont_view v = cont_grid_view(g);
  /* pressure → energy: p(ρ, e) = 1e-4 within the bisection's round-off */
  assert_true(fabs(v.p[70] - 1e-4) < 1e-12);
  /* graded towards the right end: cells shrink towards the contact with the gas */
  assert_true(v.x[60] - v.x[59] < v.x[21] - v.x[20]);
  ms_ctx ctx;
  char *dir = make_outdir(&ctx);
  assert_int_equal(cont_problem_run(&ctx, r.p), MS_OK);
  const char *files[] = {"profile_0000.h5", "profile_0000.xmf",  "profile_0000.csv",
                         "profile_0001.h5", "profile_final.csv", "history_surface.csv",
                         "history_mid.csv", "history.h5",        "xt.h5"};
  for (size_t k = 0; k < sizeof files / sizeof files[0]; ++k) {
    if (!out_exists(dir, files[k])) printf("missing %s\n", files[k]);
    assert_true(out_exists(dir, files[k]));
  }
  assert_true(fabs(cont_grid_time(g) - 0.02) < 1e-15);
  remove_dir(dir);
  free(dir);
  ms_ctx_close(&ctx);
  release(&r);
}

static void test_unstable_run_stops(void **state) {
  parsed r;
  parse(&r, "continuum:\n"
            "  layers:\n"
            "    - {material: al, thickness: 0.1, cells: 10, velocity: 1.0}\n"
            "  left: {type: wall}\n"
            "  time: {end: 1.0, dt_min: 1.0}\n");
  assert_non_null(r.p);
  ms_ctx ctx;
  char *dir = make_outdir(&ctx);
  assert_int_equal(cont_problem_run(&ctx, r.p), MS_ERR_UNSTABLE);
  const char *msg = cont_grid_error(cont_problem_grid(r.p));
  assert_non_null(strstr(msg, "step 1"));
  assert_non_null(strstr(msg, "t = 0"));
  assert_non_null(strstr(msg, "dt_min"));
  assert_true(out_exists(dir, "profile_unstable.h5"));
  assert_true(out_exists(dir, "profile_unstable.csv"));
  remove_dir(dir);
  free(dir);
  ms_ctx_close(&ctx);
  release(&r);
}

/* A deck in SI units (`units: si`) gives the same grid as its internal-unit twin: lengths m →
 * cm, velocities m/s → km/s, times s → 10 µs, pressures Pa → GPa, history tables converted
 * column by column. */
static void test_si_units(void **state) {
  const char *text =
      "units: si\n"
      "problem: continuum\n"
      "materials:\n"
      "  - name: al\n"
      "    eos: {type: mg_linear, rho0: 2703, c0: 5350, s: 1.34, gamma0: 2.0}\n"
      "continuum:\n"
      "  layers:\n"
      "    - {material: al, thickness: 0.002, cells: 20, velocity: 500, pressure: 1.0e9}\n"
      "  left: {type: piston, table: [[0, 0], [1.0e-6, 1000]]}\n"
      "  right: {type: pressure, value: 1.0e9}\n"
      "  time: {end: 2.0e-6, dt_max: 1.0e-8}\n"
      "  output: {times: [1.0e-6]}\n";
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string(text, "si.yaml", &e);
  assert_non_null(doc);
  dk_read_units(doc, &e);
  eos_materials *mats = eos_materials_read(doc, &e);
  cont_problem *p = cont_problem_read(doc, dk_get(dk_root(doc), "continuum"), mats, &e);
  if (!p) dk_errors_print(&e, stdout);
  assert_non_null(p);
  cont_grid *g = cont_problem_grid(p);
  cont_view v = cont_grid_view(g);
  /* exact decimal conversions up to one rounding each */
  assert_true(fabs(v.x[v.ncells] - 0.2) < 1e-15);
  assert_true(fabs(v.u[10] - 0.5) < 1e-15);
  assert_true(fabs(v.rho[0] - 2.703) < 1e-12);
  assert_true(fabs(v.p[5] - 1.0) < 1e-9); /* 1 GPa from the pressure → energy solve */
  /* the piston table: 1000 m/s at 1 µs = 1 km/s at t = 0.1 (internal); half-way 0.5 */
  assert_int_equal(cont_grid_run_to(g, 0.05), MS_OK);
  assert_true(fabs(v.u[0] - 0.5) < 1e-12);
  cont_problem_destroy(&p);
  eos_materials_destroy(&mats);
  dk_free(doc);
  dk_errors_free(&e);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_zero_cells),
                                     cmocka_unit_test(test_overlapping_layers),
                                     cmocka_unit_test(test_cfl_not_below_one),
                                     cmocka_unit_test(test_unknown_material),
                                     cmocka_unit_test(test_history_not_monotone),
                                     cmocka_unit_test(test_errors_collected),
                                     cmocka_unit_test(test_good_deck_runs),
                                     cmocka_unit_test(test_unstable_run_stops),
                                     cmocka_unit_test(test_si_units)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
