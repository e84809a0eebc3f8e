/* SPDX-License-Identifier: MIT */
/* The deck's materials: and mixtures: sections (docs/eos.md "Materials"): every EOS type, SI
 * conversion, and broken decks that must each give a FILE:LINE:COL error naming the problem. */
#include <math.h>

#include "eos_test_util.h"

static char tmpdir[256];

static int setup(void **state) {
  (void)state;
  eos_test_tmpdir(tmpdir, sizeof tmpdir);
  char path[512];
  /* A small cold table next to the decks (B4C MG cold form sampled at 4 points) and a broken
   * one, for file: references relative to the deck's directory. */
  snprintf(path, sizeof path, "%s/cold.txt", tmpdir);
  eos_test_write(path, "delta rho eps_x P_x\n0.9 2.259 0.43890007 -18.491141\n1.0 2.51 0 0\n"
                       "1.1 2.761 0.38720588 22.880114\n1.2 3.012 1.4717684 50.648186\n");
  snprintf(path, sizeof path, "%s/cold_truncated.txt", tmpdir);
  eos_test_write(path, "delta rho eps_x P_x\n0.9 2.259 0.43890007 -18.491141\n1.0 2.51 0 0\n"
                       "1.1 2.761 0.38720588\n");
  snprintf(path, sizeof path, "%s/cold_nonmono.txt", tmpdir);
  eos_test_write(path, "delta rho eps_x P_x\n0.9 2.259 0.43890007 -18.491141\n1.0 2.51 0 0\n"
                       "1.2 3.012 1.4717684 50.648186\n1.1 2.761 0.38720588 22.880114\n");
  snprintf(path, sizeof path, "%s/full.txt", tmpdir);
  eos_test_write(path, "# rho0: 1.0\nrho e P\n1 0 1\n1 1 2\n2 0 4\n2 1 5\n");
  return 0;
}

static int teardown(void **state) {
  (void)state;
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
  return system(cmd) == 0 ? 0 : -1;
}

/* Write `text` as deck.yaml in the temporary directory, load and read it. */
static eos_materials *read_deck(const char *text, dk_errors *e, dk_doc **doc_out, char *path,
                                size_t n) {
  snprintf(path, n, "%s/deck.yaml", tmpdir);
  eos_test_write(path, text);
  dk_doc *doc = dk_load(path, e);
  eos_materials *m = NULL;
  if (doc) {
    dk_read_units(doc, e);
    m = eos_materials_read(doc, e);
  }
  *doc_out = doc;
  return m;
}

static void test_good_deck(void **state) {
  (void)state;
  const char *text = "materials:\n"
                     "  - name: al\n"
                     "    eos: {type: mg_linear, rho0: 2.703, c0: 5.35, s: 1.34, gamma0: 2.0}\n"
                     "    shear_modulus: 26.0\n"
                     "  - name: pb\n"
                     "    eos: {type: mg_cold, rho0: 11.34, c0: 1.972, n: 3.0, gamma0: 2.0,\n"
                     "          gamma_model: rho_gamma}\n"
                     "  - name: air\n"
                     "    eos: {type: ideal_gas, gamma: 1.4}\n"
                     "    viscosity: 1.8e-9\n"
                     "  - name: b4c_tab\n"
                     "    eos: {type: table_cold, file: cold.txt, gamma0: 1.5}\n"
                     "  - name: tab\n"
                     "    eos: {type: table_full, file: full.txt}\n"
                     "  - name: steel\n"
                     "    eos: {type: linear_elastic, rho0: 7.85, bulk_modulus: 66.6667}\n"
                     "mixtures:\n"
                     "  - name: mix\n"
                     "    components:\n"
                     "      - {material: al, mass_fraction: 0.2}\n"
                     "      - {material: pb, mass_fraction: 0.8}\n";
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc;
  char path[512];
  eos_materials *m = read_deck(text, &e, &doc, path, sizeof path);
  dk_report_unused(&e, doc);
  if (e.n) eos_test_dump(&e);
  assert_int_equal(e.n, 0);
  assert_non_null(m);
  assert_int_equal(m->n, 6);
  const eos_kind kinds[6] = {EOS_MG_LINEAR,  EOS_MG_COLD,    EOS_IDEAL_GAS,
                             EOS_TABLE_COLD, EOS_TABLE_FULL, EOS_LINEAR_ELASTIC};
  for (int i = 0; i < 6; ++i) assert_int_equal(eos_get_kind(m->m[i].eos), kinds[i]);
  assert_true(m->m[0].shear_modulus == 26.0 && m->m[2].viscosity == 1.8e-9);
  assert_true(m->m[0].line == 2);
  const eos_material *pb = eos_materials_find(m, "pb", &e, doc, NULL);
  assert_non_null(pb);
  assert_true(eos_rho0(pb->eos) == 11.34 && eos_c0(pb->eos) == 1.972);
  /* ideal gas defaults: air at 1 atm */
  assert_true(eos_rho0(m->m[2].eos) == 1.225e-3);
  /* mass fractions -> volume fractions α_i = (y_i/ρ0_i)/Σ(y_k/ρ0_k) */
  const eos_mixture *mx = eos_mixtures_find(m, "mix");
  assert_non_null(mx);
  double va = 0.2 / 2.703, vp = 0.8 / 11.34;
  assert_true(fabs(mx->alpha[0] - va / (va + vp)) < 1e-15);
  assert_true(mx->comp[1] == 1);
  /* lookups of unknown names report the known ones */
  assert_null(eos_materials_find(m, "cu", &e, doc, dk_root(doc)));
  assert_true(has_error(&e, "unknown material 'cu' (known: al, pb, air, b4c_tab, tab, steel)"));
  eos_materials_destroy(&m);
  dk_free(doc);
  dk_errors_free(&e);
}

/* units: si converts every dimensional value on reading. */
static void test_si_units(void **state) {
  (void)state;
  const char *text = "units: si\n"
                     "materials:\n"
                     "  - name: al\n"
                     "    eos: {type: mg_linear, rho0: 2703, c0: 5350, s: 1.34, gamma0: 2.0,\n"
                     "          cv: 900}\n"
                     "    shear_modulus: 26e9\n"
                     "  - name: air\n"
                     "    eos: {type: ideal_gas, gamma: 1.4, rho0: 1.2, p0: 2e5}\n"
                     "    viscosity: 1.8e-5\n";
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc;
  char path[512];
  eos_materials *m = read_deck(text, &e, &doc, path, sizeof path);
  if (e.n) eos_test_dump(&e);
  assert_int_equal(e.n, 0);
  /* kg/m³ -> g/cm³ 1e-3, m/s -> km/s 1e-3, Pa -> GPa 1e-9, Pa·s -> g/(cm·10µs) 1e-4 */
  assert_true(fabs(eos_rho0(m->m[0].eos) - 2.703) < 1e-12);
  assert_true(fabs(eos_c0(m->m[0].eos) - 5.35) < 1e-12);
  assert_true(fabs(m->m[0].shear_modulus - 26.0) < 1e-12);
  /* cv: J/(kg K) -> kJ/(g K) 1e-6: 900 J/(kg K) -> 9e-4; T = (e − ε_x)/cv at ρ0 */
  assert_true(fabs(eos_temperature(m->m[0].eos, 2.703, 0.27) - 300.0) < 1e-9);
  assert_true(fabs(m->m[1].viscosity - 1.8e-9) < 1e-20);
  /* c0 = sqrt(γ p0/ρ0) = sqrt(1.4 · 2e-4 GPa / 1.2e-3 g/cm³) */
  assert_true(fabs(eos_c0(m->m[1].eos) - sqrt(1.4 * 2e-4 / 1.2e-3)) < 1e-12);
  eos_materials_destroy(&m);
  dk_free(doc);
  dk_errors_free(&e);
}

/* ---- Broken decks ---------------------------------------------------------------------------- */

typedef struct bad_deck {
  const char *what, *text;
  int line;           /* expected line in deck.yaml (0: message about a data file) */
  const char *needle; /* part of the message */
} bad_deck;

#define HEAD "materials:\n  - name: al\n    eos:\n" /* lines 1-3 */

static const bad_deck bad_decks[] = {
    {"negative density",
     HEAD "      type: mg_linear\n      rho0: -2.7\n      c0: 5.35\n"
          "      s: 1.34\n      gamma0: 2\n",
     5, "rho0: expected a number > 0, found -2.7"},
    {"n <= 1",
     HEAD "      type: mg_cold\n      rho0: 11.34\n      c0: 1.972\n      n: 1.0\n"
          "      gamma0: 2\n",
     7, "expected a number > 1, found 1"},
    {"negative Grüneisen",
     HEAD "      type: mg_cold\n      rho0: 11.34\n      c0: 1.972\n"
          "      n: 3\n      gamma0: -0.5\n",
     8, "gamma0: expected a number >= 0, found -0.5"},
    {"unknown eos type", HEAD "      type: mie\n      rho0: 1\n", 4,
     "expected one of: mg_cold, mg_linear, ideal_gas, table_cold, table_full, linear_elastic"},
    {"unknown key (typo)",
     HEAD "      type: mg_linear\n      rho0: 2.7\n      c00: 5.35\n"
          "      c0: 5.35\n      s: 1.34\n      gamma0: 2\n",
     6, "unknown key 'c00'"},
    {"missing key", HEAD "      type: mg_linear\n      rho0: 2.7\n      s: 1.34\n      gamma0: 2\n",
     3, "missing required key 'c0'"},
    {"wrong value type",
     HEAD "      type: mg_linear\n      rho0: heavy\n      c0: 5.35\n"
          "      s: 1.34\n      gamma0: 2\n",
     5, "expected a number"},
    {"duplicate name",
     "materials:\n  - name: al\n    eos: {type: ideal_gas, gamma: 1.4}\n"
     "  - name: al\n    eos: {type: ideal_gas, gamma: 1.6}\n",
     4, "duplicate material name 'al' (first defined on line 2)"},
    {"nonexistent table file",
     HEAD "      type: table_cold\n      file: no_such_table.txt\n"
          "      gamma0: 2\n",
     5, "cannot open table file 'no_such_table.txt'"},
    {"truncated table",
     HEAD "      type: table_cold\n      file: cold_truncated.txt\n"
          "      gamma0: 2\n",
     5, "invalid cold-curve table"},
    {"non-monotone table",
     HEAD "      type: table_cold\n      file: cold_nonmono.txt\n"
          "      gamma0: 2\n",
     5, "invalid cold-curve table"},
    {"ideal gas gamma <= 1", HEAD "      type: ideal_gas\n      gamma: 1.0\n", 5,
     "expected a number > 1, found 1"},
    {"negative s",
     HEAD "      type: mg_linear\n      rho0: 2.7\n      c0: 5.35\n      s: -1\n"
          "      gamma0: 2\n",
     7, "s: expected a number >= 0, found -1"},
    {"zero bulk modulus",
     HEAD "      type: linear_elastic\n      rho0: 7.85\n      bulk_modulus: 0\n", 6,
     "bulk_modulus: expected a number > 0, found 0"},
    {"materials not a list", "materials:\n  al: {type: ideal_gas}\n", 2,
     "materials: expected a list"},
    {"no materials", "units: internal\n", 1, "missing required top-level key 'materials'"},
    {"empty materials", "materials: []\n", 1, "the list is empty"},
    {"material without eos", "materials:\n  - name: al\n    shear_modulus: 26\n", 2,
     "missing required key 'eos'"},
    {"eos not a mapping", "materials:\n  - name: al\n    eos: mg_linear\n", 3,
     "expected a mapping"},
    {"negative shear modulus",
     "materials:\n  - name: al\n    shear_modulus: -1\n"
     "    eos: {type: ideal_gas, gamma: 1.4}\n",
     3, "shear_modulus: expected a number >= 0, found -1"},
    {"cv not positive", HEAD "      type: ideal_gas\n      gamma: 1.4\n      cv: 0\n", 6,
     "cv: expected a number > 0, found 0"},
    {"unknown key in a material",
     "materials:\n  - name: al\n    colour: grey\n"
     "    eos: {type: ideal_gas, gamma: 1.4}\n",
     3, "unknown key 'colour'"},
    {"mixture fractions",
     "materials:\n  - name: a\n    eos: {type: ideal_gas, gamma: 1.4}\n"
     "  - name: b\n    eos: {type: ideal_gas, gamma: 1.6}\n"
     "mixtures:\n  - name: m\n    components:\n"
     "      - {material: a, volume_fraction: 0.5}\n"
     "      - {material: b, volume_fraction: 0.6}\n",
     9, "fractions must add up to 1"},
    {"mixture of an unknown material",
     "materials:\n  - name: a\n    eos: {type: ideal_gas, gamma: 1.4}\n"
     "mixtures:\n  - name: m\n    components:\n      - {material: a, volume_fraction: 0.5}\n"
     "      - {material: zz, volume_fraction: 0.5}\n",
     8, "unknown material 'zz' (known: a)"},
    {"YAML syntax error", "materials:\n  - name: al\n    eos: {type: ideal_gas, gamma: 1.4\n", 0,
     ""},
};

static void test_bad_decks(void **state) {
  (void)state;
  for (size_t i = 0; i < sizeof bad_decks / sizeof bad_decks[0]; ++i) {
    const bad_deck *b = &bad_decks[i];
    dk_errors e;
    dk_errors_init(&e);
    dk_doc *doc;
    char path[512], where[600];
    eos_materials *m = read_deck(b->text, &e, &doc, path, sizeof path);
    if (b->line > 0) snprintf(where, sizeof where, "%s:%d:", path, b->line);
    else snprintf(where, sizeof where, "%s:", path);
    if (getenv("EOS_TEST_VERBOSE")) eos_test_dump(&e);
    if (e.n == 0 || !has_error(&e, where) || !has_error(&e, b->needle)) {
      eos_test_dump(&e);
      fail_msg("bad deck '%s': expected an error at %s containing '%s'", b->what, where, b->needle);
    }
    eos_materials_destroy(&m);
    dk_free(doc);
    dk_errors_free(&e);
  }
}

/* Errors inside a table file name the table's FILE:LINE; an unknown key is reported once even
 * when the front end also runs dk_report_unused; a broken material is not reported again as
 * "unknown" when referred to. */
static void test_error_details(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc;
  char path[512], where[600];
  eos_materials *m = read_deck(HEAD "      type: table_cold\n      file: cold_truncated.txt\n"
                                    "      gamma0: 2\n",
                               &e, &doc, path, sizeof path);
  snprintf(where, sizeof where, "%s/cold_truncated.txt:4:", tmpdir);
  assert_true(has_error(&e, where) && has_error(&e, "expected 4 columns"));
  size_t n0 = e.n;
  assert_null(eos_materials_find(m, "al", &e, doc, dk_root(doc)));
  assert_int_equal(e.n, n0);
  eos_materials_destroy(&m);
  dk_free(doc);
  dk_errors_free(&e);

  dk_errors_init(&e);
  m = read_deck(HEAD "      type: ideal_gas\n      gama: 1.4\n      gamma: 1.4\n", &e, &doc, path,
                sizeof path);
  dk_report_unused(&e, doc);
  size_t count = 0;
  for (size_t i = 0; i < e.n; ++i) count += strstr(e.msg[i], "'gama'") != NULL;
  assert_int_equal(count, 1);
  eos_materials_destroy(&m);
  dk_free(doc);
  dk_errors_free(&e);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_good_deck),
      cmocka_unit_test(test_si_units),
      cmocka_unit_test(test_bad_decks),
      cmocka_unit_test(test_error_details),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
