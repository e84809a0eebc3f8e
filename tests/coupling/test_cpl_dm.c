/* SPDX-License-Identifier: MIT */
/* The coupled problem on the finite-deformation discrete model (particles.model:
 * discrete_model, particles/dm/dm_region.c), one-way drive, end to end:
 *  1. symmetric Al plate impact (2 km/s, u_p = 1 km/s, ~16 GPa): the grid's U(t) at a node
 *     0.03 cm below the free surface drives a flat 2D discrete-model slab (the grid's own Al
 *     EOS); the particles' free-surface plateau must match the grid's within 1 % (issue 21's
 *     drive check), with the velocity and with the transmitting piston; the particle energy
 *     balance closes to round-off; a flat surface ejects nothing;
 *  2. deck errors of the model's section, located, through the coupled reader;
 *  3. spall in the coupled run; 4. the default deck at CI size: the drive check and the spall
 *     plane against the grid alone; 5. sub-cycling. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
/* cmocka needs the headers above */
#include <cmocka.h>

#include "cont.h"
#include "cpl.h"
#include "cpl_test.h"

/* Al as the shipped decks give it (mg_linear 2.703, 5.35, 1.34, Γ0 2; docs/design.md §3) */
static const char *const DECK =
    "units: internal\n"
    "problem: coupled\n"
    "materials:\n"
    "  - name: al\n"
    "    eos: {type: mg_linear, rho0: 2.703, c0: 5.35, s: 1.34, gamma0: 2.0}\n"
    "  - name: air\n"
    "    eos: {type: ideal_gas, gamma: 1.4, rho0: 1.225e-3, p0: 1.01325e-4}\n"
    "    viscosity: 1.8e-9\n"
    "coupled:\n"
    "  grid:\n"
    "    layers:\n"
    "      - {name: flyer, material: al, thickness: 0.1, cells: 100, velocity: 2.0}\n"
    "      - {name: sample, material: al, thickness: 0.1, cells: 100, pressure: 1.01325e-4}\n"
    "      - {name: air, material: air, thickness: 0.5, cells: 100, density: 1.225e-3,"
    " pressure: 1.01325e-4}\n"
    "    left: {type: free}\n"
    "    right: {type: pressure, value: 1.01325e-4}\n"
    "    time: {end: 0.05}\n"
    "    tags:\n"
    "      - {name: drive, x: 0.17}\n"
    "      - {name: free_surface, layer: sample, side: right}\n"
    "  drive: {tag: drive, free_surface_tag: free_surface, mode: %s}\n"
    "  particles:\n"
    "    model: discrete_model\n"
    "    r0: 5.0e-4\n"
    "    width: 0.0025\n"
    "%s"
    "  time: {end: 0.04, outputs: 1%s}\n"
    "  fragments: {every: 10}\n"
    "  drag: {law: none}\n";

static const char *const RUN_FILES[] = {"spectrum.csv", "fragments.csv", "free_surface.csv",
                                        "particles_0001.h5", "history_drive.csv"};
#define RUN_NFILES (sizeof RUN_FILES / sizeof *RUN_FILES)

static char *deck(const char *mode, const char *keys, const char *time_keys) {
  static char buf[8192];
  snprintf(buf, sizeof buf, DECK, mode, keys, time_keys);
  return buf;
}

static cpl_run_summary run_flat(const char *mode) {
  cpl_test_run r;
  /* transmitting: Z = ρ0 c0, the strength-free model's longitudinal impedance (the default
   * √1.5 ρ0 c0 is cluster dynamics' lattice) */
  const bool tr = !strcmp(mode, "transmitting");
  char full[8192];
  snprintf(full, sizeof full, "%s", deck(mode, "    response: eos\n    yield: none\n", ""));
  if (tr) {
    char *d = strstr(full, "mode: transmitting}");
    assert_non_null(d);
    char tail[8192];
    snprintf(tail, sizeof tail, "%s", d + strlen("mode: transmitting}"));
    snprintf(d, sizeof full - (size_t)(d - full), "mode: transmitting, impedance: 14.461}%s", tail);
  }
  cpl_test_run_deck(&r, full, "test.yaml", RUN_FILES, RUN_NFILES);
  cpl_run_summary s = *cpl_problem_summary(r.p);
  printf("discrete model, symmetric Al impact, %s piston: %zu particles, %ld steps; free "
         "surface plateau %.5f (particles) vs %.5f (grid) km/s: %.3f %% over %zu samples; "
         "half-rise %.5g vs %.5g; smallest velocity after the window %.4g; energy balance %.3g "
         "of the piston work; %zu fragments\n",
         mode, s.particles, s.steps, s.check.plateau_particles, s.check.plateau_grid,
         100 * s.check.rel_diff, s.check.samples, s.check.t_half_particles, s.check.t_half_grid,
         s.check.min_after, s.energy_balance, s.fragments);
  cpl_test_run_free(&r);
  return s;
}

static void test_symmetric_flat(void **state) {
  (void)state;
  const char *modes[] = {"velocity", "transmitting"};
  for (int k = 0; k < 2; k++) {
    cpl_run_summary s = run_flat(modes[k]);
    assert_true(s.check.samples >= 5);
    /* issue 21's drive check: 1 %. The particles carry the grid's own EOS, so their Hugoniot
     * and release are the grid's; what is left is the two fronts' shapes (viscous in both) */
    assert_true(s.check.rel_diff < 0.01);
    /* symmetric impact: the free surface flies at the flyer's 2 km/s; the grid's artificial
     * viscosity and the EOS's release vs Hugoniot cost well under 1 % */
    assert_true(fabs(s.check.plateau_grid - 2.0) < 0.02);
    /* the same wave speed: the breakouts differ by the fronts' widths, a few cells and
     * spacings (0.001 and 0.0005 cm) against the 0.0045 transit time over 0.03 cm: 10 % of it */
    assert_true(fabs(s.check.t_half_particles - s.check.t_half_grid) < 0.1 * 0.03 / 6.69);
    /* dm_fin's kick–drift–kick update conserves K + U − W to round-off (no drag kicks here:
     * drag law none); 1e-10 is far above the rounding of ~1e4 steps, far below any missing term */
    assert_true(fabs(s.energy_balance) < 1e-10);
    assert_true(s.piston_work > 0);
    assert_int_equal(s.fragments, 1);
    assert_true(s.ejected_mass == 0);
  }
}

static void expect_error(const char *text, const char *where, const char *what) {
  cpl_test_run r;
  cpl_test_read(&r, text, "test.yaml");
  assert_null(r.p);
  bool found = false;
  for (size_t k = 0; k < r.e.n; k++)
    found |= strstr(r.e.msg[k], where) != NULL && strstr(r.e.msg[k], what) != NULL;
  if (!found) dk_errors_print(&r.e, stderr);
  assert_true(found);
  cpl_test_run_free(&r);
}

static void test_deck_errors(void **state) {
  (void)state;
  /* line 26: the particles section's first own key after model, r0, width */
  expect_error(deck("velocity", "    response: linear_elastic\n", ""), "test.yaml:26:15",
               "takes response: eos only");
  expect_error(deck("velocity", "    yield: elastic_plastic\n", ""), "test.yaml", "shear_modulus");
  /* the fracture map: a failure model without σ_s, σ_s ≤ 0 (line 26 as above) */
  expect_error(deck("velocity", "    fracture: {model: principal_stress}\n", ""), "test.yaml:26:15",
               "needs 'spall_strength'");
  expect_error(deck("velocity", "    fracture: {spall_strength: 0}\n", ""),
               "test.yaml:26:", "spall_strength");
}

/* The file at `rel` under MSCALE_SOURCE_DIR into text[cap] (NUL-terminated). */
static void read_source(const char *rel, char *text, size_t cap) {
  const char *src = getenv("MSCALE_SOURCE_DIR");
  assert_non_null(src);
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", src, rel);
  FILE *fp = fopen(path, "r");
  assert_non_null(fp);
  const size_t len = fread(text, 1, cap - 1, fp);
  fclose(fp);
  text[len] = 0;
}

/* In a run's fragments.csv: the outermost piece of at least 5 particles (its size, velocity)
 * and the velocity of the innermost one. */
typedef struct outer_inner {
  long count;
  double v_out, v_in;
} outer_inner;

static void read_fragments(const ms_ctx *ctx, void *user) {
  outer_inner *o = user;
  char *fr = ms_out_path(ctx, "fragments.csv");
  FILE *fp = fopen(fr, "r");
  assert_non_null(fp);
  char line[1024];
  double xmax = -INFINITY, xmin = INFINITY;
  o->count = 0, o->v_out = o->v_in = NAN;
  while (fgets(line, sizeof line, fp)) {
    long id, count;
    double mass, d, x, y, z, vx;
    if (sscanf(line, "%ld,%ld,%lf,%lf,%lf,%lf,%lf,%lf", &id, &count, &mass, &d, &x, &y, &z, &vx) !=
            8 ||
        count < 5)
      continue;
    if (x > xmax) xmax = x, o->count = count, o->v_out = vx; /* the outermost big piece */
    if (x < xmin) xmin = x, o->v_in = vx;
  }
  fclose(fp);
  free(fr);
}

/* Runs a read deck in a temporary directory (cpl_test_run_tmp_read) and reads its fragments. */
static void run_fragments(cpl_test_run *r, long *out_count, double *out_v, double *in_v) {
  outer_inner o;
  assert_int_equal(cpl_test_run_tmp_read(r, NULL, 0, read_fragments, &o), MS_OK);
  *out_count = o.count, *out_v = o.v_out, *in_v = o.v_in;
}

/* 3. Spall in the coupled run (tests/coupling/data/cpl_spall_dm.yaml: a 0.2 mm Al flyer at
 * 0.6 km/s, σ_s = 1.2 GPa): the slab breaks about a flyer thickness below the free surface and
 * the layer beyond is one fragment: the fragment holding every surface particle is a whole
 * number of layers (5 columns) between 20 and 60 of them (the spall plane at 0.01–0.03 cm:
 * a flyer thickness, 40 layers, give or take the failed zone's width, measured 15 layers),
 * moving at the free-surface velocity, away from the bulk; the energy balance with the broken
 * term closes. Without the fracture key the slab stays one fragment (its unbroken bonds). */
static void spall_fragments(bool fracture, size_t *nfrag, long *scab_count, double *scab_v,
                            double *bulk_v, double *balance) {
  static char text[16384];
  read_source("tests/coupling/data/cpl_spall_dm.yaml", text, sizeof text);
  if (!fracture) {
    char *k = strstr(text, "    fracture:");
    assert_non_null(k);
    memset(k, ' ', (size_t)(strchr(k, '\n') - k)); /* blank the line */
  }
  cpl_test_run r;
  cpl_test_read(&r, text, "spall.yaml");
  dk_errors_print(&r.e, stderr);
  assert_int_equal(r.e.n, 0);
  run_fragments(&r, scab_count, scab_v, bulk_v);
  const cpl_run_summary *sum = cpl_problem_summary(r.p);
  *nfrag = sum->fragments, *balance = sum->energy_balance;
  printf("coupled spall (fracture %s): %zu fragments; outermost piece %ld particles at %.4f km/s, "
         "bulk at %.4f km/s; energy balance %.2e of the piston work\n",
         fracture ? "on" : "off", *nfrag, *scab_count, *scab_v, *bulk_v, *balance);
  cpl_test_run_free(&r);
}

static void test_spall(void **state) {
  (void)state;
  size_t n;
  long count;
  double v, vb, bal;
  spall_fragments(true, &n, &count, &v, &vb, &bal);
  assert_true(n >= 2);
  assert_true(count % 5 == 0 && count >= 20 * 5 && count <= 60 * 5);
  /* the scab flies at about the free-surface velocity (2 u_p = 0.6 km/s less the pull-back),
   * the bulk left behind nearly at rest: 0.1 km/s separates them */
  assert_true(v > 0.45 && v - vb > 0.1);
  assert_true(fabs(bal) < 1e-10); /* K + U + broken − W: round-off */
  spall_fragments(false, &n, &count, &v, &vb, &bal);
  assert_int_equal(n, 1);
  assert_true(fabs(bal) < 1e-10);
}

/* 4. The default deck (inputs/default.yaml: a Pb flyer at 1.5 km/s on Pb, ~25 GPa; the grid's
 * Pb EOS, Steinberg–Guinan Pb strength, the tensile cut-off at σ_s), read from the source tree
 * and cut to CI size with the same physics: 5 columns instead of 60, a flat surface (the drive
 * check compares the plane free surface: grooves jet), the particle phase to just past the
 * spall, searches every 20 steps for the samples. Two checks: the drive check, and the spall
 * plane where the grid alone (no spall model) puts it. */
static void replace_once(char *text, size_t cap, const char *from, const char *to) {
  char *at = strstr(text, from);
  if (!at) fprintf(stderr, "inputs/default.yaml: '%s' not found\n", from);
  assert_non_null(at);
  if (!at) return; /* for the compiler: assert_non_null has stopped the test */
  static char tail[32768];
  snprintf(tail, sizeof tail, "%s", at + strlen(from));
  snprintf(at, cap - (size_t)(at - text), "%s%s", to, tail);
}

/* The 1D prediction of the spall plane, from the deck's own grid run alone (its layers are
 * welded and have no spall model, so the two release waves cross and the tension keeps
 * growing): the first time t_k each sample cell within `depth` of the free surface holds
 * p < −σ_s; the plane is where that tension starts inside the sample, the minimum of t_k over
 * depth — the crossing of the release from the free surface with the release from the flyer's
 * back (1D characteristics; the tension spreads both ways from there). The cells next to the
 * surface are skipped while t_k rises with depth: there the grid's viscous front overshoots
 * into tension at breakout (~0.03 us after it, within ~8 cells), a transient that starts at
 * the surface, not where the releases meet. Returns the depth (cm) of that cell's centre. */
static double grid_spall_depth(cpl_test_run *r, double sigma_s, double depth, double t_end,
                               double *t_spall) {
  dk_errors e;
  dk_errors_init(&e);
  const dk_node *G = dk_get(dk_get(dk_root(r->doc), "coupled"), "grid");
  cont_problem *cp = cont_problem_read(r->doc, G, r->mats, &e);
  assert_non_null(cp);
  assert_int_equal(e.n, 0);
  cont_grid *g = cont_problem_grid(cp);
  cont_view v = cont_grid_view(g);
  size_t top = 0; /* the sample's last cell (layer 1: flyer, sample, air) */
  for (size_t c = 0; c < v.ncells; c++)
    if (v.layer[c] == 1) top = c;
  const double x_fs = v.x[top + 1];
  size_t bot = top;
  while (bot > 0 && v.layer[bot - 1] == 1 && x_fs - 0.5 * (v.x[bot - 1] + v.x[bot]) < depth) bot--;
  const size_t n = top - bot + 1;
  double *t_first = malloc(n * sizeof *t_first), *d0 = malloc(n * sizeof *d0);
  assert_non_null(t_first);
  assert_non_null(d0);
  for (size_t k = 0; k < n; k++)
    t_first[k] = INFINITY, d0[k] = x_fs - 0.5 * (v.x[top - k] + v.x[top - k + 1]);
  while (cont_grid_time(g) < t_end) {
    assert_int_equal(cont_grid_step(g, t_end - cont_grid_time(g)), MS_OK);
    v = cont_grid_view(g);
    for (size_t k = 0; k < n; k++) /* k = 0 the surface cell, growing with depth */
      if (t_first[k] == INFINITY && v.p[top - k] < -sigma_s) t_first[k] = cont_grid_time(g);
  }
  size_t k0 = 0;
  while (k0 + 1 < n && t_first[k0 + 1] > t_first[k0]) k0++; /* the breakout transient */
  size_t kmin = k0 + 1 < n ? k0 + 1 : k0;
  for (size_t k = kmin; k < n; k++)
    if (t_first[k] < t_first[kmin]) kmin = k;
  *t_spall = t_first[kmin];
  const double d = d0[kmin];
  printf("grid alone: first p < -%.2f GPa inside the sample at %.4f cm below the free surface, "
         "t = %.5f (the breakout transient skipped: %zu cells)\n",
         sigma_s, d, *t_spall, k0 + 1);
  free(t_first);
  free(d0);
  cont_problem_destroy(&cp);
  dk_errors_free(&e);
  return d;
}

static void test_default_deck(void **state) {
  (void)state;
  static char text[32768];
  read_source("inputs/default.yaml", text, sizeof text);
  assert_non_null(strstr(text, "model: discrete_model"));
  assert_non_null(strstr(text, "fracture: {model: mean_stress"));
  /* the particle phase to 0.06: past the check window (breakout ≈ 0.025 + depth/c0 = 0.025)
   * and the spall (the grid's tension at ≈ 0.038), with ~0.01 for the scab to come off */
  const char *edits[][2] = {
      {"time: {end: 0.6,", "time: {end: 0.1,"},
      {"times: [0.02, 0.04, 0.1], xt_frames: 300", "times: [0.02], xt_frames: 20"},
      {"    width: 0.03 ", "    width: 0.0025 "},
      {"    surface: {profile: sine,", "    surface: {profile: flat}  # "},
      {"    end: 0.25 ", "    end: 0.06 "},
      {"    outputs: 6 ", "    outputs: 1 "},
      {"    every: 200 ", "    every: 20 "},
      {"    end: 2.5 ", "    end: 0.2 "},
      {"    windows: 100", "    windows: 10"},
  };
  for (size_t k = 0; k < sizeof edits / sizeof *edits; k++)
    replace_once(text, sizeof text, edits[k][0], edits[k][1]);
  cpl_test_run r;
  cpl_test_read(&r, text, "default.yaml");
  dk_errors_print(&r.e, stderr);
  assert_int_equal(r.e.n, 0);
  const dk_node *P = dk_get(dk_get(dk_root(r.doc), "coupled"), "particles");
  double sigma_s = NAN, h = NAN;
  assert_true(dk_read_double(&r.e, r.doc, dk_get(P, "fracture"), "spall_strength", MS_DIM_PRESSURE,
                             true, 0, 0, INFINITY, &sigma_s));
  assert_true(dk_read_double(&r.e, r.doc, P, "r0", MS_DIM_LENGTH, true, 0, 0, INFINITY, &h));
  long count;
  double v_scab, v_bulk;
  run_fragments(&r, &count, &v_scab, &v_bulk);
  const cpl_run_summary s = *cpl_problem_summary(r.p);
  const double depth = 100 * h; /* the region: 0.05 cm, 100 layers (the deck's drive tag) */
  double t_grid;
  const double d_grid = grid_spall_depth(&r, sigma_s, depth, 0.1, &t_grid);
  const double d_part = (double)count / 5.0 * h; /* the scab's layers (5 columns) */
  printf("default deck (Pb, discrete model, fracture, CI size): %zu particles, %ld steps; free "
         "surface plateau %.5f (particles) vs %.5f (grid) km/s: %.3f %% over %zu samples; "
         "half-rise %.5g vs %.5g; %zu fragments, the scab %ld particles (%.4f cm) at %.4f km/s, "
         "the innermost piece at %.4f km/s; spall plane %.4f cm (particles) vs %.4f cm (grid "
         "alone): %.1f spacings; energy balance %.3g of the piston work\n",
         s.particles, s.steps, s.check.plateau_particles, s.check.plateau_grid,
         100 * s.check.rel_diff, s.check.samples, s.check.t_half_particles, s.check.t_half_grid,
         s.fragments, count, d_part, v_scab, v_bulk, d_part, d_grid, (d_part - d_grid) / h,
         s.energy_balance);
  cpl_test_run_free(&r);
  /* the deck's design: the releases meet inside the region, clear of the driven layers and of
   * the surface (10 spacings each) */
  assert_true(isfinite(t_grid) && d_grid > 10 * h && d_grid < depth - 10 * h);
  assert_true(s.check.samples >= 5);
  /* issue 21's drive check: 1 % (cluster dynamics: 7.9 %, docs/particles-cd.md). The particles
   * carry the grid's own Pb EOS; Steinberg–Guinan's Y ≤ 0.1 GPa against ~25 GPa changes the
   * Hugoniot by well under 1 %; the spall comes after the window */
  assert_true(s.check.rel_diff < 0.01);
  /* symmetric Pb impact at 1.5 km/s: the free surface at about the flyer's velocity */
  assert_true(s.check.plateau_grid > 1.4 && s.check.plateau_grid < 1.6);
  /* a spall layer: the slab broke (more than one piece) and the outermost piece, a whole number
   * of layers, flies at the free-surface velocity (by t = 0.06 the pull-back has not reached it;
   * 5 % allows the ringing of the scab). Behind it the rest of the release fan fails into
   * single particles (multiple spall, docs/validation.md), so no second big piece is asserted */
  assert_true(s.fragments >= 2);
  assert_true(count % 5 == 0 && count >= 5 * 10);
  assert_true(fabs(v_scab / s.check.plateau_grid - 1) < 0.05);
  /* ... whose inner face lies where the grid's releases cross: within 4 spacings — the grid's
   * 10 um cell (2 spacings) brackets its plane to ±1 spacing, and the failed zone around the
   * particles' first failures is a few layers wide before the scab's face is clean */
  assert_true(fabs(d_part - d_grid) <= 4 * h);
}

/* 5. Sub-cycling (dm_region.c region_step): the symmetric Al impact at 6 km/s (u_p = 3 km/s,
 * ~80 GPa) with the default dt_margin 0.5 — before sub-cycling it stopped at particle step 43
 * (the model's limit 9.15e-6 under the fixed 9.35e-6, docs/particles-dm.md) — runs with the
 * model sub-stepping where its limit is below the coupled step; the drive check holds (1 %, as
 * above) and the kick–drift–kick energy identity still closes per sub-step. */
static void test_subcycling(void **state) {
  (void)state;
  char full[8192];
  snprintf(full, sizeof full, "%s", deck("velocity", "    response: eos\n    yield: none\n", ""));
  replace_once(full, sizeof full, "thickness: 0.1, cells: 100, velocity: 2.0}",
               "thickness: 0.1, cells: 100, velocity: 6.0}");
  cpl_test_run r;
  cpl_test_run_deck(&r, full, "test.yaml", RUN_FILES, RUN_NFILES);
  const cpl_run_summary s = *cpl_problem_summary(r.p);
  printf("sub-cycling: symmetric Al impact at 6 km/s: %ld steps; free surface plateau %.5f vs "
         "%.5f km/s: %.3f %% over %zu samples; energy balance %.3g of the piston work\n",
         s.steps, s.check.plateau_particles, s.check.plateau_grid, 100 * s.check.rel_diff,
         s.check.samples, s.energy_balance);
  cpl_test_run_free(&r);
  assert_true(s.check.samples >= 5);
  assert_true(s.check.rel_diff < 0.01);
  /* symmetric: u_fs ≈ the flyer's 6 km/s; at ~80 GPa the release isentrope adds a few % */
  assert_true(s.check.plateau_grid > 5.9 && s.check.plateau_grid < 6.4);
  assert_true(fabs(s.energy_balance) < 1e-10);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_symmetric_flat), cmocka_unit_test(test_deck_errors),
      cmocka_unit_test(test_spall),          cmocka_unit_test(test_default_deck),
      cmocka_unit_test(test_subcycling),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
