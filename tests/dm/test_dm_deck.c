/* SPDX-License-Identifier: MIT */
/* The `discrete_model` deck section: every error located and collected, run-time refusals
 * (unstable time step, singular shape matrices) as input errors, a small deck that runs. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <dirent.h>
#include <unistd.h>

#include "dm_test.h"
#include "test_util.h"

static const char *materials =
    "problem: discrete_model\n"
    "materials:\n"
    "  - name: steel\n"
    "    eos: {type: linear_elastic, rho0: 7.85, bulk_modulus: 66.666666666666667}\n"
    "    shear_modulus: 100.0\n";

/* The steel head + a discrete_model section, read, with the unused-key report. */
static void load(dm_test_problem *L, const char *section) {
  char text[4096];
  snprintf(text, sizeof text, "%s%s", materials, section);
  dm_test_problem_read(L, text);
  dk_report_unused(&L->e, L->doc);
}

/* Six independent mistakes: all reported in one pass, each with FILE:LINE:COL. */
static void test_errors_collected(void **state) {
  (void)state;
  dm_test_problem L;
  load(&L, "discrete_model:\n"
           "  dimension: 2\n"
           "  spacing: 0.3\n"
           "  domain: {lo: [0, 0], hi: [1.0, 0.9]}\n"     /* 1.0 is not a multiple of 0.3 */
           "  boundaries: {x_lo: periodic, x_hi: wall}\n" /* periodic on one face only */
           "  layers:\n"
           "    - {material: stel}\n" /* unknown material */
           "  initial: {profile: rod_triangle, amplitude: 0.001, length: 1}\n" /* 1D profile */
           "  integrator: leapfrog\n"                                          /* unknown scheme */
           "  t_end: 1.0\n"
           "  horizon: 0.5\n"); /* below 1 spacing */
  assert_null(L.p);
  dk_errors_print(&L.e, stderr);
  assert_true(L.e.n >= 6);
  assert_true(has_error(&L.e, "deck.yaml:9:"));
  assert_true(has_error(&L.e, "whole number of spacings"));
  assert_true(has_error(&L.e, "periodic on one face"));
  assert_true(has_error(&L.e, "stel"));
  assert_true(has_error(&L.e, "1D (rod) problem"));
  assert_true(has_error(&L.e, "leapfrog"));
  dm_test_problem_free(&L);
}

static ms_status run(dm_test_problem *L) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.verbosity = MS_LOG_ERROR;
  ms_status st = dm_problem_run(&ctx, L->p);
  ms_ctx_close(&ctx);
  return st;
}

/* A time step beyond the scheme's stability limit is refused before any step is taken. */
static void test_unstable_dt_refused(void **state) {
  (void)state;
  dm_test_problem L;
  load(&L, "discrete_model:\n"
           "  spacing: 0.05\n"
           "  domain: {lo: [0], hi: [2]}\n"
           "  boundaries: {x_lo: wall, x_hi: wall}\n"
           "  layers: [{material: steel}]\n"
           "  initial: {profile: rod_sine, amplitude: 0.001, length: 1}\n"
           "  integrator: sia4\n"
           "  courant: 1.8\n" /* SIA4's limit is ω dt < 1.573, i.e. courant < 1.57 here */
           "  t_end: 1.0\n");
  assert_non_null(L.p);
  assert_int_equal(run(&L), MS_ERR_INPUT);
  dm_test_problem_free(&L);
}

/* One layer of particles in a 3D model: every A_i is singular -> input error, no run. */
static void test_singular_geometry_refused(void **state) {
  (void)state;
  dm_test_problem L;
  load(&L, "discrete_model:\n"
           "  dimension: 3\n"
           "  spacing: 0.1\n"
           "  domain: {lo: [0, 0, 0], hi: [1, 1, 0.1]}\n"
           "  layers: [{material: steel}]\n"
           "  steps: 1\n");
  assert_non_null(L.p);
  assert_int_equal(run(&L), MS_ERR_INPUT);
  dm_test_problem_free(&L);
}

/* A small rod with every scheme runs and keeps the sine mode's energy (< 1e-3 relative:
 * courant 0.5, 40 particles), and the summary says what ran. */
static void test_small_runs(void **state) {
  (void)state;
  for (int k = 0; k < RKN_KIND_COUNT; ++k) {
    char sec[1024];
    snprintf(sec, sizeof sec,
             "discrete_model:\n"
             "  spacing: 0.05\n"
             "  domain: {lo: [0], hi: [2]}\n"
             "  boundaries: {x_lo: wall, x_hi: fixed}\n"
             "  layers: [{material: steel}]\n"
             "  initial: {profile: rod_sine, amplitude: 0.001, length: 1}\n"
             "  integrator: %s\n"
             "  t_end: 1.0\n"
             "  output: {probes: [0.5], energy_every: 10}\n",
             rkn_scheme_names[k]);
    dm_test_problem L;
    load(&L, sec);
    dk_errors_print(&L.e, stderr);
    assert_int_equal(L.e.n, 0);
    assert_int_equal(run(&L), MS_OK);
    const dm_run_summary *s = dm_problem_summary(L.p);
    assert_int_equal(s->real_particles, 40);
    assert_true(s->particles > 40);
    assert_true(fabs(s->t_end - 1.0) < 1e-12);
    assert_true(s->energy_err_max < 1e-3);
    dm_test_problem_free(&L);
  }
}


/* response: eos / yield mistakes, each located: a yield model on an ideal gas (no G either), a
 * negative and a missing yield stress, response eos on a layer without a material's eos. */
static void test_finite_errors(void **state) {
  (void)state;
  static const char *deck =
      "problem: discrete_model\n"
      "materials:\n"
      "  - name: al\n"
      "    eos: {type: mg_linear, rho0: 2.703, c0: 5.35, s: 1.34, gamma0: 2.0}\n"
      "    shear_modulus: 27.6\n"
      "  - name: gas\n"
      "    eos: {type: ideal_gas, gamma: 1.4, rho0: 1.225e-3}\n"
      "discrete_model:\n"
      "  spacing: 0.1\n"
      "  domain: {lo: [0], hi: [3.0]}\n"
      "  layers:\n"
      "    - {material: al, x_max: 1, response: eos, yield: elastic_plastic, yield_stress: -0.1}\n"
      "    - {material: gas, x_max: 2, response: eos, yield: elastic_plastic}\n"
      "    - {rho: 1, bulk_modulus: 1, response: eos}\n"
      "  t_end: 1.0\n";
  dm_test_problem L;
  dm_test_problem_read(&L, deck);
  dk_errors_print(&L.e, stderr);
  assert_null(L.p);
  assert_true(has_error(&L.e, "deck.yaml:12:"));     /* negative yield stress */
  assert_true(has_error(&L.e, "ideal gas"));         /* line 13 */
  assert_true(has_error(&L.e, "shear_modulus > 0")); /* the gas has no G */
  assert_true(has_error(&L.e, "needs 'yield_stress'"));
  assert_true(has_error(&L.e, "deck.yaml:14:"));
  assert_true(has_error(&L.e, "needs a material with an 'eos:'"));
  dm_test_problem_free(&L);
}

/* The flyer problem's per-layer 'velocity': a number in km/s within ±1000, only with
 * response: eos, not together with random_velocity; each error located. */
static void test_flyer_errors(void **state) {
  (void)state;
  static const char *eos_deck =
      "problem: discrete_model\n"
      "materials:\n"
      "  - name: al\n"
      "    eos: {type: mg_linear, rho0: 2.703, c0: 5.35, s: 1.34, gamma0: 2.0}\n"
      "discrete_model:\n"
      "  spacing: 0.1\n"
      "  domain: {lo: [0], hi: [3.0]}\n"
      "  layers:\n"
      "    - {material: al, x_max: 1, response: eos, velocity: 5000}\n"
      "    - {material: al, x_max: 2, response: eos, velocity: fast}\n"
      "    - {material: al, response: eos, velocity: 1.0}\n"
      "  initial: {profile: random_velocity, amplitude: 0.1}\n"
      "  t_end: 1.0\n";
  dm_test_problem L;
  dm_test_problem_read(&L, eos_deck);
  dk_errors_print(&L.e, stderr);
  assert_null(L.p);
  assert_true(has_error(&L.e, "deck.yaml:9:"));  /* 5000 km/s: out of range */
  assert_true(has_error(&L.e, "deck.yaml:10:")); /* not a number */
  assert_true(has_error(&L.e, "exclude each other"));
  dm_test_problem_free(&L);
  /* the linear model has no per-body velocity */
  load(&L, "discrete_model:\n"
           "  spacing: 0.1\n"
           "  domain: {lo: [0], hi: [3.0]}\n"
           "  layers:\n"
           "    - {material: steel, velocity: 1.0}\n"
           "  t_end: 1.0\n");
  dk_errors_print(&L.e, stderr);
  assert_null(L.p);
  assert_true(has_error(&L.e, "deck.yaml:10:"));
  assert_true(has_error(&L.e, "'velocity' (a body's initial velocity) needs response: eos"));
  dm_test_problem_free(&L);
}

/* The fracture keys of a layer (docs/input-dm.md): a failure model needs spall_strength > 0,
 * and response: eos; each error located. */
static void test_fracture_errors(void **state) {
  (void)state;
  static const char *deck =
      "problem: discrete_model\n"
      "materials:\n"
      "  - name: al\n"
      "    eos: {type: mg_linear, rho0: 2.703, c0: 5.35, s: 1.34, gamma0: 2.0}\n"
      "discrete_model:\n"
      "  spacing: 0.1\n"
      "  domain: {lo: [0], hi: [4.0]}\n"
      "  layers:\n"
      "    - {material: al, x_max: 1, response: eos, fracture: {model: mean_stress}}\n"
      "    - {material: al, x_max: 2, response: eos, fracture: {spall_strength: -1.2}}\n"
      "    - {material: al, x_max: 3, response: eos, fracture: {spall_strength: 0}}\n"
      "    - {material: al, fracture: {spall_strength: 1.2}}\n"
      "  t_end: 1.0\n";
  dm_test_problem L;
  dm_test_problem_read(&L, deck);
  dk_errors_print(&L.e, stderr);
  assert_null(L.p);
  assert_true(has_error(&L.e, "deck.yaml:9:")); /* no spall_strength */
  assert_true(has_error(&L.e, "needs 'spall_strength'"));
  assert_true(has_error(&L.e, "deck.yaml:10:")); /* σ_s < 0 */
  assert_true(has_error(&L.e, "deck.yaml:11:")); /* σ_s = 0 */
  assert_true(has_error(&L.e, "deck.yaml:12:")); /* the linear model */
  assert_true(has_error(&L.e, "'fracture' needs response: eos"));
  dm_test_problem_free(&L);
}

/* A piston far beyond what the time step resolves (courant 20) inverts a family: the run stops
 * with MS_ERR_UNSTABLE naming the particle, not with NaN. */
static void test_finite_degenerate_stops(void **state) {
  (void)state;
  static const char *deck =
      "problem: discrete_model\n"
      "materials:\n"
      "  - name: al\n"
      "    eos: {type: mg_linear, rho0: 2.703, c0: 5.35, s: 1.34, gamma0: 2.0}\n"
      "discrete_model:\n"
      "  spacing: 0.1\n"
      "  domain: {lo: [0], hi: [3.0]}\n"
      "  layers:\n"
      "    - {material: al, response: eos}\n"
      "  piston: {velocity: 5.0}\n"
      "  courant: 20\n"
      "  t_end: 0.5\n";
  dm_test_problem L;
  dm_test_problem_read(&L, deck);
  assert_non_null(L.p);
  assert_int_equal(run(&L), MS_ERR_UNSTABLE);
  dm_test_problem_free(&L);
}


/* A snapshot (written through ptl_write_snapshot, docs/input-dm.md) holds exactly the layout
 * every particle problem shares (docs/output.md, "Particle snapshots": x, v, mass, material,
 * vertex) and the DM's own datasets, one row per real particle, with particles/x = X + w and
 * particles/v = u to the bit and the attributes time and step; its sidecar names the file and
 * the vertex dataset, and the time series particles.xmf lists it. */
static void test_snapshot_layout(void **state) {
  (void)state;
  dm_test_problem L;
  load(&L, "discrete_model:\n"
           "  spacing: 0.05\n"
           "  domain: {lo: [0], hi: [1]}\n"
           "  boundaries: {x_lo: wall, x_hi: free}\n"
           "  layers: [{material: steel}]\n"
           "  initial: {profile: rod_sine, amplitude: 0.001, length: 1}\n"
           "  steps: 4\n"
           "  dt: 0.002\n"
           "  output: {snapshot_times: [0.004]}\n");
  dk_errors_print(&L.e, stderr);
  assert_int_equal(L.e.n, 0);
  char dir[] = "/tmp/dm_snap_test_XXXXXX";
  assert_non_null(mkdtemp(dir));
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.quiet = true;
  assert_int_equal(ms_outdir_create(&ctx, dir, true), MS_OK);
  assert_int_equal(dm_problem_run(&ctx, L.p), MS_OK);
  ms_ctx_close(&ctx);
  char path[512];
  snprintf(path, sizeof path, "%s/particles_0000.h5", dir);
  ms_h5r *h = ms_h5_open_read(path, &L.e);
  assert_non_null(h);
  ms_h5_entry *items = NULL;
  size_t nitems = 0;
  assert_int_equal(ms_h5_list(h, "particles", &items, &nitems, &L.e), MS_OK);
  static const char *const want[] = {"X",        "cauchy",    "mass",  "material",
                                     "pressure", "sigma_xx",  "speed", "v",
                                     "vertex",   "von_mises", "w",     "x"};
  static const size_t cols[] = {3, 9, 1, 1, 1, 1, 1, 3, 1, 1, 3, 3};
  assert_int_equal(nitems, sizeof want / sizeof want[0]);
  for (size_t k = 0; k < nitems; k++) {
    assert_string_equal(items[k].name, want[k]);
    assert_int_equal(items[k].rows, 20); /* the real particles: 1 / 0.05 */
    assert_int_equal(items[k].cols, cols[k]);
  }
  ms_h5_entries_free(items, nitems);
  double *x = NULL, *X = NULL, *w = NULL, *v = NULL, *speed = NULL, t = 0, step = 0;
  size_t n0 = 0, n1 = 0;
  assert_int_equal(ms_h5_read_doubles(h, "particles/v", &v, &n0, &n1, &L.e), MS_OK);
  assert_int_equal(ms_h5_read_doubles(h, "particles/speed", &speed, &n0, &n1, &L.e), MS_OK);
  for (size_t i = 0; i < n0; i++) /* |u| from the same u: the speed of v, to the bit */
    assert_true(speed[i] == sqrt(v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] +
                                 v[3 * i + 2] * v[3 * i + 2]));
  assert_int_equal(ms_h5_read_doubles(h, "particles/x", &x, &n0, &n1, &L.e), MS_OK);
  assert_int_equal(ms_h5_read_doubles(h, "particles/X", &X, &n0, &n1, &L.e), MS_OK);
  assert_int_equal(ms_h5_read_doubles(h, "particles/w", &w, &n0, &n1, &L.e), MS_OK);
  for (size_t i = 0; i < 3 * n0; i++) assert_true(x[i] == X[i] + w[i]);
  double wmax = 0;
  for (size_t i = 0; i < n0; i++) wmax = fmax(wmax, fabs(w[3 * i]));
  assert_true(wmax > 0); /* the displaced rod, not a zero field */
  assert_int_equal(ms_h5_read_attr_double(h, "particles", "time", &t, &L.e), MS_OK);
  assert_int_equal(ms_h5_read_attr_double(h, "particles", "step", &step, &L.e), MS_OK);
  /* step 2 of dt = 0.002 (10 us), written in us: 10 x 2 x 0.002 (two roundings only) */
  assert_true(fabs(t - 0.04) < 1e-15);
  assert_true(step == 2.0);
  char *names = NULL; /* the material table: the one layer's material */
  assert_int_equal(ms_h5_read_attr_string(h, "particles", "material_names", &names, &L.e), MS_OK);
  assert_string_equal(names, "steel");
  free(names);
  ms_h5_close_read(h);
  free(x), free(X), free(w), free(v), free(speed);
  snprintf(path, sizeof path, "%s/particles_0000.xmf", dir);
  FILE *f = fopen(path, "r");
  assert_non_null(f);
  char xmf[8192];
  size_t len = fread(xmf, 1, sizeof xmf - 1, f);
  fclose(f);
  xmf[len] = 0;
  assert_non_null(strstr(xmf, "particles_0000.h5:particles/x"));
  assert_non_null(strstr(xmf, "particles_0000.h5:particles/v"));
  assert_non_null(strstr(xmf, "particles_0000.h5:particles/vertex"));
  snprintf(path, sizeof path, "%s/particles.xmf", dir);
  f = fopen(path, "r");
  assert_non_null(f);
  len = fread(xmf, 1, sizeof xmf - 1, f);
  fclose(f);
  xmf[len] = 0;
  assert_non_null(strstr(xmf, "href=\"particles_0000.xmf\""));
  DIR *d = opendir(dir);
  assert_non_null(d);
  for (struct dirent *de; (de = readdir(d));)
    if (de->d_name[0] != '.') {
      snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
      unlink(path);
    }
  closedir(d);
  rmdir(dir);
  dm_test_problem_free(&L);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_errors_collected),
      cmocka_unit_test(test_finite_errors),
      cmocka_unit_test(test_flyer_errors),
      cmocka_unit_test(test_fracture_errors),
      cmocka_unit_test(test_finite_degenerate_stops),
      cmocka_unit_test(test_unstable_dt_refused),
      cmocka_unit_test(test_singular_geometry_refused),
      cmocka_unit_test(test_small_runs),
      cmocka_unit_test(test_snapshot_layout),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
