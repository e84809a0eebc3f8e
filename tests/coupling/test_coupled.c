/* SPDX-License-Identifier: MIT */
/* The `coupled` problem end to end (one-way drive, docs/coupling.md §6):
 *  1. symmetric plate impact (Pb on Pb, 0.5 km/s): the grid's U(t) at a node 0.02 cm below the
 *     free surface drives a flat 2D cluster-dynamics slab; the particle free-surface velocity
 *     plateau must match the grid's (exactly 2 up = 0.5 km/s in both) within 2 % (the issue's
 *     evidence), the particle energy balance must close, and a flat surface ejects nothing;
 *  2. the same with a grooved surface: jets form, fragments are found, and ejecta reach a
 *     detector through the air (drag from the grid's gas layer);
 *  3. deck errors: a missing tag, a drive node beyond the free surface, a gas without
 *     viscosity are reported with their deck location. */
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

#include "cpl.h"
#include "cpl_test.h"
#include "test_util.h"

static const char *const MATERIALS =
    "units: internal\n"
    "problem: coupled\n"
    "materials:\n"
    "  - name: pb\n"
    "    eos: {type: mg_cold, rho0: 11.34, c0: 1.972, n: 3.0, gamma0: 2.0}\n"
    "  - name: air\n"
    "    eos: {type: ideal_gas, gamma: 1.4, rho0: 1.225e-3, p0: 1.01325e-4}\n"
    "    viscosity: %s\n";

static const char *const GRID =
    "coupled:\n"
    "  grid:\n"
    "    layers:\n"
    "      - {name: flyer, material: pb, thickness: 0.1, cells: 200, velocity: %s}\n"
    "      - {name: sample, material: pb, thickness: 0.1, cells: 200, pressure: 1.01325e-4}\n"
    "      - {name: air, material: air, thickness: 0.5, cells: 100, density: 1.225e-3,"
    " pressure: 1.01325e-4}\n"
    "    left: {type: free}\n"
    "    right: {type: pressure, value: 1.01325e-4}\n"
    "    time: {end: 0.12}\n"
    "    tags:\n"
    "      - {name: drive, x: %s}\n"
    "      - {name: free_surface, layer: sample, side: right}\n"
    "  drive: {tag: %s, free_surface_tag: free_surface}\n";

/* Outputs every one-way run must write. */
static const char *const RUN_FILES[] = {
    "spectrum.csv",      "fragments.csv",      "ejecta_mass.csv",  "free_surface.csv",
    "particles_0001.h5", "particles_0001.xmf", "history_drive.csv"};
#define RUN_NFILES (sizeof RUN_FILES / sizeof *RUN_FILES)

static char *deck(const char *viscosity, const char *drive_x, const char *drive_tag,
                  const char *rest) {
  static char buf[8192];
  /* 0.5 km/s (≈ 6 GPa) for the flat drive check; 1.5 km/s (≈ 20 GPa) where jets must form */
  const char *flyer = strstr(rest, "grooves") ? "1.5" : "0.5";
  int n = snprintf(buf, sizeof buf, MATERIALS, viscosity);
  n += snprintf(buf + n, sizeof buf - (size_t)n, GRID, flyer, drive_x, drive_tag);
  snprintf(buf + n, sizeof buf - (size_t)n, "%s", rest);
  return buf;
}

/* Runs the symmetric flat-surface case with the given piston mode; returns its summary. */
static cpl_run_summary run_flat(const char *mode) {
  char rest[512];
  snprintf(rest, sizeof rest,
           "  particles: {lattice: tri2d, spacing: 2.0e-4, width: 0.004, cutoff: 1.2,"
           " cutoff_mode: bonded, damping_j: 50}\n"
           "  time: {end: 0.076, outputs: 1}\n"
           "  fragments: {every: 50}\n");
  char *text = deck("1.8e-9", "0.18", "drive", rest);
  /* the piston mode goes into the drive section */
  char full[8192], *d = strstr(text, "free_surface_tag: free_surface}");
  assert_non_null(d);
  snprintf(full, sizeof full, "%.*sfree_surface_tag: free_surface, mode: %s}%s", (int)(d - text),
           text, mode, d + strlen("free_surface_tag: free_surface}"));
  cpl_test_run r;
  cpl_test_run_deck(&r, full, "test.yaml", RUN_FILES, RUN_NFILES);
  cpl_run_summary s = *cpl_problem_summary(r.p);
  printf("symmetric impact, %s piston: %zu particles, %ld steps; free surface plateau %.5f "
         "(particles) vs %.5f (grid) km/s: %.3f %%; half-rise %.5g vs %.5g; smallest velocity "
         "after the window %.4g; energy balance %.3g of the piston work; %zu fragments\n",
         mode, s.particles, s.steps, s.check.plateau_particles, s.check.plateau_grid,
         100 * s.check.rel_diff, s.check.t_half_particles, s.check.t_half_grid, s.check.min_after,
         s.energy_balance, s.fragments);
  cpl_test_run_free(&r);
  return s;
}

static void test_symmetric_flat(void **state) {
  (void)state;
  /* velocity piston (the papers' one-way drive: the particles' boundary moves exactly as the
   * grid node) */
  cpl_run_summary v = run_flat("velocity");
  /* the evidence: the same free-surface velocity as the grid alone within 2 %
   * (measured 0.14 %: the lattice's Hugoniot differs slightly from the grid's EOS) */
  assert_true(v.check.samples >= 5);
  assert_true(v.check.rel_diff < 0.02);
  /* symmetric impact: the free surface flies at the flyer's speed, 0.5 km/s; the grid's
   * artificial viscosity costs < 1 % */
  assert_true(fabs(v.check.plateau_grid - 0.5) < 0.005);
  /* the lattice carries the wave faster than the grid (shear stiffness of a pair-potential
   * lattice): the particle surface breaks out earlier, by less than 20 % of the transit time
   * over the 0.02 cm region (≈ 0.009) — measured 0.0013 */
  assert_true(v.check.t_half_particles <= v.check.t_half_grid);
  assert_true(v.check.t_half_grid - v.check.t_half_particles < 0.2 * 0.009);
  /* bonded velocity Verlet with damping: the balance (kinetic + potential + damped − piston
   * work) closes to 1e-4 of the work (measured 1.2e-6) */
  assert_true(fabs(v.energy_balance) < 1e-4);
  assert_true(v.piston_work > 0);
  /* a flat surface: one piece, nothing ejected */
  assert_int_equal(v.fragments, 1);
  assert_true(v.ejected_mass == 0);

  /* transmitting piston u = U + (p_grid − p_particles)/Z: the release from the free surface
   * passes out through the piston instead of coming back as a dip (velocity piston: measured
   * down to 0.02 km/s; transmitting: ≥ 0.46 km/s). The price is the pressure mismatch of the
   * lattice against the grid's EOS at the same velocity, which shifts the plateau (measured
   * 7.2 % at this low pressure, 0.3 % at 25 GPa — docs/coupling.md §5). */
  cpl_run_summary t = run_flat("transmitting");
  assert_true(t.check.rel_diff < 0.10);
  assert_true(t.check.min_after > 0.85 * t.check.plateau_grid);
  assert_true(v.check.min_after < 0.5 * v.check.plateau_grid); /* what the mode is for */
  assert_true(fabs(t.energy_balance) < 1e-4);
  assert_int_equal(t.fragments, 1);
}

static void test_grooved_ejecta(void **state) {
  (void)state;
  /* Pb on Pb at 1.5 km/s; one groove 40 µm deep, 40 µm period; a = 2 µm; 0.5 µs after
   * breakout; detector 0.2 cm beyond the free surface */
  const char *rest =
      "  particles:\n"
      "    {lattice: tri2d, spacing: 2.0e-4, width: 0.004, cutoff: 1.2, cutoff_mode: bonded,"
      " damping_j: 50, surface: {type: grooves, depth: 40.0e-4, wavelength: 40.0e-4}}\n"
      "  time: {end: 0.085, outputs: 2}\n"
      "  fragments: {every: 100}\n"
      "  transport: {detector: 0.2, end: 1.0, windows: 20}\n";
  cpl_test_run r;
  cpl_test_run_deck(&r, deck("1.8e-9", "0.18", "drive", rest), "test.yaml", RUN_FILES, RUN_NFILES);
  const cpl_run_summary *s = cpl_problem_summary(r.p);
  printf("grooved surface: %zu particles, %zu fragments, ejected %.4g g, %zu of %zu transported "
         "fragments at the detector\n",
         s->particles, s->fragments, s->ejected_mass, s->arrived, s->transported);
  /* a groove as deep as its period jets faster than the free surface: material leaves the
   * bulk — fragments besides the bulk, with positive mass (measured: 32 fragments) — and the
   * ejecta reach a detector 2 mm away within 9 µs (they fly at ≳ 1.5 km/s: ≈ 1.3 µs). The
   * energy balance is not asserted here: bond breaking is booked by the particle code
   * (cd_energy.broken), which the flat case above checks without broken bonds. */
  assert_true(s->fragments >= 2);
  assert_true(s->ejected_mass > 0);
  assert_true(s->transported >= 1);
  assert_int_equal(s->arrived, s->transported);
  /* the same groove given as its amplitude (half the depth: [Davydov]'s a0) cuts the same
   * lattice: the same particle count (a particle phase cut short, no transport, suffices; read
   * as a depth of 20 µm it would keep more particles) */
  const char *rest_amp =
      "  particles:\n"
      "    {lattice: tri2d, spacing: 2.0e-4, width: 0.004, cutoff: 1.2, cutoff_mode: bonded,"
      " damping_j: 50, surface: {type: grooves, amplitude: 20.0e-4, wavelength: 40.0e-4}}\n"
      "  time: {end: 0.065, outputs: 1}\n";
  cpl_test_run ra;
  cpl_test_run_deck(&ra, deck("1.8e-9", "0.18", "drive", rest_amp), "test.yaml", RUN_FILES,
                    RUN_NFILES);
  assert_int_equal(cpl_problem_summary(ra.p)->particles, s->particles);
  cpl_test_run_free(&ra);
  cpl_test_run_free(&r);
}

static void test_deck_errors(void **state) {
  (void)state;
  const char *rest = "  particles: {spacing: 2.0e-4, width: 0.004}\n"
                     "  time: {end: 0.065}\n";
  struct {
    const char *visc, *x, *tag, *needle;
  } cases[] = {
      {"1.8e-9", "0.18", "nodrive", "test.yaml:21:16: drive.tag: no tag named 'nodrive'"},
      {"1.8e-9", "0.25", "drive", "must lie left of the free surface"},
      {"0", "0.18", "drive", "drag needs the gas viscosity: give material 'air'"},
  };
  for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
    cpl_test_run r;
    cpl_test_read(&r, deck(cases[c].visc, cases[c].x, cases[c].tag, rest), "test.yaml");
    assert_null(r.p);
    if (!has_error(&r.e, cases[c].needle)) {
      dk_errors_print(&r.e, stderr);
      fail_msg("case %zu: expected an error containing '%s'", c, cases[c].needle);
    }
    cpl_test_run_free(&r);
  }
}

/* Two-way coupling: the grid (flyer + 0.08 cm of sample) ends at the interface node; a 0.02 cm
 * particle region continues it. The shock crosses the interface, reaches the particles' free
 * surface; before the release returns (t = 0.048) the interface moves at the grid–lattice
 * transmitted velocity and the free surface at twice it. */
static void test_two_way(void **state) {
  (void)state;
  const char *text =
      "units: internal\n"
      "problem: coupled\n"
      "materials:\n"
      "  - {name: pb, eos: {type: mg_cold, rho0: 11.34, c0: 1.972, n: 3.0, gamma0: 2.0}}\n"
      "coupled:\n"
      "  grid:\n"
      "    layers:\n"
      "      - {name: flyer, material: pb, thickness: 0.1, cells: 200, velocity: 0.5}\n"
      "      - {name: sample, material: pb, thickness: 0.08, cells: 160, pressure: 0.0}\n"
      "    left: {type: free}\n"
      "    right: {type: free}\n"
      "    time: {end: 0.048}\n"
      "    tags: [{name: drive, layer: sample, side: right}]\n"
      "  drive: {tag: drive, mode: two_way}\n"
      "  particles: {lattice: tri2d, spacing: 2.0e-4, width: 0.004, depth: 0.02}\n"
      "  time: {end: 0.048, outputs: 1}\n";
  cpl_test_run r;
  cpl_test_run_deck(&r, text, "two.yaml", NULL, 0);
  const cpl_run_summary *s = cpl_problem_summary(r.p);
  double jerr = (s->impulse_grid + s->impulse_particles) / s->impulse_particles;
  double werr = (s->work_grid + s->work_particles) / s->work_particles;
  printf("two-way: impulse grid %.6g vs particles %.6g (%.2g), work grid %.6g vs particles %.6g "
         "(%.2g); interface u %.5f km/s (incident 0.25: %.2f %%), free surface %.5f km/s\n",
         s->impulse_grid, s->impulse_particles, jerr, s->work_grid, s->work_particles, werr,
         s->u_interface, 100 * (s->u_interface / 0.25 - 1), s->u_free_surface);
  /* the grid receives exactly the impulse the particles did, one grid step later: equal up
   * to round-off of the sums (~1e-15 relative per step, ~800 steps) */
  assert_true(s->impulse_particles > 0 && fabs(jerr) < 1e-12);
  /* work: the traction acts over the grid's step while the particles' pressure varies within
   * it — an O(Δp Δx) difference per step, 1e-2 (measured 1.2e-3) */
  assert_true(s->work_particles > 0 && fabs(werr) < 1e-2);
  /* transmitted velocity: u = 2 Z_g/(Z_g + Z_p) u_p; the lattice is stiffer than the grid's
   * EOS at 6 GPa (shear stiffness), measured −7.0 % (−1.8 % at 25 GPa, docs/coupling.md):
   * a reflection of the impedance mismatch, not of the coupling — bound 10 % */
  assert_true(s->u_interface < 0.25 && s->u_interface > 0.9 * 0.25);
  /* the particles' free surface doubles the transmitted velocity (within 1 %) */
  assert_true(fabs(s->u_free_surface / (2 * s->u_interface) - 1) < 0.01);
  cpl_test_run_free(&r);
}

/* Two-way with a gas layer (`gas:`): the grid writes its usual outputs, the interface balance
 * holds as without gas, the gas grid's first node follows the particles' free surface, and the
 * jet fragments feel the gas (drag returned to it) and reach the detector. */
static void test_two_way_gas(void **state) {
  (void)state;
  const char *text =
      "units: internal\n"
      "problem: coupled\n"
      "materials:\n"
      "  - {name: pb, eos: {type: mg_cold, rho0: 11.34, c0: 1.972, n: 3.0, gamma0: 2.0}}\n"
      "  - {name: air, eos: {type: ideal_gas, gamma: 1.4, rho0: 1.225e-3, p0: 1.01325e-4},\n"
      "     viscosity: 1.8e-9}\n"
      "coupled:\n"
      "  grid:\n"
      "    layers:\n"
      "      - {name: flyer, material: pb, thickness: 0.1, cells: 200, velocity: 1.5}\n"
      "      - {name: sample, material: pb, thickness: 0.04, cells: 80, pressure: 0.0}\n"
      "    left: {type: free}\n"
      "    right: {type: free}\n"
      "    time: {end: 1.0}\n"
      "    output: {times: [0.02], xt_frames: 20}\n"
      "    tags: [{name: drive, layer: sample, side: right}]\n"
      "  gas:\n"
      "    layers: [{name: air, material: air, thickness: 0.5, cells: 100, density: 1.225e-3,\n"
      "              pressure: 1.01325e-4}]\n"
      "    left: {type: piston, value: 0}\n"
      "    right: {type: pressure, value: 1.01325e-4}\n"
      "    time: {end: 1.0}\n"
      "  drive: {tag: drive, mode: two_way}\n"
      "  particles: {lattice: tri2d, spacing: 2.0e-4, width: 0.004, depth: 0.01,\n"
      "              surface: {type: grooves, depth: 40.0e-4, wavelength: 40.0e-4}}\n"
      "  time: {end: 0.05, outputs: 1}\n"
      "  fragments: {every: 200}\n"
      "  drag: {gas_return: true}\n"
      "  transport: {detector: 0.1, end: 0.3, windows: 50}\n";
  /* the grid's outputs, as in a one-way (or grid-only) run, and the ejecta outputs */
  const char *const files[] = {
      "profile_0000.csv",     "profile_final.csv", "history_drive.csv", "xt.h5",
      "interface.csv",        "ejecta_mass.csv",   "fragments.csv",     "arrivals.csv",
      "spectrum_detector.csv"};
  cpl_test_run r;
  cpl_test_run_deck(&r, text, "twogas.yaml", files, sizeof files / sizeof *files);
  const cpl_run_summary *s = cpl_problem_summary(r.p);
  double jerr = (s->impulse_grid + s->impulse_particles) / s->impulse_particles;
  printf("two-way with gas: impulse balance %.2g; free surface %.4f km/s, gas boundary moved "
         "%.5g cm; %zu fragments, %zu transported, %zu arrived; gas received %.4g g*km/s, "
         "%.4g kJ\n",
         jerr, s->u_free_surface, s->gas_shift, s->fragments, s->transported, s->arrived,
         s->gas_momentum, s->gas_energy);
  /* the gas changes nothing at the interface: exact impulse exchange (round-off) */
  assert_true(fabs(jerr) < 1e-12);
  /* the gas boundary moved forward with the free surface (the surface layer's mean velocity,
   * jets included: measured 1.77 km/s at the end, 0.0577 cm from breakout at t ≈ 0.016): more
   * than a third and less than all of 1.6 km/s × 0.05 */
  assert_true(s->gas_shift > 0.33 * 1.6 * 0.05 && s->gas_shift < 1.6 * 0.05);
  /* the grooves jet; the jets detach, fly through the gas and arrive 0.1 cm out */
  assert_true(s->transported > 0 && s->arrived == s->transported);
  /* drag slowed them (they outrun the gas pushed by the free surface): the gas received
   * forward momentum and energy */
  assert_true(s->gas_momentum > 0 && s->gas_energy > 0);
  cpl_test_run_free(&r);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_deck_errors),    cmocka_unit_test(test_symmetric_flat),
      cmocka_unit_test(test_grooved_ejecta), cmocka_unit_test(test_two_way),
      cmocka_unit_test(test_two_way_gas),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
