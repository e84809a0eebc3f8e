/* SPDX-License-Identifier: MIT */
/* `mscale hugoniot` through the built binary ($MSCALE_BINARY): CSV format, values, mixtures,
 * and exit codes with FILE:LINE:COL messages for broken decks (docs/design.md §8). */
#include <math.h>
#include <sys/wait.h>

#include "eos_test_util.h"

static char tmpdir[256];

static int setup(void **state) {
  (void)state;
  eos_test_tmpdir(tmpdir, sizeof tmpdir);
  /* a cold-curve table covering only 0.9 <= delta <= 1.2 (B4C MG cold form sampled) */
  char path[512];
  snprintf(path, sizeof path, "%s/cold.txt", tmpdir);
  eos_test_write(path, "delta rho eps_x P_x\n0.9 2.259 0.43890007 -18.491141\n1.0 2.51 0 0\n"
                       "1.1 2.761 0.38720588 22.880114\n1.2 3.012 1.4717684 50.648186\n");
  return 0;
}

static int teardown(void **state) {
  (void)state;
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
  return system(cmd) == 0 ? 0 : -1;
}

typedef struct run_result {
  int status;
  char out[16384], err[8192];
} run_result;

static void slurp(const char *path, char *buf, size_t n) {
  FILE *f = fopen(path, "r");
  size_t k = f ? fread(buf, 1, n - 1, f) : 0;
  buf[k] = '\0';
  if (f) fclose(f);
}

/* Run `mscale hugoniot ARGS` with stdout and stderr captured. */
static void run_hugoniot(const char *args, run_result *r) {
  const char *bin = getenv("MSCALE_BINARY");
  assert_non_null(bin);
  char cmd[2048], outp[400], errp[400];
  snprintf(outp, sizeof outp, "%s/stdout", tmpdir);
  snprintf(errp, sizeof errp, "%s/stderr", tmpdir);
  snprintf(cmd, sizeof cmd, "cd '%s' && '%s' hugoniot %s >'%s' 2>'%s'", tmpdir, bin, args, outp,
           errp);
  int st = system(cmd);
  assert_true(st != -1 && WIFEXITED(st));
  r->status = WEXITSTATUS(st);
  slurp(outp, r->out, sizeof r->out);
  slurp(errp, r->err, sizeof r->err);
}

static void write_deck(const char *name, const char *text) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", tmpdir, name);
  eos_test_write(path, text);
}

static const char *good_deck =
    "materials:\n"
    "  - name: al\n"
    "    eos: {type: mg_linear, rho0: 2.703, c0: 5.35, s: 1.34, gamma0: 2.0}\n"
    "  - name: b4c\n"
    "    eos: {type: mg_cold, rho0: 2.51, c0: 9.06, n: 3.13, gamma0: 1.5}\n"
    "  - name: bn\n"
    "    eos: {type: mg_cold, rho0: 2.29, c0: 3.19, n: 10.41, gamma0: 1.5}\n"
    "  - name: small\n"
    "    eos: {type: table_cold, file: cold.txt, gamma0: 1.5}\n"
    "mixtures:\n"
    "  - name: half\n"
    "    components:\n"
    "      - {material: b4c, volume_fraction: 0.5}\n"
    "      - {material: bn, volume_fraction: 0.5}\n"
    "# sections for other commands are not read (and not reported) by `hugoniot`\n"
    "problem: continuum\n"
    "continuum: {layers: [], whatever: 1}\n";

/* Parse the CSV: '# ' comments, then exactly "up,Us,P,rho,e", then rows. Returns the rows. */
static size_t parse_csv(const char *out, double rows[][5], size_t maxrows, bool *units_ok) {
  char *copy = strdup(out), *save = NULL;
  size_t nrow = 0;
  bool header = false;
  *units_ok = false;
  for (char *line = strtok_r(copy, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
    if (!header) {
      if (strncmp(line, "# ", 2) == 0) {
        if (strstr(line, "up [km/s], Us [km/s], P [GPa], rho [g/cm^3], e [kJ/g]")) *units_ok = true;
        continue;
      }
      assert_string_equal(line, "up,Us,P,rho,e");
      header = true;
      continue;
    }
    assert_true(nrow < maxrows);
    int k = sscanf(line, "%lf,%lf,%lf,%lf,%lf", &rows[nrow][0], &rows[nrow][1], &rows[nrow][2],
                   &rows[nrow][3], &rows[nrow][4]);
    assert_int_equal(k, 5);
    ++nrow;
  }
  free(copy);
  assert_true(header);
  return nrow;
}

static void test_cli_material(void **state) {
  (void)state;
  write_deck("deck.yaml", good_deck);
  run_result r;
  run_hugoniot("deck.yaml --material al --up 0.5,1,2", &r);
  if (r.status != 0) fprintf(stderr, "%s", r.err);
  assert_int_equal(r.status, 0);
  double rows[8][5];
  bool units_ok;
  assert_int_equal(parse_csv(r.out, rows, 8, &units_ok), 3);
  assert_true(units_ok);
  const double up[3] = {0.5, 1, 2};
  for (int i = 0; i < 3; ++i) {
    /* rows are printed with 10 significant digits: 1e-9 relative */
    assert_true(fabs(rows[i][0] - up[i]) < 1e-12);
    assert_true(fabs(rows[i][1] - (5.35 + 1.34 * up[i])) < 1e-9 * rows[i][1]);
    assert_true(fabs(rows[i][2] - 2.703 * rows[i][1] * up[i]) < 1e-9 * rows[i][2]);
    assert_true(fabs(rows[i][3] - 2.703 * rows[i][1] / (rows[i][1] - up[i])) < 1e-9 * rows[i][3]);
    assert_true(fabs(rows[i][4] - 0.5 * up[i] * up[i]) < 1e-9 * rows[i][4]);
  }
  /* the range form FIRST:LAST:COUNT */
  run_hugoniot("deck.yaml --material=b4c --up 1:3:5", &r);
  assert_int_equal(r.status, 0);
  assert_int_equal(parse_csv(r.out, rows, 8, &units_ok), 5);
  assert_true(fabs(rows[4][0] - 3.0) < 1e-12 && rows[4][1] > rows[3][1]);
}

static void test_cli_mixture(void **state) {
  (void)state;
  write_deck("deck.yaml", good_deck);
  run_result r1, r2;
  run_hugoniot("deck.yaml --mixture half --up 1,2", &r1);
  run_hugoniot("deck.yaml --mixture b4c:0.5,bn:0.5 --up 1,2", &r2);
  assert_int_equal(r1.status, 0);
  assert_int_equal(r2.status, 0);
  double a[4][5], b[4][5];
  bool u;
  assert_int_equal(parse_csv(r1.out, a, 4, &u), 2);
  assert_int_equal(parse_csv(r2.out, b, 4, &u), 2);
  for (int i = 0; i < 2; ++i) {
    assert_true(fabs(a[i][1] - b[i][1]) < 1e-9 * a[i][1]); /* deck mixture == inline spec */
    /* p = ρ0 D u with ρ0 = (2.51 + 2.29)/2 */
    assert_true(fabs(a[i][2] - 2.4 * a[i][1] * a[i][0]) < 1e-8 * a[i][2]);
  }
}

/* Broken decks: exit 2 and the error at DECK:LINE:COL; bad usage: exit 2; no solution: 1. */
static void test_cli_errors(void **state) {
  (void)state;
  run_result r;
  write_deck("bad.yaml", "materials:\n  - name: al\n    eos:\n      type: mg_linear\n"
                         "      rho0: -2.7\n      c0: 5.35\n      s: 1.34\n      gamma0: 2\n");
  run_hugoniot("bad.yaml --material al --up 1", &r);
  assert_int_equal(r.status, 2);
  assert_non_null(strstr(r.err, "bad.yaml:5:13: materials[0].eos.rho0: expected a number > 0"));
  assert_true(r.out[0] == '\0'); /* nothing on stdout */

  write_deck("typo.yaml", "materials:\n  - name: al\n    eos: {type: mg_linear, rho0: 2.7,\n"
                          "          c0: 5.35, s: 1.34, gama0: 2}\n");
  run_hugoniot("typo.yaml --material al --up 1", &r);
  assert_int_equal(r.status, 2);
  assert_non_null(strstr(r.err, "typo.yaml:4:"));
  assert_non_null(strstr(r.err, "unknown key 'gama0'"));

  write_deck("syntax.yaml", "materials:\n  - name: al\n    eos: {type: [\n");
  run_hugoniot("syntax.yaml --material al --up 1", &r);
  assert_int_equal(r.status, 2);
  assert_non_null(strstr(r.err, "syntax.yaml:"));

  write_deck("deck.yaml", good_deck);
  run_hugoniot("deck.yaml --material cu --up 1", &r);
  assert_int_equal(r.status, 2);
  assert_non_null(strstr(r.err, "no material 'cu' (known: al, b4c, bn, small)"));
  run_hugoniot("deck.yaml --material al --up 1,x", &r);
  assert_int_equal(r.status, 2);
  run_hugoniot("deck.yaml --material al --up -1", &r);
  assert_int_equal(r.status, 2);
  run_hugoniot("deck.yaml --material al", &r);
  assert_int_equal(r.status, 2);
  run_hugoniot("deck.yaml --material al --up 1 --bogus", &r);
  assert_int_equal(r.status, 2);
  run_hugoniot("missing.yaml --material al --up 1", &r);
  assert_int_equal(r.status, 2);
  assert_non_null(strstr(r.err, "missing.yaml"));
  run_hugoniot("--help", &r);
  assert_int_equal(r.status, 0);
  assert_non_null(strstr(r.out, "Usage: mscale hugoniot"));

  /* beyond the table no state exists: exit 1, the other rows printed */
  run_hugoniot("deck.yaml --material small --up 0.5,3", &r);
  assert_int_equal(r.status, 1);
  double rows[4][5];
  bool u;
  assert_int_equal(parse_csv(r.out, rows, 4, &u), 1);
  assert_non_null(strstr(r.err, "no shock state found for up = 3 km/s"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_cli_material),
      cmocka_unit_test(test_cli_mixture),
      cmocka_unit_test(test_cli_errors),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
