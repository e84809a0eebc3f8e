/* SPDX-License-Identifier: MIT */
/* Rz80 / Rz20 at reduced size ([Davydov] §4.2; docs/coupling.md §9, docs/validation.md "At the
 * paper's 15 GPa"), CI-sized: a shipped deck with the particle phase cut to t = 0.10 (1 µs,
 * 0.7 µs after the grid's free-surface breakout) and no transport. The measure is the run's own
 * split of the detached material (cpl_ejecta_classify, docs/coupling.md §9 "The split"): spall
 * layers are the detached fragments spanning the periodic width, jets the detached material
 * ahead of the foremost full-width fragment's front, debris the rest. Masses are compared per
 * unit surface area (the region's cross-section: periodic width × plane-strain thickness: a for
 * cluster dynamics, 1 cm for the discrete model's 2D region).
 * Argument: the deck's name without inputs/coupled- and .yaml (one ctest entry each):
 *   rz80, rz20             cluster dynamics, the ~30 GPa decks (its documented result);
 *   dm-rz80-15gpa, dm-rz20-15gpa   the discrete model at the paper's 15 GPa, at twice the
 *                          decks' spacing (CI size, ~5 s each on an idle core): the paper's claim.
 * Why 0.7 µs after breakout: by then the release from the free surface has crossed the 500 µm
 * region and come back (2 h / c_L ≈ 0.45 µs, c_L = Z / ρ0 = 2.2 km/s from the decks' piston
 * impedance), so every spall plane the region can hold has opened and the layers have separated
 * by more than the bond reach; later
 * the 15 GPa Rz80 region comes apart into single failed particles (at 2.7 µs after breakout a
 * cloud, docs/validation.md), which neither the paper's picture nor this split describes. The
 * time was fixed from the 30 GPa runs' tables before this test was written. */
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

static const char *which = "rz20";

/* The deck file with the particle phase shortened and the transport removed. */
static char *load_deck(void) {
  const char *src = getenv("MSCALE_SOURCE_DIR");
  char path[1024];
  snprintf(path, sizeof path, "%s/inputs/coupled-%s.yaml", src ? src : ".", which);
  FILE *f = fopen(path, "rb");
  if (!f) fail_msg("cannot open %s (set MSCALE_SOURCE_DIR)", path);
  static char buf[16384];
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  buf[n] = 0;
  const char *end_line = "    end: 0.3 ";
  char *e = strstr(buf, end_line);
  char *t = strstr(buf, "  transport:");
  if (!e || !t)
    fail_msg("%s: the time.end line or the transport section moved; update the test", path);
  memcpy(e, "    end: 0.10", strlen(end_line));
  *t = 0;
  /* the discrete model's cases at twice the deck's spacing (CI size): the split's answer holds
   * from h = 8 to 3 µm (Rz80) and 4 to 2 µm (Rz20), docs/validation.md "Resolution" */
  static const char *const coarse[][2] = {{"dm-rz80-15gpa", "    r0: 4.0e-4"},
                                          {"dm-rz20-15gpa", "    r0: 2.0e-4"}};
  for (size_t k = 0; k < 2; k++) {
    if (strcmp(which, coarse[k][0])) continue;
    char *r = strstr(buf, coarse[k][1]);
    if (!r) fail_msg("%s: the r0 line moved; update the test", path);
    r[8] = r[8] == '4' ? '8' : '4'; /* "    r0: 4.0e-4" -> 8.0e-4, 2.0e-4 -> 4.0e-4 */
  }
  return buf;
}

/* Per case: the region's cross-section (deck width × thickness) and the grid's free-surface
 * jump-off velocity of its loading (u_ref, the first peak: 1.53 km/s at ~30 GPa, 0.923 km/s for
 * the pulse scaled to 15.45 GPa; docs/validation.md). */
typedef struct rz_case {
  const char *name;
  double area, u_ref;
} rz_case;
static const rz_case CASES[] = {{"rz80", 0.03 * 4.0e-4, 1.53},
                                {"rz20", 0.004 * 2.0e-4, 1.53},
                                {"dm-rz80-15gpa", 0.03 * 1.0, 0.923},
                                {"dm-rz20-15gpa", 0.004 * 1.0, 0.923}};

static void test_rz(void **state) {
  (void)state;
  const rz_case *rc = NULL;
  for (size_t k = 0; k < sizeof CASES / sizeof *CASES; k++)
    if (!strcmp(CASES[k].name, which)) rc = &CASES[k];
  if (!rc) fail_msg("unknown case %s", which);
  cpl_test_run r;
  cpl_test_run_deck(&r, load_deck(), which, NULL, 0);
  const cpl_run_summary *s = cpl_problem_summary(r.p);
  const cpl_ejecta_classes *c = &s->classes;
  const double a = rc->area;
  printf("%s: %zu particles, u_ref %.4f km/s, plateau %.4f km/s; per cm^2: bulk %.4g g, jets "
         "%.4g g, layers %.4g g (%zu), debris %.4g g; fragments ahead %zu, behind %zu; fast "
         "%.4g g (%zu); fastest detached %.4f km/s\n",
         which, s->particles, s->u_ref, s->u_plateau, c->m_bulk / a, c->m_jet / a, c->m_layer / a,
         c->n_layer, c->m_debris / a, c->n_jet, c->n_debris, c->m_fast / a, c->n_fast, c->v_max);
  /* the loading is the documented one (the grid alone decides u_ref: 2 % covers the sampling
   * of the first peak at the fragment-search interval) */
  assert_true(fabs(s->u_ref - rc->u_ref) < 0.02 * rc->u_ref);
  /* something must have detached at all: 50 µm of lead (0.057 g/cm²), so that the comparisons
   * below are between masses that exist */
  const double detached = c->m_jet + c->m_layer + c->m_debris;
  assert_true(detached / a > 0.057);
  if (!strncmp(which, "dm-", 3)) {
    /* the discrete model's balance with the drag on its ejecta booked (docs/coupling.md §4,
     * "In the particles' balance"): the kicks' ΔK is the view's ½m(v1² − v0²), the model's
     * kinetic energy at the step's synchronised velocities differs by O(dt) per kick —
     * bounded, measured ≤ 3e-6 of the piston work; the drag itself took 5e-5 of it by 1 µs at
     * the coarse Rz20 size, which a balance without the term shows */
    printf("%s: energy balance %.3g of the piston work (drag booked); failed particles %ld by "
           "the criterion, %ld isolated, %ld degenerate\n",
           which, s->energy_balance, s->failed[0], s->failed[1], s->failed[2]);
    assert_true(fabs(s->energy_balance) < 1e-5);
    /* the counts reach the summary: these decks fail particles by the criterion */
    assert_true(s->failed[0] > 0);
  } else {
    /* cluster dynamics has no fracture model: no counts */
    assert_true(s->failed[0] == 0 && s->failed[1] == 0 && s->failed[2] == 0);
  }
  if (!strcmp(which, "dm-rz80-15gpa")) {
    /* [Davydov] Fig. 28, Rz80: no spall near the free surface, intense jet formation — the
     * jets' mass exceeds the spall layers' */
    assert_true(c->m_jet > c->m_layer);
  } else if (!strcmp(which, "dm-rz20-15gpa")) {
    /* Rz20: spall clearly visible — the layers' mass exceeds the jets' */
    assert_true(c->m_layer > c->m_jet);
  } else if (!strcmp(which, "rz20")) {
    /* cluster dynamics, Rz20 (docs/coupling.md §9): spall layers, a few tip clusters ahead */
    assert_true(c->m_jet < 0.1 * c->m_layer);
  } else {
    /* cluster dynamics, Rz80: the grooved layer breaks off in chunks that no layer spans, so
     * the shape split puts them ahead ("jets", docs/coupling.md "The split": its limit), but
     * none outruns a flat free surface — no Richtmyer–Meshkov jet (the former velocity split's
     * criterion, 1.1 u_ref, kept here as the documented cluster-dynamics result) */
    assert_true(c->v_max < 1.1 * s->u_ref);
  }
  cpl_test_run_free(&r);
}

int main(int argc, char **argv) {
  if (argc > 1) which = argv[1];
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_rz)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
