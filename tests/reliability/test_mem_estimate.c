/* SPDX-License-Identifier: MIT */
/* Check-time memory estimate (core/mem_estimate.c): a deck asking for more memory than the
 * machine has is rejected with an estimate that names the deck position and the largest items. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core.h"

static const double GiB = 1073741824.0;

static void test_format(void **state) {
  (void)state;
  char b[32];
  ms_mem_format(1536, b, sizeof b);
  assert_string_equal(b, "1.5 KiB");
  ms_mem_format(100, b, sizeof b);
  assert_string_equal(b, "100 B");
  ms_mem_format(3 * GiB, b, sizeof b);
  assert_string_equal(b, "3 GiB");
  ms_mem_format(1e12 * 200, b, sizeof b); /* 2e14 B = 182 TiB */
  assert_string_equal(b, "182 TiB");
}

static void test_huge_particle_count_rejected(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string("particles:\n  count: 1e12\ngrid:\n  cells: 1000\n", "big.yaml", &e);
  assert_non_null(doc);
  const dk_node *count = dk_get(dk_get(dk_root(doc), "particles"), "count");
  const dk_node *cells = dk_get(dk_get(dk_root(doc), "grid"), "cells");
  ms_mem_estimate m;
  ms_mem_init(&m);
  ms_mem_add(&m, count, "particles.count: particles", 1e12, 200);
  ms_mem_add(&m, cells, "grid.cells: cells", 1000, 136);
  ms_mem_add(&m, NULL, "ignored", NAN, 8);
  assert_int_equal(m.n, 2);
  /* 2e14 + 1.36e5 bytes: exact sum of the items */
  assert_true(m.total == 1e12 * 200 + 1000 * 136);
  assert_false(ms_mem_check(&m, 64 * GiB, 1, 1, &e, doc));
  dk_errors_print(&e, stderr);
  assert_int_equal(e.n, 1);
  /* at the node that sets the count (line 2, column 10), largest item first */
  assert_non_null(strstr(e.msg[0], "big.yaml:2:10: the run would need about 182 TiB"));
  assert_non_null(strstr(e.msg[0], "but 64 GiB is available"));
  assert_non_null(strstr(e.msg[0], "largest: particles.count: particles: 1e+12 x 200 B = 182 TiB; "
                                   "grid.cells: cells: 1e+03 x 136 B = 133 KiB"));
  ms_mem_free(&m);
  dk_free(doc);
  dk_errors_free(&e);
}

static void test_ranks_share_the_estimate(void **state) {
  (void)state;
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string("n: 1\n", "r.yaml", &e);
  ms_mem_estimate m;
  ms_mem_init(&m);
  ms_mem_add(&m, NULL, "particles", 1e9, 100);              /* 93.1 GiB in total */
  assert_true(ms_mem_check(&m, 100 * GiB, 1, 1, &e, doc));  /* fits on one node */
  assert_false(ms_mem_check(&m, 32 * GiB, 1, 1, &e, doc));  /* does not */
  assert_true(ms_mem_check(&m, 32 * GiB, 16, 4, &e, doc));  /* 23.3 GiB per node */
  assert_false(ms_mem_check(&m, 32 * GiB, 16, 8, &e, doc)); /* 46.6 GiB per node */
  assert_int_equal(e.n, 2);
  assert_non_null(strstr(e.msg[1], "(16 ranks, 8 per node: 46.6 GiB per node)"));
  assert_non_null(strstr(e.msg[1], "r.yaml: the run would need")); /* no deck position */
  ms_mem_free(&m);
  dk_free(doc);
  dk_errors_free(&e);
}

static void test_limit_from_environment(void **state) {
  (void)state;
  unsetenv("MSCALE_MEMORY_LIMIT");
  double machine = ms_mem_limit();
  assert_true(machine > 0); /* physical memory is known on Linux */
  setenv("MSCALE_MEMORY_LIMIT", "512M", 1);
  assert_true(ms_mem_limit() == fmin(machine, 512.0 * 1048576.0));
  setenv("MSCALE_MEMORY_LIMIT", "1.5 GiB", 1);
  assert_true(ms_mem_limit() == fmin(machine, 1.5 * GiB));
  setenv("MSCALE_MEMORY_LIMIT", "lots", 1); /* malformed: ignored */
  assert_true(ms_mem_limit() == machine);
  unsetenv("MSCALE_MEMORY_LIMIT");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_format),
      cmocka_unit_test(test_huge_particle_count_rejected),
      cmocka_unit_test(test_ranks_share_the_estimate),
      cmocka_unit_test(test_limit_from_environment),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
