/* SPDX-License-Identifier: MIT */
/* The `cluster_dynamics` deck section (docs/input-cd.md): a good deck reads and runs; bad input
 * gives clear deck errors with FILE:LINE:COL — overlapping regions of different materials,
 * fewer than 2 lattice periods across a periodic dimension, R_c not above the nearest-neighbour
 * distance, a piston history with a jump in time, a region outside the box, a first step beyond
 * 0.5 r0. A polycrystal region with a profiled face fills the profile; a polycrystalline sphere
 * keeps its velocity across the relaxation. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <dirent.h>
#include <cmocka.h>

#include "cd.h"

static const char *mats = "materials:\n"
                          "  - name: al\n"
                          "    eos: {type: mg_cold, rho0: 2.71, c0: 5.35, n: 4.0, gamma0: 2.0}\n"
                          "  - name: pb\n"
                          "    eos: {type: mg_cold, rho0: 11.34, c0: 1.972, n: 3.0, gamma0: 2.0}\n";

/* a small piston problem; a = sqrt(2)*5e-4 = 7.0710678118654752e-4, 4 periods across x and y */
#define GOOD_SECTION                                                                               \
  "cluster_dynamics:\n"                                                                            \
  "  r0: 5.0e-4\n"                                                                                 \
  "  cutoff: %s\n"                                                                                 \
  "  t_end: 2.0e-5\n"                                                                              \
  "  box: {lo: [0, 0, 0], hi: [%s, 2.8284271247461901e-3, 1.0e-2], boundary: [periodic, "          \
  "periodic, free]}\n"                                                                             \
  "  regions:\n"                                                                                   \
  "    - {material: al, lo: [0, 0, 0], hi: [1, 1, 1.4e-3], piston: true}\n"                        \
  "    - {material: %s, lo: [0, 0, %s], hi: [1, 1, 1.0e-2]}\n"                                     \
  "  piston: {direction: [0, 0, 1], %s}\n"                                                         \
  "  output: {every: 5, profile_bins: 20, snapshots: 1}\n"

static cd_problem *read_deck(const char *text, dk_errors *e, dk_doc **docp, eos_materials **mp) {
  dk_doc *doc = dk_load_string(text, "test.yaml", e);
  assert_non_null(doc);
  eos_materials *m = eos_materials_read(doc, e);
  assert_non_null(m);
  cd_problem *p = cd_problem_read(doc, dk_get(dk_root(doc), "cluster_dynamics"), m, e);
  *docp = doc;
  *mp = m;
  return p;
}

/* Frees what read_deck made (p may be NULL: a deck with errors). */
static void free_deck(cd_problem *p, eos_materials *m, dk_doc *doc, dk_errors *e) {
  cd_problem_destroy(&p);
  eos_materials_destroy(&m);
  dk_free(doc);
  dk_errors_free(e);
}

static char *deck(const char *rc, const char *lx, const char *mat2, const char *z2,
                  const char *piston) {
  char *buf = malloc(8192);
  int n = snprintf(buf, 8192, "%s", mats);
  snprintf(buf + n, 8192 - n, GOOD_SECTION, rc, lx, mat2, z2, piston);
  return buf;
}

static bool has_error(const dk_errors *e, const char *needle) {
  for (size_t k = 0; k < e->n; k++)
    if (strstr(e->msg[k], needle) && strstr(e->msg[k], "test.yaml:")) return true;
  return false;
}

/* Reads a deck that must have no errors and runs it into a fresh temporary directory `dir`
 * (a mkdtemp template, filled in). */
static cd_problem *run_deck(const char *text, char *dir, dk_errors *e, dk_doc **doc,
                            eos_materials **m) {
  cd_problem *p = read_deck(text, e, doc, m);
  dk_errors_print(e, stderr);
  assert_int_equal(e->n, 0);
  assert_non_null(p);
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.quiet = true;
  assert_non_null(mkdtemp(dir));
  assert_int_equal(ms_outdir_create(&ctx, dir, true), MS_OK);
  assert_int_equal(cd_problem_run(&ctx, p), MS_OK);
  ms_ctx_close(&ctx);
  return p;
}

/* Removes a run directory and every file in it (snapshot names carry the step number). */
static void remove_run_dir(const char *dir) {
  char path[512];
  DIR *d = opendir(dir);
  assert_non_null(d);
  for (struct dirent *de; (de = readdir(d));)
    if (de->d_name[0] != '.') {
      snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
      unlink(path);
    }
  closedir(d);
  rmdir(dir);
}

static void test_good_deck_runs(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc;
  eos_materials *m;
  char *text = deck("1.2", "2.8284271247461901e-3", "al", "1.4e-3", "velocity: 1.0");
  char dir[] = "/tmp/cd_deck_test_XXXXXX";
  cd_problem *p = run_deck(text, dir, &e, &doc, &m);
  char path[512];
  snprintf(path, sizeof path, "%s/cd_energy.csv", dir);
  FILE *f = fopen(path, "r");
  assert_non_null(f); /* the energy balance was written */
  fclose(f);
  snprintf(path, sizeof path, "%s/particles_0000.xmf", dir);
  assert_int_equal(access(path, R_OK), 0);
  remove_run_dir(dir);
  free_deck(p, m, doc, &e);
  free(text);
}

static void expect_error(const char *text, const char *needle) {
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc;
  eos_materials *m;
  cd_problem *p = read_deck(text, &e, &doc, &m);
  dk_errors_print(&e, stdout);
  assert_null(p);
  assert_true(has_error(&e, needle));
  free_deck(NULL, m, doc, &e);
}

static void test_bad_input(void **state) {
  (void)state;
  char *t;
  /* R_c at or below the nearest-neighbour distance */
  expect_error(t = deck("0.95", "2.8284271247461901e-3", "al", "1.4e-3", "velocity: 1.0"),
               "must exceed 1");
  free(t);
  /* one lattice period across periodic x */
  expect_error(t = deck("1.2", "7.0710678118654752e-4", "al", "1.4e-3", "velocity: 1.0"),
               "fewer than 2 lattice periods");
  free(t);
  /* overlapping regions of different materials (second region starts inside the first) */
  expect_error(t = deck("1.2", "2.8284271247461901e-3", "pb", "1.0e-3", "velocity: 1.0"),
               "must not overlap");
  free(t);
  /* piston history with a jump in time (t repeats) */
  char hist[] = "/tmp/cd_hist_XXXXXX";
  int fd = mkstemp(hist);
  assert_true(fd >= 0);
  FILE *f = fdopen(fd, "w");
  fprintf(f, "t,u\n0,0\n1e-5,1\n1e-5,2\n2e-5,2\n");
  fclose(f);
  char pist[256];
  snprintf(pist, sizeof pist, "history: %s", hist);
  expect_error(t = deck("1.2", "2.8284271247461901e-3", "al", "1.4e-3", pist),
               "rejected"); /* and the file:row "jump in time" message */
  free(t);
  unlink(hist);
  /* a relaxation stage without its time, and with a negative damping (the piston's flow map
   * closes and a `relax:` map follows) */
  expect_error(t = deck("1.2", "2.8284271247461901e-3", "al", "1.4e-3",
                        "velocity: 1.0}\n  relax: {damping: 5"),
               "time");
  free(t);
  expect_error(t = deck("1.2", "2.8284271247461901e-3", "al", "1.4e-3",
                        "velocity: 1.0}\n  relax: {time: 1e-4, damping: -1"),
               "damping");
  free(t);
}

/* A polycrystal region with a sine-profiled face (2D): the grains fill the profile up to its
 * crests and nothing lies above it. Box x periodic (40 r0 = one wavelength), y free; the sample
 * region y in [2 r0, 30 r0] with amplitude 5 r0. The sites of the initial snapshot are checked:
 * none above the face (tolerance 1e-9 r0: the filter compares exactly), crest sites within one
 * r0 of the crest (the lattice rows are √3/2 r0 apart, rotated grains at most r0), and the
 * count of sample sites against the region's volume: between 80 % and 100 % of the dense count
 * (the grain boundaries leave a few % porosity, min_distance 0.8). */
static void test_polycrystal_profiled(void **state) {
  (void)state;
  const double r0 = 1.0e-3, lx = 0.04, y0 = 2.0e-3, y1 = 0.03, amp = 5.0e-3;
  char *text = malloc(8192);
  int n = snprintf(text, 8192, "%s", mats);
  snprintf(text + n, 8192 - n,
           "cluster_dynamics:\n"
           "  dimension: 2\n"
           "  r0: %g\n"
           "  t_end: 1.0e-6\n"
           "  box: {lo: [0, 0], hi: [%g, 0.06], boundary: [periodic, free]}\n"
           "  regions:\n"
           "    - {material: pb, lo: [0, 0], hi: [1, %g], piston: true}\n"
           "    - material: pb\n"
           "      lo: [0, %g]\n"
           "      hi: [1, %g]\n"
           "      surface: {profile: sine, axis: 1, along: 0, amplitude: %g, wavelength: %g}\n"
           "      polycrystal: {grains: 12, seed: 3}\n"
           "  piston: {direction: [0, 1], velocity: 0.5}\n"
           "  output: {every: 5, snapshots: 1}\n",
           r0, lx, y0, y0, y1, amp, lx);
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc;
  eos_materials *m;
  char dir[] = "/tmp/cd_poly_test_XXXXXX";
  cd_problem *p = run_deck(text, dir, &e, &doc, &m);
  char path[512];
  snprintf(path, sizeof path, "%s/particles_0000.h5", dir);
  ms_h5r *h = ms_h5_open_read(path, &e);
  assert_non_null(h);
  double *x = NULL;
  size_t np = 0, nc = 0;
  assert_int_equal(ms_h5_read_doubles(h, "particles/x", &x, &np, &nc, &e), MS_OK);
  ms_h5_close_read(h);
  const double two_pi = 6.283185307179586;
  size_t nsample = 0;
  double crest_top = -INFINITY;
  for (size_t i = 0; i < np; i++) {
    const double xi = x[nc * i], yi = x[nc * i + 1];
    const double face = y1 + amp * sin(two_pi * xi / lx);
    assert_true(yi < face + 1e-9 * r0);
    if (yi >= y0) nsample++;
    if (fabs(xi - 0.25 * lx) < 2 * r0 && yi > crest_top) crest_top = yi;
  }
  const double dense =
      lx * (y1 - y0) / (0.5 * sqrt(3.0) * r0 * r0); /* sites of the dense lattice */
  printf("polycrystal with a sine face: %zu sample sites, %.3f of dense; crest site %.3f r0 below "
         "the crest\n",
         nsample, nsample / dense, (y1 + amp - crest_top) / r0);
  assert_true(crest_top > y1 + amp - r0);
  assert_true(nsample > 0.8 * dense && nsample < dense);
  free(x);
  remove_run_dir(dir);
  free_deck(p, m, doc, &e);
  free(text);
}

/* Bodies for impact decks (docs/input-cd.md "Regions"): a polycrystalline sphere moving at
 * 1 km/s above a plate at rest, relaxed first. In the initial snapshot (after the relaxation)
 * every sphere cluster moves at exactly the region's velocity and every plate cluster is at
 * rest (the relaxation runs at rest and gives the velocities back); the sphere's clusters lie
 * within its radius plus r0/2 (the relaxation moves them by a fraction of r0), and their count
 * is 75-100 % of the dense lattice's 4/3 π R³ / (r0³/√2) (grain-boundary porosity ~5-20 % at
 * min_distance 0.8, and the lattice's own cut of the sphere). */
static void test_bodies(void **state) {
  (void)state;
  const double r0 = 1.0e-3, R = 6.0e-3, c[3] = {0.015, 0.015, 0.01};
  char *text = malloc(8192);
  int n = snprintf(text, 8192, "%s", mats);
  snprintf(text + n, 8192 - n,
           "cluster_dynamics:\n"
           "  r0: %g\n"
           "  t_end: 1.0e-5\n"
           "  box: {lo: [0, 0, 0], hi: [0.03, 0.03, 0.03], boundary: [free, free, free]}\n"
           "  regions:\n"
           "    - {shape: sphere, material: al, center: [%g, %g, %g], radius: %g,\n"
           "       velocity: [0, 0, 1.0], polycrystal: {grains: 6, seed: 2}}\n"
           "    - {material: pb, lo: [0, 0, 0.02], hi: [0.03, 0.03, 0.025]}\n"
           "  relax: {time: 2.0e-4, box: false}\n"
           "  output: {every: 5, snapshots: 1}\n",
           r0, c[0], c[1], c[2], R);
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc;
  eos_materials *m;
  char dir[] = "/tmp/cd_bodies_test_XXXXXX";
  cd_problem *p = run_deck(text, dir, &e, &doc, &m);
  char path[512];
  snprintf(path, sizeof path, "%s/particles_0000.h5", dir);
  ms_h5r *h = ms_h5_open_read(path, &e);
  assert_non_null(h);
  double *x = NULL, *v = NULL;
  size_t np = 0, nc = 0, nv = 0, ncv = 0;
  assert_int_equal(ms_h5_read_doubles(h, "particles/x", &x, &np, &nc, &e), MS_OK);
  assert_int_equal(ms_h5_read_doubles(h, "particles/v", &v, &nv, &ncv, &e), MS_OK);
  ms_h5_close_read(h);
  assert_int_equal(np, nv);
  size_t nsphere = 0, nplate = 0;
  double rmax = 0;
  for (size_t i = 0; i < np; i++) {
    const double *xi = x + nc * i, *vi = v + ncv * i;
    if (xi[2] < 0.018) { /* the sphere */
      nsphere++;
      rmax = fmax(rmax, sqrt((xi[0] - c[0]) * (xi[0] - c[0]) + (xi[1] - c[1]) * (xi[1] - c[1]) +
                             (xi[2] - c[2]) * (xi[2] - c[2])));
      assert_true(vi[0] == 0.0 && vi[1] == 0.0 && vi[2] == 1.0);
    } else {
      nplate++;
      assert_true(vi[0] == 0.0 && vi[1] == 0.0 && vi[2] == 0.0);
    }
  }
  const double dense = 4.0 / 3.0 * M_PI * R * R * R / (r0 * r0 * r0 / sqrt(2.0));
  printf("polycrystal sphere: %zu clusters (%.3f of dense), farthest %.3f r0 from the centre; "
         "plate %zu\n",
         nsphere, nsphere / dense, rmax / r0, nplate);
  assert_true(nsphere > 0.75 * dense && nsphere < dense);
  assert_true(rmax < R + 0.5 * r0);
  assert_true(nplate > 0);
  free(x);
  free(v);
  remove_run_dir(dir);
  free_deck(p, m, doc, &e);
  free(text);
}

/* A dense block of ~1400 clusters and a few clusters 95 r0 away (a debris cloud's spread): the
 * link cells, capped at 2n + 64 over the particles' extent, are ~8 r0 wide and one row of them
 * holds more than the list build's 510 candidates; the build raises the cap (neighbour.c) and
 * the run goes on (without it: MS_ERR_UNSTABLE at the first build). */
static void test_spread_cells(void **state) {
  (void)state;
  char *text = malloc(8192);
  int n = snprintf(text, 8192, "%s", mats);
  snprintf(text + n, 8192 - n,
           "cluster_dynamics:\n"
           "  r0: 1.0e-3\n"
           "  t_end: 2.0e-5\n"
           "  box: {lo: [0, 0, 0], hi: [0.1, 0.1, 0.1], boundary: [free, free, free]}\n"
           "  regions:\n"
           "    - {material: al, lo: [0, 0, 0], hi: [0.01, 0.01, 0.01]}\n"
           "    - {shape: sphere, material: al, center: [0.0955, 0.0955, 0.0955], radius: "
           "1.5e-3}\n"
           "  output: {every: 5}\n");
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc;
  eos_materials *m;
  char dir[] = "/tmp/cd_spread_test_XXXXXX";
  cd_problem *p = run_deck(text, dir, &e, &doc, &m);
  remove_run_dir(dir);
  free_deck(p, m, doc, &e);
  free(text);
}

/* Bodies: a region outside the box, a first step beyond 0.5 r0, a polycrystal half-space. */
static void test_bodies_bad(void **state) {
  (void)state;
  static const char *const bad[][2] = {
      {"{shape: sphere, material: al, center: [0.1, 0.1, 0.1], radius: 0.005}",
       "holds no lattice site inside the box"},
      {"{shape: sphere, material: al, center: [0.015, 0.015, 0.015], radius: 0.005, "
       "velocity: [0, 0, 2.0e3]}",
       "moves a particle"},
      {"{shape: halfspace, material: al, axis: 2, below: 0.01, polycrystal: {grains: 4}}",
       "fills a box, sphere or cylinder"}};
  for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
    char *text = malloc(8192);
    int n = snprintf(text, 8192, "%s", mats);
    snprintf(text + n, 8192 - n,
             "cluster_dynamics:\n"
             "  r0: 1.0e-3\n"
             "  t_end: 1.0e-5\n"
             "  box: {lo: [0, 0, 0], hi: [0.03, 0.03, 0.03], boundary: [free, free, free]}\n"
             "  regions:\n"
             "    - %s\n",
             bad[k][0]);
    expect_error(text, bad[k][1]);
    free(text);
  }
}

/* every example deck inputs/cd-*.yaml reads without errors (they are documentation) */
static void test_example_decks(void **state) {
  (void)state;
  const char *src = getenv("MSCALE_SOURCE_DIR");
  static const char *const names[] = {
      "cd-piston-al.yaml",        "cd-piston-history.yaml",     "cd-dusting.yaml",
      "cd-grooves-2d.yaml",       "cd-heterogeneous.yaml",      "cd-poly-al.yaml",
      "cd-rz80-polycrystal.yaml", "cd-taylor-cu.yaml",          "cd-taylor-cu-coarse.yaml",
      "cd-piekutowski.yaml",      "cd-piekutowski-coarse.yaml", "cd-piekutowski-poly.yaml"};
  for (size_t k = 0; k < sizeof names / sizeof *names; k++) {
    char path[4096];
    snprintf(path, sizeof path, "%s/inputs/%s", src ? src : "../..", names[k]);
    dk_errors e;
    dk_errors_init(&e);
    dk_doc *doc = dk_load(path, &e);
    assert_non_null(doc);
    dk_read_units(doc, &e);
    eos_materials *m = eos_materials_read(doc, &e);
    const dk_node *root = dk_root(doc);
    dk_get(root, "problem");
    cd_problem *p = cd_problem_read(doc, dk_get(root, "cluster_dynamics"), m, &e);
    dk_report_unused(&e, doc);
    printf("%s: %zu errors\n", names[k], e.n);
    dk_errors_print(&e, stdout);
    assert_int_equal(e.n, 0);
    assert_non_null(p);
    free_deck(p, m, doc, &e);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_good_deck_runs),       cmocka_unit_test(test_bad_input),
      cmocka_unit_test(test_polycrystal_profiled), cmocka_unit_test(test_bodies),
      cmocka_unit_test(test_bodies_bad),           cmocka_unit_test(test_spread_cells),
      cmocka_unit_test(test_example_decks)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
