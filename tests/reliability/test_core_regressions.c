/* SPDX-License-Identifier: MIT */
/* Regression tests for core bugs found by fuzzing (docs/reliability.md, "Findings").
 * Each test names the fuzz harness and the crash input kept under crashes/<harness>/. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "core.h"

#include <hdf5.h>

static bool has_error(const dk_errors *e, const char *needle) {
  for (size_t i = 0; i < e->n; i++)
    if (strstr(e->msg[i], needle)) return true;
  return false;
}

static char *scratch(const char *name) {
  const char *dir = getenv("TMPDIR");
  char *p = malloc(4096);
  snprintf(p, 4096, "%s/mscale-rel-%ld-%s", dir && dir[0] ? dir : "/tmp", (long)getpid(), name);
  return p;
}

static void write_text(const char *path, const char *text, size_t n) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  assert_int_equal(fwrite(text, 1, n, f), n);
  fclose(f);
}

/* fuzz_deck, crashes/fuzz_deck/empty-anchored-key-resolved.yaml: the resolved deck wrote map
 * keys verbatim, so an empty key (`{&a : x}`), a key holding ": " or "#", or values with
 * characters YAML cannot hold verbatim (DEL, NEL, U+2028) came back as a syntax error or as
 * different text. The resolved deck must load again with the same keys and values. */
static void test_resolved_deck_round_trip(void **state) {
  (void)state;
  const char *text = "\"\": 1\n"
                     "\"a: b\": 2\n"
                     "\"c #d\": 3\n"
                     "\"-e\": 4\n"
                     "\"sp \": \"x \"\n"
                     "del: \"\\x7f\"\n"
                     "nel: \"a\\Nb\"\n"
                     "ls: \"a\\Lb\"\n"
                     "bom: \"\\uFEFF\"\n"
                     "tab: \"\\t\"\n"
                     "utf8: \"сталь µs\"\n"
                     "nested: {\"k: v\": [\"\", \"#\", {\"\": \"\"}]}\n"
                     "\"... n\": \"...\"\n"; /* '...' at a line start ends the document */
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string(text, "t.yaml", &e);
  assert_non_null(doc);
  assert_int_equal(e.n, 0);
  char *path = scratch("resolved.yaml");
  assert_int_equal(dk_write_resolved(doc, path), MS_OK);
  dk_doc *again = dk_load(path, &e);
  dk_errors_print(&e, stderr);
  assert_non_null(again);
  assert_int_equal(e.n, 0);
  const dk_node *r1 = dk_root(doc), *r2 = dk_root(again);
  assert_int_equal(dk_map_len(r1), dk_map_len(r2));
  for (size_t i = 0; i < dk_map_len(r1); i++) {
    assert_string_equal(dk_map_key(r1, i), dk_map_key(r2, i));
    const char *v1 = dk_scalar(dk_map_value(r1, i)), *v2 = dk_scalar(dk_map_value(r2, i));
    if (v1) assert_string_equal(v1, v2);
  }
  const dk_node *n1 = dk_get(dk_get(r1, "nested"), "k: v"),
                *n2 = dk_get(dk_get(r2, "nested"), "k: v");
  assert_int_equal(dk_seq_len(n2), 3);
  assert_string_equal(dk_scalar(dk_seq_at(n1, 1)), dk_scalar(dk_seq_at(n2, 1)));
  assert_string_equal(dk_map_key(dk_seq_at(n2, 2), 0), "");
  remove(path);
  free(path);
  dk_free(again);
  dk_free(doc);
  dk_errors_free(&e);
}

/* fuzz_table, crashes/fuzz_table/separator-row-min-cols-0.csv: a row of separators only
 * (",,,,") was a data row with zero columns, accepted as a 0-column table; text after a NUL
 * byte was silently dropped; a file without line breaks was read into one unbounded line. */
static void test_table_separator_rows_skipped(void **state) {
  (void)state;
  char *path = scratch("sep.csv");
  const char *text = "x,y\n,,,\n1,2\n ; ,\n3,4\n,,\n";
  write_text(path, text, strlen(text));
  dk_errors e;
  dk_errors_init(&e);
  double *t;
  size_t nr, nc;
  assert_int_equal(ms_read_table(path, 0, &t, &nr, &nc, &e), MS_OK);
  assert_int_equal(nr, 2);
  assert_int_equal(nc, 2);
  assert_true(t[0] == 1 && t[3] == 4);
  free(t);
  /* nothing but separators: no data rows */
  write_text(path, ",,,\n;;\n", 7);
  assert_int_equal(ms_read_table(path, 0, &t, &nr, &nc, &e), MS_ERR_INPUT);
  assert_true(has_error(&e, "no data rows"));
  remove(path);
  free(path);
  dk_errors_free(&e);
}

static void test_table_nul_byte_is_an_error(void **state) {
  (void)state;
  char *path = scratch("nul.csv");
  const char text[] = "1 2\n3 4\n5\0 6\n";
  write_text(path, text, sizeof text - 1);
  dk_errors e;
  dk_errors_init(&e);
  double *t;
  size_t nr, nc;
  assert_int_equal(ms_read_table(path, 2, &t, &nr, &nc, &e), MS_ERR_INPUT);
  dk_errors_print(&e, stderr);
  char where[4200];
  snprintf(where, sizeof where, "%s:3:2: a NUL byte", path);
  assert_true(has_error(&e, where));
  /* a non-finite value is reported at its own column, with the value */
  write_text(path, "1 2\n3   inf\n", 11);
  assert_int_equal(ms_read_table(path, 2, &t, &nr, &nc, &e), MS_ERR_INPUT);
  snprintf(where, sizeof where, "%s:2:5: column 2 is not a finite number (inf)", path);
  assert_true(has_error(&e, where));
  remove(path);
  free(path);
  dk_errors_free(&e);
}

static void test_table_line_too_long(void **state) {
  (void)state;
  char *path = scratch("long.csv");
  size_t n = 200000;
  char *text = malloc(n);
  for (size_t i = 0; i < n; i++) text[i] = i % 2 ? ' ' : '1';
  write_text(path, text, n);
  free(text);
  dk_errors e;
  dk_errors_init(&e);
  double *t;
  size_t nr, nc;
  assert_int_equal(ms_read_table(path, 1, &t, &nr, &nc, &e), MS_ERR_INPUT);
  assert_true(has_error(&e, ":1:1: line longer than"));
  /* /dev/zero has neither line breaks nor an end: the reader must stop on its own */
  dk_errors_free(&e);
  assert_int_equal(ms_read_table("/dev/zero", 1, &t, &nr, &nc, &e), MS_ERR_INPUT);
  assert_true(has_error(&e, "/dev/zero:1:1: line longer than"));
  remove(path);
  free(path);
  dk_errors_free(&e);
}

/* fuzz_h5, crashes/fuzz_h5/huge-declared-chunked.bin: a chunked dataset declaring 2^30 x 8
 * values with nothing stored made ms_h5_read_doubles calloc 8 GiB (abort instead of exit 2).
 * Now the stored size is checked against the shape before allocating. */
static void test_h5_declared_size_not_stored(void **state) {
  (void)state;
  char *path = scratch("huge.h5");
  hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  assert_true(f >= 0);
  hsize_t big[2] = {(hsize_t)1 << 30, 8}, chunk[2] = {4, 1}, small[1] = {3};
  hid_t space = H5Screate_simple(2, big, NULL), dcpl = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(dcpl, 2, chunk);
  hid_t ds = H5Dcreate2(f, "P", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  assert_true(ds >= 0);
  H5Dclose(ds);
  H5Pclose(dcpl);
  H5Sclose(space);
  /* a normal dataset next to it still reads */
  double v[3] = {1, 2, 3};
  space = H5Screate_simple(1, small, NULL);
  ds = H5Dcreate2(f, "rho", H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v);
  H5Dclose(ds);
  H5Sclose(space);
  H5Fclose(f);

  dk_errors e;
  dk_errors_init(&e);
  ms_h5r *h = ms_h5_open_read(path, &e);
  assert_non_null(h);
  double *data;
  size_t n0, n1;
  assert_int_equal(ms_h5_read_doubles(h, "P", &data, &n0, &n1, &e), MS_ERR_INPUT);
  assert_null(data);
  dk_errors_print(&e, stderr);
  assert_true(has_error(&e, "dataset 'P' of shape [1073741824][8] stores only 0 of its"));
  assert_int_equal(ms_h5_read_doubles(h, "rho", &data, &n0, &n1, &e), MS_OK);
  assert_int_equal(n0, 3);
  assert_int_equal(n1, 1);
  assert_true(data[2] == 3);
  free(data);
  ms_h5_close_read(h);
  remove(path);
  free(path);
  dk_errors_free(&e);
}

/* Bad-input corpus, bad/inf_in_deck.yaml: 1e999 was reported as "expected a number" (strtod's
 * ERANGE); a value that overflows only on unit conversion (1e305 s in an SI deck) was accepted
 * as infinity by readers without an upper bound. */
static void test_deck_number_out_of_range(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc =
      dk_load_string("units: si\nbig: 1e999\ntiny: 1e-400\nlong: 1e305\nok: 2e-5\n", "r.yaml", &e);
  assert_non_null(doc);
  dk_read_units(doc, &e);
  double v;
  const dk_node *root = dk_root(doc);
  assert_false(dk_read_double(&e, doc, root, "big", MS_DIM_NONE, true, 0, -INFINITY, INFINITY, &v));
  assert_false(
      dk_read_double(&e, doc, root, "tiny", MS_DIM_NONE, true, 0, -INFINITY, INFINITY, &v));
  assert_false(dk_read_positive(&e, doc, root, "long", MS_DIM_TIME, true, 0, &v));
  assert_true(dk_read_positive(&e, doc, root, "ok", MS_DIM_TIME, true, 0, &v));
  assert_true(fabs(v - 2.0) < 1e-12); /* 2e-5 s = 2 x 10 us */
  dk_errors_print(&e, stderr);
  assert_int_equal(e.n, 3);
  assert_true(has_error(&e, "r.yaml:2:6: big: '1e999' is outside the range of a double"));
  assert_true(has_error(&e, "r.yaml:3:7: tiny: '1e-400' is outside the range"));
  assert_true(has_error(&e, "r.yaml:4:7: long: '1e305' is outside the range of a double-precision "
                            "number once converted to internal units"));
  dk_free(doc);
  dk_errors_free(&e);
}

/* fuzz_deck, crashes/fuzz_deck/alias-bomb-timeout.yaml: a "billion laughs" deck was expanded
 * up to the 10^6-node limit before being refused (> 10 s and ~1 GB under ASan). Copies made
 * through aliases now have a budget of their own (10^4 nodes); ordinary reuse still works. */
static void test_alias_expansion_budget(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  /* 10 x 10 x 10 x 10 = 10^4 copies of the leaf, plus the lists holding them: over budget */
  const char *bomb = "a: &a [x, x, x, x, x, x, x, x, x, x]\n"
                     "b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a]\n"
                     "c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b, *b]\n"
                     "d: [*c, *c, *c, *c, *c, *c, *c, *c, *c, *c]\n";
  assert_null(dk_load_string(bomb, "bomb.yaml", &e));
  dk_errors_print(&e, stderr);
  /* located at the copied node's anchor (libyaml does not keep where an alias was used) */
  assert_true(has_error(&e, "bomb.yaml:1:11: the deck nests deeper than 64 levels, expands to more "
                            "than 1000000 nodes, or copies more than 10000 nodes through aliases"));
  dk_errors_free(&e);
  /* one level less (about 10^3 copies) is a legitimate, if odd, deck */
  const char *reuse = "eos: &al {type: mg_linear, rho0: 2.703}\n"
                      "a: &a [x, x, x, x, x, x, x, x, x, x]\n"
                      "b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a]\n"
                      "c: [*b, *b, *b, *b, *b, *b, *b, *b, *b, *b]\n"
                      "materials: [{name: x, eos: *al}, {name: y, eos: *al}]\n";
  dk_doc *doc = dk_load_string(reuse, "reuse.yaml", &e);
  assert_non_null(doc);
  assert_int_equal(e.n, 0);
  const dk_node *c = dk_get(dk_root(doc), "c");
  assert_int_equal(dk_seq_len(c), 10);
  assert_int_equal(dk_seq_len(dk_seq_at(dk_seq_at(c, 9), 9)), 10);
  const dk_node *y = dk_seq_at(dk_get(dk_root(doc), "materials"), 1);
  assert_string_equal(dk_scalar(dk_get(dk_get(y, "eos"), "rho0")), "2.703");
  dk_free(doc);
  dk_errors_free(&e);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_resolved_deck_round_trip),
      cmocka_unit_test(test_table_separator_rows_skipped),
      cmocka_unit_test(test_table_nul_byte_is_an_error),
      cmocka_unit_test(test_table_line_too_long),
      cmocka_unit_test(test_h5_declared_size_not_stored),
      cmocka_unit_test(test_deck_number_out_of_range),
      cmocka_unit_test(test_alias_expansion_budget),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
