/* SPDX-License-Identifier: MIT */
/* Deck reader: positions in messages, every error collected, unknown keys, defaults written
 * back, unit conversion. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core.h"
#include "test_util.h"

static void dump(const dk_errors *e) { dk_errors_print(e, stderr); }

static void test_values_and_positions(void **state) {
  (void)state;
  const char *text = "units: internal\n"
                     "block:\n"
                     "  rho: 2.7\n"
                     "  n: 12\n"
                     "  flag: yes\n"
                     "  name: al\n"
                     "  list: [1, 2.5, 3e-1]\n";
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string(text, "t.yaml", &e);
  assert_non_null(doc);
  dk_read_units(doc, &e);
  const dk_node *b = dk_get(dk_root(doc), "block");
  double rho, missing_default;
  long n;
  bool flag;
  const char *name;
  double *list;
  size_t nl;
  assert_true(dk_read_positive(&e, doc, b, "rho", MS_DIM_DENSITY, true, 0, &rho));
  assert_true(dk_read_int(&e, doc, b, "n", true, 0, 1, 100, &n));
  assert_true(dk_read_bool(&e, doc, b, "flag", true, false, &flag));
  assert_true(dk_read_string(&e, doc, b, "name", true, NULL, &name));
  assert_true(dk_read_double_list(&e, doc, b, "list", MS_DIM_NONE, true, &list, &nl));
  assert_true(
      dk_read_double(&e, doc, b, "gamma", MS_DIM_NONE, false, 1.4, 1.0, 3.0, &missing_default));
  dk_report_unused(&e, doc);
  dump(&e);
  assert_int_equal(e.n, 0);
  assert_true(rho == 2.7 && n == 12 && flag && !strcmp(name, "al"));
  assert_int_equal(nl, 3);
  assert_true(list[2] == 0.3);
  assert_true(missing_default == 1.4);
  free(list);
  dk_free(doc);
  dk_errors_free(&e);
}

/* Every problem is reported at its own line and column, not only the first one. */
static void test_all_errors_with_lines(void **state) {
  (void)state;
  const char *text = "block:\n"         /* line 1 */
                     "  rho: -2.7\n"    /* line 2: negative density */
                     "  n: twelve\n"    /* line 3: not an integer */
                     "  rh0: 1\n"       /* line 4: typo (c0 is the missing key) */
                     "  kind: squre\n"; /* line 5: not one of the choices */
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string(text, "bad.yaml", &e);
  assert_non_null(doc);
  const dk_node *b = dk_get(dk_root(doc), "block");
  double rho, c0;
  long n;
  int kind;
  static const char *const kinds[] = {"square", "circle", NULL};
  assert_false(dk_read_positive(&e, doc, b, "rho", MS_DIM_DENSITY, true, 0, &rho));
  assert_false(dk_read_int(&e, doc, b, "n", true, 0, 1, 100, &n));
  assert_false(dk_read_positive(&e, doc, b, "c0", MS_DIM_VELOCITY, true, 0, &c0));
  assert_false(dk_read_enum(&e, doc, b, "kind", true, 0, kinds, &kind));
  dk_report_unused(&e, doc);
  dump(&e);
  assert_int_equal(e.n, 5);
  assert_true(has_error(&e, "bad.yaml:2:8: block.rho: expected a number > 0, found -2.7"));
  assert_true(has_error(&e, "bad.yaml:3:6: block.n: expected an integer, found 'twelve'"));
  assert_true(has_error(&e, "bad.yaml:1:1: block: missing required key 'c0'"));
  assert_true(has_error(&e, "bad.yaml:5:9: block.kind: expected one of: square, circle"));
  assert_true(has_error(&e, "bad.yaml:4:8: block: unknown key 'rh0' (did you mean 'c0'?)"));
  dk_free(doc);
  dk_errors_free(&e);
}

static void test_syntax_error_position(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string("a: 1\nb: [1, 2\nc: 3\n", "syn.yaml", &e);
  assert_null(doc);
  dump(&e);
  assert_int_equal(e.n, 1);
  assert_true(has_error(&e, "syn.yaml:3:"));
  assert_true(has_error(&e, "YAML syntax error"));
  dk_errors_free(&e);
  /* duplicate keys are a mistake YAML parsers let through */
  dk_errors_init(&e);
  doc = dk_load_string("a: 1\na: 2\n", "dup.yaml", &e);
  assert_true(has_error(&e, "dup.yaml:2:1: deck: key 'a' appears twice"));
  dk_free(doc);
  dk_errors_free(&e);
}

/* An alias bomb must be refused, not expanded into gigabytes. */
static void test_alias_bomb(void **state) {
  (void)state;
  const char *text = "a: &a [x, x, x, x, x, x, x, x, x, x]\n"
                     "b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a]\n"
                     "c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b, *b]\n"
                     "d: &d [*c, *c, *c, *c, *c, *c, *c, *c, *c, *c]\n"
                     "e: &e [*d, *d, *d, *d, *d, *d, *d, *d, *d, *d]\n"
                     "f: &f [*e, *e, *e, *e, *e, *e, *e, *e, *e, *e]\n";
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string(text, "bomb.yaml", &e);
  assert_null(doc);
  assert_true(has_error(&e, "expands to more than"));
  dk_errors_free(&e);
}

/* SI decks are converted on reading: 2700 kg/m^3 = 2.7 g/cm^3, 5350 m/s = 5.35 km/s,
 * 1 GPa = 1e9 Pa, 1 us = 0.1 (10 us). Exact up to the last bit of the factors. */
static void test_si_units(void **state) {
  (void)state;
  const char *text = "units: si\nm:\n  rho: 2700\n  c: 5350\n  p: 1.0e9\n  t: 1.0e-6\n";
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string(text, "si.yaml", &e);
  dk_read_units(doc, &e);
  const dk_node *m = dk_get(dk_root(doc), "m");
  double rho, c, p, t;
  dk_read_positive(&e, doc, m, "rho", MS_DIM_DENSITY, true, 0, &rho);
  dk_read_positive(&e, doc, m, "c", MS_DIM_VELOCITY, true, 0, &c);
  dk_read_positive(&e, doc, m, "p", MS_DIM_PRESSURE, true, 0, &p);
  dk_read_positive(&e, doc, m, "t", MS_DIM_TIME, true, 0, &t);
  assert_int_equal(e.n, 0);
  assert_true(fabs(rho - 2.7) < 1e-15 && fabs(c - 5.35) < 1e-15);
  assert_true(fabs(p - 1.0) < 1e-15 && fabs(t - 0.1) < 1e-16);
  dk_free(doc);
  dk_errors_free(&e);
}

/* The resolved deck shows defaults and parses back to the same values. */
static void test_resolved_deck(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string("m:\n  name: \"a: b\"\n", "r.yaml", &e);
  const dk_node *m = dk_get(dk_root(doc), "m");
  double g;
  const char *name;
  dk_read_double(&e, doc, m, "gamma", MS_DIM_NONE, false, 1.4, 1, 3, &g);
  dk_read_string(&e, doc, m, "name", true, NULL, &name);
  char path[] = "/tmp/mscale_test_resolved_XXXXXX";
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  assert_int_equal(dk_write_resolved(doc, path), MS_OK);
  dk_doc *back = dk_load(path, &e);
  assert_non_null(back);
  const dk_node *mb = dk_get(dk_root(back), "m");
  double g2;
  const char *name2;
  assert_true(dk_read_double(&e, back, mb, "gamma", MS_DIM_NONE, true, 0, 1, 3, &g2));
  assert_true(dk_read_string(&e, back, mb, "name", true, NULL, &name2));
  assert_true(g2 == 1.4);
  assert_string_equal(name2, "a: b");
  dump(&e);
  assert_int_equal(e.n, 0);
  remove(path);
  dk_free(back);
  dk_free(doc);
  dk_errors_free(&e);
}

/* Errors print sorted by file (first mention), line and column; a message recorded twice (two
 * readers checking the same node) is kept once. */
static void test_errors_sorted_once(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string("a: 1\nb: 2\nc: 3\n", "s.yaml", &e);
  const dk_node *root = dk_root(doc);
  dk_error(&e, doc, dk_get(root, "c"), "third");
  dk_error_at(&e, "table.csv", 4, 1, "in a data file");
  dk_error(&e, doc, dk_get(root, "a"), "first");
  dk_error(&e, doc, dk_get(root, "c"), "third"); /* the same message again */
  dk_error(&e, doc, NULL, "whole file");
  dk_error(&e, doc, dk_get(root, "b"), "second");
  assert_int_equal(e.n, 6);                 /* every error counts (readers compare counts) */
  assert_int_equal(dk_errors_count(&e), 5); /* the repeat is not printed */
  char buf[1024] = "";
  FILE *f = fmemopen(buf, sizeof buf, "w");
  assert_non_null(f);
  dk_errors_print(&e, f);
  fclose(f);
  assert_string_equal(buf, "s.yaml: whole file\n"
                           "s.yaml:1:4: first\n"
                           "s.yaml:2:4: second\n"
                           "s.yaml:3:4: third\n"
                           "table.csv:4:1: in a data file\n");
  dk_free(doc);
  dk_errors_free(&e);
}

/* A required key that is missing beside its misspelling is one message, in either order. */
static void test_misspelt_required_key(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string("m:\n  gama: 1.4\n  q: 2\n", "t.yaml", &e);
  const dk_node *m = dk_get(dk_root(doc), "m");
  double g, r;
  assert_false(dk_read_double(&e, doc, m, "gamma", MS_DIM_NONE, true, 0, 1, 3, &g));
  assert_false(dk_read_double(&e, doc, m, "rho", MS_DIM_NONE, true, 0, 0, 3, &r));
  dk_mark_used(m, "q");
  dk_report_unused(&e, doc);
  assert_int_equal(e.n, 3);
  assert_int_equal(dk_errors_count(&e), 2);
  char buf[1024] = "";
  FILE *f = fmemopen(buf, sizeof buf, "w");
  dk_errors_print(&e, f);
  fclose(f);
  assert_string_equal(buf, "t.yaml:1:1: m: missing required key 'rho' (a number in [0, 3])\n"
                           "t.yaml:2:9: m: unknown key 'gama' (did you mean 'gamma'?)\n");
  dk_free(doc);
  dk_errors_free(&e);
}

/* dk_suggest: close names only, never the word itself. */
static void test_suggest(void **state) {
  (void)state;
  static const char *const names[] = {"planar", "cylindrical", "spherical", "check", NULL};
  assert_string_equal(dk_suggest("planer", names), "planar");
  assert_string_equal(dk_suggest("chek", names), "check");
  assert_null(dk_suggest("planar", names));
  assert_null(dk_suggest("xyz", names));
  assert_null(dk_suggest("ab", names));
}

/* --set overrides: a new key, a list item, a replaced mapping, and messages naming them. */
static void test_set_overrides(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string("m:\n  x: 1\n  l: [1, 2, 3]\n", "o.yaml", &e);
  assert_true(dk_set(doc, "m.x", "2.5", &e));
  assert_true(dk_set(doc, "m.l[2]", "7", &e));
  assert_true(dk_set(doc, "m.new.deep", "[4, 5]", &e));
  assert_false(dk_set(doc, "m.l[3]", "1", &e));
  assert_false(dk_set(doc, "m.x.y", "1", &e));
  assert_false(dk_set(doc, "m.", "1", &e));
  const dk_node *m = dk_get(dk_root(doc), "m");
  double x, *l = NULL, *deep = NULL;
  size_t nl = 0, nd = 0;
  assert_true(dk_read_double(&e, doc, m, "x", MS_DIM_NONE, true, 0, 0, 10, &x));
  assert_true(x == 2.5);
  assert_true(dk_read_double_list(&e, doc, m, "l", MS_DIM_NONE, true, &l, &nl));
  assert_int_equal(nl, 3);
  assert_true(l[2] == 7.0);
  assert_true(
      dk_read_double_list(&e, doc, dk_get(m, "new"), "deep", MS_DIM_NONE, true, &deep, &nd));
  assert_int_equal(nd, 2);
  assert_true(deep[1] == 5.0);
  assert_int_equal(e.n, 3);
  assert_true(has_error(&e, "--set m.l[3]=1: m.l (line 3 of o.yaml) has no item [3]"));
  assert_true(has_error(&e, "--set m.x.y=1: m.x (from --set m.x=2.5) is not a mapping"));
  assert_true(has_error(&e, "--set m.=1: the key path ends with '.'"));
  /* a bad value is reported at the override */
  assert_true(dk_set(doc, "m.x", "abc", &e));
  assert_false(dk_read_double(&e, doc, m, "x", MS_DIM_NONE, true, 0, 0, 10, &x));
  assert_true(has_error(&e, "--set m.x=abc: m.x: expected a number"));
  free(l);
  free(deep);
  dk_free(doc);
  dk_errors_free(&e);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_values_and_positions),
                                     cmocka_unit_test(test_all_errors_with_lines),
                                     cmocka_unit_test(test_syntax_error_position),
                                     cmocka_unit_test(test_alias_bomb),
                                     cmocka_unit_test(test_si_units),
                                     cmocka_unit_test(test_resolved_deck),
                                     cmocka_unit_test(test_errors_sorted_once),
                                     cmocka_unit_test(test_suggest),
                                     cmocka_unit_test(test_misspelt_required_key),
                                     cmocka_unit_test(test_set_overrides)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
