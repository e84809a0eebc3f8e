/* SPDX-License-Identifier: MIT */
/* Table readers (cold-curve and full (ρ, e) tables): formats, round trips through text and
 * HDF5, interpolation properties, and FILE:LINE errors for broken files (docs/eos.md). */
#include <math.h>

#include "eos_test_util.h"

static char tmpdir[256];

static int setup(void **state) {
  (void)state;
  eos_test_tmpdir(tmpdir, sizeof tmpdir);
  return 0;
}

static int teardown(void **state) {
  (void)state;
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
  return system(cmd) == 0 ? 0 : -1;
}

static void tmp_path(char *buf, size_t n, const char *name) {
  snprintf(buf, n, "%s/%s", tmpdir, name);
}

/* A small valid cold table: δ increasing, with a δ = 1 row, consistent with the MG cold form of
 * B4C (values computed from it, 8 digits). */
static const char *good_cold = "# test cold curve\n"
                               "delta rho eps_x P_x\n"
                               "0.9 2.259 0.43890007 -18.491141\n"
                               "1.0 2.51 0 0\n"
                               "1.1 2.761 0.38720588 22.880114\n"
                               "1.2 3.012 1.4717684 50.648186\n";

/* Returns the cold-table EOS for `text` (NULL on error) and leaves the messages in *e. */
static eos_t *cold_from_text(const char *name, const char *text, dk_errors *e, char *path,
                             size_t n) {
  tmp_path(path, n, name);
  eos_test_write(path, text);
  return eos_create_table_cold(path, 2.0, false, e);
}

static void expect_cold_error(const char *name, const char *text, int line, const char *needle) {
  dk_errors e;
  dk_errors_init(&e);
  char path[512], where[600];
  eos_t *eos = cold_from_text(name, text, &e, path, sizeof path);
  snprintf(where, sizeof where, "%s:%d:", path, line);
  if (eos || !has_error(&e, where) || !has_error(&e, needle)) {
    eos_test_dump(&e);
    fail_msg("%s: expected an error at %s containing '%s'", name, where, needle);
  }
  dk_errors_free(&e);
}

static void test_cold_table_good_and_broken(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  char path[512];
  eos_t *eos = cold_from_text("good.txt", good_cold, &e, path, sizeof path);
  if (!eos) eos_test_dump(&e);
  assert_non_null(eos);
  assert_true(eos_rho0(eos) == 2.51);
  assert_true(fabs(eos_cold_pressure(eos, 1.1) - 22.880114) < 1e-12);
  /* between nodes: the Hermite interpolant vs the exact MG cold curve it was sampled from
   * (h = 0.1: cubic error ~1e-4 relative) */
  double d = 1.05, n = 3.13, c0 = 9.06;
  double px = 2.51 * c0 * c0 / n * (pow(d, n) - 1.0);
  assert_true(fabs(eos_cold_pressure(eos, d) - px) < 1e-3 * fabs(px));
  eos_destroy(&eos);
  dk_errors_free(&e);

  /* truncated: the last row lost its P_x column */
  expect_cold_error("truncated.txt",
                    "delta rho eps_x P_x\n0.9 2.259 0.43890007 -18.491141\n1.0 2.51 0 0\n"
                    "1.1 2.761 0.38720588 22.880114\n1.2 3.012 1.4717684\n",
                    5, "expected 4 columns");
  /* non-monotone δ */
  expect_cold_error("order.txt",
                    "0.9 2.259 0.43890007 -18.491141\n1.0 2.51 0 0\n1.2 3.012 1.4717684 50.648186\n"
                    "1.1 2.761 0.38720588 22.880114\n",
                    4, "not strictly monotone");
  /* non-monotone P_x */
  expect_cold_error(
      "pmono.txt",
      "0.9 2.259 0.43890007 -18.491141\n1.0 2.51 0 0\n1.1 2.761 0.38720588 22.880114\n"
      "1.2 3.012 1.4717684 21.0\n",
      4, "P_x is not monotone");
  /* a word where a number belongs */
  expect_cold_error("word.txt",
                    "0.9 2.259 0.43890007 -18.491141\n1.0 2.51 zero 0\n1.1 2.761 0.92 23\n", 2,
                    "expected a finite number, found 'zero'");
  /* no reference row δ = 1 */
  expect_cold_error("noref.txt",
                    "0.9 2.259 0.43890007 -18.491141\n1.1 2.761 0.38720588 22.880114\n"
                    "1.2 3.012 1.4717684 50.648186\n",
                    3, "no reference row");
  /* δ and ρ/ρ0 disagree */
  expect_cold_error(
      "mismatch.txt",
      "0.9 2.259 0.43890007 -18.491141\n1.0 2.51 0 0\n1.1 2.861 0.38720588 22.880114\n"
      "1.2 3.012 1.4717684 50.648186\n",
      3, "does not match delta");
  /* negative density */
  expect_cold_error(
      "negrho.txt",
      "0.9 -2.259 0.43890007 -18.491141\n1.0 2.51 0 0\n1.1 2.761 0.38720588 22.880114\n", 1,
      "rho must be > 0");
  /* ε_x inconsistent with P_x: the interpolated P_x overshoots */
  expect_cold_error("inconsistent.txt",
                    "0.9 2.259 0.43890007 -18.491141\n1.0 2.51 0 0\n1.1 2.761 3.0 22.880114\n"
                    "1.2 3.012 3.1 50.648186\n",
                    3, "inconsistent");
  /* empty file */
  expect_cold_error("empty.txt", "# nothing here\n", 1, "no data rows");

  /* missing file */
  dk_errors_init(&e);
  tmp_path(path, sizeof path, "does_not_exist.txt");
  assert_null(eos_create_table_cold(path, 2.0, false, &e));
  assert_true(has_error(&e, path) && has_error(&e, "cannot open"));
  dk_errors_free(&e);
}

/* ---- Full (ρ, e) tables ---------------------------------------------------------------------- */

static void test_full_table_roundtrip(void **state) {
  (void)state;
  eos_t *pb = eos_create_mg_cold(11.34, 1.972, 3.0, 2.0, false);
  eos_t *t = eos_create_table_from(pb, 9.0, 16.0, 71, 0.0, 5.0, 23);
  assert_non_null(t);
  assert_int_equal(eos_get_kind(t), EOS_TABLE_FULL);
  const char *names[2] = {"pb_table.txt", "pb_table.h5"};
  for (int k = 0; k < 2; ++k) {
    char path[512];
    tmp_path(path, sizeof path, names[k]);
    assert_int_equal(eos_table_write(t, path), MS_OK);
    dk_errors e;
    dk_errors_init(&e);
    eos_t *r = eos_create_table_full(path, &e);
    if (!r) eos_test_dump(&e);
    assert_non_null(r);
    assert_true(eos_rho0(r) == 11.34);
    /* %.17g text and binary HDF5 are exact: the same interpolant to round-off */
    for (int i = 0; i < 50; ++i) {
      double rho = 9.0 + 7.0 * (i + 0.31) / 50, e = 5.0 * ((i * 7) % 50 + 0.5) / 50;
      assert_true(fabs(eos_pressure(r, rho, e) - eos_pressure(t, rho, e)) <=
                  1e-13 * fabs(eos_pressure(t, rho, e)) + 1e-13);
      assert_true(fabs(eos_sound_speed(r, rho, e) - eos_sound_speed(t, rho, e)) <= 1e-13);
    }
    eos_destroy(&r);
    dk_errors_free(&e);
  }
  eos_destroy(&t);
  eos_destroy(&pb);
}

/* Interpolation: exact at nodes, monotone in ρ, O(h²) in P and O(h²) in the nodal c², NaN
 * outside; the cold curve of a table is its isentrope through (ρ0, 0). */
static void test_full_table_interpolation(void **state) {
  (void)state;
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  eos_t *t = eos_create_table_from(al, 2.2, 6.2, 201, -0.05, 9.0, 51); /* h_ρ = 0.02 */
  assert_non_null(t);
  /* nodes */
  assert_true(fabs(eos_pressure(t, 3.0, 1.0) - eos_pressure(al, 3.0, 1.0)) < 1e-12);
  /* between nodes: bilinear error ≤ h²/8 |P_ρρ| (P is linear in e); measured max 5.6e-4
   * relative for P (at high compression, where |P_ρρ| is largest) and 5e-5 for c; 1e-3. */
  double pmax_err = 0.0, cmax_err = 0.0, prev = -INFINITY;
  for (int i = 0; i <= 1000; ++i) {
    double rho = 2.2 + 4.0 * i / 1000.0, e = 1.234;
    double p = eos_pressure(t, rho, e), pa = eos_pressure(al, rho, e);
    assert_true(p >= prev); /* monotone in ρ */
    prev = p;
    pmax_err = fmax(pmax_err, fabs(p - pa) / (fabs(pa) + 1.0));
    cmax_err = fmax(cmax_err, fabs(eos_sound_speed(t, rho, e) - eos_sound_speed(al, rho, e)) /
                                  eos_sound_speed(al, rho, e));
  }
  print_message("full table h_rho = 0.02: max rel. error P %.2e, c %.2e\n", pmax_err, cmax_err);
  assert_true(pmax_err < 1e-3 && cmax_err < 1e-3);
  /* outside: NaN and MS_ERR_UNSTABLE */
  assert_true(isnan(eos_pressure(t, 6.5, 1.0)) && isnan(eos_pressure(t, 2.1, 1.0)) &&
              isnan(eos_pressure(t, 3.0, 9.5)));
  double rho[2] = {3.0, 7.0}, e[2] = {1.0, 1.0}, p[2];
  size_t bad = 9;
  assert_int_equal(eos_eval(t, 2, rho, e, p, NULL, &bad), MS_ERR_UNSTABLE);
  assert_int_equal(bad, 1);
  /* cold curve: the table's isentrope ≈ the analytic one (interpolation error O(h²)) */
  double dmin, dmax;
  assert_true(eos_cold_range(t, &dmin, &dmax));
  /* the isentrope leaves the table where its energy passes e_max = 9 (δ ≈ 1.87) */
  assert_true(dmin < 0.85 && dmax > 1.8 && dmax < 1.9);
  assert_true(isnan(eos_cold_pressure(t, dmax + 0.01)));
  for (double d = 0.85; d < dmax; d += 0.1)
    assert_true(fabs(eos_cold_pressure(t, d) - eos_cold_pressure(al, d)) <
                1e-3 * (fabs(eos_cold_pressure(al, d)) + 1.0));
  eos_destroy(&t);
  eos_destroy(&al);
}

static void expect_full_error(const char *name, const char *text, int line, const char *needle) {
  char path[512], where[600];
  tmp_path(path, sizeof path, name);
  eos_test_write(path, text);
  dk_errors e;
  dk_errors_init(&e);
  eos_t *eos = eos_create_table_full(path, &e);
  snprintf(where, sizeof where, "%s:%d:", path, line);
  if (eos || !has_error(&e, where) || !has_error(&e, needle)) {
    eos_test_dump(&e);
    fail_msg("%s: expected an error at %s containing '%s'", name, where, needle);
  }
  dk_errors_free(&e);
}

static void test_full_table_broken(void **state) {
  (void)state;
  const char *head = "# rho0: 1.0\nrho e P\n"; /* lines 1-2 */
  char text[1024];
  /* good 2 x 3 */
  snprintf(text, sizeof text, "%s1 0 1\n1 1 2\n1 2 3\n2 0 4\n2 1 5\n2 2 6\n", head);
  char path[512];
  tmp_path(path, sizeof path, "full_good.txt");
  eos_test_write(path, text);
  dk_errors e;
  dk_errors_init(&e);
  eos_t *ok = eos_create_table_full(path, &e);
  if (!ok) eos_test_dump(&e);
  assert_non_null(ok);
  assert_true(fabs(eos_pressure(ok, 1.5, 0.5) - 3.0) < 1e-14); /* bilinear: 1.5·... = 3 */
  eos_destroy(&ok);
  dk_errors_free(&e);
  /* truncated: the last row is missing */
  snprintf(text, sizeof text, "%s1 0 1\n1 1 2\n1 2 3\n2 0 4\n2 1 5\n", head);
  expect_full_error("full_trunc.txt", text, 7, "not a rectangular");
  /* truncated inside a row */
  snprintf(text, sizeof text, "%s1 0 1\n1 1 2\n1 2 3\n2 0 4\n2 1 5\n2 2\n", head);
  expect_full_error("full_trunc2.txt", text, 8, "expected 3 columns");
  /* P decreasing with ρ */
  snprintf(text, sizeof text, "%s1 0 1\n1 1 2\n1 2 3\n2 0 4\n2 1 1.5\n2 2 6\n", head);
  expect_full_error("full_mono.txt", text, 7, "not monotone in rho");
  /* a different e grid in the second group */
  snprintf(text, sizeof text, "%s1 0 1\n1 1 2\n1 2 3\n2 0 4\n2 1.5 5\n2 2 6\n", head);
  expect_full_error("full_egrid.txt", text, 7, "the same e values");
  /* no reference density */
  expect_full_error("full_norho0.txt", "1 0 1\n1 1 2\n2 0 4\n2 1 5\n", 1, "rho0");
  /* non-positive sound speed column */
  snprintf(text, sizeof text, "# rho0: 1\n1 0 1 1\n1 1 2 1\n2 0 4 -1\n2 1 5 1\n");
  expect_full_error("full_c.txt", text, 4, "sound speed must be > 0");
  /* HDF5 tables with wrong shapes or axes */
  {
    const double rho3[3] = {1, 2, 3}, rho_bad[3] = {1, 3, 2}, e2[2] = {0, 1}, P4[4] = {1, 2, 4, 5};
    const double P6[6] = {1, 2, 4, 5, 7, 8}, rho0 = 1.0;
    struct {
      const char *name;
      const double *rho, *P;
      size_t pr;
      const char *needle;
    } cases[] = {
        {"h5_shape.h5", rho3, P4, 2, "inconsistent table shapes"},
        {"h5_axis.h5", rho_bad, P6, 3, "rho axis must be positive and strictly increasing"}};
    for (int k = 0; k < 2; ++k) {
      tmp_path(path, sizeof path, cases[k].name);
      ms_h5 *h = ms_h5_create(path);
      assert_non_null(h);
      assert_int_equal(ms_h5_write_doubles(h, "rho", 3, 0, cases[k].rho, "g/cm^3"), MS_OK);
      assert_int_equal(ms_h5_write_doubles(h, "e", 2, 0, e2, "kJ/g"), MS_OK);
      assert_int_equal(ms_h5_write_doubles(h, "P", cases[k].pr, 2, cases[k].P, "GPa"), MS_OK);
      assert_int_equal(ms_h5_write_doubles(h, "rho0", 1, 0, &rho0, "g/cm^3"), MS_OK);
      assert_int_equal(ms_h5_close(h), MS_OK);
      dk_errors_init(&e);
      assert_null(eos_create_table_full(path, &e));
      if (!has_error(&e, path) || !has_error(&e, cases[k].needle)) {
        eos_test_dump(&e);
        fail_msg("%s: expected '%s'", cases[k].name, cases[k].needle);
      }
      dk_errors_free(&e);
    }
  }
  /* HDF5 file that does not exist */
  dk_errors_init(&e);
  tmp_path(path, sizeof path, "missing.h5");
  assert_null(eos_create_table_full(path, &e));
  assert_true(e.n > 0);
  dk_errors_free(&e);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_cold_table_good_and_broken),
      cmocka_unit_test(test_full_table_roundtrip),
      cmocka_unit_test(test_full_table_interpolation),
      cmocka_unit_test(test_full_table_broken),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
