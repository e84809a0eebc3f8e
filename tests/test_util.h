/* SPDX-License-Identifier: MIT */
/* Small helpers shared by the cmocka tests (tests/<module>/ include it as "test_util.h"). */
#ifndef MSCALE_TEST_UTIL_H
#define MSCALE_TEST_UTIL_H

#include <stdbool.h>
#include <string.h>

#include "core.h"

/* True if some collected error message contains `needle` (e.g. "deck.yaml:4:8: rho0"). */
static inline bool has_error(const dk_errors *e, const char *needle) {
  for (size_t i = 0; i < e->n; i++)
    if (strstr(e->msg[i], needle)) return true;
  return false;
}

#endif
