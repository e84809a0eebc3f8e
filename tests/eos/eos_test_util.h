/* SPDX-License-Identifier: MIT */
/* Small helpers shared by the EOS tests. */
#ifndef MSCALE_EOS_TEST_UTIL_H
#define MSCALE_EOS_TEST_UTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "eos.h"
#include "test_util.h" /* has_error */

static inline void eos_test_dump(const dk_errors *e) {
  for (size_t i = 0; i < e->n; ++i) fprintf(stderr, "  | %s\n", e->msg[i]);
}

/* Path of a file in the source tree (MSCALE_SOURCE_DIR, set by ctest). */
static inline void eos_test_source_path(char *buf, size_t n, const char *rel) {
  const char *root = getenv("MSCALE_SOURCE_DIR");
  snprintf(buf, n, "%s/%s", root ? root : "../..", rel);
}

/* A fresh temporary directory (removed by the test's own cleanup). */
static inline void eos_test_tmpdir(char *buf, size_t n) {
  snprintf(buf, n, "/tmp/mscale_eos_test_XXXXXX");
  if (!mkdtemp(buf)) {
    perror("mkdtemp");
    abort();
  }
}

static inline void eos_test_write(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

#endif
